//! The image the film develops: linear RGB radiance per pixel, and its luminance.

use glam::Vec3;

/// A linear RGB image (radiance), row-major from the top-left pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width_px: u32,
    pub height_px: u32,
    pub pixels: Vec<Vec3>,
}

impl Image {
    pub fn new(width_px: u32, height_px: u32) -> Self {
        Image { width_px, height_px, pixels: vec![Vec3::ZERO; width_px as usize * height_px as usize] }
    }

    pub fn get(&self, x: u32, y: u32) -> Vec3 {
        self.pixels[(y * self.width_px + x) as usize]
    }

    /// Sets pixel (x, y); panics when outside the image (an internal invariant of the caller).
    pub fn set(&mut self, x: u32, y: u32, radiance: Vec3) {
        let i = (y * self.width_px + x) as usize;
        self.pixels[i] = radiance;
    }

    /// True when `pixels` holds exactly `width_px · height_px` values.
    pub fn is_consistent(&self) -> bool {
        self.pixels.len() == self.width_px as usize * self.height_px as usize
    }
}

/// Rec. 709 luminance Y = 0.2126 R + 0.7152 G + 0.0722 B.
pub fn luminance(radiance: Vec3) -> f32 {
    0.2126 * radiance.x + 0.7152 * radiance.y + 0.0722 * radiance.z
}
