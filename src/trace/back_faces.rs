//! How much of the camera's view lands on the back of one-sided surfaces, which pass two shows black:
//! a deterministic grid of primary rays, for `radray info` and the warning `render` gives. Scenes
//! converted from renderers whose materials are two-sided by default are the usual cause.

use serde::Serialize;

use super::camera::PinholeCamera;
use crate::accel::Accel;
use crate::mesh::Mesh;
use crate::scene::{Camera, Material};
use crate::transport::hit::SurfaceHit;

/// Above this share of primary hits on back faces, `render` warns and `info` suggests
/// `two_sided = true` (5%: a few back faces seen through a gap are normal, a twentieth of the picture
/// is not).
pub const WARN_SHARE: f64 = 0.05;

/// Rays across the longer side of the probe grid; the shorter side follows the image's aspect. 64
/// rays give the share to about ±1% (a 64 × 48 grid samples 3072 pixels) for a few milliseconds.
pub const PROBE_RAYS_ACROSS: u32 = 64;

/// What the probe grid saw.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BackFaceShare {
    /// Primary rays traced (the probe grid).
    pub rays: u64,
    /// Rays that hit the scene.
    pub hits: u64,
    /// Hits on the back of a one-sided, non-transparent surface (dielectrics refract on both sides).
    pub back_hits: u64,
}

impl BackFaceShare {
    /// back_hits / hits (0 when nothing was hit).
    pub fn share(&self) -> f64 {
        if self.hits == 0 {
            0.0
        } else {
            self.back_hits as f64 / self.hits as f64
        }
    }

    /// The share exceeds `WARN_SHARE`.
    pub fn is_large(&self) -> bool {
        self.share() > WARN_SHARE
    }

    /// The one-line warning `render` prints and `info` lists, or `None` below `WARN_SHARE`.
    pub fn warning(&self) -> Option<String> {
        self.is_large().then(|| {
            format!(
                "{:.1}% of the camera's primary hits ({} of {} probe rays that hit) are on the back of one-sided \
                 surfaces, which render black; if the scene comes from a renderer with two-sided materials, set \
                 `two_sided = true` on its meshes",
                100.0 * self.share(),
                self.back_hits,
                self.hits
            )
        })
    }
}

/// Traces a grid of `PROBE_RAYS_ACROSS` rays across the longer side of a `width_px` × `height_px`
/// image (through the centres of equal cells, so the result is deterministic) from `camera` and
/// counts the hits on back faces of one-sided surfaces. Cut-outs are not followed: a ray stops at the
/// first triangle it meets.
pub fn probe(
    mesh: &Mesh,
    accel: &Accel,
    materials: &[Material],
    camera: &Camera,
    width_px: u32,
    height_px: u32,
) -> BackFaceShare {
    let (width_px, height_px) = (width_px.max(1), height_px.max(1));
    let longer = width_px.max(height_px) as f32;
    let cells = |side: u32| ((PROBE_RAYS_ACROSS as f32 * side as f32 / longer).round() as u32).max(1);
    let (nx, ny) = (cells(width_px), cells(height_px));
    let pinhole = PinholeCamera::new(camera, width_px, height_px);
    let mut share = BackFaceShare { rays: 0, hits: 0, back_hits: 0 };
    for j in 0..ny {
        for i in 0..nx {
            let film_x = (i as f32 + 0.5) / nx as f32 * width_px as f32;
            let film_y = (j as f32 + 0.5) / ny as f32 * height_px as f32;
            let ray = pinhole.ray(film_x, film_y);
            share.rays += 1;
            let Some(hit) = accel.closest_hit(ray.origin, ray.dir, 0.0, f32::INFINITY) else { continue };
            share.hits += 1;
            if is_black_back_face(materials, &SurfaceHit::new(mesh, &hit, ray.dir)) {
                share.back_hits += 1;
            }
        }
    }
    share
}

/// The hit is on the back of a one-sided surface that is not a dielectric.
fn is_black_back_face(materials: &[Material], hit: &SurfaceHit) -> bool {
    !hit.front && hit.element.is_none() && !materials[hit.material as usize].is_dielectric()
}

/// The share for a scene's own camera and image size.
pub fn probe_scene(scene: &crate::scene::SceneDescription, mesh: &Mesh, accel: &Accel) -> BackFaceShare {
    probe(mesh, accel, &scene.materials, &scene.camera, scene.image.width_px, scene.image.height_px)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn share_is_back_hits_over_hits_and_warns_only_above_five_percent() {
        let at = |back_hits| BackFaceShare { rays: 200, hits: 100, back_hits };
        assert_eq!(at(5).share(), 0.05);
        assert!(at(5).warning().is_none(), "exactly 5% does not warn");
        let text = at(6).warning().expect("6% warns");
        assert!(text.contains("6.0%") && text.contains("two_sided = true"), "{text}");
        assert_eq!(BackFaceShare { rays: 10, hits: 0, back_hits: 0 }.share(), 0.0);
    }
}
