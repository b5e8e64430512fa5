//! Pass one: view-independent diffuse radiosity. Form factors by the hemicube (Cohen and Greenberg
//! 1985), the system B = E + ρ·F·B solved by one of the pass-one methods (`method`): Gauss-Seidel
//! with overrelaxation, Jacobi or progressive refinement over a stored matrix (`matrix`, `solver`), or
//! progressive refinement without one (`matrix_free`), or hierarchically over clusters and adaptively
//! subdivided elements (`hierarchical`, on the mesh of its leaves: `leaf_mesh`). The result is the immutable `Solution` that
//! pass two reads.

pub mod adaptive;
pub mod boundary_vertices;
pub mod fingerprint;
pub mod hemicube;
pub mod hierarchical;
pub mod hierarchy;
pub mod irradiance;
pub mod leaf_mesh;
pub mod matrix;
pub mod matrix_free;
pub mod method;
pub mod resume;
pub mod sampled_direct;
pub mod smooth_mesh;
pub mod smoothing_groups;
pub mod solution;
pub mod solution_file;
pub mod solver;
pub mod specular;
pub mod stats;
pub mod t_junctions;

pub use matrix::form_factors;
pub use matrix::FormFactors;
pub use method::{PassOne, PassOneMethod};
pub use solution::Solution;
pub use stats::{PassOneStats, SolveStats};
