//! Where a pixel's samples go: the per-pixel `Sampler` that the film hands on to the shader (with
//! Owen-scrambled Sobol patterns shared across the pixel's samples), the pixel's own shuffled,
//! scrambled Sobol sequence of film positions.

use crate::rng::{splitmix64, Pcg32};
pub use crate::sobol::{owen_scramble, owen_sobol_2d, sobol_2d_bits};

/// The random numbers one pixel's samples draw, seeded per pixel so that the image does not depend on
/// the thread schedule.
#[derive(Clone, Debug)]
pub enum Sampler {
    /// Independent uniform numbers from a PCG32 stream (`Pcg32::new(seed, stream)`); its patterns
    /// (`pattern_2d`) are stratified along x only, within one call.
    Independent(Pcg32),
    /// A film pixel: independent numbers for the camera jitter and what is not a pattern, and
    /// Owen-scrambled Sobol patterns shared by the pixel's samples (see `pattern_2d`).
    Pixel(PixelSampler),
}

/// State of a film pixel's sampler: its stream, its scrambling key, which of its samples is being
/// shaded and how many patterns that sample has asked for.
#[derive(Clone, Debug)]
pub struct PixelSampler {
    rng: Pcg32,
    key: u64,
    sample_index: u32,
    dimension: u32,
    /// Made by `Sampler::pixel_adaptive`: the pixel's adaptive samples.
    adaptive: bool,
}

/// A 2-D point set handed out by [`Sampler::pattern_2d`]; [`Sampler::point_2d`] reads its points.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pattern2d {
    count: u32,
    /// Index of point 0 in the Sobol sequence, and the two scrambling seeds (`Pixel` samplers only).
    sobol: Option<(u32, [u32; 2])>,
}

impl Pattern2d {
    /// Points in the pattern.
    pub fn len(&self) -> u32 {
        self.count
    }

    pub fn is_empty(&self) -> bool {
        self.count == 0
    }
}

impl Sampler {
    /// Independent numbers for stream `stream` (a pixel index) of seed `seed`.
    pub fn independent(seed: u64, stream: u64) -> Sampler {
        Sampler::Independent(Pcg32::new(seed, stream))
    }

    /// The film's sampler for pixel `pixel` (its index y·width + x) of seed `seed`: the same stream as
    /// `independent(seed, pixel)`, plus a scrambling key from both. Call `start_sample` before each of
    /// the pixel's samples.
    pub fn pixel(seed: u64, pixel: u64) -> Sampler {
        Sampler::Pixel(PixelSampler {
            rng: Pcg32::new(seed, pixel),
            key: pixel_key(seed, pixel),
            sample_index: 0,
            dimension: 0,
            adaptive: false,
        })
    }

    /// The film's sampler for pixel `pixel`'s adaptive samples, drawn after its base samples were
    /// shaded by `pixel(seed, pixel)`: the same scrambling key, so its samples (numbered on from the
    /// base count) continue the pixel's Sobol patterns and positions, and a random stream of its own,
    /// so that its independent numbers do not repeat the base samples'.
    pub fn pixel_adaptive(seed: u64, pixel: u64) -> Sampler {
        let stream_seed = splitmix64(seed ^ ADAPTIVE_STREAM);
        Sampler::Pixel(PixelSampler {
            rng: Pcg32::new(stream_seed, pixel),
            key: pixel_key(seed, pixel),
            sample_index: 0,
            dimension: 0,
            adaptive: true,
        })
    }

    /// Whether this sampler draws a pixel's adaptive samples (`pixel_adaptive`), which estimates may
    /// spend fewer rays on (see `FinalGather::irradiance`).
    pub fn is_adaptive(&self) -> bool {
        matches!(self, Sampler::Pixel(PixelSampler { adaptive: true, .. }))
    }

    /// Where in its pixel sample `index` lands, in [0, 1)²: point `shuffle(index)` of the 2-D Sobol
    /// sequence, Owen-scrambled, with the shuffle and both scrambles seeded by the pixel's key alone
    /// (Burley 2020, "Practical hash-based Owen scrambling"). The shuffle is a nested uniform
    /// scramble of the index, which maps every aligned block of 2^m indices onto an aligned block, so
    /// the pixel's first 2^m samples (its base samples, and its base and adaptive samples together)
    /// are a (0, m, 2)-net: one sample in each elementary interval of area 2^-m, N-rooks included.
    /// The shuffle decorrelates the positions from the shading patterns, which use the same sequence
    /// unshuffled. An `Independent` sampler draws uniform positions from its stream.
    pub fn film_position(&mut self, index: u32) -> [f32; 2] {
        match self {
            Sampler::Independent(rng) => [rng.next_f32(), rng.next_f32()],
            Sampler::Pixel(p) => {
                let h = splitmix64(p.key ^ FILM_POSITION_DIMENSION);
                let shuffled = owen_scramble(index, (h >> 40) as u32 ^ h as u32);
                let seeds = splitmix64(h);
                owen_sobol_2d(shuffled, [seeds as u32, (seeds >> 32) as u32])
            }
        }
    }

    /// Marks the start of the pixel's sample `index` (0, 1, … in the order they are shaded, adaptive
    /// ones continuing the count); patterns are counted afresh within each sample.
    pub fn start_sample(&mut self, index: u32) {
        if let Sampler::Pixel(p) = self {
            p.sample_index = index;
            p.dimension = 0;
        }
    }

    /// The next number, uniform in [0, 1).
    pub fn next_1d(&mut self) -> f32 {
        self.rng().next_f32()
    }

    /// The next 32 uniform bits (for shuffles).
    pub fn next_u32(&mut self) -> u32 {
        self.rng().next_u32()
    }

    /// Independent numbers from a side stream `stream` forked off this sampler's (`Pcg32::fork`),
    /// leaving this sampler as it was: an estimate drawn from the fork (a pilot gather, say) does not
    /// change the numbers the sampler's own estimates draw next.
    pub fn fork(&self, stream: u64) -> Sampler {
        let rng = match self {
            Sampler::Independent(rng) => rng,
            Sampler::Pixel(p) => &p.rng,
        };
        Sampler::Independent(rng.fork(stream))
    }

    fn rng(&mut self) -> &mut Pcg32 {
        match self {
            Sampler::Independent(rng) => rng,
            Sampler::Pixel(p) => &mut p.rng,
        }
    }

    /// A pattern of `count` 2-D points for one estimate (the shadow rays of one hit, say). With a
    /// `Pixel` sampler, the d-th pattern asked for within sample s holds points s·count … s·count +
    /// count − 1 of the 2-D Sobol sequence (a (0, 2)-sequence), Owen-scrambled with seeds of
    /// (pixel, d): the d-th patterns of all the pixel's samples together are one stratified set of
    /// spp·count points (every power-of-two prefix has one point in each elementary interval of its
    /// size), and each point alone is uniform, so estimates stay unbiased (Owen 1995; Burley 2020's
    /// hash-based scrambling). With an `Independent` sampler, point k has x jittered in
    /// [k/count, (k+1)/count) and y uniform.
    pub fn pattern_2d(&mut self, count: u32) -> Pattern2d {
        match self {
            Sampler::Independent(_) => Pattern2d { count, sobol: None },
            Sampler::Pixel(p) => {
                let h = splitmix64(p.key ^ (p.dimension as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15));
                p.dimension += 1;
                let first = p.sample_index.wrapping_mul(count);
                Pattern2d { count, sobol: Some((first, [h as u32, (h >> 32) as u32])) }
            }
        }
    }

    /// Point k (< `pattern.len()`) of a pattern, in [0, 1)².
    pub fn point_2d(&mut self, pattern: &Pattern2d, k: u32) -> [f32; 2] {
        match pattern.sobol {
            Some((first, seeds)) => owen_sobol_2d(first.wrapping_add(k), seeds),
            None => {
                let x = (k as f32 + self.next_1d()) / pattern.count.max(1) as f32;
                [x.min(ONE_BELOW), self.next_1d()]
            }
        }
    }
}

/// The scrambling key of pixel `pixel` of seed `seed`.
fn pixel_key(seed: u64, pixel: u64) -> u64 {
    splitmix64(splitmix64(seed) ^ pixel.wrapping_mul(0xD1B5_4A32_D192_ED03))
}

/// Mixed into a pixel's key for its film positions. Pattern d mixes in (d + 1)·0x9E37_79B9_7F4A_7C15,
/// which equals this only for d + 1 = 0x498C_2FF4_E281_0000: never in practice.
const FILM_POSITION_DIMENSION: u64 = 0xF11B_0517_1095_0000;

/// Mixed into the seed for the random stream of a pixel's adaptive samples.
const ADAPTIVE_STREAM: u64 = 0xADA9_7153_A3B1_E500;

const ONE_BELOW: f32 = 1.0 - f32::EPSILON / 2.0;

#[cfg(test)]
mod tests {
    use super::*;

    /// The first 2^m points of a (0, 2)-sequence put exactly one point in each elementary interval of
    /// area 2^-m: here every 2^a × 2^(m−a) grid, a = 0..=m.
    fn one_point_per_elementary_interval(points: &[[f32; 2]], m: u32) -> bool {
        (0..=m).all(|a| {
            let (nx, ny) = (1usize << a, 1usize << (m - a));
            let mut seen = vec![false; nx * ny];
            points.iter().all(|p| {
                let cell = (p[1] * ny as f32) as usize * nx + (p[0] * nx as f32) as usize;
                !std::mem::replace(&mut seen[cell], true)
            })
        })
    }

    #[test]
    fn scrambled_sobol_keeps_its_strata_in_every_pixel() {
        let m = 6;
        for pixel in 0..20u64 {
            let mut s = Sampler::pixel(3, pixel);
            let mut points = Vec::new();
            // 16 samples of 4 points each: the first pattern of every sample, 64 points together.
            for sample in 0..16 {
                s.start_sample(sample);
                let pattern = s.pattern_2d(4);
                let _second = s.pattern_2d(4);
                points.extend((0..4).map(|k| s.point_2d(&pattern, k)));
            }
            assert!(one_point_per_elementary_interval(&points, m), "pixel {pixel}");
        }
    }

    #[test]
    fn scrambled_sobol_points_are_uniform_over_pixels() {
        // One point per pixel (sample 0, k = 0): over 20 000 pixels the mean of x, y and xy must be
        // those of the uniform square, 1/2, 1/2, 1/4, within 5 standard errors (σ/√n ≈ 0.002).
        let n = 20_000;
        let (mut sx, mut sy, mut sxy) = (0.0f64, 0.0f64, 0.0f64);
        for pixel in 0..n {
            let mut s = Sampler::pixel(0, pixel);
            s.start_sample(0);
            let pattern = s.pattern_2d(1);
            let [x, y] = s.point_2d(&pattern, 0);
            sx += x as f64;
            sy += y as f64;
            sxy += (x * y) as f64;
        }
        let tol = 5.0 * (1.0f64 / 12.0 / n as f64).sqrt();
        assert!((sx / n as f64 - 0.5).abs() < tol);
        assert!((sy / n as f64 - 0.5).abs() < tol);
        assert!((sxy / n as f64 - 0.25).abs() < tol);
    }
}
