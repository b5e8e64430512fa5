//! Criterion benches of the film: per-sample overhead with a trivial shader (512×512, 16 spp, per
//! filter) and the comparison metrics on 512×512 images.
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use glam::Vec3;
use radray::compare;
use radray::film::{self, Image};
use radray::rng::Pcg32;
use radray::scene::{FilterKind, ImageSettings};
use std::hint::black_box;

fn film_overhead(c: &mut Criterion) {
    let mut group = c.benchmark_group("film_512x512x16spp");
    group.sample_size(10);
    group.throughput(Throughput::Elements(512 * 512 * 16));
    for (name, filter, radius_px) in [
        ("box", FilterKind::Box, 0.5),
        ("gaussian", FilterKind::Gaussian, 1.5),
        ("mitchell", FilterKind::Mitchell, 2.0),
    ] {
        let settings = ImageSettings {
            width_px: 512,
            height_px: 512,
            samples_per_pixel: 16,
            filter,
            filter_radius_px: radius_px,
            adaptive_threshold: None,
            adaptive_error: None,
            adaptive_max_samples: 16,
            adaptive_budget: film::DEFAULT_ADAPTIVE_BUDGET,
            seed: 1,
            exposure: Default::default(),
        };
        group.bench_function(name, |b| {
            b.iter(|| film::render(black_box(&settings), |x, y, _| Vec3::new(x, y, 1.0), &|| {}))
        });
    }
    group.finish();
}

fn noisy_image(seed: u64) -> Image {
    let mut rng = Pcg32::new(seed, 0);
    let pixels = (0..512 * 512).map(|_| Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32())).collect();
    Image { width_px: 512, height_px: 512, pixels }
}

fn metrics(c: &mut Criterion) {
    let (test, reference) = (noisy_image(1), noisy_image(2));
    let mut group = c.benchmark_group("compare_512x512");
    group.throughput(Throughput::Elements(512 * 512));
    group.bench_function("metrics", |b| b.iter(|| compare::metrics(black_box(&test), black_box(&reference), None)));
    group.bench_function("difference_image", |b| {
        b.iter(|| compare::difference_image(black_box(&test), black_box(&reference)))
    });
    group.finish();
}

criterion_group!(benches, film_overhead, metrics);
criterion_main!(benches);
