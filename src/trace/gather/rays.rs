//! The rays of one final gather: a stratified cosine-weighted hemisphere at a diffuse point, each ray
//! reading the radiosity solution where it lands (less the emission, which the direct term holds), or
//! estimating it again at the point where the hit is near (`near`), with mirrors and glass on the way
//! followed by the Whitted rules to a bounded depth.

use std::f32::consts::PI;

use glam::Vec3;

use super::hemisphere::{estimate, fill_untraced, frame, HemisphereEstimate, Strata};
use super::near::NearBounce;
use crate::film::Sampler;
use crate::trace::whitted::{RayCounts, Tracer};
use crate::transport::hit::leave_surface;
use crate::transport::ray_stack::RayStack;
use crate::transport::scatter::scatter;
use crate::transport::shading::SurfaceNormals;

/// Specular bounces a gather ray follows (mirror, glass) before it stops.
pub const GATHER_SPECULAR_DEPTH: u32 = 4;
const GATHER_STACK: usize = GATHER_SPECULAR_DEPTH as usize + 2;

impl Tracer<'_> {
    /// The gather at point `p` with unit normals `normals` (the side being shaded: a `Vec3` for a flat
    /// point, else geometric and smooth shading normals) over `strata`, one jittered ray per cell
    /// (`gather_radiance`), and its irradiance, harmonic mean distance and gradients
    /// (`hemisphere::estimate`). The irradiance is the indirect part: light from the emitters along
    /// straight lines is left out; what arrives through mirrors and glass is in. Near hits get the
    /// tracer's second bounce (`[render] near_bounce`, see `near`). With a caustic map (`Tracer::with_caustics`)
    /// the light of emitters seen through mirrors and glass is left out too: the map holds all of it
    /// (LS+D), with less noise than rays that must find a small emitter through a curved mirror, and
    /// the camera hit adds it once (`Diffuse::radiance`'s caustic term).
    ///
    /// With a shading normal n_s the cells are cosine-weighted around n_s (the Lambertian lobe of the
    /// smooth surface) and rays leave along the geometric normal n_g. A cell whose direction lies
    /// below the geometric plane (n_g·ω ≤ 0: a sliver of the outer rings on the side n_s leans away
    /// from) is not traced: light cannot arrive through the facet. Its share of the lobe goes to the
    /// traced cells (`hemisphere::fill_untraced`: it reads their mean radiance), so the estimate is
    /// E = π·(1/T) Σ_traced L_jk, T the cells traced: the Lambertian integral over the directions
    /// above the facet renormalised to the whole lobe, ∫_{n_g·ω>0} L max(0, n_s·ω) dω / c with
    /// c = (1 + n_s·n_g)/2 its share there, as the direct light weighs it (`SurfaceNormals::cosine`).
    /// Under uniform radiance L it is πL exactly, at every tilt: a white furnace stays exact.
    /// Counting the cell as zero and dividing the sum by c instead would be unbiased too, but a cell
    /// the plane cuts then reads all or nothing: at the corners of a coarse sphere (n_s 30° off the
    /// facet) some 25 of 256 cells straddle the plane, and a furnace's pixels scattered by ±1%
    /// (tests/shading_normals.rs) where the mean gives 0; the cache's gradients would also see a
    /// dark horizon that is not there. The mean is a ratio estimator: its bias, O(1/T) where the
    /// field varies, is far below the gather's own noise.
    pub fn gather(
        &self,
        p: Vec3,
        normals: impl Into<SurfaceNormals>,
        strata: Strata,
        sampler: &mut Sampler,
        counts: &mut RayCounts,
    ) -> HemisphereEstimate {
        let normals = normals.into();
        let n = normals.shading;
        let (t, b) = frame(n);
        let origin = leave_surface(p, normals.geometric, self.ray_offset());
        let mut radiance = Vec::with_capacity(strata.cells());
        let mut distance = Vec::with_capacity(strata.cells());
        let mut traced = Vec::with_capacity(strata.cells());
        for j in 0..strata.rings {
            for k in 0..strata.sectors {
                let local = strata.direction(j, k, sampler.next_1d(), sampler.next_1d());
                let dir = (t * local.x + b * local.y + n * local.z).normalize();
                let admitted = normals.admits(dir);
                let (l, r) = if admitted {
                    self.gather_radiance(origin, dir, self.near_bounce(), sampler, counts)
                } else {
                    (Vec3::ZERO, f32::INFINITY)
                };
                radiance.push(l);
                distance.push(r);
                traced.push(admitted);
            }
        }
        fill_untraced(&mut radiance, &mut distance, &traced);
        estimate(strata, &radiance, &distance, n)
    }

    /// Radiance arriving at `origin` from `dir` as the gather counts it, and the distance to the first
    /// surface (infinite if none): at a diffuse hit x on element e, (B(x) − E_e)/π, with B the
    /// interpolated exitance (`Diffuse::radiosity_at`); the emission E_e counts only after a specular
    /// bounce (shadow rays and pass one's direct part see straight paths only), and only when the
    /// tracer has no caustic map. With `near`, a first
    /// hit closer than `NearBounce::applies` reads B(x) − E from `near_exitance` instead, estimated at
    /// x. Mirrors and glass add their branches (`transport::scatter`) up to `GATHER_SPECULAR_DEPTH`
    /// bounces; with a caustic map, the emission reached after a specular bounce is the map's and is
    /// left out as at a straight hit (B − E), so the caustic is not counted twice.
    pub fn gather_radiance(
        &self,
        origin: Vec3,
        dir: Vec3,
        near: Option<&NearBounce>,
        sampler: &mut Sampler,
        counts: &mut RayCounts,
    ) -> (Vec3, f32) {
        let mut stack = RayStack::<GATHER_STACK>::new(origin, dir);
        let mut radiance = Vec3::ZERO;
        let mut first_distance = f32::INFINITY;
        let elements = &self.mesh().elements;
        let caustics_mapped = self.caustics().is_some();
        while let Some(ray) = stack.pop() {
            counts.secondary += 1;
            let Some((hit, distance)) = self.closest_opaque_hit(ray.origin, ray.dir) else {
                continue;
            };
            if ray.depth == 0 {
                first_distance = distance;
            }
            let material = &self.materials()[hit.material as usize];
            if let Some(element) = hit.element.map(|e| e as usize) {
                let reflected = match near {
                    Some(near) if ray.depth == 0 && near.applies(distance, elements.area[element]) => {
                        self.near_exitance(&hit, element, near, distance, sampler, counts)
                    }
                    _ => {
                        let exitance = self.diffuse().radiosity_at(&hit);
                        let emission =
                            if ray.depth == 0 || caustics_mapped { elements.emission[element] } else { Vec3::ZERO };
                        exitance - emission
                    }
                };
                radiance += ray.throughput * reflected.max(Vec3::ZERO) / PI;
            } else if !material.is_dielectric() {
                continue;
            }
            if ray.depth >= GATHER_SPECULAR_DEPTH || !material.is_specular() {
                continue;
            }
            let hit = hit.with_shading_normal(self.mesh(), self.surfaces(), ray.dir);
            stack.push_branches(
                &ray,
                &scatter(material, ray.dir, &hit),
                &hit,
                self.ray_offset(),
                self.min_throughput(),
            );
        }
        (radiance, first_distance)
    }
}
