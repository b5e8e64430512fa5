//! `radray info`: what a scene holds and what solving it will cost, reported before anything is
//! solved, with the suspicious geometry that usually causes light leaks.

use crate::mesh;
use crate::radiosity::adaptive::Adaptive;
use crate::radiosity::method::PassOneMethod;
use crate::radiosity::{hierarchical, hierarchy, method};
use crate::scene::{MethodChoice, SceneDescription};
use crate::trace::back_faces::{self, BackFaceShare};

/// One emitting material's share of the scene.
#[derive(Debug, Clone, serde::Serialize)]
pub struct EmitterInfo {
    pub material: String,
    pub surfaces: usize,
    pub area: f64,
    /// Emitted power Φ = π·Ke·A per channel (scene units: radiance × area).
    pub power: [f64; 3],
}

#[derive(Debug, Clone, serde::Serialize)]
pub struct InfoReport {
    pub scene: String,
    pub surfaces: usize,
    pub materials: usize,
    /// Triangle pairs the mesher takes as quads (`mesh::pair_triangles`).
    pub triangle_pairs: usize,
    pub elements: u64,
    pub max_element_edge: f32,
    pub hemicube_resolution_px: u32,
    pub solver: String,
    /// The pass-one method the scene will use, and for `method = "auto"` why (`method::auto_method`).
    pub pass_one_method: String,
    pub emitters: Vec<EmitterInfo>,
    /// Predicted size of the form-factor matrix (`radiosity::form_factors::estimate`).
    pub estimated_form_factor_bytes: u64,
    /// Predicted hemicube time on this machine's cores (`radiosity::form_factors::estimate`).
    pub estimated_form_factor_seconds: f64,
    /// The same on one core: the CPU seconds `method = "auto"` compares with its limit.
    pub estimated_form_factor_cpu_seconds: f64,
    pub warnings: Vec<String>,
    /// Share of the camera's primary hits on back faces of one-sided surfaces (`trace::back_faces`);
    /// `None` when the scene is too large to mesh.
    pub back_faces: Option<BackFaceShare>,
    pub geometry: crate::scene::lint::GeometryReport,
}

/// Polygon area by Newell's formula (`scene::shapes::polygon_normal`: on the polygon's own edges).
fn area(v: &[glam::Vec3]) -> f64 {
    0.5 * crate::scene::shapes::polygon_normal(v).length() as f64
}

/// Builds the report (meshing is only counted, never done).
pub fn describe(scene: &SceneDescription) -> InfoReport {
    let p = &scene.radiosity;
    let elements = mesh::count_elements(scene, p.max_element_edge);
    let mut emitters: Vec<EmitterInfo> = Vec::new();
    for s in &scene.surfaces {
        let m = &scene.materials[s.material as usize];
        if !m.is_emitter() {
            continue;
        }
        let a = area(&s.vertices) * if s.two_sided { 2.0 } else { 1.0 };
        let e = match emitters.iter_mut().position(|e| e.material == m.name) {
            Some(i) => &mut emitters[i],
            None => {
                emitters.push(EmitterInfo { material: m.name.clone(), surfaces: 0, area: 0.0, power: [0.0; 3] });
                emitters.last_mut().expect("just pushed")
            }
        };
        e.surfaces += 1;
        e.area += a;
        for c in 0..3 {
            e.power[c] += std::f64::consts::PI * m.emitted_radiance[c] as f64 * a;
        }
    }
    // Meshing is cheap (milliseconds for 10⁵ elements), so the estimate uses the real mesh unless the
    // element count is beyond what radray would mesh at all.
    let (bytes, seconds, cpu_seconds, back_faces) = if elements <= crate::run::MAX_ELEMENTS {
        let mesh = mesh::Mesh::build(scene, p.max_element_edge);
        let e = method::matrix_estimate(scene, &mesh);
        let accel = crate::accel::Accel::build(&mesh.positions, &mesh.triangles);
        (e.matrix_bytes, e.seconds, e.cpu_seconds, Some(back_faces::probe_scene(scene, &mesh, &accel)))
    } else {
        (u64::MAX, f64::INFINITY, f64::INFINITY, None)
    };
    InfoReport {
        scene: scene.path.display().to_string(),
        surfaces: scene.surfaces.len(),
        materials: scene.materials.len(),
        triangle_pairs: mesh::pair_triangles(&scene.surfaces)
            .iter()
            .filter(|m| matches!(m, mesh::Meshing::Quad { .. }))
            .count(),
        elements,
        max_element_edge: p.max_element_edge,
        hemicube_resolution_px: p.hemicube_resolution_px,
        solver: p.solver.name().to_string(),
        pass_one_method: pass_one_method(scene),
        emitters,
        estimated_form_factor_bytes: bytes,
        estimated_form_factor_seconds: seconds,
        estimated_form_factor_cpu_seconds: cpu_seconds,
        warnings: scene.warnings.clone(),
        back_faces,
        geometry: crate::scene::lint::check(scene),
    }
}

/// The method `run` will choose, with the reason for `auto` and, for the hierarchy, its input size.
fn pass_one_method(scene: &SceneDescription) -> String {
    // `auto` meshes the scene and draws a sample of hemicubes: ask it once.
    let (name, why) = match scene.radiosity.method {
        MethodChoice::Auto => {
            let name = |choice: MethodChoice| match choice {
                MethodChoice::Hierarchical => hierarchical::Hierarchical.name(),
                MethodChoice::Adaptive => Adaptive { solver: scene.radiosity.solver }.name(),
                MethodChoice::Matrix | MethodChoice::Auto => method::for_params(&scene.radiosity).name(),
            };
            let [(choice, reason), (radiosity_choice, radiosity_reason)] = method::auto_methods(scene);
            // Runs that draw only radiosity-mode images may take another mesh (`auto_method_for`).
            let radiosity = if radiosity_choice != choice {
                format!("; for radiosity-mode renders {} ({radiosity_reason})", name(radiosity_choice))
            } else {
                String::new()
            };
            // Shards cannot split the adaptive levels: say what they take instead (`shard_method`).
            let shards = match choice {
                MethodChoice::Adaptive => format!(
                    "; under --shard/--merge {} on the uniform mesh (the adaptive levels each need the whole \
                     solve of the level before)",
                    method::for_params(&scene.radiosity).name()
                ),
                _ => String::new(),
            };
            (name(choice), format!(" (auto: {reason}){radiosity}{shards}"))
        }
        _ => (method::for_scene(scene).name(), String::new()),
    };
    let size = if name == "hierarchical" {
        format!(
            "; {} input triangles, at least {:.1} MiB before refinement, budget {:.1} GB",
            hierarchy::count_input_triangles(scene),
            hierarchical::minimum_bytes(scene) as f64 / (1u64 << 20) as f64,
            scene.radiosity.hierarchy.memory_bytes as f64 / 1e9
        )
    } else {
        String::new()
    };
    format!("{name}{why}{size}")
}

impl std::fmt::Display for InfoReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        const MIB: f64 = (1u64 << 20) as f64;
        writeln!(f, "scene           {}", self.scene)?;
        write!(f, "surfaces        {} ({} materials", self.surfaces, self.materials)?;
        if self.triangle_pairs > 0 {
            write!(f, "; {} triangle pairs meshed as quads", self.triangle_pairs)?;
        }
        writeln!(f, ")")?;
        writeln!(f, "elements        {} (max element edge {})", self.elements, self.max_element_edge)?;
        writeln!(f, "hemicube        {}² top face, solver {}", self.hemicube_resolution_px, self.solver)?;
        writeln!(f, "pass one        {}", self.pass_one_method)?;
        if self.emitters.is_empty() {
            writeln!(f, "emitters        none: the radiosity solution will be black")?;
        }
        for e in &self.emitters {
            writeln!(
                f,
                "emitter         `{}`: {} surface(s), area {:.4}, power [{:.4}, {:.4}, {:.4}]",
                e.material, e.surfaces, e.area, e.power[0], e.power[1], e.power[2]
            )?;
        }
        writeln!(
            f,
            "form factors    about {:.1} MiB, about {:.1} s ({:.1} CPU-s; a sample of hemicubes drawn and counted)",
            self.estimated_form_factor_bytes as f64 / MIB,
            self.estimated_form_factor_seconds,
            self.estimated_form_factor_cpu_seconds
        )?;
        if let Some(b) = &self.back_faces {
            writeln!(
                f,
                "back faces      {:.1}% of primary hits ({} of {} probe rays hit)",
                100.0 * b.share(),
                b.hits,
                b.rays
            )?;
            if b.is_large() {
                writeln!(
                    f,
                    "                suggestion: `two_sided = true` on the meshes seen from behind (pass two shows \
                     the back of a one-sided surface black)"
                )?;
            }
        }
        for w in &self.warnings {
            writeln!(f, "warning         {w}")?;
        }
        writeln!(f, "{}", self.geometry)
    }
}
