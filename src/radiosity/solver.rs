//! Solvers of B = E + ρ·F·B: Gauss-Seidel with overrelaxation, Jacobi, progressive refinement.
