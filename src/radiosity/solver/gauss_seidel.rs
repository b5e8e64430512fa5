//! Gauss-Seidel with overrelaxation (SOR) over a stored matrix: sweeps in row order, each row solved
//! for its own exitance with the newest values of the rows before it.

use glam::DVec3;
use rayon::prelude::*;

use super::{gather, sweep_until_converged, SweepChange};
use crate::radiosity::matrix::FormFactors;
use crate::radiosity::stats::SolveStats;
use crate::scene::RadiosityParams;

/// F_ii of row i (0 when not stored). A flat element's hemicube never sees the element itself, so
/// this is 0 for hemicube form factors; the Gauss-Seidel sweep still handles it.
pub fn row_diagonal(ff: &FormFactors, i: usize) -> f32 {
    let (c, v) = ff.row(i);
    c.iter().zip(v).filter(|(&j, _)| j as usize == i).map(|(_, &f)| f).sum()
}

/// The diagonal F_ii of every row (see `row_diagonal`), serially.
pub fn diagonal(ff: &FormFactors) -> Vec<f32> {
    (0..ff.len()).map(|i| row_diagonal(ff, i)).collect()
}

/// One in-place Gauss-Seidel sweep with overrelaxation (SOR) over all rows, in row order:
///
/// B_i ← (1 − ω) B_i + ω (E_i + ρ_i Σ_{j≠i} F_ij B_j) / (1 − ρ_i F_ii)
///
/// per channel, where the B_j of rows already visited are this sweep's new values. Dividing by
/// 1 − ρ_i F_ii solves row i for B_i exactly when the element sees itself (F_ii ≠ 0); for a flat
/// element F_ii = 0 and this is the textbook B_i ← (1 − ω)B_i + ω(E_i + ρ_i Σ_j F_ij B_j)
/// (Cohen and Greenberg 1985, Gauss-Seidel; ω = 1 is plain Gauss-Seidel).
///
/// `diagonal` is `diagonal(ff)`. Returns the sweep's change for the stopping rule.
pub fn gauss_seidel_sweep(
    ff: &FormFactors,
    diagonal: &[f32],
    reflectance: &[DVec3],
    emission: &[DVec3],
    relaxation: f64,
    exitance: &mut [DVec3],
) -> SweepChange {
    let n = ff.len();
    assert!(diagonal.len() == n && reflectance.len() == n && emission.len() == n && exitance.len() == n);
    let mut change = SweepChange::default();
    for i in 0..n {
        let (columns, factors) = ff.row(i);
        let old = exitance[i];
        let f_ii = diagonal[i] as f64;
        // The gathered sum includes F_ii·B_i(old); take it out and solve row i for B_i instead.
        let gathered = gather(columns, factors, exitance) - old * f_ii;
        let rho = reflectance[i];
        let solved = (emission[i] + rho * gathered) / (DVec3::ONE - rho * f_ii);
        let new = old + (solved - old) * relaxation;
        exitance[i] = new;
        change = change.merge(SweepChange::of(old, new));
    }
    change
}

/// Solves B = E + ρ·F·B by SOR sweeps from B = E with ω = `params.relaxation` (see
/// `sweep_until_converged` for the stopping rule; abandoned when `stop` says so).
pub fn solve(
    ff: &FormFactors,
    reflectance: &[DVec3],
    emission: &[DVec3],
    params: &RadiosityParams,
    on_iteration: &mut dyn FnMut(u32, f64),
    stop: &dyn Fn() -> bool,
) -> Option<(Vec<DVec3>, SolveStats)> {
    // Finding F_ii reads every column index, so split it over rows.
    let diagonal: Vec<f32> = (0..ff.len()).into_par_iter().map(|i| row_diagonal(ff, i)).collect();
    sweep_until_converged(emission, params, on_iteration, stop, |exitance| {
        gauss_seidel_sweep(ff, &diagonal, reflectance, emission, params.relaxation, exitance)
    })
}
