//! The irradiance an element reflected in pass one, recovered from its exitance: what the light does
//! there, apart from the surface's albedo (a texture's contrast moves exitance, not irradiance).

use glam::{DVec3, Vec3};

use crate::mesh::Mesh;

/// The irradiance H (W/m²) behind a reflected exitance: B = E + ρ·H per channel (Lambertian), so
///   H = (B − E)/ρ  where ρ > 0,  and 0 where ρ = 0 (a black channel reflects nothing, and its
/// irradiance does not reach the image).
pub fn reflected_irradiance(exitance: Vec3, emission: Vec3, reflectance: Vec3) -> Vec3 {
    let f = |b: f32, e: f32, r: f32| if r > 0.0 { (b - e) / r } else { 0.0 };
    Vec3::new(
        f(exitance.x, emission.x, reflectance.x),
        f(exitance.y, emission.y, reflectance.y),
        f(exitance.z, emission.z, reflectance.z),
    )
}

/// Per element of `mesh`, the irradiance Hₑ = (Bₑ − Eₑ)/ρ̄ₑ it reflected (`reflected_irradiance`),
/// ρ̄ₑ and Eₑ the element's own (on a textured surface, the texture's mean over it), given its
/// exitance Bₑ (`element_exitance`; pass `emission = false` for a part of it that holds no
/// emission, such as the direct part).
pub fn element_irradiance(mesh: &Mesh, element_exitance: &[Vec3], emission: bool) -> Vec<DVec3> {
    let e = &mesh.elements;
    assert_eq!(element_exitance.len(), e.len());
    (0..e.len())
        .map(|i| {
            let emitted = if emission { e.emission[i] } else { Vec3::ZERO };
            reflected_irradiance(element_exitance[i], emitted, e.reflectance[i]).as_dvec3()
        })
        .collect()
}
