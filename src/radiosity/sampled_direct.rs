//! The direct irradiance at a point, estimated with shadow rays to points stratified over the
//! emitters: pass one's sampled direct part (the hierarchy's element centres) and the adaptive mesh's
//! test for shadow boundaries between an element's corners.

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use crate::accel::Accel;
use crate::mesh::Mesh;
use crate::rng::Pcg32;
use crate::scene::Material;
use crate::transport::emitters::Emitters;
use crate::transport::hit::{leave_surface, offset_at};

/// The direct irradiance at x (unit normal n, x already off its surface) from `samples` shadow rays
/// to points y_k stratified over the emitters (`Emitters::sample_from`: by power and area, by solid
/// angle on an emitter close to x):
///
/// E_d(x) ≈ (1/K) Σ_k E_k cos θ_x cos θ_k / (π d_k² p_A(y_k)) · V(x, y_k)
///
/// (E_k the emitted exitance of the side of the emitter facing x), and the part of it the shadow rays
/// found blocked: the same sum over the samples with V = 0.
pub fn direct_irradiance_at(
    mesh: &Mesh,
    emitters: &Emitters,
    accel: &Accel,
    x: Vec3,
    n: Vec3,
    samples: u32,
    rng: &mut Pcg32,
) -> DirectLight {
    let e = &mesh.elements;
    let (mut irradiance, mut blocked) = (DVec3::ZERO, DVec3::ZERO);
    for k in 0..samples {
        let xi = (k as f32 + rng.next_f32()) / samples as f32;
        let Some(sample) = emitters.sample_from(mesh, x, xi, rng.next_f32()) else { break };
        let to_light = sample.point - x;
        let dist2 = to_light.length_squared();
        if !(dist2 > 0.0) {
            continue;
        }
        let dist = dist2.sqrt();
        let w = to_light / dist;
        let cos_here = n.dot(w);
        let t = sample.triangle as usize;
        let cos_front = -e.normal[mesh.triangle_element[t] as usize].dot(w);
        let Some(emitter) = mesh.side_element(t, cos_front > 0.0) else { continue };
        if cos_here <= 0.0 {
            continue;
        }
        let g = cos_here * cos_front.abs() / (std::f32::consts::PI * dist2);
        let arriving = (e.emission[emitter] * g * sample.inverse_density).as_dvec3();
        if accel.occluded(x, w, dist - (dist * 1e-4).max(offset_at(sample.point, 0.0))) {
            blocked += arriving;
        } else {
            irradiance += arriving;
        }
    }
    let k = samples.max(1) as f64;
    DirectLight { irradiance: irradiance / k, blocked: blocked / k }
}

/// What `direct_irradiance_at` estimates at a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectLight {
    /// E_d, the direct irradiance.
    pub irradiance: DVec3,
    /// The irradiance the emitters would add with nothing in the way.
    pub blocked: DVec3,
}

/// The offset that moves a point off its surface before its shadow rays: 1e-5 of the mesh's diagonal.
pub fn surface_offset(mesh: &Mesh) -> f32 {
    let (lo, hi) =
        mesh.positions.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    (hi - lo).length() * 1e-5
}

/// The direct part of each element's exitance, B_d,i = ρ_i·E_d(x_i), E_d at its centre x_i by
/// `direct_irradiance_at` with `samples` rays. Each element has its own random stream, so the result
/// does not depend on the thread count.
pub fn sampled_direct_exitance(
    mesh: &Mesh,
    materials: &[Material],
    accel: &Accel,
    samples: u32,
    seed: u64,
) -> Vec<DVec3> {
    let emitters = Emitters::new(mesh, materials);
    let e = &mesh.elements;
    if emitters.is_empty() || samples == 0 {
        return vec![DVec3::ZERO; e.len()];
    }
    let offset = surface_offset(mesh);
    (0..e.len())
        .into_par_iter()
        .map(|i| {
            let rho = e.reflectance[i];
            if rho.max_element() <= 0.0 {
                return DVec3::ZERO;
            }
            let (n, origin) = (e.normal[i], leave_surface(e.centre[i], e.normal[i], offset));
            let mut rng = Pcg32::new(seed ^ 0x6469_7265_6374, i as u64);
            rho.as_dvec3() * direct_irradiance_at(mesh, &emitters, accel, origin, n, samples, &mut rng).irradiance
        })
        .collect()
}
