//! Solvers of B = E + ρ·F·B (per RGB channel, accumulated in f64): Gauss-Seidel with overrelaxation,
//! Jacobi (the truncated von Neumann series) and progressive refinement by shooting.
//!
//! The sweeps and the shot are pure kernels over slices; `solve` chooses the method and the
//! parallelism (a Jacobi sweep is split over rows with rayon, which is deterministic: every row is
//! written by exactly one task and the convergence measure is a maximum).

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use super::form_factors::FormFactors;
use super::solution::SolveStats;
use crate::scene::{RadiosityParams, SolverKind};

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

    fn merge(self, other: SweepChange) -> SweepChange {
        SweepChange {
            max_abs_change: self.max_abs_change.max(other.max_abs_change),
            max_abs_exitance: self.max_abs_exitance.max(other.max_abs_exitance),
        }
    }

    fn of(old: DVec3, new: DVec3) -> SweepChange {
        SweepChange { max_abs_change: (new - old).abs().max_element(), max_abs_exitance: new.abs().max_element() }
    }
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

/// One shot of progressive refinement (Cohen, Chen, Wallace and Greenberg 1988): element i's unshot
/// exitance ΔB_i leaves it, and every element j that sees it receives
///
/// ΔB_j ← ΔB_j + ρ_j F_ji ΔB_i,   B_j ← B_j + ρ_j F_ji ΔB_i,
///
/// with F_ji read from j's own hemicube (`received_by` is the transposed matrix: its row i lists
/// (j, F_ji)). The classic algorithm uses i's hemicube and reciprocity, F_ji = F_ij A_i / A_j; hemicube
/// factors are reciprocal only approximately (most visibly between neighbours), so with a stored
/// matrix the receivers' factors make shooting converge to exactly the solution gathering finds.
///
/// ΔB_i is zeroed before the distribution, so light an element sends to itself (F_ii ≠ 0) comes
/// back as new unshot exitance. Returns the power shot, ΔB_i A_i (per channel).
pub fn shoot(
    received_by: &FormFactors,
    shooter: usize,
    reflectance: &[DVec3],
    area: &[f64],
    exitance: &mut [DVec3],
    unshot_exitance: &mut [DVec3],
) -> DVec3 {
    let shot_power = unshot_exitance[shooter] * area[shooter];
    let shot_exitance = unshot_exitance[shooter];
    unshot_exitance[shooter] = DVec3::ZERO;
    let (columns, factors) = received_by.row(shooter);
    for (&j, &f) in columns.iter().zip(factors) {
        let j = j as usize;
        let received = reflectance[j] * shot_exitance * f as f64;
        exitance[j] += received;
        unshot_exitance[j] += received;
    }
    shot_power
}

/// The ambient term of a partial progressive solution (Cohen et al. 1988, section 4.1): the unshot
/// exitance spread evenly over the scene and reflected indefinitely,
///
/// ambient = R · Σ_j ΔB_j A_j / Σ_j A_j,   R = 1 / (1 − ρ_avg),   ρ_avg = Σ_j ρ_j A_j / Σ_j A_j
///
/// per channel. For display only: element i is shown as B_i + ρ_i · ambient.
pub fn ambient_exitance(reflectance: &[DVec3], area: &[f64], unshot_exitance: &[DVec3]) -> DVec3 {
    let total_area: f64 = area.iter().sum();
    if total_area.is_nan() || total_area <= 0.0 {
        return DVec3::ZERO;
    }
    let mut weighted_reflectance = DVec3::ZERO;
    let mut unshot_power = DVec3::ZERO;
    for ((&rho, &a), &db) in reflectance.iter().zip(area).zip(unshot_exitance) {
        weighted_reflectance += rho * a;
        unshot_power += db * a;
    }
    let average_reflectance = weighted_reflectance / total_area;
    let interreflection = DVec3::ONE / (DVec3::ONE - average_reflectance).max(DVec3::splat(1e-12));
    interreflection * unshot_power / total_area
}

/// Index of the element with the most unshot power Σ_c ΔB_ic A_i (the lowest index on ties; `None`
/// when nothing is left), and the total unshot power per channel Σ_i ΔB_i A_i, in one scan.
///
/// A linear scan rather than a max-heap: a shot changes the priority of every receiver (thousands per
/// row), so a heap would take thousands of O(log n) updates per shot where the scan reads n values
/// contiguously (see `benches/solver.rs`, `progressive select` against `progressive shoot`).
pub fn brightest_unshot(area: &[f64], unshot_exitance: &[DVec3]) -> (Option<usize>, DVec3) {
    let mut best = None;
    let mut best_power = 0.0;
    let mut total = DVec3::ZERO;
    for (i, (&a, &db)) in area.iter().zip(unshot_exitance).enumerate() {
        let power = db * a;
        total += power;
        let key = power.element_sum();
        if key > best_power {
            best_power = key;
            best = Some(i);
        }
    }
    (best, total)
}

/// Progressive refinement as a stepper, so a caller can display partial solutions (with
/// `exitance_with_ambient`) between shots.
///
/// Convergence measure (`unshot_fraction`): the largest, over channels with emitted power, of the
/// unshot power Σ_i ΔB_i A_i divided by the emitted power Σ_i E_i A_i. It starts at 1 and falls
/// towards 0; the remaining error in B is at most ρ_max/(1 − ρ_max) · max_i ΔB_i.
#[derive(Clone, Debug)]
pub struct Shooter {
    /// The transposed matrix: who receives from each shooter, with the receivers' factors.
    received_by: FormFactors,
    reflectance: Vec<DVec3>,
    area: Vec<f64>,
    exitance: Vec<DVec3>,
    unshot_exitance: Vec<DVec3>,
    emitted_power: DVec3,
    /// From the last scan: the next shooter and the unshot power.
    next_shooter: Option<usize>,
    unshot_power: DVec3,
    shots: u32,
}

impl Shooter {
    /// Starts with B = ΔB = E.
    pub fn new(ff: &FormFactors, reflectance: &[Vec3], emission: &[Vec3], area: &[f32]) -> Self {
        let n = ff.len();
        assert!(reflectance.len() == n && emission.len() == n && area.len() == n);
        let emission: Vec<DVec3> = emission.iter().map(|e| e.as_dvec3()).collect();
        let area: Vec<f64> = area.iter().map(|&a| a as f64).collect();
        let (next_shooter, unshot_power) = brightest_unshot(&area, &emission);
        Shooter {
            received_by: ff.transpose(),
            reflectance: reflectance.iter().map(|r| r.as_dvec3()).collect(),
            area,
            exitance: emission.clone(),
            unshot_exitance: emission,
            emitted_power: unshot_power,
            next_shooter,
            unshot_power,
            shots: 0,
        }
    }

    /// Shoots the element with the most unshot power; returns it, or `None` when nothing is left.
    pub fn step(&mut self) -> Option<usize> {
        let i = self.next_shooter?;
        shoot(&self.received_by, i, &self.reflectance, &self.area, &mut self.exitance, &mut self.unshot_exitance);
        self.shots += 1;
        (self.next_shooter, self.unshot_power) = brightest_unshot(&self.area, &self.unshot_exitance);
        Some(i)
    }

    /// Unshot power / emitted power, the largest over channels that emit (0 for a dark scene).
    pub fn unshot_fraction(&self) -> f64 {
        let mut fraction: f64 = 0.0;
        for c in 0..3 {
            if self.emitted_power[c] > 0.0 {
                fraction = fraction.max(self.unshot_power[c] / self.emitted_power[c]);
            }
        }
        fraction
    }

    pub fn shots(&self) -> u32 {
        self.shots
    }

    /// The exitance gathered so far (without the ambient term).
    pub fn exitance(&self) -> &[DVec3] {
        &self.exitance
    }

    pub fn unshot_exitance(&self) -> &[DVec3] {
        &self.unshot_exitance
    }

    /// Cohen et al.'s ambient term for the current unshot exitance (see `ambient_exitance`).
    pub fn ambient_exitance(&self) -> DVec3 {
        ambient_exitance(&self.reflectance, &self.area, &self.unshot_exitance)
    }

    /// The partial solution for display: B_i + ρ_i · ambient.
    pub fn exitance_with_ambient(&self) -> Vec<DVec3> {
        let ambient = self.ambient_exitance();
        self.exitance.iter().zip(&self.reflectance).map(|(&b, &rho)| b + rho * ambient).collect()
    }

    /// The exitance gathered so far, consuming the shooter.
    pub fn into_exitance(self) -> Vec<DVec3> {
        self.exitance
    }
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
    let n = ff.len();
    assert!(reflectance.len() == n && emission.len() == n && area.len() == n, "one value per element");
    match params.solver {
        SolverKind::GaussSeidel | SolverKind::Jacobi => {
            let reflectance: Vec<DVec3> = reflectance.iter().map(|r| r.as_dvec3()).collect();
            let emission: Vec<DVec3> = emission.iter().map(|e| e.as_dvec3()).collect();
            gathering(ff, &reflectance, &emission, params, on_iteration)
        }
        SolverKind::Progressive => progressive(ff, reflectance, emission, area, params, on_iteration),
    }
}

fn gathering(
    ff: &FormFactors,
    reflectance: &[DVec3],
    emission: &[DVec3],
    params: &RadiosityParams,
    on_iteration: &mut dyn FnMut(u32, f64),
) -> (Vec<DVec3>, SolveStats) {
    let mut stats = SolveStats { solver: params.solver, iterations: 0, residual_history: Vec::new(), converged: false };
    let mut exitance = emission.to_vec();
    let mut scratch = vec![DVec3::ZERO; exitance.len()];
    // Only Gauss-Seidel needs F_ii; finding it reads every column index, so split it over rows.
    let diagonal: Vec<f32> = match params.solver {
        SolverKind::GaussSeidel => (0..ff.len()).into_par_iter().map(|i| row_diagonal(ff, i)).collect(),
        _ => Vec::new(),
    };
    while stats.iterations < params.max_iterations {
        let change = match params.solver {
            SolverKind::Jacobi => {
                let change = scratch
                    .par_iter_mut()
                    .enumerate()
                    .map(|(i, b)| {
                        *b = jacobi_row(ff, i, reflectance, emission, &exitance);
                        SweepChange::of(exitance[i], *b)
                    })
                    .reduce(SweepChange::default, SweepChange::merge);
                std::mem::swap(&mut exitance, &mut scratch);
                change
            }
            _ => gauss_seidel_sweep(ff, &diagonal, reflectance, emission, params.relaxation, &mut exitance),
        };
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
    (exitance, stats)
}

fn progressive(
    ff: &FormFactors,
    reflectance: &[Vec3],
    emission: &[Vec3],
    area: &[f32],
    params: &RadiosityParams,
    on_iteration: &mut dyn FnMut(u32, f64),
) -> (Vec<DVec3>, SolveStats) {
    let mut shooter = Shooter::new(ff, reflectance, emission, area);
    let mut stats =
        SolveStats { solver: SolverKind::Progressive, iterations: 0, residual_history: Vec::new(), converged: false };
    let max_shots = (params.max_iterations as u64).saturating_mul(ff.len() as u64).min(u32::MAX as u64) as u32;
    stats.converged = shooter.unshot_fraction() < params.tolerance;
    while !stats.converged && stats.iterations < max_shots {
        if shooter.step().is_none() {
            stats.converged = true;
            break;
        }
        stats.iterations = shooter.shots();
        let measure = shooter.unshot_fraction();
        if !measure.is_finite() {
            break;
        }
        stats.residual_history.push(measure);
        on_iteration(stats.iterations, measure);
        stats.converged = measure < params.tolerance;
    }
    (shooter.into_exitance(), stats)
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
        let shot = shoot(&received_by, 0, &rho, &area, &mut b, &mut db);
        assert_eq!(shot, DVec3::splat(6.0));
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
