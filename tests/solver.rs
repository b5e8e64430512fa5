//! Integration tests of pass one's solvers and solution: exact furnace and enclosure solutions from
//! `tests/data` (see the validation README, "Radiosity" and "furnace.json"), agreement of the three
//! solvers, overrelaxation, the progressive ambient term, and the solution file.
// Dense elimination and per-element checks index several parallel arrays: indices read best there.
#![allow(clippy::needless_range_loop)]

mod common;

use std::path::Path;

use glam::{DVec3, Vec3};
use radray::mesh::Mesh;
use radray::radiosity::fingerprint::fingerprint;
use radray::radiosity::smooth_mesh::SmoothMesh;
use radray::radiosity::solution_file::{
    SolutionFileError, FILE_MAGIC, FILE_VERSION, FILE_VERSION_LEAF_MESH, FILE_VERSION_LEAF_MESH_CAUSTICS,
    FILE_VERSION_REFINED_MESH,
};
use radray::radiosity::solver::{self, Shooter};
use radray::radiosity::{FormFactors, Solution};
use radray::scene::{Material, RadiosityParams, SceneDescription, SolverKind, Surface};
use serde_json::Value;

const ALL_SOLVERS: [SolverKind; 3] = [SolverKind::GaussSeidel, SolverKind::Jacobi, SolverKind::Progressive];

/// Unit roundoff of f32 (2^-24): `FormFactors` stores every F_ij rounded to f32, a relative error of at
/// most this per entry.
const F32_UNIT_ROUNDOFF: f64 = 1.0 / (1u64 << 24) as f64;

fn data(name: &str) -> Value {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(name);
    serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap()
}

fn dense(v: &Value) -> Vec<Vec<f64>> {
    v.as_array().unwrap().iter().map(|r| r.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect()).collect()
}

/// A per-patch value that is either a scalar (grey) or an RGB triple.
fn colour(v: &Value) -> Vec3 {
    match v {
        Value::Array(c) => {
            Vec3::new(c[0].as_f64().unwrap() as f32, c[1].as_f64().unwrap() as f32, c[2].as_f64().unwrap() as f32)
        }
        x => Vec3::splat(x.as_f64().unwrap() as f32),
    }
}

fn colours(v: &Value) -> Vec<Vec3> {
    v.as_array().unwrap().iter().map(colour).collect()
}

fn colours_f64(v: &Value) -> Vec<DVec3> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| match x {
            Value::Array(c) => DVec3::new(c[0].as_f64().unwrap(), c[1].as_f64().unwrap(), c[2].as_f64().unwrap()),
            x => DVec3::splat(x.as_f64().unwrap()),
        })
        .collect()
}

fn params(solver: SolverKind, tolerance: f64) -> RadiosityParams {
    RadiosityParams { solver, tolerance, max_iterations: 100_000, ..Default::default() }
}

/// The system B = E + ρFB with f32 inputs, as the solver sees them.
struct System {
    ff: FormFactors,
    reflectance: Vec<Vec3>,
    emission: Vec<Vec3>,
    area: Vec<f32>,
}

impl System {
    fn solve(&self, p: &RadiosityParams) -> (Vec<DVec3>, radray::radiosity::SolveStats) {
        solver::solve_f64(&self.ff, &self.reflectance, &self.emission, &self.area, p, &mut |_, _| {})
    }

    /// q = max_i,c ρ_ic Σ_j F_ij: the ∞-norm of K = diag(ρ)F, the contraction factor of every sweep.
    fn contraction(&self) -> f64 {
        (0..self.ff.len()).map(|i| self.reflectance[i].max_element() as f64 * self.ff.row_sum(i)).fold(0.0, f64::max)
    }

    /// Reference: (I − diag(ρ)F)B = E solved directly (Gaussian elimination, partial pivoting, f64) on
    /// the same f32-rounded F, per channel.
    fn direct_solution(&self) -> Vec<DVec3> {
        let n = self.ff.len();
        let mut out = vec![DVec3::ZERO; n];
        for c in 0..3 {
            let mut a: Vec<Vec<f64>> = (0..n)
                .map(|i| {
                    let mut row: Vec<f64> =
                        (0..n).map(|j| -(self.reflectance[i][c] as f64) * self.ff.get(i, j)).collect();
                    row[i] += 1.0;
                    row.push(self.emission[i][c] as f64);
                    row
                })
                .collect();
            for k in 0..n {
                let p = (k..n).max_by(|&x, &y| a[x][k].abs().total_cmp(&a[y][k].abs())).unwrap();
                a.swap(k, p);
                for i in k + 1..n {
                    let m = a[i][k] / a[k][k];
                    for j in k..=n {
                        a[i][j] -= m * a[k][j];
                    }
                }
            }
            for i in (0..n).rev() {
                let s: f64 = (i + 1..n).map(|j| a[i][j] * out[j][c]).sum();
                out[i][c] = (a[i][n] - s) / a[i][i];
            }
        }
        out
    }

    /// ||B − E − ρFB||∞.
    fn residual(&self, b: &[DVec3]) -> f64 {
        (0..self.ff.len())
            .map(|i| {
                let (c, f) = self.ff.row(i);
                let gathered = solver::gather(c, f, b);
                (b[i] - self.emission[i].as_dvec3() - self.reflectance[i].as_dvec3() * gathered).abs().max_element()
            })
            .fold(0.0, f64::max)
    }
}

fn max_abs(b: &[DVec3]) -> f64 {
    b.iter().map(|v| v.abs().max_element()).fold(0.0, f64::max)
}

fn max_abs_diff(a: &[DVec3], b: &[DVec3]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (*x - *y).abs().max_element()).fold(0.0, f64::max)
}

/// Bound on the relative (to max|B|) error a solver leaves when stopped at `tolerance`, for a system
/// with contraction factor q. Gauss-Seidel and Jacobi are contractions by q in the ∞-norm, so after a
/// sweep changing B by δ the error is ≤ δ q/(1 − q). Progressive refinement stopped at unshot fraction
/// τ leaves ΔB_i ≤ τ · (emitted power / smallest area) and an error ≤ ΔB_max q/(1 − q); `emitter_ratio`
/// is (emitted power / smallest area) / max|B| (≤ 6 in every scene here). SOR (ω = 1.2) is not a
/// ∞-norm contraction with the same factor; the factor 10 covers it and the emitter ratio.
fn solver_error_bound(tolerance: f64, q: f64) -> f64 {
    10.0 * tolerance * q / (1.0 - q)
}

fn furnace_system(case: &Value) -> System {
    let f = dense(&case["form_factors"]["F"]);
    let area = case["geometry"]["patches"].as_array().unwrap().iter().map(|p| p["area"].as_f64().unwrap() as f32);
    System {
        ff: FormFactors::from_dense(&f),
        reflectance: colours(&case["reflectance"]),
        emission: colours(&case["emission"]),
        area: area.collect(),
    }
}

#[test]
fn furnace_cases_match_exact_solutions() {
    let furnace = data("furnace.json");
    // The README asks for 1e-9·max|B| with a 1e-12 update tolerance — for F in f64.
    let tolerance = 1e-12;
    for case in furnace["cases"].as_array().unwrap() {
        let id = case["id"].as_str().unwrap();
        let system = furnace_system(case);
        let expected = colours_f64(&case["expected"]["B"]);
        let q = system.contraction();
        let scale = max_abs(&expected);
        // F rounded to f32 perturbs K = diag(ρ)F by ||δK||∞ ≤ u·q, which moves B by at most
        // ||(I − K)^-1||∞ ||δK||∞ ||B||∞ ≤ u·q/(1 − q)·max|B| (first order; the factor 2 covers the
        // second-order term and the exact F's own row-sum error, ≤ 7e-16). ρ = 0.9: 1.1e-6 relative.
        let f32_bound = 2.0 * F32_UNIT_ROUNDOFF * q / (1.0 - q);
        let direct = system.direct_solution();
        for solver in ALL_SOLVERS {
            let (b, stats) = system.solve(&params(solver, tolerance));
            assert!(stats.converged, "{id} {solver:?}");
            let to_exact = max_abs_diff(&b, &expected) / scale;
            let bound = f32_bound + solver_error_bound(tolerance, q);
            assert!(to_exact <= bound, "{id} {solver:?}: {to_exact:e} > {bound:e}");
            // Against a direct solve of the same f32 matrix the f32 term vanishes: the README's 1e-9.
            let to_direct = max_abs_diff(&b, &direct) / scale;
            assert!(to_direct <= 1e-9, "{id} {solver:?}: {to_direct:e} from the direct solve");
            println!("{id:36} {:12} {:5} iterations, {to_exact:.1e} from exact", solver.name(), stats.iterations);
        }
    }
}

/// The 96-patch unit cube (each face split 4×4) of enclosures.json with its exact F.
fn cube_4x4() -> (Value, FormFactors) {
    let enclosures = data("enclosures.json");
    let case =
        enclosures["cases"].as_array().unwrap().iter().find(|c| c["id"] == "enc_cube_split_4x4").unwrap().clone();
    let ff = FormFactors::from_dense(&dense(&case["expected"]["F"]));
    (case, ff)
}

fn patch_names(case: &Value) -> Vec<String> {
    case["geometry"]["patches"].as_array().unwrap().iter().map(|p| p["name"].as_str().unwrap().to_string()).collect()
}

#[test]
fn furnace_closed_cube_gives_e_over_one_minus_rho() {
    let (_, ff) = cube_4x4();
    let n = ff.len();
    let (rho, e) = (0.5f32, 1.0f32);
    let system = System {
        ff,
        reflectance: vec![Vec3::splat(rho); n],
        emission: vec![Vec3::splat(e); n],
        area: vec![1.0 / 16.0; n],
    };
    let q = system.contraction();
    let expected = (e / (1.0 - rho)) as f64;
    let tolerance = 1e-10;
    for solver in ALL_SOLVERS {
        let (b, stats) = system.solve(&params(solver, tolerance));
        assert!(stats.converged);
        // Row sums of the f32 matrix are 1 within u (plus 4.4e-16 from the data), which moves
        // B = E/(1 − ρ·rowsum) by u·q/(1 − q) relative; the solver adds its stopping error.
        let bound = expected * (2.0 * F32_UNIT_ROUNDOFF * q / (1.0 - q) + solver_error_bound(tolerance, q));
        for (i, bi) in b.iter().enumerate() {
            assert!((*bi - DVec3::splat(expected)).abs().max_element() <= bound, "{solver:?} patch {i}: {bi}");
        }
        println!("{:12} {:5} iterations", solver.name(), stats.iterations);
    }
}

const WHITE: Vec3 = Vec3::new(0.725, 0.71, 0.68);
const RED: Vec3 = Vec3::new(0.63, 0.065, 0.05);
const GREEN: Vec3 = Vec3::new(0.14, 0.45, 0.091);
/// A Cornell-box light: E = π · Ke with Ke = (17, 12, 4).
const LIGHT_EXITANCE: Vec3 =
    Vec3::new(17.0 * std::f32::consts::PI, 12.0 * std::f32::consts::PI, 4.0 * std::f32::consts::PI);

/// The 4×4-split cube coloured like a Cornell box: red wall x = 0, green wall x = 1, the rest white,
/// and one emitting ceiling patch z+[1,1].
fn cornell_cube() -> (Value, System) {
    let (case, ff) = cube_4x4();
    let names = patch_names(&case);
    let reflectance = names
        .iter()
        .map(|n| match &n[..2] {
            "x-" => RED,
            "x+" => GREEN,
            _ => WHITE,
        })
        .collect();
    let emission = names.iter().map(|n| if n == "z+[1,1]" { LIGHT_EXITANCE } else { Vec3::ZERO }).collect();
    let n = ff.len();
    (case, System { ff, reflectance, emission, area: vec![1.0 / 16.0; n] })
}

#[test]
fn solvers_agree_within_tolerance() {
    let (_, system) = cornell_cube();
    let reference = system.direct_solution();
    let scale = max_abs(&reference);
    let q = system.contraction();
    for tolerance in [1e-4, 1e-7] {
        let solutions: Vec<(SolverKind, Vec<DVec3>)> =
            ALL_SOLVERS.iter().map(|&s| (s, system.solve(&params(s, tolerance)).0)).collect();
        for (solver, b) in &solutions {
            let error = max_abs_diff(b, &reference) / scale;
            println!("tolerance {tolerance:e}: {:12} {error:.2e} from the direct solve", solver.name());
            assert!(error <= solver_error_bound(tolerance, q), "{solver:?}: {error:e}");
        }
        // Pairwise, then, within twice the bound.
        for (a, ba) in &solutions {
            for (b, bb) in &solutions {
                assert!(max_abs_diff(ba, bb) / scale <= 2.0 * solver_error_bound(tolerance, q), "{a:?} vs {b:?}");
            }
        }
    }
}

#[test]
fn overrelaxation_needs_fewer_sweeps_than_gauss_seidel_and_jacobi() {
    let (_, system) = cornell_cube();
    let tolerance = 1e-6;
    let sweeps = |solver: SolverKind, relaxation: f64| {
        let (_, stats) = system.solve(&RadiosityParams { relaxation, ..params(solver, tolerance) });
        assert!(stats.converged);
        stats.iterations
    };
    let jacobi = sweeps(SolverKind::Jacobi, 1.0);
    let gauss_seidel = sweeps(SolverKind::GaussSeidel, 1.0);
    let sor = sweeps(SolverKind::GaussSeidel, 1.2);
    let scan: Vec<(f64, u32)> =
        (0..=9).map(|k| 1.0 + 0.1 * k as f64).map(|w| (w, sweeps(SolverKind::GaussSeidel, w))).collect();
    println!("sweeps to {tolerance:e}: Jacobi {jacobi}, Gauss-Seidel {gauss_seidel}, SOR(1.2) {sor}");
    println!("SOR sweeps by ω: {scan:?}");
    assert!(sor < gauss_seidel, "SOR {sor} vs Gauss-Seidel {gauss_seidel}");
    assert!(gauss_seidel < jacobi, "Gauss-Seidel {gauss_seidel} vs Jacobi {jacobi}");
}

#[test]
fn residual_is_small() {
    let (_, system) = cornell_cube();
    let q = system.contraction();
    let tolerance = 1e-8;
    for solver in ALL_SOLVERS {
        let (b, _) = system.solve(&params(solver, tolerance));
        // r = (I − K)(B − B*), so ||r||∞ ≤ (1 + q)||B − B*||∞.
        let relative = system.residual(&b) / max_abs(&b);
        assert!(relative <= (1.0 + q) * solver_error_bound(tolerance, q), "{solver:?}: {relative:e}");
    }
}

#[test]
fn energy_check() {
    // README: in a closed enclosure with uniform ρ, Σ A_i B_i = Σ A_i E_i / (1 − ρ) for any E
    // (reciprocity and unit row sums). Uniform ρ = 0.6 on the 4×4 cube, E on a few patches only.
    let (_, ff) = cube_4x4();
    let n = ff.len();
    let rho = 0.6f32;
    let emission = (0..n).map(|i| if i % 17 == 3 { Vec3::new(5.0, 2.0, 1.0) * (i as f32 + 1.0) } else { Vec3::ZERO });
    let system =
        System { ff, reflectance: vec![Vec3::splat(rho); n], emission: emission.collect(), area: vec![1.0 / 16.0; n] };
    let q = system.contraction();
    let tolerance = 1e-10;
    let emitted: DVec3 = (0..n).map(|i| system.emission[i].as_dvec3() * system.area[i] as f64).sum();
    let expected = emitted / (1.0 - rho as f64);
    for solver in ALL_SOLVERS {
        let (b, _) = system.solve(&params(solver, tolerance));
        let total: DVec3 = (0..n).map(|i| b[i] * system.area[i] as f64).sum();
        // The f32 F breaks row sums and reciprocity by u relative (bound as in the furnace test); the
        // solver's error is a fraction of max|B| ≤ Σ A B / A_min = 16 Σ A B.
        let bound = 2.0 * F32_UNIT_ROUNDOFF * q / (1.0 - q) + 16.0 * solver_error_bound(tolerance, q);
        let relative = ((total - expected) / expected).abs().max_element();
        assert!(relative <= bound, "{solver:?}: {relative:e} > {bound:e}");
    }
}

/// A scene with one one-sided quad surface per patch of `case`, so that `Mesh::build` with unbounded
/// elements gives one element per patch, in patch order.
fn patch_scene(case: &Value, reflectance: &[Vec3], emission: &[Vec3]) -> SceneDescription {
    let mut materials = Vec::new();
    let mut surfaces = Vec::new();
    for (i, p) in case["geometry"]["patches"].as_array().unwrap().iter().enumerate() {
        let mut m = Material::diffuse(&format!("patch{i}"), reflectance[i]);
        m.emitted_radiance = emission[i] / std::f32::consts::PI;
        materials.push(m);
        let vertices: Vec<Vec3> = p["vertices"].as_array().unwrap().iter().map(colour).collect();
        surfaces.push(Surface { object: format!("patch{i}"), ..common::surface(vertices, i as u32, false) });
    }
    common::scene(materials, surfaces)
}

/// The validation cube as a scene (for its materials), its mesh and its linear system.
fn cornell_mesh() -> (SceneDescription, Mesh, System) {
    let (case, system) = cornell_cube();
    let scene = patch_scene(&case, &system.reflectance, &system.emission);
    let mesh = Mesh::build(&scene, f32::INFINITY);
    assert_eq!(mesh.elements.len(), system.ff.len());
    (scene, mesh, system)
}

/// The validation cube solved by Gauss-Seidel to 1e-6 (`solver::solve_solution`, uniform mesh).
fn gauss_seidel_solution(scene: &SceneDescription, mesh: &Mesh, system: &System) -> Solution {
    let gauss_seidel = params(SolverKind::GaussSeidel, 1e-6);
    let vertex_step = SmoothMesh::new(mesh);
    solver::solve_solution(mesh, &scene.materials, &system.ff, &gauss_seidel, &vertex_step, &mut |_, _| {})
}

#[test]
fn direct_part_is_first_bounce() {
    let (scene, mesh, system) = cornell_mesh();
    let solution = gauss_seidel_solution(&scene, &mesh, &system);
    // One Jacobi sweep from B = E is E + ρFE: the first bounce plus the emission.
    let one_bounce = RadiosityParams { max_iterations: 1, ..params(SolverKind::Jacobi, 0.0) };
    let (b1, _) = system.solve(&one_bounce);
    let e = &mesh.elements;
    for i in 0..e.len() {
        let emission = e.emission[i].as_dvec3();
        let (c, f) = system.ff.row(i);
        let gathered: DVec3 = c.iter().zip(f).map(|(&j, &f)| e.emission[j as usize].as_dvec3() * f as f64).sum();
        let direct = e.reflectance[i].as_dvec3() * gathered;
        let stored = solution.element_direct_exitance[i].as_dvec3();
        // Stored as f32: rounding 2^-24 relative, and the gathering order differs (f64, negligible).
        let tol = 2.0 * F32_UNIT_ROUNDOFF * direct.abs().max_element();
        assert!((stored - direct).abs().max_element() <= tol, "element {i}: {stored} vs {direct}");
        assert!((stored - (b1[i] - emission)).abs().max_element() <= tol, "element {i}: not the first Jacobi term");
        // Light reaches every patch but the emitter's own face in one bounce; the emitter's face gets none.
        let on_ceiling = e.normal[i].z < -0.5;
        assert_eq!(stored.max_element() > 0.0, !on_ceiling, "element {i}");
        // Emission excluded, interreflection excluded: direct < total − emission.
        let total = solution.element_exitance[i].as_dvec3();
        assert!((total - emission - stored).min_element() > -tol, "element {i}");
    }
    // Each patch has its own four vertices: their averages are the patch's value.
    for (i, corners) in e.corners.iter().enumerate() {
        for &v in corners {
            let (ve, ee) = (solution.vertex_direct_exitance[v as usize], solution.element_direct_exitance[i]);
            assert!((ve - ee).abs().max_element() <= 1e-6 * ee.abs().max_element().max(1e-30));
        }
    }
}

/// Area-weighted mean absolute error over elements and channels, relative to the reference's mean.
fn mean_relative_error(b: &[DVec3], reference: &[DVec3], area: &[f32]) -> f64 {
    let err: f64 = b.iter().zip(reference).zip(area).map(|((x, y), &a)| (*x - *y).abs().element_sum() * a as f64).sum();
    let norm: f64 = reference.iter().zip(area).map(|(y, &a)| y.abs().element_sum() * a as f64).sum();
    err / norm
}

#[test]
fn progressive_ambient_term_makes_partial_solution_closer() {
    let (_, system) = cornell_cube();
    let reference = system.direct_solution();
    let mut shooter = Shooter::new(&system.ff, &system.reflectance, &system.emission, &system.area);
    for shots in [1, 2, 5, 10, 20, 50, 96] {
        while shooter.shots() < shots {
            shooter.step().unwrap();
        }
        let without = mean_relative_error(shooter.exitance(), &reference, &system.area);
        let with = mean_relative_error(&shooter.exitance_with_ambient(), &reference, &system.area);
        println!("{shots:3} shots: mean relative error {without:.3e} without ambient, {with:.3e} with");
        assert!(with < without, "after {shots} shots: {with:e} with ambient, {without:e} without");
    }
    // The ambient term vanishes as the unshot exitance does.
    while shooter.unshot_fraction() > 1e-9 {
        shooter.step().unwrap();
    }
    assert!(shooter.ambient_exitance().max_element() <= 1e-8 * max_abs(&reference));
}

fn solved_cornell() -> (SceneDescription, Mesh, Solution) {
    let (scene, mesh, system) = cornell_mesh();
    let solution = gauss_seidel_solution(&scene, &mesh, &system);
    (scene, mesh, solution)
}

#[test]
fn solution_file_round_trips() {
    let (scene, mesh, solution) = solved_cornell();
    assert_eq!(solution.mesh_fingerprint, fingerprint(&mesh, &scene.materials));
    assert!(solution.stats.converged && !solution.stats.residual_history.is_empty());
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cornell.solution");
    solution.save(&path).unwrap();
    let loaded = Solution::load(&path, fingerprint(&mesh, &scene.materials)).unwrap();
    assert_eq!(loaded, solution);
}

#[test]
fn fingerprint_changes_with_geometry_or_any_material_property() {
    let (case, system) = cornell_cube();
    let scene = patch_scene(&case, &system.reflectance, &system.emission);
    let of = |scene: &SceneDescription, edge: f32| fingerprint(&Mesh::build(scene, edge), &scene.materials);
    let base = of(&scene, f32::INFINITY);
    assert_eq!(base, of(&scene, f32::INFINITY), "deterministic");
    assert_ne!(base, of(&scene, 0.2), "finer meshing");
    let mut recoloured = scene.clone();
    recoloured.materials[7].diffuse_reflectance.y += 0.01;
    assert_ne!(base, of(&recoloured, f32::INFINITY), "Kd");
    // Ks, Ni and d steer the extended form factors, so each one makes a saved solution stale.
    let mut mirrored = scene.clone();
    mirrored.materials[7].specular_reflectance = Vec3::splat(0.5);
    mirrored.materials[7].diffuse_reflectance *= 0.5;
    let mirror = of(&mirrored, f32::INFINITY);
    assert_ne!(base, mirror, "Ks");
    let mut glass = mirrored.clone();
    glass.materials[7].transmittance = 0.2;
    assert_ne!(mirror, of(&glass, f32::INFINITY), "d");
    let mut denser = glass.clone();
    denser.materials[7].ior = 1.7;
    assert_ne!(of(&glass, f32::INFINITY), of(&denser, f32::INFINITY), "Ni");
}

/// Saves the Cornell solution, lets `damage` change the bytes, loads them back.
fn load_damaged(damage: impl FnOnce(&mut Vec<u8>), fingerprint_delta: u64) -> SolutionFileError {
    let (scene, mesh, solution) = solved_cornell();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("damaged.solution");
    let mut bytes = solution.to_bytes();
    damage(&mut bytes);
    std::fs::write(&path, &bytes).unwrap();
    let err = Solution::load(&path, fingerprint(&mesh, &scene.materials) ^ fingerprint_delta).unwrap_err();
    assert!(err.to_string().contains(&path.display().to_string()), "the message names the file: {err}");
    err
}

#[test]
fn stale_solution_file_is_refused() {
    let err = load_damaged(|_| {}, 1);
    assert!(matches!(err, SolutionFileError::Stale { .. }), "{err:?}");
    let message = err.to_string();
    assert!(
        message.contains("solution was computed for a different scene or mesh; re-run `radray solve`"),
        "{message}"
    );
}

#[test]
fn foreign_file_is_refused() {
    let err = load_damaged(|b| *b = b"P6\n2 2\n255\n0123456789ab".to_vec(), 0);
    assert!(matches!(err, SolutionFileError::NotASolution { .. }), "{err:?}");
    let err = load_damaged(|b| b.clear(), 0);
    assert!(matches!(err, SolutionFileError::NotASolution { .. }), "empty file: {err:?}");
}

#[test]
fn unsupported_version_is_refused() {
    // The next version after every one this radray reads (2, 3 and 5 for hierarchical leaf meshes, 4
    // for adaptive refined meshes).
    let next =
        FILE_VERSION.max(FILE_VERSION_LEAF_MESH).max(FILE_VERSION_REFINED_MESH).max(FILE_VERSION_LEAF_MESH_CAUSTICS)
            + 1;
    let err = load_damaged(|b| b[FILE_MAGIC.len()..FILE_MAGIC.len() + 4].copy_from_slice(&next.to_le_bytes()), 0);
    assert!(
        matches!(err, SolutionFileError::UnsupportedVersion { found, supported: FILE_VERSION, .. } if found == next),
        "{err:?}"
    );
}

#[test]
fn truncated_file_is_refused() {
    for keep in [10, 40, 100, 1000] {
        let err = load_damaged(|b| b.truncate(keep), 0);
        assert!(matches!(err, SolutionFileError::Truncated { .. }), "{keep} bytes: {err:?}");
    }
    let err = load_damaged(|b| b.truncate(b.len() - 1), 0);
    assert!(matches!(err, SolutionFileError::Truncated { .. }), "{err:?}");
}

#[test]
fn corrupted_file_is_refused() {
    // A flipped bit in the element data, in the checksum, and an extra byte at the end.
    let err = load_damaged(|b| b[200] ^= 0x10, 0);
    assert!(matches!(err, SolutionFileError::Corrupted { .. }), "{err:?}");
    let err = load_damaged(|b| *b.last_mut().unwrap() ^= 1, 0);
    assert!(matches!(err, SolutionFileError::Corrupted { .. }), "{err:?}");
    let err = load_damaged(|b| b.push(0), 0);
    assert!(matches!(err, SolutionFileError::Corrupted { .. }), "{err:?}");
}

#[test]
fn missing_file_is_an_io_error() {
    let err = Solution::load(Path::new("/nonexistent/radray.solution"), 0).unwrap_err();
    assert!(matches!(err, SolutionFileError::Io { .. }) && err.to_string().contains("/nonexistent/radray.solution"));
}

#[test]
fn scene_without_emitter_solves_to_black() {
    let (scene, mesh, system) = cornell_mesh();
    let mut dark = mesh.clone();
    dark.elements.emission.iter_mut().for_each(|e| *e = Vec3::ZERO);
    let black = Solution::black(&dark, &scene.materials);
    assert_eq!(black.mesh_fingerprint, fingerprint(&dark, &scene.materials));
    assert!(black.stats.converged);
    for solver in ALL_SOLVERS {
        let computed = solver::solve_solution(
            &dark,
            &scene.materials,
            &system.ff,
            &params(solver, 1e-6),
            &SmoothMesh::new(&dark),
            &mut |_, _| {},
        );
        assert!(computed.stats.converged, "{solver:?}");
        assert_eq!(computed.element_exitance, black.element_exitance);
        assert_eq!(computed.vertex_exitance, black.vertex_exitance);
        assert_eq!(computed.element_direct_exitance, black.element_direct_exitance);
    }
}
