//! Pass two: a Whitted ray tracer (Whitted 1980) whose diffuse term is the radiosity solution.
//! `camera` makes primary rays, `diffuse` reads the solution back at a hit, `gather` gathers
//! the indirect light from it at the points the camera sees (with an irradiance cache), `caustics` sharpens the
//! light that reached diffuse surfaces through mirrors and glass, and `whitted` is the ray-stack tracer
//! that the film calls once per sample. The specular rules live in `transport`, shared with pass one.

pub mod back_faces;
pub mod camera;
pub mod caustics;
pub mod diffuse;
pub mod direct_light;
pub mod gather;
pub mod parts;
pub mod whitted;

pub use camera::PinholeCamera;
pub use diffuse::{Diffuse, DiffuseEstimator};
pub use parts::RadianceParts;
pub use whitted::{RayCounts, TraceError, TraceMode, Tracer};

use glam::Vec3;

/// A ray: `origin + t·dir`, `dir` of unit length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: Vec3,
    pub dir: Vec3,
}
