//! The tile loop: pixels rendered in square tiles in parallel, each from its own `Sampler`, with
//! Whitted-style adaptive supersampling where a pixel's samples disagree.

use super::filter::{reconstruct_pixel, FilterSampler};
use super::image::{luminance, Image};
use super::sampler::{multi_jittered, stratum_grid, Sampler};
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
    if radiance.is_empty() {
        return 0.0;
    }
    let (mut lo, mut hi) = (f32::INFINITY, 0f32);
    for l in radiance {
        let y = luminance(*l).max(0.0);
        lo = lo.min(y);
        hi = hi.max(y);
    }
    (hi - lo) / (hi + lo + ADAPTIVE_CONTRAST_EPSILON)
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

/// Renders the film: for each pixel, `samples_per_pixel` multi-jittered points warped by the filter's
/// importance sampler, `shade(x_px, y_px, sampler)` at each (film coordinates from the top-left; pixel
/// (x, y) covers [x, x+1)×[y, y+1)), reconstructed by normalised weights; adaptive samples where the
/// base samples disagree. Each pixel uses `Sampler::pixel(seed, y·width + x)` for its jitter and passes it
/// on to the shader, so the image is the same whatever the thread count or tile order.
/// `on_tile_done` is called (from worker threads) after each 16×16 tile.
pub fn render<F>(settings: &ImageSettings, shade: F, on_tile_done: &(dyn Fn() + Sync)) -> (Image, FilmStats)
where
    F: Fn(f32, f32, &mut Sampler) -> Vec3 + Sync,
{
    let (image, stats, _) =
        render_with(settings, || (), |_: &mut (), x, y, sampler| shade(x, y, sampler), on_tile_done);
    (image, stats)
}

/// [`render`] with per-worker scratch state: `init` makes a state for each piece of parallel work
/// (rayon `fold`), `shade` gets it mutably, and all states are returned (their number depends on the
/// schedule; sums over them, such as ray counts, do not).
pub fn render_with<S, I, F>(
    settings: &ImageSettings,
    init: I,
    shade: F,
    on_tile_done: &(dyn Fn() + Sync),
) -> (Image, FilmStats, Vec<S>)
where
    S: Send,
    I: Fn() -> S + Sync,
    F: Fn(&mut S, f32, f32, &mut Sampler) -> Vec3 + Sync,
{
    let (width, height) = (settings.width_px, settings.height_px);
    let mut image = Image::new(width, height);
    if width == 0 || height == 0 {
        return (image, FilmStats::default(), Vec::new());
    }
    let radius_px = if settings.filter_radius_px.is_finite() && settings.filter_radius_px > 0.0 {
        settings.filter_radius_px
    } else {
        0.5
    };
    let plan = PixelPlan {
        filter: FilterSampler::new(settings.filter, radius_px),
        width,
        seed: settings.seed,
        base_samples: settings.samples_per_pixel.max(1),
        adaptive: settings.adaptive_threshold.and_then(|t| {
            let extra = settings.adaptive_max_samples.saturating_sub(settings.samples_per_pixel.max(1));
            (extra > 0).then_some((t, extra))
        }),
    };
    let tiles_x = width.div_ceil(TILE_SIZE_PX);
    let tiles_y = height.div_ceil(TILE_SIZE_PX);
    let folded: Vec<(S, Vec<TileResult>)> = (0..tiles_x * tiles_y)
        .into_par_iter()
        .fold(
            || (init(), Vec::new()),
            |(mut state, mut done), tile| {
                let x0 = (tile % tiles_x) * TILE_SIZE_PX;
                let y0 = (tile / tiles_x) * TILE_SIZE_PX;
                let x1 = (x0 + TILE_SIZE_PX).min(width);
                let y1 = (y0 + TILE_SIZE_PX).min(height);
                done.push(plan.render_tile(x0, y0, x1, y1, &mut state, &shade));
                on_tile_done();
                (state, done)
            },
        )
        .collect();

    let mut stats = FilmStats::default();
    let mut states = Vec::with_capacity(folded.len());
    for (state, tiles) in folded {
        for t in tiles {
            let tile_width = (t.x1 - t.x0) as usize;
            for y in t.y0..t.y1 {
                let row = (y - t.y0) as usize * tile_width;
                let dst = (y * width + t.x0) as usize;
                image.pixels[dst..dst + tile_width].copy_from_slice(&t.radiance[row..row + tile_width]);
            }
            stats.add(&t.stats);
        }
        states.push(state);
    }
    (image, stats, states)
}

struct TileResult {
    x0: u32,
    y0: u32,
    x1: u32,
    y1: u32,
    radiance: Vec<Vec3>,
    stats: FilmStats,
}

/// Everything a pixel needs, shared read-only by all tiles.
struct PixelPlan {
    filter: FilterSampler,
    width: u32,
    seed: u64,
    base_samples: u32,
    /// (contrast threshold, extra samples) when adaptive supersampling is on.
    adaptive: Option<(f32, u32)>,
}

/// Per-tile scratch buffers.
#[derive(Default)]
struct PixelScratch {
    points: Vec<[f32; 2]>,
    radiance: Vec<Vec3>,
    weights: Vec<f32>,
}

impl PixelPlan {
    fn render_tile<S, F>(&self, x0: u32, y0: u32, x1: u32, y1: u32, state: &mut S, shade: &F) -> TileResult
    where
        F: Fn(&mut S, f32, f32, &mut Sampler) -> Vec3,
    {
        let mut stats = FilmStats { tiles: 1, ..FilmStats::default() };
        let mut radiance = Vec::with_capacity(((x1 - x0) * (y1 - y0)) as usize);
        let mut scratch = PixelScratch::default();
        for y in y0..y1 {
            for x in x0..x1 {
                radiance.push(self.render_pixel(x, y, state, shade, &mut scratch, &mut stats));
            }
        }
        TileResult { x0, y0, x1, y1, radiance, stats }
    }

    fn render_pixel<S, F>(
        &self,
        x: u32,
        y: u32,
        state: &mut S,
        shade: &F,
        scratch: &mut PixelScratch,
        stats: &mut FilmStats,
    ) -> Vec3
    where
        F: Fn(&mut S, f32, f32, &mut Sampler) -> Vec3,
    {
        let pixel_index = y as u64 * self.width as u64 + x as u64;
        let mut sampler = Sampler::pixel(self.seed, pixel_index);
        scratch.radiance.clear();
        scratch.weights.clear();
        let centre = [x as f32 + 0.5, y as f32 + 0.5];
        self.shade_batch(0, self.base_samples, centre, state, shade, &mut sampler, scratch, stats);
        if let Some((threshold, extra)) = self.adaptive {
            if luminance_contrast(&scratch.radiance) > threshold {
                self.shade_batch(self.base_samples, extra, centre, state, shade, &mut sampler, scratch, stats);
                stats.adaptive_extra_samples += extra as u64;
                stats.adaptive_pixels += 1;
            }
        }
        reconstruct_pixel(&scratch.radiance, &scratch.weights)
    }

    /// Draws one multi-jittered batch of `count` samples, the pixel's samples `first`, `first` + 1, …,
    /// shades them and keeps the finite ones.
    #[allow(clippy::too_many_arguments)]
    fn shade_batch<S, F>(
        &self,
        first: u32,
        count: u32,
        centre: [f32; 2],
        state: &mut S,
        shade: &F,
        sampler: &mut Sampler,
        scratch: &mut PixelScratch,
        stats: &mut FilmStats,
    ) where
        F: Fn(&mut S, f32, f32, &mut Sampler) -> Vec3,
    {
        let (columns, rows) = stratum_grid(count);
        scratch.points.clear();
        multi_jittered(columns, rows, sampler, &mut scratch.points);
        for (i, u) in scratch.points.iter().enumerate() {
            sampler.start_sample(first + i as u32);
            let s = self.filter.sample(*u);
            let l = shade(state, centre[0] + s.offset_px[0], centre[1] + s.offset_px[1], sampler);
            stats.samples += 1;
            if l.is_finite() {
                scratch.radiance.push(l);
                scratch.weights.push(s.weight);
            } else {
                stats.non_finite_samples += 1;
            }
        }
    }
}
