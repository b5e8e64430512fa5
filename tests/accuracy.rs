//! Accuracy against an independent renderer: radray's images of the canonical scenes compared with
//! converged Mitsuba 3 path-traced references (`references/*/reference.exr`, 256×256, box filter), by
//! the metrics of `references/compare.py`. On failure the test writes the image and a difference
//! image to `target/accuracy/`.

use radray::compare;
use radray::film::Image;
use radray::progress::Progress;
use radray::run::{self, RunStats};
use radray::scene::Overrides;
use radray::scene::{DirectMode, FilterKind, MethodChoice, SceneDescription};
use radray::trace::TraceMode;
use radray::transport::photons::RunPhotons;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn load(scene: &str) -> SceneDescription {
    let progress = Progress::hidden();
    let mut s = run::load_scene(&root().join("scenes").join(scene), &Overrides::default(), &progress).unwrap();
    // The references use a box filter over each pixel at 256×256.
    s.image.width_px = 256;
    s.image.height_px = 256;
    s.image.filter = FilterKind::Box;
    s.image.filter_radius_px = 0.5;
    s
}

/// Renders `scene` in each mode with one radiosity solution.
fn render(scene: &SceneDescription, modes: &[TraceMode]) -> Vec<Image> {
    let progress = Progress::hidden();
    let mut stats = RunStats::default();
    let photons = RunPhotons::default();
    let (mesh, solution) = run::pass_one(scene, None, &photons, &progress, &mut stats).unwrap();
    let accel = radray::accel::Accel::build(&mesh.positions, &mesh.triangles);
    modes
        .iter()
        .map(|&m| run::render(scene, &mesh, &accel, &solution, m, &photons, &progress, &mut stats).unwrap())
        .collect()
}

fn reference(name: &str) -> Image {
    radray::output::read_image(&root().join("references").join(name).join("reference.exr")).unwrap()
}

/// Writes the image and its difference image for a failed comparison; returns where.
fn keep_for_inspection(tag: &str, image: &Image, reference: &Image) -> PathBuf {
    let dir = root().join("target").join("accuracy");
    std::fs::create_dir_all(&dir).unwrap();
    radray::output::write_exr(image, &dir.join(format!("{tag}.exr"))).unwrap();
    let diff = compare::difference_image(image, reference).unwrap();
    radray::output::write_png(&diff, &dir.join(format!("{tag}.diff.png")), 0.0, Default::default()).unwrap();
    dir
}

/// Asserts relMSE and mean absolute relative error bounds, keeping the images on failure.
fn assert_close(tag: &str, image: &Image, reference: &Image, rel_mse: f64, mare: f64) -> compare::Metrics {
    let m = compare::metrics(image, reference, None).unwrap();
    println!(
        "{tag}: relMSE {:.5} mean abs rel err {:.4} rmse {:.4}",
        m.errors.rel_mse, m.errors.mean_abs_rel_err, m.errors.rmse
    );
    if m.errors.rel_mse > rel_mse || m.errors.mean_abs_rel_err > mare {
        let dir = keep_for_inspection(tag, image, reference);
        panic!(
            "{tag}: relMSE {:.5} (bound {rel_mse}), mean abs rel err {:.4} (bound {mare}); images in {}",
            m.errors.rel_mse,
            m.errors.mean_abs_rel_err,
            dir.display()
        );
    }
    m
}

#[test]
fn furnace_is_two_everywhere_in_both_modes() {
    let mut scene = load("furnace.toml");
    scene.image.width_px = 64;
    scene.image.height_px = 64;
    // The mesh's furnace: direct light from the solution, as the bound below assumes (the default
    // per-pixel shadow rays add their own noise: `furnace_is_two_everywhere_with_per_pixel_direct_light`).
    // So is the gather's second bounce off, for the same reason: its shadow rays at near hits see the
    // emitting walls next to them (tests/final_gather.rs checks its mean in the furnace).
    scene.render.direct = DirectMode::Radiosity;
    scene.render.near_bounce = Some(0.0);
    for image in render(&scene, &[TraceMode::Radiosity, TraceMode::Final]) {
        // Exact: L = Ke/(1 − Kd) = 2 everywhere. 1 % is the issue's bound; the hemicube's row sums are
        // within ~1e-3 of one, amplified by 1/(1 − ρ) = 2.
        for p in &image.pixels {
            for c in p.to_array() {
                assert!((c - 2.0).abs() <= 0.02, "pixel {c}");
            }
        }
    }
}

/// Emitters resting on faces (scenes/rooms/fixture_room: a fixture hung on the ceiling, a glowing
/// cube in a corner). The uniform mesh does not follow their outlines, and its elements that straddle
/// them are measured at their open part (`burial::bury`), where the ceiling's brightest strip lies.
/// Measured at their centres, under the fixture, they reflected nothing and the whole room came out
/// 3.9% dark (mean 0.6423 against the reference's 0.6681, sessions 31–32); now 0.25% bright.
#[test]
fn a_uniform_mesh_straddling_fixtures_keeps_their_light() {
    let mut scene = load("rooms/fixture_room.toml");
    scene.radiosity.method = MethodChoice::Matrix;
    let image = &render(&scene, &[TraceMode::Radiosity])[0];
    let m = compare::metrics(image, &reference("fixture_room"), None).unwrap();
    let ratio = m.mean_test / m.mean_ref;
    assert!((ratio - 1.0).abs() < 0.01, "mean {:.4} against the reference's {:.4}", m.mean_test, m.mean_ref);
}

/// The furnace at the default settings: per-pixel shadow rays and the gather's second bounce, whose
/// shadow rays land on the emitting walls beside the point they leave. Sampled by area, those walls
/// weighed their few points near the seam by cos θ cos θ'/r²: 18% of the pixels were more than 5%
/// off and the brightest was 51 (session 5 to 31). Emitters close to the receiver are now sampled by
/// solid angle (`transport::solid_angle`), so a sample weighs at most L·Ω. Over the uniform mesh and
/// the hierarchy, 64², seeds 0–2: at most 0.9% of pixels beyond 5% and 0.02% beyond 10% (10.2% at
/// worst), relMSE against 2 at most 3.3e-4.
#[test]
fn furnace_is_two_everywhere_with_per_pixel_direct_light() {
    for method in [MethodChoice::Matrix, MethodChoice::Hierarchical] {
        let mut scene = load("furnace.toml");
        scene.image.width_px = 64;
        scene.image.height_px = 64;
        scene.radiosity.method = method;
        let image = render(&scene, &[TraceMode::Final]).remove(0);
        let deviations: Vec<f32> =
            image.pixels.iter().flat_map(|p| p.to_array()).map(|c| (c / 2.0 - 1.0).abs()).collect();
        let n = deviations.len() as f32;
        let beyond_5 = deviations.iter().filter(|&&d| d > 0.05).count() as f32 / n;
        let worst = deviations.iter().fold(0.0f32, |a, &d| a.max(d));
        let rel_mse = deviations.iter().map(|d| d * d).sum::<f32>() / n;
        let mean = image.pixels.iter().map(|p| p.x + p.y + p.z).sum::<f32>() / n;
        println!("{method:?}: mean {mean:.4}, beyond 5% {beyond_5:.4}, worst {worst:.3}, relMSE {rel_mse:.2e}");
        assert!((mean / 2.0 - 1.0).abs() < 0.01, "{method:?}: mean {mean}");
        assert!(beyond_5 <= 0.02 && worst <= 0.15 && rel_mse <= 6e-4, "{method:?}: {beyond_5} {worst} {rel_mse}");
    }
}

/// The two canonical Cornell boxes at the default preset with per-pixel direct light, each as
/// (reference name, radiosity-mode image, final image) from one radiosity solution. Both Cornell tests
/// read it: the radiosity mode does not depend on the direct estimator, so one pass one per scene
/// serves both, solved once per test binary.
fn cornell_images() -> &'static [(&'static str, Image, Image)] {
    static IMAGES: OnceLock<Vec<(&'static str, Image, Image)>> = OnceLock::new();
    IMAGES.get_or_init(|| {
        [("cornell_box.toml", "cornell_original"), ("cornell_empty.toml", "cornell_empty")]
            .into_iter()
            .map(|(scene, reference_name)| {
                let mut s = load(scene);
                s.render.direct = DirectMode::Pixel;
                let [radiosity, final_]: [Image; 2] =
                    render(&s, &[TraceMode::Radiosity, TraceMode::Final]).try_into().unwrap();
                (reference_name, radiosity, final_)
            })
            .collect()
    })
}

#[test]
fn cornell_boxes_in_radiosity_mode_match_the_path_tracer_at_64_spp() {
    // Bounds: the path tracer's own error at 64 samples per pixel (references/README.md).
    for (reference_name, image, _) in cornell_images() {
        assert_close(&format!("{reference_name}.radiosity"), image, &reference(reference_name), 0.003, 0.065);
    }
}

#[test]
fn cornell_boxes_with_per_pixel_direct_light_match_the_path_tracer_at_256_spp() {
    // Bounds: the path tracer's own error at 256 samples per pixel (references/README.md).
    for (reference_name, _, image) in cornell_images() {
        assert_close(&format!("{reference_name}.final_pixel"), image, &reference(reference_name), 0.0007, 0.033);
    }
}

/// Final and pure-radiosity renders of the specular Cornell box with per-pixel direct light, and their
/// metrics against the reference. The tests that use it check the Whitted pass's mirror and glass
/// images and the issue's bound, not the default preset's accuracy (the Cornell boxes above do), so
/// they leave out the default's gather second bounce and adaptive samples: a cheaper and slightly
/// noisier final image held to the same bounds.
fn specular_metrics(hemicube_resolution_px: u32) -> (Image, compare::Metrics, compare::Metrics) {
    let mut s = load("cornell_specular.toml");
    s.render.direct = DirectMode::Pixel;
    s.render.near_bounce = Some(0.0);
    s.image.adaptive_error = None;
    s.radiosity.hemicube_resolution_px = hemicube_resolution_px;
    let mut images = render(&s, &[TraceMode::Final, TraceMode::Radiosity]);
    let r = reference("cornell_specular");
    let final_ = compare::metrics(&images[0], &r, None).unwrap();
    let radiosity = compare::metrics(&images[1], &r, None).unwrap();
    println!(
        "cornell_specular: final relMSE {:.5}, radiosity relMSE {:.5}",
        final_.errors.rel_mse, radiosity.errors.rel_mse
    );
    (images.swap_remove(0), final_, radiosity)
}

#[test]
fn specular_cornell_box_final_is_closer_than_pure_radiosity() {
    // The Whitted pass adds the mirror and glass images that pure radiosity shows as black.
    let (image, final_, radiosity) = specular_metrics(128);
    if final_.errors.rel_mse >= radiosity.errors.rel_mse {
        let dir = keep_for_inspection("cornell_specular.final", &image, &reference("cornell_specular"));
        panic!(
            "final {:.5} not below radiosity {:.5}; images in {}",
            final_.errors.rel_mse,
            radiosity.errors.rel_mse,
            dir.display()
        );
    }
}

#[test]
fn specular_cornell_box_final_is_within_the_issue_bound() {
    // Issue 5 asked for 0.005, over every pixel (nothing masked). The reference's caustics reach radray as
    // light traced from the emitter through the spheres (`trace::caustics`): pass one's extended form
    // factors to the emitter come from those photons, and pass two sharpens them per pixel by density
    // estimation. Measured 0.00157 at `specular_metrics`'s settings (session 6); 0.00050 when the
    // caustic photons landed, at that time's settings; 0.0075 before, when the caustic came from
    // hemicube paths at element resolution. With the final gather on (the scene's default) it was
    // 0.00175 while the gather rays also counted the lamp seen through the spheres, on top of the
    // photons' detail (session 22); 0.00054 once the gather left that light to the photons, 0.00050
    // with the wide caustic kernel. The bound is held at 0.001 so that such a double count cannot
    // come back unseen.
    let (image, final_, radiosity) = specular_metrics(256);
    println!(
        "cornell_specular (hemicube 256): final relMSE {:.5} MARE {:.4}, radiosity relMSE {:.5} MARE {:.4}",
        final_.errors.rel_mse,
        final_.errors.mean_abs_rel_err,
        radiosity.errors.rel_mse,
        radiosity.errors.mean_abs_rel_err
    );
    if final_.errors.rel_mse > 0.001 || final_.errors.rel_mse >= radiosity.errors.rel_mse {
        let dir = keep_for_inspection("cornell_specular.final", &image, &reference("cornell_specular"));
        panic!(
            "relMSE {:.5} above 0.001 (or not below radiosity's {:.5}); images in {}",
            final_.errors.rel_mse,
            radiosity.errors.rel_mse,
            dir.display()
        );
    }
}
