//! `method = "adaptive"` (issue 10's adaptive subdivision on the matrix path): the furnace stays exact
//! with the mesh refined, the refinement criterion splits along a shadow boundary and nowhere else,
//! and a hanging vertex takes its edge's interpolated value (no T-vertex cracks).

use std::path::Path;

use glam::Vec3;
use radray::mesh::Mesh;
use radray::progress::Progress;
use radray::radiosity::adaptive::criterion::elements_to_split;
use radray::radiosity::adaptive::hanging::{conform, hanging_vertices};
use radray::radiosity::adaptive::subdivide::{split, EdgeMidpoints};
use radray::run::{self, RunStats};
use radray::scene::{self, Camera, ImageSettings, Material, MethodChoice, RadiosityParams, RenderParams};
use radray::scene::{SceneDescription, SourceLoc, Surface};
use radray::transport::photons::RunPhotons;

/// A 1 × 1 floor quad (y = 0, facing up), meshed uniformly at `edge`.
fn floor_mesh(edge: f32) -> Mesh {
    let floor = Surface {
        vertices: vec![Vec3::ZERO, Vec3::new(0.0, 0.0, 1.0), Vec3::new(1.0, 0.0, 1.0), Vec3::new(1.0, 0.0, 0.0)],
        material: 0,
        two_sided: false,
        shading_normals: None,
        uvs: None,
        object: "floor".into(),
        source: SourceLoc::default(),
    };
    let scene = SceneDescription {
        path: "test".into(),
        camera: Camera { eye: Vec3::Y, look_at: Vec3::ZERO, up: Vec3::Z, vfov_deg: 40.0 },
        image: ImageSettings::default(),
        radiosity: RadiosityParams::default(),
        render: RenderParams::default(),
        materials: vec![Material::diffuse("floor", Vec3::splat(0.5))],
        surfaces: vec![floor],
        warnings: Vec::new(),
    };
    Mesh::build(&scene, edge)
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
    let chosen = elements_to_split(&mesh, &element, &vertex, 0.1, 0.05, 0.01, &vec![true; element.len()]);
    assert_eq!(mesh.elements.len(), 100);
    for (e, c) in mesh.elements.centre.iter().enumerate() {
        let near = (c.x - 0.5).abs() < 0.1;
        assert_eq!(chosen[e], near, "element at x = {} split: {}", c.x, chosen[e]);
    }
    // A flat solution is never split.
    let flat = vec![Vec3::ONE; element.len()];
    let none = elements_to_split(&mesh, &flat, &vec![Vec3::ONE; mesh.positions.len()], 0.1, 0.05, 0.01, &[true; 100]);
    assert!(none.iter().all(|&s| !s));
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
