//! Fixtures shared by the integration tests and the benches: scenes built in code (the Cornell box,
//! quads, one-sided surfaces), the usual materials, hand-made radiosity solutions and the `radray`
//! binary runner. Benches include this file with `#[path = "../tests/common/mod.rs"] mod common;`.

// Each test binary compiles its own copy of this module and uses only some of the fixtures.
#![allow(dead_code)]

use std::path::PathBuf;
use std::process::{Command, Output};

use glam::{vec3, DVec3, Vec3};
use radray::accel::Accel;
use radray::mesh::Mesh;
use radray::progress::Progress;
use radray::radiosity::smooth_mesh::SmoothMesh;
use radray::radiosity::solution::{Solution, SolveStats};
use radray::run::{self, RunStats};
use radray::scene::{
    Camera, ImageSettings, Material, RadiosityParams, RenderParams, SceneDescription, SolverKind, SourceLoc, Surface,
};
use radray::trace::Tracer;
use radray::transport::photons::RunPhotons;

/// Runs the `radray` binary built for these tests with `args`.
pub fn radray(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_radray")).args(args).output().expect("the radray binary runs")
}

/// A surface of the given corners (counter-clockwise about its front) and material index, with no
/// shading normals, no object name and no source location.
pub fn surface(vertices: impl Into<Vec<Vec3>>, material: u32, two_sided: bool) -> Surface {
    Surface {
        vertices: vertices.into(),
        material,
        two_sided,
        shading_normals: None,
        uvs: None,
        object: String::new(),
        source: SourceLoc::default(),
    }
}

/// Quad in the plane z = `z`, side 2·`half`, facing +z (or −z).
pub fn z_quad(z: f32, half: f32, facing_plus_z: bool, material: u32, two_sided: bool) -> Surface {
    let (a, b, c, d) = (vec3(-half, -half, z), vec3(half, -half, z), vec3(half, half, z), vec3(-half, half, z));
    if facing_plus_z {
        surface([a, b, c, d], material, two_sided)
    } else {
        surface([a, d, c, b], material, two_sided)
    }
}

/// A scene description of `materials` and `surfaces` with default settings, seen from z = 5 towards the
/// origin (tests that render choose their own camera).
pub fn scene(materials: Vec<Material>, surfaces: Vec<Surface>) -> SceneDescription {
    SceneDescription {
        path: PathBuf::from("test.scene"),
        camera: Camera { eye: vec3(0.0, 0.0, 5.0), look_at: Vec3::ZERO, up: Vec3::Y, vfov_deg: 40.0 },
        image: ImageSettings::default(),
        radiosity: RadiosityParams::default(),
        render: RenderParams::default(),
        materials,
        surfaces,
        warnings: Vec::new(),
    }
}

/// Radiosity settings for form-factor tests: hemicubes of `resolution_px` that are never rotated, so
/// results are reproducible sample for sample.
pub fn hemicube_params(resolution_px: u32) -> RadiosityParams {
    RadiosityParams { hemicube_resolution_px: resolution_px, rotate_hemicubes: false, ..Default::default() }
}

/// A black material emitting `radiance` (Ke).
pub fn emitter(name: &str, radiance: Vec3) -> Material {
    Material { emitted_radiance: radiance, ..Material::diffuse(name, Vec3::ZERO) }
}

/// A black mirror of reflectance `ks` (Ks).
pub fn mirror(name: &str, ks: f32) -> Material {
    Material { specular_reflectance: Vec3::splat(ks), ..Material::diffuse(name, Vec3::ZERO) }
}

/// Clear glass: Ks 1, Ni 1.5, d 0.
pub fn glass(name: &str) -> Material {
    Material { specular_reflectance: Vec3::ONE, ior: 1.5, transmittance: 1.0, ..Material::diffuse(name, Vec3::ZERO) }
}

/// The Cornell box's camera (published data): from z = −800 mm through the open front.
pub fn cornell_camera() -> Camera {
    Camera { eye: vec3(278.0, 273.0, -800.0), look_at: vec3(278.0, 273.0, 0.0), up: Vec3::Y, vfov_deg: 39.307_648 }
}

/// The Cornell box's white, red and green reflectances and its light's radiance, as materials 0 to 3.
pub fn cornell_materials() -> Vec<Material> {
    vec![
        Material::diffuse("white", vec3(0.725, 0.71, 0.68)),
        Material::diffuse("red", vec3(0.63, 0.065, 0.05)),
        Material::diffuse("green", vec3(0.14, 0.45, 0.091)),
        emitter("light", vec3(17.0, 12.0, 4.0)),
    ]
}

/// The Cornell box (published coordinates, mm; light lowered to y = 548.7; open front), copied from
/// the reference scene.obj: (material, quad) with 0 white, 1 red, 2 green, 3 light.
const CORNELL: &[(u32, [[f32; 3]; 4])] = &[
    (0, [[552.8, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 559.2], [549.6, 0.0, 559.2]]),
    (0, [[556.0, 548.8, 0.0], [556.0, 548.8, 559.2], [0.0, 548.8, 559.2], [0.0, 548.8, 0.0]]),
    (0, [[549.6, 0.0, 559.2], [0.0, 0.0, 559.2], [0.0, 548.8, 559.2], [556.0, 548.8, 559.2]]),
    (1, [[552.8, 0.0, 0.0], [549.6, 0.0, 559.2], [556.0, 548.8, 559.2], [556.0, 548.8, 0.0]]),
    (2, [[0.0, 0.0, 559.2], [0.0, 0.0, 0.0], [0.0, 548.8, 0.0], [0.0, 548.8, 559.2]]),
    (3, [[343.0, 548.7, 227.0], [343.0, 548.7, 332.0], [213.0, 548.7, 332.0], [213.0, 548.7, 227.0]]),
    (0, [[130.0, 165.0, 65.0], [82.0, 165.0, 225.0], [240.0, 165.0, 272.0], [290.0, 165.0, 114.0]]),
    (0, [[290.0, 0.0, 114.0], [290.0, 165.0, 114.0], [240.0, 165.0, 272.0], [240.0, 0.0, 272.0]]),
    (0, [[130.0, 0.0, 65.0], [130.0, 165.0, 65.0], [290.0, 165.0, 114.0], [290.0, 0.0, 114.0]]),
    (0, [[82.0, 0.0, 225.0], [82.0, 165.0, 225.0], [130.0, 165.0, 65.0], [130.0, 0.0, 65.0]]),
    (0, [[240.0, 0.0, 272.0], [240.0, 165.0, 272.0], [82.0, 165.0, 225.0], [82.0, 0.0, 225.0]]),
    (0, [[423.0, 330.0, 247.0], [265.0, 330.0, 296.0], [314.0, 330.0, 456.0], [472.0, 330.0, 406.0]]),
    (0, [[423.0, 0.0, 247.0], [423.0, 330.0, 247.0], [472.0, 330.0, 406.0], [472.0, 0.0, 406.0]]),
    (0, [[472.0, 0.0, 406.0], [472.0, 330.0, 406.0], [314.0, 330.0, 456.0], [314.0, 0.0, 456.0]]),
    (0, [[314.0, 0.0, 456.0], [314.0, 330.0, 456.0], [265.0, 330.0, 296.0], [265.0, 0.0, 296.0]]),
    (0, [[265.0, 0.0, 296.0], [265.0, 330.0, 296.0], [423.0, 330.0, 247.0], [423.0, 0.0, 247.0]]),
];

/// The Cornell box as a scene description: 16 one-sided quads, the materials of [`cornell_materials`],
/// seen from [`cornell_camera`].
pub fn cornell() -> SceneDescription {
    let surfaces = CORNELL.iter().map(|(material, quad)| surface(quad.map(Vec3::from), *material, false)).collect();
    SceneDescription { camera: cornell_camera(), ..scene(cornell_materials(), surfaces) }
}

/// A hand-made solution: per-element exitance and its direct part, vertex values as the solver makes
/// them on the uniform mesh (`SmoothMesh::vertex_values`, in f64).
pub fn solution(mesh: &Mesh, exitance: Vec<Vec3>, direct: Vec<Vec3>) -> Solution {
    let vertex_step = SmoothMesh::new(mesh);
    let average = |values: &[Vec3]| -> Vec<Vec3> {
        let wide: Vec<DVec3> = values.iter().map(|v| v.as_dvec3()).collect();
        vertex_step.vertex_values(&wide)
    };
    Solution {
        vertex_exitance: average(&exitance),
        vertex_direct_exitance: average(&direct),
        element_exitance: exitance,
        element_direct_exitance: direct,
        mesh_fingerprint: 0,
        stats: SolveStats {
            solver: SolverKind::GaussSeidel,
            iterations: 0,
            residual_history: Vec::new(),
            converged: true,
        },
        leaf_geometry: None,
        refinement: None,
        holds_caustic_light: true,
    }
}

/// One of the analytic validation cases in `tests/data/` (form factors, enclosures, the furnace).
pub fn validation_json(name: &str) -> serde_json::Value {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(name);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// A validation case's 3-vector.
pub fn json_vec3(v: &serde_json::Value) -> Vec3 {
    let a = v.as_array().expect("a 3-vector");
    Vec3::new(a[0].as_f64().unwrap() as f32, a[1].as_f64().unwrap() as f32, a[2].as_f64().unwrap() as f32)
}

/// A validation case's vertex list.
pub fn json_polygon(v: &serde_json::Value) -> Vec<Vec3> {
    v.as_array().expect("a vertex list").iter().map(json_vec3).collect()
}

/// One `[[job]]` table of a batch file: a tiny preview render of `scene` to `output` (a TOML value,
/// e.g. `"a.png"` or `["a.png", "a.exr"]`), 16 pixels wide and `height` high, 1 spp, plus the
/// `extra` key lines.
pub fn small_batch_job(scene: &str, output: &str, height: u32, extra: &str) -> String {
    format!(
        "[[job]]\nscene = \"{scene}\"\noutput = {output}\nwidth = 16\nheight = {height}\nspp = 1\n\
         quality = \"preview\"\n{extra}\n"
    )
}

/// A scene ready for pass two: its mesh, BVH, a radiosity solution and the materials.
pub struct Setup {
    pub mesh: Mesh,
    pub accel: Accel,
    pub solution: Solution,
    pub materials: Vec<Material>,
}

impl Setup {
    /// A hand-made solution on `scene` meshed at `max_edge`: `exitance(mesh)` gives each element's
    /// exitance B and its direct part.
    pub fn hand_made(
        scene: &SceneDescription,
        max_edge: f32,
        exitance: impl Fn(&Mesh) -> (Vec<Vec3>, Vec<Vec3>),
    ) -> Setup {
        let mesh = Mesh::build(scene, max_edge);
        let accel = Accel::build(&mesh.positions, &mesh.triangles);
        let (b, direct) = exitance(&mesh);
        let solution = solution(&mesh, b, direct);
        Setup { mesh, accel, solution, materials: scene.materials.clone() }
    }

    /// Pass one as `radray render` runs it.
    pub fn solved(scene: &SceneDescription) -> Setup {
        let mut stats = RunStats::default();
        let (mesh, solution) =
            run::pass_one(scene, None, &RunPhotons::default(), &Progress::hidden(), &mut stats).unwrap();
        let accel = Accel::build(&mesh.positions, &mesh.triangles);
        Setup { mesh, accel, solution: (*solution).clone(), materials: scene.materials.clone() }
    }

    /// The tracer with the default render settings.
    pub fn tracer(&self) -> Tracer<'_> {
        self.tracer_with(&RenderParams::default())
    }

    pub fn tracer_with(&self, params: &RenderParams) -> Tracer<'_> {
        Tracer::new(&self.mesh, &self.accel, &self.solution, &self.materials, params).expect("consistent inputs")
    }
}
