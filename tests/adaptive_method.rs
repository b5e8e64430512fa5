//! `method = "adaptive"` (issue 10's adaptive subdivision on the matrix path): the furnace stays exact
//! with the mesh refined (and its unsplit rows kept, substructuring), the refinement criterion splits
//! along a shadow boundary and nowhere else and is carried across concave corners, a hanging vertex
//! takes its edge's interpolated value (no T-vertex cracks), and boundary vertices are extrapolated
//! (exact on a linear solution, near Lambert's value beside a wall lamp). A refined level's hemicube
//! draws a far split patch whole and shares its form factor among the leaves by area; near, it draws
//! the leaves, bit for bit as without that cut.

use std::ops::Range;
use std::path::Path;

use glam::Vec3;
use radray::mesh::Mesh;
use radray::progress::Progress;
use radray::radiosity::adaptive::criterion::{
    across_concave_edges, across_concave_edges_and_emitters, elements_to_split, irradiance_variation, variation,
};
use radray::radiosity::adaptive::hanging::{conform, conforming_vertex_values, hanging_vertices};
use radray::radiosity::adaptive::reflectors::Reflectors;
use radray::radiosity::adaptive::shadow_boundaries::{blocked_light_variation, BlockedLightTest};
use radray::radiosity::adaptive::subdivide::{split, EdgeMidpoints};
use radray::radiosity::adaptive::substructure::{kept_rows, new_indices};
use radray::radiosity::boundary_vertices::{boundary_vertices, vertex_values};
use radray::radiosity::form_factors::ElementHierarchy;
use radray::radiosity::hemicube::{Hemicube, ItemBuffer};
use radray::radiosity::hierarchy::form_factor::point_to_polygon;
use radray::radiosity::matrix::patch_cut::{PatchCut, FAR_PATCH_RADIUS_PX};
use radray::radiosity::matrix::FormFactors;
use radray::radiosity::smooth_mesh::SmoothMesh;
use radray::run::{self, RunStats};
use radray::scene::{self, Camera, ImageSettings, Material, MethodChoice, RadiosityParams, RenderParams};
use radray::scene::{SceneDescription, SourceLoc, Surface};
use radray::transport::photons::RunPhotons;

/// A one-sided quad of material 0 named `object`.
fn quad(object: &str, vertices: [Vec3; 4]) -> Surface {
    Surface {
        vertices: vertices.to_vec(),
        material: 0,
        two_sided: false,
        shading_normals: None,
        uvs: None,
        object: object.into(),
        source: SourceLoc::default(),
    }
}

/// The 1 × 1 floor (y = 0, facing up, x and z in [0, 1]).
fn floor() -> Surface {
    quad("floor", [Vec3::ZERO, Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 0.0, 1.0), Vec3::new(1.0, 0.0, 0.0)])
}

/// A 1 × 1 floor quad (y = 0, facing up), meshed uniformly at `edge`.
fn floor_mesh(edge: f32) -> Mesh {
    mesh_of(vec![floor()], edge)
}

/// `surfaces` (all of material 0, diffuse 0.5) meshed uniformly at `edge`.
fn mesh_of(surfaces: Vec<Surface>, edge: f32) -> Mesh {
    Mesh::build(&scene_of(vec![Material::diffuse("floor", Vec3::splat(0.5))], surfaces), edge)
}

/// A scene of `materials` and `surfaces` with default settings, looking down at the floor.
fn scene_of(materials: Vec<Material>, surfaces: Vec<Surface>) -> SceneDescription {
    SceneDescription {
        path: "test".into(),
        camera: Camera { eye: Vec3::Y, look_at: Vec3::ZERO, up: Vec3::Z, vfov_deg: 40.0 },
        image: ImageSettings::default(),
        radiosity: RadiosityParams::default(),
        render: RenderParams::default(),
        materials,
        surfaces,
        warnings: Vec::new(),
    }
}

/// The furnace solved adaptively, one level, with a threshold so low that hemicube noise alone
/// splits elements: the scene, the refined mesh and its solution.
fn refined_furnace() -> (SceneDescription, Mesh, std::sync::Arc<radray::radiosity::Solution>) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/furnace.toml");
    let mut scene = scene::load(&path).unwrap();
    scene.radiosity.method = MethodChoice::Adaptive;
    scene.radiosity.adaptive.levels = 1;
    scene.radiosity.adaptive.threshold = 1e-6;
    let mut stats = RunStats::default();
    let (mesh, solution) =
        run::pass_one(&scene, None, &RunPhotons::default(), &Progress::hidden(), &mut stats).unwrap();
    (scene, mesh, solution)
}

/// The furnace (scenes/furnace.toml: closed unit cube, Kd 0.5, Ke 1) has B = E/(1 − ρ) = 2π
/// everywhere. Solved adaptively with a threshold so low that hemicube noise alone splits elements,
/// every element and every vertex (hanging ones included) stays within the 1%.
#[test]
fn furnace_stays_exact_within_one_percent_when_refined() {
    let (scene, mesh, solution) = refined_furnace();
    let uniform = radray::mesh::count_elements(&scene, scene.radiosity.max_element_edge) as usize;
    assert!(mesh.elements.len() > uniform, "the low threshold split elements: {} of {uniform}", mesh.elements.len());
    let exact = 2.0 * std::f32::consts::PI;
    for b in solution.element_exitance.iter().chain(&solution.vertex_exitance) {
        assert!(((b.x - exact) / exact).abs() <= 0.01, "exitance {b} against {exact}");
    }
}

/// A shadow boundary across the floor at x = 0.5: exitance 1 in the light (x < 0.45), 0.2 in the
/// umbra (x > 0.55), linear through the penumbra. On a 10 × 10 grid, elements are split only in the
/// two columns whose corners see the step (centres 0.05 from the boundary), and all of them.
#[test]
fn a_shadow_boundary_is_refined_where_the_solution_has_a_gradient_and_nowhere_else() {
    let mesh = floor_mesh(0.1);
    let exitance_at = |x: f32| {
        Vec3::splat(if x < 0.45 {
            1.0
        } else if x > 0.55 {
            0.2
        } else {
            1.0 - 8.0 * (x - 0.45)
        })
    };
    let element: Vec<Vec3> = mesh.elements.centre.iter().map(|c| exitance_at(c.x)).collect();
    let vertex = mesh.vertex_average(&element.iter().map(|v| v.as_dvec3()).collect::<Vec<_>>());
    let vertex: Vec<Vec3> = vertex.iter().map(|v| v.as_vec3()).collect();
    let delta = variation(&mesh, &element, &vertex, None);
    let chosen = elements_to_split(&mesh, &element, &delta, 0.1, 0.05, 0.01, &vec![true; element.len()]);
    assert_eq!(mesh.elements.len(), 100);
    for (e, c) in mesh.elements.centre.iter().enumerate() {
        let near = (c.x - 0.5).abs() < 0.1;
        assert_eq!(chosen[e], near, "element at x = {} split: {}", c.x, chosen[e]);
    }
    // A flat solution is never split.
    let flat = vec![Vec3::ONE; element.len()];
    let flat_delta = variation(&mesh, &flat, &vec![Vec3::ONE; mesh.positions.len()], None);
    let none = elements_to_split(&mesh, &flat, &flat_delta, 0.1, 0.05, 0.01, &[true; 100]);
    assert!(none.iter().all(|&s| !s));
}

/// Irradiance of a light boundary along x = 0.5 across the floor of a room corner (the floor y = 0 and
/// the wall x = 0 meet along the z axis): 1 in the light (x < 0.4), a penumbra to 0.15 at x = 0.6,
/// brighter towards z = 1 (gradient 0.5), and a dip to 0.6 within 0.15 of the corner line on both
/// surfaces (floor x < 0.15, wall y < 0.15). Smooth, stepped and flat parts, so that some elements
/// split and some do not.
fn room_irradiance(p: Vec3) -> Vec3 {
    let shadow = 1.0 - 0.85 * ((p.x - 0.4) / 0.2).clamp(0.0, 1.0);
    let corner = if p.x.hypot(p.y) < 0.15 { 0.6 } else { 1.0 };
    Vec3::new(1.0, 0.9, 0.7) * shadow * corner * (1.0 + 0.5 * p.z)
}

/// For a uniform albedo ρ over each surface (and no emission), Bₑ = ρ·Hₑ, and the vertex step is
/// linear and positively homogeneous per channel, so the irradiance criterion scaled by ρ,
/// ρ·|H_v − Hₑ|, is the exitance criterion |B_v − Bₑ| and every decision is the same. Checked on a
/// floor and a wall of different coloured albedos meeting in a corner, with extrapolated boundary
/// vertices and hanging vertices (one level already split), for thresholds from 0.02 to 0.5.
#[test]
fn the_irradiance_criterion_scaled_by_a_uniform_albedo_is_the_exitance_criterion() {
    let wall = quad("wall", [Vec3::ZERO, Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.0, 1.0, 1.0), Vec3::new(0.0, 0.0, 1.0)]);
    let coarse = mesh_of(vec![floor(), wall], 0.1);
    let mut midpoints = EdgeMidpoints::default();
    // Split beside the penumbra and along the corner line (the floor's first column, the wall's
    // first row).
    let chosen: Vec<bool> =
        coarse.elements.centre.iter().map(|c| (c.x - 0.5).abs() < 0.1 || c.x.hypot(c.y) < 0.1).collect();
    let mut mesh = split(&coarse, &chosen, &mut midpoints);
    let hanging = hanging_vertices(&mesh, &midpoints);
    assert!(!hanging.is_empty(), "the split leaves T-vertices");
    let (floor_rho, wall_rho) = (Vec3::new(0.8, 0.5, 0.2), Vec3::new(0.3, 0.6, 0.9));
    let e = &mut mesh.elements;
    for i in 0..e.len() {
        e.reflectance[i] = if e.normal[i].y > 0.5 { floor_rho } else { wall_rho };
    }
    let e = &mesh.elements;
    let exitance: Vec<Vec3> = (0..e.len()).map(|i| e.reflectance[i] * room_irradiance(e.centre[i])).collect();
    // Today's criterion: the exitance's own vertex step (as the solver makes `vertex_exitance`).
    let vertex_step = SmoothMesh::new(&mesh);
    let vertex_exitance =
        conforming_vertex_values(&vertex_step, &exitance.iter().map(|b| b.as_dvec3()).collect::<Vec<_>>(), &hanging);
    let by_exitance = variation(&mesh, &exitance, &vertex_exitance, None);
    let by_irradiance = irradiance_variation(&mesh, &exitance, &vertex_step, &hanging);
    let largest = by_exitance.iter().copied().fold(0.0f32, f32::max);
    assert!(largest > 0.1, "the field varies: {largest}");
    for (i, (x, h)) in by_exitance.iter().zip(&by_irradiance).enumerate() {
        // f32 rounding of B/ρ, a mean and ρ·ΔH: a few ulps of values of order 1.
        assert!((x - h).abs() <= 1e-6 * largest.max(1.0) * 8.0, "element {i}: exitance {x}, irradiance {h}");
    }
    let all = vec![true; exitance.len()];
    for threshold in [0.02, 0.1, 0.2, 0.5] {
        let a = elements_to_split(&mesh, &exitance, &by_exitance, threshold, 0.05, 0.001, &all);
        let b = elements_to_split(&mesh, &exitance, &by_irradiance, threshold, 0.05, 0.001, &all);
        let count = a.iter().filter(|&&s| s).count();
        assert!(count > 0 && count < a.len(), "τ = {threshold}: {count} of {} split", a.len());
        assert_eq!(a, b, "τ = {threshold}: the two criteria split different elements");
    }
}

/// A checker of albedos 0.8 and 0.1, one square per element, on the 10 × 10 floor. Under flat light
/// (H = 1) the exitance jumps eightfold between neighbours and the exitance criterion splits every
/// element; the irradiance criterion splits none. With a shadow boundary at x = 0.5 (H = 1 for
/// x < 0.45, 0.2 for x > 0.55, linear between: the element centres see a step from 1 to 0.2) it
/// splits the two columns beside it, and on the floor's outline rows (z = 0.05, 0.95) also the next
/// element on either side: their outline corners at x = 0.4 and 0.6 are extrapolated
/// (`boundary_vertices::extrapolate`), and the penumbra element's least-squares slope through the
/// step carries into them, H_v = 1.17 and 0.1 against their own 1 and 0.2 (17% and 50%, over
/// τ = 10%): an interpolation error the image would show, whatever the albedo. Nothing else splits.
#[test]
fn a_textured_floor_is_split_at_a_shadow_boundary_not_at_its_texture() {
    let mut mesh = floor_mesh(0.1);
    let cell = |c: Vec3| ((c.x * 10.0).floor() + (c.z * 10.0).floor()) as i32 % 2 == 0;
    for i in 0..mesh.elements.len() {
        mesh.elements.reflectance[i] = Vec3::splat(if cell(mesh.elements.centre[i]) { 0.8 } else { 0.1 });
    }
    let vertex_step = SmoothMesh::new(&mesh);
    let all = vec![true; mesh.elements.len()];
    let rho = mesh.elements.reflectance.clone();
    let exitance_under = |h: &dyn Fn(f32) -> f32| -> Vec<Vec3> {
        mesh.elements.centre.iter().zip(&rho).map(|(c, r)| *r * h(c.x)).collect()
    };
    // Flat light.
    let flat = exitance_under(&|_| 1.0);
    let vertex = vertex_step.vertex_values(&flat.iter().map(|b| b.as_dvec3()).collect::<Vec<_>>());
    let by_exitance = elements_to_split(&mesh, &flat, &variation(&mesh, &flat, &vertex, None), 0.1, 0.05, 0.01, &all);
    assert!(by_exitance.iter().all(|&s| s), "the texture alone splits every element by exitance");
    let by_irradiance =
        elements_to_split(&mesh, &flat, &irradiance_variation(&mesh, &flat, &vertex_step, &[]), 0.1, 0.05, 0.01, &all);
    assert!(by_irradiance.iter().all(|&s| !s), "flat light: nothing to split");
    // A shadow boundary.
    let shadow = |x: f32| {
        if x < 0.45 {
            1.0
        } else if x > 0.55 {
            0.2
        } else {
            1.0 - 8.0 * (x - 0.45)
        }
    };
    let shaded = exitance_under(&shadow);
    let chosen = elements_to_split(
        &mesh,
        &shaded,
        &irradiance_variation(&mesh, &shaded, &vertex_step, &[]),
        0.1,
        0.05,
        0.01,
        &all,
    );
    for (e, c) in mesh.elements.centre.iter().enumerate() {
        let outline_row = c.z < 0.1 || c.z > 0.9;
        let expected = (c.x - 0.5).abs() < 0.1 || (outline_row && (c.x - 0.5).abs() < 0.2);
        assert_eq!(chosen[e], expected, "element at x = {}, z = {}", c.x, c.z);
    }
}

/// A floor [−1, 1]² at z = 0 facing up, textured by an 8 × 8 checker of sRGB 200 and 60 (Kd 0.9, one
/// texel per element at the 0.25 edge, so neighbouring elements' mean albedos differ 12-fold), under
/// a lamp (Kd 0, Ke 1) at height 0.05 facing down over x in [−1.5, `lamp_x_max`], y in [−1.5, 1.5];
/// solved by the adaptive method without refining (`adaptive_levels = 0`): the patch mesh and its
/// solution.
fn checker_under_lamp(lamp_x_max: f32) -> (Mesh, std::sync::Arc<radray::radiosity::Solution>) {
    let dir = tempfile::tempdir().expect("temp dir");
    let grey: Vec<u8> = (0..64).map(|k| if (k % 8 + k / 8) % 2 == 0 { 200 } else { 60 }).collect();
    let image = image::GrayImage::from_raw(8, 8, grey).expect("size matches");
    image.save(dir.path().join("c.png")).expect("write PNG");
    let x = lamp_x_max;
    let obj = format!(
        "mtllib m.mtl\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nv {x} -1.5 0.05\nv -1.5 -1.5 0.05\nv -1.5 1.5 0.05\n\
         v {x} 1.5 0.05\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl floor\nf 1/1 2/2 3/3 4/4\nusemtl lamp\nf 5 6 7 8\n"
    );
    std::fs::write(dir.path().join("m.obj"), obj).expect("write OBJ");
    let mtl = "newmtl lamp\nKd 0 0 0\nKe 1 1 1\n\nnewmtl floor\nKd 0.9 0.9 0.9\nmap_Kd c.png\n";
    std::fs::write(dir.path().join("m.mtl"), mtl).expect("write MTL");
    let toml = "[camera]\neye = [0.0, 0.0, 0.05]\nlook_at = [0.0, 0.0, 0.0]\nup = [0.0, 1.0, 0.0]\nvfov_deg = 60.0\n\n\
                [image]\nwidth = 8\nheight = 8\nsamples_per_pixel = 1\n\n[radiosity]\nmax_element_edge = 0.25\n\
                method = \"adaptive\"\nadaptive_levels = 0\n\n[[mesh]]\nobj = \"m.obj\"\n";
    std::fs::write(dir.path().join("scene.toml"), toml).expect("write scene");
    let scene = scene::load(&dir.path().join("scene.toml")).expect("scene loads");
    let mut stats = RunStats::default();
    run::pass_one(&scene, None, &RunPhotons::default(), &Progress::hidden(), &mut stats).expect("pass one")
}

/// The split decisions on the floor of `checker_under_lamp` by the exitance and by the irradiance
/// criterion (τ = 0.1, floor 5%), with the centres of the floor's elements.
fn checker_decisions(lamp_x_max: f32) -> Vec<(Vec3, bool, bool)> {
    let (mesh, solution) = checker_under_lamp(lamp_x_max);
    let e = &mesh.elements;
    let vertex_step = SmoothMesh::new(&mesh);
    let all = vec![true; e.len()];
    let exitance = &solution.element_exitance;
    let by_exitance = variation(&mesh, exitance, &solution.vertex_exitance, None);
    let by_exitance = elements_to_split(&mesh, exitance, &by_exitance, 0.1, 0.05, 0.01, &all);
    let by_irradiance = irradiance_variation(&mesh, exitance, &vertex_step, &[]);
    let by_irradiance = elements_to_split(&mesh, exitance, &by_irradiance, 0.1, 0.05, 0.01, &all);
    let floor: Vec<usize> = (0..e.len()).filter(|&i| e.centre[i].z.abs() < 1e-6).collect();
    assert_eq!(floor.len(), 64);
    floor.into_iter().map(|i| (e.centre[i], by_exitance[i], by_irradiance[i])).collect()
}

/// End to end, through a real texture and solve: under a lamp wider than the floor (flat light, within
/// 1% over the floor) the checker alone would split nearly every floor element by exitance, and the
/// irradiance criterion splits none. With the lamp ending at x = 0 it splits the two columns beside
/// the edge, every element of them, and nothing farther than 0.5 from it. Beyond its edge a lamp at
/// height h lights the floor at distance d with irradiance ∝ (1 − d/√(d² + h²))/2 ≈ h²/4d²; at
/// h = 0.05 that tail varies across the elements past 0.5 by under a third of the limit
/// τ·f·B_ref (the 5% floor of the brightest exitance), so the light there is flat for the criterion.
#[test]
fn a_checker_textured_floor_under_a_solved_lamp_is_split_at_the_lamps_edge_not_at_its_checks() {
    let flat = checker_decisions(1.5);
    let by_exitance = flat.iter().filter(|d| d.1).count();
    assert!(by_exitance >= 48, "the checker splits {by_exitance} of 64 by exitance");
    let by_irradiance: Vec<Vec3> = flat.iter().filter(|d| d.2).map(|d| d.0).collect();
    assert!(by_irradiance.is_empty(), "flat light, split at {by_irradiance:?}");
    for (centre, _, split) in checker_decisions(0.0) {
        if centre.x.abs() < 0.25 {
            assert!(split, "beside the lamp's edge, at {centre}: not split");
        } else if centre.x.abs() > 0.5 {
            assert!(!split, "far from the lamp's edge, at {centre}: split");
        }
    }
}

/// Two quads side by side; the left one split twice at its right neighbour's edge. Every midpoint on
/// the unsplit quad's edge hangs and takes the linear interpolation of that edge's ends, so the
/// values along the edge are the same from both sides.
#[test]
fn a_hanging_vertex_takes_its_edges_interpolated_value() {
    let mesh = floor_mesh(0.5);
    assert_eq!(mesh.elements.len(), 4);
    let mut midpoints = EdgeMidpoints::default();
    let once = split(&mesh, &[true, false, false, false], &mut midpoints);
    assert_eq!(once.elements.len(), 7);
    let area: f32 = once.elements.area.iter().sum();
    assert!((area - 1.0).abs() < 1e-5, "area {area}");
    // Split the child of element 0 that touches the most split edges again.
    let again: Vec<bool> = (0..once.elements.len()).map(|e| e == 1).collect();
    let twice = split(&once, &again, &mut midpoints);
    let hanging = hanging_vertices(&twice, &midpoints);
    assert!(!hanging.is_empty());
    // Values linear in x + 2z at the original corners; every hanging vertex must land on that plane.
    let f = |p: Vec3| Vec3::splat(p.x + 2.0 * p.z);
    let mut values: Vec<Vec3> =
        twice
            .positions
            .iter()
            .map(|&p| {
                if hanging.iter().any(|h| twice.positions[h.vertex as usize] == p) {
                    Vec3::splat(-99.0)
                } else {
                    f(p)
                }
            })
            .collect();
    conform(&mut values, &hanging);
    for h in &hanging {
        let p = twice.positions[h.vertex as usize];
        assert!((values[h.vertex as usize] - f(p)).abs().max_element() < 1e-5, "hanging vertex at {p}");
        let (a, b) = h.ends;
        let (pa, pb) = (twice.positions[a as usize], twice.positions[b as usize]);
        assert!(((pa + pb) * 0.5 - p).length() < 1e-6, "a hanging vertex sits at its edge's midpoint");
        // The edge (a, b) is an edge of an unsplit element (that is what makes it hang), or lies
        // inside one.
        let on_unsplit_edge = twice.elements.corners.iter().any(|c| {
            let n = if c[3] == radray::mesh::NONE { 3 } else { 4 };
            (0..n).any(|k| {
                let (u, v) = (twice.positions[c[k] as usize], twice.positions[c[(k + 1) % n] as usize]);
                (u - v).cross(p - u).length() < 1e-6 && (p - u).dot(p - v) < 0.0
            })
        });
        assert!(on_unsplit_edge, "hanging vertex at {p} lies inside an element edge");
    }
}

/// Refinement decisions are serial and every level's form factors are row-independent, so the
/// refined mesh and its solution are the same bits on one thread and on two.
#[test]
fn the_refined_solution_is_the_same_at_any_thread_count() {
    let on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(refined_furnace)
    };
    let ((_, mesh_1, solution_1), (_, mesh_2, solution_2)) = (on(1), on(2));
    assert_eq!(mesh_1.positions, mesh_2.positions);
    assert_eq!(mesh_1.elements.corners, mesh_2.elements.corners);
    assert_eq!(solution_1.element_exitance, solution_2.element_exitance);
    assert_eq!(solution_1.vertex_exitance, solution_2.vertex_exitance);
}

/// Extrapolated boundary values of `element` on `mesh` (no T-vertices), interior vertices averaged:
/// the shared vertex step (`vertex_values`).
fn extrapolated(mesh: &Mesh, element: &[Vec3]) -> Vec<Vec3> {
    let wide: Vec<_> = element.iter().map(|v| v.as_dvec3()).collect();
    vertex_values(mesh, &wide, &boundary_vertices(mesh, &|_, _| None))
}

/// On a 10 × 10 grid with a linear solution B = 1 + 2x + 0.5z (all positive), every vertex value,
/// boundary and corners included, is B at the vertex: extrapolation is exact for linear data (f32
/// rounding: 1e-5), where the plain average is off by half an element's change at the boundary.
#[test]
fn boundary_vertices_are_exact_on_a_linear_solution() {
    let mesh = floor_mesh(0.1);
    let b = |p: Vec3| Vec3::splat(1.0 + 2.0 * p.x + 0.5 * p.z);
    let element: Vec<Vec3> = mesh.elements.centre.iter().map(|&c| b(c)).collect();
    let boundary = boundary_vertices(&mesh, &|_, _| None);
    assert_eq!(boundary.iter().filter(|&&x| x).count(), 40, "the grid's outline has 40 vertices");
    let vertex = extrapolated(&mesh, &element);
    for (v, &p) in mesh.positions.iter().enumerate() {
        assert!((vertex[v] - b(p)).abs().max_element() < 1e-5, "vertex at {p}: {} against {}", vertex[v], b(p));
    }
}

/// A step (1 for x < 0.5, 0.2 beyond) reaching the boundary: the extrapolated values stay within the
/// limiter's range, [lo − (hi − lo)/2, hi + (hi − lo)/2] of each element's neighbourhood, and never
/// go negative, so a shadow boundary is not extrapolated into a spike.
#[test]
fn boundary_extrapolation_is_limited_at_a_step() {
    let mesh = floor_mesh(0.1);
    let element: Vec<Vec3> =
        mesh.elements.centre.iter().map(|c| Vec3::splat(if c.x < 0.5 { 1.0 } else { 0.2 })).collect();
    let vertex = extrapolated(&mesh, &element);
    for (v, p) in mesh.positions.iter().enumerate() {
        let x = vertex[v].x;
        assert!((-1e-6..=1.4 + 1e-6).contains(&x), "vertex at {p}: {x}");
        if p.x < 0.35 || p.x > 0.65 {
            let flat = if p.x < 0.5 { 1.0 } else { 0.2 };
            assert!((x - flat).abs() < 1e-6, "vertex at {p} two elements from the step: {x}");
        }
    }
}

/// The ceiling beside a wall lamp, analytically: a floor (the receiver, 10 × 10 elements of 0.1)
/// meets at x = 0 the plane of a lamp (y 0.2–0.5, z 0.3–0.7, facing +x, exitance E = 1), so its
/// direct exitance ρ·E·F(p → lamp) (Lambert's point-to-polygon form factor, exact) falls to zero at
/// the edge x = 0, where every direction to the lamp grazes the lamp's plane. Element values are the
/// exact values at the centres (a hemicube's row is a point value at the centre). Along that edge,
/// Gouraud's average shows the value half an element in. The extrapolation is exact only for linear
/// data and F bends within an element here (it peaks about 0.2 from the wall), so it is not exact:
/// it is at least 1.5× closer at every vertex of that edge (1.64× where the lamp is widest) and 2×
/// closer summed along it (2.18×; the values are exact arithmetic, no sampling), and no worse than
/// the average anywhere else on the outline.
#[test]
fn boundary_vertices_beside_a_wall_lamp_follow_lamberts_form_factor() {
    let mesh = floor_mesh(0.1);
    let lamp = [Vec3::new(0.0, 0.2, 0.3), Vec3::new(0.0, 0.5, 0.3), Vec3::new(0.0, 0.5, 0.7), Vec3::new(0.0, 0.2, 0.7)];
    let exact = |p: Vec3| 0.5 * point_to_polygon(p, Vec3::Y, &lamp) as f32;
    let element: Vec<Vec3> = mesh.elements.centre.iter().map(|&c| Vec3::splat(exact(c))).collect();
    let average: Vec<Vec3> = mesh
        .vertex_average(&element.iter().map(|v| v.as_dvec3()).collect::<Vec<_>>())
        .iter()
        .map(|v| v.as_vec3())
        .collect();
    let vertex = extrapolated(&mesh, &element);
    let boundary = boundary_vertices(&mesh, &|_, _| None);
    let (mut edge_average, mut edge_extrapolated) = (0.0f32, 0.0f32);
    for (v, &p) in mesh.positions.iter().enumerate().filter(|&(v, _)| boundary[v]) {
        let (a, x) = ((average[v].x - exact(p)).abs(), (vertex[v].x - exact(p)).abs());
        if p.x == 0.0 {
            assert_eq!(exact(p), 0.0, "the lamp's plane: no direct light");
            assert!(1.5 * x <= a, "edge vertex at {p}: extrapolated error {x} against the average's {a}");
            edge_average += a;
            edge_extrapolated += x;
        } else {
            assert!(x <= a + 1e-6, "vertex at {p}: extrapolated error {x} against the average's {a}");
        }
    }
    assert!(edge_average > 0.1, "the average is visibly off along the edge: {edge_average}");
    assert!(2.0 * edge_extrapolated < edge_average, "edge error {edge_extrapolated} against {edge_average}");
}

/// A floor and a wall meeting in a concave corner along x = 0, 10 × 10 elements each. When the floor
/// elements along the corner are marked for splitting, the wall elements along the corner (and only
/// they) are marked too; the floor's other elements, and elements on the same surface, are not.
#[test]
fn refinement_is_carried_across_a_concave_corner_and_nowhere_else() {
    let wall = quad("wall", [Vec3::ZERO, Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.0, 1.0, 1.0), Vec3::new(0.0, 0.0, 1.0)]);
    let mesh = mesh_of(vec![floor(), wall], 0.1);
    assert_eq!(mesh.elements.len(), 200);
    let e = &mesh.elements;
    let on_floor = |i: usize| e.normal[i].y > 0.5;
    let marked: Vec<bool> = (0..e.len()).map(|i| on_floor(i) && e.centre[i].x < 0.1).collect();
    let out = across_concave_edges(&mesh, &marked, 0.01, &vec![true; e.len()]);
    for i in 0..e.len() {
        let expected = if on_floor(i) { marked[i] } else { e.centre[i].y < 0.1 };
        assert_eq!(out[i], expected, "element at {} (floor: {})", e.centre[i], on_floor(i));
    }
    // Elements too small to split (longest edge under twice the minimum) are left alone.
    let none = across_concave_edges(&mesh, &marked, 0.06, &vec![true; e.len()]);
    assert_eq!(none, marked);
}

/// A glowing wall standing on a floor (a lamp on a table): with nothing marked by the solution, the
/// floor elements along the wall's foot are split, the emitter's own elements are not, and nothing else
/// is. The same wall lifted off the floor (no concave edge) marks nothing.
#[test]
fn the_surface_at_an_emitters_foot_is_refined_beside_it() {
    let emitting = |mut mesh: Mesh| {
        for i in 0..mesh.elements.len() {
            if mesh.elements.normal[i].x > 0.5 {
                mesh.elements.emission[i] = Vec3::splat(10.0);
            }
        }
        mesh
    };
    let wall = |y0: f32| {
        let (a, b) = (Vec3::new(0.0, y0, 0.0), Vec3::new(0.0, y0, 1.0));
        quad("lamp", [a, a + Vec3::Y, b + Vec3::Y, b])
    };
    let mesh = emitting(mesh_of(vec![floor(), wall(0.0)], 0.1));
    let e = &mesh.elements;
    let nothing = vec![false; e.len()];
    let out = across_concave_edges_and_emitters(&mesh, &nothing, 0.01, &vec![true; e.len()]);
    for (i, &marked) in out.iter().enumerate() {
        let at_foot = e.normal[i].y > 0.5 && e.centre[i].x < 0.1;
        assert_eq!(marked, at_foot, "element at {} (emitting: {})", e.centre[i], e.emission[i].x > 0.0);
    }
    assert_eq!(out.iter().filter(|&&s| s).count(), 10);
    // The plain rule carries only what the solution marked.
    assert_eq!(across_concave_edges(&mesh, &nothing, 0.01, &vec![true; e.len()]), nothing);
    // Lifted by half a metre, the lamp's elements no longer touch the floor's.
    let lifted = emitting(mesh_of(vec![floor(), wall(0.5)], 0.1));
    let none = vec![false; lifted.elements.len()];
    assert_eq!(across_concave_edges_and_emitters(&lifted, &none, 0.01, &vec![true; none.len()]), none);
}

/// A floor of 0.25 m elements and an arbitrary matrix with every entry distinct:
/// F_ij = (1 + i + 3j) / 1000 off the diagonal.
fn floor_with_distinct_form_factors() -> (Mesh, FormFactors) {
    let coarse = floor_mesh(0.25);
    let n = coarse.elements.len();
    let rows: Vec<Vec<(u32, f32)>> = (0..n)
        .map(|i| (0..n).filter(|&j| j != i).map(|j| (j as u32, (1 + i + 3 * j) as f32 / 1000.0)).collect())
        .collect();
    (coarse, FormFactors::from_rows(rows))
}

/// Substructuring: the rows kept for unsplit elements share a split element's form factor among its
/// children by area, so every kept row sums to what it summed before the split, and a kept entry to
/// an unsplit element is unchanged.
#[test]
fn kept_rows_conserve_each_rows_sum() {
    let (coarse, ff) = floor_with_distinct_form_factors();
    let n = coarse.elements.len();
    let chosen: Vec<bool> = (0..n).map(|i| i % 3 == 0).collect();
    let refined = split(&coarse, &chosen, &mut EdgeMidpoints::default());
    let kept = kept_rows(&coarse, &ff, &chosen, &refined);
    assert_eq!(kept.len(), refined.elements.len());
    assert_eq!(kept.done_count(), chosen.iter().filter(|&&c| !c).count());
    let index = new_indices(&chosen);
    for i in (0..n).filter(|&i| !chosen[i]) {
        let row = index[i].start as usize;
        assert!((kept.ff.row_sum(row) - ff.row_sum(i)).abs() < 1e-6, "row {i}");
        for j in (0..n).filter(|&j| !chosen[j] && j != i) {
            assert_eq!(kept.ff.get(row, index[j].start as usize), ff.get(i, j));
        }
    }
}

#[test]
fn kept_rows_share_a_split_elements_form_factor_among_its_open_children_only() {
    // The receiver's hemicube saw only the open part of a patch that an object rests on; a buried
    // child's share would gather light the receiver never saw. One child buried: the others take the
    // whole form factor by their area, so each row's sum is still kept.
    let (coarse, ff) = floor_with_distinct_form_factors();
    let n = coarse.elements.len();
    let chosen: Vec<bool> = (0..n).map(|i| i == 5).collect();
    let mut refined = split(&coarse, &chosen, &mut EdgeMidpoints::default());
    let children = new_indices(&chosen)[5].clone();
    refined.element_buried = vec![false; refined.elements.len()];
    refined.element_buried[children.start as usize] = true;
    let kept = kept_rows(&coarse, &ff, &chosen, &refined);
    let open_area: f64 = children.clone().skip(1).map(|c| refined.elements.area[c as usize] as f64).sum();
    for i in (0..n).filter(|&i| i != 5) {
        let row = new_indices(&chosen)[i].start as usize;
        assert!((kept.ff.row_sum(row) - ff.row_sum(i)).abs() < 1e-6, "row {i}");
        assert_eq!(kept.ff.get(row, children.start as usize), 0.0, "the buried child gets no share");
        for c in children.clone().skip(1) {
            let expected = ff.get(i, 5) * refined.elements.area[c as usize] as f64 / open_area;
            assert!((kept.ff.get(row, c as usize) - expected).abs() < 1e-7, "row {i}, child {c}");
        }
    }
}

/// A linear solution B = 1 + 2x + 0.5z on a refined floor (a 10 × 10 grid, a band of elements split
/// once and its middle split again, as two adaptive levels leave it) comes back exactly at every
/// vertex, the corners where coarse and fine elements meet included (f32 rounding: 1e-5). There the
/// plain area mean is biased by the offset of its elements' weighted centroid from the vertex: a
/// coarse element's centre lies twice as far as a fine one's and weighs four times as much, so the
/// mean leans towards the coarse side by about 0.7 fine half-widths of the slope (the ridge along
/// cornell_empty's refinement boundaries, docs/accuracy.md session 34).
#[test]
fn a_linear_solution_is_exact_at_every_vertex_of_a_refined_mesh() {
    let coarse = floor_mesh(0.1);
    let mut midpoints = EdgeMidpoints::default();
    let band: Vec<bool> = coarse.elements.centre.iter().map(|c| (0.3..0.7).contains(&c.x)).collect();
    let once = split(&coarse, &band, &mut midpoints);
    let middle: Vec<bool> =
        once.elements.centre.iter().map(|c| (0.4..0.6).contains(&c.x) && (0.3..0.7).contains(&c.z)).collect();
    let mesh = split(&once, &middle, &mut midpoints);
    let hanging = hanging_vertices(&mesh, &midpoints);
    assert!(!hanging.is_empty(), "the refinement leaves T-vertices");
    let b = |p: Vec3| Vec3::splat(1.0 + 2.0 * p.x + 0.5 * p.z);
    let element: Vec<_> = mesh.elements.centre.iter().map(|&c| b(c).as_dvec3()).collect();
    let vertex = conforming_vertex_values(&SmoothMesh::new(&mesh), &element, &hanging);
    let mean = mesh.vertex_average(&element);
    let inside = |p: Vec3| p.x > 0.01 && p.x < 0.99 && p.z > 0.01 && p.z < 0.99;
    let hangs = |v: usize| hanging.iter().any(|h| h.vertex as usize == v);
    let worst_mean = (0..mesh.positions.len())
        .filter(|&v| inside(mesh.positions[v]) && !hangs(v))
        .map(|v| (mean[v].as_vec3() - b(mesh.positions[v])).abs().max_element())
        .fold(0.0, f32::max);
    assert!(worst_mean > 0.01, "the plain mean is off at a corner inside the floor: {worst_mean}");
    for (v, &p) in mesh.positions.iter().enumerate() {
        assert!((vertex[v] - b(p)).abs().max_element() < 1e-5, "vertex at {p}: {} against {}", vertex[v], b(p));
    }
}

/// A 2 × 2 floor (Kd 0.5) meshed into 0.5 m patches, a 0.1 m lamp 1 m above its centre line x = 1, and
/// a 6 cm bar along z halfway up, whose shadow (x within about 6 cm of 1) falls on the patch corners at
/// x = 1 and between every patch centre (0.25, 0.75, 1.25, 1.75).
fn floor_under_a_barred_lamp() -> (SceneDescription, Mesh) {
    floor_under_a_bar(Material { emitted_radiance: Vec3::splat(10.0), ..Material::diffuse("lamp", Vec3::ZERO) })
}

/// `floor_under_a_barred_lamp` with `panel` in the lamp's place (surface 1).
fn floor_under_a_bar(panel: Material) -> (SceneDescription, Mesh) {
    let at = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    let facing_down = |object: &str, x0: f32, x1: f32, y: f32, z0: f32, z1: f32, material: u32| Surface {
        material,
        ..quad(object, [at(x0, y, z0), at(x1, y, z0), at(x1, y, z1), at(x0, y, z1)])
    };
    let floor = quad("floor", [at(0.0, 0.0, 0.0), at(0.0, 0.0, 2.0), at(2.0, 0.0, 2.0), at(2.0, 0.0, 0.0)]);
    let scene = scene_of(
        vec![Material::diffuse("floor", Vec3::splat(0.5)), panel],
        vec![
            floor,
            facing_down("panel", 0.95, 1.05, 1.0, 0.95, 1.05, 1),
            facing_down("bar", 0.97, 1.03, 0.5, -1.0, 3.0, 0),
        ],
    );
    let mesh = Mesh::build(&scene, 0.5);
    (scene, mesh)
}

#[test]
fn a_shadow_between_the_patch_centres_is_found_at_their_corners() {
    // The patches beside the shadow (a corner at x = 1) see the lamp blocked at that corner only: their
    // blocked light spreads by about ρ·E_d there. The patches farther out see it at no corner: 0
    // exactly. Every patch centre is lit alike, so the solution's own values show no shadow.
    let (scene, mesh) = floor_under_a_barred_lamp();
    let accel = radray::accel::Accel::build(&mesh.positions, &mesh.triangles);
    let floor: Vec<usize> = (0..mesh.elements.len()).filter(|&e| mesh.elements.normal[e].y > 0.5).collect();
    assert_eq!(floor.len(), 16);
    let wanted: Vec<bool> = (0..mesh.elements.len()).map(|e| floor.contains(&e)).collect();
    // Only the lamp lights the floor: no element reflects anything yet.
    let unlit = mesh.elements.emission.clone();
    let spread =
        blocked_light_variation(&mesh, &scene.materials, &unlit, &accel, &wanted, 1, BlockedLightTest::CornerSpread);
    for &e in &floor {
        let c = mesh.elements.centre[e];
        // ρ·E_d at the shadow's centre: the lamp (L = 10, 0.1 × 0.1 m) 1 m straight up, E ≈ L·A/d².
        let shadowed = 0.5 * 10.0 * 0.01;
        println!("patch at ({}, {}): spread {} (ρ·E_d {shadowed})", c.x, c.z, spread[e]);
        if (c.x - 1.0).abs() < 0.5 {
            assert!(spread[e] > 0.5 * shadowed, "patch at x = {}: spread {}", c.x, spread[e]);
        } else {
            assert_eq!(spread[e], 0.0, "patch at x = {}", c.x);
        }
    }
}

#[test]
fn a_streak_between_the_corners_is_found_by_the_interpolation_error_not_by_the_spread() {
    // One floor element 0.5 m square centred under the barred lamp (x from 0.75 to 1.25): the bar's
    // shadow (x within about 6 cm of 1) crosses its middle and misses all four corners. The corners see
    // no light blocked, so their spread is 0 exactly; the centre and the midpoints of the two edges
    // across the shadow lie in it, fully blocked, so the interpolation error is ρ·E_d there.
    let at = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    let facing_down = |object: &str, x0: f32, x1: f32, y: f32, z0: f32, z1: f32, material: u32| Surface {
        material,
        ..quad(object, [at(x0, y, z0), at(x1, y, z0), at(x1, y, z1), at(x0, y, z1)])
    };
    let lamp = Material { emitted_radiance: Vec3::splat(10.0), ..Material::diffuse("lamp", Vec3::ZERO) };
    let scene = scene_of(
        vec![Material::diffuse("floor", Vec3::splat(0.5)), lamp],
        vec![
            quad("floor", [at(0.75, 0.0, 0.0), at(0.75, 0.0, 0.5), at(1.25, 0.0, 0.5), at(1.25, 0.0, 0.0)]),
            facing_down("panel", 0.95, 1.05, 1.0, 0.2, 0.3, 1),
            facing_down("bar", 0.97, 1.03, 0.5, -1.0, 2.0, 0),
        ],
    );
    let mesh = Mesh::build(&scene, 0.5);
    let accel = radray::accel::Accel::build(&mesh.positions, &mesh.triangles);
    let wanted: Vec<bool> = (0..mesh.elements.len()).map(|e| mesh.elements.surface[e] == 0).collect();
    assert_eq!(wanted.iter().filter(|&&w| w).count(), 1, "the floor is one element");
    let floor = wanted.iter().position(|&w| w).unwrap();
    let unlit = mesh.elements.emission.clone();
    let variation = |test| blocked_light_variation(&mesh, &scene.materials, &unlit, &accel, &wanted, 1, test)[floor];
    // ρ·E_d under the lamp (L = 10, 0.1 × 0.1 m, 1 m up): 0.5 · 10 · 0.01.
    let shadowed = 0.5 * 10.0 * 0.01;
    assert_eq!(variation(BlockedLightTest::CornerSpread), 0.0);
    let error = variation(BlockedLightTest::Interpolation);
    assert!((error / shadowed - 1.0).abs() < 0.2, "interpolation error {error} against ρ·E_d {shadowed}");
}

#[test]
fn a_shadow_of_reflected_light_between_the_patch_centres_is_found_at_their_corners() {
    // The lamp of the test above made a reflector: a white panel that emits nothing and reflects the
    // exitance B = π·10 (a ceiling lit from below). No emitter, so only the rays to the reflecting
    // elements can find the bar's shadow; they find it as the lamp's.
    let (scene, mesh) = floor_under_a_bar(Material::diffuse("panel", Vec3::ONE));
    let accel = radray::accel::Accel::build(&mesh.positions, &mesh.triangles);
    let panel = |e: usize| mesh.elements.surface[e] == 1;
    let exitance: Vec<Vec3> = (0..mesh.elements.len())
        .map(|e| if panel(e) { Vec3::splat(std::f32::consts::PI * 10.0) } else { Vec3::ZERO })
        .collect();
    let floor: Vec<usize> = (0..mesh.elements.len()).filter(|&e| mesh.elements.normal[e].y > 0.5).collect();
    assert_eq!(floor.len(), 16);
    let wanted: Vec<bool> = (0..mesh.elements.len()).map(|e| floor.contains(&e)).collect();
    let spread =
        blocked_light_variation(&mesh, &scene.materials, &exitance, &accel, &wanted, 1, BlockedLightTest::CornerSpread);
    let shadowed = 0.5 * 10.0 * 0.01; // ρ·B·A/(π d²), as the lamp's
    for &e in &floor {
        let x = mesh.elements.centre[e].x;
        if (x - 1.0).abs() < 0.5 {
            assert!(spread[e] > 0.5 * shadowed, "patch at x = {x}: spread {}", spread[e]);
        } else {
            assert_eq!(spread[e], 0.0, "patch at x = {x}");
        }
    }
}

#[test]
fn the_reflected_light_a_wall_blocks_is_the_point_to_polygon_form_factor() {
    // A point 1 m under a 1 m reflecting square (B = 2), a slab between them hiding all of it: the
    // blocked irradiance is all the square sends, B·F(point → square), F Lambert's exact form factor.
    let at = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
    let square = [at(-0.5, 1.0, -0.5), at(0.5, 1.0, -0.5), at(0.5, 1.0, 0.5), at(-0.5, 1.0, 0.5)];
    let slab = [at(-2.0, 0.5, -2.0), at(2.0, 0.5, -2.0), at(2.0, 0.5, 2.0), at(-2.0, 0.5, 2.0)];
    let scene = scene_of(vec![Material::diffuse("white", Vec3::ONE)], vec![quad("square", square), quad("slab", slab)]);
    let mesh = Mesh::build(&scene, 0.25);
    let accel = radray::accel::Accel::build(&mesh.positions, &mesh.triangles);
    let exitance: Vec<Vec3> = (0..mesh.elements.len())
        .map(|e| if mesh.elements.surface[e] == 0 { Vec3::splat(2.0) } else { Vec3::ZERO })
        .collect();
    let reflectors = Reflectors::new(&mesh, &exitance).expect("the square reflects");
    let points = reflectors.draw(&mesh, 4096, &mut radray::rng::Pcg32::new(7, 0));
    let x = at(0.1, 0.0, 0.2);
    let blocked = reflectors.blocked_irradiance(&mesh, &accel, x, Vec3::Y, &points);
    let exact = 2.0 * point_to_polygon(x, Vec3::Y, &square) as f32;
    assert!((blocked.x / exact - 1.0).abs() < 0.02, "blocked {} against B·F {exact}", blocked.x);
    // Without the slab nothing is blocked.
    let open = scene_of(vec![Material::diffuse("white", Vec3::ONE)], vec![quad("square", square)]);
    let mesh = Mesh::build(&open, 0.25);
    let accel = radray::accel::Accel::build(&mesh.positions, &mesh.triangles);
    let exitance = vec![Vec3::splat(2.0); mesh.elements.len()];
    let reflectors = Reflectors::new(&mesh, &exitance).expect("the square reflects");
    let points = reflectors.draw(&mesh, 256, &mut radray::rng::Pcg32::new(7, 0));
    assert_eq!(reflectors.blocked_irradiance(&mesh, &accel, x, Vec3::Y, &points), Vec3::ZERO);
}

/// A 0.1 m receiver square at the origin facing up, and a 1 m square at `height` above it facing down.
fn receiver_under_a_square(height: f32) -> (Vec<Vec3>, Mesh) {
    let at = Vec3::new;
    let r = 0.05;
    let receiver = [at(-r, 0.0, -r), at(-r, 0.0, r), at(r, 0.0, r), at(r, 0.0, -r)];
    let source = [at(-0.5, height, -0.5), at(0.5, height, -0.5), at(0.5, height, 0.5), at(-0.5, height, 0.5)];
    let white = vec![Material::diffuse("white", Vec3::splat(0.5))];
    let scene = scene_of(white, vec![quad("receiver", receiver), quad("source", source)]);
    (source.to_vec(), Mesh::build(&scene, 1.0))
}

/// The patches (one receiver, one source square) refined twice: the square into four, then one of its
/// quarters into four again (leaves of two sizes), with each patch's leaves.
fn refined(patches: &Mesh) -> (Mesh, Vec<Range<u32>>) {
    assert_eq!(patches.elements.len(), 2);
    let source = (0..2).find(|&e| patches.elements.normal[e].y < 0.0).unwrap();
    let mut leaves: Vec<Range<u32>> = (0..2).map(|p| p..p + 1).collect();
    let mut mesh = patches.clone();
    let mut midpoints = EdgeMidpoints::default();
    for _ in 0..2 {
        // The first leaf of the square: the square itself, then its first quarter.
        let chosen: Vec<bool> = (0..mesh.elements.len()).map(|e| e == leaves[source].start as usize).collect();
        mesh = split(&mesh, &chosen, &mut midpoints);
        let index = new_indices(&chosen);
        for range in &mut leaves {
            *range = index[range.start as usize].start..index[range.end as usize - 1].end;
        }
    }
    assert_eq!(leaves[source].len(), 7);
    (mesh, leaves)
}

/// The receiver's row of a refined `receiver_under_a_square`, with and without the far patches drawn
/// whole (`radiosity::matrix::patch_cut`).
struct Rows {
    square: Vec<Vec3>,
    mesh: Mesh,
    with_cut: Vec<(u32, f32)>,
    leaf_by_leaf: Vec<(u32, f32)>,
}

fn cut_rows(height: f32) -> Rows {
    let (square, patches) = receiver_under_a_square(height);
    let (mesh, leaves) = refined(&patches);
    let receiver = (0..mesh.elements.len()).find(|&e| mesh.elements.normal[e].y > 0.0).unwrap();
    let params = RadiosityParams::default();
    let cut = PatchCut::new(&patches, &leaves, &mesh, params.hemicube_resolution_px);
    assert_eq!(cut.len(), 1, "the square is the one split patch");
    let hierarchy = ElementHierarchy::new(&mesh);
    let hc = Hemicube::new(params.hemicube_resolution_px);
    let mut buffers = ItemBuffer::new(&hc);
    let (mut with_cut, mut leaf_by_leaf) = (Vec::new(), Vec::new());
    hierarchy.element_row_cut(&mesh, &params, &hc, &mut buffers, receiver, Some(&cut), &mut with_cut);
    hierarchy.element_row(&mesh, &params, &hc, &mut buffers, receiver, &mut leaf_by_leaf);
    Rows { square, mesh, with_cut, leaf_by_leaf }
}

#[test]
fn a_far_split_patch_is_drawn_whole_and_its_form_factor_shared_by_area() {
    // 6 m away the square's radius (0.71 m) covers 128/2 · 0.71/6 ≈ 7.5 pixels: drawn whole.
    let height = 6.0;
    assert!(0.5f32.hypot(0.5) * 128.0 / 2.0 / height < FAR_PATCH_RADIUS_PX);
    let Rows { square, mesh, with_cut, leaf_by_leaf } = cut_rows(height);
    assert_eq!(with_cut.len(), 7, "every leaf gets a share: {with_cut:?}");
    assert!(with_cut.windows(2).all(|w| w[0].0 < w[1].0), "columns ascending");
    // Shared by area: F/A the same for every leaf.
    let density: Vec<f32> = with_cut.iter().map(|&(j, f)| f / mesh.elements.area[j as usize]).collect();
    for d in &density {
        assert!((d / density[0] - 1.0).abs() < 1e-5, "F/A per leaf {density:?}");
    }
    // The leaves tile the patch exactly under the rasteriser's fill rule, so the whole patch wins the
    // pixels its leaves win: the same sum. Both are Lambert's form factor within the hemicube's
    // aliasing for a square 15 pixels across (2%).
    let sum = |row: &[(u32, f32)]| row.iter().map(|&(_, f)| f64::from(f)).sum::<f64>();
    assert!((sum(&with_cut) / sum(&leaf_by_leaf) - 1.0).abs() < 1e-6, "whole against leaf by leaf");
    let exact = point_to_polygon(Vec3::new(0.0, 5e-5, 0.0), Vec3::Y, &square);
    assert!((sum(&with_cut) / exact - 1.0).abs() < 0.02, "whole {} against exact {exact}", sum(&with_cut));
}

#[test]
fn a_near_split_patch_is_drawn_leaf_by_leaf_as_without_the_cut() {
    // 1 m away the square covers ≈ 45 pixels of radius: its leaves are drawn, bit for bit as before.
    let Rows { with_cut, leaf_by_leaf, .. } = cut_rows(1.0);
    assert_eq!(with_cut.len(), 7);
    assert_eq!(with_cut, leaf_by_leaf);
}
