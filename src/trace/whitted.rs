//! The Whitted tracer (Whitted 1980) over a radiosity solution: an explicit stack of rays instead of
//! recursion, the diffuse term read from the interpolated vertex radiosity, mirror reflection,
//! Fresnel reflection and refraction through smooth dielectrics, Phong highlights and (optionally)
//! per-pixel direct light from the emitters with shadow rays.

use std::f32::consts::PI;
use std::ops::AddAssign;

use glam::Vec3;

use super::caustics::{trace_photons, CausticMap, Landing};
use super::optics::{fresnel_dielectric, reflect, refract};
use crate::accel::Accel;
use crate::mesh::{Mesh, NONE};
use crate::radiosity::Solution;
use crate::rng::Pcg32;
use crate::scene::{DirectMode, Material, RenderParams, Surface};

/// What the tracer returns per ray.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TraceMode {
    /// Radiosity diffuse term plus mirror, dielectric, highlights (and per-pixel direct light when
    /// `RenderParams::direct` asks for it).
    Final,
    /// Only the first hit's interpolated radiosity B/π: the view of pass one alone.
    Radiosity,
}

/// Rays traced, to be added up per thread and merged at the end.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RayCounts {
    /// Closest-hit rays from the camera.
    pub primary: u64,
    /// Closest-hit rays spawned at surfaces (reflection, refraction).
    pub secondary: u64,
    /// Any-hit rays towards emitter samples.
    pub shadow: u64,
}

impl RayCounts {
    pub fn total(&self) -> u64 {
        self.primary + self.secondary + self.shadow
    }
}

impl AddAssign for RayCounts {
    fn add_assign(&mut self, other: RayCounts) {
        self.primary += other.primary;
        self.secondary += other.secondary;
        self.shadow += other.shadow;
    }
}

impl std::iter::Sum for RayCounts {
    fn sum<I: Iterator<Item = RayCounts>>(iter: I) -> RayCounts {
        let mut total = RayCounts::default();
        for c in iter {
            total += c;
        }
        total
    }
}

/// Inputs that do not belong together.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum TraceError {
    #[error("the radiosity solution has {found} {what} values but the mesh has {expected}")]
    SolutionMismatch { what: &'static str, expected: usize, found: usize },
    #[error("element {element} uses material {material} but there are only {count} materials")]
    MissingMaterial { element: usize, material: u32, count: usize },
    #[error("the accelerator holds {found} triangles but the mesh has {expected}")]
    AccelMismatch { expected: usize, found: usize },
}

/// Deepest ray tree the fixed-size stack supports; `RenderParams::max_depth` is clamped to it.
pub const MAX_DEPTH_LIMIT: u32 = 30;
/// A depth-first walk pops one ray and pushes at most two one level deeper, so the stack never holds
/// more than `max_depth + 2` rays.
const STACK_SIZE: usize = MAX_DEPTH_LIMIT as usize + 2;

/// Ray origins are moved off surfaces by this fraction of the scene's size (its largest coordinate
/// magnitude or extent): about 100 ulps of the coordinates, far below any feature size.
const RELATIVE_OFFSET: f32 = 1e-5;

#[derive(Clone, Copy, Debug, Default)]
struct StackRay {
    origin: Vec3,
    dir: Vec3,
    throughput: Vec3,
    depth: u32,
}

/// Triangles of emitting elements, for choosing emitter points by area.
#[derive(Clone, Debug, Default)]
struct Emitters {
    triangle: Vec<u32>,
    /// Cumulative area fraction up to and including each triangle; the last is 1.
    cdf: Vec<f32>,
    total_area: f32,
}

/// Pass two over one meshed scene and its radiosity solution. Shared between threads (`&self`); each
/// thread brings its own generator and ray counts.
pub struct Tracer<'a> {
    mesh: &'a Mesh,
    accel: &'a Accel,
    solution: &'a Solution,
    materials: &'a [Material],
    params: RenderParams,
    max_depth: u32,
    emitters: Emitters,
    /// Distance ray origins are moved off a surface (scene units).
    offset: f32,
    /// The scene's surfaces, when their smooth-shading normals should bend specular rays.
    surfaces: Option<&'a [Surface]>,
    /// Light traced from the emitters through mirrors and glass (`with_caustics`).
    caustics: Option<CausticMap>,
    /// The scene's size, which the caustic kernel is relative to.
    scale: f32,
}

/// Which element a ray hit and on which side.
struct SideHit {
    element: usize,
    vertices: [u32; 3],
}

impl<'a> Tracer<'a> {
    pub fn new(
        mesh: &'a Mesh,
        accel: &'a Accel,
        solution: &'a Solution,
        materials: &'a [Material],
        params: &RenderParams,
    ) -> Result<Tracer<'a>, TraceError> {
        let checks = [
            ("element exitance", mesh.elements.len(), solution.element_exitance.len()),
            ("element direct exitance", mesh.elements.len(), solution.element_direct_exitance.len()),
            ("vertex exitance", mesh.positions.len(), solution.vertex_exitance.len()),
            ("vertex direct exitance", mesh.positions.len(), solution.vertex_direct_exitance.len()),
        ];
        for (what, expected, found) in checks {
            if expected != found {
                return Err(TraceError::SolutionMismatch { what, expected, found });
            }
        }
        if accel.len() != mesh.triangles.len() {
            return Err(TraceError::AccelMismatch { expected: mesh.triangles.len(), found: accel.len() });
        }
        for (element, &material) in mesh.elements.material.iter().enumerate() {
            if material as usize >= materials.len() {
                return Err(TraceError::MissingMaterial { element, material, count: materials.len() });
            }
        }

        let (lo, hi) = mesh
            .positions
            .iter()
            .fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(lo, hi), &p| (lo.min(p), hi.max(p)));
        let scale = if mesh.positions.is_empty() {
            1.0
        } else {
            lo.abs().max(hi.abs()).max_element().max((hi - lo).max_element()).max(f32::MIN_POSITIVE)
        };

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
                emitters.cdf.push(area_sum as f32);
            }
        }
        if area_sum > 0.0 {
            for c in &mut emitters.cdf {
                *c = (*c as f64 / area_sum) as f32;
            }
            if let Some(last) = emitters.cdf.last_mut() {
                *last = 1.0;
            }
        }
        emitters.total_area = area_sum as f32;

        Ok(Tracer {
            mesh,
            accel,
            solution,
            materials,
            params: params.clone(),
            max_depth: params.max_depth.min(MAX_DEPTH_LIMIT),
            emitters,
            offset: RELATIVE_OFFSET * scale,
            surfaces: None,
            caustics: None,
            scale,
        })
    }

    /// Uses the surfaces' smooth-shading normals (`Surface::shading_normals`, the scene the mesh was
    /// built from) for mirror, dielectric and highlight directions. The geometric normal still decides
    /// the side hit and offsets ray origins.
    pub fn with_shading_normals(mut self, surfaces: &'a [Surface]) -> Self {
        self.surfaces = Some(surfaces);
        self
    }

    /// Traces a caustic map (`trace_photons`, batches in parallel; the photons pass one traced too) so that
    /// `TraceMode::Final` shows LS+D light at pixel resolution: at a diffuse point the map's density
    /// estimate replaces the same light at element resolution, ρ/π·(E_caustic(p) − Ẽ_caustic(p)), Ẽ its
    /// per-element average Gouraud-interpolated as pass one's exitance is. Pass one's extended form
    /// factors keep the amount of LS+D light; the map moves it where it belongs within the elements.
    /// Call after `with_shading_normals`. Does nothing in a scene without specular surfaces.
    pub fn with_caustics(mut self) -> Self {
        use rayon::prelude::*;
        let run = |count: u32, trace: &(dyn Fn(u32) -> (Vec<Landing>, u64) + Sync)| {
            (0..count).into_par_iter().map(trace).collect::<Vec<_>>()
        };
        self.caustics = trace_photons(self.mesh, self.accel, self.materials, self.surfaces, run)
            .map(|photons| CausticMap::new(self.mesh, &photons, self.scale));
        self
    }

    /// The caustic map, if `with_caustics` made one.
    pub fn caustics(&self) -> Option<&CausticMap> {
        self.caustics.as_ref()
    }

    /// The shading normal at `p` on the element's scene surface, oriented like `facing`: the
    /// surface's vertex normals interpolated linearly over the triangle (a quad: over the fan
    /// triangle (0,1,2) or (0,2,3) holding p). Falls back to `facing` where there is none or where it
    /// faces away from `incoming`.
    fn shading_normal(&self, element: usize, p: Vec3, facing: Vec3, incoming: Vec3) -> Vec3 {
        match self.surfaces {
            Some(surfaces) => self.mesh.shading_normal(surfaces, element, p, facing, incoming),
            None => facing,
        }
    }

    /// Total area of the emitting triangles (scene units²).
    pub fn emitter_area(&self) -> f32 {
        self.emitters.total_area
    }

    /// Distance by which secondary ray origins leave a surface.
    pub fn ray_offset(&self) -> f32 {
        self.offset
    }

    /// Radiance arriving at `origin` from direction −`dir` (i.e. carried along the ray
    /// `origin + t·dir`), by Whitted's recursion unrolled onto an explicit stack of
    /// (ray, throughput, depth):
    ///
    /// L = L_d + Ks·L(mirror ray) + Ks·R·L(reflected ray) + (1 − R)·(1 − d)·L(refracted ray),
    ///
    /// with L_d = B(p)/π the Gouraud-interpolated radiosity (emission and all diffuse interreflection),
    /// R the unpolarised Fresnel reflectance of a dielectric with index `Ni`, plus Phong highlights
    /// from the emitters. With `DirectMode::Pixel`, L_d = E/π + (B − E − B_direct)(p)/π + L_direct
    /// where L_direct is estimated with shadow rays (see `direct_light`). Rays deeper than
    /// `max_depth` or with throughput below `min_throughput` are not traced; rays leaving the scene
    /// see black.
    pub fn radiance(&self, origin: Vec3, dir: Vec3, mode: TraceMode, rng: &mut Pcg32, counts: &mut RayCounts) -> Vec3 {
        let mesh = self.mesh;
        let elements = &mesh.elements;
        let mut stack = [StackRay::default(); STACK_SIZE];
        stack[0] = StackRay { origin, dir: dir.normalize(), throughput: Vec3::ONE, depth: 0 };
        let mut len = 1;
        let mut radiance = Vec3::ZERO;

        while len > 0 {
            len -= 1;
            let ray = stack[len];
            if ray.depth == 0 {
                counts.primary += 1;
            } else {
                counts.secondary += 1;
            }
            let Some(hit) = self.accel.closest_hit(ray.origin, ray.dir, 0.0, f32::INFINITY) else {
                continue;
            };
            let t = hit.triangle as usize;
            let front_element = mesh.triangle_element[t] as usize;
            let normal = elements.normal[front_element];
            let front = ray.dir.dot(normal) < 0.0;
            let material = &self.materials[elements.material[front_element] as usize];
            let side = if front {
                Some(SideHit { element: front_element, vertices: mesh.triangles[t] })
            } else if mesh.triangle_back_element[t] != NONE {
                Some(SideHit {
                    element: mesh.triangle_back_element[t] as usize,
                    vertices: mesh.triangle_back_vertices[t],
                })
            } else {
                None
            };
            // The geometric normal on the side the ray arrives from.
            let facing = if front { normal } else { -normal };
            let bary = [1.0 - hit.u - hit.v, hit.u, hit.v];
            let [i0, i1, i2] = mesh.triangles[t];
            let p = mesh.positions[i0 as usize] * bary[0]
                + mesh.positions[i1 as usize] * bary[1]
                + mesh.positions[i2 as usize] * bary[2];
            // The normal that bends specular rays (the geometric one unless smooth shading applies).
            let shading = if mode == TraceMode::Final && material.is_specular() {
                self.shading_normal(front_element, p, facing, ray.dir)
            } else {
                facing
            };

            if let Some(side) = &side {
                let exitance = interpolate(&self.solution.vertex_exitance, side.vertices, bary);
                if mode == TraceMode::Radiosity {
                    radiance += ray.throughput * exitance / PI;
                    continue;
                }
                let reflectance = elements.reflectance[side.element];
                let highlight = match material.phong_exponent {
                    Some(n) if material.specular_reflectance.max_element() > 0.0 => {
                        Some((reflect(ray.dir, shading), n))
                    }
                    _ => None,
                };
                let pixel_direct = self.params.direct == DirectMode::Pixel;
                let needs_light = (pixel_direct && reflectance.max_element() > 0.0) || highlight.is_some();
                let (irradiance, phong) = if needs_light {
                    self.direct_light(p, facing, highlight, rng, counts)
                } else {
                    (Vec3::ZERO, Vec3::ZERO)
                };
                // Caustic detail: the LS+D light at pixel resolution minus the same at element resolution.
                let caustic = match &self.caustics {
                    Some(map) if reflectance.max_element() > 0.0 => {
                        reflectance
                            * (map.irradiance(p, elements.surface[side.element])
                                - map.smooth_irradiance(side.vertices, bary))
                    }
                    _ => Vec3::ZERO,
                };
                let diffuse = if pixel_direct {
                    let emission = elements.emission[side.element];
                    let direct = interpolate(&self.solution.vertex_direct_exitance, side.vertices, bary);
                    let indirect = (exitance - emission - direct + caustic).max(Vec3::ZERO);
                    (emission + indirect) / PI + reflectance / PI * irradiance
                } else {
                    (exitance + caustic).max(Vec3::ZERO) / PI
                };
                radiance += ray.throughput * diffuse;
                if let Some((_, n)) = highlight {
                    // Normalised Phong lobe: f = Ks·(n + 2)/(2π)·cosⁿα.
                    radiance += ray.throughput * material.specular_reflectance * ((n + 2.0) / (2.0 * PI)) * phong;
                }
            } else if mode == TraceMode::Radiosity || !material.is_dielectric() {
                // Back of a one-sided surface: black, and the path ends (a dielectric is still
                // refracting from inside).
                continue;
            }
            if mode == TraceMode::Radiosity || ray.depth >= self.max_depth {
                continue;
            }

            let above = p + facing * self.offset;
            let mut push = |origin: Vec3, dir: Vec3, throughput: Vec3| {
                if throughput.max_element() >= self.params.min_throughput && throughput.max_element() > 0.0 {
                    assert!(len < STACK_SIZE, "ray stack overflow: depth is clamped so this cannot happen");
                    stack[len] = StackRay { origin, dir, throughput, depth: ray.depth + 1 };
                    len += 1;
                }
            };
            if material.is_dielectric() {
                let (eta_i, eta_t) = if front { (1.0, material.ior) } else { (material.ior, 1.0) };
                let cos_i = -ray.dir.dot(shading);
                let reflectance = fresnel_dielectric(cos_i, eta_i, eta_t);
                push(
                    above,
                    mirror(ray.dir, shading, facing),
                    ray.throughput * material.specular_reflectance * reflectance,
                );
                if reflectance < 1.0 {
                    if let Some(refracted) = refract(ray.dir, shading, eta_i / eta_t).filter(|t| t.dot(facing) < 0.0) {
                        let below = p - facing * self.offset;
                        let weight = (1.0 - reflectance) * material.transmittance;
                        push(below, refracted.normalize(), ray.throughput * weight);
                    }
                }
            } else if material.specular_reflectance.max_element() > 0.0 {
                push(above, mirror(ray.dir, shading, facing), ray.throughput * material.specular_reflectance);
            }
        }
        radiance
    }

    /// Light from the emitters at point `p` with unit normal `n` (on the side being shaded), by
    /// `light_samples` shadow rays to points x_k chosen on the emitters by area (stratified in the
    /// area-cumulative coordinate):
    ///
    /// irradiance ≈ (A/N) Σ_k V(p, x_k) L_e(x_k) cos θ_k cos θ'_k / r_k²,
    ///
    /// with A the total emitter area, θ at p, θ' at the emitter (only its emitting side counts). The
    /// diffuse reflected radiance is ρ/π times it. With `highlight = (mirror direction r, exponent n)`
    /// it also returns the same sum weighted by cosⁿα, α the angle between r and the light direction
    /// (the Phong lobe without its Ks·(n + 2)/(2π) normalisation).
    fn direct_light(
        &self,
        p: Vec3,
        n: Vec3,
        highlight: Option<(Vec3, f32)>,
        rng: &mut Pcg32,
        counts: &mut RayCounts,
    ) -> (Vec3, Vec3) {
        let samples = self.params.light_samples;
        if samples == 0 || self.emitters.triangle.is_empty() {
            return (Vec3::ZERO, Vec3::ZERO);
        }
        let mesh = self.mesh;
        let origin = p + n * self.offset;
        let weight = self.emitters.total_area / samples as f32;
        let mut irradiance = Vec3::ZERO;
        let mut phong = Vec3::ZERO;
        for k in 0..samples {
            let xi = (k as f32 + rng.next_f32()) / samples as f32;
            let i = self.emitters.cdf.partition_point(|&c| c <= xi).min(self.emitters.cdf.len() - 1);
            let lo = if i == 0 { 0.0 } else { self.emitters.cdf[i - 1] };
            let hi = self.emitters.cdf[i];
            let s = if hi > lo { ((xi - lo) / (hi - lo)).clamp(0.0, 1.0) } else { 0.5 };
            let r = rng.next_f32();
            let t = self.emitters.triangle[i] as usize;
            let [v0, v1, v2] = mesh.triangles[t].map(|v| mesh.positions[v as usize]);
            // Uniform point on a triangle: √s picks the distance from v0 (Turk 1990).
            let su = s.sqrt();
            let x = v0 * (1.0 - su) + v1 * (su * (1.0 - r)) + v2 * (su * r);

            let to_light = x - origin;
            let dist2 = to_light.length_squared();
            if dist2.is_nan() || dist2 <= 0.0 {
                continue;
            }
            let dist = dist2.sqrt();
            let w = to_light / dist;
            let cos_here = n.dot(w);
            if cos_here <= 0.0 {
                continue;
            }
            let front_element = mesh.triangle_element[t] as usize;
            let cos_front = -mesh.elements.normal[front_element].dot(w);
            let Some(element) = mesh.side_element(t, cos_front > 0.0) else {
                continue;
            };
            let cos_light = cos_front.abs();
            let emitted_radiance = mesh.elements.emission[element] / PI;
            if emitted_radiance.max_element() <= 0.0 || cos_light <= 0.0 {
                continue;
            }
            counts.shadow += 1;
            if self.accel.occluded(origin, w, dist - self.offset) {
                continue;
            }
            let contribution = emitted_radiance * (cos_here * cos_light / dist2 * weight);
            irradiance += contribution;
            if let Some((mirror, exponent)) = highlight {
                let cos_alpha = mirror.dot(w).max(0.0);
                phong += contribution * cos_alpha.powf(exponent);
            }
        }
        (irradiance, phong)
    }
}

/// Mirror direction of `d` about the shading normal, or about the geometric normal `facing` when the
/// shading normal would send it below the surface.
fn mirror(d: Vec3, shading: Vec3, facing: Vec3) -> Vec3 {
    let r = reflect(d, shading);
    if r.dot(facing) > 0.0 {
        r
    } else {
        reflect(d, facing)
    }
}

/// Gouraud interpolation of per-vertex values at barycentrics `bary` of a triangle's corners.
fn interpolate(values: &[Vec3], vertices: [u32; 3], bary: [f32; 3]) -> Vec3 {
    values[vertices[0] as usize] * bary[0]
        + values[vertices[1] as usize] * bary[1]
        + values[vertices[2] as usize] * bary[2]
}
