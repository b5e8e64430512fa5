//! Extended form factors through specular surfaces (Wallace, Cohen and Greenberg 1987) against closed
//! forms: a plane mirror shows the emitter's mirror image at Ks times its form factor, a glass slab
//! passes the Fresnel transmittance of its two interfaces, closed boxes with mirrors create no energy,
//! and diffuse scenes keep their plain form factors bit for bit.

mod common;

use common::hemicube_params;
use glam::Vec3;
use radray::accel::Accel;
use radray::mesh::Mesh;
use radray::radiosity::form_factors::{compute, compute_extended, FormFactors};
use radray::radiosity::specular::{SpecularPaths, SPECULAR_RESOLUTION_PX};
use radray::scene::{Material, SceneDescription};
use radray::transport::optics::fresnel_dielectric;
use radray::transport::photons::trace_photons;

const DIFFUSE: u32 = 0;
const EMITTER: u32 = 1;
const MIRROR: u32 = 2;
const GLASS: u32 = 3;
/// Mirror reflectance of the test mirrors.
const KS: f32 = 0.8;

fn materials() -> Vec<Material> {
    let grey = Material::diffuse("grey", Vec3::splat(0.5));
    vec![grey, common::emitter("light", Vec3::ONE), common::mirror("mirror", KS), common::glass("glass")]
}

/// One-sided surfaces (corners counter-clockwise about the front) with the materials above.
fn scene(surfaces: Vec<(Vec<Vec3>, u32)>) -> SceneDescription {
    let surfaces =
        surfaces.into_iter().map(|(vertices, material)| common::surface(vertices, material, false)).collect();
    common::scene(materials(), surfaces)
}

/// Plain and extended form factors of a scene's mesh.
fn extended(scene: &SceneDescription, mesh: &Mesh, resolution_px: u32) -> FormFactors {
    let accel = Accel::build(&mesh.positions, &mesh.triangles);
    let paths = SpecularPaths::new(mesh, &accel, &scene.materials);
    compute_extended(mesh, &hemicube_params(resolution_px), &paths, &|| {}).0
}

/// Axis-aligned rectangle at height y over [x0, x1] × [z0, z1], facing +y (`up`) or −y.
fn horizontal(y: f32, (x0, x1): (f32, f32), (z0, z1): (f32, f32), up: bool) -> Vec<Vec3> {
    let mut v = vec![Vec3::new(x0, y, z0), Vec3::new(x0, y, z1), Vec3::new(x1, y, z1), Vec3::new(x1, y, z0)];
    if !up {
        v.reverse();
    }
    v
}

/// A square receiver of half-width `half` at y = 1 facing down onto an 8 m mirror (y = 0, Ks = 0.8),
/// and a 1 m² emitter at y = 1.5 beside it, also facing down: the scene, its mesh (one element per
/// surface) and the emitter's corners.
fn mirror_scene(half: f32) -> (SceneDescription, Mesh, Vec<Vec3>) {
    let emitter = horizontal(1.5, (1.0, 2.0), (-0.5, 0.5), false);
    let s = scene(vec![
        (horizontal(1.0, (-half, half), (-half, half), false), DIFFUSE),
        (horizontal(0.0, (-4.0, 4.0), (-4.0, 4.0), true), MIRROR),
        (emitter.clone(), EMITTER),
    ]);
    let mesh = Mesh::build(&s, f32::INFINITY);
    assert_eq!(mesh.elements.len(), 3);
    (s, mesh, emitter)
}

/// Lambert's closed form for the form factor from a differential area at `p` with unit normal `n` to a
/// polygon it fully sees: F = (1/2π) Σ_k γ_k n·(R_k × R_k+1)/|R_k × R_k+1|, γ_k the angle between the
/// corner vectors R_k = v_k − p (orientation-free: the absolute value is returned).
fn lambert(p: Vec3, n: Vec3, poly: &[Vec3]) -> f64 {
    let mut sum = 0.0f64;
    for k in 0..poly.len() {
        let a = (poly[k] - p).as_dvec3().normalize();
        let b = (poly[(k + 1) % poly.len()] - p).as_dvec3().normalize();
        let c = a.cross(b);
        sum += a.dot(b).clamp(-1.0, 1.0).acos() * n.as_dvec3().dot(c.normalize());
    }
    (sum / (2.0 * std::f64::consts::PI)).abs()
}

/// The hemicube's eye for a one-element surface: its centre lifted by 1e-3·√area along the normal
/// (`form_factors::element_row`).
fn eye(mesh: &Mesh, i: usize) -> Vec3 {
    let e = &mesh.elements;
    e.centre[i] + e.normal[i] * (1e-3 * e.area[i].sqrt())
}

/// N_s: the resolution at which a hemicube of resolution N samples its specular pixels.
fn specular_resolution(n: u32) -> f64 {
    n.min(SPECULAR_RESOLUTION_PX) as f64
}

fn sum_of(part: (&[u32], &[f32]), j: usize) -> f64 {
    part.0.iter().zip(part.1).filter(|(&c, _)| c as usize == j).map(|(_, &f)| f as f64).sum()
}

/// A 0.1 m patch at y = 1 facing down onto an 8 m mirror (y = 0, Ks = 0.8); a 1 m² emitter at y = 1.5,
/// also facing down, is behind the patch's plane (no direct view) but its mirror image (y = −1.5) is in
/// full view. Then Fˢ(patch → emitter) = Ks × F(patch → mirror image) (Wallace et al. 1987), F by
/// Lambert's closed form. One ray per block of specular pixels samples the image polygon as a
/// hemicube of resolution N_s = min(N, SPECULAR_RESOLUTION_PX) samples a polygon, so the hemicube
/// tolerance 0.5/N_s (README of point_to_polygon.json) applies, scaled by Ks, plus 1e-5 for f32 sums
/// and ray offsets.
#[test]
fn plane_mirror_shows_the_emitter_image_at_ks_times_its_form_factor() {
    let (s, mesh, emitter) = mirror_scene(0.05);
    for n in [128u32, 256] {
        let ff = extended(&s, &mesh, n);
        assert_eq!(sum_of(ff.row_plain(0), 2), 0.0, "no straight view of the emitter");
        assert_eq!(sum_of(ff.row_plain(0), 1), 0.0, "the pure mirror's plain entry is dropped");
        let image: Vec<Vec3> = emitter.iter().map(|v| Vec3::new(v.x, -v.y, v.z)).collect();
        let expected = KS as f64 * lambert(eye(&mesh, 0), mesh.elements.normal[0], &image);
        let got = sum_of(ff.row_extended(0), 2);
        let tolerance = KS as f64 * 0.5 / specular_resolution(n) + 1e-5;
        assert!((got - expected).abs() <= tolerance, "N = {n}: Fˢ = {got} vs Ks·F = {expected} (±{tolerance})");
    }
}

/// Transmittance of a glass slab with n = 1.5 at incidence θ: two interfaces with reflectance R and
/// the internal reflections between them, T = (1 − R)² Σ_k R^2k = (1 − R)/(1 + R).
fn slab_transmittance(theta_rad: f32) -> f64 {
    let r = fresnel_dielectric(theta_rad.cos(), 1.0, 1.5) as f64;
    (1.0 - r) / (1.0 + r)
}

/// A 0.1 m patch on the floor facing up, a 2 m × 2 m emitter 2 m above facing down, and between them a
/// 2 mm glass slab (n = 1.5, a closed box of six one-sided faces) covering the whole view. The
/// emitter is then seen only through the slab: Fˢ = T(θ)·F with F the open form factor (Lambert) and T
/// the slab's transmittance, which over the emitter's incidence angles θ ≤ θ_max ≈ 35° lies between
/// T(θ_max) ≈ 0.917 and T(0) ≈ 0.923 (so a lossless slab, T = 1, fails). Tolerance: the hemicube's
/// 0.5/N_s (as above) plus 2e-4 for the slab bringing the emitter's image t(1 − 1/n) ≈ 0.7 mm closer
/// (F grows by ≈ 2·0.7 mm / 2 m ≈ 0.07 %) and the throughput cutoff (drops paths after R⁴ ≈ 3e-6).
#[test]
fn glass_slab_passes_its_fresnel_transmittance() {
    let emitter = horizontal(2.0, (-1.0, 1.0), (-1.0, 1.0), false);
    let (y0, y1, w) = (0.9f32, 0.902f32, 6.0f32);
    let c = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    let slab = vec![
        horizontal(y1, (-w, w), (-w, w), true),
        horizontal(y0, (-w, w), (-w, w), false),
        vec![c(w, y0, -w), c(w, y1, -w), c(w, y1, w), c(w, y0, w)],
        vec![c(-w, y0, -w), c(-w, y0, w), c(-w, y1, w), c(-w, y1, -w)],
        vec![c(-w, y0, w), c(w, y0, w), c(w, y1, w), c(-w, y1, w)],
        vec![c(-w, y0, -w), c(-w, y1, -w), c(w, y1, -w), c(w, y0, -w)],
    ];
    let mut surfaces = vec![(horizontal(0.0, (-0.05, 0.05), (-0.05, 0.05), true), DIFFUSE), (emitter.clone(), EMITTER)];
    surfaces.extend(slab.into_iter().map(|p| (p, GLASS)));
    let s = scene(surfaces);
    let mesh = Mesh::build(&s, f32::INFINITY);
    // Every slab face points outwards.
    for i in 2..8 {
        assert!(mesh.elements.normal[i].dot(mesh.elements.centre[i] - Vec3::new(0.0, 0.901, 0.0)) > 0.0, "face {i}");
    }
    let n = 256u32;
    let ff = extended(&s, &mesh, n);
    assert_eq!(sum_of(ff.row_plain(0), 1), 0.0, "the slab hides the emitter from straight view");
    let open = lambert(eye(&mesh, 0), Vec3::Y, &emitter);
    let theta_max = (1.0f32.hypot(1.0) / 2.0).atan();
    let tolerance = 0.5 / specular_resolution(n) + 2e-4;
    let got = sum_of(ff.row_extended(0), 1);
    let (lo, hi) = (slab_transmittance(theta_max) * open, slab_transmittance(0.0) * open);
    assert!(
        got >= lo - tolerance && got <= hi + tolerance,
        "Fˢ = {got}, expected T·F in [{lo}, {hi}] ± {tolerance} (open F = {open})"
    );
}

/// A 0.1 m patch on the floor facing up, 2 mm under an open glass sheet (one-sided, n = 1.5, its front
/// facing up: a water surface seen from below), and a 2 m × 2 m emitter 2 m above facing down. The
/// patch's hemicube sees the sheet's back; a ray through it leaves the medium, refracted, with
/// throughput (1 − R)·n² (the radiance outside read from inside the medium: L/n² is conserved), and
/// the cone it reaches outside is n² times wider in projected solid angle than the cone inside, so
/// Fˢ = (1 − R(θ))·F with F the open form factor and θ the angle in air, between 1 − R(θ_max) ≈ 0.958
/// and 1 − R(0) = 0.96. The back of a one-sided opaque surface would give 0 (it absorbs), as did a
/// dielectric one before session 25, which also counted the patch as buried. Tolerance as for the
/// slab.
#[test]
fn open_glass_sheet_passes_the_light_above_to_a_patch_beneath() {
    let emitter = horizontal(2.0, (-1.0, 1.0), (-1.0, 1.0), false);
    let patch = horizontal(0.0, (-0.05, 0.05), (-0.05, 0.05), true);
    let sheet = horizontal(0.002, (-6.0, 6.0), (-6.0, 6.0), true);
    let s = scene(vec![(patch, DIFFUSE), (emitter.clone(), EMITTER), (sheet, GLASS)]);
    let mesh = Mesh::build(&s, f32::INFINITY);
    assert!(mesh.back_refracts(2) && !mesh.back_refracts(0));
    let accel = Accel::build(&mesh.positions, &mesh.triangles);
    assert_eq!(radray::burial::hidden_share(&mesh, &accel)[0], 0.0, "the patch is not buried under the sheet");
    let n = 256u32;
    let ff = extended(&s, &mesh, n);
    assert_eq!(sum_of(ff.row_plain(0), 1), 0.0, "the sheet hides the emitter from straight view");
    assert_eq!(sum_of(ff.row_plain(0), 2), 0.0, "the sheet's back has no plain entry");
    let open = lambert(eye(&mesh, 0), Vec3::Y, &emitter);
    let theta_max = (1.0f32.hypot(1.0) / 2.0).atan();
    let transmitted = |theta: f32| 1.0 - fresnel_dielectric(theta.cos(), 1.0, 1.5) as f64;
    let tolerance = 0.5 / specular_resolution(n) + 2e-4;
    let got = sum_of(ff.row_extended(0), 1);
    let (lo, hi) = (transmitted(theta_max) * open, transmitted(0.0) * open);
    assert!(
        got >= lo - tolerance && got <= hi + tolerance,
        "Fˢ = {got}, expected (1 − R)·F in [{lo}, {hi}] ± {tolerance} (open F = {open})"
    );
}

/// The unit cube, inward-facing, with an emitting ceiling; `mirror_floor` makes the floor a mirror.
fn box_scene(mirror_floor: bool) -> SceneDescription {
    let c = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    let floor = horizontal(0.0, (0.0, 1.0), (0.0, 1.0), true);
    let ceiling = horizontal(1.0, (0.0, 1.0), (0.0, 1.0), false);
    let walls = vec![
        vec![c(0.0, 0.0, 0.0), c(1.0, 0.0, 0.0), c(1.0, 1.0, 0.0), c(0.0, 1.0, 0.0)],
        vec![c(0.0, 0.0, 1.0), c(0.0, 1.0, 1.0), c(1.0, 1.0, 1.0), c(1.0, 0.0, 1.0)],
        vec![c(0.0, 0.0, 0.0), c(0.0, 1.0, 0.0), c(0.0, 1.0, 1.0), c(0.0, 0.0, 1.0)],
        vec![c(1.0, 0.0, 0.0), c(1.0, 0.0, 1.0), c(1.0, 1.0, 1.0), c(1.0, 1.0, 0.0)],
    ];
    let mut surfaces = vec![(floor, if mirror_floor { MIRROR } else { DIFFUSE }), (ceiling, EMITTER)];
    surfaces.extend(walls.into_iter().map(|w| (w, DIFFUSE)));
    scene(surfaces)
}

/// In a closed box whose floor is a mirror (Ks = 0.8) every ray through a mirror pixel reflects once
/// (the floor is the only mirror and the reflected ray goes up) onto a diffuse wall (at N = 64 every
/// specular pixel is its own block), so each diffuse
/// row sums to Σ_diffuse F + Ks·F_mirror with F_mirror the dropped plain share of the mirror: at most
/// Σ ΔF ≤ 1 + 1/N² (mirrors with Ks ≤ 1 create no energy), and at least that figure less 0.5 % of
/// the mirrored share.
#[test]
fn mirror_box_rows_sum_to_at_most_one() {
    let s = box_scene(true);
    let mesh = Mesh::build(&s, 0.25 * 1.0001);
    let n = 64u32;
    let plain = compute(&mesh, &hemicube_params(n), &|| {});
    let ff = extended(&s, &mesh, n);
    let mirror: Vec<bool> = (0..mesh.elements.len()).map(|j| mesh.elements.material[j] == MIRROR).collect();
    let (mut rows, mut worst_deficit) = (0, 0.0f64);
    for i in 0..mesh.elements.len() {
        if mirror[i] {
            assert_eq!(ff.row(i).0.len(), 0, "a pure mirror needs no row");
            continue;
        }
        let (cols, vals) = plain.row(i);
        let (mut diffuse, mut mirrored) = (0.0, 0.0);
        for (&j, &f) in cols.iter().zip(vals) {
            if mirror[j as usize] {
                mirrored += f as f64;
            } else {
                diffuse += f as f64;
            }
        }
        let sum = ff.row_sum(i);
        assert!(sum <= 1.0 + 1.0 / (n * n) as f64 + 1e-5, "row {i}: Σ(F + Fˢ) = {sum}");
        let expected = diffuse + KS as f64 * mirrored;
        // Lower bound: the mirror returns Ks of its share, less 0.5 % of that share. Deficits were up to
        // 0.6 % while the accelerator's BVH missed walls hit exactly on an edge shared by two elements
        // (see `bvh_hits_a_wall_exactly_on_a_shared_element_edge`); with padded BVH boxes the worst is
        // 0.21 % at N = 64, from paths not yet accounted for (open: rays through the box's corners?).
        assert!(sum >= expected - 0.005 * mirrored, "row {i}: Σ(F + Fˢ) = {sum} vs {expected}");
        if mirrored > 0.0 {
            rows += 1;
            worst_deficit = worst_deficit.max((expected - sum) / mirrored);
        }
    }
    println!("{rows} rows see the mirror; worst deficit {:.3e} of the mirrored share", worst_deficit);
    assert!(rows > 50, "only {rows} rows see the mirror");
}

/// A scene without specular surfaces keeps exactly the plain form factors (no rays are traced), and
/// the extended ones do not depend on the thread count.
#[test]
fn diffuse_scenes_keep_plain_form_factors_bit_for_bit() {
    let s = box_scene(false);
    let mesh = Mesh::build(&s, 0.25 * 1.0001);
    let plain = compute(&mesh, &hemicube_params(64), &|| {});
    let accel = Accel::build(&mesh.positions, &mesh.triangles);
    let paths = SpecularPaths::new(&mesh, &accel, &s.materials);
    let (ff, stats) = compute_extended(&mesh, &hemicube_params(64), &paths, &|| {});
    assert_eq!(stats.rays, 0);
    assert_eq!(ff, plain);
    for i in 0..ff.len() {
        assert_eq!(ff.row_plain(i), ff.row(i));
    }

    let s = box_scene(true);
    let mesh = Mesh::build(&s, 0.25 * 1.0001);
    let run = |threads| {
        rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap().install(|| extended(&s, &mesh, 32))
    };
    assert_eq!(run(1), run(2));
}

/// The same mirror scene with a 1 m × 1 m receiver, its entry to the emitter taken from light traced
/// from the emitter (`SpecularPaths::with_light_paths`): Fˢ = Ks × the area-averaged form factor to the
/// mirror image, the average by the midpoint rule over 20 × 20 points of Lambert's closed form (error
/// < 0.1 %: F varies by ~10 % across the receiver, smoothly). Tolerance 5 %: the photon estimate's
/// standard error is 1/√k with k ≈ 1000 photons landing on the receiver (from `PHOTONS_PER_OBJECT` =
/// 2¹⁷ sent uniformly over the sphere of directions, since the emitter lies inside the mirror's bounding
/// sphere), about 3 %; the seed is fixed, so the result is deterministic (+1.7 % measured). 5 % is far
/// below the 20 % (1 − Ks) a missing mirror factor would make.
#[test]
fn light_paths_give_the_mirror_images_form_factor() {
    let (s, mesh, emitter) = mirror_scene(0.5);
    let accel = Accel::build(&mesh.positions, &mesh.triangles);
    let photons =
        trace_photons(&mesh, &accel, &s.materials, Some(&s.surfaces), |count, trace| (0..count).map(trace).collect())
            .expect("a mirror and an emitter");
    let paths =
        SpecularPaths::new(&mesh, &accel, &s.materials).with_shading_normals(&s.surfaces).with_light_paths(&photons);
    let ff = compute_extended(&mesh, &hemicube_params(128), &paths, &|| {}).0;
    let image: Vec<Vec3> = emitter.iter().map(|v| Vec3::new(v.x, -v.y, v.z)).collect();
    let m = 20;
    let mut average = 0.0;
    for a in 0..m {
        for b in 0..m {
            let p = Vec3::new(-0.5 + (a as f32 + 0.5) / m as f32, 1.0, -0.5 + (b as f32 + 0.5) / m as f32);
            average += lambert(p, -Vec3::Y, &image) / (m * m) as f64;
        }
    }
    let expected = KS as f64 * average;
    let got = sum_of(ff.row_extended(0), 2);
    println!("Fˢ = {got} vs Ks·F̄ = {expected}: {:+.2}%", 100.0 * (got / expected - 1.0));
    assert!((got / expected - 1.0).abs() <= 0.05, "Fˢ = {got} vs Ks·F̄ = {expected}");
}

/// A reflected ray of the mirror box above that was lost: from the mirror floor it meets the wall z = 0
/// at x = 0.5 exactly, the edge between two 0.25 m elements. The watertight triangle test hits the
/// triangle (0.25,0,0), (0.5,0,0), (0.5,0.25,0) at t ≈ 0.1514, but obvhs' compressed-BVH node test is
/// not conservative (slab test without the 1 + 2γ widening of Ize 2013): for a flat node (zero extent
/// in z) entered exactly on its x boundary t_min and t_max are equal up to rounding, and both
/// neighbouring nodes are culled. `accel` now builds the BVH from boxes widened by a few ulps
/// (`BOX_PADDING`); this ray was the "lost mirror paths" deficit of `mirror_box_rows_sum_to_at_most_one`.
#[test]
fn bvh_hits_a_wall_exactly_on_a_shared_element_edge() {
    let s = box_scene(true);
    let mesh = Mesh::build(&s, 0.25 * 1.0001);
    let accel = Accel::build(&mesh.positions, &mesh.triangles);
    let origin = Vec3::new(0.546957, 0.00001, 0.015652344);
    let dir = Vec3::new(-0.31010038, 0.9450678, -0.10336679);
    let ray = radray::accel::WatertightRay::new(origin, dir);
    let brute = mesh
        .triangles
        .iter()
        .filter_map(|tri| {
            let [a, b, c] = tri.map(|v| mesh.positions[v as usize]);
            ray.intersect(a, b, c, 0.0, f32::INFINITY).map(|h| h.t)
        })
        .fold(f32::INFINITY, f32::min);
    assert!(brute.is_finite(), "the ray meets a wall of the closed box");
    let hit = accel.closest_hit(origin, dir, 0.0, f32::INFINITY);
    assert_eq!(hit.map(|h| h.t), Some(brute), "BVH closest hit vs brute force");
}

/// The receiver of `mirror_scene` sees the emitter only in the mirror, so all its light comes by the
/// light paths (photons) of the emitter's extended form factors. Matrix-free shooting must follow them
/// as the stored matrix does (it once skipped them and left the receiver black). The two solve
/// reciprocal systems (hemicube reciprocity error, a few per cent at this resolution), so they agree
/// within 5 %.
#[test]
fn matrix_free_follows_the_light_paths_like_the_stored_matrix() {
    use radray::progress::Progress;
    use radray::radiosity::method::{FullMatrix, MatrixFree, PassOneMethod, Reuse};
    use radray::scene::SolverKind;
    use radray::transport::photons::RunPhotons;
    let (mut s, mesh, _) = mirror_scene(0.5);
    s.radiosity.hemicube_resolution_px = 128;
    s.radiosity.solver = SolverKind::Progressive;
    s.radiosity.tolerance = 1e-6;
    let receiver = |method: &dyn PassOneMethod| {
        let done = method.solve(&s, mesh.clone(), &mut Reuse::none(), &RunPhotons::default(), &Progress::hidden());
        done.unwrap().solution.element_exitance[0].x as f64
    };
    let stored = receiver(&FullMatrix { solver: SolverKind::Progressive });
    let matrix_free = receiver(&MatrixFree);
    println!("receiver exitance: stored matrix {stored}, matrix-free {matrix_free}");
    assert!(stored > 0.0, "the stored matrix must carry the mirrored light");
    assert!((matrix_free / stored - 1.0).abs() <= 0.05, "matrix-free {matrix_free} vs stored {stored}");
}

/// Radiance seen straight down through a 0.1-thick glass slab (a closed box of outward faces, half-width
/// 10, n = 1.5, d = 0, transmission filter `filter`) onto an emitter of Ke = 1 below it, by pass two's
/// final mode (the radiosity mode shows only the first hit's radiosity).
fn radiance_through_slab(filter: Vec3) -> Vec3 {
    use radray::film::Sampler;
    use radray::progress::Progress;
    use radray::run::{self, RunStats};
    use radray::trace::{RayCounts, TraceMode, Tracer};
    use radray::transport::photons::RunPhotons;
    let glass = Material { transmission_filter: filter, ..common::glass("tinted") };
    let materials = vec![common::emitter("light", Vec3::ONE), glass];
    let (y0, y1, w) = (0.5f32, 0.6f32, 10.0f32);
    let c = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    let slab = [
        horizontal(y1, (-w, w), (-w, w), true),
        horizontal(y0, (-w, w), (-w, w), false),
        vec![c(w, y0, -w), c(w, y1, -w), c(w, y1, w), c(w, y0, w)],
        vec![c(-w, y0, -w), c(-w, y0, w), c(-w, y1, w), c(-w, y1, -w)],
        vec![c(-w, y0, w), c(w, y0, w), c(w, y1, w), c(-w, y1, w)],
        vec![c(-w, y0, -w), c(-w, y1, -w), c(w, y1, -w), c(w, y0, -w)],
    ];
    let mut surfaces = vec![common::surface(horizontal(0.0, (-w, w), (-w, w), true), 0, false)];
    surfaces.extend(slab.into_iter().map(|p| common::surface(p, 1, false)));
    let s = common::scene(materials, surfaces);
    let mut stats = RunStats::default();
    let (mesh, solution) =
        run::pass_one(&s, None, &RunPhotons::default(), &Progress::hidden(), &mut stats).expect("pass one");
    let accel = Accel::build(&mesh.positions, &mesh.triangles);
    let tracer = Tracer::new(&mesh, &accel, &solution, &s.materials, &s.render).expect("tracer");
    let (mut sampler, mut counts) = (Sampler::independent(1, 1), RayCounts::default());
    tracer.radiance(Vec3::new(0.1, 2.0, 0.2), Vec3::NEG_Y, TraceMode::Final, &mut sampler, &mut counts)
}

/// MTL's Tf filters the light a transparent object lets through, once per passage through the object
/// (not once per interface): through a slab of filter Tf the emitter shows Tf·(1 − R)/(1 + R) per
/// channel, R = 0.04 at normal incidence (`slab_transmittance`). Tolerances: 1e-5 relative for the ratio
/// of two renders that differ only in Tf (f32 rounding); 1e-3 for the clear slab, whose internal
/// reflections are followed until the throughput cutoff.
#[test]
fn a_coloured_glass_slab_tints_the_light_it_passes_by_its_filter_colour() {
    let clear = radiance_through_slab(Vec3::ONE);
    let expected = slab_transmittance(0.0) as f32;
    assert!((clear - Vec3::splat(expected)).abs().max_element() < 1e-3, "clear slab {clear}, expected {expected}");
    let filter = Vec3::new(1.0, 0.5, 0.25);
    let tinted = radiance_through_slab(filter);
    let ratio = tinted / clear;
    assert!((ratio - filter).abs().max_element() < 1e-5, "tinted / clear = {ratio}, expected Tf = {filter}");
}

/// The caustic map's estimate of the mirror's light on `mirror_scene`'s 1 m × 1 m receiver, against
/// the closed form E(p) = Ks·π·L·F(p → the emitter's mirror image) (L = 1, Lambert's F), at 7 × 7
/// points at least a wide kernel's radius (0.16 m: 2 % of the scene's 8 m) from the receiver's edges,
/// where no kernel reaches past it. About 1,000 photons land on the receiver: 5 within a fine kernel
/// (r = 0.04 m), 80 within a wide one. The fine kernel alone scattered the estimate by a relative RMS
/// of 0.48 (worst point 0.88); the map now reads the wide kernel where the light is even at its scale
/// (`CausticMap::irradiance`): 0.106 (worst 0.300).
/// Bounds: 0.15, and 0.4 for the worst of 49 points (about 3σ of an 80-photon Epanechnikov estimate,
/// whose weights make it noisier than a plain count's 1/√80).
#[test]
fn the_caustic_map_reads_a_plane_mirrors_light_without_grain() {
    use radray::trace::caustics::CausticMap;
    use radray::transport::hit::scene_scale;
    let (s, mesh, emitter) = mirror_scene(0.5);
    let accel = Accel::build(&mesh.positions, &mesh.triangles);
    let photons =
        trace_photons(&mesh, &accel, &s.materials, Some(&s.surfaces), |count, trace| (0..count).map(trace).collect())
            .expect("a mirror and an emitter");
    let map = CausticMap::new(&mesh, &photons, scene_scale(&mesh));
    let image: Vec<Vec3> = emitter.iter().map(|v| Vec3::new(v.x, -v.y, v.z)).collect();
    let (mut sum, mut worst, mut count) = (0.0f64, 0.0f64, 0);
    for a in 0..7 {
        for b in 0..7 {
            let p = Vec3::new(-0.3 + 0.1 * a as f32, 1.0, -0.3 + 0.1 * b as f32);
            let exact = KS as f64 * std::f64::consts::PI * lambert(p, -Vec3::Y, &image);
            let got = map.irradiance(p, mesh.elements.surface[0]).x as f64;
            let error = got / exact - 1.0;
            sum += error * error;
            worst = worst.max(error.abs());
            count += 1;
        }
    }
    let rms = (sum / count as f64).sqrt();
    println!("caustic map on the receiver: relative RMS error {rms:.3}, worst {worst:.3} over {count} points");
    assert!(rms <= 0.15 && worst <= 0.4, "relative RMS error {rms}, worst {worst}");
}
