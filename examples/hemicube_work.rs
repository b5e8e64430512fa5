//! Draws the form-factor hemicubes of a scene's uniform mesh (all rows, or an evenly spaced sample)
//! and prints their counted work and its time, the measurements behind `matrix::cost`:
//! `cargo run --release --example hemicube_work -- SCENE.toml|procedural:TRIANGLES
//! [preview|default|high|scene] [ROWS]` (a procedural room keeps its 128² hemicubes).

use std::process::ExitCode;
use std::time::Instant;

use radray::mesh::Mesh;
use radray::radiosity::matrix::cost;
use radray::radiosity::method;
use radray::radiosity::specular::SpecularPaths;
use radray::scene::Quality;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().collect();
    let Some(path) = args.get(1) else {
        eprintln!("usage: hemicube_work SCENE.toml|procedural:TRIANGLES [preview|default|high|scene] [ROWS]");
        return ExitCode::FAILURE;
    };
    let procedural = path.strip_prefix("procedural:").and_then(|n| n.parse().ok());
    let mut scene = match procedural {
        Some(triangles) => radray::radiosity::hierarchy::procedural::room_with_objects(triangles),
        None => match radray::scene::load(std::path::Path::new(path)) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("{e}");
                return ExitCode::FAILURE;
            }
        },
    };
    match args.get(2).map(String::as_str) {
        Some("preview") => scene.apply_quality(Quality::Preview),
        Some("default") => scene.apply_quality(Quality::Default),
        Some("high") => scene.apply_quality(Quality::High),
        Some("scene") | None => {}
        Some(other) => {
            eprintln!("unknown quality `{other}`");
            return ExitCode::FAILURE;
        }
    }
    let sample: Option<usize> = args.get(3).and_then(|s| s.parse().ok());
    let params = &scene.radiosity;
    let mesh = Mesh::build(&scene, params.max_element_edge);
    let rows = cost::rows_needed(&mesh);
    let drawn = sample.map_or_else(|| rows.clone(), |k| cost::sample_rows(&rows, k));
    let accel = method::specular_accel(&scene, &mesh);
    let paths =
        accel.as_ref().map(|a| SpecularPaths::new(&mesh, a, &scene.materials).with_shading_normals(&scene.surfaces));
    let start = Instant::now();
    let work = cost::measure_work(&mesh, params, paths.as_ref(), &drawn);
    let seconds = start.elapsed().as_secs_f64();
    println!(
        "{{\"scene\": \"{path}\", \"elements\": {}, \"rows\": {}, \"resolution_px\": {}, \"work\": {}, \"seconds\": {seconds:.3}, \"model_cpu_seconds\": {:.3}}}",
        mesh.elements.len(),
        rows.len(),
        params.hemicube_resolution_px,
        serde_json::to_string(&work).unwrap_or_default(),
        work.cpu_seconds(params.hemicube_resolution_px)
    );
    ExitCode::SUCCESS
}
