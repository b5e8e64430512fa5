//! Per-pixel direct light from the emitters: shadow rays to points chosen by power (`Emitters`) on
//! Owen-scrambled Sobol patterns shared across a pixel's samples, and the Phong highlight weighed
//! between light sampling and lobe sampling by multiple importance sampling.

use std::f32::consts::PI;

use glam::Vec3;

use super::whitted::RayCounts;
use crate::accel::Accel;
use crate::film::Sampler;
use crate::mesh::Mesh;
use crate::transport::cut_outs::OpaqueRay;
use crate::transport::emitters::Emitters;
use crate::transport::hit::{leave_surface, offset_at};
use crate::transport::shading::SurfaceNormals;

/// The direct light at a diffuse hit: irradiance E_direct and the highlight integral (see
/// [`DirectLight::estimate`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DirectEstimate {
    /// E = ∫ L_e(ω) cos θ dω over the emitters seen from the point.
    pub irradiance: Vec3,
    /// H = ∫ L_e(ω) cos θ cosⁿα dω, α the angle between ω and the mirror direction (the Phong lobe
    /// without its Ks·(n + 2)/(2π) normalisation); zero without a highlight.
    pub highlight: Vec3,
}

/// The power heuristic with β = 2 (Veach and Guibas 1995): the weight of a sample drawn by strategy a
/// (n_a samples, density p_a) against strategy b: w_a = (n_a p_a)² / ((n_a p_a)² + (n_b p_b)²), and 1
/// where b cannot draw it (p_b = 0). The weights of the two strategies sum to 1 wherever either can
/// draw the sample, so the combination stays unbiased.
pub fn power_heuristic(n_a: f32, p_a: f32, n_b: f32, p_b: f32) -> f32 {
    let a = (n_a * p_a) * (n_a * p_a);
    let b = (n_b * p_b) * (n_b * p_b);
    if a + b > 0.0 {
        a / (a + b)
    } else {
        0.0
    }
}

/// Density (per steradian) of the normalised Phong lobe around the mirror direction,
/// p(ω) = (n + 1)/(2π)·cosⁿα for cos α > 0, else 0.
pub fn phong_lobe_density(cos_alpha: f32, exponent: f32) -> f32 {
    if cos_alpha > 0.0 {
        (exponent + 1.0) / (2.0 * PI) * cos_alpha.powf(exponent)
    } else {
        0.0
    }
}

/// A direction of the Phong lobe around unit `mirror` with density `phong_lobe_density` from uniform
/// (u, v): cos α = u^(1/(n+1)), azimuth φ = 2πv.
pub fn sample_phong_lobe(mirror: Vec3, exponent: f32, [u, v]: [f32; 2]) -> Vec3 {
    let cos_alpha = (1.0 - u).powf(1.0 / (exponent + 1.0));
    let sin_alpha = (1.0 - cos_alpha * cos_alpha).max(0.0).sqrt();
    let phi = 2.0 * PI * v;
    let (t, b) = mirror.any_orthonormal_pair();
    (mirror * cos_alpha + (t * phi.cos() + b * phi.sin()) * sin_alpha).normalize()
}

/// The emitters of one mesh with what shadow rays need. Shared between threads (`&self`).
pub struct DirectLight<'a> {
    mesh: &'a Mesh,
    accel: &'a Accel,
    emitters: Emitters,
    /// Shadow rays per estimate (and lobe rays per highlight).
    samples: u32,
    /// Distance ray origins are moved off a surface (scene units).
    offset: f32,
}

impl<'a> DirectLight<'a> {
    pub fn new(mesh: &'a Mesh, accel: &'a Accel, emitters: Emitters, samples: u32, offset: f32) -> DirectLight<'a> {
        DirectLight { mesh, accel, emitters, samples, offset }
    }

    /// Shadow rays per estimate (and lobe rays per highlight) of the render settings
    /// (`RenderParams::light_samples`).
    pub fn light_samples(&self) -> u32 {
        self.samples
    }

    /// Shadow and highlight rays pass cut-outs, reading their finest texels.
    fn opaque_ray(&self) -> OpaqueRay<'a> {
        OpaqueRay { mesh: self.mesh, accel: self.accel, offset: self.offset, spread_rad: 0.0 }
    }

    pub fn emitters(&self) -> &Emitters {
        &self.emitters
    }

    /// Light from the emitters at point `p` with unit normals `normals` (on the side being shaded: a
    /// `Vec3` for a flat point, else geometric and smooth shading normals), with N =
    /// `samples` shadow rays (the tracer passes [`DirectLight::light_samples`]; a final gather's
    /// near bounce its own count) to points x_k drawn on the emitters with area density p_A(x_k)
    /// (polygon by power, then uniform on it, or uniform in its solid angle from p when p is close
    /// to it; `Emitters::sample_from`) from one `Sampler::pattern_2d`:
    ///
    /// E ≈ (1/N) Σ_k V(p, x_k) L_e(x_k) cos θ_k cos θ'_k / (r_k² p_A(x_k)),
    ///
    /// θ at p, θ' at the emitter (only its emitting side counts). With a shading normal cos θ is
    /// `SurfaceNormals::cosine`: max(0, n_s·ω) normalised, and zero for a sample below the geometric
    /// plane (such a light cannot reach the facet, whatever the shading normal leans towards); rays
    /// leave along the geometric normal. The diffuse reflected radiance is
    /// ρ/π·E. With `highlight = (mirror direction r, exponent n)` it also estimates H (see
    /// [`DirectEstimate`]) by two strategies combined with the power heuristic: the same N light
    /// samples, of solid-angle density p_L(ω) = p_A r²/cos θ', weighted w_L; and N directions drawn
    /// from the Phong lobe (`sample_phong_lobe`, density p_B), each traced to the first surface and
    /// counted, weighted w_B, when it is an emitter's emitting side:
    ///
    /// H ≈ (1/N) Σ_k w_L L_e cos θ cosⁿα / p_L + (1/N) Σ_j w_B L_e cos θ cosⁿα / p_B.
    ///
    /// Light sampling wins for small lights and broad lobes, lobe sampling for large lights and
    /// sharp lobes; the heuristic keeps each where it is better.
    pub fn estimate(
        &self,
        samples: u32,
        p: Vec3,
        normals: impl Into<SurfaceNormals>,
        highlight: Option<(Vec3, f32)>,
        sampler: &mut Sampler,
        counts: &mut RayCounts,
    ) -> DirectEstimate {
        let mut out = DirectEstimate::default();
        if samples == 0 || self.emitters.is_empty() {
            return out;
        }
        let normals = normals.into();
        let mesh = self.mesh;
        let origin = leave_surface(p, normals.geometric, self.offset);
        let count = samples as f32;
        let pattern = sampler.pattern_2d(samples);
        for k in 0..samples {
            let [xi, r] = sampler.point_2d(&pattern, k);
            let Some(sample) = self.emitters.sample_from(mesh, origin, xi, r) else {
                break;
            };
            let to_light = sample.point - origin;
            let dist2 = to_light.length_squared();
            if dist2.is_nan() || dist2 <= 0.0 {
                continue;
            }
            let dist = dist2.sqrt();
            let w = to_light / dist;
            let cos_here = normals.cosine(w);
            if cos_here <= 0.0 {
                continue;
            }
            let Some((emitted_radiance, cos_light)) = self.emitted_towards(sample.triangle as usize, w) else {
                continue;
            };
            counts.shadow += 1;
            if self.opaque_ray().blocked(origin, w, dist - offset_at(sample.point, self.offset)) {
                continue;
            }
            let contribution = emitted_radiance * (cos_here * cos_light / dist2 * sample.inverse_density / count);
            out.irradiance += contribution;
            if let Some((mirror, exponent)) = highlight {
                let cos_alpha = mirror.dot(w).max(0.0);
                let p_light = dist2 / (cos_light * sample.inverse_density);
                let weight = power_heuristic(count, p_light, count, phong_lobe_density(cos_alpha, exponent));
                out.highlight += contribution * (cos_alpha.powf(exponent) * weight);
            }
        }
        if let Some((mirror, exponent)) = highlight {
            out.highlight += self.highlight_by_lobe(samples, origin, normals, mirror, exponent, sampler, counts);
        }
        out
    }

    /// The emitted radiance L_e = E/π of mesh triangle `t` towards direction −`w` (w from the receiver
    /// to the emitter) and cos θ' at the emitter, when that side emits.
    fn emitted_towards(&self, t: usize, w: Vec3) -> Option<(Vec3, f32)> {
        let mesh = self.mesh;
        let front_element = mesh.triangle_element[t] as usize;
        let cos_front = -mesh.elements.normal[front_element].dot(w);
        let element = mesh.side_element(t, cos_front > 0.0)?;
        let cos_light = cos_front.abs();
        let emitted_radiance = mesh.elements.emission[element] / PI;
        (emitted_radiance.max_element() > 0.0 && cos_light > 0.0).then_some((emitted_radiance, cos_light))
    }

    /// The lobe-sampling half of the highlight estimate (see `estimate`): N directions from the Phong
    /// lobe, each weighted by the power heuristic against the light samples' density for it.
    #[allow(clippy::too_many_arguments)]
    fn highlight_by_lobe(
        &self,
        samples: u32,
        origin: Vec3,
        normals: SurfaceNormals,
        mirror: Vec3,
        exponent: f32,
        sampler: &mut Sampler,
        counts: &mut RayCounts,
    ) -> Vec3 {
        let count = samples as f32;
        let pattern = sampler.pattern_2d(samples);
        let mut sum = Vec3::ZERO;
        for j in 0..samples {
            let w = sample_phong_lobe(mirror, exponent, sampler.point_2d(&pattern, j));
            let cos_here = normals.cosine(w);
            if cos_here <= 0.0 {
                continue;
            }
            counts.shadow += 1;
            let Some((hit, dist)) = self.opaque_ray().closest_hit(origin, w, f32::INFINITY) else {
                continue;
            };
            let Some((emitted_radiance, cos_light)) = self.emitted_towards(hit.triangle as usize, w) else {
                continue;
            };
            let p_lobe = phong_lobe_density(mirror.dot(w), exponent);
            if p_lobe <= 0.0 {
                continue;
            }
            let p_light =
                self.emitters.area_density_from(hit.triangle, origin, origin + w * dist) * dist * dist / cos_light;
            let weight = power_heuristic(count, p_lobe, count, p_light);
            // L_e cos θ cosⁿα / p_B = L_e cos θ · 2π/(n + 1).
            sum += emitted_radiance * (cos_here * 2.0 * PI / (exponent + 1.0) * weight / count);
        }
        sum
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn power_heuristic_weights_sum_to_one() {
        for (pa, pb) in [(1.0, 1.0), (0.3, 7.0), (5.0, 0.0), (0.0, 2.0)] {
            let sum = power_heuristic(4.0, pa, 2.0, pb) + power_heuristic(2.0, pb, 4.0, pa);
            assert!((sum - 1.0).abs() < 1e-6, "{pa} {pb}: {sum}");
        }
    }

    #[test]
    fn phong_lobe_samples_follow_their_density() {
        // ∫ cosⁿ⁺¹α dω over the hemisphere around the mirror direction is 2π/(n + 2); estimated as the
        // mean of f/p = cos α · 2π/(n + 1) over lobe samples on a stratified 64×64 grid. The integrand
        // is smooth in u, so the midpoint rule's error is far below the 0.1% allowed.
        let mirror = Vec3::new(0.3, 0.8, -0.52).normalize();
        let exponent = 8.0;
        let m = 64;
        let mut sum = 0.0f64;
        for i in 0..m {
            for j in 0..m {
                let u = [(i as f32 + 0.5) / m as f32, (j as f32 + 0.5) / m as f32];
                let w = sample_phong_lobe(mirror, exponent, u);
                assert!((w.length() - 1.0).abs() < 1e-5);
                let cos_alpha = mirror.dot(w);
                let f = cos_alpha.powf(exponent + 1.0);
                sum += (f / phong_lobe_density(cos_alpha, exponent)) as f64;
            }
        }
        let mean = sum / (m * m) as f64;
        let exact = 2.0 * std::f64::consts::PI / (exponent as f64 + 2.0);
        assert!((mean - exact).abs() < 1e-3 * exact, "{mean} vs {exact}");
    }
}
