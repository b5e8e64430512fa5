//! Solvers of B = E + ρ·F·B over a stored matrix (per RGB channel, accumulated in f64), one method
//! per file: Gauss-Seidel with overrelaxation (`gauss_seidel`), Jacobi, the truncated von Neumann
//! series (`jacobi`), and progressive refinement by shooting (`shooting`, whose kernels the
//! matrix-free method shares). Here: the gather over one row, the sweep measure and the stopping rule
//! the sweeping solvers share, and `solve`, which chooses the method.
//!
//! The sweeps and the shot are pure kernels over slices; each method's `solve` chooses the
//! parallelism (a Jacobi sweep is split over rows with rayon, which is deterministic: every row is
//! written by exactly one task and the convergence measure is a maximum).

pub mod direct;
pub mod gauss_seidel;
pub mod jacobi;
pub mod shooting;

use glam::{DVec3, Vec3};

use super::matrix::FormFactors;
use super::smooth_mesh::SmoothMesh;
use super::solution::Solution;
use super::stats::SolveStats;
use crate::mesh::Mesh;
use crate::scene::{Material, RadiosityParams, SolverKind};

pub use direct::direct_exitance;
pub use gauss_seidel::{diagonal, gauss_seidel_sweep, row_diagonal};
pub use jacobi::{jacobi_row, jacobi_sweep};
pub use shooting::{ambient_exitance, brightest_unshot, shoot, Shooter, Shooting};

/// Denominator floor of the relative change: below it, exitances count as zero (a black scene
/// converges at once instead of dividing by zero).
pub const TINY_EXITANCE: f64 = 1e-300;

/// Σ_j F_ij B_j over one stored row (`columns`, `factors`) of the form-factor matrix: the exitance
/// an element gathers, before its reflectance. Four partial sums keep the additions pipelined.
#[inline]
pub fn gather(columns: &[u32], factors: &[f32], exitance: &[DVec3]) -> DVec3 {
    debug_assert_eq!(columns.len(), factors.len());
    let mut acc = [DVec3::ZERO; 4];
    let mut c4 = columns.chunks_exact(4);
    let mut f4 = factors.chunks_exact(4);
    for (c, f) in (&mut c4).zip(&mut f4) {
        for k in 0..4 {
            acc[k] += exitance[c[k] as usize] * f[k] as f64;
        }
    }
    for (&c, &f) in c4.remainder().iter().zip(f4.remainder()) {
        acc[0] += exitance[c as usize] * f as f64;
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3])
}

/// What one sweep changed: `max_abs_change` = max_i,c |B_ic^new − B_ic^old| and `max_abs_exitance`
/// = max_i,c |B_ic^new|. Their ratio is the convergence measure.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SweepChange {
    pub max_abs_change: f64,
    pub max_abs_exitance: f64,
}

impl SweepChange {
    /// The largest relative change, max_i |ΔB_i| / max(max_i |B_i|, tiny), over channels.
    pub fn relative(&self) -> f64 {
        self.max_abs_change / self.max_abs_exitance.max(TINY_EXITANCE)
    }

    pub(crate) fn merge(self, other: SweepChange) -> SweepChange {
        SweepChange {
            max_abs_change: self.max_abs_change.max(other.max_abs_change),
            max_abs_exitance: self.max_abs_exitance.max(other.max_abs_exitance),
        }
    }

    pub(crate) fn of(old: DVec3, new: DVec3) -> SweepChange {
        SweepChange { max_abs_change: (new - old).abs().max_element(), max_abs_exitance: new.abs().max_element() }
    }
}

/// Runs sweeps until the largest relative change of one, `SweepChange::relative`, is below
/// `params.tolerance`, or `params.max_iterations` sweeps. `sweep(exitance)` performs one sweep in
/// place. `on_iteration(k, measure)` sees every sweep; a non-finite measure (a diverging system) stops
/// unconverged and is not recorded. `stop` is polled before every sweep: once true, the solve is
/// abandoned (`None`).
pub(crate) fn sweep_until_converged(
    start: &[DVec3],
    params: &RadiosityParams,
    on_iteration: &mut dyn FnMut(u32, f64),
    stop: &dyn Fn() -> bool,
    mut sweep: impl FnMut(&mut Vec<DVec3>) -> SweepChange,
) -> Option<(Vec<DVec3>, SolveStats)> {
    let mut stats = SolveStats { solver: params.solver, iterations: 0, residual_history: Vec::new(), converged: false };
    let mut exitance = start.to_vec();
    while stats.iterations < params.max_iterations {
        if stop() {
            return None;
        }
        let change = sweep(&mut exitance);
        stats.iterations += 1;
        let measure = change.relative();
        if !measure.is_finite() {
            break;
        }
        stats.residual_history.push(measure);
        on_iteration(stats.iterations, measure);
        if measure < params.tolerance {
            stats.converged = true;
            break;
        }
    }
    Some((exitance, stats))
}

/// Solves B = E + ρ·F·B with the method of `params.solver` and returns B as f32 (see `solve_f64`).
pub fn solve(
    ff: &FormFactors,
    reflectance: &[Vec3],
    emission: &[Vec3],
    area: &[f32],
    params: &RadiosityParams,
    on_iteration: &mut dyn FnMut(u32, f64),
) -> (Vec<Vec3>, SolveStats) {
    let (exitance, stats) = solve_f64(ff, reflectance, emission, area, params, on_iteration);
    (exitance.iter().map(|b| b.as_vec3()).collect(), stats)
}

/// Solves B = E + ρ·F·B per channel in f64 with the method of `params.solver`:
///
/// * Gauss-Seidel with overrelaxation ω = `params.relaxation` (`gauss_seidel_sweep`) and Jacobi
///   (`jacobi_row`, rows in parallel) start from B = E and stop when the largest relative change of a
///   sweep, max_i,c |ΔB_ic| / max_i,c |B_ic|, is below `params.tolerance`, or after
///   `params.max_iterations` sweeps;
/// * progressive refinement (`Shooter`) stops when `Shooter::unshot_fraction` is below
///   `params.tolerance`, or after `params.max_iterations` × n shots (its exitance is returned without
///   the ambient term).
///
/// `on_iteration(k, measure)` is called after every sweep or shot with its number (from 1) and the
/// convergence measure, which `SolveStats::residual_history` also records. A non-finite measure
/// (a diverging system, ρ ≥ 1) stops the solve unconverged and is not recorded.
/// `area` is used by progressive refinement only.
pub fn solve_f64(
    ff: &FormFactors,
    reflectance: &[Vec3],
    emission: &[Vec3],
    area: &[f32],
    params: &RadiosityParams,
    on_iteration: &mut dyn FnMut(u32, f64),
) -> (Vec<DVec3>, SolveStats) {
    to_the_end(|stop| solve_f64_until(ff, reflectance, emission, area, params, on_iteration, stop))
}

/// Runs an `_until` solve that is never stopped, which therefore finishes.
fn to_the_end<T>(solve: impl FnOnce(&dyn Fn() -> bool) -> Option<T>) -> T {
    solve(&|| false).expect("a solve that is never stopped finishes")
}

/// `solve_f64`, abandoned (`None`) as soon as `stop` returns true; it is polled before every sweep
/// or shot.
pub fn solve_f64_until(
    ff: &FormFactors,
    reflectance: &[Vec3],
    emission: &[Vec3],
    area: &[f32],
    params: &RadiosityParams,
    on_iteration: &mut dyn FnMut(u32, f64),
    stop: &dyn Fn() -> bool,
) -> Option<(Vec<DVec3>, SolveStats)> {
    let n = ff.len();
    assert!(reflectance.len() == n && emission.len() == n && area.len() == n, "one value per element");
    match params.solver {
        SolverKind::GaussSeidel | SolverKind::Jacobi => {
            let reflectance: Vec<DVec3> = reflectance.iter().map(|r| r.as_dvec3()).collect();
            let emission: Vec<DVec3> = emission.iter().map(|e| e.as_dvec3()).collect();
            if params.solver == SolverKind::Jacobi {
                jacobi::solve(ff, &reflectance, &emission, params, on_iteration, stop)
            } else {
                gauss_seidel::solve(ff, &reflectance, &emission, params, on_iteration, stop)
            }
        }
        SolverKind::Progressive => shooting::solve(ff, reflectance, emission, area, params, on_iteration, stop),
    }
}

/// Pass one over a stored matrix: solves B = E + ρ·F·B with `params` (see `solve_f64`) and adds the
/// direct part (`direct_exitance`), the vertex values (`vertex_step`, the mesh welded within its
/// smoothing groups: `Solution::from_element_values`) and the fingerprint of `mesh` and `materials` (the scene's
/// material table, which `mesh.elements.material` indexes). `on_iteration` sees every sweep or shot.
pub fn solve_solution(
    mesh: &Mesh,
    materials: &[Material],
    ff: &FormFactors,
    params: &RadiosityParams,
    vertex_step: &SmoothMesh,
    on_iteration: &mut dyn FnMut(u32, f64),
) -> Solution {
    to_the_end(|stop| solve_solution_until(mesh, materials, ff, params, vertex_step, on_iteration, stop))
}

/// `solve_solution`, abandoned (`None`) as soon as `stop` returns true (polled before every sweep or
/// shot).
pub fn solve_solution_until(
    mesh: &Mesh,
    materials: &[Material],
    ff: &FormFactors,
    params: &RadiosityParams,
    vertex_step: &SmoothMesh,
    on_iteration: &mut dyn FnMut(u32, f64),
    stop: &dyn Fn() -> bool,
) -> Option<Solution> {
    let e = &mesh.elements;
    assert_eq!(ff.len(), e.len(), "one form-factor row per element");
    let (exitance, stats) = solve_f64_until(ff, &e.reflectance, &e.emission, &e.area, params, on_iteration, stop)?;
    let direct = direct_exitance(ff, &e.reflectance, &e.emission);
    Some(Solution::from_element_values(mesh, materials, &exitance, &direct, vertex_step, stats))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params(solver: SolverKind, tolerance: f64) -> RadiosityParams {
        RadiosityParams { solver, tolerance, max_iterations: 10_000, ..Default::default() }
    }

    /// Two elements that see each other and themselves (concave elements): exact B by Cramer's rule on
    /// (I − ρF)B = E.
    fn self_seeing_pair() -> (FormFactors, Vec<Vec3>, Vec<Vec3>, Vec<f32>, [f64; 2]) {
        // Reciprocal with A = (1, 2): A_0 F_01 = A_1 F_10 = 0.4.
        let f = [[0.3, 0.4], [0.2, 0.5]];
        let ff = FormFactors::from_dense(&[vec![f[0][0], f[0][1]], vec![f[1][0], f[1][1]]]);
        let rho = [0.6f32, 0.7];
        let e = [2.0f32, 0.5];
        // Use the f32-rounded factors the solver sees, so the reference is exact for them.
        let ff32 = |i: usize, j: usize| f[i][j] as f32 as f64;
        let (r0, r1) = (rho[0] as f64, rho[1] as f64);
        let a = [[1.0 - r0 * ff32(0, 0), -r0 * ff32(0, 1)], [-r1 * ff32(1, 0), 1.0 - r1 * ff32(1, 1)]];
        let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
        let b0 = (e[0] as f64 * a[1][1] - a[0][1] * e[1] as f64) / det;
        let b1 = (a[0][0] * e[1] as f64 - a[1][0] * e[0] as f64) / det;
        (ff, rho.map(Vec3::splat).to_vec(), e.map(Vec3::splat).to_vec(), vec![1.0, 2.0], [b0, b1])
    }

    #[test]
    fn every_solver_handles_a_nonzero_diagonal() {
        let (ff, rho, e, area, exact) = self_seeing_pair();
        for solver in [SolverKind::GaussSeidel, SolverKind::Jacobi, SolverKind::Progressive] {
            let (b, stats) = solve_f64(&ff, &rho, &e, &area, &params(solver, 1e-13), &mut |_, _| {});
            assert!(stats.converged, "{solver:?}");
            for i in 0..2 {
                // Stopping at 1e-13 (relative change or unshot fraction) with contraction factor
                // max_i ρ_i Σ_j F_ij = 0.49 leaves an error of order 1e-13 · 0.49/0.51 · (emitted power /
                // smallest area = 3) relative: 1e-11 bounds it with margin.
                assert!((b[i].x - exact[i]).abs() <= 1e-11 * exact[0], "{solver:?} {i}: {} vs {}", b[i].x, exact[i]);
            }
        }
    }

    #[test]
    fn one_gauss_seidel_sweep_solves_a_lone_self_seeing_element_exactly() {
        // B = E + ρ F_00 B  ⇒  B = E / (1 − ρ F_00): with the diagonal divided out, one sweep at ω = 1.
        let ff = FormFactors::from_dense(&[vec![0.5]]);
        let mut b = [DVec3::splat(1.0)];
        gauss_seidel_sweep(&ff, &diagonal(&ff), &[DVec3::splat(0.8)], &[DVec3::splat(1.0)], 1.0, &mut b);
        assert!((b[0].x - 1.0 / 0.6).abs() < 1e-15);
    }

    #[test]
    fn shot_conserves_power_by_reciprocity() {
        // Element 0 (A = 2) is seen by 1 (A = 1) and 2 (A = 4) with reciprocal factors F_10 = 0.5 and
        // F_20 = 0.25 (F_01 = 0.25, F_02 = 0.5): received power = ρ_j F_j0 ΔB_0 A_j = ρ_j F_0j ΔB_0 A_0.
        let received_by = FormFactors::from_rows(vec![vec![(1, 0.5), (2, 0.25)], vec![], vec![]]);
        let rho = [DVec3::splat(0.5); 3];
        let area = [2.0, 1.0, 4.0];
        let mut b = [DVec3::splat(3.0), DVec3::ZERO, DVec3::ZERO];
        let mut db = b;
        let shot = shoot(shooting::received_from_matrix(&received_by, 0), 0, &rho, &mut b, &mut db);
        assert_eq!(shot * area[0], DVec3::splat(6.0));
        assert_eq!(db[0], DVec3::ZERO);
        assert!((b[1].x * area[1] - 0.5 * 0.25 * 6.0).abs() < 1e-15);
        assert!((b[2].x * area[2] - 0.5 * 0.5 * 6.0).abs() < 1e-15);
        assert_eq!(b[1], db[1]);
    }

    #[test]
    fn ambient_follows_cohen_et_al_1988() {
        // ΣA = 4, ρ_avg = (0.5·1 + 0.25·3)/4 = 0.3125, R = 1/0.6875, Σ ΔB A = 2·1 = 2.
        let ambient =
            ambient_exitance(&[DVec3::splat(0.5), DVec3::splat(0.25)], &[1.0, 3.0], &[DVec3::splat(2.0), DVec3::ZERO]);
        assert!((ambient.x - 2.0 / 4.0 / 0.6875).abs() < 1e-15);
    }

    #[test]
    fn dark_scene_converges_at_once() {
        let ff = FormFactors::from_dense(&[vec![0.0, 1.0], vec![1.0, 0.0]]);
        for solver in [SolverKind::GaussSeidel, SolverKind::Jacobi, SolverKind::Progressive] {
            let (b, stats) =
                solve(&ff, &[Vec3::splat(0.5); 2], &[Vec3::ZERO; 2], &[1.0; 2], &params(solver, 1e-4), &mut |_, _| {});
            assert!(stats.converged && b.iter().all(|&b| b == Vec3::ZERO), "{solver:?}");
        }
    }

    #[test]
    fn diverging_system_stops_unconverged() {
        // ρ = 2 in a closed pair: ρF has spectral radius 2, B grows without bound.
        let ff = FormFactors::from_dense(&[vec![0.0, 1.0], vec![1.0, 0.0]]);
        let p = RadiosityParams { max_iterations: 50, ..params(SolverKind::GaussSeidel, 1e-6) };
        let (_, stats) = solve(&ff, &[Vec3::splat(2.0); 2], &[Vec3::ONE; 2], &[1.0; 2], &p, &mut |_, _| {});
        assert!(!stats.converged);
        assert_eq!(stats.iterations, 50);
    }
}
