//! Reconstruction filters: each 1-D filter f(x) has support [−r, r] and ∫ f dx = 1, the 2-D filter is
//! the separable product f(x)·f(y); their importance samplers; and the normalised-weight reconstruction
//! of a pixel from its samples.

use crate::scene::FilterKind;
use glam::Vec3;

/// Bins of the tabulated 1-D filter distributions (Gaussian, Mitchell) across the diameter.
pub const FILTER_TABLE_BINS: usize = 256;

/// Mitchell–Netravali parameters B = C = 1/3 (Mitchell & Netravali 1988's recommendation).
const MITCHELL_B: f32 = 1.0 / 3.0;
const MITCHELL_C: f32 = 1.0 / 3.0;

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
