//! The specular rules of smooth surfaces, written once for both passes (Whitted 1980): a mirror
//! reflects with its Ks; a dielectric reflects with Ks·R and refracts with (1 − R)·(1 − d)·Tf on the
//! way in, (1 − R)·(1 − d) on the way out, R the unpolarised Fresnel reflectance and Tf the
//! transmission filter colour; and the one throughput cutoff that ends a branch.
//!
//! Radiance changes across a refracting interface: L/η² is what a path conserves (Veach 1997,
//! §5.2), so light passing from a medium of index η_t into one of index η_i arrives with radiance
//! ×(η_i/η_t)². A ray traced from the eye or a gathering point (`Scatter::split`) meets that light
//! going the other way: its refracted branch takes the factor (η_i/η_t)², η_i the index on the side
//! the ray comes from. Through a closed solid the two crossings cancel; a diffuse surface inside a
//! dielectric (a pool's floor under its water) is seen 1/η² as bright as in air. Photons
//! (`Scatter::choose`) carry flux, which needs no factor.

use glam::Vec3;

use super::hit::SurfaceHit;
use super::optics::{fresnel_dielectric, reflect, refract};
use crate::scene::Material;

/// What a smooth surface does to a ray that meets it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Scatter {
    /// Neither mirror nor glass: no specular branch.
    None,
    /// A mirror: one reflected branch with weight Ks.
    Mirror { dir: Vec3, reflectance: Vec3 },
    /// A smooth dielectric: a reflected branch with weight Ks·R and, unless light cannot leave on the
    /// other side (total internal reflection, or a shading normal that allows no refraction), a
    /// refracted branch with weight (1 − R)·T, T = (1 − d)·Tf entering and 1 − d leaving.
    Dielectric {
        reflected: Vec3,
        refracted: Option<Vec3>,
        /// R, the unpolarised Fresnel reflectance (`fresnel_dielectric`).
        fresnel: f32,
        /// Ks.
        reflectance: Vec3,
        /// T per channel: (1 − d)·Tf when the ray enters the front side, 1 − d when it leaves.
        transmittance: Vec3,
        /// (η_i/η_t)²: what radiance traced backwards through the interface is multiplied by (see the
        /// module); 1/Ni² entering, Ni² leaving.
        radiance_scale: f32,
    },
}

/// One ray leaving a specular surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Branch {
    pub dir: Vec3,
    /// The ray goes through the surface (its origin is below it, `SurfaceHit::below`).
    pub transmitted: bool,
    /// The path's throughput after the surface.
    pub throughput: Vec3,
    /// The refraction's radiance factor (η_i/η_t)² in `throughput` (1 for a reflection), which the
    /// throughput cutoff leaves out (`ray_stack`).
    pub radiance_scale: f32,
}

impl Branch {
    /// Where the branch's ray starts, `offset` off the surface on the side it leaves by.
    pub fn origin(&self, hit: &SurfaceHit, offset: f32) -> Vec3 {
        if self.transmitted {
            hit.below(offset)
        } else {
            hit.above(offset)
        }
    }
}

/// The specular response of `material` to a ray of unit direction `dir` at `hit`: directions from the
/// shading normal n_s (mirror: r = d − 2(d·n_s)n_s, falling back to the geometric normal when r would
/// leave below the surface; refraction by Snell's law with η_i/η_t = 1/Ni entering, Ni leaving), and
/// R = `fresnel_dielectric`(−d·n_s, η_i, η_t).
///
/// The filter colour Tf (`Material::transmission_filter`) tints light once per passage through a closed
/// solid, when it enters by the front: a glass slab or sphere of filter Tf passes T·Tf, not T·Tf², since
/// MTL's Tf describes the object, not each of its interfaces.
pub fn scatter(material: &Material, dir: Vec3, hit: &SurfaceHit) -> Scatter {
    let (shading, facing) = (hit.shading_normal, hit.geometric_normal);
    if material.is_dielectric() {
        let (eta_i, eta_t) = if hit.front { (1.0, material.ior) } else { (material.ior, 1.0) };
        let fresnel = fresnel_dielectric(-dir.dot(shading), eta_i, eta_t);
        Scatter::Dielectric {
            reflected: mirror(dir, shading, facing),
            refracted: refract(dir, shading, eta_i / eta_t).filter(|t| t.dot(facing) < 0.0).map(Vec3::normalize),
            fresnel,
            reflectance: material.specular_reflectance,
            transmittance: material.transmittance * if hit.front { material.transmission_filter } else { Vec3::ONE },
            radiance_scale: (eta_i / eta_t) * (eta_i / eta_t),
        }
    } else if material.specular_reflectance.max_element() > 0.0 {
        Scatter::Mirror { dir: mirror(dir, shading, facing), reflectance: material.specular_reflectance }
    } else {
        Scatter::None
    }
}

impl Scatter {
    /// Both branches of a path with throughput T traced backwards, from the eye or a gathering point
    /// (Whitted's tree): mirror T·Ks; dielectric reflected T·Ks·R and, when R < 1, refracted
    /// T·(1 − R)·T_d·(η_i/η_t)² (`Scatter::Dielectric::transmittance`, `radiance_scale`: see the
    /// module). The reflected branch comes first.
    pub fn split(&self, throughput: Vec3) -> [Option<Branch>; 2] {
        match *self {
            Scatter::None => [None, None],
            Scatter::Mirror { dir, reflectance } => [
                Some(Branch { dir, transmitted: false, throughput: throughput * reflectance, radiance_scale: 1.0 }),
                None,
            ],
            Scatter::Dielectric { reflected, refracted, fresnel, reflectance, transmittance, radiance_scale } => [
                Some(Branch {
                    dir: reflected,
                    transmitted: false,
                    throughput: throughput * reflectance * fresnel,
                    radiance_scale: 1.0,
                }),
                refracted.filter(|_| fresnel < 1.0).map(|dir| Branch {
                    dir,
                    transmitted: true,
                    throughput: throughput * ((1.0 - fresnel) * radiance_scale * transmittance),
                    radiance_scale,
                }),
            ],
        }
    }

    /// One branch by Russian roulette (a photon keeps a single path): a dielectric that can refract
    /// reflects with probability R, drawn as `u() < R` (u uniform in [0, 1), drawn only then), so the
    /// weights divided by their probabilities are Ks and T_d; one that cannot refract reflects with
    /// Ks·R. Returns (direction, transmitted, factor): the new throughput is T·factor.
    pub fn choose(&self, u: impl FnOnce() -> f32) -> Option<(Vec3, bool, Vec3)> {
        match *self {
            Scatter::None => None,
            Scatter::Mirror { dir, reflectance } => Some((dir, false, reflectance)),
            Scatter::Dielectric { reflected, refracted, fresnel, reflectance, transmittance, .. } => match refracted {
                Some(dir) if u() >= fresnel => Some((dir, true, transmittance)),
                Some(_) => Some((reflected, false, reflectance)),
                None => Some((reflected, false, reflectance * fresnel)),
            },
        }
    }
}

/// The one cutoff rule: a branch is followed while the largest channel of its throughput is positive
/// and at least `min_throughput`. The largest channel, not the mean, so that a strongly tinted path
/// (red glass) is not dropped while one of its channels still carries light.
pub fn carries(throughput: Vec3, min_throughput: f32) -> bool {
    let largest = throughput.max_element();
    largest > 0.0 && largest >= min_throughput
}

/// Mirror direction of `d` about the shading normal, or about the geometric normal `facing` when the
/// shading normal would send it below the surface.
pub fn mirror(d: Vec3, shading: Vec3, facing: Vec3) -> Vec3 {
    let r = reflect(d, shading);
    if r.dot(facing) > 0.0 {
        r
    } else {
        reflect(d, facing)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A hit by a ray going down (−y): the normals face the ray; `front` says which side it is.
    fn hit(front: bool) -> SurfaceHit {
        let n = Vec3::Y;
        SurfaceHit {
            position: Vec3::ZERO,
            geometric_normal: n,
            shading_normal: n,
            smooth_normal: n,
            triangle: 0,
            front,
            front_element: 0,
            element: Some(0),
            surface: 0,
            vertices: [0, 1, 2],
            bary: [1.0 / 3.0; 3],
            uv: glam::Vec2::ZERO,
            material: 0,
        }
    }

    /// Straight through a clear glass (n = 1.5) interface: entering, the refracted branch of a ray
    /// traced backwards carries (1 − R)/n² (radiance grows by n² towards the denser side, so what the
    /// ray reads there counts 1/n²); leaving, (1 − R)·n². Through a closed solid they cancel, leaving
    /// the two interfaces' (1 − R)².
    #[test]
    fn refraction_scales_backward_radiance_by_the_squared_index_ratio() {
        let glass = Material {
            ior: 1.5,
            transmittance: 1.0,
            specular_reflectance: Vec3::ONE,
            ..Material::diffuse("glass", Vec3::ZERO)
        };
        assert!(glass.is_dielectric());
        let r = fresnel_dielectric(1.0, 1.0, 1.5);
        let into = scatter(&glass, Vec3::NEG_Y, &hit(true)).split(Vec3::ONE)[1].expect("refracts");
        let out = scatter(&glass, Vec3::NEG_Y, &hit(false)).split(Vec3::ONE)[1].expect("refracts");
        assert!((into.throughput.x - (1.0 - r) / 2.25).abs() < 1e-6, "{}", into.throughput);
        assert!((out.throughput.x - (1.0 - r) * 2.25).abs() < 1e-6, "{}", out.throughput);
        assert!((into.radiance_scale - 1.0 / 2.25).abs() < 1e-7 && out.radiance_scale == 2.25);
        assert!((into.throughput.x * out.throughput.x - (1.0 - r) * (1.0 - r)).abs() < 1e-6);
        // Photons carry flux: no factor.
        let (_, transmitted, factor) = scatter(&glass, Vec3::NEG_Y, &hit(true)).choose(|| 0.5).unwrap();
        assert!(transmitted);
        assert_eq!(factor, Vec3::ONE);
    }
}
