//! The parts of a camera ray's radiance, for layered EXR output: how the light arrived (emitted,
//! direct, indirect, specular; they add up to the beauty radiance) and what the first hit was
//! (albedo, world-space normal, distance along the ray). The tracer fills them only when asked
//! (`Record`), so the plain path traces exactly as before.

use glam::Vec3;

use crate::film::FilmSample;

/// One camera sample split by how its light arrived, plus the first hit's surface values.
///
/// beauty = emitted + direct + indirect + specular, with, at the first hit (if diffuse):
/// emitted = E/π (the surface's own emission), direct = the light it reflects straight from the
/// emitters (B_direct/π interpolated, or ρ/π·E_direct from shadow rays with per-pixel direct light),
/// indirect = the rest of its diffuse term; specular = everything seen through mirrors and glass
/// (rays after a specular bounce) and Phong highlights.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RadianceParts {
    pub beauty: Vec3,
    pub emitted: Vec3,
    pub direct: Vec3,
    pub indirect: Vec3,
    pub specular: Vec3,
    /// Diffuse reflectance of the first hit (the texel albedo on a textured surface); 0 on a miss.
    pub albedo: Vec3,
    /// Shading normal of the first hit, world space, on the side the ray hit; 0 on a miss.
    pub normal: Vec3,
    /// Distance along the (unit) camera ray to the first hit; 0 on a miss.
    pub depth: f32,
}

/// What the tracer's loop records into: nothing (`()`, the plain path, compiled away) or the parts.
pub trait Record {
    fn parts(&mut self) -> Option<&mut RadianceParts>;
}

impl Record for () {
    #[inline(always)]
    fn parts(&mut self) -> Option<&mut RadianceParts> {
        None
    }
}

impl Record for RadianceParts {
    #[inline(always)]
    fn parts(&mut self) -> Option<&mut RadianceParts> {
        Some(self)
    }
}

impl FilmSample for RadianceParts {
    fn radiance(&self) -> Vec3 {
        self.beauty
    }

    /// Every field reconstructed with the same weights as the beauty (`film::reconstruct_pixel`), so
    /// the beauty equals the plain render's and the parts still add up to it.
    fn reconstruct(samples: &[Self], weights: &[f32]) -> Self {
        let field = |get: fn(&RadianceParts) -> Vec3| {
            let values: Vec<Vec3> = samples.iter().map(get).collect();
            crate::film::reconstruct_pixel(&values, weights)
        };
        RadianceParts {
            beauty: field(|p| p.beauty),
            emitted: field(|p| p.emitted),
            direct: field(|p| p.direct),
            indirect: field(|p| p.indirect),
            specular: field(|p| p.specular),
            albedo: field(|p| p.albedo),
            normal: field(|p| p.normal),
            depth: field(|p| Vec3::splat(p.depth)).x,
        }
    }
}
