//! Final gather over the radiosity solution (Reichert 1992; Lischinski, Tampieri and Greenberg 1993):
//! at a diffuse point seen by the camera the indirect light is gathered over the hemisphere from the
//! solution, so the elements' errors matter one bounce away, smoothed by the integral. An irradiance
//! cache with gradients (Ward, Rubinstein and Clear 1988; Ward and Heckbert 1992) makes it cheap.
//! `hemisphere` holds the cells and gradient kernels, `rays` what one gather ray reads, `near` the
//! second bounce where a ray lands close by, `refine` which records gather more rays, `cache` the records and their interpolation, `prepass`
//! the deterministic filling before the image.

pub mod cache;
pub mod hemisphere;
pub mod near;
pub mod prepass;
pub mod rays;
pub mod refine;

pub use cache::{IrradianceCache, IrradianceRecord};
pub use hemisphere::{HemisphereEstimate, Strata};
pub use near::NearBounce;
pub use prepass::{fill, PrepassStats, LEVELS};
pub use refine::GatherRefinement;

use glam::Vec3;

use crate::film::Sampler;
use crate::scene::{ImageSettings, RenderParams};
use crate::trace::camera::PinholeCamera;
use crate::trace::whitted::{RayCounts, Tracer};
use crate::transport::shading::SurfaceNormals;

/// The final gather for one image through `camera` as `params` ask: strata for `gather_rays`, and
/// unless `cache_accuracy` is 0 the cache filled by `prepass::fill` (seeded by the image's seed),
/// which calls `on_level_done` after each level.
pub fn for_image(
    tracer: &Tracer,
    camera: &PinholeCamera,
    params: &RenderParams,
    image: &ImageSettings,
    pixel_angle_rad: f32,
    on_level_done: &(dyn Fn(usize) + Sync),
) -> (FinalGather, PrepassStats) {
    let strata = Strata::for_rays(params.gather_rays);
    let adaptive_strata = Strata::for_rays(adaptive_gather_rays(params.gather_rays));
    if params.cache_accuracy <= 0.0 {
        return (FinalGather { strata, adaptive_strata, cache: None }, PrepassStats::default());
    }
    let (cache, stats) = fill(
        tracer,
        camera,
        image.width_px,
        image.height_px,
        pixel_angle_rad,
        strata,
        GatherRefinement::new(params.gather_rays, params.gather_refine_error).as_ref(),
        params.cache_accuracy,
        image.seed,
        on_level_done,
    );
    (FinalGather { strata, adaptive_strata, cache: Some(cache) }, stats)
}

/// An adaptive sample's own gathers take this fraction of `gather_rays` (see `FinalGather::irradiance`).
pub const ADAPTIVE_GATHER_DIVISOR: u32 = 4;

/// Rays of a gather made for an adaptive sample: `gather_rays` / [`ADAPTIVE_GATHER_DIVISOR`], at least
/// 16 (a 2 × 8 stratification).
pub fn adaptive_gather_rays(gather_rays: u32) -> u32 {
    (gather_rays / ADAPTIVE_GATHER_DIVISOR).max(16)
}

/// Where the gathered indirect irradiance comes from during the image.
#[derive(Clone, Debug)]
pub struct FinalGather {
    pub strata: Strata,
    /// The strata of the gathers adaptive samples make (`adaptive_gather_rays`).
    pub adaptive_strata: Strata,
    /// The prepass's records; `None` gathers at every diffuse hit (`cache_accuracy = 0`).
    pub cache: Option<IrradianceCache>,
}

impl FinalGather {
    /// The indirect irradiance at diffuse point `p` with `normals` (see `Tracer::gather`): the cache's
    /// interpolation where a record serves, else a gather of its own (drawn from the pixel's `sampler`, not stored, so the
    /// image does not depend on which thread got there first).
    ///
    /// A pixel's adaptive samples (`Sampler::is_adaptive`) land where the base samples disagreed:
    /// silhouettes and contact edges, where the cache serves least, so most of them gather. Their
    /// gathers use `adaptive_strata`, a quarter of the rays. This adds no bias: a gather is a stratified
    /// estimate Ĥ = Σ_cells (π/MN)·L(ω_jk), one jittered direction per cell, and E[Ĥ] = H for any
    /// M × N (each cell's jitter is uniform over it), so only its variance grows, about 4×; the pixel
    /// averages that gather with its other samples (tens of them in an adaptive pixel), whose own
    /// noise (edges, direct light) is what sent it to the adaptive pass.
    ///
    /// Records are keyed by the shading normal (`prepass`), so on a smooth surface Ward's weight and
    /// the rotation gradient follow the normal the lobe is built around, not the facets.
    pub fn irradiance(
        &self,
        tracer: &Tracer,
        p: Vec3,
        normals: impl Into<SurfaceNormals>,
        sampler: &mut Sampler,
        counts: &mut RayCounts,
    ) -> Vec3 {
        let normals = normals.into();
        if let Some(e) = self.cache.as_ref().and_then(|c| c.lookup(p, normals.shading)) {
            return e;
        }
        let strata = if sampler.is_adaptive() { self.adaptive_strata } else { self.strata };
        tracer.gather(p, normals, strata, sampler, counts).irradiance
    }
}
