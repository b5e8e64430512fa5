//! The tile loop: pixels rendered in square tiles in parallel, each from its own `Sampler`, then
//! adaptive supersampling of the pixels whose samples, or whose neighbours' samples, say that their
//! base samples are not enough (Whitted's contrast, and the error one sample may carry).

use super::filter::{reconstruct_pixel, FilterSampler};
use super::image::{luminance, Image};
use super::sampler::Sampler;
use crate::scene::ImageSettings;
use glam::Vec3;
use rayon::prelude::*;

/// Side of the square tiles the film is rendered in (the unit of parallel work).
pub const TILE_SIZE_PX: u32 = 16;

/// ε in the adaptive contrast (max − min) / (max + min + ε) of sample luminances: keeps black pixels
/// with a speck of noise from counting as infinitely contrasted.
pub const ADAPTIVE_CONTRAST_EPSILON: f32 = 1e-4;

/// Whitted's (1980) adaptive criterion as a contrast of the samples' luminances Y (negatives clamped
/// to 0): (max Y − min Y) / (max Y + min Y + ε), ε = [`ADAPTIVE_CONTRAST_EPSILON`]; 0 for no samples.
pub fn luminance_contrast(radiance: &[Vec3]) -> f32 {
    contrast(radiance)
}

/// [`luminance_contrast`] of the samples' radiance.
fn contrast<T: FilmSample>(samples: &[T]) -> f32 {
    LuminanceRange::of(samples).map_or(0.0, |r| r.contrast())
}

/// ε² in the relative error of a pixel, |ΔY| / √(Y² + ε²): the 0.01 of relMSE's denominator
/// (x − ref)² / (ref² + 0.01), so that adaptive sampling bounds the error that metric counts and black
/// pixels are not infinitely sensitive.
pub const ADAPTIVE_ERROR_EPSILON_SQ: f32 = 0.01;

/// The relative error one of a pixel's `samples` samples may carry (the criterion of
/// `adaptive_error`): e = max(Y_hi − Ȳ, Ȳ − Y_lo) / (n·√(Ȳ² + ε²)), ε² = [`ADAPTIVE_ERROR_EPSILON_SQ`],
/// where Ȳ is the pixel's luminance and [Y_lo, Y_hi] the luminance range of the samples of the pixel
/// and its neighbours. A feature of luminance Y_hi that a neighbour's samples saw may reach into the
/// pixel between its n stratified samples, over about 1/n of it, unseen: e bounds the relative change
/// it would make, so a thin bright emitter edge next to a dark pixel asks for more samples while the
/// pixels on the emitter (Ȳ ≈ Y_hi) and ordinary shading edges do not. 0 for no samples.
pub fn one_sample_error(pixel_luminance: f32, range_lo: f32, range_hi: f32, samples: u32) -> f32 {
    if samples == 0 {
        return 0.0;
    }
    let y = pixel_luminance.max(0.0);
    let swing = (range_hi - y).max(y - range_lo).max(0.0);
    swing / (samples as f32 * (y * y + ADAPTIVE_ERROR_EPSILON_SQ).sqrt())
}

/// The measured relative standard error of a pixel's mean: s / (√n·√(Ȳ² + ε²)), with s² the unbiased
/// sample variance of the n samples' luminances (negatives clamped to 0), Ȳ the pixel's luminance and
/// ε² = [`ADAPTIVE_ERROR_EPSILON_SQ`]; 0 for fewer than two samples. Stratification makes the true
/// error smaller than s/√n, so this errs on the side of more samples.
pub fn relative_standard_error(luminances: &[f32], pixel_luminance: f32) -> f32 {
    let n = luminances.len();
    if n < 2 {
        return 0.0;
    }
    let mean = luminances.iter().map(|&y| y as f64).sum::<f64>() / n as f64;
    let variance = luminances.iter().map(|&y| (y as f64 - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
    let y = pixel_luminance.max(0.0) as f64;
    ((variance / n as f64).sqrt() / (y * y + ADAPTIVE_ERROR_EPSILON_SQ as f64).sqrt()) as f32
}

/// The range of luminances (negatives clamped to 0) of some samples.
#[derive(Clone, Copy, Debug, PartialEq)]
struct LuminanceRange {
    lo: f32,
    hi: f32,
}

impl LuminanceRange {
    /// None for no samples.
    fn of<T: FilmSample>(samples: &[T]) -> Option<Self> {
        samples.iter().map(|l| luminance(l.radiance()).max(0.0)).fold(None, |r, y| {
            let r = r.unwrap_or(LuminanceRange { lo: y, hi: y });
            Some(LuminanceRange { lo: r.lo.min(y), hi: r.hi.max(y) })
        })
    }

    fn union(self, other: LuminanceRange) -> Self {
        LuminanceRange { lo: self.lo.min(other.lo), hi: self.hi.max(other.hi) }
    }

    /// Whitted's contrast (hi − lo) / (hi + lo + ε).
    fn contrast(self) -> f32 {
        (self.hi - self.lo) / (self.hi + self.lo + ADAPTIVE_CONTRAST_EPSILON)
    }
}

/// What the film takes per sample and develops per pixel: radiance (`Vec3`), or radiance with other
/// values that are filtered the same way (`trace::RadianceParts`, the layers of a layered EXR).
pub trait FilmSample: Copy + Default + Send + Sync {
    /// The radiance that adaptive sampling and the finiteness check look at.
    fn radiance(&self) -> Vec3;
    /// The pixel from its finite samples and their filter weights, as [`reconstruct_pixel`]: every
    /// value Σ wᵢ·xᵢ / Σ wᵢ (the unweighted mean when Σ wᵢ ≤ 0; no samples give zero).
    fn reconstruct(samples: &[Self], weights: &[f32]) -> Self;
}

impl FilmSample for Vec3 {
    #[inline]
    fn radiance(&self) -> Vec3 {
        *self
    }

    #[inline]
    fn reconstruct(samples: &[Vec3], weights: &[f32]) -> Vec3 {
        reconstruct_pixel(samples, weights)
    }
}

/// What the film tells its caller while it works (called from worker threads). A closure
/// `Fn() + Sync` is a `FilmProgress` that counts tiles and ignores the adaptive pass.
pub trait FilmProgress: Sync {
    /// One 16×16 tile of base samples is done.
    fn tile_done(&self);
    /// The adaptive pass starts: `pixels` pixels will take `extra_samples` samples beyond their base
    /// samples, in all.
    fn adaptive_start(&self, _pixels: u64, _extra_samples: u64) {}
    /// `extra_samples` more adaptive samples are done.
    fn adaptive_done(&self, _extra_samples: u64) {}
}

impl<F: Fn() + Sync> FilmProgress for F {
    fn tile_done(&self) {
        self()
    }
}

/// What the film spent.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct FilmStats {
    /// Shader calls (base + adaptive), including those whose value was dropped.
    pub samples: u64,
    /// Shader calls made by adaptive supersampling beyond the base samples.
    pub adaptive_extra_samples: u64,
    /// Pixels that received adaptive samples.
    pub adaptive_pixels: u64,
    /// Samples whose radiance had a NaN or infinite channel; they are dropped from their pixel.
    pub non_finite_samples: u64,
    pub tiles: u32,
}

impl FilmStats {
    fn add(&mut self, other: &FilmStats) {
        self.samples += other.samples;
        self.adaptive_extra_samples += other.adaptive_extra_samples;
        self.adaptive_pixels += other.adaptive_pixels;
        self.non_finite_samples += other.non_finite_samples;
        self.tiles += other.tiles;
    }
}

/// Renders the film: for each pixel, `samples_per_pixel` points of its own shuffled, scrambled Sobol
/// sequence (`Sampler::film_position`) warped by the filter's importance sampler, `shade(x_px, y_px,
/// sampler)` at each (film coordinates from the top-left; pixel (x, y) covers [x, x+1)×[y, y+1)),
/// reconstructed by normalised weights; then adaptive samples where the base samples ask for them
/// (see [`render_samples_with`]). Each pixel uses `Sampler::pixel(seed, y·width + x)` for its base
/// samples and passes it on to the shader, so the image is the same whatever the thread count or tile
/// order. `progress` hears (from worker threads) of each 16×16 tile of base samples and of the adaptive
/// pass.
pub fn render<F>(settings: &ImageSettings, shade: F, progress: &dyn FilmProgress) -> (Image, FilmStats)
where
    F: Fn(f32, f32, &mut Sampler) -> Vec3 + Sync,
{
    let (image, stats, _) = render_with(settings, || (), |_: &mut (), x, y, sampler| shade(x, y, sampler), progress);
    (image, stats)
}

/// [`render`] with per-worker scratch state: `init` makes a state for each piece of parallel work
/// (rayon `fold`), `shade` gets it mutably, and all states are returned (their number depends on the
/// schedule; sums over them, such as ray counts, do not).
pub fn render_with<S, I, F>(
    settings: &ImageSettings,
    init: I,
    shade: F,
    progress: &dyn FilmProgress,
) -> (Image, FilmStats, Vec<S>)
where
    S: Send,
    I: Fn() -> S + Sync,
    F: Fn(&mut S, f32, f32, &mut Sampler) -> Vec3 + Sync,
{
    let (pixels, stats, states) = render_samples_with(settings, init, shade, progress);
    (Image { width_px: settings.width_px, height_px: settings.height_px, pixels }, stats, states)
}

/// [`render_with`] for any [`FilmSample`]: the pixels row-major from the top-left.
///
/// Two passes. First every pixel takes its base samples, tile by tile in parallel. Then, when
/// `adaptive_max_samples` exceeds them, a pixel takes samples up to that count (continuing its
/// sequence, from `Sampler::pixel_adaptive`) if its own samples' contrast exceeds
/// `adaptive_threshold` (Whitted 1980), or if [`one_sample_error`] over its and its neighbours' samples
/// (those within the filter's reach plus one pixel) exceeds `adaptive_error`; all of them together take
/// at most `adaptive_budget` times the base samples ([`within_budget`]). The decision reads only
/// base samples, so it does not depend on the schedule either. The adaptive samples join the pixel as
/// more samples of the same estimate: the base samples enter as their reconstruction with the sum of
/// their weights (exact whenever that sum is positive, as it always is for box, tent and Gaussian).
pub fn render_samples_with<T, S, I, F>(
    settings: &ImageSettings,
    init: I,
    shade: F,
    progress: &dyn FilmProgress,
) -> (Vec<T>, FilmStats, Vec<S>)
where
    T: FilmSample,
    S: Send,
    I: Fn() -> S + Sync,
    F: Fn(&mut S, f32, f32, &mut Sampler) -> T + Sync,
{
    let (width, height) = (settings.width_px, settings.height_px);
    if width == 0 || height == 0 {
        return (Vec::new(), FilmStats::default(), Vec::new());
    }
    let radius_px = if settings.filter_radius_px.is_finite() && settings.filter_radius_px > 0.0 {
        settings.filter_radius_px
    } else {
        0.5
    };
    let base_samples = settings.samples_per_pixel.max(1);
    let extra_samples = settings.adaptive_max_samples.saturating_sub(base_samples);
    let criteria = AdaptiveCriteria {
        contrast: settings.adaptive_threshold,
        error: settings.adaptive_error,
        reach_px: (radius_px - 0.5).max(0.0).ceil() as u32 + 1,
    };
    let plan = PixelPlan {
        filter: FilterSampler::new(settings.filter, radius_px),
        width,
        seed: settings.seed,
        base_samples,
        extra_samples: if criteria.any() { extra_samples } else { 0 },
    };
    let tiles_x = width.div_ceil(TILE_SIZE_PX);
    let tiles_y = height.div_ceil(TILE_SIZE_PX);
    let folded: Vec<(S, Vec<TileResult<T>>)> = (0..tiles_x * tiles_y)
        .into_par_iter()
        .fold(
            || (init(), Vec::new()),
            |(mut state, mut done), tile| {
                let x0 = (tile % tiles_x) * TILE_SIZE_PX;
                let y0 = (tile / tiles_x) * TILE_SIZE_PX;
                let x1 = (x0 + TILE_SIZE_PX).min(width);
                let y1 = (y0 + TILE_SIZE_PX).min(height);
                done.push(plan.render_tile(x0, y0, x1, y1, &mut state, &shade));
                progress.tile_done();
                (state, done)
            },
        )
        .collect();

    let mut records = vec![BaseRecord::<T>::default(); width as usize * height as usize];
    let mut stats = FilmStats::default();
    let mut states = Vec::with_capacity(folded.len());
    for (state, tiles) in folded {
        for t in tiles {
            let tile_width = (t.x1 - t.x0) as usize;
            for y in t.y0..t.y1 {
                let row = (y - t.y0) as usize * tile_width;
                let dst = (y * width + t.x0) as usize;
                records[dst..dst + tile_width].copy_from_slice(&t.records[row..row + tile_width]);
            }
            stats.add(&t.stats);
        }
        states.push(state);
    }

    let mut pixels: Vec<T> = records.iter().map(|r| r.value).collect();
    if plan.extra_samples > 0 {
        let max_samples = base_samples + plan.extra_samples;
        let wanted: Vec<Wanted> = (0..width * height)
            .filter_map(|p| criteria.samples_wanted(&records, width, height, p, max_samples).map(|w| (p, w)))
            .filter(|&(_, (n, _))| n > base_samples)
            .map(|(pixel, (samples, priority))| Wanted { pixel, samples, priority })
            .collect();
        let base_total = width as u64 * height as u64 * base_samples as u64;
        let budget = (settings.adaptive_budget.max(0.0) as f64 * base_total as f64) as u64;
        let chosen: Vec<(u32, u32)> =
            within_budget(wanted, base_samples, budget).into_iter().map(|w| (w.pixel, w.samples)).collect();
        let extra_of = |chunk: &[(u32, u32)]| chunk.iter().map(|&(_, n)| (n - base_samples) as u64).sum::<u64>();
        progress.adaptive_start(chosen.len() as u64, extra_of(&chosen));
        let folded: Vec<AdaptiveChunk<S, T>> = chosen
            .par_chunks(ADAPTIVE_CHUNK_PX)
            .fold(
                || (init(), Vec::new(), FilmStats::default()),
                |(mut state, mut done, mut stats), chunk| {
                    let mut scratch = PixelScratch::default();
                    for &(p, total) in chunk {
                        let base = &records[p as usize];
                        let value = plan.add_samples(p, base, total, &mut state, &shade, &mut scratch, &mut stats);
                        done.push((p, value));
                    }
                    progress.adaptive_done(extra_of(chunk));
                    (state, done, stats)
                },
            )
            .collect();
        for (state, done, chunk_stats) in folded {
            for (p, value) in done {
                pixels[p as usize] = value;
            }
            stats.add(&chunk_stats);
            states.push(state);
        }
    }
    (pixels, stats, states)
}

/// `[image] adaptive_budget` by default: the most adaptive samples one image takes, as a multiple of its
/// base samples (width × height × samples per pixel). The criteria alone bound each pixel's error, not
/// the image's cost: on a scene whose samples are noisy everywhere they ask for the cap almost
/// everywhere (textured Crytek Sponza at 160×90: 75% of the pixels, 5.5× the base samples, about 9× the
/// base pass's time; docs/performance.md, "Adaptive film on Sponza"). The rooms and the Cornell box ask
/// for 8–32% (docs/accuracy.md, "Seeds and adaptive sampling"), so this budget leaves them as they were.
pub const DEFAULT_ADAPTIVE_BUDGET: f32 = 0.5;

/// A pixel the adaptive criteria picked: how many samples in all it asks for, and how urgently (the
/// factor by which its estimated error exceeds the bound; infinite for Whitted's contrast).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Wanted {
    pub pixel: u32,
    pub samples: u32,
    pub priority: f32,
}

/// Fits the adaptive pixels' requests (each over `base_samples`) into `budget` extra samples in all.
/// Within budget they are kept as they are. Otherwise every request is capped at the largest of the
/// requested counts M for which Σ (min(nᵢ, M) − base) ≤ budget, so the pixels that ask the most give
/// up samples first (an extra sample does the most good where a pixel has the fewest). If even the
/// smallest requested count does not fit, every pixel is cut to it and they are kept by priority (then
/// pixel order) while the budget lasts. Returned in pixel order; deterministic.
pub fn within_budget(mut wanted: Vec<Wanted>, base_samples: u32, budget: u64) -> Vec<Wanted> {
    let extra = |w: &[Wanted], cap: u32| w.iter().map(|x| (x.samples.min(cap) - base_samples) as u64).sum::<u64>();
    if extra(&wanted, u32::MAX) <= budget {
        return wanted;
    }
    let mut counts: Vec<u32> = wanted.iter().map(|w| w.samples).collect();
    counts.sort_unstable();
    counts.dedup();
    if let Some(&cap) = counts.iter().rev().find(|&&cap| extra(&wanted, cap) <= budget) {
        wanted.iter_mut().for_each(|w| w.samples = w.samples.min(cap));
        return wanted;
    }
    let cap = counts[0];
    wanted.sort_by(|a, b| b.priority.total_cmp(&a.priority).then(a.pixel.cmp(&b.pixel)));
    let keep = (budget / (cap - base_samples) as u64) as usize;
    wanted.truncate(keep);
    wanted.iter_mut().for_each(|w| w.samples = cap);
    wanted.sort_by_key(|w| w.pixel);
    wanted
}

/// What one worker of the adaptive pass returns: its state, the (pixel, value) pairs it redid, and
/// what it spent.
type AdaptiveChunk<S, T> = (S, Vec<(u32, T)>, FilmStats);

/// Pixels per piece of parallel work in the adaptive pass.
const ADAPTIVE_CHUNK_PX: usize = 16;

struct TileResult<T> {
    x0: u32,
    y0: u32,
    x1: u32,
    y1: u32,
    records: Vec<BaseRecord<T>>,
    stats: FilmStats,
}

/// What a pixel's base samples left: their reconstruction, the sum of their weights, how many were
/// finite and their luminance range.
#[derive(Clone, Copy, Debug, Default)]
struct BaseRecord<T> {
    value: T,
    weight_sum: f32,
    samples: u32,
    range: Option<LuminanceRange>,
    /// [`relative_standard_error`] of the base samples.
    relative_std_error: f32,
}

/// When a pixel takes adaptive samples.
struct AdaptiveCriteria {
    /// Whitted's contrast threshold on the pixel's own samples (`adaptive_threshold`).
    contrast: Option<f32>,
    /// Bound on [`one_sample_error`] (`adaptive_error`).
    error: Option<f32>,
    /// How far (in pixels) a neighbour's samples count for the error criterion.
    reach_px: u32,
}

impl AdaptiveCriteria {
    fn any(&self) -> bool {
        self.contrast.is_some() || self.error.is_some()
    }

    /// How many samples in all the pixel should take, and its priority (None: its base samples are
    /// enough). The contrast
    /// criterion asks for `max_samples`. The error criterion asks for as many as bring the estimated
    /// error under the bound: the unseen-feature error falls as 1/n on stratified edges, the standard
    /// error as 1/√n, so n·max(e_unseen/bound, (e_std/bound)²), rounded up to a power of two (so the
    /// pixel's samples stay a net) and capped at `max_samples`.
    fn samples_wanted<T: FilmSample>(
        &self,
        records: &[BaseRecord<T>],
        width: u32,
        height: u32,
        pixel: u32,
        max_samples: u32,
    ) -> Option<(u32, f32)> {
        let own = &records[pixel as usize];
        let own_range = own.range?;
        if self.contrast.is_some_and(|t| own_range.contrast() > t) {
            return Some((max_samples, f32::INFINITY));
        }
        let bound = self.error?;
        let (x, y) = (pixel % width, pixel / width);
        let r = self.reach_px;
        let mut range = own_range;
        for ny in y.saturating_sub(r)..=(y + r).min(height - 1) {
            for nx in x.saturating_sub(r)..=(x + r).min(width - 1) {
                if let Some(n) = records[(ny * width + nx) as usize].range {
                    range = range.union(n);
                }
            }
        }
        let unseen = one_sample_error(luminance(own.value.radiance()), range.lo, range.hi, own.samples);
        let factor = (unseen / bound).max((own.relative_std_error / bound).powi(2));
        if factor <= 1.0 {
            return None;
        }
        let wanted = (own.samples as f32 * factor).min(max_samples as f32) as u32;
        Some((wanted.max(own.samples + 1).next_power_of_two().min(max_samples), factor))
    }
}

/// Everything a pixel needs, shared read-only by all tiles.
struct PixelPlan {
    filter: FilterSampler,
    width: u32,
    seed: u64,
    base_samples: u32,
    /// Samples an adaptive pixel takes beyond its base samples (0: no adaptive pass).
    extra_samples: u32,
}

/// Per-worker scratch buffers.
struct PixelScratch<T> {
    radiance: Vec<T>,
    weights: Vec<f32>,
}

impl<T> Default for PixelScratch<T> {
    fn default() -> Self {
        PixelScratch { radiance: Vec::new(), weights: Vec::new() }
    }
}

impl PixelPlan {
    fn render_tile<T, S, F>(&self, x0: u32, y0: u32, x1: u32, y1: u32, state: &mut S, shade: &F) -> TileResult<T>
    where
        T: FilmSample,
        F: Fn(&mut S, f32, f32, &mut Sampler) -> T,
    {
        let mut stats = FilmStats { tiles: 1, ..FilmStats::default() };
        let mut records = Vec::with_capacity(((x1 - x0) * (y1 - y0)) as usize);
        let mut scratch = PixelScratch::default();
        for y in y0..y1 {
            for x in x0..x1 {
                let pixel = y * self.width + x;
                let mut sampler = Sampler::pixel(self.seed, pixel as u64);
                scratch.radiance.clear();
                scratch.weights.clear();
                self.shade_samples(pixel, 0..self.base_samples, state, shade, &mut sampler, &mut scratch, &mut stats);
                let value = T::reconstruct(&scratch.radiance, &scratch.weights);
                let luminances: Vec<f32> = scratch.radiance.iter().map(|l| luminance(l.radiance()).max(0.0)).collect();
                records.push(BaseRecord {
                    relative_std_error: relative_standard_error(&luminances, luminance(value.radiance())),
                    value,
                    weight_sum: scratch.weights.iter().sum(),
                    samples: scratch.radiance.len() as u32,
                    range: LuminanceRange::of(&scratch.radiance),
                });
            }
        }
        TileResult { x0, y0, x1, y1, records, stats }
    }

    /// The pixel with its adaptive samples, up to `total` in all, added to what its base samples left.
    #[allow(clippy::too_many_arguments)]
    fn add_samples<T, S, F>(
        &self,
        pixel: u32,
        base: &BaseRecord<T>,
        total: u32,
        state: &mut S,
        shade: &F,
        scratch: &mut PixelScratch<T>,
        stats: &mut FilmStats,
    ) -> T
    where
        T: FilmSample,
        F: Fn(&mut S, f32, f32, &mut Sampler) -> T,
    {
        let mut sampler = Sampler::pixel_adaptive(self.seed, pixel as u64);
        scratch.radiance.clear();
        scratch.weights.clear();
        if base.samples > 0 {
            scratch.radiance.push(base.value);
            scratch.weights.push(base.weight_sum);
        }
        self.shade_samples(pixel, self.base_samples..total, state, shade, &mut sampler, scratch, stats);
        stats.adaptive_extra_samples += (total - self.base_samples) as u64;
        stats.adaptive_pixels += 1;
        T::reconstruct(&scratch.radiance, &scratch.weights)
    }

    /// Shades the pixel's samples `indices` at their film positions and keeps the finite ones.
    #[allow(clippy::too_many_arguments)]
    fn shade_samples<T, S, F>(
        &self,
        pixel: u32,
        indices: std::ops::Range<u32>,
        state: &mut S,
        shade: &F,
        sampler: &mut Sampler,
        scratch: &mut PixelScratch<T>,
        stats: &mut FilmStats,
    ) where
        T: FilmSample,
        F: Fn(&mut S, f32, f32, &mut Sampler) -> T,
    {
        let centre = [(pixel % self.width) as f32 + 0.5, (pixel / self.width) as f32 + 0.5];
        for index in indices {
            sampler.start_sample(index);
            let s = self.filter.sample(sampler.film_position(index));
            let l = shade(state, centre[0] + s.offset_px[0], centre[1] + s.offset_px[1], sampler);
            stats.samples += 1;
            if l.radiance().is_finite() {
                scratch.radiance.push(l);
                scratch.weights.push(s.weight);
            } else {
                stats.non_finite_samples += 1;
            }
        }
    }
}
