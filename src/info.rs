//! `radray info`: what a scene holds and what solving it will cost, reported before anything is
//! solved, with the suspicious geometry that usually causes light leaks.

use crate::mesh;
use crate::scene::SceneDescription;

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
    pub elements: u64,
    pub max_element_edge: f32,
    pub hemicube_resolution_px: u32,
    pub solver: String,
    pub emitters: Vec<EmitterInfo>,
    /// Upper bound of the form-factor matrix's size (8 bytes per entry, rows of reflecting or
    /// emitting elements, at most one entry per other element or per hemicube pixel).
    pub estimated_form_factor_bytes: u64,
    /// Rough hemicube time on this machine's cores (see `estimate_form_factor_seconds`).
    pub estimated_form_factor_seconds: f64,
    pub warnings: Vec<String>,
    pub geometry: crate::diagnose::GeometryReport,
}

/// Polygon area by Newell's formula.
fn area(v: &[glam::Vec3]) -> f64 {
    let n: glam::Vec3 = (0..v.len()).map(|i| v[i].cross(v[(i + 1) % v.len()])).sum();
    0.5 * n.length() as f64
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
    let reflecting = |m: &crate::scene::Material| m.diffuse_reflectance.max_element() > 0.0 || m.is_emitter();
    let row_fraction = {
        let total: u64 = elements.max(1);
        let with_rows: u64 = scene
            .surfaces
            .iter()
            .filter(|s| reflecting(&scene.materials[s.material as usize]))
            .map(|s| mesh::count_surface_elements(s, p.max_element_edge))
            .sum();
        with_rows as f64 / total as f64
    };
    let rows = (elements as f64 * row_fraction) as u64;
    let pixels = 3 * (p.hemicube_resolution_px as u64).pow(2);
    InfoReport {
        scene: scene.path.display().to_string(),
        surfaces: scene.surfaces.len(),
        materials: scene.materials.len(),
        elements,
        max_element_edge: p.max_element_edge,
        hemicube_resolution_px: p.hemicube_resolution_px,
        solver: p.solver.name().to_string(),
        emitters,
        estimated_form_factor_bytes: rows * elements.min(pixels) * 8,
        estimated_form_factor_seconds: estimate_form_factor_seconds(rows, elements, p.hemicube_resolution_px),
        warnings: scene.warnings.clone(),
        geometry: crate::diagnose::diagnose(scene),
    }
}

/// Hemicube time model: each of `rows` hemicubes clears and scans its 3N² pixels and projects the
/// `elements` polygons, spread over the machine's cores. The constants were measured on the
/// development machine (see the closing notes / docs/performance.md).
pub fn estimate_form_factor_seconds(rows: u64, elements: u64, resolution_px: u32) -> f64 {
    const SECONDS_PER_PIXEL: f64 = 2.0e-9;
    const SECONDS_PER_POLYGON: f64 = 6.0e-8;
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get()) as f64;
    let per_hemicube = 3.0 * (resolution_px as f64).powi(2) * SECONDS_PER_PIXEL + elements as f64 * SECONDS_PER_POLYGON;
    rows as f64 * per_hemicube / cores
}

impl std::fmt::Display for InfoReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        const MIB: f64 = (1u64 << 20) as f64;
        writeln!(f, "scene           {}", self.scene)?;
        writeln!(f, "surfaces        {} ({} materials)", self.surfaces, self.materials)?;
        writeln!(f, "elements        {} (max element edge {})", self.elements, self.max_element_edge)?;
        writeln!(f, "hemicube        {}² top face, solver {}", self.hemicube_resolution_px, self.solver)?;
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
            "form factors    at most {:.1} MiB, about {:.1} s",
            self.estimated_form_factor_bytes as f64 / MIB,
            self.estimated_form_factor_seconds
        )?;
        for w in &self.warnings {
            writeln!(f, "warning         {w}")?;
        }
        write!(f, "{}", self.geometry)
    }
}
