//! Choosing points on the emitters: which emitting triangle (a selector over a cumulative table, today
//! by area) and a uniform point on it. Pass two's shadow rays and the photons both draw from here.

use glam::Vec3;

use crate::mesh::{Mesh, NONE};
use crate::scene::Material;

/// Uniform point on triangle (v₀, v₁, v₂) from two uniform numbers (Turk 1990): with s' = √s,
/// x = (1 − s')·v₀ + s'(1 − r)·v₁ + s'r·v₂ (√s picks the distance from v₀).
pub fn uniform_triangle_point([v0, v1, v2]: [Vec3; 3], s: f32, r: f32) -> Vec3 {
    let su = s.sqrt();
    v0 * (1.0 - su) + v1 * (su * (1.0 - r)) + v2 * (su * r)
}

/// A point chosen on an emitter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmitterSample {
    /// Index into `Mesh::triangles`.
    pub triangle: u32,
    pub point: Vec3,
    /// 1/p_A, the inverse of the area density the point was drawn with (scene units²).
    pub inverse_density: f32,
}

/// How an emitting triangle is selected from a uniform number ξ. The table here selects by area
/// (p_A = 1/A); a selector by emitted power would fill the same table with power fractions.
#[derive(Clone, Debug, Default)]
struct AreaTable {
    /// Cumulative fraction up to and including each entry; the last is 1.
    cdf: Vec<f32>,
}

impl AreaTable {
    /// Entry i with cdf[i−1] ≤ ξ < cdf[i], and ξ rescaled to [0, 1] within it (0.5 for an empty one).
    fn select(&self, xi: f32) -> (usize, f32) {
        let i = self.cdf.partition_point(|&c| c <= xi).min(self.cdf.len() - 1);
        let lo = if i == 0 { 0.0 } else { self.cdf[i - 1] };
        let hi = self.cdf[i];
        let s = if hi > lo { ((xi - lo) / (hi - lo)).clamp(0.0, 1.0) } else { 0.5 };
        (i, s)
    }
}

/// The triangles of emitting elements (by their front side's material), for direct light: points are
/// chosen uniformly by area over all of them.
#[derive(Clone, Debug, Default)]
pub struct Emitters {
    triangle: Vec<u32>,
    table: AreaTable,
    total_area: f32,
}

impl Emitters {
    /// The emitting triangles of `mesh` of positive area; `materials` must cover `Elements::material`.
    pub fn new(mesh: &Mesh, materials: &[Material]) -> Emitters {
        let mut emitters = Emitters::default();
        let mut area_sum = 0.0f64;
        for (t, tri) in mesh.triangles.iter().enumerate() {
            let e = mesh.triangle_element[t] as usize;
            if !materials[mesh.elements.material[e] as usize].is_emitter() {
                continue;
            }
            let p = tri.map(|v| mesh.positions[v as usize]);
            let area = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length() as f64;
            if area > 0.0 {
                area_sum += area;
                emitters.triangle.push(t as u32);
                emitters.table.cdf.push(area_sum as f32);
            }
        }
        if area_sum > 0.0 {
            for c in &mut emitters.table.cdf {
                *c = (*c as f64 / area_sum) as f32;
            }
            if let Some(last) = emitters.table.cdf.last_mut() {
                *last = 1.0;
            }
        }
        emitters.total_area = area_sum as f32;
        emitters
    }

    pub fn is_empty(&self) -> bool {
        self.triangle.is_empty()
    }

    /// Total area A of the emitting triangles (scene units²).
    pub fn total_area(&self) -> f32 {
        self.total_area
    }

    /// The point for uniform numbers (ξ, r): ξ selects the triangle (and, rescaled, the distance from
    /// its first corner), r the position across (`uniform_triangle_point`). Stratifying ξ stratifies
    /// the points by area. `None` without emitters.
    pub fn sample(&self, mesh: &Mesh, xi: f32, r: f32) -> Option<EmitterSample> {
        if self.triangle.is_empty() {
            return None;
        }
        let (i, s) = self.table.select(xi);
        let t = self.triangle[i];
        let corners = mesh.triangles[t as usize].map(|v| mesh.positions[v as usize]);
        Some(EmitterSample {
            triangle: t,
            point: uniform_triangle_point(corners, s, r),
            inverse_density: self.total_area,
        })
    }
}

/// The triangles that emit on either side, which photons leave from, with cumulative areas in f64.
#[derive(Clone, Debug)]
pub struct PhotonSources {
    triangle: Vec<u32>,
    cumulative_area: Vec<f64>,
}

impl PhotonSources {
    /// `None` when no triangle of positive area emits.
    pub fn new(mesh: &Mesh) -> Option<PhotonSources> {
        let e = &mesh.elements;
        let triangle: Vec<u32> = (0..mesh.triangles.len() as u32)
            .filter(|&t| {
                let front = mesh.triangle_element[t as usize] as usize;
                let back = mesh.triangle_back_element[t as usize];
                e.emission[front].max_element() > 0.0 || (back != NONE && e.emission[back as usize].max_element() > 0.0)
            })
            .collect();
        let mut cumulative_area = Vec::with_capacity(triangle.len());
        let mut sum = 0.0f64;
        for &t in &triangle {
            let [a, b, c] = mesh.triangles[t as usize].map(|v| mesh.positions[v as usize]);
            sum += 0.5 * (b - a).cross(c - a).length() as f64;
            cumulative_area.push(sum);
        }
        (sum > 0.0).then_some(PhotonSources { triangle, cumulative_area })
    }

    /// Total emitting area A (scene units²).
    pub fn total_area(&self) -> f64 {
        self.cumulative_area.last().copied().unwrap_or(0.0)
    }

    /// The point for uniform numbers: `xi` ∈ [0, 1) selects the triangle by area, (s, r) place the
    /// point on it (`uniform_triangle_point`).
    pub fn sample(&self, mesh: &Mesh, xi: f64, s: f32, r: f32) -> EmitterSample {
        let total = self.total_area();
        let x = xi * total;
        let k = self.cumulative_area.partition_point(|&c| c <= x).min(self.cumulative_area.len() - 1);
        let t = self.triangle[k];
        let corners = mesh.triangles[t as usize].map(|v| mesh.positions[v as usize]);
        EmitterSample { triangle: t, point: uniform_triangle_point(corners, s, r), inverse_density: total as f32 }
    }
}
