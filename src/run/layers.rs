//! A job's layered EXR (`render --layers FILE.exr`, the batch key `layers`): the final image split
//! into its parts (`trace::RadianceParts`: direct, indirect, specular, emitted, which add up to the
//! beauty), the pure radiosity image, and the first hit's albedo, world-space normal and depth.

use std::path::Path;
use std::time::Instant;

use glam::Vec3;

use super::{render, tracer_for, Failure, RunStats};
use crate::accel::Accel;
use crate::film::{self, Sampler};
use crate::mesh::Mesh;
use crate::output::{self, Layers};
use crate::progress::Progress;
use crate::radiosity::Solution;
use crate::scene::SceneDescription;
use crate::trace::camera::PinholeCamera;
use crate::trace::whitted::{RayCounts, TraceMode};
use crate::trace::RadianceParts;
use crate::transport::photons::RunPhotons;

/// Refuses a layers path that is not `.exr` or whose directory does not exist, before any work.
pub fn check_layers_path(path: &Path) -> Result<(), Failure> {
    if !path.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr")) {
        return Err(Failure::input(anyhow::anyhow!("{}: layers are written as OpenEXR (.exr)", path.display())));
    }
    super::check_output_directory(path)
}

/// Renders the layers of `scene` and writes them to `path` (one EXR; names in `output::layers`).
pub fn write_layers(
    scene: &SceneDescription,
    mesh: &Mesh,
    solution: &Solution,
    path: &Path,
    photons: &RunPhotons,
    progress: &Progress,
    stats: &mut RunStats,
) -> Result<(), Failure> {
    let accel = Accel::build(&mesh.positions, &mesh.triangles);
    let image = &scene.image;
    let camera = PinholeCamera::new(&scene.camera, image.width_px, image.height_px);
    let tracer = tracer_for(scene, mesh, &accel, solution, TraceMode::Final, photons, progress, stats)?;
    let stages = super::film_stages::FilmStages::start(progress, "render layers", image);
    let start = Instant::now();
    let (parts, film_stats, counts) = film::render_samples_with(
        image,
        RayCounts::default,
        |counts: &mut RayCounts, x, y, sampler: &mut Sampler| {
            let ray = camera.ray(x, y);
            tracer.radiance_parts(ray.origin, ray.dir, sampler, counts)
        },
        &stages,
    );
    let total: RayCounts = counts.into_iter().sum();
    stats.render_seconds += start.elapsed().as_secs_f64();
    stats.primary_rays += total.primary;
    stats.secondary_rays += total.secondary;
    stats.shadow_rays += total.shadow;
    stats.samples += film_stats.samples;
    stats.adaptive_extra_samples += film_stats.adaptive_extra_samples;
    stats.adaptive_pixels += film_stats.adaptive_pixels;
    stats.adaptive_seconds += stages.finish(&format!("{}×{} layers", image.width_px, image.height_px));
    let radiosity = render(scene, mesh, &accel, solution, TraceMode::Radiosity, photons, progress, stats)?;

    let layer = |get: fn(&RadianceParts) -> Vec3| parts.iter().map(get).collect::<Vec<Vec3>>();
    let layers = Layers {
        width_px: image.width_px,
        height_px: image.height_px,
        beauty: layer(|p| p.beauty),
        rgb: vec![
            ("direct".into(), layer(|p| p.direct)),
            ("indirect".into(), layer(|p| p.indirect)),
            ("specular".into(), layer(|p| p.specular)),
            ("emitted".into(), layer(|p| p.emitted)),
            ("radiosity".into(), radiosity.pixels),
            ("albedo".into(), layer(|p| p.albedo)),
            ("normal".into(), layer(|p| p.normal)),
        ],
        scalar: vec![("depth.Z".into(), parts.iter().map(|p| p.depth).collect())],
    };
    output::write_layered_exr(&layers, path)?;
    Ok(())
}
