//! Jacobi over a stored matrix: every sweep computes all rows from the previous sweep's values, so
//! after k sweeps from B = E the result holds exactly k bounces (the truncated von Neumann series).

use glam::DVec3;
use rayon::prelude::*;

use super::{gather, sweep_until_converged, SweepChange};
use crate::radiosity::matrix::FormFactors;
use crate::radiosity::stats::SolveStats;
use crate::scene::RadiosityParams;

/// One row of a Jacobi sweep, the next term of the von Neumann series B = E + KE + K²E + … with
/// K = diag(ρ)·F:
///
/// B_i^{k+1} = E_i + ρ_i Σ_j F_ij B_j^k
///
/// The diagonal is kept in the sum (the series converges to the same B for any F_ii, since
/// ρ_i Σ_j F_ij < 1), so after k sweeps from B^0 = E the result holds exactly k bounces.
#[inline]
pub fn jacobi_row(ff: &FormFactors, i: usize, reflectance: &[DVec3], emission: &[DVec3], previous: &[DVec3]) -> DVec3 {
    let (columns, factors) = ff.row(i);
    emission[i] + reflectance[i] * gather(columns, factors, previous)
}

/// One serial Jacobi sweep, `next` ← E + ρ F `previous` (see `jacobi_row`). The solver runs the same
/// rows in parallel; this serial form is for benches and tests.
pub fn jacobi_sweep(
    ff: &FormFactors,
    reflectance: &[DVec3],
    emission: &[DVec3],
    previous: &[DVec3],
    next: &mut [DVec3],
) -> SweepChange {
    let n = ff.len();
    assert!(reflectance.len() == n && emission.len() == n && previous.len() == n && next.len() == n);
    let mut change = SweepChange::default();
    for (i, b) in next.iter_mut().enumerate() {
        *b = jacobi_row(ff, i, reflectance, emission, previous);
        change = change.merge(SweepChange::of(previous[i], *b));
    }
    change
}

/// Solves B = E + ρ·F·B by Jacobi sweeps from B = E, rows in parallel (see `sweep_until_converged`
/// for the stopping rule).
pub fn solve(
    ff: &FormFactors,
    reflectance: &[DVec3],
    emission: &[DVec3],
    params: &RadiosityParams,
    on_iteration: &mut dyn FnMut(u32, f64),
    stop: &dyn Fn() -> bool,
) -> Option<(Vec<DVec3>, SolveStats)> {
    let mut scratch = vec![DVec3::ZERO; emission.len()];
    sweep_until_converged(emission, params, on_iteration, stop, |exitance| {
        let change = scratch
            .par_iter_mut()
            .enumerate()
            .map(|(i, b)| {
                *b = jacobi_row(ff, i, reflectance, emission, exitance);
                SweepChange::of(exitance[i], *b)
            })
            .reduce(SweepChange::default, SweepChange::merge);
        std::mem::swap(exitance, &mut scratch);
        change
    })
}
