//! The second bounce of a final gather where its ray lands close by (Lischinski, Tampieri and
//! Greenberg 1993; Lightscape's regathering): there the hit element subtends a large solid angle, and
//! its interpolated exitance carries the element's own bias (along a concave edge, the same bias the
//! gather is meant to remove), so the exitance is estimated again at the point.

use std::f32::consts::PI;

use glam::Vec3;

use super::hemisphere::{frame, Strata};
use crate::film::Sampler;
use crate::trace::whitted::{RayCounts, Tracer};
use crate::transport::hit::leave_surface;
use crate::transport::SurfaceHit;

/// Shadow rays per near hit: one, since a gather averages its near hits' estimates over hundreds of
/// cells (and each cell's sample stays unbiased).
pub const NEAR_LIGHT_SAMPLES: u32 = 1;

/// When and how a gather ray's hit is re-estimated (`[render] near_bounce`, `near_bounce_rays`;
/// `scene::RenderParams::near_bounce_for`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NearBounce {
    /// A hit closer than `distance_factor`·√Aₑ (Aₑ the hit element's area) is re-estimated; 0 turns
    /// the second bounce off, infinity applies it to every hit.
    pub distance_factor: f32,
    /// A re-estimated hit closer than `shadow_factor`·√Aₑ takes its direct light from a shadow ray; a
    /// farther one the solution's direct part B_direct interpolated there (`near_exitance`).
    pub shadow_factor: f32,
    /// Cells of the secondary gather at a re-estimated hit.
    pub strata: Strata,
}

impl NearBounce {
    /// `rays` cells: M × N as `Strata::for_rays` from 6 rays up, one ring of `rays` sectors below.
    /// Every re-estimated hit takes a shadow ray (`shadow_factor` = `distance_factor`).
    pub fn new(distance_factor: f32, rays: u32) -> NearBounce {
        let strata = if rays >= 6 { Strata::for_rays(rays) } else { Strata { rings: 1, sectors: rays.max(1) } };
        NearBounce { distance_factor, shadow_factor: distance_factor, strata }
    }

    /// Shadow rays only at hits closer than `shadow_factor`·√Aₑ (at most `distance_factor`).
    pub fn with_shadow_factor(self, shadow_factor: f32) -> NearBounce {
        NearBounce { shadow_factor: shadow_factor.min(self.distance_factor), ..self }
    }

    /// Whether a hit `distance` away on an element of area `element_area` is near: r < k·√Aₑ.
    pub fn applies(&self, distance: f32, element_area: f32) -> bool {
        distance < self.distance_factor * element_area.max(0.0).sqrt()
    }

    /// Whether a re-estimated hit `distance` away on an element of area `element_area` takes its
    /// direct light from a shadow ray: r < `shadow_factor`·√Aₑ.
    pub fn shadow_ray_at(&self, distance: f32, element_area: f32) -> bool {
        distance < self.shadow_factor * element_area.max(0.0).sqrt()
    }
}

impl Tracer<'_> {
    /// The reflected exitance B(x) − E at a gather ray's near hit x on `element` (reflectance ρₑ, the
    /// element's as in pass one), estimated at the point rather than interpolated:
    ///
    /// B(x) − E = ρₑ·(E_direct(x) + H(x) + E_caustic(x)),
    ///
    /// E_direct from `NEAR_LIGHT_SAMPLES` shadow rays (`DirectLight::irradiance`) where the hit, `distance`
    /// from the gather's point, is within `NearBounce::shadow_ray_at`, else ρₑ·E_direct(x) = B_direct(x)
    /// the solution's direct part interpolated at x (a shadow ray's variance grows as 1/d² near an
    /// emitter's edge, and a gather whose every hit bounces sees many of them: a furnace's pixels
    /// scattered by 6% rms, 86% at worst), H = π/(MN) Σ L_jk a
    /// secondary gather over `near.strata` whose rays read the interpolated solution
    /// (`gather_radiance` without a further near bounce) and E_caustic the caustic map's density
    /// estimate at x (0 without a map; with one, the secondary gather leaves that light to it). The
    /// solution's errors then enter one bounce
    /// further away, damped by ρ. On a smooth surface both take its shading normal, guarded by the
    /// geometric one as at the camera's hits (`Tracer::gather`: H = π/T Σ over the T cells above the
    /// facet's plane).
    pub fn near_exitance(
        &self,
        hit: &SurfaceHit,
        element: usize,
        near: &NearBounce,
        distance: f32,
        sampler: &mut Sampler,
        counts: &mut RayCounts,
    ) -> Vec3 {
        let elements = &self.mesh().elements;
        let reflectance = elements.reflectance[element];
        if reflectance.max_element() <= 0.0 {
            return Vec3::ZERO;
        }
        let x = hit.position;
        let normals = self.smooth_normals(hit);
        let direct_exitance = if near.shadow_ray_at(distance, elements.area[element]) {
            reflectance * self.direct_light().estimate(NEAR_LIGHT_SAMPLES, x, normals, None, sampler, counts).irradiance
        } else {
            self.diffuse().direct_exitance_at(hit)
        };
        let n = normals.shading;
        let (t, b) = frame(n);
        let origin = leave_surface(x, normals.geometric, self.ray_offset());
        let strata = near.strata;
        let mut sum = Vec3::ZERO;
        let mut traced = 0;
        for j in 0..strata.rings {
            for k in 0..strata.sectors {
                let local = strata.direction(j, k, sampler.next_1d(), sampler.next_1d());
                let dir = (t * local.x + b * local.y + n * local.z).normalize();
                if normals.admits(dir) {
                    sum += self.gather_radiance(origin, dir, None, sampler, counts).0;
                    traced += 1;
                }
            }
        }
        // Cells below the geometric plane give their share to the traced ones, as in `Tracer::gather`.
        let indirect = if traced > 0 { sum * (PI / traced as f32) } else { Vec3::ZERO };
        // The light through mirrors and glass to an emitter, which the gather rays leave to the map.
        let caustic = self.caustics().map_or(Vec3::ZERO, |map| map.irradiance(x, hit.surface));
        direct_exitance + reflectance * (indirect + caustic)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn few_rays_get_one_ring() {
        assert_eq!(NearBounce::new(2.0, 4).strata, Strata { rings: 1, sectors: 4 });
        assert_eq!(NearBounce::new(2.0, 16).strata, Strata::for_rays(16));
    }

    #[test]
    fn near_is_relative_to_the_hit_elements_size() {
        let near = NearBounce::new(2.0, 8);
        assert!(near.applies(0.19, 0.01) && !near.applies(0.21, 0.01));
        assert!(!NearBounce::new(0.0, 8).applies(0.0, 1.0));
        assert!(NearBounce::new(f32::INFINITY, 8).applies(100.0, 1e-6));
    }

    #[test]
    fn shadow_rays_only_within_their_own_distance() {
        let every = NearBounce::new(f32::INFINITY, 1).with_shadow_factor(2.5);
        assert!(every.applies(1.0, 0.01) && !every.shadow_ray_at(1.0, 0.01) && every.shadow_ray_at(0.2, 0.01));
        let near = NearBounce::new(2.0, 2);
        assert!(near.shadow_ray_at(0.19, 0.01) && !near.shadow_ray_at(0.21, 0.01));
        assert_eq!(NearBounce::new(2.0, 2).with_shadow_factor(5.0).shadow_factor, 2.0);
    }
}
