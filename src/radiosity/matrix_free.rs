//! Progressive refinement without a stored matrix (Cohen, Chen, Wallace and Greenberg 1988): each
//! shot rasterises the shooter's own hemicube and distributes its unshot exitance by reciprocity, so
//! pass one needs O(n) memory instead of the O(n²) form-factor matrix. This is the mode for scenes
//! whose matrix would not fit in memory; with a loose tolerance and the ambient term it also gives a
//! usable picture after few shots.

use glam::DVec3;
use rayon::prelude::*;

use super::hemicube::{Hemicube, ItemBuffer};
use super::matrix::form_factors::{needs_row, ElementHierarchy};
use super::solver::shooting::{received_by_reciprocity, Shooting, ShotCount};
use super::specular::SpecularPaths;
use super::stats::SolveStats;
use crate::mesh::Mesh;
use crate::scene::RadiosityParams;

/// Shooters whose hemicubes are rasterised together (in parallel), then shot one after another, each
/// with the unshot exitance it has at its turn. A constant, so the result does not depend on the
/// thread count.
pub const SHOT_BATCH: usize = 8;

/// What a matrix-free solve produces.
#[derive(Clone, Debug)]
pub struct MatrixFreeSolution {
    /// B_i + ρ_i · ambient: the shot exitance plus Cohen et al.'s ambient term for what is still
    /// unshot (which vanishes as the solve converges).
    pub exitance: Vec<DVec3>,
    /// The first-bounce part, ρ_j Σ_i F_ji E_i over the plain (straight-line) factors, with
    /// F_ji = F_ij A_i / A_j from each emitter's hemicube.
    pub direct_exitance: Vec<DVec3>,
    /// The ambient term included in `exitance` (element i shows ρ_i times it); zero when converged.
    pub ambient_exitance: DVec3,
    pub stats: SolveStats,
}

/// One shooter's row: (j, F_ij) plain entries first, then extended entries through specular
/// surfaces; the length of the plain part.
type ShooterRow = (Vec<(u32, f32)>, usize);

/// The `SHOT_BATCH` elements with the most unshot power Σ_c ΔB_ic A_i, brightest first (lower index
/// on ties); elements with no unshot power are never chosen.
pub fn brightest_unshot_batch(area: &[f64], unshot_exitance: &[DVec3]) -> Vec<usize> {
    let mut best: Vec<(f64, usize)> = Vec::with_capacity(SHOT_BATCH + 1);
    for (i, (&a, &db)) in area.iter().zip(unshot_exitance).enumerate() {
        let power = (db * a).element_sum();
        if power <= 0.0 || (best.len() == SHOT_BATCH && power <= best[SHOT_BATCH - 1].0) {
            continue;
        }
        let at = best.partition_point(|&(p, _)| p >= power);
        best.insert(at, (power, i));
        best.truncate(SHOT_BATCH);
    }
    best.into_iter().map(|(_, i)| i).collect()
}

/// Solves B = E + ρ·F·B by progressive refinement with every row computed when its element shoots
/// (hemicube at the shooter, `ElementHierarchy::element_row`; extended through mirrors and glass when
/// `specular` is given). Stops when the unshot fraction (unshot power / emitted power, the largest
/// over emitting channels) is below `params.tolerance`, or after `params.max_iterations` × n shots.
/// `on_shot(k, unshot_fraction)` is called after every shot.
///
/// Shooting uses the shooter's factors and reciprocity, the classic algorithm: hemicube factors are
/// reciprocal only approximately, so the result differs from the stored-matrix solvers by that
/// discretisation error (about a percent on the Cornell box), not by the tolerance.
pub fn solve(
    mesh: &Mesh,
    params: &RadiosityParams,
    specular: Option<&SpecularPaths>,
    on_shot: &mut dyn FnMut(u32, f64),
) -> MatrixFreeSolution {
    let e = &mesh.elements;
    let n = e.len();
    let hc = Hemicube::new(params.hemicube_resolution_px);
    let hierarchy = ElementHierarchy::new(mesh);
    let reflectance: Vec<DVec3> = e.reflectance.iter().map(|r| r.as_dvec3()).collect();
    let emission: Vec<DVec3> = e.emission.iter().map(|x| x.as_dvec3()).collect();
    let area: Vec<f64> = e.area.iter().map(|&a| a as f64).collect();
    let row_of = |buffers: &mut ItemBuffer, i: usize| -> ShooterRow {
        let mut row = Vec::new();
        if !needs_row(mesh, i) {
            return (row, 0);
        }
        hierarchy.element_row(mesh, params, &hc, buffers, i, &mut row);
        let mut plain = row.len();
        if let Some(specular) = specular {
            row.retain(|&(j, _)| !specular.is_pure_specular(j as usize));
            plain = row.len();
            specular.extend_row(&hc, buffers, params.seed, i, &mut row);
        }
        (row, plain)
    };
    let rows_of = |shooters: &[usize]| -> Vec<ShooterRow> {
        shooters.par_iter().map_init(|| ItemBuffer::new(&hc), |buffers, &i| row_of(buffers, i)).collect()
    };

    // Emitters whose emission has gone into `direct` (at their first shot).
    let mut direct = vec![DVec3::ZERO; n];
    let mut direct_done: Vec<bool> = emission.iter().map(|x| x.max_element() <= 0.0).collect();
    let add_direct = |direct: &mut [DVec3], i: usize, plain_row: &[(u32, f32)]| {
        for &(j, f) in plain_row {
            let j = j as usize;
            direct[j] += reflectance[j] * emission[i] * (f as f64 * area[i] / area[j]);
        }
    };
    let mut state = Shooting::new(reflectance.clone(), area.clone(), emission.clone());
    let mut count = ShotCount::new(params, n, state.unshot_fraction());
    'solve: while count.goes_on() {
        let shooters = brightest_unshot_batch(&area, state.unshot_exitance());
        if shooters.is_empty() {
            count.nothing_left();
            break;
        }
        for (&i, (row, plain)) in shooters.iter().zip(rows_of(&shooters)) {
            if !direct_done[i] {
                add_direct(&mut direct, i, &row[..plain]);
                direct_done[i] = true;
            }
            state.shoot(i, received_by_reciprocity(&row, i, &area));
            if !count.record(state.unshot_fraction(), on_shot) {
                break 'solve;
            }
        }
    }
    // An early stop can leave emitters unshot; their first bounce still belongs to the direct part.
    let pending: Vec<usize> = (0..n).filter(|&i| !direct_done[i]).collect();
    for (&i, (row, plain)) in pending.iter().zip(rows_of(&pending)) {
        add_direct(&mut direct, i, &row[..plain]);
    }

    let ambient = state.ambient_exitance();
    let exitance = state.exitance_with_ambient();
    MatrixFreeSolution { exitance, direct_exitance: direct, ambient_exitance: ambient, stats: count.into_stats() }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn batch_is_the_brightest_first_without_dark_elements() {
        let area = vec![1.0, 2.0, 1.0, 4.0, 1.0];
        let unshot = [0.5, 1.0, 0.0, 0.25, 3.0].map(DVec3::splat).to_vec();
        // Powers: 1.5, 6, 0, 3, 9 (summed over channels).
        assert_eq!(brightest_unshot_batch(&area, &unshot), vec![4, 1, 3, 0]);
    }

    #[test]
    fn batch_keeps_only_the_brightest_of_many() {
        let n = 3 * SHOT_BATCH;
        let area = vec![1.0; n];
        let unshot: Vec<DVec3> = (0..n).map(|i| DVec3::splat(((i * 7) % n) as f64)).collect();
        let batch = brightest_unshot_batch(&area, &unshot);
        let mut expected: Vec<usize> = (0..n).collect();
        expected.sort_by(|&a, &b| unshot[b].x.total_cmp(&unshot[a].x).then(a.cmp(&b)));
        assert_eq!(batch, expected[..SHOT_BATCH]);
    }

    #[test]
    fn a_shot_conserves_power_by_reciprocity() {
        // Element 0 (area 2) shoots into 1 (area 1) and 2 (area 4); with ρ = 1 the power received,
        // Σ_j ΔB_j A_j = ΔB_0 A_0 Σ_j F_0j, is what element 0's row intercepts.
        let row = [(1u32, 0.25f32), (2, 0.5)];
        let reflectance = vec![DVec3::ONE; 3];
        let area = vec![2.0, 1.0, 4.0];
        let mut exitance = vec![DVec3::new(3.0, 2.0, 1.0), DVec3::ZERO, DVec3::ZERO];
        let mut unshot = exitance.clone();
        crate::radiosity::solver::shoot(
            received_by_reciprocity(&row, 0, &area),
            0,
            &reflectance,
            &mut exitance,
            &mut unshot,
        );
        assert_eq!(unshot[0], DVec3::ZERO);
        let received = unshot[1] * area[1] + unshot[2] * area[2];
        let expected = DVec3::new(3.0, 2.0, 1.0) * 2.0 * 0.75;
        assert!((received - expected).abs().max_element() < 1e-12, "{received} vs {expected}");
        assert_eq!(exitance[1], unshot[1]);
    }
}
