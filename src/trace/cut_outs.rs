//! Cut-outs (`map_d` or the alpha of `map_Kd`) as rays see them: a surface whose opacity reads below ½
//! at a hit is not there. Camera paths (`whitted`) and shadow rays (`whitted`, `direct_light`) share
//! these rules, so a leaf's shadow has the leaf's holes.

use glam::Vec3;

use crate::accel::Accel;
use crate::mesh::Mesh;
use crate::transport::SurfaceHit;

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

/// A shadow ray from `origin` along unit `dir` meets an opaque surface before `t_max`. Cut-outs let it
/// through where their opacity is below ½ (the finest texels: a shadow ray has no pixel footprint);
/// more than `MAX_CUTOUT_CROSSINGS` cut-outs count as blocked. Each crossing moves on by `offset`.
/// Without cut-outs in the scene this is the accelerator's any-hit query.
pub fn shadow_blocked(mesh: &Mesh, accel: &Accel, offset: f32, origin: Vec3, dir: Vec3, t_max: f32) -> bool {
    if !mesh.textures.has_cut_outs() {
        return accel.occluded(origin, dir, t_max);
    }
    let mut from = origin;
    let mut travelled = 0.0f32;
    for _ in 0..=MAX_CUTOUT_CROSSINGS {
        let Some(hit) = accel.closest_hit(from, dir, 0.0, t_max - travelled) else {
            return false;
        };
        let surface_hit = SurfaceHit::new(mesh, &hit, dir);
        if !is_cut_out(mesh, &surface_hit, 0.0) {
            return true;
        }
        from = surface_hit.position + dir * offset;
        travelled += hit.t + offset;
        if travelled >= t_max {
            return false;
        }
    }
    true
}
