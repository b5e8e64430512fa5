//! Progressive refinement by shooting (Cohen, Chen, Wallace and Greenberg 1988), written once: the
//! shot, the choice of shooter, the ambient term, the stopping rule and the per-element state. The
//! stored-matrix solver (`Shooter`, `solve`) and the matrix-free method (`radiosity::matrix_free`)
//! differ only in where a shot's factors come from.

use glam::{DVec3, Vec3};

use crate::radiosity::matrix::FormFactors;
use crate::radiosity::stats::SolveStats;
use crate::scene::{RadiosityParams, SolverKind};

/// One shot of progressive refinement (Cohen, Chen, Wallace and Greenberg 1988): element i's unshot
/// exitance ΔB_i leaves it, and every element j that sees it receives
///
/// ΔB_j ← ΔB_j + ρ_j F_ji ΔB_i,   B_j ← B_j + ρ_j F_ji ΔB_i,
///
/// with `received` listing (j, F_ji). Where F_ji comes from is the caller's choice: the receivers' own
/// hemicubes (`received_from_matrix`, a stored transposed matrix; hemicube factors are reciprocal only
/// approximately, most visibly between neighbours, so shooting then converges to exactly the solution
/// gathering finds) or the shooter's hemicube and reciprocity, F_ji = F_ij A_i / A_j
/// (`received_by_reciprocity`, the classic algorithm, needing no stored matrix).
///
/// ΔB_i is zeroed before the distribution, so light an element sends to itself (F_ii ≠ 0) comes
/// back as new unshot exitance. Returns the exitance shot, ΔB_i (the power is ΔB_i A_i).
#[inline]
pub fn shoot(
    received: impl IntoIterator<Item = (usize, f64)>,
    shooter: usize,
    reflectance: &[DVec3],
    exitance: &mut [DVec3],
    unshot_exitance: &mut [DVec3],
) -> DVec3 {
    let shot_exitance = unshot_exitance[shooter];
    unshot_exitance[shooter] = DVec3::ZERO;
    for (j, f_ji) in received {
        let received = reflectance[j] * shot_exitance * f_ji;
        exitance[j] += received;
        unshot_exitance[j] += received;
    }
    shot_exitance
}

/// (j, F_ji) for the receivers of `shooter` from the transposed matrix (`received_by` row i lists
/// (j, F_ji) from j's own hemicube).
#[inline]
pub fn received_from_matrix(received_by: &FormFactors, shooter: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
    let (columns, factors) = received_by.row(shooter);
    columns.iter().zip(factors).map(|(&j, &f)| (j as usize, f as f64))
}

/// (j, F_ji) for the receivers of `shooter` from its own row (j, F_ij) by reciprocity,
/// F_ji = F_ij A_i / A_j.
#[inline]
pub fn received_by_reciprocity<'a>(
    row: &'a [(u32, f32)],
    shooter: usize,
    area: &'a [f64],
) -> impl Iterator<Item = (usize, f64)> + 'a {
    let shooter_area = area[shooter];
    row.iter().map(move |&(j, f)| (j as usize, f as f64 * shooter_area / area[j as usize]))
}

/// Σ_i ΔB_i A_i per channel: the unshot (or, from E, the emitted) power.
pub fn total_power(area: &[f64], exitance: &[DVec3]) -> DVec3 {
    exitance.iter().zip(area).fold(DVec3::ZERO, |s, (&db, &a)| s + db * a)
}

/// The convergence measure of shooting: unshot power / emitted power, the largest over the channels
/// that emit (0 for a dark scene). It starts at 1 and falls towards 0; the remaining error in B is at
/// most ρ_max/(1 − ρ_max) · max_i ΔB_i.
pub fn unshot_fraction(unshot_power: DVec3, emitted_power: DVec3) -> f64 {
    (0..3).filter(|&c| emitted_power[c] > 0.0).map(|c| unshot_power[c] / emitted_power[c]).fold(0.0, f64::max)
}

/// The stopping rule of a shooting solve: shots until the unshot fraction is below
/// `params.tolerance`, at most `params.max_iterations` × n of them. A non-finite measure (a diverging
/// system) stops the solve unconverged and is not recorded.
#[derive(Clone, Debug)]
pub struct ShotCount {
    stats: SolveStats,
    max_shots: u32,
    tolerance: f64,
}

impl ShotCount {
    /// Before the first shot, for `elements` elements and the initial unshot fraction.
    pub fn new(params: &RadiosityParams, elements: usize, unshot_fraction: f64) -> Self {
        let max_shots = (params.max_iterations as u64).saturating_mul(elements as u64).min(u32::MAX as u64) as u32;
        let stats = SolveStats {
            solver: SolverKind::Progressive,
            iterations: 0,
            residual_history: Vec::new(),
            converged: unshot_fraction < params.tolerance,
        };
        ShotCount { stats, max_shots, tolerance: params.tolerance }
    }

    /// Whether another shot is due.
    pub fn goes_on(&self) -> bool {
        !self.stats.converged && self.stats.iterations < self.max_shots
    }

    /// Nothing is left to shoot: converged.
    pub fn nothing_left(&mut self) {
        self.stats.converged = true;
    }

    /// Records one shot and the unshot fraction after it; `on_shot(k, measure)` sees it. Returns
    /// whether the solve goes on.
    pub fn record(&mut self, measure: f64, on_shot: &mut dyn FnMut(u32, f64)) -> bool {
        self.stats.iterations += 1;
        if !measure.is_finite() {
            return false;
        }
        self.stats.residual_history.push(measure);
        on_shot(self.stats.iterations, measure);
        if measure < self.tolerance {
            self.stats.converged = true;
            return false;
        }
        self.stats.iterations < self.max_shots
    }

    pub fn into_stats(self) -> SolveStats {
        self.stats
    }
}

/// What shooting keeps per element, whatever the source of the factors: reflectance, area, the
/// exitance gathered so far and the unshot exitance. Starts with B = ΔB = E.
#[derive(Clone, Debug)]
pub struct Shooting {
    reflectance: Vec<DVec3>,
    area: Vec<f64>,
    exitance: Vec<DVec3>,
    unshot_exitance: Vec<DVec3>,
    emitted_power: DVec3,
}

impl Shooting {
    pub fn new(reflectance: Vec<DVec3>, area: Vec<f64>, emission: Vec<DVec3>) -> Self {
        assert!(reflectance.len() == area.len() && emission.len() == area.len(), "one value per element");
        let emitted_power = total_power(&area, &emission);
        Shooting { reflectance, area, exitance: emission.clone(), unshot_exitance: emission, emitted_power }
    }

    /// Shoots element `shooter`'s unshot exitance to `received` (j, F_ji) (see `shoot`).
    #[inline]
    pub fn shoot(&mut self, shooter: usize, received: impl IntoIterator<Item = (usize, f64)>) -> DVec3 {
        shoot(received, shooter, &self.reflectance, &mut self.exitance, &mut self.unshot_exitance)
    }

    pub fn reflectance(&self) -> &[DVec3] {
        &self.reflectance
    }

    pub fn area(&self) -> &[f64] {
        &self.area
    }

    /// The exitance gathered so far (without the ambient term).
    pub fn exitance(&self) -> &[DVec3] {
        &self.exitance
    }

    pub fn unshot_exitance(&self) -> &[DVec3] {
        &self.unshot_exitance
    }

    /// Σ_i E_i A_i per channel.
    pub fn emitted_power(&self) -> DVec3 {
        self.emitted_power
    }

    /// The unshot fraction for the current unshot exitance (see `unshot_fraction`).
    pub fn unshot_fraction(&self) -> f64 {
        unshot_fraction(total_power(&self.area, &self.unshot_exitance), self.emitted_power)
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

    /// The exitance gathered so far, consuming the state.
    pub fn into_exitance(self) -> Vec<DVec3> {
        self.exitance
    }
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

/// Progressive refinement over a stored matrix as a stepper, so a caller can display partial
/// solutions (with `exitance_with_ambient`) between shots. It shoots with the receivers' factors (the
/// transposed matrix) and picks the brightest unshot element each time (`brightest_unshot`).
#[derive(Clone, Debug)]
pub struct Shooter {
    /// The transposed matrix: who receives from each shooter, with the receivers' factors.
    received_by: FormFactors,
    state: Shooting,
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
        let state = Shooting::new(reflectance.iter().map(|r| r.as_dvec3()).collect(), area, emission);
        Shooter { received_by: ff.transpose(), state, next_shooter, unshot_power, shots: 0 }
    }

    /// Shoots the element with the most unshot power; returns it, or `None` when nothing is left.
    pub fn step(&mut self) -> Option<usize> {
        let i = self.next_shooter?;
        self.state.shoot(i, received_from_matrix(&self.received_by, i));
        self.shots += 1;
        (self.next_shooter, self.unshot_power) = brightest_unshot(self.state.area(), self.state.unshot_exitance());
        Some(i)
    }

    /// Unshot power / emitted power, the largest over channels that emit (0 for a dark scene).
    pub fn unshot_fraction(&self) -> f64 {
        unshot_fraction(self.unshot_power, self.state.emitted_power())
    }

    pub fn shots(&self) -> u32 {
        self.shots
    }

    /// The exitance gathered so far (without the ambient term).
    pub fn exitance(&self) -> &[DVec3] {
        self.state.exitance()
    }

    pub fn unshot_exitance(&self) -> &[DVec3] {
        self.state.unshot_exitance()
    }

    /// Cohen et al.'s ambient term for the current unshot exitance (see `ambient_exitance`).
    pub fn ambient_exitance(&self) -> DVec3 {
        self.state.ambient_exitance()
    }

    /// The partial solution for display: B_i + ρ_i · ambient.
    pub fn exitance_with_ambient(&self) -> Vec<DVec3> {
        self.state.exitance_with_ambient()
    }

    /// The exitance gathered so far, consuming the shooter.
    pub fn into_exitance(self) -> Vec<DVec3> {
        self.state.into_exitance()
    }
}

/// Solves B = E + ρ·F·B over a stored matrix by shooting (`Shooter`) until `ShotCount` stops it; the
/// exitance is returned without the ambient term. `on_shot(k, unshot_fraction)` sees every shot;
/// `stop` is polled before every shot, and once true the solve is abandoned (`None`).
pub fn solve(
    ff: &FormFactors,
    reflectance: &[Vec3],
    emission: &[Vec3],
    area: &[f32],
    params: &RadiosityParams,
    on_shot: &mut dyn FnMut(u32, f64),
    stop: &dyn Fn() -> bool,
) -> Option<(Vec<DVec3>, SolveStats)> {
    let mut shooter = Shooter::new(ff, reflectance, emission, area);
    let mut count = ShotCount::new(params, ff.len(), shooter.unshot_fraction());
    while count.goes_on() {
        if stop() {
            return None;
        }
        if shooter.step().is_none() {
            count.nothing_left();
            break;
        }
        if !count.record(shooter.unshot_fraction(), on_shot) {
            break;
        }
    }
    Some((shooter.into_exitance(), count.into_stats()))
}
