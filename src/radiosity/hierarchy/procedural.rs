//! Procedural test scenes for the hierarchy's tests, bench and measurements: a 10 × 4 × 10 room with a
//! ceiling lamp, filled with a grid of tessellated spheres and boxes, of about a requested triangle
//! count. Deterministic (no random numbers).

use glam::{vec3, Vec3};

use crate::scene::{
    Camera, ImageSettings, Material, RadiosityParams, RenderParams, SceneDescription, SourceLoc, Surface,
};

/// Sphere tessellation: segments around, rings from pole to pole (2·S·(R − 1) triangles).
const SPHERE_SEGMENTS: u32 = 24;
const SPHERE_RINGS: u32 = 12;
/// Room walls are cut into this many quads per side (two triangles each).
const WALL_GRID: u32 = 8;

/// A room of about `target_triangles` input triangles (at least the room itself, ~800).
pub fn room_with_objects(target_triangles: usize) -> SceneDescription {
    let materials = vec![
        Material::diffuse("white", Vec3::splat(0.7)),
        Material::diffuse("red", vec3(0.63, 0.065, 0.05)),
        Material::diffuse("green", vec3(0.14, 0.45, 0.091)),
        Material::diffuse("grey", Vec3::splat(0.5)),
        Material { emitted_radiance: Vec3::splat(10.0), ..Material::diffuse("lamp", Vec3::ZERO) },
    ];
    let mut surfaces = Vec::new();
    let mut add = |vertices: Vec<Vec3>, material: u32| {
        surfaces.push(Surface {
            vertices,
            material,
            two_sided: false,
            shading_normals: None,
            uvs: None,
            object: "procedural".into(),
            source: SourceLoc::default(),
        })
    };
    let (w, h, d) = (10.0f32, 4.0f32, 10.0f32);
    // Inward-facing walls as (origin, u, v) with u × v pointing into the room.
    let walls = [
        (vec3(0.0, 0.0, 0.0), vec3(0.0, 0.0, d), vec3(w, 0.0, 0.0), 0), // floor, normal +y
        (vec3(0.0, h, 0.0), vec3(w, 0.0, 0.0), vec3(0.0, 0.0, d), 0),   // ceiling, −y
        (vec3(0.0, 0.0, 0.0), vec3(0.0, h, 0.0), vec3(0.0, 0.0, d), 1), // x = 0, +x
        (vec3(w, 0.0, 0.0), vec3(0.0, 0.0, d), vec3(0.0, h, 0.0), 2),   // x = w, −x
        (vec3(0.0, 0.0, 0.0), vec3(w, 0.0, 0.0), vec3(0.0, h, 0.0), 0), // z = 0, +z
        (vec3(0.0, 0.0, d), vec3(0.0, h, 0.0), vec3(w, 0.0, 0.0), 0),   // z = d, −z
    ];
    for (o, u, v, m) in walls {
        let n = WALL_GRID as f32;
        for j in 0..WALL_GRID {
            for i in 0..WALL_GRID {
                let p = |a: u32, b: u32| o + u * (a as f32 / n) + v * (b as f32 / n);
                add(vec![p(i, j), p(i + 1, j), p(i + 1, j + 1)], m);
                add(vec![p(i, j), p(i + 1, j + 1), p(i, j + 1)], m);
            }
        }
    }
    // Lamp: a 2 × 2 quad just below the ceiling, facing down.
    let y = h - 1e-3;
    add(vec![vec3(4.0, y, 4.0), vec3(6.0, y, 4.0), vec3(6.0, y, 6.0), vec3(4.0, y, 6.0)], 4);
    let room = 6 * 2 * (WALL_GRID * WALL_GRID) as usize + 2;
    let per_cell = (2 * SPHERE_SEGMENTS * (SPHERE_RINGS - 1)) as usize + 12;
    let cells = target_triangles.saturating_sub(room).div_ceil(per_cell);
    let grid = (cells as f32).sqrt().ceil().max(1.0) as u32;
    let cell = 9.0 / grid as f32;
    let mut placed = 0;
    'grid: for gz in 0..grid {
        for gx in 0..grid {
            if placed == cells {
                break 'grid;
            }
            placed += 1;
            let base = vec3(0.5 + (gx as f32 + 0.5) * cell, 0.0, 0.5 + (gz as f32 + 0.5) * cell);
            let r = 0.3 * cell;
            let centre = base + vec3(-0.1 * cell, r + 0.02 * cell, -0.1 * cell);
            sphere(centre, r, 3, &mut add);
            let b = 0.15 * cell;
            let lo = base + vec3(0.2 * cell, 0.0, 0.2 * cell);
            cube(lo, lo + Vec3::splat(b), if (gx + gz) % 2 == 0 { 1 } else { 2 }, &mut add);
        }
    }
    SceneDescription {
        path: "procedural".into(),
        camera: Camera { eye: vec3(5.0, 2.0, 0.5), look_at: vec3(5.0, 1.0, 9.0), up: Vec3::Y, vfov_deg: 70.0 },
        image: ImageSettings::default(),
        radiosity: RadiosityParams::default(),
        render: RenderParams::default(),
        materials,
        surfaces,
        warnings: Vec::new(),
    }
}

/// A UV sphere with outward-facing triangles.
fn sphere(centre: Vec3, radius: f32, material: u32, add: &mut impl FnMut(Vec<Vec3>, u32)) {
    let point = |seg: u32, ring: u32| {
        let theta = std::f32::consts::PI * ring as f32 / SPHERE_RINGS as f32;
        let phi = 2.0 * std::f32::consts::PI * (seg % SPHERE_SEGMENTS) as f32 / SPHERE_SEGMENTS as f32;
        centre + radius * vec3(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin())
    };
    for ring in 0..SPHERE_RINGS {
        for seg in 0..SPHERE_SEGMENTS {
            let (a, b, c, e) = (point(seg, ring), point(seg + 1, ring), point(seg + 1, ring + 1), point(seg, ring + 1));
            // Outward winding: near the top pole (b − a) × (c − a) ≈ ∂φ × ∂θ = +y.
            if ring != 0 {
                add(vec![a, b, c], material);
            }
            if ring != SPHERE_RINGS - 1 {
                add(vec![a, c, e], material);
            }
        }
    }
}

/// An axis-aligned cube with outward faces, each as one quad.
fn cube(lo: Vec3, hi: Vec3, material: u32, add: &mut impl FnMut(Vec<Vec3>, u32)) {
    let c = |x: bool, y: bool, z: bool| {
        vec3(if x { hi.x } else { lo.x }, if y { hi.y } else { lo.y }, if z { hi.z } else { lo.z })
    };
    let (f, t) = (false, true);
    let faces = [
        [c(f, f, f), c(f, f, t), c(f, t, t), c(f, t, f)], // −x
        [c(t, f, f), c(t, t, f), c(t, t, t), c(t, f, t)], // +x
        [c(f, f, f), c(t, f, f), c(t, f, t), c(f, f, t)], // −y
        [c(f, t, f), c(f, t, t), c(t, t, t), c(t, t, f)], // +y
        [c(f, f, f), c(f, t, f), c(t, t, f), c(t, f, f)], // −z
        [c(f, f, t), c(t, f, t), c(t, t, t), c(f, t, t)], // +z
    ];
    for q in faces {
        add(q.to_vec(), material);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn objects_face_outwards_and_walls_inwards() {
        let scene = room_with_objects(3000);
        let middle = vec3(5.0, 2.0, 5.0);
        for s in &scene.surfaces {
            let v = &s.vertices;
            let n = (v[1] - v[0]).cross(v[2] - v[0]);
            let centroid = v.iter().copied().sum::<Vec3>() / v.len() as f32;
            if s.material == 0 && (centroid.y <= 0.0 || centroid.y >= 4.0) || s.material == 4 {
                // Floor and ceiling face into the room (towards the middle height); the lamp faces down.
                assert!(n.dot(middle - centroid) > 0.0, "{v:?}");
            }
        }
        let count = crate::radiosity::hierarchy::count_input_triangles(&scene);
        assert!((2500..4500).contains(&count), "{count}");
    }
}
