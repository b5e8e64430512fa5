//! Final gather over the radiosity solution (Reichert 1992; Lischinski, Tampieri and Greenberg 1993):
//! at a diffuse point seen by the camera the indirect light is gathered over the hemisphere from the
//! solution, so the elements' errors matter one bounce away, smoothed by the integral. An irradiance
//! cache with gradients (Ward, Rubinstein and Clear 1988; Ward and Heckbert 1992) makes it cheap.
//! `hemisphere` holds the cells and gradient kernels, `rays` what one gather ray reads, `near` the
//! second bounce where a ray lands close by, `cache` the records and their interpolation, `prepass`
//! the deterministic filling before the image.

pub mod cache;
pub mod hemisphere;
pub mod near;
pub mod prepass;
pub mod rays;

pub use cache::{IrradianceCache, IrradianceRecord};
pub use hemisphere::{HemisphereEstimate, Strata};
pub use near::NearBounce;
pub use prepass::{fill, PrepassStats, LEVELS};

use glam::Vec3;

use crate::film::Sampler;
use crate::scene::{ImageSettings, RenderParams};
use crate::trace::camera::PinholeCamera;
use crate::trace::whitted::{RayCounts, Tracer};

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
    if params.cache_accuracy <= 0.0 {
        return (FinalGather { strata, cache: None }, PrepassStats::default());
    }
    let (cache, stats) = fill(
        tracer,
        camera,
        image.width_px,
        image.height_px,
        pixel_angle_rad,
        strata,
        params.cache_accuracy,
        image.seed,
        on_level_done,
    );
    (FinalGather { strata, cache: Some(cache) }, stats)
}

/// Where the gathered indirect irradiance comes from during the image.
#[derive(Clone, Debug)]
pub struct FinalGather {
    pub strata: Strata,
    /// The prepass's records; `None` gathers at every diffuse hit (`cache_accuracy = 0`).
    pub cache: Option<IrradianceCache>,
}

impl FinalGather {
    /// The indirect irradiance at diffuse point `p` with normal `n`: the cache's interpolation where a
    /// record serves, else a gather of its own (drawn from the pixel's `sampler`, not stored, so the
    /// image does not depend on which thread got there first).
    pub fn irradiance(&self, tracer: &Tracer, p: Vec3, n: Vec3, sampler: &mut Sampler, counts: &mut RayCounts) -> Vec3 {
        if let Some(e) = self.cache.as_ref().and_then(|c| c.lookup(p, n)) {
            return e;
        }
        tracer.gather(p, n, self.strata, sampler, counts).irradiance
    }
}
