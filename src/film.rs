//! The film: stratified jittered samples per pixel, reconstruction filters, and the finished image.

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
}
