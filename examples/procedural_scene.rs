//! Writes a procedural room of about N input triangles (`hierarchy::procedural::room_with_objects`) as
//! a scene the binary reads: OUT_DIR/scene.obj, scene.mtl and scene.toml (`method = "hierarchical"`).
//! `docs/scaling.py` drives it to measure how pass one scales:
//! `cargo run --release --example procedural_scene -- TRIANGLES OUT_DIR`.

use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;

use radray::radiosity::hierarchy::procedural;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().collect();
    let (Some(count), Some(out)) = (args.get(1).and_then(|c| c.parse::<usize>().ok()), args.get(2)) else {
        eprintln!("usage: procedural_scene TRIANGLES OUT_DIR");
        return ExitCode::FAILURE;
    };
    let scene = procedural::room_with_objects(count);
    let dir = PathBuf::from(out);
    let mut mtl = String::new();
    for m in &scene.materials {
        let (kd, ke) = (m.diffuse_reflectance, m.emitted_radiance);
        let _ = writeln!(mtl, "newmtl {}\nKd {} {} {}\nKe {} {} {}\n", m.name, kd.x, kd.y, kd.z, ke.x, ke.y, ke.z);
    }
    let mut obj = String::from("mtllib scene.mtl\n");
    let mut vertices = 0usize;
    let mut material = u32::MAX;
    for s in &scene.surfaces {
        if s.material != material {
            material = s.material;
            let _ = writeln!(obj, "usemtl {}", scene.materials[material as usize].name);
        }
        for v in &s.vertices {
            let _ = writeln!(obj, "v {} {} {}", v.x, v.y, v.z);
        }
        let face: Vec<String> = (0..s.vertices.len()).map(|k| (vertices + k + 1).to_string()).collect();
        let _ = writeln!(obj, "f {}", face.join(" "));
        vertices += s.vertices.len();
    }
    let c = &scene.camera;
    let toml = format!(
        "# A procedural room of about {count} input triangles (radray's examples/procedural_scene.rs).\n\
         [camera]\neye = [{}, {}, {}]\nlook_at = [{}, {}, {}]\nvfov_deg = {}\n\n\
         [radiosity]\nmethod = \"hierarchical\"\n\n[[mesh]]\nobj = \"scene.obj\"\n",
        c.eye.x, c.eye.y, c.eye.z, c.look_at.x, c.look_at.y, c.look_at.z, c.vfov_deg
    );
    let written = std::fs::create_dir_all(&dir)
        .and_then(|()| std::fs::write(dir.join("scene.mtl"), mtl))
        .and_then(|()| std::fs::write(dir.join("scene.obj"), obj))
        .and_then(|()| std::fs::write(dir.join("scene.toml"), toml));
    match written {
        Ok(()) => {
            println!("{} surfaces in {}", scene.surfaces.len(), dir.display());
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("{}: {e}", dir.display());
            ExitCode::FAILURE
        }
    }
}
