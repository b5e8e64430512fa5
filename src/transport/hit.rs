//! Where a ray meets the mesh, seen from the side it arrives on: the one reconstruction of a hit point,
//! its normals, element and material for both passes, and the scene-scale distance by which new rays
//! leave a surface.

use glam::{Vec2, Vec3};

use crate::accel::Hit;
use crate::mesh::{flat_within_tolerance, Mesh, NONE};
use crate::scene::Surface;
use crate::transport::shading::SurfaceNormals;

/// Ray origins are moved off surfaces by this fraction of the scene's size (`scene_scale`): about
/// 100 ulps of the coordinates of a scene near the origin, far below any feature size.
pub const RELATIVE_OFFSET: f32 = 1e-5;

/// Near a point p an f32 coordinate is only known to about ε·max|pᵢ| (ε = `f32::EPSILON`, one to two
/// ulps), and a hit point reconstructed from barycentrics carries about that much error (Pharr, Jakob
/// and Humphreys, *PBR* 3rd ed., 3.9). A ray leaving p moves off its surface by at least this many
/// ε·max|pᵢ|, so a scene far from the origin (an architectural export at 10⁵ units) does not hit
/// itself. Measured on a 4 × 3 × 5 room moved to x = 10⁵ (tests/invariance.rs' scene): 0 gives
/// self-shadowing (final image relMSE 7.8e-3 against the room at the origin), 0.5 to 2 agree to
/// < 1e-4; 4 and more lift the probes of `burial` past the room's 0.03-unit gap between lamp and
/// ceiling (4 ulps there), so the bound stays small.
pub const COORDINATE_OFFSET_EPSILONS: f32 = 2.0;

/// The scene's size: its largest extent along the axes (1 for an empty mesh). Offsets and kernel
/// radii are fractions of it, so they follow the scene's unit and ignore where it sits.
pub fn scene_scale(mesh: &Mesh) -> f32 {
    if mesh.positions.is_empty() {
        return 1.0;
    }
    let (lo, hi) = mesh
        .positions
        .iter()
        .fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    (hi - lo).max_element().max(f32::MIN_POSITIVE)
}

/// Distance by which ray origins leave a surface of a scene of size `scale`: `RELATIVE_OFFSET · scale`,
/// before `offset_at` raises it to the precision of the coordinates where the ray starts.
pub fn ray_offset(scale: f32) -> f32 {
    RELATIVE_OFFSET * scale
}

/// The offset a ray leaving point `p` takes: max(`offset`, k·ε·max|pᵢ|), k = `COORDINATE_OFFSET_EPSILONS`.
/// Scaling a scene by s scales both terms by s; translating it changes only the second, which is then
/// the coordinates' own resolution.
pub fn offset_at(p: Vec3, offset: f32) -> f32 {
    offset.max(p.abs().max_element() * (COORDINATE_OFFSET_EPSILONS * f32::EPSILON))
}

/// p moved off its surface along `dir` (a unit normal, or its negation) by `offset_at(p, offset)`.
pub fn leave_surface(p: Vec3, dir: Vec3, offset: f32) -> Vec3 {
    p + dir * offset_at(p, offset)
}

/// A ray's closest hit on the mesh, seen from the side the ray arrives on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceHit {
    /// The hit point p = b₀v₀ + b₁v₁ + b₂v₂ on the triangle.
    pub position: Vec3,
    /// The triangle's geometric normal turned towards the arriving ray: it decides the side and
    /// offsets new ray origins.
    pub geometric_normal: Vec3,
    /// The normal that bends specular rays: the geometric one unless `with_shading_normal` found the
    /// surface's smooth-shading normal (and it faces the arriving ray).
    pub shading_normal: Vec3,
    /// The normal the diffuse term's cosines use (`normals`): the surface's interpolated vertex normal
    /// turned to the side hit once `with_shading_normal` has looked (`Mesh::smooth_normal`), the
    /// geometric one without vertex normals (or with a flat face's own). Unlike `shading_normal` it does not fall back where it
    /// faces away from the ray: the Lambertian term does not depend on where the viewer is, and a
    /// fallback there would draw the facets back in along a silhouette.
    pub smooth_normal: Vec3,
    /// Index into `Mesh::triangles`.
    pub triangle: u32,
    /// The ray arrives on the side the triangle's normal points to.
    pub front: bool,
    /// The element that owns the triangle (its front side); the material is read from it.
    pub front_element: u32,
    /// The element on the side hit; `None` behind a one-sided surface.
    pub element: Option<u32>,
    /// The mesh surface (`Elements::surface`) of the side hit (of the front side when there is none).
    pub surface: u32,
    /// The corners of the side hit (`Mesh::triangle_back_vertices` on a back side), for Gouraud
    /// interpolation of per-vertex values at `bary`.
    pub vertices: [u32; 3],
    /// Barycentrics (b₀, b₁, b₂) of `position` on the triangle.
    pub bary: [f32; 3],
    /// Texture coordinates at the hit, uv = Σ_k b_k uv(v_k) over the triangle ((0, 0) on surfaces
    /// without uv).
    pub uv: Vec2,
    /// Material index (`Elements::material` of `front_element`).
    pub material: u32,
}

impl SurfaceHit {
    /// The hit `hit` of a ray with direction `dir` on `mesh` (whose triangles the accelerator was
    /// built from).
    pub fn new(mesh: &Mesh, hit: &Hit, dir: Vec3) -> SurfaceHit {
        let t = hit.triangle as usize;
        let elements = &mesh.elements;
        let front_element = mesh.triangle_element[t];
        let normal = elements.normal[front_element as usize];
        let front = dir.dot(normal) < 0.0;
        let (element, vertices) = if front {
            (Some(front_element), mesh.triangles[t])
        } else if mesh.triangle_back_element[t] != NONE {
            (Some(mesh.triangle_back_element[t]), mesh.triangle_back_vertices[t])
        } else {
            (None, mesh.triangles[t])
        };
        let bary = [1.0 - hit.u - hit.v, hit.u, hit.v];
        let [i0, i1, i2] = mesh.triangles[t];
        let position = mesh.positions[i0 as usize] * bary[0]
            + mesh.positions[i1 as usize] * bary[1]
            + mesh.positions[i2 as usize] * bary[2];
        let uv = if mesh.uvs.len() == mesh.positions.len() {
            mesh.uvs[i0 as usize] * bary[0] + mesh.uvs[i1 as usize] * bary[1] + mesh.uvs[i2 as usize] * bary[2]
        } else {
            Vec2::ZERO
        };
        let facing = if front { normal } else { -normal };
        SurfaceHit {
            position,
            geometric_normal: facing,
            shading_normal: facing,
            smooth_normal: facing,
            triangle: hit.triangle,
            front,
            front_element,
            element,
            surface: elements.surface[element.unwrap_or(front_element) as usize],
            vertices,
            bary,
            uv,
            material: elements.material[front_element as usize],
        }
    }

    /// Sets, from the surfaces' vertex normals interpolated at the hit (`Mesh::interpolated_normal`;
    /// `surfaces` is the scene the mesh was built from), the smooth normal (as `Mesh::smooth_normal`)
    /// and the shading normal that bends specular rays for a ray arriving along `incoming`: the
    /// interpolated normal n where n·incoming < 0, else the geometric one (a mirror direction would
    /// point into the surface). Pass one's specular paths and pass two's
    /// Whitted rays both bend by this rule. Keeps the geometric normal without `surfaces`.
    pub fn with_shading_normal(mut self, mesh: &Mesh, surfaces: Option<&[Surface]>, incoming: Vec3) -> SurfaceHit {
        if let Some(surfaces) = surfaces {
            let (facing, element) = (self.geometric_normal, self.front_element as usize);
            let interpolated = mesh.interpolated_normal(surfaces, element, self.position, facing);
            self.shading_normal = if interpolated.dot(incoming) < 0.0 { interpolated } else { facing };
            self.smooth_normal = flat_within_tolerance(interpolated, facing);
        }
        self
    }

    /// The normals the diffuse term is shaded with at this hit: geometric and smooth
    /// (`transport::shading`).
    pub fn normals(&self) -> SurfaceNormals {
        SurfaceNormals { geometric: self.geometric_normal, shading: self.smooth_normal }
    }

    /// How many uv units one unit of length on the hit triangle spans: √(A_uv / A_world), with A_uv and
    /// A_world the triangle's areas in uv and in space (0 for a triangle without uv extent). A pixel
    /// footprint of w scene units is w times this in uv units.
    pub fn uv_per_length(&self, mesh: &Mesh) -> f32 {
        let [i0, i1, i2] = mesh.triangles[self.triangle as usize].map(|i| i as usize);
        if mesh.uvs.len() != mesh.positions.len() {
            return 0.0;
        }
        let (p, t) = (&mesh.positions, &mesh.uvs);
        let world = (p[i1] - p[i0]).cross(p[i2] - p[i0]).length();
        let uv = (t[i1] - t[i0]).perp_dot(t[i2] - t[i0]).abs();
        if world > 0.0 && uv.is_finite() {
            (uv / world).sqrt()
        } else {
            0.0
        }
    }

    /// Origin of a ray leaving on the side the ray arrived from: p + `offset_at`(p, offset)·n_g.
    pub fn above(&self, offset: f32) -> Vec3 {
        leave_surface(self.position, self.geometric_normal, offset)
    }

    /// Origin of a ray going through the surface: p − `offset_at`(p, offset)·n_g.
    pub fn below(&self, offset: f32) -> Vec3 {
        leave_surface(self.position, -self.geometric_normal, offset)
    }

    /// Gouraud interpolation of per-vertex `values` over the side hit: Σ_k b_k·values[v_k].
    pub fn interpolate(&self, values: &[Vec3]) -> Vec3 {
        values[self.vertices[0] as usize] * self.bary[0]
            + values[self.vertices[1] as usize] * self.bary[1]
            + values[self.vertices[2] as usize] * self.bary[2]
    }
}
