//! Triangle pairs meshed as quads (`mesh::pair_triangles`): a quad that an exporter wrote as two
//! triangles is meshed, counted and solved as the quad; triangles that are not halves of one planar
//! quad with one material and one texture mapping keep their own grids.

mod common;

use common::{emitter, scene, surface, Setup};
use glam::{vec2, vec3, Vec3};
use radray::mesh::{count_elements, pair_triangles, Mesh, Meshing};
use radray::scene::{Material, Quality, SceneDescription, Surface};

/// Quad (a, b, c, d) as the two triangles an exporter writes: (a, b, c) and (a, c, d).
fn halves(quad: [Vec3; 4], material: u32, two_sided: bool) -> [Surface; 2] {
    let [a, b, c, d] = quad;
    [surface([a, b, c], material, two_sided), surface([a, c, d], material, two_sided)]
}

/// A 4 × 0.1 strip in the plane z = 0, facing +z: a skirting board.
const STRIP: [Vec3; 4] = [vec3(0.0, 0.0, 0.0), vec3(4.0, 0.0, 0.0), vec3(4.0, 0.1, 0.0), vec3(0.0, 0.1, 0.0)];

fn grey() -> Vec<Material> {
    vec![Material::diffuse("grey", Vec3::splat(0.5)), Material::diffuse("red", vec3(0.6, 0.1, 0.1))]
}

fn sorted_points(mesh: &Mesh) -> Vec<[u32; 3]> {
    let mut points: Vec<[u32; 3]> = mesh.positions.iter().map(|p| (*p * 1e4).round().as_uvec3().to_array()).collect();
    points.sort_unstable();
    points
}

#[test]
fn a_rectangle_written_as_two_triangles_is_meshed_as_its_quad() {
    let quad = scene(grey(), vec![surface(STRIP, 0, false)]);
    for two_sided in [false, true] {
        // Either diagonal.
        let [s0, s1, s2, s3] = STRIP;
        for corners in [[s0, s1, s2, s3], [s1, s2, s3, s0]] {
            let triangles = scene(grey(), halves(corners, 0, two_sided).to_vec());
            let quad = scene(grey(), vec![surface(corners, 0, two_sided)]);
            let (from_triangles, from_quad) = (Mesh::build(&triangles, 0.5), Mesh::build(&quad, 0.5));
            assert_eq!(from_triangles.elements.len(), from_quad.elements.len());
            assert_eq!(count_elements(&triangles, 0.5), from_quad.elements.len() as u64);
            assert_eq!(sorted_points(&from_triangles), sorted_points(&from_quad), "the same grid, shared vertices");
            assert!((from_triangles.total_area() - from_quad.total_area()).abs() < 1e-5);
        }
    }
    // 8 quad cells along the strip; as triangles with their own grids it would be 2 × 9² = 162 slivers.
    assert_eq!(Mesh::build(&quad, 0.5).elements.len(), 8);
}

#[test]
fn a_grid_of_split_squares_pairs_across_the_diagonals() {
    // 3 × 3 unit squares, each written as two triangles: every triangle could also pair with its
    // neighbour across a square's side (a parallelogram at 45°), but the most rectangular pairs win.
    let mut surfaces = Vec::new();
    for j in 0..3 {
        for i in 0..3 {
            let (x, y) = (i as f32, j as f32);
            let square = [vec3(x, y, 0.0), vec3(x + 1.0, y, 0.0), vec3(x + 1.0, y + 1.0, 0.0), vec3(x, y + 1.0, 0.0)];
            surfaces.extend(halves(square, 0, false));
        }
    }
    let plan = pair_triangles(&surfaces);
    for (k, meshing) in plan.iter().enumerate() {
        match meshing {
            Meshing::Quad { corners, partner } => {
                assert_eq!(*partner as usize, k + 1, "paired with its own square's other half");
                let (min, max) = corners.iter().fold((Vec3::MAX, Vec3::MIN), |(lo, hi), &p| (lo.min(p), hi.max(p)));
                assert_eq!(max - min, vec3(1.0, 1.0, 0.0));
            }
            Meshing::Absorbed => assert_eq!(k % 2, 1),
            Meshing::Own => panic!("triangle {k} left unpaired"),
        }
    }
}

/// An edit of a triangle pair.
type Change = dyn Fn(&mut [Surface; 2]);

#[test]
fn triangles_that_are_not_halves_of_one_planar_quad_keep_their_own_grids() {
    let [a, b, c, d] = [vec3(0.0, 0.0, 0.0), vec3(1.0, 0.0, 0.0), vec3(1.0, 1.0, 0.0), vec3(0.0, 1.0, 0.0)];
    let with = |f: &Change| {
        let mut pair = halves([a, b, c, d], 0, false);
        f(&mut pair);
        pair_triangles(&pair)
    };
    assert!(matches!(with(&|_| {})[0], Meshing::Quad { partner: 1, .. }), "the plain square pairs");
    let cases: [(&str, &Change); 8] = [
        ("another material", &|p| p[1].material = 1),
        ("one side against two", &|p| p[1].two_sided = true),
        ("another object", &|p| p[1].object = "lamp".into()),
        ("folded by 1°", &|p| p[1].vertices[2].z = 1.0f32.to_radians().tan()),
        ("a dart, not convex", &|p| p[1].vertices[2] = vec3(2.0, 3.0, 0.0)),
        ("a 30° corner", &|p| p[1].vertices[2] = vec3(-(60.0f32.to_radians().tan()), 1.0, 0.0)),
        ("an edge that is not shared", &|p| p[1].vertices[1] = vec3(1.0, 1.0 + 1e-3, 0.0)),
        ("a uv seam along the diagonal", &|p| {
            p[0].uvs = Some(vec![vec2(0.0, 0.0), vec2(1.0, 0.0), vec2(1.0, 1.0)]);
            p[1].uvs = Some(vec![vec2(0.5, 0.0), vec2(1.5, 1.0), vec2(0.5, 1.0)]);
        }),
    ];
    for (what, change) in cases {
        assert_eq!(with(change), vec![Meshing::Own, Meshing::Own], "{what}");
    }
    // What exporters write of a flat quad still pairs: coordinates rounded off the plane, uv rounded to
    // 4 digits, smooth shading normals (each half keeps its own: see the next test).
    let written: [(&str, &Change); 3] = [
        ("a corner 1e-4 off the plane", &|p| p[1].vertices[2].z = 1e-4),
        ("uv rounded to 4 digits", &|p| {
            p[0].uvs = Some(vec![vec2(0.0, 0.0), vec2(0.3333, 0.0), vec2(0.3333, 0.1429)]);
            p[1].uvs = Some(vec![vec2(0.0, 0.0), vec2(0.3333, 0.1429), vec2(0.0, 0.1428)]);
        }),
        ("smooth shading normals", &|p| {
            p[0].shading_normals = Some(vec![vec3(-0.3, 0.0, 1.0).normalize(), Vec3::Z, Vec3::Z]);
        }),
    ];
    for (what, change) in written {
        assert!(matches!(with(change)[0], Meshing::Quad { partner: 1, .. }), "{what}");
    }
}

#[test]
fn a_pair_with_smooth_normals_shades_as_its_two_triangles() {
    // A flat square whose exporter wrote normals of a curved surface, different on the two halves'
    // corners (a crease along the diagonal).
    let mut pair = halves(STRIP, 0, false);
    let tilt = |x: f32, y: f32| vec3(x, y, 1.0).normalize();
    pair[0].shading_normals = Some(vec![tilt(-0.3, 0.0), tilt(0.3, 0.0), tilt(0.3, 0.2)]);
    pair[1].shading_normals = Some(vec![tilt(-0.3, 0.1), tilt(0.3, -0.2), tilt(-0.3, 0.0)]);
    let s = scene(grey(), pair.to_vec());
    let mesh = Mesh::build(&s, 0.5);
    assert_eq!(mesh.elements.len(), 8, "paired");
    let expected = |p: Vec3| {
        for triangle in &s.surfaces {
            let [a, b, c] = [0, 1, 2].map(|k| triangle.vertices[k]);
            let n = (b - a).cross(c - a);
            let w1 = (p - a).cross(c - a).dot(n) / n.length_squared();
            let w2 = (b - a).cross(p - a).dot(n) / n.length_squared();
            if w1 >= 0.0 && w2 >= 0.0 && w1 + w2 <= 1.0 {
                let normals = triangle.shading_normals.as_ref().unwrap();
                return (normals[0] * (1.0 - w1 - w2) + normals[1] * w1 + normals[2] * w2).normalize();
            }
        }
        unreachable!("{p} on the strip")
    };
    for e in 0..mesh.elements.len() {
        for (s_, t_) in [(0.2, 0.3), (0.5, 0.5), (0.9, 0.05), (0.1, 0.8)] {
            let c = mesh.elements.corners[e].map(|v| mesh.positions[v as usize]);
            let p = c[0] * ((1.0 - s_) * (1.0 - t_))
                + c[1] * (s_ * (1.0 - t_))
                + c[2] * (s_ * t_)
                + c[3] * ((1.0 - s_) * t_);
            let n = mesh.interpolated_normal(&s.surfaces, e, p, Vec3::Z);
            assert!((n - expected(p)).length() < 1e-5, "at {p}: {n} against the triangles' {}", expected(p));
        }
    }
}

#[test]
fn a_textured_pair_keeps_its_texture_coordinates() {
    // uv = (x/4, 10y + 0.25), an affine map, written per triangle as a textured exporter would.
    let uv_of = |p: Vec3| vec2(p.x / 4.0, 10.0 * p.y + 0.25);
    let mut pair = halves(STRIP, 0, false);
    for s in pair.iter_mut() {
        s.uvs = Some(s.vertices.iter().map(|&p| uv_of(p)).collect());
    }
    let textured = scene(grey(), pair.to_vec());
    assert!(matches!(pair_triangles(&textured.surfaces)[0], Meshing::Quad { .. }));
    let mesh = Mesh::build(&textured, 0.5);
    assert_eq!(mesh.elements.len(), 8);
    for (p, uv) in mesh.positions.iter().zip(&mesh.uvs) {
        assert!((*uv - uv_of(*p)).abs().max_element() < 1e-5, "uv {uv} at {p}, expected {}", uv_of(*p));
    }
    assert!(mesh.surface_has_uv[0]);
    assert_eq!(mesh.uvs.len(), mesh.positions.len());
}

/// Quad (a, b, c, d) wound so that its front faces `facing`.
fn facing(quad: [Vec3; 4], facing: Vec3) -> [Vec3; 4] {
    let [a, b, c, d] = quad;
    if (b - a).cross(c - a).dot(facing) > 0.0 {
        quad
    } else {
        [a, d, c, b]
    }
}

/// A 4 × 3 × 5 room lit by a 1 m² ceiling panel, one red wall, a 1 m block on the floor: (material,
/// quad) with 0 grey, 1 red, 2 the panel.
fn room() -> Vec<(u32, [Vec3; 4])> {
    let rect = |o: Vec3, u: Vec3, v: Vec3| [o, o + u, o + u + v, o + v];
    let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
    vec![
        (0, facing(rect(Vec3::ZERO, 4.0 * x, 5.0 * z), y)),
        (0, facing(rect(3.0 * y, 4.0 * x, 5.0 * z), -y)),
        (1, facing(rect(Vec3::ZERO, 3.0 * y, 5.0 * z), x)),
        (0, facing(rect(4.0 * x, 3.0 * y, 5.0 * z), -x)),
        (0, facing(rect(Vec3::ZERO, 4.0 * x, 3.0 * y), z)),
        (0, facing(rect(5.0 * z, 4.0 * x, 3.0 * y), -z)),
        (2, facing(rect(vec3(1.5, 2.999, 2.0), x, z), -y)),
        (0, facing(rect(vec3(2.0, 1.0, 1.0), x, z), y)),
        (0, facing(rect(vec3(2.0, 0.0, 1.0), x, y), -z)),
        (0, facing(rect(vec3(2.0, 0.0, 2.0), x, y), z)),
        (0, facing(rect(vec3(2.0, 0.0, 1.0), y, z), -x)),
        (0, facing(rect(vec3(3.0, 0.0, 1.0), y, z), x)),
    ]
}

#[test]
fn a_room_written_as_triangles_solves_like_the_room_written_as_quads() {
    let materials = vec![
        Material::diffuse("grey", Vec3::splat(0.7)),
        Material::diffuse("red", vec3(0.6, 0.1, 0.1)),
        emitter("panel", Vec3::splat(5.0)),
    ];
    let quads = room().into_iter().map(|(m, q)| surface(q, m, false)).collect();
    let mut quads = scene(materials, quads);
    quads.apply_quality(Quality::Default);
    let triangles = SceneDescription {
        surfaces: room().into_iter().flat_map(|(m, q)| halves(q, m, false)).collect(),
        ..quads.clone()
    };
    let (q, t) = (Setup::solved(&quads), Setup::solved(&triangles));
    assert_eq!(q.mesh.elements.len(), t.mesh.elements.len());
    // Power Σ B·A of each face: quad face i is the pair of triangles 2i and 2i + 1, meshed under 2i.
    let power = |setup: &Setup, face_of: &dyn Fn(usize) -> usize| {
        let mut per_face = vec![Vec3::ZERO; quads.surfaces.len()];
        let e = &setup.mesh.elements;
        for i in 0..e.len() {
            per_face[face_of(e.surface[i] as usize)] += setup.solution.element_exitance[i] * e.area[i];
        }
        per_face
    };
    let (from_quads, from_triangles) = (power(&q, &|s| s), power(&t, &|s| s / 2));
    for (face, (a, b)) in from_quads.iter().zip(&from_triangles).enumerate() {
        let relative = ((*a - *b).abs() / *a).max_element();
        assert!(relative < 1e-3, "face {face}: power {a} as a quad, {b} as triangles");
    }
}

#[test]
fn the_textured_box_written_as_triangles_solves_like_the_box_written_as_quads() {
    // The shipped textured box (picture, checker and wood maps with uv) with every quad written as the
    // two triangles an exporter writes, uv and all: the pairs mesh to the quads' elements, whose
    // texture means and solved exitance are the quads' own.
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/rooms/textured_box.toml");
    let mut quads = radray::scene::load(&path).expect("textured_box loads");
    quads.radiosity.method = radray::scene::MethodChoice::Matrix;
    let mut triangles = quads.clone();
    triangles.surfaces = quads
        .surfaces
        .iter()
        .flat_map(|s| {
            assert_eq!(s.vertices.len(), 4);
            [[0, 1, 2], [0, 2, 3]].map(|k| Surface {
                vertices: k.iter().map(|&i| s.vertices[i]).collect(),
                uvs: s.uvs.as_ref().map(|uv| k.iter().map(|&i| uv[i]).collect()),
                shading_normals: s.shading_normals.as_ref().map(|n| k.iter().map(|&i| n[i]).collect()),
                ..s.clone()
            })
        })
        .collect();
    assert!(quads.surfaces.iter().any(|s| s.uvs.is_some()), "textured");
    let (q, t) = (Setup::solved(&quads), Setup::solved(&triangles));
    let (eq, et) = (&q.mesh.elements, &t.mesh.elements);
    assert_eq!(eq.len(), et.len());
    for e in 0..eq.len() {
        assert!((eq.centre[e] - et.centre[e]).length() < 1e-5, "element {e} in the same place");
        assert!((eq.reflectance[e] - et.reflectance[e]).abs().max_element() < 1e-5, "element {e}'s texture mean");
        let (bq, bt) = (q.solution.element_exitance[e], t.solution.element_exitance[e]);
        assert!((bq - bt).abs().max_element() <= 1e-4 * bq.max_element().max(1e-3), "element {e}: {bq} against {bt}");
    }
}
