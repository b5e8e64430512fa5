//! The film: stratified (multi-jittered) samples per pixel, reconstruction filters sampled by filter
//! importance sampling, Whitted-style adaptive supersampling, tiled parallel rendering, and the image.

use crate::rng::Pcg32;
use crate::scene::{FilterKind, ImageSettings};
use glam::Vec3;
use rayon::prelude::*;

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

/// Side of the square tiles the film is rendered in (the unit of parallel work).
pub const TILE_SIZE_PX: u32 = 16;

/// Bins of the tabulated 1-D filter distributions (Gaussian, Mitchell) across the diameter.
pub const FILTER_TABLE_BINS: usize = 256;

/// ε in the adaptive contrast (max − min) / (max + min + ε) of sample luminances: keeps black pixels
/// with a speck of noise from counting as infinitely contrasted.
pub const ADAPTIVE_CONTRAST_EPSILON: f32 = 1e-4;

/// Mitchell–Netravali parameters B = C = 1/3 (Mitchell & Netravali 1988's recommendation).
const MITCHELL_B: f32 = 1.0 / 3.0;
const MITCHELL_C: f32 = 1.0 / 3.0;

/// Invalid film settings (see [`check_settings`]).
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum FilmError {
    #[error("image size {width_px}×{height_px}: both sides must be at least one pixel")]
    EmptyImage { width_px: u32, height_px: u32 },
    #[error("samples per pixel must be at least 1")]
    NoSamples,
    #[error("filter radius {0} px must be finite and positive")]
    FilterRadius(f32),
    #[error("adaptive threshold {0} must be finite and non-negative")]
    AdaptiveThreshold(f32),
}

/// Rejects settings the film would otherwise have to repair: call it where settings enter the
/// program (parser, CLI). [`render`] itself never fails: it uses at least one sample per pixel and a
/// 0.5 px radius in place of a non-positive or non-finite one.
pub fn check_settings(settings: &ImageSettings) -> Result<(), FilmError> {
    if settings.width_px == 0 || settings.height_px == 0 {
        return Err(FilmError::EmptyImage { width_px: settings.width_px, height_px: settings.height_px });
    }
    if settings.samples_per_pixel == 0 {
        return Err(FilmError::NoSamples);
    }
    if !(settings.filter_radius_px.is_finite() && settings.filter_radius_px > 0.0) {
        return Err(FilmError::FilterRadius(settings.filter_radius_px));
    }
    if let Some(t) = settings.adaptive_threshold {
        if !(t.is_finite() && t >= 0.0) {
            return Err(FilmError::AdaptiveThreshold(t));
        }
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------------
// Reconstruction filters. Each 1-D filter f(x) has support [−r, r] and ∫ f dx = 1; the 2-D filter is
// the separable product f(x)·f(y), so it integrates to 1 over the square [−r, r]².
// ---------------------------------------------------------------------------------------------------

/// Box filter: f(x) = 1 / (2r) for |x| ≤ r, else 0.
pub fn box_filter(x: f32, radius_px: f32) -> f32 {
    if x.abs() <= radius_px {
        0.5 / radius_px
    } else {
        0.0
    }
}

/// Tent (triangle) filter: f(x) = max(0, r − |x|) / r².
pub fn tent_filter(x: f32, radius_px: f32) -> f32 {
    (radius_px - x.abs()).max(0.0) / (radius_px * radius_px)
}

/// Truncated Gaussian with σ = r/3 shifted to reach zero at the radius (pbrt's form):
/// g(x) = exp(−x²/(2σ²)), f(x) = (g(x) − g(r)) / N for |x| ≤ r, with
/// N = σ√(2π)·erf(r/(σ√2)) − 2r·g(r) so that ∫ f = 1.
pub fn gaussian_filter(x: f32, radius_px: f32) -> f32 {
    GaussianTerms::new(radius_px).eval(x)
}

/// The constants of [`gaussian_filter`] for one radius, so that hot loops evaluate one `exp` per call.
#[derive(Clone, Copy, Debug)]
struct GaussianTerms {
    radius_px: f32,
    inv_two_sigma_sq: f64,
    g_at_radius: f64,
    inv_norm: f64,
}

impl GaussianTerms {
    fn new(radius_px: f32) -> Self {
        let r = radius_px as f64;
        let sigma = r / 3.0;
        let inv_two_sigma_sq = 1.0 / (2.0 * sigma * sigma);
        let g_at_radius = (-r * r * inv_two_sigma_sq).exp();
        let norm = sigma * (2.0 * std::f64::consts::PI).sqrt() * erf(r / (sigma * std::f64::consts::SQRT_2))
            - 2.0 * r * g_at_radius;
        GaussianTerms { radius_px, inv_two_sigma_sq, g_at_radius, inv_norm: 1.0 / norm }
    }

    fn eval(&self, x: f32) -> f32 {
        if x.abs() > self.radius_px {
            return 0.0;
        }
        let x = x as f64;
        (((-x * x * self.inv_two_sigma_sq).exp() - self.g_at_radius) * self.inv_norm) as f32
    }
}

/// Mitchell–Netravali cubic (Mitchell & Netravali 1988, "Reconstruction filters in computer graphics")
/// with B = C = 1/3, stretched from its natural support [−2, 2] to [−r, r]: f(x) = (2/r)·k(2x/r) with
/// k(t) = ((12 − 9B − 6C)|t|³ + (−18 + 12B + 6C)|t|² + (6 − 2B)) / 6 for |t| < 1,
/// k(t) = ((−B − 6C)|t|³ + (6B + 30C)|t|² + (−12B − 48C)|t| + (8B + 24C)) / 6 for 1 ≤ |t| < 2,
/// 0 beyond. ∫ k = 1 (the family reproduces constants), and k < 0 in its outer lobes.
pub fn mitchell_filter(x: f32, radius_px: f32) -> f32 {
    let t = (2.0 * x / radius_px).abs();
    let (b, c) = (MITCHELL_B, MITCHELL_C);
    let k = if t < 1.0 {
        ((12.0 - 9.0 * b - 6.0 * c) * t * t * t + (-18.0 + 12.0 * b + 6.0 * c) * t * t + (6.0 - 2.0 * b)) / 6.0
    } else if t < 2.0 {
        ((-b - 6.0 * c) * t * t * t + (6.0 * b + 30.0 * c) * t * t + (-12.0 * b - 48.0 * c) * t + (8.0 * b + 24.0 * c))
            / 6.0
    } else {
        0.0
    };
    k * 2.0 / radius_px
}

/// The 1-D filter of `kind`.
pub fn filter_1d(kind: FilterKind, x: f32, radius_px: f32) -> f32 {
    match kind {
        FilterKind::Box => box_filter(x, radius_px),
        FilterKind::Tent => tent_filter(x, radius_px),
        FilterKind::Gaussian => gaussian_filter(x, radius_px),
        FilterKind::Mitchell => mitchell_filter(x, radius_px),
    }
}

/// The separable 2-D filter f(dx)·f(dy).
pub fn filter_2d(kind: FilterKind, dx: f32, dy: f32, radius_px: f32) -> f32 {
    filter_1d(kind, dx, radius_px) * filter_1d(kind, dy, radius_px)
}

/// The error function, Abramowitz & Stegun 7.1.26 (|error| ≤ 1.5·10⁻⁷).
fn erf(x: f64) -> f64 {
    let sign = x.signum();
    let x = x.abs();
    let t = 1.0 / (1.0 + 0.327_591_1 * x);
    let poly =
        t * (0.254_829_592 + t * (-0.284_496_736 + t * (1.421_413_741 + t * (-1.453_152_027 + t * 1.061_405_429))));
    sign * (1.0 - poly * (-x * x).exp())
}

/// One sample offset drawn from the filter, and its weight f/p (the sign of f for an exactly
/// importance-sampled filter, up to a constant factor that normalisation cancels).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilterSample {
    /// Offset from the pixel centre, in pixels.
    pub offset_px: [f32; 2],
    pub weight: f32,
}

/// Filter importance sampling (pbrt-v4's approach, made separable): maps a point of [0, 1)² to an
/// offset distributed ∝ |f(x)|·|f(y)| by a monotone inverse CDF per axis, so stratified inputs stay
/// stratified. Box and tent are inverted analytically (weight exactly 1); Gaussian and Mitchell use a
/// piecewise-constant table of |f| at [`FILTER_TABLE_BINS`] bin centres.
#[derive(Clone, Debug)]
pub struct FilterSampler {
    kind: FilterKind,
    radius_px: f32,
    /// Cumulative |f| table, `FILTER_TABLE_BINS + 1` entries from 0 to 1 (empty for box and tent).
    cdf: Vec<f32>,
    /// pdf of each bin (1/px): |f(centre)| / (Σ|f|·Δ).
    pdf: Vec<f32>,
    gaussian: GaussianTerms,
}

impl FilterSampler {
    pub fn new(kind: FilterKind, radius_px: f32) -> Self {
        let mut sampler = FilterSampler {
            kind,
            radius_px,
            cdf: Vec::new(),
            pdf: Vec::new(),
            gaussian: GaussianTerms::new(radius_px),
        };
        if matches!(kind, FilterKind::Gaussian | FilterKind::Mitchell) {
            let n = FILTER_TABLE_BINS;
            let bin_px = 2.0 * radius_px as f64 / n as f64;
            let magnitude: Vec<f64> = (0..n)
                .map(|k| {
                    filter_1d(kind, (-radius_px as f64 + (k as f64 + 0.5) * bin_px) as f32, radius_px).abs() as f64
                })
                .collect();
            let total: f64 = magnitude.iter().sum();
            let mut acc = 0.0;
            sampler.cdf.push(0.0);
            for m in &magnitude {
                acc += m;
                sampler.cdf.push((acc / total) as f32);
            }
            sampler.cdf[n] = 1.0;
            sampler.pdf = magnitude.iter().map(|m| (m / (total * bin_px)) as f32).collect();
        }
        sampler
    }

    pub fn kind(&self) -> FilterKind {
        self.kind
    }

    pub fn radius_px(&self) -> f32 {
        self.radius_px
    }

    /// The offset x ∈ [−r, r] for u ∈ [0, 1) (monotone in u), and the weight f(x)/p(x).
    pub fn sample_1d(&self, u: f32) -> (f32, f32) {
        let r = self.radius_px;
        match self.kind {
            FilterKind::Box => (r * (2.0 * u - 1.0), 1.0),
            FilterKind::Tent => {
                // CDF of the tent: P(x) = (r + x)²/(2r²) for x ≤ 0, its mirror for x > 0.
                if u < 0.5 {
                    (-r + r * (2.0 * u).sqrt(), 1.0)
                } else {
                    (r - r * (2.0 * (1.0 - u)).sqrt(), 1.0)
                }
            }
            FilterKind::Gaussian | FilterKind::Mitchell => {
                let n = self.pdf.len();
                let k = (self.cdf.partition_point(|&c| c <= u).max(1) - 1).min(n - 1);
                let (lo, hi) = (self.cdf[k], self.cdf[k + 1]);
                let t = if hi > lo { ((u - lo) / (hi - lo)).clamp(0.0, 1.0) } else { 0.5 };
                let bin_px = 2.0 * r / n as f32;
                let x = (-r + (k as f32 + t) * bin_px).clamp(-r, r);
                let pdf = self.pdf[k];
                let f = if self.kind == FilterKind::Gaussian { self.gaussian.eval(x) } else { mitchell_filter(x, r) };
                let weight = if pdf > 0.0 { f / pdf } else { 0.0 };
                (x, weight)
            }
        }
    }

    /// A 2-D offset for a point of [0, 1)², with weight wx·wy.
    pub fn sample(&self, u: [f32; 2]) -> FilterSample {
        let (x, wx) = self.sample_1d(u[0]);
        let (y, wy) = self.sample_1d(u[1]);
        FilterSample { offset_px: [x, y], weight: wx * wy }
    }
}

// ---------------------------------------------------------------------------------------------------
// Stratified sampling.
// ---------------------------------------------------------------------------------------------------

/// The stratum grid (columns, rows) for `count` samples: columns·rows = count with columns the largest
/// divisor ≤ √count, so square counts give square grids and a prime p gives 1×p (which multi-jittering
/// still stratifies into p strata along each axis).
pub fn stratum_grid(count: u32) -> (u32, u32) {
    let count = count.max(1);
    let mut columns = (count as f64).sqrt() as u32;
    while columns > 1 && !count.is_multiple_of(columns) {
        columns -= 1;
    }
    let columns = columns.max(1);
    (columns, count / columns)
}

/// Multi-jittered sampling (Chiu, Shirley & Wang 1994): `columns × rows` points in [0, 1)², exactly one
/// in each cell of the columns×rows grid AND exactly one in each of the N = columns·rows strata of
/// width 1/N along each axis (N-rooks). Cell (i, j) starts at the canonical
/// x = (i + (j + ξ)/rows)/columns, y = (j + (i + ξ')/columns)/rows; x values are then shuffled among the
/// cells of a column and y values among the cells of a row, which keeps both properties.
/// Points are appended to `out` row by row.
pub fn multi_jittered(columns: u32, rows: u32, rng: &mut Pcg32, out: &mut Vec<[f32; 2]>) {
    let (nc, nr) = (columns as usize, rows as usize);
    let start = out.len();
    for j in 0..nr {
        for i in 0..nc {
            let x = (i as f32 + (j as f32 + rng.next_f32()) / nr as f32) / nc as f32;
            let y = (j as f32 + (i as f32 + rng.next_f32()) / nc as f32) / nr as f32;
            // f32 rounding of values just below 1 must not escape the unit square.
            out.push([x.min(ONE_BELOW), y.min(ONE_BELOW)]);
        }
    }
    let cells = &mut out[start..];
    for i in 0..nc {
        for j in (1..nr).rev() {
            let k = ((rng.next_u32() as u64 * (j as u64 + 1)) >> 32) as usize;
            let (a, b) = (j * nc + i, k * nc + i);
            let tmp = cells[a][0];
            cells[a][0] = cells[b][0];
            cells[b][0] = tmp;
        }
    }
    for j in 0..nr {
        for i in (1..nc).rev() {
            let k = ((rng.next_u32() as u64 * (i as u64 + 1)) >> 32) as usize;
            let (a, b) = (j * nc + i, j * nc + k);
            let tmp = cells[a][1];
            cells[a][1] = cells[b][1];
            cells[b][1] = tmp;
        }
    }
}

const ONE_BELOW: f32 = 1.0 - f32::EPSILON / 2.0;

// ---------------------------------------------------------------------------------------------------
// Reconstruction and adaptivity kernels.
// ---------------------------------------------------------------------------------------------------

/// Normalised-weight reconstruction of one pixel: L = Σ wᵢ·Lᵢ / Σ wᵢ (accumulated in f64, so a
/// constant radiance comes back bit-exact). When Σ wᵢ ≤ 0 (possible only with a few samples all in
/// Mitchell's negative lobes) it falls back to the unweighted mean; no samples give zero.
pub fn reconstruct_pixel(radiance: &[Vec3], weights: &[f32]) -> Vec3 {
    assert_eq!(radiance.len(), weights.len());
    if radiance.is_empty() {
        return Vec3::ZERO;
    }
    let (mut sum, mut plain, mut weight_sum) = ([0f64; 3], [0f64; 3], 0f64);
    for (l, &w) in radiance.iter().zip(weights) {
        for c in 0..3 {
            sum[c] += w as f64 * l[c] as f64;
            plain[c] += l[c] as f64;
        }
        weight_sum += w as f64;
    }
    let (num, den) = if weight_sum > 0.0 { (sum, weight_sum) } else { (plain, radiance.len() as f64) };
    Vec3::new((num[0] / den) as f32, (num[1] / den) as f32, (num[2] / den) as f32)
}

/// Rec. 709 luminance Y = 0.2126 R + 0.7152 G + 0.0722 B.
pub fn luminance(radiance: Vec3) -> f32 {
    0.2126 * radiance.x + 0.7152 * radiance.y + 0.0722 * radiance.z
}

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

// ---------------------------------------------------------------------------------------------------
// Rendering.
// ---------------------------------------------------------------------------------------------------

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
/// importance sampler, `shade(x_px, y_px, rng)` at each (film coordinates from the top-left; pixel
/// (x, y) covers [x, x+1)×[y, y+1)), reconstructed by normalised weights; adaptive samples where the
/// base samples disagree. Each pixel uses `Pcg32::new(seed, y·width + x)` for its jitter and passes it
/// on to the shader, so the image is the same whatever the thread count or tile order.
/// `on_tile_done` is called (from worker threads) after each 16×16 tile.
pub fn render<F>(settings: &ImageSettings, shade: F, on_tile_done: &(dyn Fn() + Sync)) -> (Image, FilmStats)
where
    F: Fn(f32, f32, &mut Pcg32) -> Vec3 + Sync,
{
    let (image, stats, _) = render_with(settings, || (), |_: &mut (), x, y, rng| shade(x, y, rng), on_tile_done);
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
    F: Fn(&mut S, f32, f32, &mut Pcg32) -> Vec3 + Sync,
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
        sampler: FilterSampler::new(settings.filter, radius_px),
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
    sampler: FilterSampler,
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
        F: Fn(&mut S, f32, f32, &mut Pcg32) -> Vec3,
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
        F: Fn(&mut S, f32, f32, &mut Pcg32) -> Vec3,
    {
        let pixel_index = y as u64 * self.width as u64 + x as u64;
        let mut rng = Pcg32::new(self.seed, pixel_index);
        scratch.radiance.clear();
        scratch.weights.clear();
        let centre = [x as f32 + 0.5, y as f32 + 0.5];
        self.shade_batch(self.base_samples, centre, state, shade, &mut rng, scratch, stats);
        if let Some((threshold, extra)) = self.adaptive {
            if luminance_contrast(&scratch.radiance) > threshold {
                self.shade_batch(extra, centre, state, shade, &mut rng, scratch, stats);
                stats.adaptive_extra_samples += extra as u64;
                stats.adaptive_pixels += 1;
            }
        }
        reconstruct_pixel(&scratch.radiance, &scratch.weights)
    }

    /// Draws one multi-jittered batch of `count` samples, shades them and keeps the finite ones.
    #[allow(clippy::too_many_arguments)]
    fn shade_batch<S, F>(
        &self,
        count: u32,
        centre: [f32; 2],
        state: &mut S,
        shade: &F,
        rng: &mut Pcg32,
        scratch: &mut PixelScratch,
        stats: &mut FilmStats,
    ) where
        F: Fn(&mut S, f32, f32, &mut Pcg32) -> Vec3,
    {
        let (columns, rows) = stratum_grid(count);
        scratch.points.clear();
        multi_jittered(columns, rows, rng, &mut scratch.points);
        for u in &scratch.points {
            let s = self.sampler.sample(*u);
            let l = shade(state, centre[0] + s.offset_px[0], centre[1] + s.offset_px[1], rng);
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn erf_matches_known_values() {
        // erf(0.5) = 0.5204998778, erf(1) = 0.8427007929, erf(3/√2) = 0.9973002039 (tables);
        // A&S 7.1.26 guarantees 1.5e-7.
        for (x, e) in [(0.5, 0.5204998778), (1.0, 0.8427007929), (3.0 / 2f64.sqrt(), 0.9973002039)] {
            assert!((erf(x) - e).abs() < 1.5e-7, "erf({x}) = {}", erf(x));
            assert!((erf(-x) + e).abs() < 1.5e-7);
        }
    }

    #[test]
    fn stratum_grid_is_as_square_as_the_count_allows() {
        assert_eq!(stratum_grid(16), (4, 4));
        assert_eq!(stratum_grid(8), (2, 4));
        assert_eq!(stratum_grid(12), (3, 4));
        assert_eq!(stratum_grid(7), (1, 7));
        assert_eq!(stratum_grid(1), (1, 1));
        assert_eq!(stratum_grid(0), (1, 1));
    }

    #[test]
    fn filter_samplers_are_monotone_and_stay_inside_the_radius() {
        for kind in [FilterKind::Box, FilterKind::Tent, FilterKind::Gaussian, FilterKind::Mitchell] {
            let s = FilterSampler::new(kind, 1.5);
            let mut previous = -f32::INFINITY;
            for i in 0..1000 {
                let (x, w) = s.sample_1d(i as f32 / 1000.0);
                assert!(x >= previous, "{kind:?} not monotone at {i}");
                assert!(x.abs() <= 1.5 && w.is_finite(), "{kind:?}: {x} {w}");
                previous = x;
            }
        }
    }

    #[test]
    fn mitchell_sampler_weights_carry_the_sign_of_the_filter() {
        let s = FilterSampler::new(FilterKind::Mitchell, 2.0);
        for i in 0..1000 {
            let (x, w) = s.sample_1d((i as f32 + 0.5) / 1000.0);
            let f = mitchell_filter(x, 2.0);
            assert!(f == 0.0 || w.signum() == f.signum(), "x {x}: f {f}, w {w}");
        }
    }
}
