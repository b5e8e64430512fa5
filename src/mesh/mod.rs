//! Meshing: the scene's polygons become elements. Quads are cut into quad grids and triangles into
//! triangle grids so that no element edge exceeds `max_element_edge`; the elements of one surface share
//! their vertices, so per-vertex values interpolate without T-vertices inside a surface. Two triangles
//! that are the halves of one planar quad are meshed as that quad (`pairs`).
//!
//! Hot per-element data is kept as a struct of arrays (`Elements`); each element is also split into
//! one or two triangles for ray tracing (`Mesh::triangles`).
//!
//! Texture coordinates are interpolated like positions. An element of a `map_Kd` material reflects its
//! mean albedo over its uv triangles in pass one (`Mesh::build_with_textures`).

mod pairs;

pub use pairs::{pair_triangles, Meshing};

use crate::material::SceneTextures;
use crate::scene::{Material, SceneDescription, Surface};
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use std::sync::Arc;

/// Marks "no index" in `u32` index arrays (the fourth corner of a triangle, a missing back side).
pub const NONE: u32 = u32::MAX;

/// Per-element data, one entry per element in every array.
#[derive(Clone, Debug, Default)]
pub struct Elements {
    /// Vertex indices into `Mesh::positions`, counter-clockwise seen from the front; a triangle has
    /// `NONE` as its fourth corner.
    pub corners: Vec<[u32; 4]>,
    pub centre: Vec<Vec3>,
    /// Unit normal by the right-hand rule (the front side).
    pub normal: Vec<Vec3>,
    pub area: Vec<f32>,
    /// Index of the scene surface the element was cut from (its back side, for a two-sided surface,
    /// has its own surface index past the scene's surfaces: see `Mesh::surface_source`).
    pub surface: Vec<u32>,
    pub material: Vec<u32>,
    /// Diffuse reflectance ρ: the material's `Kd`, or with a `map_Kd` texture the element's mean albedo
    /// ρ̄ₑ over its uv triangles.
    pub reflectance: Vec<Vec3>,
    /// Emitted exitance E = π·Ke.
    pub emission: Vec<Vec3>,
}

impl Elements {
    pub fn len(&self) -> usize {
        self.centre.len()
    }

    pub fn is_empty(&self) -> bool {
        self.centre.is_empty()
    }

    /// The element's polygon as 3 or 4 points.
    pub fn polygon<'a>(&self, positions: &'a [Vec3], i: usize) -> impl Iterator<Item = Vec3> + 'a {
        let c = self.corners[i];
        c.into_iter().filter(|&v| v != NONE).map(move |v| positions[v as usize])
    }

    /// Number of corners (3 or 4).
    pub fn corner_count(&self, i: usize) -> usize {
        if self.corners[i][3] == NONE {
            3
        } else {
            4
        }
    }
}

/// An interpolated normal n with n·n_g ≥ this (within about 0.08° of the facet's n_g) is n_g itself
/// for the diffuse term (`Mesh::smooth_normal`), so a flat face's rounded vertex normals render as
/// no normals do.
/// The snap moves any cosine by at most sin 0.08° ≈ 1.4e-3, below what 8-bit output shows; it happens
/// only near a facet's centre on a tessellation fine enough (over 2000 segments around) that its
/// facets could not be told apart anyway.
pub const FLAT_NORMAL_COS: f32 = 1.0 - 1e-6;

/// `facing` where unit normal n lies within `FLAT_NORMAL_COS` of it, else n.
pub fn flat_within_tolerance(n: Vec3, facing: Vec3) -> Vec3 {
    if n.dot(facing) >= FLAT_NORMAL_COS {
        facing
    } else {
        n
    }
}

/// The meshed scene.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    /// Vertex positions, shared by the elements of one surface side.
    pub positions: Vec<Vec3>,
    /// Texture coordinates, one per position ((0, 0) on surfaces without uv).
    pub uvs: Vec<Vec2>,
    pub elements: Elements,
    /// Triangles for ray tracing: vertex indices, counter-clockwise seen from the front.
    pub triangles: Vec<[u32; 3]>,
    /// The element each triangle belongs to (its front side).
    pub triangle_element: Vec<u32>,
    /// For a two-sided surface: the element on the triangle's back side, else `NONE`.
    pub triangle_back_element: Vec<u32>,
    /// For a two-sided surface: the back side's vertex indices at the same three corners.
    pub triangle_back_vertices: Vec<[u32; 3]>,
    /// For each mesh surface (scene surfaces, then back sides of two-sided ones): the scene surface.
    pub surface_source: Vec<u32>,
    /// For each mesh surface: its scene surface has texture coordinates.
    pub surface_has_uv: Vec<bool>,
    /// For each mesh surface meshed as a triangle pair's quad (`pair_triangles`): the scene triangle
    /// paired with its own (whose shading normals hold beyond the shared edge), else `NONE`; empty
    /// when no surface is paired.
    pub surface_partner: Vec<u32>,
    /// For each mesh surface: one-sided and dielectric (a water surface, an open glass sheet), so a
    /// ray that meets its back is refracted out of the medium instead of stopped (`back_refracts`);
    /// empty when the scene has none.
    pub surface_back_refracts: Vec<bool>,
    /// The scene's loaded texture maps (empty for an untextured scene), shared with pass two.
    pub textures: Arc<SceneTextures>,
    /// Per element, its mean opacity ᾱₑ (`mean_element_coverage`) when the scene has cut-outs
    /// (`map_d`, or the alpha of `map_Kd`); empty otherwise. Hemicubes skip elements with ᾱₑ < ½
    /// (`hidden_from_hemicubes`).
    pub element_coverage: Vec<f32>,
    /// Per element: buried under the back of a one-sided surface (`burial::buried_elements`), left out
    /// of `vertex_average`; empty when not computed (every element counts).
    pub element_buried: Vec<bool>,
    /// Per element: where its hemicube's eye sits (`Mesh::eye`), set by `burial::bury` when some
    /// element's centre is buried but part of it is open (a capital's underside pierced by its
    /// column); empty when every eye is at its element's centre.
    pub element_eye: Vec<Vec3>,
    /// For a mesh refined by splitting elements (the adaptive method's): the vertex made at the
    /// midpoint of each split edge, keyed by the edge's end vertices (smaller index first), so that
    /// later readers find its T-vertices; empty for a conforming mesh.
    pub split_edge_midpoints: rustc_hash::FxHashMap<(u32, u32), u32>,
}

/// Texture coordinates at point `p` of a planar triangle or convex quad with corner uvs: for a
/// triangle uv = Σ bₖ uvₖ with p's barycentrics bₖ; for a quad the bilinear map
/// p(s, t) = (1−s)(1−t)p₀ + s(1−t)p₁ + st·p₂ + (1−s)t·p₃ is inverted for (s, t) (a few Newton steps
/// from the parallelogram guess) and uv(s, t) takes the same weights, so uv follows the mesher's grid.
pub fn surface_uv(corners: &[Vec3], uvs: &[Vec2], p: Vec3) -> Vec2 {
    if corners.len() == 3 {
        let b = barycentric(corners[0], corners[1], corners[2], p);
        return uvs[0] * b.x + uvs[1] * b.y + uvs[2] * b.z;
    }
    let q = corners;
    let n = (q[2] - q[0]).cross(q[3] - q[1]);
    let (mut s, mut t) = (0.5f32, 0.5f32);
    for _ in 0..8 {
        let f = q[0] * ((1.0 - s) * (1.0 - t)) + q[1] * (s * (1.0 - t)) + q[2] * (s * t) + q[3] * ((1.0 - s) * t) - p;
        let ds = (q[1] - q[0]) * (1.0 - t) + (q[2] - q[3]) * t;
        let dt = (q[3] - q[0]) * (1.0 - s) + (q[2] - q[1]) * s;
        // Solve f + ds·Δs + dt·Δt = 0 in the plane (Cramer's rule with the normal n).
        let det = ds.cross(dt).dot(n);
        if det.abs() <= f32::MIN_POSITIVE {
            break;
        }
        let delta_s = -f.cross(dt).dot(n) / det;
        let delta_t = -ds.cross(f).dot(n) / det;
        s += delta_s;
        t += delta_t;
        if delta_s.abs().max(delta_t.abs()) < 1e-7 {
            break;
        }
    }
    uvs[0] * ((1.0 - s) * (1.0 - t)) + uvs[1] * (s * (1.0 - t)) + uvs[2] * (s * t) + uvs[3] * ((1.0 - s) * t)
}

/// Barycentrics (b₀, b₁, b₂) of p in triangle (a, b, c): b₁ = ((p−a)×(c−a))·n/|n|², b₂ =
/// ((b−a)×(p−a))·n/|n|², b₀ = 1 − b₁ − b₂, n = (b−a)×(c−a).
fn barycentric(a: Vec3, b: Vec3, c: Vec3, p: Vec3) -> Vec3 {
    let n = (b - a).cross(c - a);
    let inv = 1.0 / n.length_squared();
    let w1 = (p - a).cross(c - a).dot(n) * inv;
    let w2 = (b - a).cross(p - a).dot(n) * inv;
    Vec3::new(1.0 - w1 - w2, w1, w2)
}

/// Pass one's reflectance of element `e` of a textured material: its mean albedo
/// ρ̄ₑ = Σ_△ A_△ ρ̄_△ / Σ_△ A_△ over the element's one or two triangles, ρ̄_△ the exact area average of
/// min(Kd·t, ρ_max) over the triangle's uv image (`MaterialMaps::mean_albedo_over`; uv is affine on
/// each triangle, so the uv-area average is the surface-area average). `None` when the element's
/// material has no diffuse map or its surface has no uv (it keeps Kd).
pub fn mean_element_albedo(mesh: &Mesh, textures: &SceneTextures, e: usize) -> Option<Vec3> {
    let maps = textures.maps(mesh.elements.material[e]).filter(|m| m.has_diffuse_texture())?;
    element_uv_mean(mesh, e, |a, b, c| maps.mean_albedo_over(a, b, c))
}

/// Pass one's emission of element `e` of a material with `map_Ke`: its mean emitted exitance
/// Ēₑ = π·Σ_△ A_△ L̄_△ / Σ_△ A_△, L̄_△ = Ke·(exact area average of the texture over the triangle's uv
/// image) (`MaterialMaps::mean_emission_over`). `None` without an emission map or without uv (the
/// element keeps π·Ke).
pub fn mean_element_emission(mesh: &Mesh, textures: &SceneTextures, e: usize) -> Option<Vec3> {
    let maps = textures.maps(mesh.elements.material[e]).filter(|m| m.has_emission_texture())?;
    element_uv_mean(mesh, e, |a, b, c| maps.mean_emission_over(a, b, c)).map(|l| l * std::f32::consts::PI)
}

/// Element `e`'s mean opacity ᾱₑ, the exact area average of its cut-out map over its uv triangles
/// (`MaterialMaps::mean_opacity_over`); `None` without a cut-out map or uv (the element is opaque).
pub fn mean_element_coverage(mesh: &Mesh, textures: &SceneTextures, e: usize) -> Option<f32> {
    let maps = textures.maps(mesh.elements.material[e]).filter(|m| m.has_opacity())?;
    element_uv_mean(mesh, e, |a, b, c| Vec3::splat(maps.mean_opacity_over(a, b, c))).map(|v| v.x)
}

/// Area average Σ_△ A_△ m(uv_△) / Σ_△ A_△ of a per-uv-triangle mean `m` over element `e`'s one or two
/// triangles; `None` when its surface has no uv or the element no area.
fn element_uv_mean(mesh: &Mesh, e: usize, mean_over: impl Fn(Vec2, Vec2, Vec2) -> Vec3) -> Option<Vec3> {
    if !mesh.surface_has_uv.get(mesh.elements.surface[e] as usize).copied().unwrap_or(false) {
        return None;
    }
    let c = mesh.elements.corners[e];
    let fans: &[[usize; 3]] = if c[3] == NONE { &[[0, 1, 2]] } else { &[[0, 1, 2], [0, 2, 3]] };
    let (mut sum, mut total) = (Vec3::ZERO, 0.0f32);
    for f in fans {
        let [a, b, d] = f.map(|k| c[k] as usize);
        let area = 0.5 * (mesh.positions[b] - mesh.positions[a]).cross(mesh.positions[d] - mesh.positions[a]).length();
        sum += mean_over(mesh.uvs[a], mesh.uvs[b], mesh.uvs[d]) * area;
        total += area;
    }
    (total > 0.0).then(|| sum / total)
}

/// Grid resolution needed so that no piece of an edge of length `len` exceeds `max_edge`.
fn segments(len: f32, max_edge: f32) -> u32 {
    if !(max_edge.is_finite() && max_edge > 0.0) {
        return 1;
    }
    ((len / max_edge) * (1.0 - 1e-6)).ceil().max(1.0) as u32
}

/// Elements `Mesh::build` would make of `scene` at `max_element_edge`, counted without building
/// anything (so a run can refuse an impossible mesh before allocating it).
pub fn count_elements(scene: &SceneDescription, max_element_edge: f32) -> u64 {
    let plan = pair_triangles(&scene.surfaces);
    scene
        .surfaces
        .iter()
        .zip(&plan)
        .map(|(surface, meshing)| {
            let per_side = match meshing {
                Meshing::Own => count_polygon_elements(&surface.vertices, max_element_edge),
                Meshing::Quad { corners, .. } => count_polygon_elements(corners, max_element_edge),
                Meshing::Absorbed => 0,
            };
            if surface.two_sided {
                2 * per_side
            } else {
                per_side
            }
        })
        .sum()
}

/// Elements one side of a polygon (a triangle or quad) becomes.
fn count_polygon_elements(q: &[Vec3], max_element_edge: f32) -> u64 {
    if q.len() == 4 {
        let nu = segments((q[1] - q[0]).length().max((q[2] - q[3]).length()), max_element_edge) as u64;
        let nv = segments((q[3] - q[0]).length().max((q[2] - q[1]).length()), max_element_edge) as u64;
        nu * nv
    } else {
        let longest = (0..q.len()).map(|k| (q[(k + 1) % q.len()] - q[k]).length()).fold(0.0, f32::max);
        (segments(longest, max_element_edge) as u64).pow(2)
    }
}

impl Mesh {
    /// Bytes its arrays hold (by length; the shared textures are not counted): what a cache that
    /// keeps this mesh is charged.
    pub fn memory_bytes(&self) -> u64 {
        fn bytes<T>(v: &[T]) -> u64 {
            std::mem::size_of_val(v) as u64
        }
        let e = &self.elements;
        bytes(&self.positions)
            + bytes(&self.uvs)
            + bytes(&e.corners)
            + bytes(&e.centre)
            + bytes(&e.normal)
            + bytes(&e.area)
            + bytes(&e.surface)
            + bytes(&e.material)
            + bytes(&e.reflectance)
            + bytes(&e.emission)
            + bytes(&self.triangles)
            + bytes(&self.triangle_element)
            + bytes(&self.triangle_back_element)
            + bytes(&self.triangle_back_vertices)
            + bytes(&self.surface_source)
            + bytes(&self.surface_has_uv)
            + bytes(&self.surface_partner)
            + bytes(&self.surface_back_refracts)
            + bytes(&self.element_coverage)
            + bytes(&self.element_buried)
            + bytes(&self.element_eye)
    }

    /// Cuts every surface of the scene into elements of at most `max_element_edge` (see module docs).
    pub fn build(scene: &SceneDescription, max_element_edge: f32) -> Mesh {
        Mesh::build_with_textures(scene, max_element_edge, Arc::new(SceneTextures::default()))
    }

    /// `build`, then the reflectance of every element of a textured material on a surface with uv is
    /// its mean albedo ρ̄ₑ (`mean_element_albedo`), with `map_Ke` its emission the mean emitted
    /// exitance (`mean_element_emission`), and with cut-outs every element gets its mean opacity
    /// (`element_coverage`); the textures stay with the mesh for pass two.
    pub fn build_with_textures(scene: &SceneDescription, max_element_edge: f32, textures: Arc<SceneTextures>) -> Mesh {
        let mut mesh = Mesh::build_geometry(scene, max_element_edge);
        if textures.is_textured() {
            let means: Vec<(Option<Vec3>, Option<Vec3>)> = (0..mesh.elements.len())
                .into_par_iter()
                .map(|e| (mean_element_albedo(&mesh, &textures, e), mean_element_emission(&mesh, &textures, e)))
                .collect();
            for (e, (albedo, emission)) in means.into_iter().enumerate() {
                if let Some(a) = albedo {
                    mesh.elements.reflectance[e] = a;
                }
                if let Some(x) = emission {
                    mesh.elements.emission[e] = x;
                }
            }
            if textures.has_cut_outs() {
                mesh.element_coverage = (0..mesh.elements.len())
                    .into_par_iter()
                    .map(|e| mean_element_coverage(&mesh, &textures, e).unwrap_or(1.0))
                    .collect();
            }
        }
        mesh.textures = textures;
        mesh
    }

    fn build_geometry(scene: &SceneDescription, max_element_edge: f32) -> Mesh {
        let mut mesh = Mesh::default();
        // Two-sided surfaces with the ranges of elements and triangles their front side produced
        // (one surface's pieces are contiguous), so mirroring them is linear in the mesh size.
        let mut back_sides = Vec::new();
        let plan = pair_triangles(&scene.surfaces);
        for ((s, surface), meshing) in scene.surfaces.iter().enumerate().zip(&plan) {
            let material = &scene.materials[surface.material as usize];
            let (first_element, first_triangle) = (mesh.elements.len(), mesh.triangles.len());
            let first_vertex = mesh.positions.len();
            let polygon: &[Vec3] = match meshing {
                Meshing::Own => &surface.vertices,
                Meshing::Quad { corners, .. } => corners,
                Meshing::Absorbed => &[],
            };
            if !polygon.is_empty() {
                mesh.add_surface(polygon, s as u32, surface.material, material, max_element_edge);
            }
            mesh.interpolate_uvs(first_vertex, surface);
            mesh.surface_source.push(s as u32);
            mesh.surface_has_uv.push(surface.uvs.is_some());
            mesh.surface_back_refracts.push(!surface.two_sided && material.is_dielectric());
            mesh.surface_partner.push(match meshing {
                Meshing::Quad { partner, .. } => *partner,
                _ => NONE,
            });
            if surface.two_sided && !polygon.is_empty() {
                back_sides.push((s, first_element..mesh.elements.len(), first_triangle..mesh.triangles.len()));
            }
        }
        // Back sides come after all front sides: the same grid with reversed winding.
        for (s, front, front_triangles) in back_sides {
            let surface = &scene.surfaces[s];
            let material = &scene.materials[surface.material as usize];
            let mesh_surface = mesh.surface_source.len() as u32;
            mesh.surface_source.push(s as u32);
            mesh.surface_has_uv.push(surface.uvs.is_some());
            mesh.surface_back_refracts.push(false);
            mesh.surface_partner.push(mesh.surface_partner[s]);
            mesh.add_back_side(front, front_triangles, mesh_surface, surface.material, material);
        }
        if !mesh.surface_back_refracts.contains(&true) {
            mesh.surface_back_refracts = Vec::new();
        }
        if mesh.surface_partner.iter().all(|&p| p == NONE) {
            mesh.surface_partner = Vec::new();
        }
        mesh
    }

    /// Texture coordinates of the vertices `first_vertex..` that `add_surface` just made of `surface`:
    /// the surface's uv at the same bilinear (quad) or barycentric (triangle) weights as each position,
    /// recovered from the position itself (over a paired quad, the triangle's affine map extended);
    /// (0, 0) without uv.
    fn interpolate_uvs(&mut self, first_vertex: usize, surface: &Surface) {
        let uvs = match &surface.uvs {
            Some(uvs) if uvs.len() == surface.vertices.len() => uvs,
            _ => {
                self.uvs.resize(self.positions.len(), Vec2::ZERO);
                return;
            }
        };
        for k in first_vertex..self.positions.len() {
            let uv = surface_uv(&surface.vertices, uvs, self.positions[k]);
            self.uvs.push(uv);
        }
    }

    fn add_surface(&mut self, polygon: &[Vec3], surface: u32, material_index: u32, material: &Material, max_edge: f32) {
        match polygon.len() {
            3 => self.add_triangle_grid(polygon, surface, material_index, material, max_edge),
            4 => self.add_quad_grid(polygon, surface, material_index, material, max_edge),
            n => panic!("surfaces are triangles or quads (the parser fans larger polygons), got {n}"),
        }
    }

    fn add_quad_grid(&mut self, q: &[Vec3], surface: u32, material_index: u32, material: &Material, max_edge: f32) {
        let nu = segments((q[1] - q[0]).length().max((q[2] - q[3]).length()), max_edge);
        let nv = segments((q[3] - q[0]).length().max((q[2] - q[1]).length()), max_edge);
        let base = self.positions.len() as u32;
        for j in 0..=nv {
            let t = j as f32 / nv as f32;
            for i in 0..=nu {
                let s = i as f32 / nu as f32;
                let p =
                    q[0] * ((1.0 - s) * (1.0 - t)) + q[1] * (s * (1.0 - t)) + q[2] * (s * t) + q[3] * ((1.0 - s) * t);
                self.positions.push(p);
            }
        }
        let idx = |i: u32, j: u32| base + j * (nu + 1) + i;
        for j in 0..nv {
            for i in 0..nu {
                let c = [idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)];
                self.push_element(c, surface, material_index, material);
            }
        }
    }

    fn add_triangle_grid(
        &mut self,
        tri: &[Vec3],
        surface: u32,
        material_index: u32,
        material: &Material,
        max_edge: f32,
    ) {
        let longest = (tri[1] - tri[0]).length().max((tri[2] - tri[1]).length()).max((tri[0] - tri[2]).length());
        let n = segments(longest, max_edge);
        let base = self.positions.len() as u32;
        // Row j holds n + 1 − j vertices: P(i, j) = v0 + (i/n)(v1 − v0) + (j/n)(v2 − v0).
        let mut row_start = Vec::with_capacity(n as usize + 1);
        for j in 0..=n {
            row_start.push(self.positions.len() as u32 - base);
            for i in 0..=(n - j) {
                let p = tri[0] + (tri[1] - tri[0]) * (i as f32 / n as f32) + (tri[2] - tri[0]) * (j as f32 / n as f32);
                self.positions.push(p);
            }
        }
        let idx = |i: u32, j: u32| base + row_start[j as usize] + i;
        for j in 0..n {
            for i in 0..(n - j) {
                self.push_element([idx(i, j), idx(i + 1, j), idx(i, j + 1), NONE], surface, material_index, material);
                if i + j + 1 < n {
                    self.push_element(
                        [idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1), NONE],
                        surface,
                        material_index,
                        material,
                    );
                }
            }
        }
    }

    /// Mirrors the elements `front` of one scene surface (already meshed, with their triangles
    /// `front_triangles`) as a back side with its own vertices and reversed winding, and links the front
    /// triangles to it.
    fn add_back_side(
        &mut self,
        front: std::ops::Range<usize>,
        front_triangles: std::ops::Range<usize>,
        mesh_surface: u32,
        material_index: u32,
        material: &Material,
    ) {
        let mut triangles_of = std::collections::HashMap::<u32, Vec<usize>>::new();
        for t in front_triangles {
            triangles_of.entry(self.triangle_element[t]).or_default().push(t);
        }
        let mut remap = std::collections::HashMap::new();
        for e in front {
            let c = self.elements.corners[e];
            let mut back = [NONE; 4];
            let n = self.elements.corner_count(e);
            for k in 0..n {
                let v = c[n - 1 - k];
                back[k] = *remap.entry(v).or_insert_with(|| {
                    self.positions.push(self.positions[v as usize]);
                    self.uvs.push(self.uvs[v as usize]);
                    self.positions.len() as u32 - 1
                });
            }
            let back_element = self.elements.len() as u32;
            let first_triangle = self.triangles.len();
            self.push_element(back, mesh_surface, material_index, material);
            // The back element's own triangles are not traced; the front triangles point to it.
            self.triangles.truncate(first_triangle);
            self.triangle_element.truncate(first_triangle);
            self.triangle_back_element.truncate(first_triangle);
            self.triangle_back_vertices.truncate(first_triangle);
            for &t in &triangles_of[&(e as u32)] {
                self.triangle_back_element[t] = back_element;
                self.triangle_back_vertices[t] = self.triangles[t].map(|v| remap[&v]);
            }
        }
    }

    fn push_element(&mut self, corners: [u32; 4], surface: u32, material_index: u32, material: &Material) {
        let p = |k: usize| self.positions[corners[k] as usize];
        let (cross, centre) = if corners[3] == NONE {
            ((p(1) - p(0)).cross(p(2) - p(0)), (p(0) + p(1) + p(2)) / 3.0)
        } else {
            ((p(2) - p(0)).cross(p(3) - p(1)), (p(0) + p(1) + p(2) + p(3)) / 4.0)
        };
        let area = 0.5 * cross.length();
        if !(area > 0.0) || !area.is_finite() {
            return; // degenerate piece: the parser already rejected degenerate faces; never a NaN here.
        }
        let element = self.elements.len() as u32;
        let e = &mut self.elements;
        e.corners.push(corners);
        e.centre.push(centre);
        e.normal.push(cross / (2.0 * area));
        e.area.push(area);
        e.surface.push(surface);
        e.material.push(material_index);
        e.reflectance.push(material.diffuse_reflectance);
        e.emission.push(material.emitted_exitance());
        let tris: &[[u32; 3]] = if corners[3] == NONE {
            &[[corners[0], corners[1], corners[2]]]
        } else {
            &[[corners[0], corners[1], corners[2]], [corners[0], corners[2], corners[3]]]
        };
        for &t in tris {
            self.triangles.push(t);
            self.triangle_element.push(element);
            self.triangle_back_element.push(NONE);
            self.triangle_back_vertices.push([NONE; 3]);
        }
    }

    /// Element e is on a one-sided dielectric surface (`surface_back_refracts`): what lies behind it is
    /// seen through its back, refracted, rather than hidden by it.
    pub fn back_refracts(&self, e: usize) -> bool {
        self.surface_back_refracts.get(self.elements.surface[e] as usize).copied().unwrap_or(false)
    }

    /// Pass one's treatment of cut-outs: an element whose mean opacity ᾱₑ is below ½ is not drawn in
    /// any hemicube, so it neither occludes nor receives a share of another element's view (it still
    /// gathers light through its own hemicube, for pass two to show on its opaque texels). An element
    /// with ᾱₑ ≥ ½ is drawn whole. The occlusion error is the misclassified part of each element,
    /// min(ᾱₑ, 1 − ᾱₑ) ≤ ½ of its projected area, and vanishes as elements shrink to the scale of the
    /// map's features (then ᾱₑ tends to 0 or 1); light through foliage with random coverage errs both
    /// ways and partly cancels.
    pub fn hidden_from_hemicubes(&self, e: usize) -> bool {
        self.element_coverage.get(e).is_some_and(|&alpha| alpha < 0.5)
    }

    /// The element on the side of triangle `t` that a ray or a light direction meets: the triangle's
    /// own element when `front` (the direction is on the side its normal points to), the back element
    /// of a two-sided surface otherwise, `None` behind a one-sided surface.
    pub fn side_element(&self, t: usize, front: bool) -> Option<usize> {
        if front {
            Some(self.triangle_element[t] as usize)
        } else if self.triangle_back_element[t] != NONE {
            Some(self.triangle_back_element[t] as usize)
        } else {
            None
        }
    }

    /// Where element i's value is measured: its hemicube's eye before the lift off the surface
    /// (`element_eye`, else the centre).
    pub fn eye(&self, i: usize) -> Vec3 {
        self.element_eye.get(i).copied().unwrap_or(self.elements.centre[i])
    }

    /// Per-vertex values from per-element values: the area-weighted mean over the elements that share
    /// the vertex (vertices are shared only within one surface side, so values never bleed across
    /// surfaces). This is Gouraud's vertex interpolation of a radiosity solution. Buried elements
    /// (`element_buried`) are left out, unless every element at the vertex is buried.
    pub fn vertex_average<T>(&self, element_values: &[T]) -> Vec<T>
    where
        T: Copy + Default + std::ops::Add<Output = T> + std::ops::Mul<f64, Output = T>,
    {
        assert_eq!(element_values.len(), self.elements.len());
        let mut sum = vec![T::default(); self.positions.len()];
        let mut weight = vec![0.0f64; self.positions.len()];
        let mut buried_sum = vec![T::default(); self.positions.len()];
        let mut buried_weight = vec![0.0f64; self.positions.len()];
        for (e, corners) in self.elements.corners.iter().enumerate() {
            let a = self.elements.area[e] as f64;
            let buried = self.element_buried.get(e).copied().unwrap_or(false);
            let (sum, weight) = if buried { (&mut buried_sum, &mut buried_weight) } else { (&mut sum, &mut weight) };
            for &v in corners.iter().filter(|&&v| v != NONE) {
                sum[v as usize] = sum[v as usize] + element_values[e] * a;
                weight[v as usize] += a;
            }
        }
        (0..sum.len())
            .map(|v| match (weight[v] > 0.0, buried_weight[v] > 0.0) {
                (true, _) => sum[v] * (1.0 / weight[v]),
                (false, true) => buried_sum[v] * (1.0 / buried_weight[v]),
                (false, false) => sum[v],
            })
            .collect()
    }

    /// The smooth normal at `p` on `element`'s scene surface, oriented like `facing`: the surface's
    /// vertex normals (`Surface::shading_normals`) interpolated linearly over the triangle (a quad: over
    /// the fan triangle (0,1,2) or (0,2,3) holding p; a triangle pair's quad, `surface_partner`: over
    /// the scene triangle of the pair that holds p, so the pair shades as the two triangles did).
    /// `facing` where that surface has none (or they cancel). The diffuse term's cosines use it
    /// (`transport::shading`).
    pub fn interpolated_normal(&self, surfaces: &[Surface], element: usize, p: Vec3, facing: Vec3) -> Vec3 {
        let mesh_surface = self.elements.surface[element] as usize;
        let Some(mut surface) = self.surface_source.get(mesh_surface).and_then(|&s| surfaces.get(s as usize)) else {
            return facing;
        };
        let partner = self.surface_partner.get(mesh_surface).and_then(|&t| surfaces.get(t as usize));
        if let Some(partner) = partner.filter(|_| surface.vertices.len() == 3) {
            let v = &surface.vertices;
            if barycentric(v[0], v[1], v[2], p).min_element() < 0.0 {
                surface = partner;
            }
        }
        let Some(normals) = &surface.shading_normals else {
            return facing;
        };
        if normals.len() != surface.vertices.len() || surface.vertices.len() < 3 {
            return facing;
        }
        let v = &surface.vertices;
        let w = barycentric(v[0], v[1], v[2], p);
        let n = if v.len() == 4 && w.y < 0.0 {
            let u = barycentric(v[0], v[2], v[3], p);
            normals[0] * u.x + normals[2] * u.y + normals[3] * u.z
        } else {
            normals[0] * w.x + normals[1] * w.y + normals[2] * w.z
        };
        let n = n.normalize_or_zero();
        if n == Vec3::ZERO {
            facing
        } else if n.dot(facing) < 0.0 {
            -n
        } else {
            n
        }
    }

    /// The normal the diffuse term's cosines use at `p` (`transport::shading`): `interpolated_normal`,
    /// but `facing` itself where the two lie within `FLAT_NORMAL_COS`: a flat face's own vertex
    /// normals, as exporters write them rounded to 4–6 digits (1 − cos ≈ 1e-9), then take the flat
    /// surface's arithmetic bit for bit.
    pub fn smooth_normal(&self, surfaces: &[Surface], element: usize, p: Vec3, facing: Vec3) -> Vec3 {
        flat_within_tolerance(self.interpolated_normal(surfaces, element, p, facing), facing)
    }

    /// Sum of element areas.
    pub fn total_area(&self) -> f64 {
        self.elements.area.iter().map(|&a| a as f64).sum()
    }
}
