//! The caustic map: photons (`transport::photons`) that reached a diffuse surface through mirrors and
//! glass, gathered by density estimation (Jensen 1996) so that pass two can sharpen the LS+D light that
//! pass one's extended form factors carry only at element resolution. Two kernels: a fine one for
//! where photons are dense (focused caustics) and a wide one for weak, spread light (`irradiance`).

use glam::{DVec3, Vec3};
use rustc_hash::FxHashMap;
use std::f32::consts::PI;

use crate::mesh::Mesh;
use crate::transport::{Photons, SurfaceHit};

/// Photons of one surface closer than this fraction of the kernel radius are merged (`Kernel::new`).
pub const MERGE_FRACTION: f32 = 0.25;
/// Radius of the density-estimation kernel as a fraction of the scene's size (its largest coordinate
/// magnitude or extent): 0.5 % is 2.8 mm in the 556 mm Cornell box, about a pixel's footprint at
/// 256² and a tenth of a 25 mm element.
pub const KERNEL_RADIUS_FRACTION: f32 = 0.005;
/// The wider kernel's radius, in fine kernel radii (`CausticMap::irradiance`).
pub const WIDE_KERNEL_FACTOR: f32 = 4.0;
/// Photons in the fine kernel above which its estimate is kept without a look at the wide one
/// (relative noise about 1/√256 ≈ 6 %).
pub const DENSE_KERNEL_PHOTONS: u32 = 256;

/// Photons that reached a diffuse surface after one or more specular bounces, gathered by a fine
/// and a wide kernel, and the same light averaged per element and over the vertices as pass one
/// represents it.
pub struct CausticMap {
    /// Radius `KERNEL_RADIUS_FRACTION` of the scene's size: sharp where the photons are dense.
    fine: Kernel,
    /// `WIDE_KERNEL_FACTOR` times wider, for where they are sparse (`irradiance`).
    wide: Kernel,
    /// Per vertex: area-weighted average of the elements' caustic irradiance (Σ power / area), the
    /// element-resolution view that Gouraud interpolation of pass one's solution gives.
    vertex_irradiance: Vec<Vec3>,
    /// Photons stored (by the fine kernel, after merging) and rays traced to make them.
    pub photons: usize,
    pub rays: u64,
}

/// A stored photon: position, power, surface, and how many photons were merged into it.
type StoredPhoton = (Vec3, Vec3, u32, u32);

/// The photons of a caustic map stored for one kernel radius: merged within a quarter of it and
/// sorted into a grid of cells twice as wide.
struct Kernel {
    /// Photon positions, sorted by grid cell.
    position: Vec<Vec3>,
    /// Photon power (flux, scene units) per channel.
    power: Vec<Vec3>,
    /// Photons merged into each stored one.
    count: Vec<u32>,
    /// Mesh surface (`Elements::surface`) the photon landed on: the kernel gathers within one surface.
    surface: Vec<u32>,
    /// Range of photons per grid cell (an FxHash map: the gather looks up 8 cells per diffuse hit).
    cells: FxHashMap<[i32; 3], (u32, u32)>,
    /// Kernel radius r (scene units); grid cells are 2r wide.
    radius: f32,
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
        // Element irradiance and its vertex average.
        let mut element_irradiance = vec![DVec3::ZERO; e.len()];
        for &(_, power, element) in &landings {
            let i = element as usize;
            element_irradiance[i] += power.as_dvec3() / (e.area[i] as f64).max(f64::MIN_POSITIVE);
        }
        let vertex_irradiance = mesh.vertex_average(&element_irradiance).iter().map(|v| v.as_vec3()).collect();
        let landed: Vec<(Vec3, Vec3, u32)> =
            landings.iter().map(|&(p, power, element)| (p, power, e.surface[element as usize])).collect();
        let radius = KERNEL_RADIUS_FRACTION * scale;
        let fine = Kernel::new(&landed, radius);
        let wide = Kernel::new(&landed, radius * WIDE_KERNEL_FACTOR);
        CausticMap { photons: fine.position.len(), rays: photons.rays, fine, wide, vertex_irradiance }
    }

    /// Caustic irradiance at `p` on mesh surface `surface`, by density estimation (`Kernel::estimate`)
    /// with a fine kernel of radius r where photons are dense or the light changes within the wide
    /// kernel's radius R = 4r, else with the wide kernel:
    ///
    /// E(p) = E_r(p) if n_r ≥ `DENSE_KERNEL_PHOTONS` or |n_r − m| > 3·√(m + 1), else E_R(p),
    ///
    /// n the photons within each radius and m = n_R·(r/R)² the count the fine kernel would hold if
    /// the density were the same over the wide kernel's disc (a Poisson count's 3σ). Where the light
    /// is even at the wide kernel's scale, weak and spread (a convex mirror's light over a room's
    /// walls: a photon or two per fine kernel, grain) or a moderate patch (a plane mirror's image of
    /// the lamp: tens), the wide estimate averages 16 times the area; beside a focus or an edge the
    /// counts disagree and the fine estimate keeps it sharp. What the wide kernel costs is a band R
    /// wide along a surface's edges where it reaches past the surface and reads up to half the light
    /// (the fine kernel does the same in a band r wide).
    pub fn irradiance(&self, p: Vec3, surface: u32) -> Vec3 {
        let (fine, n_fine) = self.fine.estimate(p, surface);
        if n_fine >= DENSE_KERNEL_PHOTONS {
            return fine;
        }
        let (wide, n_wide) = self.wide.estimate(p, surface);
        let expected_fine = n_wide as f32 / (WIDE_KERNEL_FACTOR * WIDE_KERNEL_FACTOR);
        if (n_fine as f32 - expected_fine).abs() <= 3.0 * (expected_fine + 1.0).sqrt() {
            wide
        } else {
            fine
        }
    }

    /// The caustic irradiance at element resolution at `hit`, interpolated like pass one's exitance:
    /// the vertices' averages Gouraud-interpolated over the side hit.
    pub fn smooth_irradiance(&self, hit: &SurfaceHit) -> Vec3 {
        hit.interpolate(&self.vertex_irradiance)
    }
}

impl Kernel {
    /// `landed` photons (position, power, surface) stored for kernel radius `radius`: photons of one
    /// surface within a cube of r/4 are merged into one at their power-weighted centroid (the kernel
    /// hardly changes over r/4, and in a focused caustic thousands of photons fall within one kernel,
    /// so the gather's work there drops by an order of magnitude while sparse regions keep every
    /// photon), then sorted by grid cell.
    fn new(landed: &[(Vec3, Vec3, u32)], radius: f32) -> Kernel {
        let fine = radius * MERGE_FRACTION;
        let mut by_fine: Vec<([i32; 3], u32, Vec3, Vec3)> = landed
            .iter()
            .map(|&(p, power, surface)| ((p / fine).floor().as_ivec3().to_array(), surface, p, power))
            .collect();
        by_fine.sort_by_key(|a| (a.0, a.1));
        let mut merged: Vec<StoredPhoton> = Vec::new();
        for run in by_fine.chunk_by(|a, b| a.0 == b.0 && a.1 == b.1) {
            let (mut weighted, mut weight, mut power) = (DVec3::ZERO, 0.0f64, DVec3::ZERO);
            for &(_, _, p, pw) in run {
                let w = pw.element_sum() as f64;
                weighted += p.as_dvec3() * w;
                weight += w;
                power += pw.as_dvec3();
            }
            let centroid = if weight > 0.0 { (weighted / weight).as_vec3() } else { run[0].2 };
            merged.push((centroid, power.as_vec3(), run[0].1, run.len() as u32));
        }
        // Grid of cells twice as wide as the kernel: a gather reads the 2 × 2 × 2 cells nearest its point
        // (see `estimate`).
        let cell_of = |p: Vec3| -> [i32; 3] { (p / (2.0 * radius)).floor().as_ivec3().to_array() };
        let mut keyed: Vec<([i32; 3], StoredPhoton)> = merged.iter().map(|l| (cell_of(l.0), *l)).collect();
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
        Kernel {
            position: keyed.iter().map(|(_, l)| l.0).collect(),
            power: keyed.iter().map(|(_, l)| l.1).collect(),
            surface: keyed.iter().map(|(_, l)| l.2).collect(),
            count: keyed.iter().map(|(_, l)| l.3).collect(),
            cells,
            radius,
        }
    }

    /// Caustic irradiance at `p` on mesh surface `surface` with the Epanechnikov kernel
    /// K(d) = 2/(π r²)·(1 − d²/r²) over the photons of that surface within r, E(p) = Σ_k Φ_k K(|x_k − p|),
    /// and how many photons (before merging) lie within r.
    fn estimate(&self, p: Vec3, surface: u32) -> (Vec3, u32) {
        let r2 = self.radius * self.radius;
        // In cells 2r wide, the ball of radius r about p lies in p's cell and, along each axis, the
        // neighbour on the side of the cell's half that p is in.
        let scaled = p / (2.0 * self.radius);
        let c = scaled.floor();
        let step = (scaled - c).cmpge(Vec3::splat(0.5));
        let c = c.as_ivec3();
        let next = |axis: usize| if step.test(axis) { 1 } else { -1 };
        let (mut sum, mut photons) = (Vec3::ZERO, 0u32);
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
                            photons += self.count[k];
                        }
                    }
                }
            }
        }
        (sum * (2.0 / (PI * r2)), photons)
    }
}
