//! Today's full matrix: the form factors of every element pair stored as sparse rows
//! (`form_factors`). The solvers in `radiosity::solver` iterate over it.

pub mod form_factors;

pub use form_factors::FormFactors;
