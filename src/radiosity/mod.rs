//! Pass one: view-independent diffuse radiosity. Form factors by the hemicube (Cohen and Greenberg
//! 1985), the system B = E + ρ·F·B solved by Gauss-Seidel with overrelaxation, Jacobi or progressive
//! refinement (with a stored matrix, or matrix-free in `progressive`), and the immutable `Solution`
//! that pass two reads.

pub mod form_factors;
pub mod hemicube;
pub mod hierarchy;
pub mod progressive;
pub mod solution;
pub mod solver;
pub mod specular;

pub use form_factors::FormFactors;
pub use solution::Solution;
