//! Specification tests of the film (filters, stratification, reconstruction, adaptivity, determinism),
//! image output (PNG/EXR, atomic writes) and image comparison.

use glam::Vec3;
use radray::compare::{self, CompareError, PixelChannel};
use radray::film::Sampler;
use radray::film::{self, FilterSampler, Image};
use radray::output::{self, OutputError, ToneCurve};
use radray::rng::Pcg32;
use radray::scene::{FilterKind, ImageSettings};
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};

const ALL_FILTERS: [FilterKind; 4] = [FilterKind::Box, FilterKind::Tent, FilterKind::Gaussian, FilterKind::Mitchell];

fn settings(
    width_px: u32,
    height_px: u32,
    samples_per_pixel: u32,
    filter: FilterKind,
    radius_px: f32,
) -> ImageSettings {
    ImageSettings {
        width_px,
        height_px,
        samples_per_pixel,
        filter,
        filter_radius_px: radius_px,
        adaptive_threshold: None,
        adaptive_error: None,
        adaptive_max_samples: samples_per_pixel,
        // No total budget: the adaptive tests below check the criteria alone (on films of a few
        // pixels, a thin border is a large share of the image); the budget has tests of its own.
        adaptive_budget: f32::INFINITY,
        seed: 42,
        exposure: Default::default(),
    }
}

fn no_progress() {}

// ---------------------------------------------------------------------------------------------------
// Filters
// ---------------------------------------------------------------------------------------------------

#[test]
fn each_filter_integrates_to_one_over_its_support() {
    // Midpoint rule with 100 000 cells over [−r, r] (cell edges fall on the tent's and box's kinks).
    // The quadrature error of the smooth filters is ≲ (2r)·h²·max|f''|/24 < 1e-9; f32 evaluation
    // adds ~1e-7 relative and the erf approximation in the Gaussian's normalisation 1.5e-7, so 1e-5
    // bounds all of it with margin.
    for kind in ALL_FILTERS {
        for radius_px in [0.5f32, 1.0, 1.5, 2.0] {
            let n = 100_000;
            let h = 2.0 * radius_px as f64 / n as f64;
            let integral: f64 = (0..n)
                .map(|i| film::filter_1d(kind, (-radius_px as f64 + (i as f64 + 0.5) * h) as f32, radius_px) as f64 * h)
                .sum();
            assert!((integral - 1.0).abs() < 1e-5, "{kind:?} r={radius_px}: ∫f = {integral}");
            // Zero outside the support.
            assert_eq!(film::filter_1d(kind, radius_px * 1.001, radius_px), 0.0);
        }
    }
}

#[test]
fn mitchell_filter_has_negative_lobes_and_gaussian_reaches_zero_at_its_radius() {
    // k(1.5) = ((−B−6C)·3.375 + (6B+30C)·2.25 + (−12B−48C)·1.5 + 8B+24C)/6 with B=C=1/3
    //        = (−7.875 + 27 − 30 + 10.666…)/6 = −0.034722…; f(x) = (2/r)·k(2x/r), r = 2 → f(1.5) = k(1.5).
    assert!((film::mitchell_filter(1.5, 2.0) - (-0.034_722_22)).abs() < 1e-6);
    assert!(film::gaussian_filter(1.5, 1.5).abs() < 1e-7);
}

#[test]
fn importance_sampled_filter_weights_average_to_the_filter_integral() {
    // E[f(x)/p(x)] = ∫ f = 1 for x ~ p. Over 4096 1-D strata (stratum centres) the estimate's error is
    // the variation of f/p within a stratum divided by the count, far below 1e-3.
    for kind in ALL_FILTERS {
        let sampler = FilterSampler::new(kind, 1.5);
        let n = 4096;
        let mean: f64 = (0..n).map(|i| sampler.sample_1d((i as f32 + 0.5) / n as f32).1 as f64).sum::<f64>() / n as f64;
        assert!((mean - 1.0).abs() < 1e-3, "{kind:?}: mean weight {mean}");
    }
}

#[test]
fn normalised_weights_of_a_pixel_sum_to_one() {
    // The weights a pixel's reconstruction applies are wᵢ/Σw; in f64 their sum is 1 to rounding
    // (N ≤ 64 terms, relative error ≲ 64·2⁻⁵³ < 1e-12).
    for kind in ALL_FILTERS {
        for spp in [1u32, 7, 16, 64] {
            let filter = FilterSampler::new(kind, 2.0);
            let mut sampler = Sampler::pixel(3, spp as u64);
            let points: Vec<[f32; 2]> = (0..spp).map(|i| sampler.film_position(i)).collect();
            let weights: Vec<f64> = points.iter().map(|u| filter.sample(*u).weight as f64).collect();
            let total: f64 = weights.iter().sum();
            assert!(total > 0.0, "{kind:?} spp {spp}: Σw = {total}");
            let normalised_sum: f64 = weights.iter().map(|w| w / total).sum();
            assert!((normalised_sum - 1.0).abs() < 1e-12, "{kind:?} spp {spp}: {normalised_sum}");
            // And the reconstruction of a constant built from these weights is that constant, exactly.
            let c = Vec3::new(0.3, 1.7, 1e-3);
            let weights_f32: Vec<f32> = weights.iter().map(|w| *w as f32).collect();
            assert_eq!(film::reconstruct_pixel(&vec![c; weights.len()], &weights_f32), c);
        }
    }
}

// ---------------------------------------------------------------------------------------------------
// Stratification
// ---------------------------------------------------------------------------------------------------

/// True if the points put exactly one point in each elementary interval of area 1/len: every
/// 2^a × 2^(m−a) grid, len = 2^m (a (0, m, 2)-net; a = 0 and a = m are the N-rooks strata).
fn is_a_net(points: &[[f32; 2]]) -> bool {
    let m = points.len().trailing_zeros();
    assert_eq!(1 << m, points.len());
    (0..=m).all(|a| {
        let (nx, ny) = (1usize << a, 1usize << (m - a));
        let mut seen = vec![false; nx * ny];
        points.iter().all(|[x, y]| {
            assert!((0.0..1.0).contains(x) && (0.0..1.0).contains(y), "{x} {y}");
            let cell = (y * ny as f32) as usize * nx + (x * nx as f32) as usize;
            !std::mem::replace(&mut seen[cell], true)
        })
    })
}

#[test]
fn film_positions_of_a_pixel_are_a_net_at_every_power_of_two() {
    // A pixel's first 16 samples (the default base count), its first 64 (with adaptive samples),
    // and the adaptive block 16..32 alone: each set is stratified in every elementary interval.
    for pixel in 0..50u64 {
        let mut sampler = Sampler::pixel(7, pixel);
        let points: Vec<[f32; 2]> = (0..64).map(|i| sampler.film_position(i)).collect();
        assert!(is_a_net(&points[..16]), "pixel {pixel}: first 16");
        assert!(is_a_net(&points[16..32]), "pixel {pixel}: 16..32");
        assert!(is_a_net(&points), "pixel {pixel}: first 64");
        // The adaptive sampler continues the same positions.
        let mut adaptive = Sampler::pixel_adaptive(7, pixel);
        assert_eq!(adaptive.film_position(40), points[40]);
    }
    // Different pixels get different (scrambled and shuffled) positions.
    let first = |pixel| Sampler::pixel(7, pixel).film_position(0);
    assert_ne!(first(0), first(1));
}

#[test]
fn film_positions_are_uniform_over_pixels() {
    // Sample 5 of 20 000 pixels: the means of x, y and xy are those of the uniform square, 1/2, 1/2,
    // 1/4, within 5 standard errors (σ/√n ≈ 0.002 for x and y; xy's σ is smaller).
    let n = 20_000u64;
    let (mut sx, mut sy, mut sxy) = (0.0f64, 0.0f64, 0.0f64);
    for pixel in 0..n {
        let [x, y] = Sampler::pixel(1, pixel).film_position(5);
        sx += x as f64;
        sy += y as f64;
        sxy += (x * y) as f64;
    }
    let tol = 5.0 * (1.0f64 / 12.0 / n as f64).sqrt();
    let n = n as f64;
    assert!((sx / n - 0.5).abs() < tol && (sy / n - 0.5).abs() < tol && (sxy / n - 0.25).abs() < tol);
}

// ---------------------------------------------------------------------------------------------------
// Rendering
// ---------------------------------------------------------------------------------------------------

#[test]
fn constant_shader_gives_exactly_the_constant_for_every_filter() {
    let c = Vec3::new(0.25, 3.5, 1e-4);
    for kind in ALL_FILTERS {
        for (radius_px, spp) in [(0.5, 1), (1.5, 7), (2.0, 16)] {
            let s = settings(19, 17, spp, kind, radius_px);
            let (image, stats) = film::render(&s, |_, _, _| c, &no_progress);
            assert!(image.pixels.iter().all(|p| *p == c), "{kind:?} r {radius_px} spp {spp}");
            assert_eq!(stats.samples, 19 * 17 * spp as u64);
        }
    }
}

#[test]
fn box_filtered_edge_pixels_get_their_coverage_fraction() {
    // Row y has a vertical edge at x = 3 + f(y), f(y) = 0.05 + 0.1·y: radiance 1 left of it, 0 right.
    // With the box filter (r = 0.5) pixel 3 of row y should be f(y). The x offsets are N-rook
    // stratified (N = spp = 16), so all but the one stratum containing the edge are classified exactly:
    // the error is below 1/N = 1/16.
    let spp = 16;
    let fraction = |y: u32| 0.05 + 0.1 * y as f32;
    let s = settings(8, 10, spp, FilterKind::Box, 0.5);
    let (image, _) =
        film::render(&s, |x, y, _| if x < 3.0 + fraction(y as u32) { Vec3::ONE } else { Vec3::ZERO }, &no_progress);
    for y in 0..10 {
        let v = image.get(3, y);
        assert_eq!(v.x, v.y);
        assert!((v.x - fraction(y)).abs() < 1.0 / spp as f32, "row {y}: {} vs {}", v.x, fraction(y));
        for x in 0..3 {
            assert_eq!(image.get(x, y), Vec3::ONE);
        }
        for x in 4..8 {
            assert_eq!(image.get(x, y), Vec3::ZERO);
        }
    }
}

/// A shader that uses its position and its sampler, so any change of sample order or stream shows.
fn noisy_shader(x: f32, y: f32, sampler: &mut Sampler) -> Vec3 {
    let edge = if x + 0.3 * y < 20.0 { 1.0 } else { 0.1 };
    Vec3::new(edge * sampler.next_1d(), (x * 0.1).sin().abs(), (y * 0.07).cos().abs() + sampler.next_1d())
}

fn render_in_pool(threads: usize, s: &ImageSettings) -> (Image, film::FilmStats) {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    pool.install(|| film::render(s, noisy_shader, &no_progress))
}

#[test]
fn images_are_bit_identical_with_one_and_two_threads() {
    for kind in ALL_FILTERS {
        let mut s = settings(37, 29, 8, kind, 1.5);
        s.adaptive_threshold = Some(0.3);
        s.adaptive_error = Some(0.2);
        s.adaptive_max_samples = 24;
        let (a, stats_a) = render_in_pool(1, &s);
        let (b, stats_b) = render_in_pool(2, &s);
        let bits = |i: &Image| i.pixels.iter().flat_map(|p| p.to_array().map(f32::to_bits)).collect::<Vec<u32>>();
        assert_eq!(bits(&a), bits(&b), "{kind:?}");
        assert_eq!(stats_a, stats_b);
        // 3×2 tiles of 16×16 cover 37×29.
        assert_eq!(stats_a.tiles, 6);
    }
}

#[test]
fn adaptive_supersampling_spends_extra_samples_only_at_edges() {
    // A vertical edge at x = 5.3 inside pixel column 5. With a box filter of radius 0.5 only column 5's
    // samples straddle it: its 4 base samples are N-rook stratified in x, so the one in [0, 0.25) is
    // bright and those in [0.5, 1) dark, contrast 1 > 0.5. Every other pixel is uniform (contrast 0).
    let (width, height) = (12u32, 9u32);
    let mut s = settings(width, height, 4, FilterKind::Box, 0.5);
    s.adaptive_threshold = Some(0.5);
    s.adaptive_max_samples = 16;
    let (image, stats, counts) = film::render_with(
        &s,
        || vec![0u32; (width * height) as usize],
        |calls: &mut Vec<u32>, x, y, _| {
            calls[(y as u32 * width + x as u32) as usize] += 1;
            if x < 5.3 {
                Vec3::splat(2.0)
            } else {
                Vec3::ZERO
            }
        },
        &no_progress,
    );
    let mut calls = vec![0u32; (width * height) as usize];
    for c in &counts {
        for (total, n) in calls.iter_mut().zip(c) {
            *total += n;
        }
    }
    for y in 0..height {
        for x in 0..width {
            let expected = if x == 5 { 16 } else { 4 };
            assert_eq!(calls[(y * width + x) as usize], expected, "pixel ({x}, {y})");
        }
        // Coverage 0.3 of radiance 2.0. The base and adaptive samples together are the pixel's first 16
        // film positions, N-rook stratified (one in each 1/16 of x): all but the stratum holding the
        // edge are classified exactly, so the coverage error is below 1/16, i.e. 2.0/16 in radiance.
        assert!((image.get(5, y).x - 0.6).abs() < 2.0 / 16.0, "{}", image.get(5, y).x);
    }
    assert_eq!(stats.adaptive_pixels, height as u64);
    assert_eq!(stats.adaptive_extra_samples, height as u64 * 12);
    assert_eq!(stats.samples, (width * height * 4) as u64 + height as u64 * 12);
}

#[test]
fn one_sample_error_is_the_swing_over_n_relative_to_the_pixel() {
    // A dark pixel (Y = 0.3) next to an emitter of luminance 24 seen by a neighbour, 16 samples:
    // (24 − 0.3) / (16·√(0.3² + 0.01)) = 23.7 / (16·0.316228) = 4.684.
    assert!((film::one_sample_error(0.3, 0.3, 24.0, 16) - 4.684).abs() < 1e-3);
    // The emitter's own pixel beside the dark one: (24 − 0.3) / (16·√(24² + 0.01)) = 0.0617.
    assert!((film::one_sample_error(24.0, 0.3, 24.0, 16) - 0.0617).abs() < 1e-4);
    assert_eq!(film::one_sample_error(0.5, 0.5, 0.5, 16), 0.0);
    assert_eq!(film::one_sample_error(0.5, 0.0, 9.0, 0), 0.0);
}

#[test]
fn adaptive_error_supersamples_the_dark_side_of_a_thin_emitter_border() {
    // An emitter of radiance 24 left of x = 5.02 on a background of 0.3. Pixel column 5 is covered
    // 2%: its true value is 0.02·24 + 0.98·0.3 = 0.774, and 16 N-rook samples hit the emitter 0 or 1
    // times (0.3 or 1.78). Its neighbours in column 4 see 24, so one_sample_error ≈ 4.7 > 0.25 asks for
    // more samples; column 4 (0.06) and the uniform columns do not. Column 6 may: its neighbour in
    // column 5 saw 24 if one of its samples hit.
    let (width, height) = (12u32, 9u32);
    let mut s = settings(width, height, 16, FilterKind::Box, 0.5);
    s.adaptive_error = Some(0.25);
    s.adaptive_max_samples = 256;
    let (image, stats, counts) = film::render_with(
        &s,
        || vec![0u32; (width * height) as usize],
        |calls: &mut Vec<u32>, x, y, _| {
            calls[(y as u32 * width + x as u32) as usize] += 1;
            Vec3::splat(if x < 5.02 { 24.0 } else { 0.3 })
        },
        &no_progress,
    );
    let mut calls = vec![0u32; (width * height) as usize];
    for c in &counts {
        for (total, n) in calls.iter_mut().zip(c) {
            *total += n;
        }
    }
    for y in 0..height {
        for x in (0..width).filter(|&x| x != 6) {
            let expected = if x == 5 { 256 } else { 16 };
            assert_eq!(calls[(y * width + x) as usize], expected, "pixel ({x}, {y})");
        }
        // 256 N-rook samples: the coverage error is below 1/256, i.e. (24 − 0.3)/256 in radiance.
        let v = image.get(5, y).x;
        assert!((v - 0.774).abs() < 23.7 / 256.0, "row {y}: {v}");
    }
    assert!(stats.adaptive_pixels >= height as u64);
}

fn wanted(requests: &[(u32, u32, f32)]) -> Vec<film::Wanted> {
    requests.iter().map(|&(pixel, samples, priority)| film::Wanted { pixel, samples, priority }).collect()
}

#[test]
fn requests_within_the_adaptive_budget_are_kept_as_they_are() {
    let w = wanted(&[(3, 256, 9.0), (7, 32, 1.5), (9, 64, 2.5)]);
    // 240 + 16 + 48 = 304 extra samples over 16 base samples.
    assert_eq!(film::within_budget(w.clone(), 16, 304), w);
    assert_eq!(film::within_budget(w.clone(), 16, 10_000), w);
}

#[test]
fn over_budget_the_largest_requests_are_capped_first() {
    let w = wanted(&[(3, 256, 9.0), (7, 32, 1.5), (9, 64, 2.5), (12, 128, 4.0)]);
    // Caps: 256 → 240+16+48+112 = 416, 128 → 112+16+48+112 = 288, 64 → 48+16+48+48 = 160,
    // 32 → 16·4 = 64. A budget of 300 allows 128, 200 allows 64.
    let capped = |cap: u32| w.iter().map(|x| film::Wanted { samples: x.samples.min(cap), ..*x }).collect::<Vec<_>>();
    assert_eq!(film::within_budget(w.clone(), 16, 300), capped(128));
    assert_eq!(film::within_budget(w.clone(), 16, 200), capped(64));
    assert_eq!(film::within_budget(w.clone(), 16, 64), capped(32));
    // Below the smallest request for every pixel: 40 extra samples keep the two most urgent pixels at
    // 32 (16 extra each), in pixel order.
    let kept = film::within_budget(w, 16, 40);
    assert_eq!(kept, wanted(&[(3, 32, 9.0), (12, 32, 4.0)]));
    assert_eq!(film::within_budget(Vec::new(), 16, 0), Vec::new());
}

#[test]
fn the_adaptive_pass_spends_at_most_its_budget_on_an_image_that_is_noisy_everywhere() {
    // Every sample is independent noise (`noisy_shader`), so the standard-error criterion at a tight
    // bound asks for the cap in nearly every pixel; the budget keeps the extra samples within
    // `adaptive_budget` times the base samples.
    let mut s = settings(48, 32, 16, FilterKind::Box, 0.5);
    s.adaptive_error = Some(0.001);
    s.adaptive_max_samples = 256;
    s.adaptive_budget = 0.75;
    let (_, stats) = film::render(&s, noisy_shader, &no_progress);
    let base = 48 * 32 * 16;
    let budget = (0.75 * base as f64) as u64;
    assert!(stats.adaptive_extra_samples <= budget, "{} > {budget}", stats.adaptive_extra_samples);
    assert!(stats.adaptive_extra_samples > budget / 2, "the budget should be used: {}", stats.adaptive_extra_samples);
    assert_eq!(stats.samples, base as u64 + stats.adaptive_extra_samples);
}

#[test]
fn non_finite_samples_are_dropped_and_counted() {
    // Samples in the left quarter of each pixel return NaN or ∞; the rest 0.5. Box r = 0.5, 16 N-rook
    // samples: exactly 4 per pixel fall in [x, x + 0.25).
    let s = settings(5, 3, 16, FilterKind::Box, 0.5);
    let (image, stats) = film::render(
        &s,
        |x, _, _| {
            if x.fract() < 0.25 {
                if x < 2.0 {
                    Vec3::splat(f32::NAN)
                } else {
                    Vec3::new(0.5, f32::INFINITY, 0.5)
                }
            } else {
                Vec3::splat(0.5)
            }
        },
        &no_progress,
    );
    assert!(image.pixels.iter().all(|p| *p == Vec3::splat(0.5)));
    assert_eq!(stats.non_finite_samples, 15 * 4);
    assert_eq!(stats.samples, 15 * 16);
}

#[test]
fn every_tile_reports_done_once() {
    let done = AtomicU32::new(0);
    let s = settings(40, 20, 1, FilterKind::Tent, 1.0);
    let (_, stats) = film::render(&s, |_, _, _| Vec3::ONE, &|| {
        done.fetch_add(1, Ordering::Relaxed);
    });
    // ⌈40/16⌉·⌈20/16⌉ = 3·2 tiles.
    assert_eq!(done.load(Ordering::Relaxed), 6);
    assert_eq!(stats.tiles, 6);
}

/// A `FilmProgress` that records what it hears.
#[derive(Default)]
struct Recorded {
    tiles: AtomicU64,
    starts: AtomicU64,
    pixels: AtomicU64,
    announced: AtomicU64,
    done: AtomicU64,
}

impl film::FilmProgress for Recorded {
    fn tile_done(&self) {
        self.tiles.fetch_add(1, Ordering::Relaxed);
    }
    fn adaptive_start(&self, pixels: u64, extra_samples: u64) {
        self.starts.fetch_add(1, Ordering::Relaxed);
        self.pixels.store(pixels, Ordering::Relaxed);
        self.announced.store(extra_samples, Ordering::Relaxed);
    }
    fn adaptive_done(&self, extra_samples: u64) {
        self.done.fetch_add(extra_samples, Ordering::Relaxed);
    }
}

#[test]
fn the_adaptive_pass_reports_its_pixels_and_samples_as_it_goes() {
    // The thin-emitter-border film of `adaptive_error_supersamples_the_dark_side_of_a_thin_emitter_border`,
    // 40 rows so that the adaptive pass has several pieces of work: what the pass announces, what it
    // reports done and what it spent are the same numbers.
    let mut s = settings(12, 40, 16, FilterKind::Box, 0.5);
    s.adaptive_error = Some(0.25);
    s.adaptive_max_samples = 256;
    let recorded = Recorded::default();
    let (_, stats) = film::render(&s, |x, _, _| Vec3::splat(if x < 5.02 { 24.0 } else { 0.3 }), &recorded);
    assert_eq!(recorded.tiles.load(Ordering::Relaxed), 3);
    assert_eq!(recorded.starts.load(Ordering::Relaxed), 1);
    assert!(stats.adaptive_pixels >= 40);
    assert_eq!(recorded.pixels.load(Ordering::Relaxed), stats.adaptive_pixels);
    assert_eq!(recorded.announced.load(Ordering::Relaxed), stats.adaptive_extra_samples);
    assert_eq!(recorded.done.load(Ordering::Relaxed), stats.adaptive_extra_samples);

    // Without adaptive samples the pass is not announced.
    let recorded = Recorded::default();
    film::render(&settings(12, 40, 16, FilterKind::Box, 0.5), |_, _, _| Vec3::ONE, &recorded);
    assert_eq!(recorded.starts.load(Ordering::Relaxed), 0);
    assert_eq!(recorded.tiles.load(Ordering::Relaxed), 3);
}

#[test]
fn film_coordinates_cover_each_pixel_from_its_top_left_corner() {
    // With a box filter of radius 0.5 every sample of pixel (x, y) lies in [x, x+1)×[y, y+1).
    let s = settings(6, 4, 9, FilterKind::Box, 0.5);
    let (image, _) = film::render(&s, |x, y, _| Vec3::new(x.floor(), y.floor(), 0.0), &no_progress);
    for y in 0..4 {
        for x in 0..6 {
            assert_eq!(image.get(x, y), Vec3::new(x as f32, y as f32, 0.0));
        }
    }
}

#[test]
fn invalid_settings_are_rejected() {
    let good = settings(4, 4, 4, FilterKind::Gaussian, 1.5);
    assert_eq!(film::check_settings(&good), Ok(()));
    assert!(film::check_settings(&ImageSettings { samples_per_pixel: 0, ..good.clone() }).is_err());
    assert!(film::check_settings(&ImageSettings { filter_radius_px: 0.0, ..good.clone() }).is_err());
    assert!(film::check_settings(&ImageSettings { width_px: 0, ..good.clone() }).is_err());
    assert!(film::check_settings(&ImageSettings { adaptive_threshold: Some(f32::NAN), ..good }).is_err());
}

// ---------------------------------------------------------------------------------------------------
// Output
// ---------------------------------------------------------------------------------------------------

fn test_image(width_px: u32, height_px: u32, max: f32) -> Image {
    let mut rng = Pcg32::new(5, 0);
    let pixels = (0..width_px * height_px)
        .map(|_| Vec3::new(rng.next_f32() * max, rng.next_f32() * max, rng.next_f32() * max))
        .collect();
    Image { width_px, height_px, pixels }
}

fn leftover_temporaries(dir: &std::path::Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".tmp-"))
        .collect()
}

#[test]
fn exr_round_trip_is_exact_for_f32() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("radiance.exr");
    let mut image = test_image(13, 7, 100.0);
    image.pixels[0] = Vec3::new(1e-30, 65504.0 * 10.0, 0.0);
    output::write_image(&image, &path, 3.0, ToneCurve::Aces).unwrap();
    assert_eq!(output::read_image(&path).unwrap(), image);
}

#[test]
fn png_round_trip_is_within_half_a_code_value_in_srgb() {
    // Writing rounds sRGB(x)·255 to the nearest integer, so after reading back the sRGB values differ by
    // at most 0.5/255 (+1e-5 for f32 evaluation of the OETF and EOTF).
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("image.png");
    let image = test_image(11, 6, 1.0);
    output::write_png(&image, &path, 0.0, ToneCurve::Clamp).unwrap();
    let back = output::read_image(&path).unwrap();
    assert_eq!((back.width_px, back.height_px), (11, 6));
    for (a, b) in image.pixels.iter().zip(&back.pixels) {
        for c in 0..3 {
            let (sa, sb) = (output::srgb_oetf(a[c]), output::srgb_oetf(b[c]));
            assert!((sa - sb).abs() <= 0.5 / 255.0 + 1e-5, "{} vs {}", a[c], b[c]);
        }
    }
}

#[test]
fn unit_radiance_at_zero_stops_is_255_and_one_stop_doubles_radiance() {
    assert_eq!(output::tone_map_to_srgb8(Vec3::ONE, 0.0, ToneCurve::Clamp), [255; 3]);
    assert_eq!(output::tone_map_to_srgb8(Vec3::ZERO, 0.0, ToneCurve::Clamp), [0; 3]);
    // +1 stop of 0.2 is 0.4 at 0 stops (2^1 = 2 exactly, 0.2·2 = 0.4 exactly in f32).
    for v in [0.01f32, 0.1, 0.2, 0.45] {
        assert_eq!(
            output::tone_map_to_srgb8(Vec3::splat(v), 1.0, ToneCurve::Clamp),
            output::tone_map_to_srgb8(Vec3::splat(2.0 * v), 0.0, ToneCurve::Clamp)
        );
    }
    // sRGB(0.5) = 1.055·0.5^(1/2.4) − 0.055 = 0.735357 → 187.5 → 188 (0.25 at +1 stop).
    assert_eq!(output::tone_map_to_srgb8(Vec3::splat(0.25), 1.0, ToneCurve::Clamp), [188; 3]);
    // And through a file: 1.0 radiance reads back as exactly 1.0 (code value 255).
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("white.png");
    output::write_png(&Image { width_px: 1, height_px: 1, pixels: vec![Vec3::ONE] }, &path, 0.0, ToneCurve::Clamp)
        .unwrap();
    assert_eq!(output::read_image(&path).unwrap().pixels, vec![Vec3::ONE]);
}

#[test]
fn atomic_write_leaves_only_the_target_behind() {
    let dir = tempfile::tempdir().unwrap();
    let image = test_image(4, 4, 1.0);
    output::write_image(&image, &dir.path().join("a.png"), 0.0, ToneCurve::Reinhard).unwrap();
    output::write_image(&image, &dir.path().join("a.exr"), 0.0, ToneCurve::Clamp).unwrap();
    // Overwriting an existing file also goes through a temporary.
    output::write_image(&image, &dir.path().join("a.exr"), 0.0, ToneCurve::Clamp).unwrap();
    assert!(leftover_temporaries(dir.path()).is_empty());
    let mut names: Vec<String> =
        std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    names.sort();
    assert_eq!(names, ["a.exr", "a.png"]);
}

#[test]
fn failed_write_leaves_neither_target_nor_temporary() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("no-such-dir").join("out.png");
    let err = output::write_png(&test_image(2, 2, 1.0), &missing, 0.0, ToneCurve::Clamp).unwrap_err();
    assert!(matches!(err, OutputError::Write { .. }), "{err}");
    assert!(err.to_string().contains("out.png"), "{err}");
    assert!(!missing.exists());
    assert!(leftover_temporaries(dir.path()).is_empty());

    // An image that cannot be encoded (pixel count disagrees with its size) writes nothing either.
    let bad = Image { width_px: 3, height_px: 3, pixels: vec![Vec3::ZERO; 2] };
    let target = dir.path().join("bad.exr");
    assert!(matches!(output::write_exr(&bad, &target), Err(OutputError::InconsistentImage { .. })));
    assert!(!target.exists());
    assert!(leftover_temporaries(dir.path()).is_empty());
}

#[test]
fn unsupported_extensions_and_unreadable_files_are_typed_errors_naming_the_path() {
    let dir = tempfile::tempdir().unwrap();
    let tiff = dir.path().join("image.tiff");
    let err = output::write_image(&test_image(2, 2, 1.0), &tiff, 0.0, ToneCurve::Clamp).unwrap_err();
    assert!(matches!(err, OutputError::UnsupportedFormat { .. }));
    assert!(err.to_string().contains("image.tiff"));
    assert!(!tiff.exists());

    let missing = dir.path().join("missing.exr");
    let err = output::read_image(&missing).unwrap_err();
    assert!(matches!(err, OutputError::Read { .. }) && err.to_string().contains("missing.exr"), "{err}");

    let garbage = dir.path().join("garbage.png");
    std::fs::write(&garbage, b"not a png").unwrap();
    let err = output::read_image(&garbage).unwrap_err();
    assert!(matches!(err, OutputError::PngDecode { .. }) && err.to_string().contains("garbage.png"), "{err}");

    let garbage = dir.path().join("garbage.exr");
    std::fs::write(&garbage, b"not an exr").unwrap();
    let err = output::read_image(&garbage).unwrap_err();
    assert!(matches!(err, OutputError::ExrDecode { .. }) && err.to_string().contains("garbage.exr"), "{err}");
}

// ---------------------------------------------------------------------------------------------------
// Comparison
// ---------------------------------------------------------------------------------------------------

fn two_by_one(a: [f32; 3], b: [f32; 3]) -> Image {
    Image { width_px: 2, height_px: 1, pixels: vec![Vec3::from_array(a), Vec3::from_array(b)] }
}

#[test]
fn metrics_match_hand_computed_values_on_two_pixels() {
    // test x = (1,1,1),(2,0,0); ref r = (1,1,1),(1,0,0.5). Over the 6 values:
    //   d = x − r = 0,0,0, 1,0,−0.5
    //   relMSE = (1²/(1²+0.01) + 0.5²/(0.5²+0.01)) / 6 = (1/1.01 + 0.25/0.26)/6 ≈ 0.325273
    //   mean_abs_rel_err = (1/(1+0.01) + 0.5/(0.5+0.01)) / 6 = (1/1.01 + 0.5/0.51)/6 ≈ 0.328415
    //   rmse = sqrt((1 + 0.25)/6) ≈ 0.456435
    //   scale s = Σxr/Σx² = (1+1+1+2+0+0)/(1+1+1+4+0+0) = 5/7
    //   s·x − r = −2/7 (×3), 10/7 − 1 = 3/7, 0, −0.5
    //   scaled relMSE = (3·(4/49)/1.01 + (9/49)/1.01 + 0.25/0.26)/6 = ((21/49)/1.01 + 0.25/0.26)/6
    //   scaled mean_abs_rel_err = ((3·2/7 + 3/7)/1.01 + 0.5/0.51)/6 = ((9/7)/1.01 + 0.5/0.51)/6
    //   scaled rmse = sqrt((21/49 + 0.25)/6)
    //   mean_test = 5/6, mean_ref = 4.5/6; largest |d| = 1 at pixel (1, 0), channel R.
    // All inputs are exact in f32 and the sums are done in f64, so 1e-12 covers the rounding.
    let test = two_by_one([1.0, 1.0, 1.0], [2.0, 0.0, 0.0]);
    let reference = two_by_one([1.0, 1.0, 1.0], [1.0, 0.0, 0.5]);
    let m = compare::metrics(&test, &reference, None).unwrap();
    let close = |a: f64, b: f64| assert!((a - b).abs() < 1e-12, "{a} vs {b}");
    close(m.errors.rel_mse, (1.0 / 1.01 + 0.25 / 0.26) / 6.0);
    close(m.errors.mean_abs_rel_err, (1.0 / 1.01 + 0.5 / 0.51) / 6.0);
    close(m.errors.rmse, (1.25f64 / 6.0).sqrt());
    close(m.scale, 5.0 / 7.0);
    close(m.scaled.rel_mse, ((21.0 / 49.0) / 1.01 + 0.25 / 0.26) / 6.0);
    close(m.scaled.mean_abs_rel_err, ((9.0 / 7.0) / 1.01 + 0.5 / 0.51) / 6.0);
    close(m.scaled.rmse, ((21.0 / 49.0 + 0.25) / 6.0f64).sqrt());
    close(m.mean_test, 5.0 / 6.0);
    close(m.mean_ref, 4.5 / 6.0);
    assert_eq!(m.pixels, 2);
    assert_eq!(m.max_abs_diff, 1.0);
    assert_eq!(m.max_abs_diff_at, PixelChannel { x: 1, y: 0, channel: 0 });
    assert_eq!(m.non_finite_test_values, 0);

    let json = serde_json::to_value(&m).unwrap();
    for key in ["relMSE", "mean_abs_rel_err", "rmse", "scale", "scaled", "mean_test", "mean_ref", "pixels"] {
        assert!(json.get(key).is_some(), "missing {key} in {json}");
    }
}

#[test]
fn non_finite_test_values_count_as_zero_and_the_mask_selects_pixels() {
    // Test pixel 0 is NaN/∞ → (0,0,0) as compare.py's nan_to_num; with ref (1,1,1) that pixel alone
    // gives relMSE = 1/1.01, rmse = 1. Masking it out leaves pixel 1 which matches exactly.
    let test = two_by_one([f32::NAN, f32::INFINITY, f32::NEG_INFINITY], [0.5, 0.5, 0.5]);
    let reference = two_by_one([1.0, 1.0, 1.0], [0.5, 0.5, 0.5]);
    let only_first = compare::metrics(&test, &reference, Some(&[true, false])).unwrap();
    assert_eq!(only_first.non_finite_test_values, 3);
    assert!((only_first.errors.rel_mse - 1.0 / 1.01).abs() < 1e-12);
    assert!((only_first.errors.rmse - 1.0).abs() < 1e-12);
    assert_eq!(only_first.pixels, 1);
    let only_second = compare::metrics(&test, &reference, Some(&[false, true])).unwrap();
    assert_eq!(only_second.errors.rmse, 0.0);
    assert_eq!(only_second.scale, 1.0);
    assert_eq!(compare::metrics(&test, &reference, Some(&[false, false])), Err(CompareError::NothingSelected));
    assert!(matches!(compare::metrics(&test, &reference, Some(&[true])), Err(CompareError::MaskSize { .. })));
}

#[test]
fn size_mismatch_is_an_error() {
    let a = Image::new(2, 1);
    let b = Image::new(1, 2);
    assert!(matches!(compare::metrics(&a, &b, None), Err(CompareError::SizeMismatch { .. })));
    assert!(matches!(compare::difference_image(&a, &b), Err(CompareError::SizeMismatch { .. })));
}

#[test]
fn difference_image_is_uniform_dark_where_equal_and_bright_where_different() {
    let reference = two_by_one([1.0, 1.0, 1.0], [1.0, 1.0, 1.0]);
    let test = two_by_one([1.0, 1.0, 1.0], [3.0, 1.0, 1.0]);
    let diff = compare::difference_image(&test, &reference).unwrap();
    assert_eq!(diff.get(0, 0), compare::magma(0.0));
    // Relative error 2/1.01 ≥ 1 saturates the ramp.
    assert_eq!(diff.get(1, 0), compare::magma(1.0));
    assert!(compare::magma(1.0).length() > compare::magma(0.5).length());
    assert!(compare::magma(0.5).length() > compare::magma(0.0).length());
}

#[test]
fn side_by_side_places_images_left_to_right_padding_with_black() {
    let a = Image { width_px: 1, height_px: 2, pixels: vec![Vec3::X, Vec3::Y] };
    let b = Image { width_px: 2, height_px: 1, pixels: vec![Vec3::Z, Vec3::ONE] };
    let s = compare::side_by_side(&[&a, &b]);
    assert_eq!((s.width_px, s.height_px), (3, 2));
    assert_eq!(s.pixels, vec![Vec3::X, Vec3::Z, Vec3::ONE, Vec3::Y, Vec3::ZERO, Vec3::ZERO]);
    assert_eq!(compare::side_by_side(&[]), Image::new(0, 0));
}
