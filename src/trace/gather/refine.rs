//! Adaptive rays per irradiance-cache record: a small pilot gather estimates how noisy the record's
//! own gather would be, and records whose hemisphere holds small bright regions (a patch of direct
//! light, the view through a door: a few cells 10–20× the rest) gather `REFINE_FACTOR` times the rays.
//! The pilot is thrown away, so the kept gather is independent of the decision and stays unbiased, and
//! it draws from a stream of its own (`PILOT_STREAM`, forked off the record's), so a record kept at the
//! base count gathers exactly what it gathers with the refinement off.

use glam::Vec3;

use super::hemisphere::{fill_untraced, frame, relative_error, HemisphereEstimate, Strata};
use crate::film::Sampler;
use crate::trace::whitted::{RayCounts, Tracer};
use crate::transport::hit::leave_surface;
use crate::transport::shading::SurfaceNormals;

/// Rays of the pilot gather (an 5 × 13 stratification).
pub const PILOT_RAYS: u32 = 64;
/// The pilot's side stream, forked off the record's sampler (`Sampler::fork`).
const PILOT_STREAM: u64 = 0x9170_7A3E_5C1D_0001;
/// A refined record gathers this many times `gather_rays`.
pub const REFINE_FACTOR: u32 = 4;

/// When a record's gather gets more rays (`[render] gather_refine_error`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GatherRefinement {
    pub pilot: Strata,
    /// The strata of a refined record (about `REFINE_FACTOR` × `gather_rays` cells).
    pub refined: Strata,
    /// The largest predicted relative standard error of a `gather_rays` gather kept at the base count.
    pub error_bound: f32,
}

impl GatherRefinement {
    /// The refinement of gathers of `gather_rays` rays at `error_bound`; `None` (no pilot, every record
    /// at the base count) where the bound is 0.
    pub fn new(gather_rays: u32, error_bound: f32) -> Option<GatherRefinement> {
        (error_bound > 0.0).then(|| GatherRefinement {
            pilot: Strata::for_rays(PILOT_RAYS),
            refined: Strata::for_rays(REFINE_FACTOR * gather_rays),
            error_bound,
        })
    }

    /// The relative standard error predicted for a gather over `base` from the pilot's own,
    /// σ_base/H ≈ σ_pilot/H · √(cells_pilot / cells_base): the 1/√N of Monte Carlo, which
    /// over-predicts a stratified gather's (whose edge cells fall as N^−3/4), so it errs towards
    /// refining.
    pub fn predicted_error(&self, pilot_error: f32, base: Strata) -> f32 {
        pilot_error * (self.pilot.cells() as f32 / base.cells() as f32).sqrt()
    }
}

impl Tracer<'_> {
    /// The relative standard error of a pilot gather over `strata` at (p, n) (`hemisphere::relative_error`),
    /// its rays reading the interpolated solution (no second bounce at near hits).
    /// Cells below the geometric plane are not traced and read the traced cells' mean, as in `gather`.
    pub fn pilot_error(
        &self,
        p: Vec3,
        normals: impl Into<SurfaceNormals>,
        strata: Strata,
        sampler: &mut Sampler,
        counts: &mut RayCounts,
    ) -> f32 {
        let normals = normals.into();
        let n = normals.shading;
        let (t, b) = frame(n);
        let origin = leave_surface(p, normals.geometric, self.ray_offset());
        let mut radiance = Vec::with_capacity(strata.cells());
        let mut traced = Vec::with_capacity(strata.cells());
        for j in 0..strata.rings {
            for k in 0..strata.sectors {
                let local = strata.direction(j, k, sampler.next_1d(), sampler.next_1d());
                let dir = (t * local.x + b * local.y + n * local.z).normalize();
                let admitted = normals.admits(dir);
                radiance.push(if admitted {
                    self.gather_radiance(origin, dir, None, sampler, counts).0
                } else {
                    Vec3::ZERO
                });
                traced.push(admitted);
            }
        }
        fill_untraced(&mut radiance, &mut vec![f32::INFINITY; strata.cells()], &traced);
        relative_error(strata, &radiance)
    }

    /// A record's gather at p with `normals` (`gather`): over `base`, or, where `refinement`'s pilot predicts a relative error
    /// above its bound, over its `refined` strata; and whether it was refined. Unbiased either way: the
    /// pilot draws from its own stream forked off `sampler` (which it leaves untouched), independent of
    /// the kept gather's, and each stratified gather is unbiased at any M × N. A record kept at `base`
    /// therefore returns the same bits as with `refinement` `None`.
    pub fn record_gather(
        &self,
        p: Vec3,
        normals: impl Into<SurfaceNormals>,
        base: Strata,
        refinement: Option<&GatherRefinement>,
        sampler: &mut Sampler,
        counts: &mut RayCounts,
    ) -> (HemisphereEstimate, bool) {
        let normals = normals.into();
        let refine = refinement.is_some_and(|r| {
            let pilot = self.pilot_error(p, normals, r.pilot, &mut sampler.fork(PILOT_STREAM), counts);
            r.predicted_error(pilot, base) > r.error_bound
        });
        let strata = match refinement {
            Some(r) if refine => r.refined,
            _ => base,
        };
        (self.gather(p, normals, strata, sampler, counts), refine)
    }
}
