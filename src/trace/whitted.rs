//! The Whitted tracer (Whitted 1980) over a radiosity solution: an explicit stack of rays instead of
//! recursion, the diffuse term from `diffuse`, the specular branches from `transport::scatter`, Phong
//! highlights and (optionally) per-pixel direct light from the emitters with shadow rays.

use std::f32::consts::PI;
use std::ops::AddAssign;

use glam::{Vec2, Vec3};

use super::caustics::CausticMap;
use super::diffuse::{Diffuse, DiffuseEstimator};
use super::direct_light::{DirectEstimate, DirectLight};
use super::gather::{FinalGather, NearBounce};
use super::parts::{RadianceParts, Record};
use crate::accel::Accel;
use crate::film::Sampler;
use crate::material::MaterialMaps;
use crate::mesh::Mesh;
use crate::radiosity::Solution;
use crate::scene::{Material, RenderParams, Surface};
use crate::transport::cut_outs::OpaqueRay;
use crate::transport::emitters::Emitters;
use crate::transport::hit::{ray_offset, scene_scale};
use crate::transport::optics::reflect;
use crate::transport::ray_stack::RayStack;
use crate::transport::scatter::scatter;
use crate::transport::{Photons, SurfaceHit, SurfaceNormals};

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

/// Pass two over one meshed scene and its radiosity solution. Shared between threads (`&self`); each
/// thread brings its own sampler and ray counts.
pub struct Tracer<'a> {
    mesh: &'a Mesh,
    accel: &'a Accel,
    diffuse: Diffuse<'a>,
    materials: &'a [Material],
    params: RenderParams,
    max_depth: u32,
    direct: DirectLight<'a>,
    /// Distance ray origins are moved off a surface (scene units).
    offset: f32,
    /// The scene's surfaces, when their smooth-shading normals should bend specular rays.
    surfaces: Option<&'a [Surface]>,
    /// Light traced from the emitters through mirrors and glass (`with_caustics`).
    caustics: Option<CausticMap>,
    /// The scene's size, which the caustic kernel is relative to.
    scale: f32,
    /// Angle one pixel subtends at the camera (radians), for texture footprints (`with_pixel_angle`).
    pixel_angle_rad: f32,
    /// The final gather that replaces the interpolated indirect light (`with_final_gather`).
    gather: Option<FinalGather>,
    /// The gather's second bounce at near hits (`RenderParams::near_bounce_for`; `None` when 0).
    near_bounce: Option<NearBounce>,
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

        let scale = scene_scale(mesh);
        Ok(Tracer {
            mesh,
            accel,
            diffuse: Diffuse::new(mesh, solution, DiffuseEstimator::from(params.direct)),
            materials,
            params: params.clone(),
            max_depth: params.max_depth.min(MAX_DEPTH_LIMIT),
            direct: DirectLight::new(
                mesh,
                accel,
                Emitters::new(mesh, materials),
                params.light_samples,
                ray_offset(scale),
            ),
            offset: ray_offset(scale),
            surfaces: None,
            caustics: None,
            scale,
            pixel_angle_rad: 0.0,
            gather: None,
            near_bounce: Some(params.near_bounce_for(solution.leaf_geometry.is_some()))
                .filter(|bounce| bounce.distance_factor > 0.0)
                .map(|bounce| {
                    NearBounce::new(bounce.distance_factor, bounce.rays).with_shadow_factor(bounce.shadow_factor)
                }),
        })
    }

    /// Uses the surfaces' smooth-shading normals (`Surface::shading_normals`, the scene the mesh was
    /// built from) for mirror, dielectric and highlight directions and for the diffuse term's cosines
    /// (direct light and final gather, `transport::shading`). The geometric normal still decides the
    /// side hit, which light may arrive, and offsets ray origins.
    pub fn with_shading_normals(mut self, surfaces: &'a [Surface]) -> Self {
        self.surfaces = Some(surfaces);
        self
    }

    /// Sets the angle a pixel subtends (vfov / height for a pinhole camera), from which texture lookups
    /// choose their mip level: a hit at distance t sees a footprint of t·angle scene units. Without it
    /// textures are read at full resolution.
    pub fn with_pixel_angle(mut self, pixel_angle_rad: f32) -> Self {
        self.pixel_angle_rad = if pixel_angle_rad.is_finite() { pixel_angle_rad.max(0.0) } else { 0.0 };
        self
    }

    /// A textured quantity at `hit`, reached after `distance` along the ray: `lookup(maps, uv,
    /// footprint_uv)` when `has_map(maps)`, or `None` when the material lacks that map or the surface
    /// has no uv. The lookup is trilinear over a footprint of distance·pixel angle scene units,
    /// converted to uv units by the triangle's uv-per-length (`SurfaceHit::uv_per_length`).
    fn texel_at<T>(
        &self,
        hit: &SurfaceHit,
        distance: f32,
        has_map: impl Fn(&MaterialMaps) -> bool,
        lookup: impl Fn(&MaterialMaps, Vec2, f32) -> T,
    ) -> Option<T> {
        let mesh = self.mesh;
        let maps = mesh.textures.maps(hit.material).filter(|m| has_map(m))?;
        if !mesh.surface_has_uv.get(hit.surface as usize).copied().unwrap_or(false) {
            return None;
        }
        let footprint_uv = distance * self.pixel_angle_rad * hit.uv_per_length(mesh);
        Some(lookup(maps, hit.uv, footprint_uv))
    }

    /// Texel albedo ρ(x) of the diffuse term at `hit` (`texel_at` with `map_Kd`). Pass two's texture
    /// ratio ρ(x)/ρ̄ₑ is applied through the interpolated irradiance, see `Diffuse::radiance`.
    fn texel_albedo_at(&self, hit: &SurfaceHit, distance: f32) -> Option<Vec3> {
        self.texel_at(hit, distance, MaterialMaps::has_diffuse_texture, MaterialMaps::albedo_at)
    }

    /// Emitted radiance Ke·t(uv) at `hit` (`texel_at` with `map_Ke`).
    fn texel_emission_at(&self, hit: &SurfaceHit, distance: f32) -> Option<Vec3> {
        self.texel_at(hit, distance, MaterialMaps::has_emission_texture, MaterialMaps::emission_at)
    }

    /// Takes the diffuse term's indirect light from `gather` in `TraceMode::Final` (see
    /// `Diffuse::radiance`).
    pub fn with_final_gather(mut self, gather: FinalGather) -> Self {
        self.gather = Some(gather);
        self
    }

    pub fn mesh(&self) -> &Mesh {
        self.mesh
    }

    pub fn materials(&self) -> &[Material] {
        self.materials
    }

    pub fn diffuse(&self) -> &Diffuse<'a> {
        &self.diffuse
    }

    pub fn surfaces(&self) -> Option<&[Surface]> {
        self.surfaces
    }

    /// The normals a diffuse hit is shaded with: geometric and, where the scene's surfaces give vertex
    /// normals, the smooth one (as `SurfaceHit::with_shading_normal` sets it; `SurfaceHit::normals`).
    pub fn smooth_normals(&self, hit: &SurfaceHit) -> SurfaceNormals {
        match self.surfaces {
            Some(surfaces) => SurfaceNormals {
                geometric: hit.geometric_normal,
                shading: self.mesh.smooth_normal(
                    surfaces,
                    hit.front_element as usize,
                    hit.position,
                    hit.geometric_normal,
                ),
            },
            None => SurfaceNormals::flat(hit.geometric_normal),
        }
    }

    /// Per-pixel direct light from the emitters (shadow rays).
    pub fn direct_light(&self) -> &DirectLight<'a> {
        &self.direct
    }

    /// The gather's second bounce at near hits, if on.
    pub fn near_bounce(&self) -> Option<&NearBounce> {
        self.near_bounce.as_ref()
    }

    pub fn min_throughput(&self) -> f32 {
        self.params.min_throughput
    }

    /// The closest hit along a ray that is not cut out (`transport::cut_outs`, with this tracer's pixel
    /// footprint), and its distance from `origin`.
    pub fn closest_opaque_hit(&self, origin: Vec3, dir: Vec3) -> Option<(SurfaceHit, f32)> {
        let ray =
            OpaqueRay { mesh: self.mesh, accel: self.accel, offset: self.offset, spread_rad: self.pixel_angle_rad };
        ray.closest_hit(origin, dir, f32::INFINITY)
    }

    /// Builds a caustic map from the run's `photons` (`transport::photons`, the ones pass one's
    /// extended form factors read too) so that `TraceMode::Final` shows LS+D light at pixel
    /// resolution: at a diffuse point the map's density estimate replaces the same light at element
    /// resolution, ρ·(E_caustic(p) − Ẽ_caustic(p)), Ẽ its per-element average Gouraud-interpolated as
    /// pass one's exitance is. Pass one's extended form factors keep the amount of LS+D light; the map
    /// moves it where it belongs within the elements.
    pub fn with_caustics(mut self, photons: &Photons) -> Self {
        self.caustics = Some(CausticMap::new(self.mesh, photons, self.scale));
        self
    }

    /// The caustic map, if `with_caustics` made one.
    pub fn caustics(&self) -> Option<&CausticMap> {
        self.caustics.as_ref()
    }

    /// Total area of the emitting triangles (scene units²).
    pub fn emitter_area(&self) -> f32 {
        self.direct.emitters().total_area()
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
    /// with L_d the diffuse term (`Diffuse::radiance`: the Gouraud-interpolated radiosity B(p)/π, or
    /// with `DirectMode::Pixel` its indirect part plus direct light from shadow rays, see
    /// `DirectLight::estimate`, both with the smooth shading normal where the surface has vertex
    /// normals), the branches' weights from `transport::scatter` (R the unpolarised Fresnel
    /// reflectance of a dielectric with index `Ni`), plus Phong highlights from the emitters. Rays
    /// deeper than `max_depth` or below `min_throughput` (`transport::scatter::carries`) are not
    /// traced; rays leaving the scene see black.
    pub fn radiance(
        &self,
        origin: Vec3,
        dir: Vec3,
        mode: TraceMode,
        sampler: &mut Sampler,
        counts: &mut RayCounts,
    ) -> Vec3 {
        self.trace(origin, dir, mode, sampler, counts, &mut ())
    }

    /// `radiance` in the final mode, split into its parts (`RadianceParts`) for layered output; the
    /// beauty is the same value `radiance` returns.
    pub fn radiance_parts(
        &self,
        origin: Vec3,
        dir: Vec3,
        sampler: &mut Sampler,
        counts: &mut RayCounts,
    ) -> RadianceParts {
        let mut parts = RadianceParts::default();
        parts.beauty = self.trace(origin, dir, TraceMode::Final, sampler, counts, &mut parts);
        parts
    }

    /// The loop of `radiance`, recording the parts of the light into `record` when it keeps them.
    fn trace<R: Record>(
        &self,
        origin: Vec3,
        dir: Vec3,
        mode: TraceMode,
        sampler: &mut Sampler,
        counts: &mut RayCounts,
        record: &mut R,
    ) -> Vec3 {
        let mesh = self.mesh;
        let elements = &mesh.elements;
        let mut stack = RayStack::<STACK_SIZE>::new(origin, dir);
        let mut radiance = Vec3::ZERO;

        while let Some(ray) = stack.pop() {
            if ray.depth == 0 {
                counts.primary += 1;
            } else {
                counts.secondary += 1;
            }
            let Some((hit, distance)) = self.closest_opaque_hit(ray.origin, ray.dir) else {
                continue;
            };
            let material = &self.materials[hit.material as usize];
            // The smooth normal of the diffuse term and the one that bends specular rays (both the
            // geometric one unless the surface has vertex normals).
            let hit =
                if mode == TraceMode::Final { hit.with_shading_normal(mesh, self.surfaces, ray.dir) } else { hit };
            let (p, normals) = (hit.position, hit.normals());
            if let Some(parts) = record.parts().filter(|_| ray.depth == 0) {
                parts.normal = hit.smooth_normal;
                parts.depth = distance;
            }

            if let Some(element) = hit.element.map(|e| e as usize) {
                let exitance = self.diffuse.radiosity_at(&hit);
                let texel_albedo = self.texel_albedo_at(&hit, distance);
                // With `map_Ke` the diffuse term takes its textured form (the element's flat emission Eₑ
                // plus reflected light ρ·H(p)), and Eₑ/π is then swapped for the texel's Ke·t(uv).
                let emission_swap =
                    self.texel_emission_at(&hit, distance).map(|texel| texel - elements.emission[element] / PI);
                let texel_albedo = texel_albedo.or(emission_swap.map(|_| elements.reflectance[element]));
                let emission_swap = emission_swap.unwrap_or(Vec3::ZERO);
                if mode == TraceMode::Radiosity {
                    radiance += ray.throughput
                        * (self.diffuse.radiosity_radiance(&hit, element, exitance, texel_albedo) + emission_swap);
                    continue;
                }
                // The texel albedo on a textured surface, the element's reflectance otherwise.
                let reflectance = texel_albedo.unwrap_or(elements.reflectance[element]);
                let highlight = match material.phong_exponent {
                    Some(n) if material.specular_reflectance.max_element() > 0.0 => {
                        Some((reflect(ray.dir, hit.shading_normal), n))
                    }
                    _ => None,
                };
                let needs_light =
                    (self.diffuse.needs_direct_light() && reflectance.max_element() > 0.0) || highlight.is_some();
                let light = if needs_light {
                    self.direct.estimate(self.direct.light_samples(), p, normals, highlight, sampler, counts)
                } else {
                    DirectEstimate::default()
                };
                // Caustic light (LS+D): without a gather, the detail the element solution misses, the map's
                // light at pixel resolution minus the same at element resolution; with a gather, all of
                // it, since the gather leaves the paths through mirrors and glass to an emitter to the map
                // (`gather_radiance`); all of it too over a solution without it (a hierarchical solution file from before session 23).
                let caustic = match &self.caustics {
                    Some(map) if reflectance.max_element() > 0.0 => {
                        let in_solution = if self.gather.is_none() && self.diffuse.holds_caustic_light() {
                            map.smooth_irradiance(&hit)
                        } else {
                            Vec3::ZERO
                        };
                        reflectance * (map.irradiance(p, hit.surface) - in_solution)
                    }
                    _ => Vec3::ZERO,
                };
                let gathered = match &self.gather {
                    Some(g) if reflectance.max_element() > 0.0 => Some(g.irradiance(self, p, normals, sampler, counts)),
                    _ => None,
                };
                let diffuse = self.diffuse.radiance(
                    &hit,
                    element,
                    exitance,
                    reflectance,
                    texel_albedo.is_some(),
                    (light.irradiance, gathered),
                    caustic,
                );
                radiance += ray.throughput * (diffuse + emission_swap);
                if let Some(parts) = record.parts() {
                    if ray.depth == 0 {
                        let emitted = elements.emission[element] / PI + emission_swap;
                        let direct =
                            self.diffuse.direct_radiance(&hit, reflectance, texel_albedo.is_some(), light.irradiance);
                        parts.albedo = reflectance;
                        parts.emitted += ray.throughput * emitted;
                        parts.direct += ray.throughput * direct;
                        parts.indirect += ray.throughput * (diffuse + emission_swap - emitted - direct);
                    } else {
                        parts.specular += ray.throughput * (diffuse + emission_swap);
                    }
                }
                if let Some((_, n)) = highlight {
                    // Normalised Phong lobe: f = Ks·(n + 2)/(2π)·cosⁿα.
                    let lobe =
                        ray.throughput * material.specular_reflectance * ((n + 2.0) / (2.0 * PI)) * light.highlight;
                    radiance += lobe;
                    if let Some(parts) = record.parts() {
                        parts.specular += lobe;
                    }
                }
            } else if mode == TraceMode::Radiosity || !material.is_dielectric() {
                // Back of a one-sided surface: black, and the path ends (a dielectric is still
                // refracting from inside).
                continue;
            }
            if mode == TraceMode::Radiosity || ray.depth >= self.max_depth {
                continue;
            }

            stack.push_branches(&ray, &scatter(material, ray.dir, &hit), &hit, self.offset, self.params.min_throughput);
        }
        radiance
    }
}
