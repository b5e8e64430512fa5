//! The caustic map: photons (`transport::photons`) that reached a diffuse surface through mirrors and
//! glass, gathered by density estimation (Jensen 1996) so that pass two can sharpen the LS+D light that
//! pass one's extended form factors carry only at element resolution.

use glam::{DVec3, Vec3};
use rustc_hash::FxHashMap;
use std::f32::consts::PI;

use crate::mesh::Mesh;
use crate::transport::{Photons, SurfaceHit};

/// Photons of one surface closer than this fraction of the kernel radius are merged (`CausticMap::new`).
pub const MERGE_FRACTION: f32 = 0.25;
/// Radius of the density-estimation kernel as a fraction of the scene's size (its largest coordinate
/// magnitude or extent): 0.5 % is 2.8 mm in the 556 mm Cornell box, about a pixel's footprint at
/// 256² and a tenth of a 25 mm element.
pub const KERNEL_RADIUS_FRACTION: f32 = 0.005;

/// Photons that reached a diffuse surface after one or more specular bounces, stored per grid cell,
/// and the same light averaged per element and over the vertices as pass one represents it.
pub struct CausticMap {
    /// Photon positions, sorted by grid cell.
    position: Vec<Vec3>,
    /// Photon power (flux, scene units) per channel.
    power: Vec<Vec3>,
    /// Mesh surface (`Elements::surface`) the photon landed on: the kernel gathers within one surface.
    surface: Vec<u32>,
    /// Range of photons per grid cell (an FxHash map: the gather looks up 8 cells per diffuse hit).
    cells: FxHashMap<[i32; 3], (u32, u32)>,
    /// Kernel radius r (scene units); grid cells are 2r wide.
    radius: f32,
    /// Per vertex: area-weighted average of the elements' caustic irradiance (Σ power / area), the
    /// element-resolution view that Gouraud interpolation of pass one's solution gives.
    vertex_irradiance: Vec<Vec3>,
    /// Photons stored and rays traced to make them.
    pub photons: usize,
    pub rays: u64,
}

impl CausticMap {
    /// The map of `photons` (from `transport::photons::trace_photons`) with the kernel radius `KERNEL_RADIUS_FRACTION` of
    /// the scene's size `scale`.
    pub fn new(mesh: &Mesh, photons: &Photons, scale: f32) -> CausticMap {
        let e = &mesh.elements;
        let landings: Vec<(Vec3, Vec3, u32)> = photons
            .landings
            .iter()
            .map(|l| (l.position, l.throughput * e.emission[l.source as usize] / PI, l.element))
            .collect();
        let rays = photons.rays;
        let radius = KERNEL_RADIUS_FRACTION * scale;
        // Element irradiance and its vertex average.
        let mut element_irradiance = vec![DVec3::ZERO; e.len()];
        for &(_, power, element) in &landings {
            let i = element as usize;
            element_irradiance[i] += power.as_dvec3() / (e.area[i] as f64).max(f64::MIN_POSITIVE);
        }
        let vertex_irradiance = mesh.vertex_average(&element_irradiance).iter().map(|v| v.as_vec3()).collect();
        // Merge photons of one surface that fall within a cube of r/4 into one at their power-weighted
        // centroid: the kernel hardly changes over r/4, and in a focused caustic thousands of photons
        // fall within one kernel, so the gather's work there drops by an order of magnitude while
        // sparse regions keep every photon.
        let fine = radius * MERGE_FRACTION;
        let mut by_fine: Vec<([i32; 3], u32, Vec3, Vec3)> = landings
            .iter()
            .map(|&(p, power, element)| {
                ((p / fine).floor().as_ivec3().to_array(), e.surface[element as usize], p, power)
            })
            .collect();
        by_fine.sort_by_key(|a| (a.0, a.1));
        let mut merged: Vec<(Vec3, Vec3, u32)> = Vec::new();
        for run in by_fine.chunk_by(|a, b| a.0 == b.0 && a.1 == b.1) {
            let (mut weighted, mut weight, mut power) = (DVec3::ZERO, 0.0f64, DVec3::ZERO);
            for &(_, _, p, pw) in run {
                let w = pw.element_sum() as f64;
                weighted += p.as_dvec3() * w;
                weight += w;
                power += pw.as_dvec3();
            }
            let centroid = if weight > 0.0 { (weighted / weight).as_vec3() } else { run[0].2 };
            merged.push((centroid, power.as_vec3(), run[0].1));
        }
        // Grid of cells twice as wide as the kernel: a gather reads the 2 × 2 × 2 cells nearest its point
        // (see `irradiance`).
        let cell_of = |p: Vec3| -> [i32; 3] { (p / (2.0 * radius)).floor().as_ivec3().to_array() };
        let mut keyed: Vec<([i32; 3], (Vec3, Vec3, u32))> = merged.iter().map(|l| (cell_of(l.0), *l)).collect();
        keyed.sort_by_key(|a| a.0);
        let mut cells = FxHashMap::default();
        let mut k = 0;
        while k < keyed.len() {
            let start = k;
            while k < keyed.len() && keyed[k].0 == keyed[start].0 {
                k += 1;
            }
            cells.insert(keyed[start].0, (start as u32, k as u32));
        }
        CausticMap {
            position: keyed.iter().map(|(_, l)| l.0).collect(),
            power: keyed.iter().map(|(_, l)| l.1).collect(),
            surface: keyed.iter().map(|(_, l)| l.2).collect(),
            cells,
            radius,
            vertex_irradiance,
            photons: keyed.len(),
            rays,
        }
    }

    /// Caustic irradiance at `p` on mesh surface `surface`, by density estimation with the
    /// Epanechnikov kernel K(d) = 2/(π r²)·(1 − d²/r²) over the photons of that surface within r:
    /// E(p) = Σ_k Φ_k K(|x_k − p|).
    pub fn irradiance(&self, p: Vec3, surface: u32) -> Vec3 {
        let r2 = self.radius * self.radius;
        // In cells 2r wide, the ball of radius r about p lies in p's cell and, along each axis, the
        // neighbour on the side of the cell's half that p is in.
        let scaled = p / (2.0 * self.radius);
        let c = scaled.floor();
        let step = (scaled - c).cmpge(Vec3::splat(0.5));
        let c = c.as_ivec3();
        let next = |axis: usize| if step.test(axis) { 1 } else { -1 };
        let mut sum = Vec3::ZERO;
        for dz in [0, next(2)] {
            for dy in [0, next(1)] {
                for dx in [0, next(0)] {
                    let Some(&(start, end)) = self.cells.get(&[c.x + dx, c.y + dy, c.z + dz]) else {
                        continue;
                    };
                    for k in start as usize..end as usize {
                        let d2 = self.position[k].distance_squared(p);
                        if d2 < r2 && self.surface[k] == surface {
                            sum += self.power[k] * (1.0 - d2 / r2);
                        }
                    }
                }
            }
        }
        sum * (2.0 / (PI * r2))
    }

    /// The caustic irradiance at element resolution at `hit`, interpolated like pass one's exitance:
    /// the vertices' averages Gouraud-interpolated over the side hit.
    pub fn smooth_irradiance(&self, hit: &SurfaceHit) -> Vec3 {
        hit.interpolate(&self.vertex_irradiance)
    }
}
