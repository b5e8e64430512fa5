//! The uniform mesh's vertex step across the facets of a tessellated object (`SmoothMesh`): on a
//! `[[sphere]]`'s facets lit by a smooth field, the values at a facet edge are continuous (every copy
//! of a vertex carries one value, close to the field) where the per-surface step jumped by the
//! facets' difference; a box's faces (90° creases) and a material change keep their own values, bit
//! for bit what the per-surface step gives.

mod common;

use glam::{DVec3, Vec3};
use radray::mesh::Mesh;
use radray::radiosity::boundary_vertices::{conforming_boundary, vertex_values};
use radray::radiosity::smooth_mesh::SmoothMesh;
use radray::scene::shapes::{box_faces, sphere_triangles};
use radray::scene::{Material, Surface};

fn mesh_of(surfaces: Vec<Surface>, materials: usize, edge: f32) -> Mesh {
    let materials = (0..materials).map(|m| Material::diffuse(&format!("m{m}"), Vec3::splat(0.5))).collect();
    Mesh::build(&common::scene(materials, surfaces), edge)
}

/// A smooth exitance field on the unit sphere: B = 1 + n·L with L the light direction (+y), so that
/// every facet sees a different value.
fn field(p: Vec3) -> f64 {
    1.0 + p.normalize().y as f64
}

/// The per-surface step (`conforming_boundary` + `vertex_values`) and the smooth step on one mesh.
fn both_steps(mesh: &Mesh, element: &[DVec3]) -> (Vec<Vec3>, Vec<Vec3>) {
    (vertex_values(mesh, element, &conforming_boundary(mesh)), SmoothMesh::new(mesh).vertex_values(element))
}

/// Largest spread of the values of the mesh vertices at one point (the jump across facet edges), and
/// the largest distance of a vertex value from the field there.
fn jump_and_error(mesh: &Mesh, values: &[Vec3]) -> (f64, f64) {
    let mut at_point: std::collections::HashMap<[i32; 3], (f64, f64)> = Default::default();
    let mut error = 0.0f64;
    for (p, v) in mesh.positions.iter().zip(values) {
        let key = (*p * 1e4).round().as_ivec3().to_array();
        let e = at_point.entry(key).or_insert((f64::MAX, f64::MIN));
        e.0 = e.0.min(v.x as f64);
        e.1 = e.1.max(v.x as f64);
        error = error.max((v.x as f64 - field(*p)).abs());
    }
    (at_point.values().map(|(lo, hi)| hi - lo).fold(0.0, f64::max), error)
}

#[test]
fn a_sphere_under_a_light_is_continuous_across_its_facet_edges() {
    let surfaces: Vec<Surface> =
        sphere_triangles(Vec3::ZERO, 1.0, 24).into_iter().map(|(t, _)| common::surface(t.to_vec(), 0, false)).collect();
    // Elements larger than the facets: one element per facet, as tessellated objects usually mesh.
    let mesh = mesh_of(surfaces, 1, 10.0);
    let element: Vec<DVec3> = mesh.elements.centre.iter().map(|&c| DVec3::splat(field(c))).collect();
    let (per_surface, smooth) = both_steps(&mesh, &element);
    let (jump_before, _) = jump_and_error(&mesh, &per_surface);
    let (jump_after, error_after) = jump_and_error(&mesh, &smooth);
    // 24 segments: neighbouring facets' centres are 15° apart, B changes by up to ~0.26 between them.
    assert!(jump_before > 0.1, "the per-surface step jumps at facet edges: {jump_before}");
    assert_eq!(jump_after, 0.0, "one value per point across facet edges");
    // The vertex mean of the facets around a point: within the field's change over one facet.
    assert!(error_after < 0.05, "vertex values follow the smooth field: max error {error_after}");
    assert_eq!(SmoothMesh::new(&mesh).group_count(), 1, "the sphere is one smoothing group");
}

#[test]
fn subdivided_facets_weld_their_edge_grids() {
    // Facets meshed into several elements each: the grid points the two facets put on their shared
    // edge agree only to rounding, and still become one vertex. (The sphere's two triangles per
    // band quad are planar halves of one quad and are meshed as it, `mesh::pair_triangles`: the facets
    // here are those quads and the polar triangles, with smaller steps between them than the
    // triangles had across their diagonals.)
    let surfaces: Vec<Surface> =
        sphere_triangles(Vec3::ZERO, 1.0, 16).into_iter().map(|(t, _)| common::surface(t.to_vec(), 0, false)).collect();
    // 16 segments: facets 22.5° apart, inside the smoothing angle.
    let mesh = mesh_of(surfaces, 1, 0.15);
    assert!(mesh.elements.len() > 4 * 16 * 7, "facets are subdivided: {}", mesh.elements.len());
    let element: Vec<DVec3> = mesh.elements.centre.iter().map(|&c| DVec3::splat(field(c))).collect();
    let (per_surface, smooth) = both_steps(&mesh, &element);
    let (jump_before, _) = jump_and_error(&mesh, &per_surface);
    let (jump_after, _) = jump_and_error(&mesh, &smooth);
    assert!(jump_after < 1e-6 && jump_before > 2e-3, "jump {jump_before} -> {jump_after}");
}

#[test]
fn box_faces_and_material_changes_keep_their_own_values() {
    // A box (90° creases) whose top is cut into two coplanar halves of different materials.
    let faces = box_faces(Vec3::ZERO, Vec3::ONE, false);
    let mut surfaces: Vec<Surface> = faces.iter().take(3).map(|f| common::surface(f.to_vec(), 0, false)).collect();
    let top = faces[3];
    let mid = |a: Vec3, b: Vec3| (a + b) * 0.5;
    surfaces.push(common::surface(vec![top[0], top[1], mid(top[1], top[2]), mid(top[0], top[3])], 0, false));
    surfaces.push(common::surface(vec![mid(top[0], top[3]), mid(top[1], top[2]), top[2], top[3]], 1, false));
    surfaces.extend(faces.iter().skip(4).map(|f| common::surface(f.to_vec(), 0, false)));
    let mesh = mesh_of(surfaces, 2, 0.25);
    // Any field, however it varies: the groups are the surfaces, so both steps agree bit for bit.
    let element: Vec<DVec3> = mesh
        .elements
        .centre
        .iter()
        .map(|&c| DVec3::new(c.x as f64, (c.y * c.z) as f64, 1.0 + c.x as f64 * 0.3))
        .collect();
    let (per_surface, smooth) = both_steps(&mesh, &element);
    assert_eq!(SmoothMesh::new(&mesh).group_count(), 7);
    assert_eq!(per_surface, smooth);
}

/// The largest spread of values at one point over the mesh vertices there (any field, any channel x).
fn largest_jump(mesh: &Mesh, values: &[Vec3]) -> f64 {
    let mut at_point: std::collections::HashMap<[i32; 3], (f64, f64)> = Default::default();
    for (p, v) in mesh.positions.iter().zip(values) {
        let e = at_point.entry((*p * 1e4).round().as_ivec3().to_array()).or_insert((f64::MAX, f64::MIN));
        e.0 = e.0.min(v.x as f64);
        e.1 = e.1.max(v.x as f64);
    }
    at_point.values().map(|(lo, hi)| hi - lo).fold(0.0, f64::max)
}

/// A floor piece in the plane y = 0 over [x0, x1] × [z0, z1], facing +y.
fn floor_piece(x0: f32, x1: f32, z0: f32, z1: f32) -> Surface {
    let v = |x: f32, z: f32| Vec3::new(x, 0.0, z);
    common::surface(vec![v(x0, z0), v(x0, z1), v(x1, z1), v(x1, z0)], 0, false)
}

#[test]
fn a_shadow_edge_on_a_border_between_coplanar_pieces_keeps_its_step() {
    // A floor cut at z = 1 (as a floor is cut along a pillar's face): lit on z < 1, in the pillar's
    // sharp shadow on z > 1. Each side is linear in x, so each side's own extrapolation to the border
    // is exact: the step must survive at the shared vertices, not be averaged to its middle.
    let lit = |x: f32| 1.0 + 0.2 * x as f64;
    let shadow = |x: f32| 0.1 + 0.02 * x as f64;
    let mesh = mesh_of(vec![floor_piece(0.0, 1.0, 0.0, 1.0), floor_piece(0.0, 1.0, 1.0, 2.0)], 1, 0.25);
    let element: Vec<DVec3> =
        mesh.elements.centre.iter().map(|&c| DVec3::splat(if c.z < 1.0 { lit(c.x) } else { shadow(c.x) })).collect();
    let smooth = SmoothMesh::new(&mesh);
    assert_eq!(smooth.group_count(), 1, "coplanar pieces of one material are one smoothing group");
    let values = smooth.vertex_values(&element);
    let mut on_border = 0;
    for (v, p) in mesh.positions.iter().enumerate() {
        if (p.z - 1.0).abs() > 1e-6 {
            continue;
        }
        on_border += 1;
        let side_is_lit = mesh
            .elements
            .corners
            .iter()
            .enumerate()
            .any(|(e, c)| c.contains(&(v as u32)) && mesh.elements.centre[e].z < 1.0);
        let expected = if side_is_lit { lit(p.x) } else { shadow(p.x) };
        // f32 arithmetic of the fit: a few ulps of values near 1.
        assert!(
            (values[v].x as f64 - expected).abs() < 1e-5,
            "vertex {p} of the {} side: {} vs {expected}",
            if side_is_lit { "lit" } else { "shadowed" },
            values[v].x
        );
    }
    assert_eq!(on_border, 10, "five border points, one vertex per piece");
}

#[test]
fn a_square_floor_written_as_two_pieces_under_a_lamp_shows_no_seam_on_its_diagonal() {
    // A unit floor square split into two triangles, lit by a point lamp 0.5 above (0.3, 0, 0.6):
    // irradiance h/(h² + r²)^{3/2}, smooth but far from linear (a factor of about 8 from the peak to the
    // far corner).
    let field = |p: Vec3| {
        let r2 = (p.x - 0.3).powi(2) + (p.z - 0.6).powi(2);
        0.125 / (0.25 + r2 as f64).powf(1.5)
    };
    let v = |x: f32, z: f32| Vec3::new(x, 0.0, z);
    let triangles = vec![
        common::surface(vec![v(0.0, 0.0), v(0.0, 1.0), v(1.0, 1.0)], 0, false),
        common::surface(vec![v(0.0, 0.0), v(1.0, 1.0), v(1.0, 0.0)], 0, false),
    ];
    let values = |surfaces: Vec<Surface>| {
        let mesh = mesh_of(surfaces, 1, 0.125);
        let element: Vec<DVec3> = mesh.elements.centre.iter().map(|&c| DVec3::splat(field(c))).collect();
        let (per_surface, smooth) = both_steps(&mesh, &element);
        (largest_jump(&mesh, &per_surface), largest_jump(&mesh, &smooth))
    };
    // As every exporter triangulates a floor: the halves of one quad are meshed as it
    // (`mesh::pair_triangles`), so its vertices are shared across the diagonal in either step.
    assert_eq!(values(triangles.clone()), (0.0, 0.0), "one quad grid");
    // The same halves as two objects are two surfaces: both extrapolate the same smooth field to nearly
    // one value on the diagonal, so they weld, one value per point. Their own values differ by about
    // 1% of the peak (0.012 of 0.97): well inside `AGREE_RELATIVE`.
    let mut two_objects = triangles;
    two_objects[1].object = "rug".into();
    let (per_surface, smooth) = values(two_objects);
    assert!(per_surface > 0.005, "the halves' own values differ on the diagonal");
    assert_eq!(smooth, 0.0, "one value per point on the diagonal");
}

#[test]
fn a_sphere_with_a_sharp_terminator_stays_continuous() {
    // A step across facet edges (lit above the equator, dark below): facets of a curved surface are
    // always welded, so the sphere never shows its facets, whatever the solution does there.
    let surfaces: Vec<Surface> =
        sphere_triangles(Vec3::ZERO, 1.0, 24).into_iter().map(|(t, _)| common::surface(t.to_vec(), 0, false)).collect();
    let mesh = mesh_of(surfaces, 1, 10.0);
    let element: Vec<DVec3> =
        mesh.elements.centre.iter().map(|&c| DVec3::splat(if c.y > 0.0 { field(c) } else { 0.05 })).collect();
    let (per_surface, smooth) = both_steps(&mesh, &element);
    assert!(largest_jump(&mesh, &per_surface) > 0.5, "the per-surface step jumps at the terminator");
    assert_eq!(largest_jump(&mesh, &smooth), 0.0, "one value per point across facet edges");
}

/// Largest distance of a vertex value (channel x) from `field` at the vertex.
fn largest_error(mesh: &Mesh, values: &[Vec3], field: impl Fn(Vec3) -> f64) -> f64 {
    mesh.positions.iter().zip(values).map(|(&p, v)| (v.x as f64 - field(p)).abs()).fold(0.0, f64::max)
}

#[test]
fn strips_that_meet_at_t_junctions_read_each_others_slope() {
    // A wall written as upright strips beside a stair: two coplanar strips 0.3 wide, the second
    // starting a step higher, so that each one's corners lie inside the other's edge (T-junctions)
    // and no edge is shared. Meshed at 0.4, each strip is one element wide: on its own, its elements
    // have neighbours only along it, no slope across it, and the strip shows as a flat band.
    let field = |p: Vec3| 1.0 + p.x as f64 + 0.3 * p.z as f64;
    let mesh = mesh_of(vec![floor_piece(0.0, 0.3, 0.0, 3.0), floor_piece(0.3, 0.6, 0.25, 3.0)], 1, 0.4);
    assert_eq!(mesh.elements.len(), 8 + 7, "one element across each strip");
    let element: Vec<DVec3> = mesh.elements.centre.iter().map(|&c| DVec3::splat(field(c))).collect();
    let smooth = SmoothMesh::new(&mesh);
    assert_eq!(smooth.group_count(), 2, "strips meeting at T-junctions stay groups of their own");
    let (per_surface, smooth_values) = both_steps(&mesh, &element);
    // Flat across: off by the slope times half the width, 1 × 0.15.
    assert!(largest_error(&mesh, &per_surface, field) > 0.12);
    // Each element's fit reads the other strip's elements at the T-junctions: the linear field is
    // exact at every vertex, on both sides of the shared line (f32 rounding of values near 1.5), but at
    // the pair's outer corners, where the extrapolation's limit (half the neighbours' range beyond it)
    // holds two strips' worth of slope back by a little.
    let outer = |p: Vec3| (p.x == 0.0 || p.x == 0.6) && (p.z == 0.0 || p.z == 3.0);
    for (v, &p) in mesh.positions.iter().enumerate() {
        let error = (smooth_values[v].x as f64 - field(p)).abs();
        assert!(error < if outer(p) { 0.02 } else { 1e-5 }, "vertex {p}: {} against {}", smooth_values[v].x, field(p));
    }
}

#[test]
fn a_shadow_edge_along_a_t_junction_keeps_its_step() {
    // Two coplanar floor pieces meeting along x = 1 at T-junctions (the second shifted by 0.1 in z):
    // lit on x < 1, in a sharp shadow on x > 1, each side linear in z. The fits do not read across a
    // step: each side's own extrapolation to the line stands, as it did when the pieces knew nothing
    // of each other.
    let lit = |p: Vec3| 1.0 + 0.2 * p.z as f64;
    let shadow = |p: Vec3| 0.1 + 0.02 * p.z as f64;
    let mesh = mesh_of(vec![floor_piece(0.0, 1.0, 0.0, 1.0), floor_piece(1.0, 2.0, 0.1, 1.1)], 1, 0.25);
    let element: Vec<DVec3> =
        mesh.elements.centre.iter().map(|&c| DVec3::splat(if c.x < 1.0 { lit(c) } else { shadow(c) })).collect();
    let (per_surface, smooth) = both_steps(&mesh, &element);
    let side = |v: usize| {
        mesh.elements
            .corners
            .iter()
            .enumerate()
            .any(|(e, c)| c.contains(&(v as u32)) && mesh.elements.centre[e].x < 1.0)
    };
    let expected = |v: usize| if side(v) { lit(mesh.positions[v]) } else { shadow(mesh.positions[v]) };
    for (name, values) in [("per surface", &per_surface), ("smooth", &smooth)] {
        let error = (0..mesh.positions.len()).map(|v| (values[v].x as f64 - expected(v)).abs()).fold(0.0, f64::max);
        assert!(error < 1e-5, "{name}: largest error {error}");
    }
}
