//! Today's full matrix: the form factors of every element pair stored as sparse rows
//! (`form_factors`), the rows finished so far (`partial`) and their file (`rows_file`), which
//! checkpoints and shards share. The solvers in `radiosity::solver` iterate over it.

pub mod cost;
pub mod form_factors;
pub mod partial;
pub mod patch_cut;
pub mod rows_file;

pub use form_factors::{FormFactors, RowPlan};
pub use partial::PartialRows;
