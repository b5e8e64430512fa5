//! The pinhole camera: primary rays from film positions in pixels.

use glam::Vec3;

use super::Ray;
use crate::scene::Camera;

/// A pinhole camera for an image of `width_px` × `height_px` pixels. Right-handed: forward points from
/// the eye to `look_at`, image-right = normalize(forward × up), image-up = right × forward.
#[derive(Clone, Debug, PartialEq)]
pub struct PinholeCamera {
    eye: Vec3,
    forward: Vec3,
    right: Vec3,
    up: Vec3,
    /// tan(vfov/2): half the film height at unit distance.
    tan_half_vfov: f32,
    width_px: f32,
    height_px: f32,
}

impl PinholeCamera {
    /// The camera must have been validated by the parser: 0 < vfov < 180°, eye ≠ look_at, up not
    /// parallel to the view direction.
    pub fn new(camera: &Camera, width_px: u32, height_px: u32) -> Self {
        let forward = (camera.look_at - camera.eye).normalize();
        let right = forward.cross(camera.up).normalize();
        let up = right.cross(forward);
        PinholeCamera {
            eye: camera.eye,
            forward,
            right,
            up,
            tan_half_vfov: (0.5 * camera.vfov_deg).to_radians().tan(),
            width_px: width_px as f32,
            height_px: height_px as f32,
        }
    }

    /// The ray through film position (`film_x`, `film_y`) in pixels from the image's top-left corner
    /// (pixel (x, y) covers [x, x+1) × [y, y+1)). With h = tan(vfov/2) and aspect a = width/height:
    /// dir ∝ forward + (2x/W − 1)·h·a·right + (1 − 2y/H)·h·up.
    pub fn ray(&self, film_x: f32, film_y: f32) -> Ray {
        let aspect = self.width_px / self.height_px;
        let sx = (2.0 * film_x / self.width_px - 1.0) * self.tan_half_vfov * aspect;
        let sy = (1.0 - 2.0 * film_y / self.height_px) * self.tan_half_vfov;
        Ray { origin: self.eye, dir: (self.forward + sx * self.right + sy * self.up).normalize() }
    }

    pub fn eye(&self) -> Vec3 {
        self.eye
    }

    pub fn forward(&self) -> Vec3 {
        self.forward
    }

    /// Image-right in world space.
    pub fn right(&self) -> Vec3 {
        self.right
    }

    /// Image-up in world space.
    pub fn up(&self) -> Vec3 {
        self.up
    }
}
