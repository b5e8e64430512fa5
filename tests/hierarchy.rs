//! The hierarchical radiosity solver (issue 10) against analytic cases (`tests/data/`), the furnace,
//! the full-matrix solver on the Cornell box, and its own invariants (push-pull conserves power,
//! refinement never raises the error estimate, thread-count independence, the memory budget).

mod common;

use common::{json_polygon as polygon, json_vec3 as vec3, validation_json as load_json};
use glam::{DVec3, Vec3};
use proptest::prelude::*;
use radray::radiosity::hierarchy::form_factor::{element_to_element, point_to_polygon};
use radray::radiosity::hierarchy::nodes::Nodes;
use radray::radiosity::hierarchy::ray_correction::IndirectEstimator;
use radray::radiosity::hierarchy::{self, clusters, gather, refine, solve as hsolve, HierarchyError, HierarchyParams};
use radray::scene::{
    self, Camera, ImageSettings, Material, RadiosityParams, RenderParams, SceneDescription, SourceLoc, Surface,
};

fn load_scene(name: &str) -> SceneDescription {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name);
    scene::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// A scene of one-sided surfaces with the given (reflectance, emitted radiance) per surface.
fn scene_of(surfaces: Vec<(Vec<Vec3>, f32, f32)>) -> SceneDescription {
    let mut materials = Vec::new();
    let mut out = Vec::new();
    for (i, (vertices, rho, ke)) in surfaces.into_iter().enumerate() {
        materials.push(Material {
            emitted_radiance: Vec3::splat(ke),
            ..Material::diffuse(&format!("m{i}"), Vec3::splat(rho))
        });
        out.push(Surface {
            vertices,
            material: i as u32,
            two_sided: false,
            shading_normals: None,
            uvs: None,
            object: "test".into(),
            source: SourceLoc::default(),
        });
    }
    SceneDescription {
        path: "test".into(),
        camera: Camera { eye: Vec3::ZERO, look_at: Vec3::Z, up: Vec3::Y, vfov_deg: 40.0 },
        image: ImageSettings::default(),
        radiosity: RadiosityParams::default(),
        render: RenderParams::default(),
        materials,
        surfaces: out,
        warnings: Vec::new(),
    }
}

/// Fan triangulation of a convex polygon.
fn fan(p: &[Vec3]) -> Vec<[Vec3; 3]> {
    (1..p.len() - 1).map(|i| [p[0], p[i], p[i + 1]]).collect()
}

/// Midpoint subdivision of a triangle, `levels` times (4^levels pieces).
fn subdivided(t: [Vec3; 3], levels: u32) -> Vec<[Vec3; 3]> {
    let mut tris = vec![t];
    for _ in 0..levels {
        tris = tris
            .into_iter()
            .flat_map(|[a, b, c]| {
                let (ab, bc, ca) = ((a + b) * 0.5, (b + c) * 0.5, (c + a) * 0.5);
                [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
            })
            .collect();
    }
    tris
}

fn area(t: &[Vec3; 3]) -> f64 {
    0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length() as f64
}

/// F_12 by the element estimator: receiver triangles subdivided `levels` times, each estimated against
/// every source triangle, area-weighted.
fn polygon_form_factor(p1: &[Vec3], p2: &[Vec3], levels: u32) -> f64 {
    let (mut af, mut a1) = (0.0, 0.0);
    for r in fan(p1).into_iter().flat_map(|t| subdivided(t, levels)) {
        let n = (r[1] - r[0]).cross(r[2] - r[0]).normalize();
        let a = area(&r);
        a1 += a;
        for s in fan(p2) {
            af += a * element_to_element(&r, n, &s).0;
        }
    }
    af / a1
}

/// Lambert's formula in f64 on f32 inputs: the references are 40-digit evaluations on f64 inputs, so
/// the difference is the rounding of the inputs to f32 (relative 1e-7 per coordinate, amplified by at
/// most a few) — 1e-6 relative, plus 1e-12 absolute for the tiny far case.
#[test]
fn lambert_point_to_polygon_matches_every_analytic_case() {
    let data = load_json("point_to_polygon.json");
    for case in data["cases"].as_array().unwrap() {
        let g = &case["geometry"];
        let f = point_to_polygon(vec3(&g["point"]), vec3(&g["point_normal"]).normalize(), &polygon(&g["polygon"]));
        let want = case["expected"]["F"].as_f64().unwrap();
        assert!((f - want).abs() <= 1e-6 * want + 1e-12, "{}: {f} vs {want}", case["id"]);
    }
}

/// The element-to-element estimator integrates the source exactly and the receiver with the
/// three-point rule; its error is the receiver quadrature. Measured on the twelve cases: worst relative
/// error 27.5% with each receiver as one or two triangles (level 0: a 0.5 × 3 plate receiving from
/// its 3 × 0.5 neighbour across a shared edge, which refinement always splits because its ΔF is
/// large) and 0.43% with each receiver triangle cut into 16 (level 2). Stated tolerance: 1% at level 2
/// (the perpendicular cases with a shared edge, where the integrand is log-singular at the edge, are
/// the worst); level 0 is printed, not bounded.
#[test]
fn element_estimator_matches_polygon_to_polygon_cases_within_its_stated_tolerance() {
    let data = load_json("polygon_to_polygon.json");
    let mut worst = [0.0f64; 2];
    for case in data["cases"].as_array().unwrap() {
        let g = &case["geometry"];
        let p1 = polygon(&g["polygon1"]["vertices"]);
        let p2 = polygon(&g["polygon2"]["vertices"]);
        for (k, levels) in [0u32, 2].into_iter().enumerate() {
            let f12 = polygon_form_factor(&p1, &p2, levels);
            let f21 = polygon_form_factor(&p2, &p1, levels);
            let want12 = case["expected"]["F12"].as_f64().unwrap();
            let want21 = case["expected"]["F21"].as_f64().unwrap();
            let e = ((f12 - want12) / want12).abs().max(((f21 - want21) / want21).abs());
            println!("{} level {levels}: F12 {f12:.6} (exact {want12:.6}), F21 {f21:.6} (exact {want21:.6}), rel. error {e:.2e}", case["id"]);
            worst[k] = worst[k].max(e);
        }
    }
    println!("worst relative error: level 0 {:.3e}, level 2 {:.3e}", worst[0], worst[1]);
    assert!(worst[1] <= 0.01, "level 2: {}", worst[1]);
}

/// Row sums of the unit cube's face-to-face form factors from the element estimator at level 2 are 1
/// within the 1% tolerance above, and each entry matches the exact value within it.
#[test]
fn element_estimator_closes_the_unit_cube_enclosure() {
    let data = load_json("enclosures.json");
    let case = &data["cases"][0];
    let patches: Vec<Vec<Vec3>> =
        case["geometry"]["patches"].as_array().unwrap().iter().map(|p| polygon(&p["vertices"])).collect();
    let exact = case["expected"]["F"].as_array().unwrap();
    for (i, pi) in patches.iter().enumerate() {
        let mut row = 0.0;
        for (j, pj) in patches.iter().enumerate() {
            let f = if i == j { 0.0 } else { polygon_form_factor(pi, pj, 2) };
            let want = exact[i][j].as_f64().unwrap();
            assert!((f - want).abs() <= 0.01 * want.max(0.2), "F[{i}][{j}] = {f}, exact {want}");
            row += f;
        }
        assert!((row - 1.0).abs() <= 0.01, "row {i} sums to {row}");
    }
}

/// The furnace (scenes/furnace.toml: closed unit cube, Kd 0.5, Ke 1): radiance 2 everywhere. Since
/// B = E/(1 − ρΣF), a leaf whose form factors (over its own and its ancestors' links) sum to 1 − δ is
/// off by about ρδ/(1 − ρ) = δ; the issue's bound is 1%, at the default ε. Measured: worst leaf
/// 0.48% at ε = 5e-3 (the default), 1.2% at 1e-2, 0.26% at 3e-3.
#[test]
fn furnace_closed_cube_gives_radiance_two_within_one_percent() {
    let scene = load_scene("furnace.toml");
    let solution = hierarchy::solve(&scene, &HierarchyParams::default(), &mut |_| {}).unwrap();
    let exact = 2.0 * std::f64::consts::PI;
    let mut worst = 0.0f64;
    for (b, a) in solution.leaf_exitance.iter().zip(&solution.leaf_area) {
        assert!(*a > 0.0);
        worst = worst.max(((b.x as f64 - exact) / exact).abs());
    }
    let s = &solution.stats;
    println!("furnace: {} elements, {} links, {} sweeps, worst leaf error {worst:.3e}", s.elements, s.links, s.sweeps);
    assert!(worst <= 0.01, "worst relative error {worst}");
    for v in &solution.mesh.vertex_exitance {
        assert!(((v.x as f64 - exact) / exact).abs() <= 0.01, "vertex {v}");
    }
}

/// Inside a closed cube every leaf sees its whole hemisphere: the links' row sums R = Σ_j F_ij
/// (`row_sums`: every node at exitance 1, pushed) are 1 within the furnace's 1% (measured: 0.9910 to
/// 1.0097 at the default ε). The sweeps converge, so the rows are not bounded.
#[test]
fn every_leaf_of_a_closed_cube_gathers_its_whole_hemisphere() {
    let scene = load_scene("furnace.toml");
    let (solution, structure) =
        hierarchy::solve_reusing(&scene, Default::default(), &HierarchyParams::default(), None, &mut |_| {}).unwrap();
    let (nodes, links) = (structure.nodes(), structure.links());
    let scales = gather::ArrivalScales::new(nodes, links);
    let sums = hierarchy::row_sums::row_sums(nodes, links, &scales);
    let leaves: Vec<usize> = (0..nodes.len()).filter(|&n| nodes.is_leaf(n)).collect();
    let (lo, hi) = leaves.iter().fold((f64::MAX, 0.0f64), |(lo, hi), &n| (lo.min(sums[n]), hi.max(sums[n])));
    println!("furnace: {} leaves, row sums {lo:.4} to {hi:.4}", leaves.len());
    assert!(lo >= 0.99 && hi <= 1.01, "row sums {lo} to {hi}");
    assert!(solution.stats.converged);
    assert_eq!((solution.stats.bounded_leaves, solution.stats.max_row_sum), (0, 0.0));
}

/// However far link estimates overshoot, the sweeps converge: with every form factor of the furnace
/// tripled (ρ·R = 1.5 ≥ 1, which diverged before the row bound, as pre-split Sponza did: B ×2.8 per
/// sweep on a leaf at ρ 0.47, R 2.7) the solve sees its exitance pass the physical limit, gives each
/// leaf the gain 1/R that brings its gathering back to its hemisphere, starts again, and converges to
/// the furnace's radiance 2 within 1%.
#[test]
fn tripled_form_factors_cannot_make_the_sweeps_diverge() {
    let scene = load_scene("furnace.toml");
    let (_, structure) =
        hierarchy::solve_reusing(&scene, Default::default(), &HierarchyParams::default(), None, &mut |_| {}).unwrap();
    let (mut nodes, mut links) = (structure.nodes().clone(), structure.links().clone());
    for f in &mut links.form_factor {
        *f *= 3.0;
    }
    let mut scales = gather::ArrivalScales::new(&nodes, &links);
    assert!(!scales.rows_bounded());
    hsolve::reset_to_emission(&mut nodes, structure.root());
    let mut largest = 0.0f64;
    let (sweeps, converged) = hsolve::solve_until(
        &mut nodes,
        &links,
        &mut scales,
        structure.root(),
        hsolve::SweepOrder::GaussSeidel,
        1.1,
        1e-5,
        200,
        &mut |_, c| largest = largest.max(c.max_exitance),
        &|| false,
    )
    .unwrap();
    let (overfull, max_row_sum) = scales.row_bound();
    assert!(max_row_sum > 2.9, "largest row sum {max_row_sum}");
    assert_eq!(overfull, (0..nodes.len()).filter(|&n| nodes.is_leaf(n)).count());
    // It passed the limit (twice the most a leaf could reach with its rows in their hemispheres).
    assert!(largest > hsolve::exitance_limit(&nodes, structure.root()), "largest exitance {largest}");
    let exact = 2.0 * std::f64::consts::PI;
    let mut worst = 0.0f64;
    for n in (0..nodes.len()).filter(|&n| nodes.is_leaf(n)) {
        worst = worst.max((nodes.exitance[n].x - exact).abs() / exact);
    }
    println!(
        "{overfull} leaves bounded (R up to {max_row_sum:.3}) after exitance {largest:.1}; {sweeps} sweeps, worst {worst:.2e}"
    );
    assert!(converged, "{sweeps} sweeps");
    assert!(worst <= 0.01, "worst relative error {worst}");
}

/// Two unit squares facing each other at distance 1 (tests/data/furnace.json, the open-environment
/// cases): B1 = (E1 + ρ1 F E2)/(1 − ρ1ρ2F²). Here F = 0.19982 must come from the element estimator
/// after refinement; its 1% tolerance on F moves B by at most 1% × ρF/(1 − ρ²F²) ≈ 0.1%, so 0.5% is
/// a safe bound that still catches a missing bounce (ρF ≈ 10%).
#[test]
fn two_facing_squares_match_the_closed_form_exchange() {
    let data = load_json("furnace.json");
    for case in data["cases"].as_array().unwrap() {
        if !case["id"].as_str().unwrap().starts_with("fur_two_unit_squares") {
            continue;
        }
        let patches = case["geometry"]["patches"].as_array().unwrap();
        let surfaces: Vec<(Vec<Vec3>, f32, f32)> = patches
            .iter()
            .enumerate()
            .map(|(k, p)| {
                let rho = case["reflectance"][k].as_f64().expect("reflectance") as f32;
                let e = case["emission"][k].as_f64().expect("emission") as f32;
                // E is exitance; radray's materials hold radiance Ke = E/π.
                (polygon(&p["vertices"]), rho, e / std::f32::consts::PI)
            })
            .collect();
        let scene = scene_of(surfaces);
        let solution = hierarchy::solve(&scene, &HierarchyParams::default(), &mut |_| {}).unwrap();
        let means = solution.surface_mean_exitance(2);
        for (k, want) in case["expected"]["B"].as_array().unwrap().iter().enumerate() {
            let want = want.as_f64().unwrap();
            let got = means[k].x;
            assert!(((got - want) / want).abs() <= 5e-3, "{} patch {k}: {got} vs {want}", case["id"]);
        }
    }
}

fn tiny_tree(levels: &[u8]) -> (Nodes, usize) {
    let mut nodes = Nodes::default();
    let root = nodes.push_element(
        [Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 3.0, 0.0)],
        0,
        0,
        Vec3::new(0.3, 0.5, 0.7),
        Vec3::new(1.0, 0.0, 2.0),
    ) as usize;
    // Subdivide the leaf picked by each entry (mod the current leaf count) once.
    for &pick in levels {
        let leaves: Vec<usize> = (0..nodes.len()).filter(|&n| nodes.is_leaf(n)).collect();
        nodes.subdivide(leaves[pick as usize % leaves.len()]);
    }
    (nodes, root)
}

proptest! {
    /// Push-pull conserves power: the irradiance pushed to the leaves carries the power gathered at
    /// every level (Σ_leaves A·G_total = Σ_nodes A·G_own), and the pulled root exitance carries the
    /// leaves' power (A_root·B_root = Σ_leaves A·B). f64 sums of O(10) terms: 1e-9 relative.
    #[test]
    fn push_pull_conserves_power(levels in proptest::collection::vec(0u8..255, 0..12),
                                 own in proptest::collection::vec(0.0f64..10.0, 64)) {
        let (nodes, root) = tiny_tree(&levels);
        let own_irradiance: Vec<DVec3> = (0..nodes.len()).map(|n| DVec3::new(own[n % 64], own[(n * 7 + 3) % 64], 1.0)).collect();
        let own_pushed: Vec<gather::Irradiance> = own_irradiance.iter().map(|&g| gather::Irradiance::uniform(g)).collect();
        let mut exitance = vec![DVec3::ZERO; nodes.len()];
        let total = gather::push_pull(&nodes, root, &own_pushed, &mut exitance);
        let leaves: Vec<usize> = (0..nodes.len()).filter(|&n| nodes.is_leaf(n)).collect();
        let pushed: DVec3 = leaves.iter().map(|&n| total[n] * nodes.area[n] as f64).sum();
        let gathered: DVec3 = (0..nodes.len()).map(|n| own_irradiance[n] * nodes.area[n] as f64).sum();
        prop_assert!((pushed - gathered).abs().max_element() <= 1e-9 * gathered.max_element());
        let leaf_power: DVec3 = leaves.iter().map(|&n| exitance[n] * nodes.area[n] as f64).sum();
        let root_power = exitance[root] * nodes.area[root] as f64;
        prop_assert!((leaf_power - root_power).abs().max_element() <= 1e-9 * root_power.max_element());
    }
}

/// Triangles of unit-ish size with the given normals, spread along x so that they cluster, each
/// counter-clockwise about its normal.
fn triangles_facing(normals: &[Vec3]) -> Vec<(Vec<Vec3>, f32, f32)> {
    normals
        .iter()
        .enumerate()
        .map(|(i, &n)| {
            let n = n.normalize();
            let u = n.any_orthonormal_vector();
            let v = n.cross(u);
            let c = Vec3::new(3.0 * i as f32, 0.0, 0.0);
            (vec![c, c + u, c + v], 0.5, 0.0)
        })
        .collect()
}

/// A far source element at `towards` × 1000 from the root's centre, facing back, and one link root
/// ← source of form factor `form_factor`; the source's exitance is 1.
/// One link receiver ← source whose form factor is the members' exact ones weighted by area:
/// F = Σ A_m F_m / A_receiver; returns the link and F.
fn link_of_member_form_factors(
    nodes: &Nodes,
    receiver: usize,
    source: usize,
    members: &[usize],
    member_form_factors: &[f64],
) -> (hierarchy::links::Links, f64) {
    let form_factor = members.iter().zip(member_form_factors).map(|(&m, f)| nodes.area[m] as f64 * f).sum::<f64>()
        / nodes.area[receiver] as f64;
    let links = hierarchy::links::Links::from_records(
        nodes.len(),
        vec![hierarchy::links::LinkRecord {
            receiver: receiver as u32,
            source: source as u32,
            form_factor: form_factor as f32,
            spread: 0.0,
        }],
    );
    (links, form_factor)
}

fn link_from(nodes: &mut Nodes, root: usize, towards: Vec3, form_factor: f32) -> hierarchy::links::Links {
    let c = nodes.centre[root] + towards * 1000.0;
    let (u, v) = (towards.any_orthonormal_vector(), towards.cross(towards.any_orthonormal_vector()));
    let source = nodes.push_element([c, c + v, c + u], u32::MAX - 1, 0, Vec3::ZERO, Vec3::ONE) as usize;
    hierarchy::links::Links::from_records(
        nodes.len(),
        vec![hierarchy::links::LinkRecord { receiver: root as u32, source: source as u32, form_factor, spread: 0.0 }],
    )
}

proptest! {
    /// A cluster receiver's link keeps its power through the push whatever its members' normals, in
    /// both of its forms (`gather::ArrivalScales`): as an arrival (each member by max(0, n·ω), scaled
    /// by A_R/D_open(ω)) and by member shares (each member's own form factor to the source). Σ_leaves
    /// A·G = A_R·F·B_S. The scales are f32 (rounding 6e-8 each) over f64 sums: 1e-6 relative. A member
    /// facing away from the arrival's direction gets nothing from it.
    #[test]
    fn a_cluster_link_keeps_its_power_over_any_member_normals(
        normals in proptest::collection::vec((-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0), 2..24),
        direction in (-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0),
    ) {
        let normals: Vec<Vec3> = normals.into_iter().map(|(x, y, z)| Vec3::new(x, y, z)).filter(|n| n.length() > 0.1).collect();
        let omega = Vec3::new(direction.0, direction.1, direction.2);
        prop_assume!(normals.len() >= 2 && omega.length() > 0.1);
        let omega = omega.normalize();
        let scene = scene_of(triangles_facing(&normals));
        let (mut nodes, root, inputs, _) = clusters::build(&scene).unwrap();
        let root = root as usize;
        prop_assume!(nodes.projected_area(root, omega) > 1e-3);
        let links = link_from(&mut nodes, root, omega, 1e-3);
        let power = 1e-3 * nodes.area[root] as f64;
        let leaves: Vec<usize> = (0..nodes.len()).filter(|&n| nodes.is_leaf(n) && n != links.source[0] as usize).collect();
        // As an arrival, built by hand (its direction is the link's).
        let towards = gather::arrival_direction(&nodes, root, links.source[0] as usize).unwrap();
        let scale = nodes.area[root] as f64 / nodes.open_projected_area(root, towards);
        let mut own = vec![gather::Irradiance::default(); nodes.len()];
        own[root].arrivals.push(gather::Arrival::directional(towards, DVec3::splat(1e-3 * scale)));
        let mut exitance = nodes.exitance.clone();
        let total = gather::push_pull(&nodes, root, &own, &mut exitance);
        let pushed: f64 = leaves.iter().map(|&n| total[n].x * nodes.area[n] as f64).sum();
        prop_assert!((pushed - power).abs() <= 1e-6 * power, "arrival: {pushed} vs {power}");
        for &n in &inputs.node {
            let n = n as usize;
            if nodes.normal[n].dot(towards) <= 0.0 {
                prop_assert_eq!(total[n], DVec3::ZERO);
            }
        }
        // As the solver builds it (member shares for these few pairs).
        let scales = gather::ArrivalScales::new(&nodes, &links);
        let own: Vec<gather::Irradiance> =
            (0..nodes.len()).map(|n| gather::gather(&nodes, &links, &scales, n, &nodes.exitance)).collect();
        let mut exitance = nodes.exitance.clone();
        let total = gather::push_pull(&nodes, root, &own, &mut exitance);
        let pushed: f64 = leaves.iter().map(|&n| total[n].x * nodes.area[n] as f64).sum();
        prop_assert!((pushed - power).abs() <= 1e-6 * power, "shares: {pushed} vs {power}");
    }
}

/// A cluster receiver's far link lights only the members that face the source: a cluster of a floor
/// triangle (facing +y) and a wall triangle (facing +x) under a source straight above (a small
/// element far away, facing down) gets all of the link's power on the floor and none on the wall.
/// The link is spread by the members' own form factors to the source (`gather::ArrivalScales`: two
/// pairs); the wall sees none of the source (it lies behind the wall's plane).
#[test]
fn a_cluster_receiver_pushes_a_far_link_to_the_members_facing_it() {
    let floor = vec![Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 0.0, 0.0)];
    let wall = vec![Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.0, 0.0, 1.0)];
    let scene = scene_of(vec![(floor, 0.5, 0.0), (wall, 0.5, 0.0)]);
    let (mut nodes, root, inputs, _) = clusters::build(&scene).unwrap();
    let root = root as usize;
    assert!(nodes.is_cluster[root]);
    // A source node straight above the floor, behind the wall's plane x = 0.
    let source = nodes.push_element(
        [Vec3::new(-1.0, 100.0, 0.0), Vec3::new(-0.5, 100.0, 0.0), Vec3::new(-1.0, 100.0, 0.5)],
        2, // an input triangle of its own
        0,
        Vec3::ZERO,
        Vec3::ONE,
    ) as usize;
    let links = radray::radiosity::hierarchy::links::Links::from_records(
        nodes.len(),
        vec![radray::radiosity::hierarchy::links::LinkRecord {
            receiver: root as u32,
            source: source as u32,
            form_factor: 1e-3,
            spread: 0.0,
        }],
    );
    let scales = gather::ArrivalScales::new(&nodes, &links);
    assert!(scales.receiver(root).has_shares(0));
    let own: Vec<gather::Irradiance> =
        (0..nodes.len()).map(|n| gather::gather(&nodes, &links, &scales, n, &nodes.exitance)).collect();
    let mut exitance = nodes.exitance.clone();
    let total = gather::push_pull(&nodes, root, &own, &mut exitance);
    let (floor, wall) = (inputs.node[0] as usize, inputs.node[1] as usize);
    let power = links.form_factor[0] as f64 * nodes.area[root] as f64;
    assert!((total[floor].x * nodes.area[floor] as f64 - power).abs() <= 1e-6 * power, "{total:?}");
    assert_eq!(total[wall], DVec3::ZERO);
}

/// The Cornell box's nodes with every leaf at its emission (before the first refinement), its root,
/// and the tracing triangles' acceleration structure.
fn cornell_at_emission() -> (SceneDescription, Nodes, usize, radray::accel::Accel) {
    let scene = load_scene("cornell_box.toml");
    let (mut nodes, root, _inputs, tracing) = clusters::build(&scene).unwrap();
    let root = root as usize;
    let accel = radray::accel::Accel::build(&tracing.positions, &tracing.triangles);
    hsolve::reset_to_emission(&mut nodes, root);
    (scene, nodes, root, accel)
}

/// Refinement settings on the Cornell box at relative threshold `relative` of its reference
/// exitance 0.22, elements down to 1/100 of its diagonal, a 1 GiB budget.
fn cornell_refine_settings(scene: &SceneDescription, relative: f64) -> refine::RefineSettings {
    refine::RefineSettings {
        threshold: relative * 0.22,
        floor_area: (scene.diagonal() / 100.0).powi(2),
        min_element_area: (scene.diagonal() / 100.0).powi(2),
        budget_bytes: 1 << 30,
        reference_exitance: 0.22,
        dark_receiver_floor: 1.0,
    }
}

/// The Cornell box's links from one refinement at its emission, with their arrival scales.
fn cornell_links() -> (Nodes, usize, hierarchy::links::Links, gather::ArrivalScales) {
    let (scene, mut nodes, root, accel) = cornell_at_emission();
    let ctx =
        hierarchy::visibility::VisibilityContext { accel: &accel, rays: 4, offset: scene.diagonal() * 1e-5, seed: 1 };
    let settings = cornell_refine_settings(&scene, 0.05);
    let links = refine::refine(&mut nodes, &ctx, Vec::new(), vec![root as u32], &settings, &mut |_, _, _| {}).links;
    let scales = gather::ArrivalScales::new(&nodes, &links);
    (nodes, root, links, scales)
}

/// A Jacobi sweep over the hierarchy adds exactly one bounce: from any exitance B^k (the emission,
/// then the sweep's own result), every leaf becomes B^{k+1} = S + ρ·G(B^k), G the irradiance its
/// links and its ancestors' links bring from B^k (`solve::leaf_irradiance`), whatever the order in
/// which the sweep reaches the leaves. A Gauss-Seidel sweep (ω = 1) from the same B^k is not that
/// (more than 1% of the bounce's largest change away): later leaves read values this sweep has
/// already changed. Same f64 arithmetic on both sides: 1e-12 relative.
#[test]
fn a_jacobi_sweep_over_the_hierarchy_adds_exactly_one_bounce() {
    let (mut nodes, root, links, scales) = cornell_links();
    let mut lobes = hierarchy::lobes::Lobes::new(&nodes, &links, root);
    let leaves: Vec<usize> = (0..nodes.len()).filter(|&n| nodes.is_leaf(n)).collect();
    let next_bounce = |nodes: &Nodes, lobes: &hierarchy::lobes::Lobes| -> Vec<DVec3> {
        let g = hsolve::leaf_irradiance(nodes, &links, &scales, &nodes.exitance, Some(lobes), root);
        leaves.iter().map(|&n| nodes.source_exitance(n) + nodes.reflectance[n].as_dvec3() * g[n]).collect()
    };
    let largest_difference = |nodes: &Nodes, want: &[DVec3]| {
        leaves.iter().zip(want).map(|(&n, w)| (nodes.exitance[n] - *w).abs().max_element()).fold(0.0f64, f64::max)
    };
    for bounce in 1..=3 {
        let want = next_bounce(&nodes, &lobes);
        let scale = want.iter().map(|w| w.max_element()).fold(0.0f64, f64::max);
        // The most this bounce changes any leaf.
        let step = largest_difference(&nodes, &want);
        let mut gauss_seidel = nodes.clone();
        hsolve::sweep(
            &mut gauss_seidel,
            &links,
            &scales,
            &mut lobes.clone(),
            root,
            hsolve::SweepOrder::GaussSeidel,
            1.0,
        );
        hsolve::sweep(&mut nodes, &links, &scales, &mut lobes, root, hsolve::SweepOrder::Jacobi, 1.7);
        let jacobi_error = largest_difference(&nodes, &want);
        assert!(jacobi_error <= 1e-12 * scale, "bounce {bounce}: Jacobi is {jacobi_error} off S + ρG(B)");
        let gauss_seidel_difference = largest_difference(&gauss_seidel, &want);
        assert!(
            gauss_seidel_difference > 0.01 * step,
            "bounce {bounce}: Gauss-Seidel {gauss_seidel_difference}, the bounce {step}"
        );
    }
}

/// Jacobi and Gauss-Seidel over the same links converge to the same solution (every leaf within
/// 1e-4 of the largest exitance, at a tolerance of 1e-7), Jacobi in more sweeps.
#[test]
fn jacobi_over_the_hierarchy_converges_to_the_gauss_seidel_solution() {
    let (nodes, root, links, scales) = cornell_links();
    let never = || false;
    let solve_in = |order| {
        let (mut nodes, mut scales) = (nodes.clone(), scales.clone());
        let (sweeps, converged) =
            hsolve::solve_until(&mut nodes, &links, &mut scales, root, order, 1.1, 1e-7, 500, &mut |_, _| {}, &never)
                .unwrap();
        assert!(converged, "{order:?} did not converge in {sweeps} sweeps");
        (nodes.exitance, sweeps)
    };
    let (gauss_seidel, gs_sweeps) = solve_in(hsolve::SweepOrder::GaussSeidel);
    let (jacobi, jacobi_sweeps) = solve_in(hsolve::SweepOrder::Jacobi);
    let largest = gauss_seidel.iter().map(|b| b.max_element()).fold(0.0f64, f64::max);
    let worst = (0..nodes.len())
        .filter(|&n| nodes.is_leaf(n))
        .map(|n| (jacobi[n] - gauss_seidel[n]).abs().max_element())
        .fold(0.0f64, f64::max);
    assert!(worst <= 1e-4 * largest, "largest leaf difference {worst} of {largest}");
    assert!(jacobi_sweeps > gs_sweeps, "Jacobi {jacobi_sweeps} sweeps, Gauss-Seidel {gs_sweeps}");
}

/// Refinement at a fixed exitance never raises the summed error estimate Σ ρ_R A_R B_S ΔF: a child
/// link's spread is capped by its parent's share. Checked over a run of passes with thresholds
/// falling by 2× each on the Cornell box, with the exitance of a first solve. Tolerance: the sums are
/// f64 over ≤ 10⁶ terms, 1e-9 relative.
#[test]
fn refinement_never_makes_the_error_estimate_grow() {
    let (scene, mut nodes, root, accel) = cornell_at_emission();
    let ctx =
        hierarchy::visibility::VisibilityContext { accel: &accel, rays: 4, offset: scene.diagonal() * 1e-5, seed: 1 };
    let mut settings = cornell_refine_settings(&scene, 0.3);
    let first = refine::refine(&mut nodes, &ctx, Vec::new(), vec![root as u32], &settings, &mut |_, _, _| {});
    hsolve::solve(&mut nodes, &first.links, root, 1.0, 1e-3, 100, &mut |_, _| {});
    let mut links = first.links;
    for pass in 0..5 {
        settings.threshold *= 0.5;
        let out = refine::refine(&mut nodes, &ctx, links.to_records(), Vec::new(), &settings, &mut |_, _, _| {});
        println!(
            "pass {pass}: error {:.6e} → {:.6e} W, {} links",
            out.error_before_w,
            out.error_after_w,
            out.links.len()
        );
        assert!(out.error_after_w <= out.error_before_w * (1.0 + 1e-9), "pass {pass}: {out:?}");
        links = out.links;
    }
}

/// A receiver's share of the allowed error, clamp(B_R/Ē, δ, 1): whole at or above the scene's mean
/// emitted exitance Ē, in proportion to its exitance below it, never under δ; δ = 1 (the first
/// pass) and a scene that emits nothing (Ē = 0) judge every receiver alike.
#[test]
fn a_receiver_darker_than_the_mean_emission_keeps_a_share_of_the_error_in_proportion() {
    let share = refine::dark_receiver_share;
    assert_eq!(share(2.0, 1.0, 0.25), 1.0);
    assert_eq!(share(1.0, 1.0, 0.25), 1.0);
    assert_eq!(share(0.5, 1.0, 0.25), 0.5);
    assert_eq!(share(0.1, 1.0, 0.25), 0.25);
    assert_eq!(share(0.0, 1.0, 0.25), 0.25);
    assert_eq!(share(0.1, 1.0, 1.0), 1.0);
    assert_eq!(share(0.1, 0.0, 0.25), 1.0);
    let settings = refine::RefineSettings {
        threshold: 0.01,
        floor_area: 0.5,
        min_element_area: 0.5,
        budget_bytes: 1 << 30,
        reference_exitance: 2.0,
        dark_receiver_floor: 0.25,
    };
    // ε·Ē·max(A, A_min)·s: a bright 4 m² receiver, a half-bright one, one below the floor area.
    assert!((settings.allowed_error_w(4.0, 3.0) - 0.04).abs() < 1e-12);
    assert!((settings.allowed_error_w(4.0, 1.0) - 0.02).abs() < 1e-12);
    assert!((settings.allowed_error_w(0.1, 0.0) - 0.01 * 0.5 * 0.25).abs() < 1e-12);
}

/// Holding dark receivers to a relative error refines them, not the bright ones: on the Cornell box,
/// after a first solve, a pass with δ = 1/4 makes more than twice the links of δ = 1 into receivers
/// darker than Ē, and within 2% of the same number into the brighter ones (not exactly the same: a
/// dark receiver's link may split a bright source element, which a bright receiver's links then
/// find split).
#[test]
fn holding_dark_receivers_to_a_relative_error_refines_them_not_the_bright_ones() {
    let (scene, mut nodes, root, accel) = cornell_at_emission();
    let ctx =
        hierarchy::visibility::VisibilityContext { accel: &accel, rays: 4, offset: scene.diagonal() * 1e-5, seed: 1 };
    let reference_exitance = 0.22;
    let settings = refine::RefineSettings {
        threshold: 0.05 * reference_exitance,
        floor_area: (scene.diagonal() / 100.0).powi(2),
        min_element_area: (scene.diagonal() / 100.0).powi(2),
        budget_bytes: 1 << 30,
        reference_exitance,
        dark_receiver_floor: 1.0,
    };
    let first = refine::refine(&mut nodes, &ctx, Vec::new(), vec![root as u32], &settings, &mut |_, _, _| {});
    hsolve::solve(&mut nodes, &first.links, root, 1.0, 1e-3, 100, &mut |_, _| {});
    let count = |floor: f64| {
        let mut nodes = nodes.clone();
        let settings = refine::RefineSettings { dark_receiver_floor: floor, ..settings };
        let out = refine::refine(&mut nodes, &ctx, first.links.to_records(), Vec::new(), &settings, &mut |_, _, _| {});
        let (mut bright, mut dark) = (0usize, 0usize);
        for l in out.links.to_records() {
            if nodes.exitance_mean[l.receiver as usize] >= reference_exitance {
                bright += 1;
            } else {
                dark += 1;
            }
        }
        (bright, dark)
    };
    let (alike, relative) = (count(1.0), count(0.25));
    println!("links into bright, dark receivers: δ = 1 {alike:?}, δ = 1/4 {relative:?}");
    assert!(alike.0 > 0 && alike.1 > 0, "{alike:?}");
    assert!(relative.0.abs_diff(alike.0) * 50 <= alike.0, "{relative:?} against {alike:?}");
    assert!(relative.1 > alike.1 * 2, "{relative:?} against {alike:?}");
}

/// Mean exitance per input surface on the Cornell box, hierarchy against the full-matrix hemicube
/// solver (25 mm elements, 128² hemicubes). The floor under the blocks is left out of both means: the
/// blocks have no bottoms, and a hemicube there sees the light through the blocks' back faces (the
/// full-matrix floor is 30% brighter than an independent per-element probe for that reason; the
/// hierarchy's floor matches the probe within 0.5%). Stated tolerance: 3% of each surface's mean, or 1%
/// of the brightest non-emitting surface for dim ones: the hierarchy's element links err ≤ 1% (the
/// estimator test) and the hemicube's delta form factors +0.54/N² in sum (tests/form_factors.rs).
///
/// Met since session 12 (squared six-bin weights, link-end Sobol nets, the near-link estimator exact
/// in each sampled source element): every surface within its bound, the floor worst at 91% of it
/// (red channel 0.400 against 0.420), the ceiling 0.290 against 0.301 (49%); 1.88 M links, 50k
/// leaves. Until then it was ignored: at the default ε = 5e-3 (1.44 M links) the floor was 0.92 of
/// the matrix, the ceiling 0.89, block sides 0.83–0.96, worst at 246% of the bound, and the gap did
/// not close with ε (1e-2: 445%, 3e-2: 599%), so it was not the refinement tolerance.
///
/// Session 5 (`examples/hierarchy_agreement`, 256² hemicubes): on the empty box, where every link is
/// element to element and the estimator agrees with a 768-point quadrature within 0.01% and the
/// link visibility with 256 rays within 0.1%, the surfaces are still 1.5–3.7% darker (ceiling worst).
/// On this box, with cluster links forbidden, the walls stay 4–6% and block sides 5–10% darker, so
/// the bulk of the gap is not the cluster links. What the cluster links did cause, one irradiance
/// pushed to members facing different ways, is fixed (oriented push, `gather::gather`): the short
/// block's side facing the tall block went from 1.47–1.97 of the matrix to 1.08–1.24.
#[test]
fn hierarchy_agrees_with_the_full_matrix_solver_on_the_cornell_box() {
    use radray::mesh::Mesh;
    use radray::radiosity::{form_factors, solver};
    let mut s = load_scene("cornell_box.toml");
    s.radiosity.hemicube_resolution_px = 128;
    let mesh = Mesh::build(&s, s.radiosity.max_element_edge);
    let ff = form_factors::compute(&mesh, &s.radiosity, &|| {});
    let e = &mesh.elements;
    let (b, _) = solver::solve(&ff, &e.reflectance, &e.emission, &e.area, &s.radiosity, &mut |_, _| {});
    let (mut pos, mut tris) = (Vec::new(), Vec::new());
    for surf in &s.surfaces {
        let v = &surf.vertices;
        let base = pos.len() as u32;
        pos.extend_from_slice(v);
        tris.push([base, base + 1, base + 2]);
        if v.len() == 4 {
            tris.push([base, base + 2, base + 3]);
        }
    }
    let accel = radray::accel::Accel::build(&pos, &tris);
    // A floor point is under a block when the first thing straight above it is a face seen from behind.
    let under_block = |c: Vec3| {
        accel.closest_hit(c + Vec3::Y * 0.01, Vec3::Y, 0.0, f32::INFINITY).is_some_and(|h| {
            let [a, b, c] = tris[h.triangle as usize].map(|i| pos[i as usize]);
            (b - a).cross(c - a).y > 0.0
        })
    };
    let n = s.surfaces.len();
    let (mut sum, mut area) = (vec![DVec3::ZERO; n], vec![0.0f64; n]);
    for (i, bi) in b.iter().enumerate() {
        let k = e.surface[i] as usize;
        if k >= n || (k == 0 && under_block(e.centre[i])) {
            continue;
        }
        sum[k] += bi.as_dvec3() * e.area[i] as f64;
        area[k] += e.area[i] as f64;
    }
    let full: Vec<DVec3> = sum.iter().zip(&area).map(|(s, a)| *s / *a).collect();
    let solution = hierarchy::solve(&s, &HierarchyParams::default(), &mut |_| {}).unwrap();
    let (mut sum, mut area) = (vec![DVec3::ZERO; n], vec![0.0f64; n]);
    for i in 0..solution.leaf_area.len() {
        let k = solution.leaf_surface[i] as usize;
        let t = solution.mesh.triangles[i].map(|v| solution.mesh.positions[v as usize]);
        if solution.leaf_back[i] || (k == 0 && under_block((t[0] + t[1] + t[2]) / 3.0)) {
            continue;
        }
        sum[k] += solution.leaf_exitance[i].as_dvec3() * solution.leaf_area[i] as f64;
        area[k] += solution.leaf_area[i] as f64;
    }
    let hier: Vec<DVec3> = sum.iter().zip(&area).map(|(s, a)| *s / *a).collect();
    let emitter = |k: usize| s.materials[s.surfaces[k].material as usize].is_emitter();
    let brightest = (0..n).filter(|&k| !emitter(k)).map(|k| full[k].max_element()).fold(0.0, f64::max);
    let mut worst = 0.0f64;
    for k in 0..n {
        let diff = (hier[k] - full[k]).abs().max_element();
        let bound = (0.03 * full[k].max_element()).max(0.01 * brightest);
        println!("surface {k}: full {:.3?} hierarchy {:.3?} ({:.0}% of bound)", full[k], hier[k], 100.0 * diff / bound);
        worst = worst.max(diff / bound);
    }
    println!("hierarchy: {:?}", solution.stats);
    assert!(worst <= 1.0, "worst surface at {:.0}% of its bound", worst * 100.0);
}

/// Same values, bit for bit, with one rayon thread and with four: refinement decides each round's
/// links in parallel and estimates kept near links after the round (the budget-limited run keeps
/// near links it may not split, which get their form factor that way). Links measured by hemicubes
/// (`link_form_factors = "hemicube"`) too: each receiver's hemicube is drawn on its own.
#[test]
fn results_do_not_depend_on_the_thread_count() {
    let scene = load_scene("cornell_box.toml");
    let limited = HierarchyParams { memory_bytes: 200_000, ..HierarchyParams::preview() };
    let hemicubes =
        HierarchyParams { link_form_factors: scene::LinkFormFactors::Hemicube, ..HierarchyParams::preview() };
    for params in [HierarchyParams::preview(), limited, hemicubes] {
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| hierarchy::solve(&scene, &params, &mut |_| {}).unwrap())
        };
        let (a, b) = (run(1), run(4));
        assert_eq!(a.stats, b.stats);
        let bits = |s: &hierarchy::HierarchicalSolution| {
            s.leaf_exitance.iter().map(|v| v.to_array().map(f32::to_bits)).collect::<Vec<_>>()
        };
        assert_eq!(bits(&a), bits(&b));
    }
}

/// A budget below what the input needs is refused before anything is built; a budget that fits the
/// input but not the refinement keeps coarser links, says so, and still solves.
#[test]
fn the_memory_budget_is_kept_and_reported() {
    let scene = load_scene("cornell_box.toml");
    let tiny = HierarchyParams { memory_bytes: 1000, ..HierarchyParams::preview() };
    assert!(matches!(hierarchy::solve(&scene, &tiny, &mut |_| {}), Err(HierarchyError::OverBudget { .. })));
    let small = HierarchyParams { memory_bytes: 200_000, ..HierarchyParams::preview() };
    let solution = hierarchy::solve(&scene, &small, &mut |_| {}).unwrap();
    assert!(solution.stats.budget_exceeded);
    assert!(solution.stats.peak_bytes <= 200_000, "{:?}", solution.stats);
    assert!(solution.leaf_exitance.iter().any(|b| b.max_element() > 0.0));
}

/// Conforming interpolation: a hanging node is a vertex m at the midpoint of a leaf's edge (a, b)
/// where finer leaves on the other side have the edges (a, m) and (m, b) (same vertex indices, so the
/// same smoothing group). Every hanging node must carry the mean of a and b, so that Gouraud shading
/// along the coarse edge and along the two fine edges is the same line (no T-vertex crack). Tolerance:
/// f32 vertex values, 1e-5 relative.
#[test]
fn hanging_nodes_take_their_edges_interpolated_value() {
    let scene = load_scene("cornell_box.toml");
    let solution = hierarchy::solve(&scene, &HierarchyParams::preview(), &mut |_| {}).unwrap();
    let m = &solution.mesh;
    let mut edges = std::collections::HashSet::new();
    for t in &m.triangles {
        for e in 0..3 {
            let (a, b) = (t[e], t[(e + 1) % 3]);
            edges.insert((a.min(b), a.max(b)));
        }
    }
    let mut at = std::collections::HashMap::new();
    for (i, p) in m.positions.iter().enumerate() {
        at.entry(p.to_array().map(f32::to_bits)).or_insert_with(Vec::new).push(i as u32);
    }
    let has = |a: u32, b: u32| edges.contains(&(a.min(b), a.max(b)));
    let mut hanging = 0;
    for &(a, b) in &edges {
        let mid = ((m.positions[a as usize] + m.positions[b as usize]) * 0.5).to_array().map(f32::to_bits);
        for &v in at.get(&mid).into_iter().flatten() {
            if !(has(a, v) && has(v, b)) {
                continue;
            }
            hanging += 1;
            let want = (m.vertex_exitance[a as usize] + m.vertex_exitance[b as usize]) * 0.5;
            let got = m.vertex_exitance[v as usize];
            assert!(
                (got - want).abs().max_element() <= 1e-5 * want.max_element().max(1e-6),
                "hanging node {v} on edge ({a}, {b}): {got} vs {want}"
            );
        }
    }
    println!("{hanging} hanging nodes");
    assert!(hanging > 0, "the preview solution of the Cornell box has subdivided neighbours");
}

/// A wall written as two upright strips of one material beside a stair (x ∈ [0, 0.3] and [0.3, 0.6]
/// on the floor plane y = 0, the second strip half a step higher), each a stack of 1 m quads, so that
/// the strips' corners lie inside each other's edges and no edge is shared: two smoothing groups. Under
/// a linear field every leaf's fit reads the other strip's leaves at the T-junctions, so the field is
/// exact (f32 rounding, 1e-5) at every vertex of the shared line x = 0.3 where both strips run
/// (z ∈ [0.5, 2.5]). Each strip alone, the higher strip's corner inside the lower one's edge is
/// extrapolated from its own bottom pair, whose slope the limit holds back: off by 0.15, the field's
/// change across a strip.
#[test]
fn leaves_of_strips_that_meet_at_t_junctions_read_each_others_slope() {
    let quad = |x0: f32, x1: f32, z0: f32, z1: f32| {
        let v = vec![Vec3::new(x0, 0.0, z0), Vec3::new(x0, 0.0, z1), Vec3::new(x1, 0.0, z1), Vec3::new(x1, 0.0, z0)];
        (v, 0.5, 0.0)
    };
    let mut surfaces: Vec<_> = (0..3).map(|k| quad(0.0, 0.3, k as f32, k as f32 + 1.0)).collect();
    surfaces.extend((0..2).map(|k| quad(0.3, 0.6, 0.5 + k as f32, 1.5 + k as f32)));
    let mut scene = scene_of(surfaces);
    for surface in &mut scene.surfaces {
        surface.material = 0;
    }
    let field = |p: Vec3| 1.0 + p.x as f64 + 0.3 * p.z as f64;
    let (mut nodes, root, inputs, _) = clusters::build(&scene).unwrap();
    for n in 0..nodes.len() {
        if !nodes.is_cluster[n] {
            nodes.exitance[n] = DVec3::splat(field(nodes.centre[n]));
        }
    }
    let mesh = hierarchy::interpolate::leaf_mesh(&nodes, &inputs, root as usize);
    assert!(!mesh.contacts.is_empty(), "the strips' corners lie inside each other's edges");
    let groups: std::collections::HashSet<u32> = mesh.leaf_group.iter().copied().collect();
    assert_eq!(groups.len(), 2, "strips meeting at T-junctions stay groups of their own");
    let exitance: Vec<DVec3> = mesh.leaf_node.iter().map(|&n| nodes.exitance[n as usize]).collect();
    let mut alone = mesh.clone();
    alone.contacts.clear();
    alone.leaf_family.clear();
    let alone = alone.vertex_values(&exitance);
    let error = |values: &[Vec3], v: usize| (values[v].x as f64 - field(mesh.positions[v])).abs();
    let on_line = |v: usize| {
        let p = mesh.positions[v];
        (p.x - 0.3).abs() < 1e-6 && (0.5..=2.5).contains(&p.z)
    };
    let largest =
        |values: &[Vec3]| (0..values.len()).filter(|&v| on_line(v)).map(|v| error(values, v)).fold(0.0, f64::max);
    assert!(largest(&alone) > 0.1, "each strip alone: {}", largest(&alone));
    assert!(largest(&mesh.vertex_exitance) < 1e-5, "read across the junctions: {}", largest(&mesh.vertex_exitance));
}

/// Two 4 × 2.6 × 4 m rooms side by side along z, separated by a 0.2 m wall made, as in
/// scenes/rooms/, of two one-sided faces that each face into their own room (z = 4 faces the lit
/// room, z = 4.2 the dark one). Every face is a `grid` × `grid` field of quads, so the cluster tree
/// holds clusters with pieces of both rooms and of both wall faces. The lamp is a 1 × 1 m ceiling
/// panel in the lit room only. Returns the scene and, per surface, whether it lies in the dark room.
fn two_rooms_through_a_wall(grid: u32) -> (SceneDescription, Vec<bool>) {
    let (w, h, wall_z, thickness) = (4.0f32, 2.6f32, 4.0f32, 0.2f32);
    let mut surfaces = Vec::new();
    let mut dark = Vec::new();
    // (origin, u, v) with u × v pointing into the room; rho, Ke.
    let mut face = |o: Vec3, u: Vec3, v: Vec3, rho: f32, in_dark: bool| {
        let n = grid as f32;
        for j in 0..grid {
            for i in 0..grid {
                let p = |a: u32, b: u32| o + u * (a as f32 / n) + v * (b as f32 / n);
                surfaces.push((vec![p(i, j), p(i + 1, j), p(i + 1, j + 1), p(i, j + 1)], rho, 0.0));
                dark.push(in_dark);
            }
        }
    };
    for (z0, z1, in_dark) in [(0.0, wall_z, false), (wall_z + thickness, 2.0 * wall_z + thickness, true)] {
        let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
        let d = z1 - z0;
        face(Vec3::new(0.0, 0.0, z0), z * d, x * w, 0.5, in_dark); // floor, +y
        face(Vec3::new(0.0, h, z0), x * w, z * d, 0.75, in_dark); // ceiling, −y
        face(Vec3::new(0.0, 0.0, z0), y * h, z * d, 0.7, in_dark); // x = 0, +x
        face(Vec3::new(w, 0.0, z0), z * d, y * h, 0.7, in_dark); // x = w, −x
        face(Vec3::new(0.0, 0.0, z0), x * w, y * h, 0.7, in_dark); // z = z0, +z
        face(Vec3::new(0.0, 0.0, z1), y * h, x * w, 0.7, in_dark); // z = z1, −z
    }
    // The lamp, 1 mm below the lit room's ceiling, facing down, 1.5 m from the wall.
    let y = h - 1e-3;
    let (x0, z0) = (1.5, wall_z - 2.5);
    surfaces.push((
        vec![
            Vec3::new(x0, y, z0),
            Vec3::new(x0 + 1.0, y, z0),
            Vec3::new(x0 + 1.0, y, z0 + 1.0),
            Vec3::new(x0, y, z0 + 1.0),
        ],
        0.0,
        10.0,
    ));
    dark.push(false);
    (scene_of(surfaces), dark)
}

/// Light that reaches the dark room of `two_rooms_through_a_wall` (W, the leaves' largest channel
/// times their area), the worst dark leaf (W/m²) and the lit room's power, solved at `params`.
fn leak_through_the_wall(scene: &SceneDescription, dark: &[bool], params: &HierarchyParams) -> (f64, f32, f64) {
    let solution = hierarchy::solve(scene, params, &mut |_| {}).unwrap();
    let (mut leaked_w, mut lit_w, mut worst) = (0.0f64, 0.0f64, 0.0f32);
    for i in 0..solution.leaf_area.len() {
        let power = solution.leaf_exitance[i].max_element() as f64 * solution.leaf_area[i] as f64;
        if dark[solution.leaf_surface[i] as usize] {
            leaked_w += power;
            worst = worst.max(solution.leaf_exitance[i].max_element());
        } else {
            lit_w += power;
        }
    }
    println!(
        "threshold {}: dark room {leaked_w:.4} W (worst leaf {worst:.4} W/m²), lit room {lit_w:.1} W; {:?}",
        params.error_threshold, solution.stats
    );
    (leaked_w, worst, lit_w)
}

/// No light path joins the two rooms, so every leaf of the dark room must stay exactly black: light
/// there can only have leaked through the wall (a cluster link whose visibility was assumed, or whose
/// irradiance was pushed to children behind the wall). Exact zero, not a tolerance: ray visibility
/// through a closed wall is 0 whatever the sampling, so a correct solver adds exactly nothing.
///
/// History: session 12, 0.4295 W of 90.9 W at the preview threshold; session 15 (docs/accuracy.md)
/// found two ways in, both through clusters that hold pieces of both sides of the wall: the self-link
/// of a cluster of the whole dark room plus one lit-side wall triangle (its exitance averaged into
/// what the self-link sends), and links from lit sources into a 3-member cluster whose dark-room member
/// faces the lit room through the wall (member shares and arrivals light it). Main 021e86e: 0.0542 W
/// (preview) and 0.0601 W (default). Both clusters came from the cluster build's count median cutting
/// the lit wall face (all its centroids on z = 4) by index, so that one lit triangle went with the
/// dark room; `clusters::median_split` now keeps a group of equal centroid coordinates on one side,
/// the dark room is a subtree of its own, and every link between the rooms is blocked by the wall
/// (session 16). For the same rooms turned off the world axes see
/// `light_does_not_leak_through_a_wall_turned_off_the_axes`.
#[test]
fn light_does_not_leak_through_a_wall_into_a_dark_room() {
    let (scene, dark) = two_rooms_through_a_wall(4);
    let measured: Vec<_> = [HierarchyParams::preview(), HierarchyParams::default()]
        .iter()
        .map(|params| leak_through_the_wall(&scene, &dark, params))
        .collect();
    // Asserted after both thresholds are solved, so that a failure prints the figures of both.
    for (leaked_w, _, lit_w) in measured {
        assert!(lit_w > 0.0);
        assert_eq!(leaked_w, 0.0, "{leaked_w} W leaked into the dark room (lit room: {lit_w} W)");
    }
}

/// The two rooms of `two_rooms_through_a_wall` turned about y (7° and 30°) leak nothing either, and
/// the lit room keeps the power it has unturned within 2%. The cluster tree is split and boxed along
/// the scene's principal frame (`SceneDescription::frame`), so the turned wall's faces tie again in
/// the median split. Until session 20 the tree was split along the world axes, no coordinates tied,
/// and the turned rooms leaked (30°: 3.23 W at preview and 0.087 W at default, with the lit room at
/// 71.7 W against 87.6 W unturned; 7°: 0.85 W / 0.129 W; docs/accuracy.md, session 16).
#[test]
fn light_does_not_leak_through_a_wall_turned_off_the_axes() {
    let (scene, dark) = two_rooms_through_a_wall(4);
    let params = HierarchyParams::preview();
    let (_, _, unturned_lit_w) = leak_through_the_wall(&scene, &dark, &params);
    let mut measured = Vec::new();
    for angle_deg in [7.0f32, 30.0] {
        let turn = glam::Quat::from_rotation_y(angle_deg.to_radians());
        let mut turned = scene.clone();
        for surface in &mut turned.surfaces {
            for v in &mut surface.vertices {
                *v = turn * *v;
            }
        }
        measured.push((angle_deg, leak_through_the_wall(&turned, &dark, &params)));
    }
    for (angle_deg, (leaked_w, _, lit_w)) in measured {
        assert_eq!(leaked_w, 0.0, "turned {angle_deg}°: {leaked_w} W leaked into the dark room (lit room: {lit_w} W)");
        assert!(
            (lit_w / unturned_lit_w - 1.0).abs() < 0.02,
            "turned {angle_deg}°: lit room {lit_w} W, unturned {unturned_lit_w} W"
        );
    }
}

/// The lit room of `two_rooms_through_a_wall` alone (the six faces of the room, then its lamp), the
/// room's faces `two_sided` as given (the lamp stays one-sided: two-sided, it would also light the
/// ceiling 1 mm above it).
fn one_room(grid: u32, two_sided: bool) -> SceneDescription {
    let (mut scene, dark) = two_rooms_through_a_wall(grid);
    let mut keep = dark.iter().map(|&d| !d);
    scene.surfaces.retain(|_| keep.next().unwrap());
    let lamp = scene.surfaces.len() - 1;
    for surface in &mut scene.surfaces[..lamp] {
        surface.two_sided = two_sided;
    }
    scene
}

/// A room whose surfaces are all made two-sided gathers what it gathers one-sided: the backs face out
/// of the room and see nothing, so they stay black and the fronts' exitance is unchanged (the full
/// matrix gives the same pixels either way). Per face of the room (floor, ceiling, four walls),
/// power within 2% and the whole room's within 1%, at the default threshold. (At the preview's the
/// two differ by 3% the other way: the two-sided room is refined further by its links between the
/// sides, and the one-sided room's preview is itself 3% below its default.)
///
/// History (session 17): the two sides of a triangle share its centroid, so the cluster build kept
/// them together down to clusters of one front and its back, and a cluster sends the area-weighted
/// mean of its members' exitance, half of a lit front's: this room two-sided lost 3–5% of its light
/// and its walls came out blotchy (scenes/rooms made two-sided: alcove_hall relMSE 0.00157 → 0.0294,
/// l_room 0.00189 → 0.0157); the root of the cluster tree now splits fronts from backs.
#[test]
fn a_room_made_two_sided_gathers_what_it_gathers_one_sided() {
    let grid = 4;
    let faces = |solution: &hierarchy::HierarchicalSolution, with_backs: &mut f64| {
        let mut power = [0.0f64; 7];
        for i in 0..solution.leaf_area.len() {
            let w = solution.leaf_exitance[i].max_element() as f64 * solution.leaf_area[i] as f64;
            if solution.leaf_back[i] {
                *with_backs += w;
            } else {
                power[(solution.leaf_surface[i] / (grid * grid)) as usize] += w;
            }
        }
        power
    };
    let params = HierarchyParams::default();
    let one = hierarchy::solve(&one_room(grid, false), &params, &mut |_| {}).unwrap();
    let two = hierarchy::solve(&one_room(grid, true), &params, &mut |_| {}).unwrap();
    let (mut backs_one, mut backs_two) = (0.0, 0.0);
    let (p1, p2) = (faces(&one, &mut backs_one), faces(&two, &mut backs_two));
    let (t1, t2): (f64, f64) = (p1[..6].iter().sum(), p2[..6].iter().sum());
    println!("one-sided {p1:.3?} (room {t1:.3} W), two-sided {p2:.3?} (room {t2:.3} W, backs {backs_two:.3e} W)");
    assert_eq!(backs_one, 0.0);
    // `at_most` is false for NaN, so a NaN fails.
    let at_most = |x: f64, bound: f64| x <= bound;
    let mut failures = Vec::new();
    if !at_most(backs_two, 1e-9 * t1) {
        failures.push(format!("backs of the room's faces got {backs_two} W"));
    }
    if !at_most((t2 / t1 - 1.0).abs(), 0.01) {
        failures.push(format!("room {t2:.3} W two-sided against {t1:.3} W one-sided"));
    }
    for face in 0..6 {
        if !at_most((p2[face] / p1[face] - 1.0).abs(), 0.02) {
            failures.push(format!("face {face}: {:.3} W two-sided against {:.3} W one-sided", p2[face], p1[face]));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Two clusters over the fan triangles of `p1` and `p2`, each triangle cut `levels` times, and a ray
/// accelerator over all their triangles (nothing else in the scene). Returns (nodes, receiver, source,
/// accel).
fn two_clusters(p1: &[Vec3], p2: &[Vec3], levels: u32) -> (Nodes, usize, usize, radray::accel::Accel) {
    two_clusters_with(p1, p2, levels, &[])
}

/// `two_clusters`, with the fan triangles of polygon `blockers` (if any) in the ray accelerator only.
fn two_clusters_with(
    p1: &[Vec3],
    p2: &[Vec3],
    levels: u32,
    blockers: &[Vec3],
) -> (Nodes, usize, usize, radray::accel::Accel) {
    let mut nodes = Nodes::default();
    let (mut positions, mut triangles) = (Vec::new(), Vec::new());
    let mut ends = [0usize; 2];
    for (k, p) in [p1, p2].into_iter().enumerate() {
        let cluster = nodes.push_cluster_slot() as usize;
        let first = nodes.len() as u32;
        let pieces: Vec<[Vec3; 3]> = fan(p).into_iter().flat_map(|t| subdivided(t, levels)).collect();
        for t in &pieces {
            nodes.push_element(*t, 0, 0, Vec3::splat(0.5), Vec3::ZERO);
            let base = positions.len() as u32;
            positions.extend_from_slice(t);
            triangles.push([base, base + 1, base + 2]);
        }
        nodes.set_cluster_children(cluster, first, u8::try_from(pieces.len()).unwrap());
        ends[k] = cluster;
    }
    if blockers.len() >= 3 {
        for t in fan(blockers) {
            let base = positions.len() as u32;
            positions.extend_from_slice(&t);
            triangles.push([base, base + 1, base + 2]);
        }
    }
    let accel = radray::accel::Accel::build(&positions, &triangles);
    (nodes, ends[0], ends[1], accel)
}

/// Two unit squares facing each other across z = 0 … 2 (the receiver at z = 0 facing +z, the source
/// at z = 2 facing −z, each a cluster of its two triangles) and, if `occluded`, a plate at z = 1 over
/// x < 0.5 (two triangles, wider than both squares). A segment from (x₁, ·, 0) to (x₂, ·, 2) crosses
/// z = 1 at (x₁ + x₂)/2, so it is blocked iff x₁ + x₂ < 1: for points uniform on both squares the
/// unoccluded fraction is exactly 1/2. Returns (nodes, receiver, source, accel).
fn facing_squares(occluded: bool) -> (Nodes, usize, usize, radray::accel::Accel) {
    facing_squares_behind(occluded.then_some(0.5))
}

/// `facing_squares` with the plate over x < `plate_x` (none for `None`): a segment is blocked iff
/// x₁ + x₂ < 2·plate_x.
fn facing_squares_behind(plate_x: Option<f32>) -> (Nodes, usize, usize, radray::accel::Accel) {
    let receiver =
        [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(1.0, 1.0, 0.0), Vec3::new(0.0, 1.0, 0.0)];
    let source =
        [Vec3::new(0.0, 0.0, 2.0), Vec3::new(0.0, 1.0, 2.0), Vec3::new(1.0, 1.0, 2.0), Vec3::new(1.0, 0.0, 2.0)];
    let plate = plate_x.map(|x| {
        [Vec3::new(-5.0, -5.0, 1.0), Vec3::new(x, -5.0, 1.0), Vec3::new(x, 6.0, 1.0), Vec3::new(-5.0, 6.0, 1.0)]
    });
    two_clusters_with(&receiver, &source, 0, plate.as_ref().map_or(&[], |p| p.as_slice()))
}

/// An element link whose rays all come out blocked is measured again with more rays where the light
/// they may have missed matters, and then kept for refinement, not dropped. Two unit squares face
/// each other 2 apart with a plate halfway that leaves a slit of pairs open (blocked iff x₁ + x₂ <
/// 1.96, an open share of 0.0008 of uniform pairs), so that every ray of a link between two of their
/// triangles is blocked. With n rays blocked the light it may carry is that of V ≤ 1/(n + 1), a
/// spread of (ΔF₆ + 2·F_unoccluded)/(n + 1). Below the threshold the link is dropped; above it,
/// n = `BLOCKED_CONFIRM_FACTOR` × 8 = 32 rays are traced, and the link is kept with F = 0 and the
/// spread for 32, so that refinement splits it while that matters. Until session 40 it was dropped
/// after 8 rays wherever its light mattered: vault_hall lost 2.5% of its walls' direct light.
#[test]
fn an_element_link_with_every_ray_blocked_is_confirmed_and_kept_where_its_light_matters() {
    use hierarchy::form_factor::{element_six_points, near_quadrature};
    use hierarchy::links::{estimate, link_error_power};
    use hierarchy::visibility::{link_visibility, VisibilityContext, BLOCKED_CONFIRM_FACTOR};
    let (mut nodes, r, s, accel) = facing_squares_behind(Some(0.98));
    let ctx = VisibilityContext { accel: &accel, rays: 8, offset: 1e-4, seed: 1 };
    let (re, se) = (nodes.children(r).next().unwrap(), nodes.children(s).next().unwrap());
    nodes.exitance_mean[se] = 1.0;
    assert_eq!(link_visibility(&ctx, &nodes, re, se).visible, 0.0, "every ray blocked");
    let (q3, six_point_spread, near) = element_six_points(&nodes.corners[re], nodes.normal[re], &nodes.corners[se]);
    let unoccluded = if near { near_quadrature(&nodes.corners[re], nodes.normal[re], &nodes.corners[se]) } else { q3 };
    assert!(unoccluded > 0.01, "the triangles face each other: F = {unoccluded}");
    let spread_of = |rays: u32| (six_point_spread + 2.0 * unoccluded) / (rays as f64 + 1.0);
    let error_w = link_error_power(&nodes, re, se, spread_of(8) as f32);
    assert_eq!(estimate(&nodes, &ctx, re, se, f32::MAX, 2.0 * error_w, 1e-4), None, "its light does not matter");
    let (form_factor, spread) = estimate(&nodes, &ctx, re, se, f32::MAX, 0.5 * error_w, 1e-4)
        .expect("a blocked link whose light matters is kept");
    assert_eq!(form_factor, 0.0);
    let expected = spread_of(8 * BLOCKED_CONFIRM_FACTOR);
    assert!((spread as f64 - expected).abs() <= 1e-6 * expected, "spread {spread}, not {expected}");
}

/// The confirming rays find the light the first N missed. A link between the squares' first
/// triangles with the plate over all but a strip of their pairs (blocked iff x₁ + x₂ < 1.4, an open
/// share of about 0.12) reads V = 0 from 8 rays on some seeds, as (1 − 0.12)⁸ ≈ 0.36 would have
/// it. Where its light matters, those seeds' links are measured with 32 rays, and on most of them
/// ((1 − 0.12)²⁴ ≈ 0.05) F comes out above 0.
#[test]
fn confirming_rays_find_the_light_of_a_link_whose_first_rays_were_all_blocked() {
    use hierarchy::links::estimate;
    use hierarchy::visibility::{link_visibility, VisibilityContext};
    let (mut nodes, r, s, accel) = facing_squares_behind(Some(0.7));
    let (re, se) = (nodes.children(r).next().unwrap(), nodes.children(s).next().unwrap());
    nodes.exitance_mean[se] = 1.0;
    let (mut missed_by_eight, mut still_dark) = (0, 0);
    for seed in 0..64 {
        let ctx = VisibilityContext { accel: &accel, rays: 8, offset: 1e-4, seed };
        if link_visibility(&ctx, &nodes, re, se).visible > 0.0 {
            continue;
        }
        missed_by_eight += 1;
        let (form_factor, _) = estimate(&nodes, &ctx, re, se, f32::MAX, 0.0, 1e-4).expect("kept");
        if form_factor <= 0.0 || form_factor.is_nan() {
            still_dark += 1;
        }
    }
    assert!(missed_by_eight >= 8, "{missed_by_eight} of 64 seeds' 8 rays all blocked");
    assert!(4 * still_dark <= missed_by_eight, "{still_dark} of {missed_by_eight} still dark after confirming");
}

/// Independent pairs give V's binomial variance V(1 − V)/N; the estimator before session 12 (x
/// stratified in its triangle's first coordinate, N strata, everything else independent: a cluster
/// member picked at random per point) is reproduced here as the yardstick.
fn visibility_before_session_12(
    ctx: &hierarchy::visibility::VisibilityContext,
    nodes: &Nodes,
    receiver: usize,
    source: usize,
) -> f64 {
    use hierarchy::visibility::{link_seed, triangle_point};
    use radray::rng::Pcg32;
    let n = ctx.rays;
    let mut rng = Pcg32::new(link_seed(ctx.seed, nodes, receiver, source), 0);
    let shift = rng.next_u32() % n;
    let point = |node: usize, u: f32, rng: &mut Pcg32| {
        let v = rng.next_f32();
        let children: Vec<usize> = nodes.children(node).collect();
        let total: f32 = children.iter().map(|&c| nodes.area[c]).sum();
        let mut pick = rng.next_f32() * total;
        let mut chosen = *children.last().unwrap();
        for &c in &children {
            if pick < nodes.area[c] {
                chosen = c;
                break;
            }
            pick -= nodes.area[c];
        }
        (triangle_point(&nodes.corners[chosen], u, v), nodes.normal[chosen])
    };
    let mut visible = 0;
    for k in 0..n {
        let ur = (k as f32 + rng.next_f32()) / n as f32;
        let us = (((k + shift) % n) as f32 + rng.next_f32()) / n as f32;
        let (x, nx) = point(receiver, ur, &mut rng);
        let (y, ny) = point(source, us, &mut rng);
        let (xo, yo) = (x + nx * ctx.offset, y + ny * ctx.offset);
        visible += !ctx.accel.occluded(xo, yo - xo, 1.0) as u32;
    }
    visible as f64 / n as f64
}

/// Mean and sample variance over seeds 0..`seeds` of `estimate(seed)`.
fn mean_and_variance(seeds: u64, estimate: impl Fn(u64) -> f64) -> (f64, f64) {
    let samples: Vec<f64> = (0..seeds).map(estimate).collect();
    let mean = samples.iter().sum::<f64>() / seeds as f64;
    let var = samples.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (seeds - 1) as f64;
    (mean, var)
}

/// Link visibility (`visibility::link_visibility`) of the half-occluded squares (`facing_squares`,
/// exact V = 1/2) at 16 rays over 512 seeds: the mean is within 4 standard errors of 1/2, so the
/// stratified, scrambled patterns stay unbiased; and the variance of one estimate is below 0.6 of
/// the estimator it replaced (`visibility_before_session_12`). Measured (session 12): variance
/// 5.8e-3 against 1.23e-2 before (0.47×) and V(1 − V)/N = 1.6e-2 for independent pairs. Not less:
/// whether a ray is blocked depends on x₁ + x₂, both ends at once, and stratifying each end alone
/// does not stratify that sum. The bound leaves 0.13 for the estimate of the ratio, whose relative
/// error over 512 seeds is about √(2/511)·√2 ≈ 9%.
#[test]
fn link_visibility_of_a_half_occluded_pair_converges_to_one_half_with_less_variance_than_before() {
    use hierarchy::visibility::{link_visibility, VisibilityContext};
    let (nodes, r, s, accel) = facing_squares(true);
    let ctx = |seed| VisibilityContext { accel: &accel, rays: 16, offset: 1e-5, seed };
    let seeds = 512;
    let (mean, var) = mean_and_variance(seeds, |seed| link_visibility(&ctx(seed), &nodes, r, s).visible as f64);
    let (old_mean, old_var) = mean_and_variance(seeds, |seed| visibility_before_session_12(&ctx(seed), &nodes, r, s));
    println!("V mean {mean:.4}, variance {var:.2e}; before: mean {old_mean:.4}, variance {old_var:.2e}");
    let standard_error = (var / seeds as f64).sqrt();
    assert!((mean - 0.5).abs() <= 4.0 * standard_error, "mean {mean} ± {standard_error}");
    assert!(var < 0.6 * old_var, "variance {var:.2e} against {old_var:.2e} before");
}

/// A unit square on the floor (z = 0, facing up) under a ceiling strip 8 long (z = 1, x from 0 to 8,
/// facing down), and a plate at z = 1/2 over x > 2: a segment from (x₁, ·, 0) to (x₂, ·, 1) is blocked
/// iff x₁ + x₂ > 4. More than half the strip is hidden, but the hidden part is the far one, which adds
/// little to the form factor: the share of F that nothing blocks (the exact V a link needs, F_occluded /
/// F_unoccluded, by a 4-D midpoint rule here) is 0.987, where the share of unblocked point
/// pairs is 0.43. Link visibility (16 rays, 256 seeds) must find the former within 5% (0.986; counting
/// pairs, as until session 18, gave 0.43): Sponza's floor
/// and ceiling triangles run the length of the building, and counting pairs lost the transfer of
/// their visible near parts (session 18).
#[test]
fn link_visibility_weighs_each_ray_by_the_form_factor_of_its_pair() {
    use hierarchy::visibility::{link_visibility, VisibilityContext};
    let receiver =
        [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(1.0, 1.0, 0.0), Vec3::new(0.0, 1.0, 0.0)];
    let source =
        [Vec3::new(0.0, 0.0, 1.0), Vec3::new(0.0, 1.0, 1.0), Vec3::new(8.0, 1.0, 1.0), Vec3::new(8.0, 0.0, 1.0)];
    let plate =
        [Vec3::new(2.0, -5.0, 0.5), Vec3::new(20.0, -5.0, 0.5), Vec3::new(20.0, 6.0, 0.5), Vec3::new(2.0, 6.0, 0.5)];
    let (nodes, r, s, accel) = two_clusters_with(&receiver, &source, 0, &plate);
    // The exact shares: ∫∫ K·[x₁ + x₂ < 4] / ∫∫ K with K = 1/d⁴ (cos θ_x cos θ_y / d² at height 1),
    // and the plain share of unblocked pairs.
    let (n1, n2) = (12usize, 96usize);
    let (mut seen, mut all, mut pairs_seen, mut pairs) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for i1 in 0..n1 {
        for j1 in 0..n1 {
            for i2 in 0..n2 {
                for j2 in 0..n1 {
                    let (x1, y1) = ((i1 as f64 + 0.5) / n1 as f64, (j1 as f64 + 0.5) / n1 as f64);
                    let (x2, y2) = (8.0 * (i2 as f64 + 0.5) / n2 as f64, (j2 as f64 + 0.5) / n1 as f64);
                    let d2 = (x2 - x1).powi(2) + (y2 - y1).powi(2) + 1.0;
                    let k = 1.0 / (d2 * d2);
                    let open = x1 + x2 < 4.0;
                    all += k;
                    pairs += 1.0;
                    if open {
                        seen += k;
                        pairs_seen += 1.0;
                    }
                }
            }
        }
    }
    let (exact, plain) = (seen / all, pairs_seen / pairs);
    let seeds = 256;
    let (mean, _) = mean_and_variance(seeds, |seed| {
        let ctx = VisibilityContext { accel: &accel, rays: 16, offset: 1e-5, seed };
        link_visibility(&ctx, &nodes, r, s).visible as f64
    });
    println!("V mean {mean:.4}; F-weighted share {exact:.4}, share of pairs {plain:.4}");
    assert!(exact > 0.95 && plain < 0.5, "the case itself: {exact} {plain}");
    assert!((mean / exact - 1.0).abs() < 0.05, "V {mean} against {exact}");
}

/// A link whose uniform sample pairs (almost) never face each other still has its visibility
/// measured (`visibility::facing_member_visibility`): a floor 10 m long of which only a 1 mm sliver
/// lies in front of the plane of a wall panel 5 m above it (the 4N = 64 uniform pairs of 16 rays find
/// a facing one with probability 1e-4 each) gets V = 1 with nothing between them and V = 0 under a
/// plate that hides the panel from the sliver. Until session 20 V was 1 in both cases, unmeasured:
/// the way two rooms turned off the axes passed light through their wall
/// (`light_does_not_leak_through_a_wall_turned_off_the_axes`).
#[test]
fn a_link_whose_samples_do_not_face_has_its_visibility_measured() {
    use hierarchy::visibility::{link_visibility, VisibilityContext};
    let floor = [
        Vec3::new(-10.0, 0.0, 0.0),
        Vec3::new(0.001, 0.0, 0.0),
        Vec3::new(0.001, 1.0, 0.0),
        Vec3::new(-10.0, 1.0, 0.0),
    ];
    let panel =
        [Vec3::new(0.0, 0.0, 5.0), Vec3::new(0.0, 1.0, 5.0), Vec3::new(0.0, 1.0, 6.0), Vec3::new(0.0, 0.0, 6.0)];
    let plate =
        [Vec3::new(-1.0, -1.0, 2.5), Vec3::new(1.0, -1.0, 2.5), Vec3::new(1.0, 2.0, 2.5), Vec3::new(-1.0, 2.0, 2.5)];
    let (open_nodes, r, s, open_accel) = two_clusters(&floor, &panel, 0);
    let (blocked_nodes, _, _, blocked_accel) = two_clusters_with(&floor, &panel, 0, &plate);
    for seed in 0..8 {
        let open = VisibilityContext { accel: &open_accel, rays: 16, offset: 1e-5, seed };
        let blocked = VisibilityContext { accel: &blocked_accel, rays: 16, offset: 1e-5, seed };
        assert_eq!(link_visibility(&open, &open_nodes, r, s).visible, 1.0, "seed {seed}, nothing between");
        assert_eq!(link_visibility(&blocked, &blocked_nodes, r, s).visible, 0.0, "seed {seed}, under the plate");
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Whatever the seed and ray count, V is a fraction in [0, 1], and a link nothing can block gets
    /// exactly 1 (every ray reaches: no noise where there is no occluder).
    #[test]
    fn link_visibility_is_a_fraction_and_exactly_one_when_nothing_blocks(seed in any::<u64>(), rays in 1u32..40) {
        use hierarchy::visibility::{link_visibility, VisibilityContext};
        let (nodes, r, s, accel) = facing_squares(true);
        let ctx = VisibilityContext { accel: &accel, rays, offset: 1e-5, seed };
        let v = link_visibility(&ctx, &nodes, r, s).visible;
        prop_assert!((0.0..=1.0).contains(&v), "{v}");
        let (nodes, r, s, accel) = facing_squares(false);
        let ctx = VisibilityContext { accel: &accel, rays, offset: 1e-5, seed };
        prop_assert_eq!(link_visibility(&ctx, &nodes, r, s).visible, 1.0);
    }
}

/// The near-link leaf-pair estimator (`links::near_form_factor` with at most 64 leaf pairs: the element
/// estimator summed over the pairs, times visibility) against the rectangle cases of
/// `tests/data/polygon_to_polygon.json`, F12 with each rectangle a cluster of its two triangles.
/// Stated tolerance: the element estimator's 1% (its near pairs use the 48-point rule); measured
/// worst 0.16% (pp_perp_edge1_w2_h1).
#[test]
fn near_link_leaf_pair_estimator_matches_polygon_to_polygon_cases() {
    use radray::radiosity::hierarchy::links::near_form_factor;
    use radray::radiosity::hierarchy::visibility::VisibilityContext;
    let data = load_json("polygon_to_polygon.json");
    let mut checked = 0;
    for case in data["cases"].as_array().unwrap() {
        let g = &case["geometry"];
        let (p1, p2) = (polygon(&g["polygon1"]["vertices"]), polygon(&g["polygon2"]["vertices"]));
        if p1.len() != 4 || p2.len() != 4 {
            continue;
        }
        let want = case["expected"]["F12"].as_f64().unwrap();
        let (nodes, r, s, accel) = two_clusters(&p1, &p2, 0);
        let ctx = VisibilityContext { accel: &accel, rays: 8, offset: 1e-5, seed: 0 };
        let f = near_form_factor(&nodes, &ctx, r, s).unwrap_or(0.0) as f64;
        let e = (f - want) / want;
        println!("{} leaf pairs: F12 {f:.5} (exact {want:.5}), rel. error {e:+.2e}", case["id"]);
        assert!(e.abs() <= 0.01, "{}: {e}", case["id"]);
        checked += 1;
    }
    assert_eq!(checked, 9);
}

/// The near-link sampled estimator (`visibility::sampled_form_factor`: Lambert's exact form factor
/// from a receiver point to an area-picked source element, times a ray; used by
/// `links::near_form_factor` above 64 leaf pairs) against every polygon-to-polygon case, with the
/// default 8 visibility rays (48 samples, `NEAR_SAMPLES_PER_RAY`), averaged over 64 seeds: its bias must be within 4 standard errors of
/// that mean.
///
/// Until session 15 it was ignored, biased low where the ends touch or nearly do (session 12: parallel
/// squares within 2.3%, perpendicular rectangles sharing an edge −14% to −23%, disks r 1 → 2 at
/// separation 0.5 −13%, worst at 4.4 standard errors). Not one ray was blocked in those cases: the
/// cause was the source element picked by area (weight A_S/A_t). Beside the shared edge a receiver
/// point's form factor to the small element next to it, times A_S/A_t, is a heavy tail: 64 seeds × 8
/// samples seldom reach it (−14% to −23% over 64 seeds with or without the cap), and the estimate's
/// cap at F ≤ 1 cut it off where a seed did (over 4096 seeds −2% to −7% with the cap, within 1.2%
/// without it; all of the disks' −13%). The element is now picked by a bounded kernel towards
/// the receiver point (`visibility::sample_element_towards`, its spheres' radii capped at √A);
/// measured at 8 samples: every case within 2.9% and 1.2 standard errors (shared edges −2.8% to
/// +0.6%, disks r 1 → 2 −1.2%); at 32 (session 19): within 3.9% and 1.6 standard errors.
#[test]
fn near_link_ray_estimator_is_unbiased_on_polygon_to_polygon_cases() {
    use radray::radiosity::hierarchy::links::near_form_factor;
    use radray::radiosity::hierarchy::visibility::VisibilityContext;
    let data = load_json("polygon_to_polygon.json");
    let mut worst = 0.0f64;
    for case in data["cases"].as_array().unwrap() {
        let g = &case["geometry"];
        let (p1, p2) = (polygon(&g["polygon1"]["vertices"]), polygon(&g["polygon2"]["vertices"]));
        let want = case["expected"]["F12"].as_f64().unwrap();
        // Enough leaves for more than 64 pairs: rectangles cut into 32 triangles, disks as 62.
        let (nodes, r, s, accel) = two_clusters(&p1, &p2, if p1.len() == 4 { 2 } else { 0 });
        let seeds = 64;
        let samples: Vec<f64> = (0..seeds)
            .map(|seed| {
                let ctx = VisibilityContext { accel: &accel, rays: 8, offset: 1e-5, seed };
                near_form_factor(&nodes, &ctx, r, s).unwrap_or(0.0) as f64
            })
            .collect();
        let mean = samples.iter().sum::<f64>() / seeds as f64;
        let var = samples.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (seeds - 1) as f64;
        let se = (var / seeds as f64).sqrt();
        println!(
            "{} rays: mean F12 {mean:.5} (exact {want:.5}), bias {:+.2e}, standard error {:.1e} (relative)",
            case["id"],
            (mean - want) / want,
            se / want
        );
        worst = worst.max((mean - want).abs() / se);
    }
    assert!(worst <= 4.0, "worst bias at {worst:.1} standard errors");
}

/// A near link's error is the deviation of its estimate over the receiver (`links::near_estimate`):
/// the L1 error of pushing one F_RS to every point of the receiver. Against every polygon-to-polygon
/// case, the ray estimator's deviation (default 8 rays: 32 samples; mean of 64 seeds) must not understate the
/// true one, (1/A_R) ∫ |F(x → S) − F_RS| dx with Lambert's exact point form factor over a 4^5-piece
/// grid of the receiver. Refinement keeps a near link by this figure, so an understated one keeps a
/// wrong link: until session 19 a near link's error was a bound capped by its parent's, and the
/// bound's cap hid the nave floor's error in Sponza (docs/accuracy.md).
#[test]
fn near_link_deviation_does_not_understate_the_receivers_variation() {
    use radray::radiosity::hierarchy::links::near_estimate;
    use radray::radiosity::hierarchy::visibility::VisibilityContext;
    let data = load_json("polygon_to_polygon.json");
    let mut lowest = f64::INFINITY;
    for case in data["cases"].as_array().unwrap() {
        let g = &case["geometry"];
        let (p1, p2) = (polygon(&g["polygon1"]["vertices"]), polygon(&g["polygon2"]["vertices"]));
        let (mut weighted, mut total, mut values) = (0.0, 0.0, Vec::new());
        for piece in fan(&p1).into_iter().flat_map(|t| subdivided(t, 5)) {
            let normal = (piece[1] - piece[0]).cross(piece[2] - piece[0]).normalize();
            let centre = (piece[0] + piece[1] + piece[2]) / 3.0;
            let f: f64 = fan(&p2).iter().map(|t| point_to_polygon(centre, normal, t)).sum();
            let a = area(&piece);
            weighted += a * f;
            total += a;
            values.push((a, f));
        }
        let mean = weighted / total;
        let truth = values.iter().map(|&(a, f)| a * (f - mean).abs()).sum::<f64>() / total;
        let (nodes, r, s, accel) = two_clusters(&p1, &p2, if p1.len() == 4 { 2 } else { 0 });
        let seeds = 64;
        let estimated = (0..seeds)
            .map(|seed| {
                let ctx = VisibilityContext { accel: &accel, rays: 8, offset: 1e-5, seed };
                near_estimate(&nodes, &ctx, r, s).map_or(0.0, |e| e.deviation as f64)
            })
            .sum::<f64>()
            / seeds as f64;
        println!("{}: F {mean:.4}, deviation {truth:.4}, estimated {estimated:.4}", case["id"]);
        lowest = lowest.min(estimated / truth);
        assert!(estimated >= truth, "{}: estimated {estimated} below the true {truth}", case["id"]);
    }
    println!("lowest estimated/true deviation {lowest:.2}");
}

/// A planar polygon (3 or 4 corners) of about unit size, turned by (yaw, pitch) and moved by `offset`.
fn placed(corners: &[[f32; 2]], yaw: f32, pitch: f32, offset: Vec3) -> Vec<Vec3> {
    let rotation = glam::Mat3::from_rotation_y(yaw) * glam::Mat3::from_rotation_x(pitch);
    corners.iter().map(|&[x, z]| rotation * Vec3::new(x, 0.0, z) + offset).collect()
}

/// The hierarchy's leaf mesh over the one surface `vertices` (a quad is two input triangles), every
/// input triangle cut `levels` times and then the leaves picked by `picks` (mod the leaf count) once
/// more, so that neighbouring leaves differ in depth; each leaf's exitance is `field` at its centroid.
fn leaf_mesh_of(
    vertices: Vec<Vec3>,
    levels: u32,
    picks: &[u16],
    field: &dyn Fn(Vec3) -> Vec3,
) -> hierarchy::interpolate::LeafMesh {
    let scene = scene_of(vec![(vertices, 0.5, 0.0)]);
    let (mut nodes, root, inputs, _) = clusters::build(&scene).unwrap();
    let leaves =
        |nodes: &Nodes| (0..nodes.len()).filter(|&n| nodes.is_leaf(n) && !nodes.is_cluster[n]).collect::<Vec<_>>();
    for _ in 0..levels {
        for n in leaves(&nodes) {
            nodes.subdivide(n);
        }
    }
    for &pick in picks {
        let l = leaves(&nodes);
        nodes.subdivide(l[pick as usize % l.len()]);
    }
    for n in leaves(&nodes) {
        nodes.exitance[n] = field(nodes.centre[n]).as_dvec3();
    }
    hierarchy::interpolate::leaf_mesh(&nodes, &inputs, root as usize)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// A linear field B(p) = a + g·p given at the leaf centroids comes back exactly at the leaf mesh's
    /// boundary vertices (`boundary_vertices::vertex_values` on the hierarchy's leaves), where
    /// neighbouring leaves differ in depth and hanging nodes sit next to the boundary; the plain mean is
    /// half a leaf's change off there. The exception is the limiter's: each leaf at a boundary vertex v
    /// extrapolates exactly, but its value is limited to the range [lo, hi] of the field over its own
    /// and its neighbours' centroids (leaves sharing a vertex with it), widened by half of it; where
    /// f(v) lies outside that (a leaf whose neighbours all sit on one side of it, as at a triangle's
    /// corner or beside a coarser neighbour), the limited value lies between the leaf's own and f(v), so
    /// v's error is at most the open-area-weighted mean of |B_e − f(v)| over its leaves. Two or more
    /// levels of subdivision leave some boundary vertices within every limit (asserted, so the exact
    /// case is always checked). Tolerance: f32 positions and values, 2e-5 of the field's largest value.
    #[test]
    fn a_linear_field_is_reproduced_exactly_at_the_leaf_meshs_boundary_vertices(
        triangle in any::<bool>(),
        w in 0.5f32..2.0, d in 0.5f32..2.0, apex in -0.5f32..1.5,
        yaw in 0.0f32..std::f32::consts::TAU,
        pitch in 0.0f32..std::f32::consts::TAU,
        offset in prop::array::uniform3(-3.0f32..3.0),
        gradient in prop::array::uniform3(-2.0f32..2.0),
        levels in 2u32..4,
        picks in proptest::collection::vec(any::<u16>(), 0..24),
    ) {
        let corners = if triangle { vec![[0.0, 0.0], [apex, d], [w, 0.0]] } else { vec![[0.0, 0.0], [0.0, d], [w, d], [w, 0.0]] };
        let vertices = placed(&corners, yaw, pitch, Vec3::from(offset));
        let g = Vec3::from(gradient);
        let lowest = vertices.iter().map(|&p| g.dot(p)).fold(f32::INFINITY, f32::min);
        let field = |p: Vec3| Vec3::new(1.0, 2.0, 0.5) * (1.0 - lowest + g.dot(p));
        let largest = vertices.iter().map(|&p| field(p).max_element()).fold(0.0, f32::max);
        let tolerance = 2e-5 * largest;
        let mesh = leaf_mesh_of(vertices, levels, &picks, &field);
        let centre = |l: usize| mesh.triangles[l].iter().map(|&v| mesh.positions[v as usize]).sum::<Vec3>() / 3.0;
        let mut at = vec![Vec::new(); mesh.positions.len()];
        for (l, t) in mesh.triangles.iter().enumerate() {
            for &v in t {
                at[v as usize].push(l);
            }
        }
        // f(v) within leaf l's limit (with the tolerance's margin).
        let within_limit = |l: usize, v: u32| {
            let around = mesh.triangles[l].iter().flat_map(|&c| &at[c as usize]).map(|&n| field(centre(n)));
            let (lo, hi) = around.fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), b| (lo.min(b), hi.max(b)));
            let (spread, f) = ((hi - lo) * 0.5, field(mesh.positions[v as usize]));
            (f.cmpge(lo - spread + tolerance) & f.cmple(hi + spread - tolerance)).all()
        };
        let (mut boundary, mut exact) = (0, 0);
        for (v, &p) in mesh.positions.iter().enumerate().filter(|&(v, _)| mesh.boundary[v]) {
            boundary += 1;
            let error = (mesh.vertex_exitance[v] - field(p)).abs();
            if at[v].iter().all(|&l| within_limit(l, v as u32)) {
                exact += 1;
                prop_assert!(error.max_element() <= tolerance, "vertex at {p}: {} against {}", mesh.vertex_exitance[v], field(p));
            } else {
                let (sum, area) = at[v].iter().fold((Vec3::ZERO, 0.0), |(s, a), &l| {
                    let w = mesh.leaf_open_area[l];
                    (s + (field(centre(l)) - field(p)).abs() * w, a + w)
                });
                let bound = sum / area;
                prop_assert!((error - bound).max_element() <= tolerance, "vertex at {p}: error {error} over the bound {bound}");
            }
        }
        prop_assert!(exact > 0, "{exact} of {boundary} boundary vertices within every limit");
    }
}

/// A sphere of `rings` × `segments` triangles (radius `radius`, centre `centre`), counter-clockwise
/// seen from outside, caps as fans.
fn sphere_triangles(centre: Vec3, radius: f32, rings: u32, segments: u32) -> Vec<Vec<Vec3>> {
    let point = |ring: u32, segment: u32| {
        let theta = std::f32::consts::PI * ring as f32 / rings as f32;
        let phi = std::f32::consts::TAU * segment as f32 / segments as f32;
        centre + radius * Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin())
    };
    let mut out = Vec::new();
    for ring in 0..rings {
        for segment in 0..segments {
            let (a, b) = (point(ring, segment), point(ring, segment + 1));
            let (c, d) = (point(ring + 1, segment), point(ring + 1, segment + 1));
            if ring + 1 < rings {
                out.push(vec![b, d, c]);
            }
            if ring > 0 {
                out.push(vec![a, b, c]);
            }
        }
    }
    out
}

/// A near link to a cluster receiver reaches each member by the member's own form factor to the
/// source (`gather::ArrivalScales`, `sampled_member_shares`): a sphere of 8 × 16 facets (radius 1)
/// under a triangular lamp 1.5 above its centre, close enough that the two bounding spheres
/// overlap (a near link). With the link's form factor the exact centroid rule Σ_i A_i F(x_i → S) /
/// A_R, every facet gets G_i = F(x_i → S)·B_S, Lambert's exact point-to-polygon form factor from its
/// centroid: the source is one element, so the sampled source elements are exact. Tolerance 1e-5 of
/// the largest G: the shares are f32. Facets whose plane hides the lamp get exactly 0. (The arrival
/// this replaced, max(0, n_i·ω) with ω between the centres, is off by up to 58% of the largest G
/// here: it spreads the light by a direction, not by each facet's distance to a lamp that fills
/// much of its sky.)
#[test]
fn a_near_link_reaches_each_member_by_its_exact_form_factor() {
    let sphere = sphere_triangles(Vec3::ZERO, 1.0, 8, 16);
    let scene = scene_of(sphere.into_iter().map(|t| (t, 0.5, 0.0)).collect());
    let (mut nodes, root, inputs, _) = clusters::build(&scene).unwrap();
    let root = root as usize;
    let lamp = [Vec3::new(-1.2, 1.5, -1.0), Vec3::new(1.4, 1.5, -0.6), Vec3::new(0.0, 1.5, 1.4)];
    let source = nodes.push_element(lamp, u32::MAX - 1, 0, Vec3::ZERO, Vec3::ONE) as usize;
    assert!(hierarchy::links::is_near(&nodes, root, source), "the test needs a near link");
    let members: Vec<usize> = inputs.node.iter().map(|&n| n as usize).collect();
    let exact: Vec<f64> =
        members.iter().map(|&m| point_to_polygon(nodes.centre[m], nodes.normal[m], &nodes.corners[source])).collect();
    let (links, form_factor) = link_of_member_form_factors(&nodes, root, source, &members, &exact);
    let scales = gather::ArrivalScales::new(&nodes, &links);
    assert!(scales.receiver(root).has_shares(0));
    let own: Vec<gather::Irradiance> =
        (0..nodes.len()).map(|n| gather::gather(&nodes, &links, &scales, n, &nodes.exitance)).collect();
    let mut exitance = nodes.exitance.clone();
    let total = gather::push_pull(&nodes, root, &own, &mut exitance);
    let largest = exact.iter().copied().fold(0.0, f64::max);
    let mut hidden = 0;
    for (&m, &f) in members.iter().zip(&exact) {
        assert!((total[m].x - f).abs() <= 1e-5 * largest, "member {m}: G {} vs exact {f}", total[m].x);
        if f == 0.0 {
            assert_eq!(total[m], DVec3::ZERO);
            hidden += 1;
        }
    }
    assert!(hidden > 0 && hidden < members.len(), "{hidden} hidden facets of {}", members.len());
    // What the centre-to-centre arrival would give instead, for the figure in the doc comment.
    let towards = gather::arrival_direction(&nodes, root, source).unwrap();
    let scale = nodes.area[root] as f64 / nodes.open_projected_area(root, towards);
    let worst = members
        .iter()
        .zip(&exact)
        .map(|(&m, f)| (form_factor * scale * nodes.normal[m].dot(towards).max(0.0) as f64 - f).abs() / largest)
        .fold(0.0, f64::max);
    assert!(worst > 0.3, "the arrival's worst error {worst} no longer shows what this test guards against");
}

/// A far link to a cluster of long thin coplanar members reaches each member by its own position
/// (`gather::PointSource`): a half disc of radius 1 fan-triangulated into 48 slivers (each spans the
/// whole radius, as the vault hall's lunettes do), under a small lamp (a triangle of side 0.1, facing
/// the fan's centre) 3.2 away to one side: the link root ← lamp is far (no member shares: 48 pairs),
/// so it is an arrival. With the link's form factor the exact Σ_i A_i F_i / A_R, each sliver's pushed
/// irradiance must match its exact form factor to the lamp F_i (the element estimator on the sliver
/// subdivided 4 times, 256 pieces) times B_S. Tolerance 3% of each sliver's own value: the point-source
/// weight is evaluated at the centroid, not averaged over the sliver (measured worst 1.4%). The
/// directional arrival it replaced, max(0, n·ω) on every member, gave all 48 slivers one value,
/// wrong by up to 73% here (the lamp lights the fan's near side far more than its far side). Session
/// 16: the vault hall's lunette wedges were blamed on it; they come mostly from near links
/// (docs/accuracy.md).
#[test]
fn a_far_link_reaches_each_sliver_of_a_fan_by_its_own_position() {
    let slivers = 48;
    let arc = |k: usize| {
        let theta = std::f32::consts::PI * k as f32 / slivers as f32;
        Vec3::new(theta.cos(), theta.sin(), 0.0)
    };
    let fan_triangles: Vec<[Vec3; 3]> = (0..slivers).map(|k| [Vec3::ZERO, arc(k), arc(k + 1)]).collect();
    let scene = scene_of(fan_triangles.iter().map(|t| (t.to_vec(), 0.5, 0.0)).collect());
    let (mut nodes, root, inputs, _) = clusters::build(&scene).unwrap();
    let root = root as usize;
    let lamp_centre = Vec3::new(-2.5, 0.5, 2.0);
    let facing = (nodes.centre[root] - lamp_centre).normalize();
    let u = facing.any_orthonormal_vector();
    let v = facing.cross(u);
    let lamp = [lamp_centre, lamp_centre + 0.1 * u, lamp_centre + 0.1 * v];
    let source = nodes.push_element(lamp, u32::MAX - 1, 0, Vec3::ZERO, Vec3::ONE) as usize;
    assert!(!hierarchy::links::is_near(&nodes, root, source), "the test needs a far link");
    let members: Vec<usize> = inputs.node.iter().map(|&n| n as usize).collect();
    let exact: Vec<f64> = members
        .iter()
        .map(|&m| {
            let pieces = subdivided(nodes.corners[m], 4);
            let a: f64 = pieces.iter().map(area).sum();
            pieces.iter().map(|t| area(t) * element_to_element(t, nodes.normal[m], &lamp).0).sum::<f64>() / a
        })
        .collect();
    let (links, form_factor) = link_of_member_form_factors(&nodes, root, source, &members, &exact);
    let scales = gather::ArrivalScales::new(&nodes, &links);
    assert!(!scales.receiver(root).has_shares(0) && scales.receiver(root).positional(0), "the test needs an arrival");
    let own: Vec<gather::Irradiance> =
        (0..nodes.len()).map(|n| gather::gather(&nodes, &links, &scales, n, &nodes.exitance)).collect();
    let mut exitance = nodes.exitance.clone();
    let total = gather::push_pull(&nodes, root, &own, &mut exitance);
    let b = nodes.exitance[source].x;
    let mut worst = 0.0f64;
    for (&m, &f) in members.iter().zip(&exact) {
        let error = (total[m].x - f * b).abs() / (f * b);
        worst = worst.max(error);
        assert!(error <= 0.03, "sliver {m}: G {} vs exact {}", total[m].x, f * b);
    }
    println!("worst sliver error {worst:.4}");
    // What the directional arrival would give instead (one value on all the coplanar slivers).
    let towards = gather::arrival_direction(&nodes, root, source).unwrap();
    let scale = nodes.area[root] as f64 / nodes.open_projected_area(root, towards);
    let directional = form_factor * b * scale * nodes.normal[members[0]].dot(towards).max(0.0) as f64;
    let worst_directional = exact.iter().map(|&f| (directional - f * b).abs() / (f * b)).fold(0.0, f64::max);
    println!("worst directional error {worst_directional:.4}");
    assert!(
        worst_directional > 0.1,
        "the directional error {worst_directional} no longer shows what this test guards against"
    );
}

/// A cluster's bounding sphere holds every corner of its members (input triangles) and is the sphere
/// of their exact box: its radius is half the box's diagonal, its centre the box's centre, so it does
/// not grow with the depth of the tree (it boxed its children's spheres until session 15: up to √3×
/// per level). Checked on every cluster of the rotunda (2,077). Tolerance: f32 rounding, 1e-5 of the
/// radius.
#[test]
fn cluster_bounds_hold_their_members_and_are_their_boxs_sphere() {
    let scene = load_scene("rooms/rotunda.toml");
    let (nodes, _root, _inputs, _) = clusters::build(&scene).unwrap();
    let mut members = Vec::new();
    let mut checked = 0;
    for c in (0..nodes.len()).filter(|&n| nodes.is_cluster[n]) {
        nodes.members(c, &mut members);
        let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        for &m in &members {
            for p in nodes.corners[m] {
                lo = lo.min(p);
                hi = hi.max(p);
                let d = p.distance(nodes.centre[c]);
                assert!(d <= nodes.radius[c] * (1.0 + 1e-5), "cluster {c}: corner at {d} > radius {}", nodes.radius[c]);
            }
        }
        let box_radius = (hi - lo).length() * 0.5;
        assert!(
            (nodes.radius[c] - box_radius).abs() <= 1e-5 * box_radius,
            "cluster {c}: {} vs {box_radius}",
            nodes.radius[c]
        );
        checked += 1;
    }
    assert!(checked > 1000, "{checked} clusters");
}

/// A link from a subdivided element source sends its children's exitance weighted by how the
/// receiver sees each of them (`gather::SourceWeights`), not by their areas: a floor triangle (facing
/// +y) under a wall triangle (facing +x) that shares its edge along z, the wall split in quarters
/// with the two quarters along the floor at exitance 1 and the other two at 0 (the wall's mean is 1/2).
/// The floor's exact irradiance over F_RS is B̂ = Σ_k F(R → S_k)·B_k / Σ_k F(R → S_k), each F the
/// element estimator over the receiver split 4⁴ times (`polygon_form_factor`). Tolerance 2%: the
/// weights are taken at 12 receiver points (`source_weights::receiver_points`), which along a shared
/// edge, where the integrand is log-singular, give 0.6706 against 0.6806 here (−1.5%), and are bytes
/// (each within 1/510 of its value). The area mean B_S = 1/2 was 26% low (the quarters along the
/// floor are the ones it sees best).
#[test]
fn a_link_from_a_subdivided_source_sends_its_childrens_exitance_by_form_factor() {
    let floor = vec![Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 0.0, 0.0)];
    let wall = vec![Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.0, 0.0, 1.0)];
    let scene = scene_of(vec![(floor.clone(), 0.5, 0.0), (wall, 0.5, 0.0)]);
    let (mut nodes, _, inputs, _) = clusters::build(&scene).unwrap();
    let (r, s) = (inputs.node[0] as usize, inputs.node[1] as usize);
    nodes.subdivide(s);
    let children: Vec<usize> = nodes.children(s).collect();
    assert_eq!(children.len(), 4);
    // Exitance 1 on the quarters lying along the floor (an edge at y = 0: two of them), 0 elsewhere.
    let lit = |c: usize| nodes.corners[c].iter().filter(|p| p.y == 0.0).count() == 2;
    assert_eq!(children.iter().filter(|&&c| lit(c)).count(), 2);
    for &c in &children {
        nodes.exitance[c] = DVec3::splat(if lit(c) { 1.0 } else { 0.0 });
    }
    nodes.exitance[s] = gather::pulled(&nodes, s, &nodes.exitance);
    assert!((nodes.exitance[s].x - 0.5).abs() < 1e-6);
    let exact_f: Vec<f64> = children.iter().map(|&c| polygon_form_factor(&floor, &nodes.corners[c], 4)).collect();
    let exact =
        children.iter().zip(&exact_f).map(|(&c, f)| f * nodes.exitance[c].x).sum::<f64>() / exact_f.iter().sum::<f64>();
    let form_factor = polygon_form_factor(&floor, &nodes.corners[s], 4) as f32;
    let links = hierarchy::links::Links::from_records(
        nodes.len(),
        vec![hierarchy::links::LinkRecord { receiver: r as u32, source: s as u32, form_factor, spread: 0.0 }],
    );
    let scales = gather::ArrivalScales::new(&nodes, &links);
    let sent = gather::gather(&nodes, &links, &scales, r, &nodes.exitance).mean.x / form_factor as f64;
    assert!((sent - exact).abs() <= 0.02 * exact, "sent {sent}, exact {exact}");
    assert!((0.5 - exact).abs() > 0.1 * exact, "the area mean 0.5 is not far from {exact}");
    // A uniform source sends its exitance whatever the weights.
    for &c in &children {
        nodes.exitance[c] = DVec3::splat(0.7);
    }
    let uniform = gather::gather(&nodes, &links, &scales, r, &nodes.exitance).mean.x / form_factor as f64;
    assert!((uniform - 0.7).abs() <= 1e-6, "{uniform}");
}

/// The cluster build splits the two rooms of `two_rooms_through_a_wall` apart at the root, whether
/// they lie along the world axes or are turned 7° or 30° about y: no cluster below the root holds
/// input triangles of both rooms (the median split along the scene's frame keeps each face of the
/// wall whole, `SceneDescription::frame`). Along the world axes the split ties exactly; turned,
/// the faces' coordinates along the frame's axis differ by rounding, within `clusters::TIE_TOLERANCE`.
#[test]
fn the_cluster_tree_of_two_turned_rooms_mixes_them_only_at_the_root() {
    let (scene, dark) = two_rooms_through_a_wall(4);
    for angle_deg in [0.0f32, 7.0, 30.0] {
        let turn = glam::Quat::from_rotation_y(angle_deg.to_radians());
        let mut turned = scene.clone();
        for surface in &mut turned.surfaces {
            for v in &mut surface.vertices {
                *v = turn * *v;
            }
        }
        let (nodes, root, inputs, _) = clusters::build(&turned).unwrap();
        assert_eq!(nodes.frame.is_world(), angle_deg == 0.0, "turned {angle_deg}°: {:?}", nodes.frame);
        let mut members = Vec::new();
        for n in (0..nodes.len()).filter(|&n| nodes.is_cluster[n] && n != root as usize) {
            nodes.members(n, &mut members);
            let in_dark = members.iter().filter(|&&m| dark[inputs.surface[nodes.input[m] as usize] as usize]).count();
            assert!(
                in_dark == 0 || in_dark == members.len(),
                "turned {angle_deg}°: cluster {n} holds {in_dark} dark-room triangles of {}",
                members.len()
            );
        }
    }
}

/// The spread of an element receiver's links over its leaves by position (`positional_spread`) moves
/// light between the leaves below each receiver and creates or loses none: Σ_leaves A·ΔB/ρ = 0 for
/// the whole scene (each link's is 0 by construction; f64 sums, 1e-9 relative), no exitance goes
/// negative, and on alcove_hall, whose walls are linked above their leaves, it moves something
/// (the leaves below a receiver no longer all take its mean).
#[test]
fn the_positional_spread_moves_light_between_leaves_and_conserves_it() {
    let scene = load_scene("rooms/alcove_hall.toml");
    let params = HierarchyParams::preview();
    let (_, structure) = hierarchy::solve_reusing(&scene, Default::default(), &params, None, &mut |_| {}).unwrap();
    let (nodes, links) = (structure.nodes(), structure.links());
    let scales = gather::ArrivalScales::new(nodes, links);
    let spread = hierarchy::positional_spread::spread_leaf_exitance(nodes, links, &scales, structure.root());
    assert!(spread.len() > 1000, "{} leaves spread", spread.len());
    let (mut moved_w, mut total_w, mut largest_change) = (0.0f64, 0.0f64, 0.0f64);
    for &(leaf, b) in &spread {
        assert!(nodes.is_leaf(leaf));
        assert!(b.min_element() >= 0.0, "leaf {leaf}: {b}");
        let rho = nodes.reflectance[leaf].as_dvec3();
        let old = nodes.exitance[leaf];
        for c in 0..3 {
            if rho[c] > 0.0 {
                let area = nodes.area[leaf] as f64;
                moved_w += area * (b[c] - old[c]) / rho[c];
                total_w += area * (old[c] - nodes.emission[leaf][c] as f64) / rho[c];
                largest_change = largest_change.max((b[c] - old[c]).abs() / old[c].max(1e-9));
            }
        }
    }
    println!(
        "{} leaves: net power moved {moved_w:e} W of {total_w:.3} W received; largest change {largest_change:.3}",
        spread.len()
    );
    assert!(moved_w.abs() <= 1e-9 * total_w, "net {moved_w} W of {total_w} W");
    assert!(largest_change > 0.01, "largest relative change {largest_change}");
}

/// A far link from a cluster sends the exitance of the members that face its receiver
/// (`lobes::Lobes`), not the cluster's area mean: two squares back to back 0.2 apart, the one facing
/// +x at exitance 1 and the one facing −x at 0 (area mean 1/2), seen from patches 20 away along +x.
/// With the members' normals along the axes the six lobes are exact: the patch is sent 1, the
/// direction −x is sent 0, and a direction between +x and +y (no member faces +y) sends the +x
/// member's 1 too, and the far link's gather reads it; links whose ends overlap keep the area mean.
/// A uniform cluster sends its exitance in every direction.
#[test]
fn a_far_cluster_source_sends_the_exitance_of_the_members_facing_the_receiver() {
    use radray::radiosity::hierarchy::lobes::Lobes;
    let square = |x: f32, facing: f32| {
        let p = [Vec3::new(x, -0.5, -0.5), Vec3::new(x, 0.5, -0.5), Vec3::new(x, 0.5, 0.5), Vec3::new(x, -0.5, 0.5)];
        if facing > 0.0 {
            p.to_vec()
        } else {
            p.iter().rev().copied().collect()
        }
    };
    // Two patches side by side: four triangles on either side of any median split along x.
    let patch = square(20.0, -1.0);
    let beside: Vec<Vec3> = patch.iter().map(|&p| p + Vec3::new(0.0, 0.0, 1.5)).collect();
    let scene = scene_of(vec![
        (square(0.1, 1.0), 0.5, std::f32::consts::FRAC_1_PI),
        (square(-0.1, -1.0), 0.5, 0.0),
        (patch, 0.5, 0.0),
        (beside, 0.5, 0.0),
    ]);
    let (mut nodes, root, inputs, _) = clusters::build(&scene).unwrap();
    let root = root as usize;
    let surface = |n: usize| inputs.surface[nodes.input[n] as usize];
    // The cluster holding exactly the two back-to-back squares' four triangles.
    let mut members = Vec::new();
    let pair = (0..nodes.len())
        .find(|&n| {
            nodes.is_cluster[n] && {
                nodes.members(n, &mut members);
                members.len() == 4 && members.iter().all(|&m| surface(m) < 2)
            }
        })
        .expect("a cluster of the two squares");
    // Exitance 1 on the square facing +x (its emission), 0 elsewhere, pulled up the tree.
    hsolve::reset_to_emission(&mut nodes, root);
    assert!((nodes.exitance[pair].x - 0.5).abs() < 1e-9, "area mean {}", nodes.exitance[pair]);
    let no_links = hierarchy::links::Links::from_records(nodes.len(), Vec::new());
    let lobes = Lobes::new(&nodes, &no_links, root);
    let sent = |omega: Vec3| lobes.sent(pair, omega.normalize()).expect("members face ω").x;
    assert!((sent(Vec3::X) - 1.0).abs() < 1e-9, "towards +x {}", sent(Vec3::X));
    assert!(sent(Vec3::NEG_X).abs() < 1e-9, "towards -x {}", sent(Vec3::NEG_X));
    assert!((sent(Vec3::new(1.0, 1.0, 0.0)) - 1.0).abs() < 1e-9);
    assert!((sent(Vec3::new(1.0, 0.0, -1.0)) - 1.0).abs() < 1e-9);
    // Through a far link in the gather: the patch (its triangles' cluster, or the triangle itself)
    // gathers F·1.
    let receiver = inputs.node[4] as usize;
    assert!(hierarchy::links::admissible(&nodes, receiver, pair), "the link is far");
    assert!(hierarchy::lobes::sends_directionally(&nodes, receiver, pair));
    // Ends that overlap (the root around the pair, the pair's self-link) send the area mean.
    assert!(!hierarchy::lobes::sends_directionally(&nodes, root, pair));
    assert!(!hierarchy::lobes::sends_directionally(&nodes, pair, pair));
    let links = hierarchy::links::Links::from_records(
        nodes.len(),
        vec![hierarchy::links::LinkRecord {
            receiver: receiver as u32,
            source: pair as u32,
            form_factor: 1e-3,
            spread: 0.0,
        }],
    );
    let scales = gather::ArrivalScales::new(&nodes, &links);
    let lobes = Lobes::new(&nodes, &links, root);
    let (mut arrivals, mut direct) = (Vec::new(), Vec::new());
    let (_, mean) = gather::gather_into(
        &nodes,
        &links,
        &scales,
        receiver,
        &nodes.exitance,
        Some(&lobes),
        &mut arrivals,
        &mut direct,
    );
    assert!((mean.x / 1e-3 - 1.0).abs() < 1e-6, "sent {}", mean.x / 1e-3);
    // Uniform exitance: the same in every direction.
    for n in 0..nodes.len() {
        nodes.exitance[n] = DVec3::splat(0.3);
    }
    let lobes = Lobes::new(&nodes, &links, root);
    for omega in [Vec3::X, Vec3::NEG_X, Vec3::new(0.3, -0.8, 0.5), Vec3::new(-1.0, 0.2, 0.1)] {
        let b = lobes.sent(pair, omega.normalize()).map_or(f64::NAN, |b| b.x);
        assert!((b - 0.3).abs() < 1e-12, "towards {omega}: {b}");
    }
}

/// The ray correction (`ray_correction`) measures the indirect irradiance the links bring against
/// cosine rays that read the leaves' exitance. On the Cornell box the links agree with the rays:
/// the area-weighted gain is 1 within 2% (measured 1.0052 at 64 rays per leaf). With the form
/// factor of every link from a source that emits nothing scaled to 0.7 (links that see too little
/// of the hemisphere, as Sponza's near links did) and the sweeps run again, every group is
/// corrected and the gain is what the rays see: 1/0.7 = 1.43 within 5% (measured 1.4416). Solved
/// with it, the walls' exitance comes back within 5% of the unscaled solve's (measured +0.8%), where
/// the scaled links alone left it 23% below.
#[test]
fn a_ray_measured_gain_restores_indirect_light_the_links_lose() {
    measured_gain_restores_indirect_light_the_links_lose(IndirectEstimator::Rays { rays: 64 });
}

/// The same with the hemicube cut (`hemicube_cut`) at one leaf in four in place of the rays: the
/// links' indirect light measured by an item buffer that draws the cluster hierarchy as a cut
/// (measured at every leaf: gains 1.0119 and 1.4470, the rays' 1.0121 and 1.4475).
#[test]
fn a_hemicube_measured_gain_restores_indirect_light_the_links_lose() {
    measured_gain_restores_indirect_light_the_links_lose(IndirectEstimator::Hemicube {
        resolution_px: 32,
        stride: 4,
        cut_pixels: 2.0,
        max_hemicubes: u32::MAX,
    });
}

fn measured_gain_restores_indirect_light_the_links_lose(estimator: IndirectEstimator) {
    use hierarchy::ray_correction::measure;
    let scene = load_scene("cornell_box.toml");
    let params = HierarchyParams { correction_rays: 0, ..HierarchyParams::default() };
    let (_, structure) = hierarchy::solve_reusing(&scene, Default::default(), &params, None, &mut |_| {}).unwrap();
    let (_, _, _, tracing) = clusters::build(&scene).unwrap();
    let accel = radray::accel::Accel::build(&tracing.positions, &tracing.triangles);
    let (root, inputs) = (structure.root(), structure.inputs());
    let offset = scene.diagonal() * 1e-5;
    let leaves: Vec<usize> = (0..structure.nodes().len())
        .filter(|&n| structure.nodes().is_leaf(n) && !structure.nodes().is_cluster[n])
        .collect();
    // The walls', floor's and ceiling's area-weighted exitance (mean channel), lamp and blocks aside.
    let lit = |nodes: &Nodes| {
        let (mut sum, mut area) = (0.0f64, 0.0f64);
        for &n in &leaves {
            if nodes.emission[n].max_element() == 0.0 && nodes.reflectance_max[n] > 0.0 {
                sum += nodes.exitance[n].element_sum() / 3.0 * nodes.area[n] as f64;
                area += nodes.area[n] as f64;
            }
        }
        sum / area
    };
    let solve = |nodes: &mut Nodes, links: &hierarchy::links::Links, scales: &mut gather::ArrivalScales| {
        let (_, converged) = hsolve::solve_until(
            nodes,
            links,
            scales,
            root,
            hsolve::SweepOrder::GaussSeidel,
            1.1,
            1e-6,
            400,
            &mut |_, _| {},
            &|| false,
        )
        .unwrap();
        assert!(converged);
    };

    let mut nodes = structure.nodes().clone();
    let links = structure.links().clone();
    let mut scales = gather::ArrivalScales::new(&nodes, &links);
    solve(&mut nodes, &links, &mut scales);
    let reference = lit(&nodes);
    let (_, agreeing) = measure(&mut nodes, inputs, &accel, &links, &scales, root, estimator, 7, offset);
    println!("links as estimated: {agreeing:?}");
    assert!((agreeing.mean_gain - 1.0).abs() <= 0.02, "{agreeing:?}");

    // Every link from a source that emits nothing (the lamp's links keep the direct light as it was).
    let mut weak = structure.links().clone();
    for k in 0..weak.len() {
        if structure.nodes().emission[weak.source[k] as usize].max_element() == 0.0 {
            weak.form_factor[k] *= 0.7;
        }
    }
    let mut nodes = structure.nodes().clone();
    let mut scales = gather::ArrivalScales::new(&nodes, &weak);
    solve(&mut nodes, &weak, &mut scales);
    let darkened = lit(&nodes);
    let (correction, measured) = measure(&mut nodes, inputs, &accel, &weak, &scales, root, estimator, 7, offset);
    println!("links at 0.7: {measured:?}");
    assert!((measured.mean_gain - 1.0 / 0.7).abs() <= 0.05 / 0.7, "{measured:?}");
    assert_eq!(measured.corrected, measured.groups);
    scales.set_correction(Some(correction));
    solve(&mut nodes, &weak, &mut scales);
    let corrected = lit(&nodes);
    println!("walls' exitance: {reference:.4} as estimated, {darkened:.4} at 0.7, {corrected:.4} corrected");
    assert!(darkened < 0.85 * reference, "{darkened} against {reference}");
    assert!((corrected - reference).abs() <= 0.05 * reference, "{corrected} against {reference}");
}

/// The hemicube at a point that draws the hierarchy as a cut (`hemicube_cut`), every leaf at
/// exitance 1: it sees `surfaces` with the irradiance Σ_j F_j, the point's form factor to them.
fn cut_view(
    surfaces: &SceneDescription,
    eye: Vec3,
    normal: Vec3,
    resolution_px: u32,
    cut_pixels: f32,
) -> hierarchy::hemicube_cut::CutIrradiance {
    use radray::radiosity::hemicube::{Hemicube, ItemBuffer};
    let hc = Hemicube::new(resolution_px);
    with_cut_scene(surfaces, |scene, _| {
        hierarchy::hemicube_cut::irradiance_at(scene, &hc, &mut ItemBuffer::new(&hc), eye, normal, 0.3, cut_pixels)
    })
}

/// Runs `f` on the tree `surfaces` builds as a hemicube cut draws it, every leaf at exitance 1.
fn with_cut_scene<T>(
    surfaces: &SceneDescription,
    f: impl FnOnce(&hierarchy::hemicube_cut::CutScene, &clusters::InputTriangles) -> T,
) -> T {
    use hierarchy::hemicube_cut::{two_sided_inputs, CutScene};
    let (mut nodes, root, inputs, _) = clusters::build(surfaces).unwrap();
    let root = root as usize;
    hsolve::set_leaves(&mut nodes, root, |_, _| DVec3::ONE);
    let lobes = hierarchy::lobes::Lobes::new(&nodes, &Default::default(), root);
    let two_sided = two_sided_inputs(&inputs);
    f(&CutScene { nodes: &nodes, exitance: &nodes.exitance, lobes: &lobes, two_sided: &two_sided, root }, &inputs)
}

/// A case of `tests/data/point_to_polygon.json` as a scene (the polygon cut into 4⁴ triangles per fan
/// triangle, so that clusters form), its point, normal and exact form factor.
fn point_to_polygon_case(case: &serde_json::Value) -> (SceneDescription, Vec3, Vec3, f64) {
    let g = &case["geometry"];
    let poly = polygon(&g["polygon"]);
    let pieces: Vec<(Vec<Vec3>, f32, f32)> =
        fan(&poly).into_iter().flat_map(|t| subdivided(t, 4)).map(|t| (t.to_vec(), 0.5, 0.0)).collect();
    let (eye, normal) = (vec3(&g["point"]), vec3(&g["point_normal"]).normalize());
    (scene_of(pieces), eye, normal, case["expected"]["F"].as_f64().unwrap())
}

/// The hemicube cut sees every analytic point-to-polygon case (`tests/data/point_to_polygon.json`,
/// the polygon cut into 4⁴ triangles per fan triangle, so that clusters form) with its exact form
/// factor: drawn to the leaves (no node drawn whole above them), at 128 pixels, within 1% of F plus
/// 2e-4 (the hemicube's rasterisation: measured worst 0.47% where F > 10⁻³, the rectangle on the
/// horizon line); with nodes drawn whole where they are at most two pixels across (the far small
/// square becomes one cluster drawn as a square of its lobes' projected area), within 3% of F plus
/// 5e-4 (measured: the same values, the far square's F of 10⁻⁶ within the absolute term).
#[test]
fn a_hemicube_cut_sees_each_analytic_polygon_with_its_point_form_factor() {
    let data = load_json("point_to_polygon.json");
    let mut worst = [0.0f64; 2];
    for case in data["cases"].as_array().unwrap() {
        let (scene, eye, normal, want) = point_to_polygon_case(case);
        for (k, cut_pixels) in [0.0f32, 2.0].into_iter().enumerate() {
            let seen = cut_view(&scene, eye, normal, 128, cut_pixels);
            let e = (seen.irradiance.x - want).abs();
            println!(
                "{} cut {cut_pixels}: {:.6} (exact {want:.6}), {} drawn",
                case["id"], seen.irradiance.x, seen.drawn
            );
            let (relative, absolute) = if k == 0 { (0.01, 2e-4) } else { (0.03, 5e-4) };
            assert!(
                e <= relative * want + absolute,
                "{} cut {cut_pixels}: {} vs {want}",
                case["id"],
                seen.irradiance.x
            );
            if want > 1e-3 {
                worst[k] = worst[k].max(e / want);
            }
        }
    }
    println!("worst relative error where F > 1e-3: leaves {:.3e}, cut of two pixels {:.3e}", worst[0], worst[1]);
}

/// Inside a closed room every direction meets a wall: the cut's coverage Σ F_j is 1, and at exitance 1
/// so is the irradiance, however coarse the cut (measured below), from points all over the floor.
#[test]
fn a_hemicube_cut_inside_a_closed_room_sees_its_whole_hemisphere() {
    let scene = one_room(8, false);
    for cut_pixels in [0.0f32, 1.0, 4.0] {
        let mut worst = 0.0f64;
        for (x, z) in [(0.5f32, 0.5f32), (0.1, 0.9), (0.95, 0.05), (0.3, 0.7)] {
            let seen = cut_view(&scene, Vec3::new(x * 4.0, 1e-4, z * 3.0), Vec3::Y, 64, cut_pixels);
            worst = worst.max((seen.coverage - 1.0).abs()).max((seen.irradiance.x - 1.0).abs());
            println!(
                "cut {cut_pixels} at ({x}, {z}): coverage {:.5}, E {:.5}, {} drawn",
                seen.coverage, seen.irradiance.x, seen.drawn
            );
        }
        assert!(worst <= 0.01, "cut {cut_pixels}: worst {worst}");
    }
}

/// What a links' hemicube (`hemicube_links::source_form_factors_at`) credits to each of `sources`
/// (node ids, found in the tree `surfaces` builds by `pick`) from `eye` about `normal`.
fn link_view(
    surfaces: &SceneDescription,
    eye: Vec3,
    normal: Vec3,
    resolution_px: u32,
    cut_pixels: f32,
    pick: impl Fn(&Nodes, &clusters::InputTriangles, usize) -> Vec<u32>,
) -> Vec<f64> {
    use hierarchy::hemicube_links::{source_form_factors_at, LinkCutScratch};
    let hc = radray::radiosity::hemicube::Hemicube::new(resolution_px);
    with_cut_scene(surfaces, |scene, inputs| {
        let sources = pick(scene.nodes, inputs, scene.root);
        let mut f = vec![0.0; sources.len()];
        let mut scratch = LinkCutScratch::new(&hc, scene.nodes.len());
        source_form_factors_at(scene, &hc, &mut scratch, eye, normal, 0.3, cut_pixels, &sources, &mut f);
        f
    })
}

/// A links' hemicube whose one source is the whole tree credits it the exact point form factor of
/// every analytic case of `tests/data/point_to_polygon.json` (the polygon cut into 4⁴ triangles per
/// fan triangle, so that clusters form). Elements are drawn whole at any size (their triangles are
/// exact); clusters whole where at most `cut_pixels` across, as squares of their lobes' projected
/// area. At 128 pixels, with no cluster drawn whole and at the option's two pixels
/// (`hierarchy::LINK_CUT_PIXELS`), within 1% of F plus 2e-4 (measured worst where F > 10⁻³: 0.47%,
/// the rectangle on the horizon line, both). At four pixels the offset unit square came out 11% low
/// and the tilted hexagon 2% (a cluster's square facing the eye reaches below the horizon).
#[test]
fn a_links_hemicube_credits_its_source_the_analytic_point_form_factor() {
    let data = load_json("point_to_polygon.json");
    let mut worst = [0.0f64; 2];
    for case in data["cases"].as_array().unwrap() {
        let (scene, eye, normal, want) = point_to_polygon_case(case);
        for (k, cut_pixels) in [0.0f32, hierarchy::LINK_CUT_PIXELS].into_iter().enumerate() {
            let f = link_view(&scene, eye, normal, 128, cut_pixels, |_, _, root| vec![root as u32])[0];
            println!("{} cut {cut_pixels}: {f:.6} (exact {want:.6})", case["id"]);
            assert!((f - want).abs() <= 0.01 * want + 2e-4, "{} cut {cut_pixels}: {f} vs {want}", case["id"]);
            if want > 1e-3 {
                worst[k] = worst[k].max((f - want).abs() / want);
            }
        }
    }
    println!("worst relative error where F > 1e-3: no cluster whole {:.3e}, two pixels {:.3e}", worst[0], worst[1]);
}

/// Two sources, one in front of the other: from the origin (facing +z) a square of side 0.5 at
/// z = 1 hides the middle of a square of side 2 at z = 2 (its shadow there is the square of side 1,
/// inside the big one). Each of their triangles is a source of its own, so the hemicube credits
/// pixel by pixel: the near square gets its point form factor, the far one its own less the near
/// one's (the hidden part spans the same solid angle), within the hemicube's 1% plus 2e-4 at 128
/// pixels however large the cut (measured: 0.09% and 0.01%). And a source far below a cluster that
/// would be drawn whole is still drawn on its own: one triangle of the far square, with a cut of
/// 64 pixels, gets its own form factor within 3% plus 2e-4 (a triangle a few pixels across;
/// measured 3.9% low, 5e-5).
#[test]
fn a_links_hemicube_credits_each_source_only_what_it_sees() {
    let square = |half: f32, z: f32| {
        vec![Vec3::new(-half, -half, z), Vec3::new(-half, half, z), Vec3::new(half, half, z), Vec3::new(half, -half, z)]
    };
    let (far, near) = (square(1.0, 2.0), square(0.25, 1.0));
    let pieces: Vec<(Vec<Vec3>, f32, f32)> = [&far, &near]
        .into_iter()
        .flat_map(|p| fan(p).into_iter().flat_map(|t| subdivided(t, 3)))
        .map(|t| (t.to_vec(), 0.5, 0.0))
        .collect();
    let per_square = pieces.len() / 2;
    let scene = scene_of(pieces.clone());
    let (eye, normal) = (Vec3::ZERO, Vec3::Z);
    let f_near = point_to_polygon(eye, normal, &near);
    let f_far = point_to_polygon(eye, normal, &far) - f_near;
    for cut_pixels in [0.0f32, 4.0, 64.0] {
        let f = link_view(&scene, eye, normal, 128, cut_pixels, |_, inputs, _| inputs.node.clone());
        let (got_far, got_near): (f64, f64) = (f[..per_square].iter().sum(), f[per_square..].iter().sum());
        println!("cut {cut_pixels}: far {got_far:.6} (exact {f_far:.6}), near {got_near:.6} (exact {f_near:.6})");
        assert!((got_far - f_far).abs() <= 0.01 * f_far + 2e-4, "cut {cut_pixels}: far {got_far} vs {f_far}");
        assert!((got_near - f_near).abs() <= 0.01 * f_near + 2e-4, "cut {cut_pixels}: near {got_near} vs {f_near}");
    }
    // One triangle of the far square, in its corner (outside the near square's shadow).
    let corner = pieces.iter().position(|(t, _, _)| t.iter().all(|v| v.x < -0.7 && v.y < -0.7)).unwrap();
    let want = point_to_polygon(eye, normal, &pieces[corner].0);
    let f = link_view(&scene, eye, normal, 128, 64.0, |_, inputs, _| vec![inputs.node[corner]])[0];
    println!("one far triangle under a cut of 64 pixels: {f:.6} (exact {want:.6})");
    assert!((f - want).abs() <= 0.03 * want + 2e-4, "{f} vs {want}");
}

/// The furnace with its element receivers' far links measured by hemicubes
/// (`link_form_factors = "hemicube"`) stays exact within 1%, as with the formulas, and the
/// hemicubes did measure links.
#[test]
fn furnace_stays_exact_with_links_measured_by_hemicubes() {
    let scene = load_scene("furnace.toml");
    let params = HierarchyParams { link_form_factors: scene::LinkFormFactors::Hemicube, ..Default::default() };
    let solution = hierarchy::solve(&scene, &params, &mut |_| {}).unwrap();
    let exact = 2.0 * std::f64::consts::PI;
    let worst = solution.leaf_exitance.iter().map(|b| ((b.x as f64 - exact) / exact).abs()).fold(0.0f64, f64::max);
    let m = &solution.stats.link_hemicubes;
    println!("furnace: {m:?}, worst leaf error {worst:.3e}");
    assert!(m.links > 0 && m.hemicubes >= m.receivers && m.receivers > 0, "{m:?}");
    assert!(worst <= 0.01, "worst relative error {worst}");
}
