//! Cut-outs (`map_d` or the alpha of `map_Kd`) as rays see them: a surface whose opacity reads below ½
//! at a hit is not there. Every ray kind shares these rules (camera paths, gather rays, shadow rays,
//! highlight rays and photons), so a leaf's shadow has the leaf's holes and light passes the holes
//! the camera sees through.

use glam::Vec3;

use super::hit::offset_at;
use super::SurfaceHit;
use crate::accel::Accel;
use crate::mesh::Mesh;

/// Most cut-out surfaces (opacity < ½) one ray passes through before it is stopped.
pub const MAX_CUTOUT_CROSSINGS: u32 = 64;

/// The surface's opacity map reads below ½ at `hit`, looked up over a footprint of `footprint` scene
/// units (false without a map or uv).
pub fn is_cut_out(mesh: &Mesh, hit: &SurfaceHit, footprint: f32) -> bool {
    match mesh.textures.maps(hit.material).filter(|m| m.has_opacity()) {
        Some(maps) if mesh.surface_has_uv.get(hit.surface as usize).copied().unwrap_or(false) => {
            maps.opacity_at(hit.uv, footprint * hit.uv_per_length(mesh)) < 0.5
        }
        _ => false,
    }
}

/// How a ray looks through cut-outs: the accelerator, the offset each crossing moves on by, and the
/// ray's spread (footprint = distance · `spread_rad` scene units; 0 reads the finest texels).
#[derive(Clone, Copy)]
pub struct OpaqueRay<'a> {
    pub mesh: &'a Mesh,
    pub accel: &'a Accel,
    pub offset: f32,
    pub spread_rad: f32,
}

/// Where a ray walking through cut-outs ends.
enum Walk {
    /// At an opaque surface, this far from the origin.
    Opaque(SurfaceHit, f32),
    /// Nothing opaque before `t_max`.
    Clear,
    /// Stopped after `MAX_CUTOUT_CROSSINGS` cut-outs.
    TooManyCrossings,
}

impl OpaqueRay<'_> {
    /// The closest hit with distance in (0, `t_max`] along unit `dir` that is not cut out, and its
    /// distance from `origin`. Cut-outs are passed through (at most `MAX_CUTOUT_CROSSINGS`; past that
    /// the ray is lost, `None`). Without cut-outs in the scene this is the accelerator's closest hit.
    pub fn closest_hit(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<(SurfaceHit, f32)> {
        match self.walk(origin, dir, t_max, self.spread_rad) {
            Walk::Opaque(hit, distance) => Some((hit, distance)),
            Walk::Clear | Walk::TooManyCrossings => None,
        }
    }

    /// A shadow ray from `origin` along unit `dir` meets an opaque surface before `t_max`. It reads the
    /// finest texels (a shadow ray has no footprint); more than `MAX_CUTOUT_CROSSINGS` cut-outs count
    /// as blocked. Without cut-outs in the scene this is the accelerator's any-hit query.
    pub fn blocked(&self, origin: Vec3, dir: Vec3, t_max: f32) -> bool {
        if !self.mesh.textures.has_cut_outs() {
            return self.accel.occluded(origin, dir, t_max);
        }
        !matches!(self.walk(origin, dir, t_max, 0.0), Walk::Clear)
    }

    fn walk(&self, origin: Vec3, dir: Vec3, t_max: f32, spread_rad: f32) -> Walk {
        let mut from = origin;
        let mut travelled = 0.0f32;
        for _ in 0..=MAX_CUTOUT_CROSSINGS {
            let Some(hit) = self.accel.closest_hit(from, dir, 0.0, t_max - travelled) else {
                return Walk::Clear;
            };
            let surface_hit = SurfaceHit::new(self.mesh, &hit, dir);
            let distance = travelled + hit.t;
            if !is_cut_out(self.mesh, &surface_hit, distance * spread_rad) {
                return Walk::Opaque(surface_hit, distance);
            }
            let step = offset_at(surface_hit.position, self.offset);
            from = surface_hit.position + dir * step;
            travelled = distance + step;
            if travelled >= t_max {
                return Walk::Clear;
            }
        }
        Walk::TooManyCrossings
    }
}
