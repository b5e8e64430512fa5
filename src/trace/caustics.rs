//! Caustics at pixel resolution: light traced from the emitters through mirrors and glass onto diffuse
//! surfaces (Arvo 1986, backward ray tracing; Jensen 1996, the caustic photon map), so that pass two can
//! sharpen the LS+D light that pass one's extended form factors carry only at element resolution.

use glam::{DVec3, Vec3};
use rustc_hash::FxHashMap;
use std::collections::HashMap;
use std::f32::consts::PI;

use super::optics::{fresnel_dielectric, reflect, refract};
use crate::accel::Accel;
use crate::mesh::{Mesh, NONE};
use crate::rng::Pcg32;
use crate::scene::{Material, Surface};

/// Photons shot towards each group of specular elements (one group per scene object). Measured on
/// cornell_specular (two spheres, cones about each object's tight bounding sphere), final relMSE
/// against the reference: 2¹⁹ per object 0.00050, 2¹⁸ 0.00051, 2¹⁷ 0.00054 (the bound is
/// 0.005). 2¹⁷ keeps pass two's 512² × 16 spp render of that scene under 3 s (2.91 s, plus 0.6 s to
/// trace the photons), where 2¹⁹ took 5.6 s.
pub const PHOTONS_PER_OBJECT: u32 = 1 << 17;
/// Photons of one surface closer than this fraction of the kernel radius are merged (`CausticMap::new`).
pub const MERGE_FRACTION: f32 = 0.25;
/// Photons are traced in batches of this many, each with its own generator stream, so that the map is
/// the same whatever the thread count.
pub const PHOTON_BATCH: u32 = 4096;
/// Deepest specular chain a photon follows (as pass one's `radiosity::specular::MAX_DEPTH`).
pub const MAX_DEPTH: u32 = 8;
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
    /// Range of photons per grid cell.
    /// (An FxHash map: the gather looks up 27 cells per diffuse hit, and SipHash cost 9% of a render.)
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

/// A photon where it landed: its power is L_e(source) · `throughput`, `throughput` the sampling weight
/// cos θ_e / (p_A p_ω N) times the specular tints along the path (scene units: area × steradian).
#[derive(Clone, Copy, Debug)]
pub struct Landing {
    pub position: Vec3,
    pub throughput: Vec3,
    /// The element (side) it landed on.
    pub element: u32,
    /// The emitting element (side) it left.
    pub source: u32,
}

/// All the photons that reached a diffuse surface through mirrors and glass, and the rays it took.
pub struct Photons {
    pub landings: Vec<Landing>,
    pub rays: u64,
}

/// Seed of the photons' generators: fixed, so that pass one (extended form factors to the emitters,
/// `radiosity::specular`) and pass two (`CausticMap`) trace the very same photons, and a solution
/// saved to a file still matches pass two's map.
pub const PHOTON_SEED: u64 = 0x5eed_ca05;

/// Traces `PHOTONS_PER_OBJECT` photons from the emitting triangles (uniform by area) towards each
/// scene object made of specular elements, follows them through mirrors and dielectrics by Whitted's
/// rules (a dielectric reflects with probability R, Fresnel, and
/// refracts otherwise: Russian roulette keeps one path), and stores them where they first reach a
/// diffuse surface. Directions are sampled uniformly in the cone from the emitter point that
/// holds the object's bounding sphere; a photon whose first hit is not that object is dropped, so
/// each direction is counted by one object only. Flux of a photon: Φ = L_e cos θ_e / (p_A p_ω N), with
/// p_A = 1/A (A the emitters' area) and p_ω = 1/(2π(1 − cos θ_max)).
/// `run_batches(count, trace)` maps `trace` over the batches 0..count in order (in parallel at the
/// call site). `None` when the scene has no specular element or no emitter.
pub fn trace_photons(
    mesh: &Mesh,
    accel: &Accel,
    materials: &[Material],
    surfaces: Option<&[Surface]>,
    run_batches: impl Fn(u32, &(dyn Fn(u32) -> (Vec<Landing>, u64) + Sync)) -> Vec<(Vec<Landing>, u64)>,
) -> Option<Photons> {
    let e = &mesh.elements;
    let specular: Vec<bool> =
        e.material.iter().map(|&m| materials.get(m as usize).is_some_and(Material::is_specular)).collect();
    // Groups: specular elements by scene object.
    let mut group_of_name: HashMap<&str, u32> = HashMap::new();
    let mut group = vec![NONE; e.len()];
    let mut bounds: Vec<(Vec3, Vec3)> = Vec::new();
    for i in (0..e.len()).filter(|&i| specular[i]) {
        let surface = mesh.surface_source.get(e.surface[i] as usize).copied().unwrap_or(NONE);
        let name = surfaces.and_then(|s| s.get(surface as usize)).map_or("", |s| s.object.as_str());
        let g = *group_of_name.entry(name).or_insert_with(|| {
            bounds.push((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)));
            (bounds.len() - 1) as u32
        });
        group[i] = g;
        for p in e.polygon(&mesh.positions, i) {
            bounds[g as usize].0 = bounds[g as usize].0.min(p);
            bounds[g as usize].1 = bounds[g as usize].1.max(p);
        }
    }
    // Emitting triangles (either side).
    let emitter_triangles: Vec<u32> = (0..mesh.triangles.len() as u32)
        .filter(|&t| {
            let front = mesh.triangle_element[t as usize] as usize;
            let back = mesh.triangle_back_element[t as usize];
            e.emission[front].max_element() > 0.0 || (back != NONE && e.emission[back as usize].max_element() > 0.0)
        })
        .collect();
    if bounds.is_empty() || emitter_triangles.is_empty() {
        return None;
    }
    let (lo, hi) = mesh
        .positions
        .iter()
        .fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    let scale = lo.abs().max(hi.abs()).max_element().max((hi - lo).max_element()).max(f32::MIN_POSITIVE);
    // Bounding spheres about the boxes' centres, as tight as the elements' corners allow (a sphere
    // object gets its own radius, not the box's half-diagonal, √3 times more: fewer wasted photons).
    let mut spheres: Vec<(Vec3, f32)> = bounds.iter().map(|&(lo, hi)| ((lo + hi) * 0.5, 0.0)).collect();
    for i in (0..e.len()).filter(|&i| specular[i]) {
        let (centre, radius) = &mut spheres[group[i] as usize];
        for p in e.polygon(&mesh.positions, i) {
            *radius = radius.max(p.distance(*centre));
        }
    }
    // Emitter triangles' cumulative areas.
    let mut cdf = Vec::with_capacity(emitter_triangles.len());
    let mut sum = 0.0f64;
    for &t in &emitter_triangles {
        let [a, b, c] = mesh.triangles[t as usize].map(|v| mesh.positions[v as usize]);
        sum += 0.5 * (b - a).cross(c - a).length() as f64;
        cdf.push(sum);
    }
    if sum <= 0.0 {
        return None;
    }
    let offset = 1e-5 * scale;
    let batches_per_group = PHOTONS_PER_OBJECT.div_ceil(PHOTON_BATCH);
    let batch_count = batches_per_group * spheres.len() as u32;
    let photons_per_group = (batches_per_group * PHOTON_BATCH) as f32;
    let trace = |batch: u32| -> (Vec<Landing>, u64) {
        let g = batch / batches_per_group;
        let (centre, radius) = spheres[g as usize];
        let mut rng = Pcg32::new(PHOTON_SEED, batch as u64);
        let mut out = Vec::new();
        let mut rays = 0u64;
        for _ in 0..PHOTON_BATCH {
            // A point on the emitters, uniform by area.
            let xi = rng.next_f64() * sum;
            let k = cdf.partition_point(|&c| c <= xi).min(cdf.len() - 1);
            let t = emitter_triangles[k] as usize;
            let [a, b, c] = mesh.triangles[t].map(|v| mesh.positions[v as usize]);
            let su = rng.next_f32().sqrt();
            let r = rng.next_f32();
            let x = a * (1.0 - su) + b * (su * (1.0 - r)) + c * (su * r);
            // A direction uniform in the cone around the object's bounding sphere.
            let to_centre = centre - x;
            let distance = to_centre.length();
            let cos_max = if distance > radius { (1.0 - (radius / distance).powi(2)).max(0.0).sqrt() } else { -1.0 };
            let axis = if distance > 0.0 { to_centre / distance } else { Vec3::Y };
            let cos_theta = 1.0 - rng.next_f32() * (1.0 - cos_max);
            let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
            let phi = 2.0 * PI * rng.next_f32();
            let (u, v) = axis.any_orthonormal_pair();
            let dir = (axis * cos_theta + (u * phi.cos() + v * phi.sin()) * sin_theta).normalize();
            let solid_angle = 2.0 * PI * (1.0 - cos_max);
            // Which side of the emitter faces the direction, and its radiance.
            let front_element = mesh.triangle_element[t] as usize;
            let cos_front = e.normal[front_element].dot(dir);
            let Some(element) = mesh.side_element(t, cos_front > 0.0) else {
                continue;
            };
            let cos_emit = cos_front.abs();
            let radiance = e.emission[element] / PI;
            if radiance.max_element() <= 0.0 {
                continue;
            }
            let weight = Vec3::splat(cos_emit * sum as f32 * solid_angle / photons_per_group);
            let origin = x + e.normal[front_element] * (if cos_front > 0.0 { offset } else { -offset });
            let photon = Photon { origin, dir, throughput: weight, source: element as u32 };
            rays += follow(mesh, accel, materials, surfaces, &specular, &group, g, photon, offset, &mut rng, &mut out);
        }
        (out, rays)
    };
    let results = run_batches(batch_count, &trace);
    let mut landings = Vec::new();
    let mut rays = 0;
    for (l, r) in results {
        landings.extend(l);
        rays += r;
    }
    Some(Photons { landings, rays })
}

impl CausticMap {
    /// The map of `photons` (from `trace_photons`) with the kernel radius `KERNEL_RADIUS_FRACTION` of
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
        // (see `irradiance`). Measured on cornell_specular at 512², 16 spp: 8 lookups instead of the 27
        // of r-wide cells took the gather's share of the render from 24% to 15%.
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

    /// The caustic irradiance at element resolution, interpolated like pass one's exitance: the
    /// vertices' averages at barycentrics `bary` of triangle `vertices`.
    pub fn smooth_irradiance(&self, vertices: [u32; 3], bary: [f32; 3]) -> Vec3 {
        self.vertex_irradiance[vertices[0] as usize] * bary[0]
            + self.vertex_irradiance[vertices[1] as usize] * bary[1]
            + self.vertex_irradiance[vertices[2] as usize] * bary[2]
    }
}

/// A photon leaving an emitter.
#[derive(Clone, Copy, Debug)]
struct Photon {
    origin: Vec3,
    dir: Vec3,
    throughput: Vec3,
    source: u32,
}

/// Follows one photon whose first hit must be specular group `group_wanted`; appends where it lands.
#[allow(clippy::too_many_arguments)]
fn follow(
    mesh: &Mesh,
    accel: &Accel,
    materials: &[Material],
    surfaces: Option<&[Surface]>,
    specular: &[bool],
    group: &[u32],
    group_wanted: u32,
    photon: Photon,
    offset: f32,
    rng: &mut Pcg32,
    out: &mut Vec<Landing>,
) -> u64 {
    let e = &mesh.elements;
    let Photon { mut origin, mut dir, throughput: mut power, source } = photon;
    let mut rays = 0;
    for depth in 0..=MAX_DEPTH {
        rays += 1;
        let Some(hit) = accel.closest_hit(origin, dir, 0.0, f32::INFINITY) else {
            break;
        };
        let t = hit.triangle as usize;
        let front_element = mesh.triangle_element[t] as usize;
        if depth == 0 && group[front_element] != group_wanted {
            break;
        }
        let normal = e.normal[front_element];
        let front = dir.dot(normal) < 0.0;
        let side = mesh.side_element(t, front);
        let Some(material) = materials.get(e.material[front_element] as usize) else {
            break;
        };
        let bary = [1.0 - hit.u - hit.v, hit.u, hit.v];
        let [i0, i1, i2] = mesh.triangles[t];
        let p = mesh.positions[i0 as usize] * bary[0]
            + mesh.positions[i1 as usize] * bary[1]
            + mesh.positions[i2 as usize] * bary[2];
        match side {
            Some(j) if depth > 0 && e.reflectance[j].max_element() > 0.0 => {
                out.push(Landing { position: p, throughput: power, element: j as u32, source });
            }
            None if !material.is_dielectric() => break,
            _ => {}
        }
        if !specular[front_element] {
            break;
        }
        let facing = if front { normal } else { -normal };
        let shading = surfaces.map_or(facing, |s| mesh.shading_normal(s, front_element, p, facing, dir));
        let mirror = |d: Vec3| {
            let r = reflect(d, shading);
            if r.dot(facing) > 0.0 {
                r
            } else {
                reflect(d, facing)
            }
        };
        if material.is_dielectric() {
            let (eta_i, eta_t) = if front { (1.0, material.ior) } else { (material.ior, 1.0) };
            let reflectance = fresnel_dielectric(-dir.dot(shading), eta_i, eta_t);
            let refracted = refract(dir, shading, eta_i / eta_t).filter(|t| t.dot(facing) < 0.0);
            origin = p + facing * offset;
            match refracted {
                // Russian roulette between the branches: reflect with probability R, weight Ks·R/R.
                Some(r) if rng.next_f32() >= reflectance => {
                    origin = p - facing * offset;
                    dir = r.normalize();
                    power *= material.transmittance;
                }
                Some(_) => {
                    dir = mirror(dir);
                    power *= material.specular_reflectance;
                }
                // Total internal reflection (R = 1), or a shading normal that allows no refraction.
                None => {
                    dir = mirror(dir);
                    power *= material.specular_reflectance * reflectance;
                }
            }
        } else if material.specular_reflectance.max_element() > 0.0 {
            origin = p + facing * offset;
            dir = mirror(dir);
            power *= material.specular_reflectance;
        } else {
            break;
        }
        if power.max_element() <= 0.0 {
            break;
        }
    }
    rays
}
