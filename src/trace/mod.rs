//! Pass two: a Whitted ray tracer (Whitted 1980) whose diffuse term is the radiosity solution.
//! `camera` makes primary rays, `optics` holds the reflection/refraction formulas, and `whitted` the
//! ray-stack tracer that the film calls once per sample.

pub mod camera;
pub mod caustics;
pub mod optics;
pub mod whitted;

pub use camera::PinholeCamera;
pub use whitted::{RayCounts, TraceError, TraceMode, Tracer};

use glam::Vec3;

/// A ray: `origin + t·dir`, `dir` of unit length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: Vec3,
    pub dir: Vec3,
}
