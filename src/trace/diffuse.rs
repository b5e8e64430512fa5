//! Pass two's diffuse term: the radiosity solution read back at a hit, and the estimator that turns it
//! (with per-pixel direct light and caustic detail when asked for) into the radiance a diffuse surface
//! sends towards the eye.

use std::f32::consts::PI;

use glam::Vec3;

use crate::mesh::Mesh;
use crate::radiosity::Solution;
use crate::scene::DirectMode;
use crate::transport::SurfaceHit;

/// How the light a diffuse surface reflects is estimated. (A final gather, rays from the hit reading
/// the solution where they land, would be a further estimator here.)
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DiffuseEstimator {
    /// L_d = B(p)/π: the Gouraud-interpolated radiosity holds all diffuse light, direct light
    /// included (shadows at element resolution).
    Interpolated,
    /// L_d = E/π + (B − E − B_direct)(p)/π + ρ/π·E_direct(p): direct irradiance E_direct estimated per
    /// pixel with shadow rays, only the indirect part of the radiosity interpolated.
    PixelDirect,
}

impl From<DirectMode> for DiffuseEstimator {
    fn from(mode: DirectMode) -> DiffuseEstimator {
        match mode {
            DirectMode::Radiosity => DiffuseEstimator::Interpolated,
            DirectMode::Pixel => DiffuseEstimator::PixelDirect,
        }
    }
}

/// The diffuse term over one radiosity solution. Shared between threads (`&self`).
pub struct Diffuse<'a> {
    mesh: &'a Mesh,
    solution: &'a Solution,
    estimator: DiffuseEstimator,
}

impl<'a> Diffuse<'a> {
    /// `solution` must hold one vertex value per mesh vertex (checked by `Tracer::new`).
    pub fn new(mesh: &'a Mesh, solution: &'a Solution, estimator: DiffuseEstimator) -> Diffuse<'a> {
        Diffuse { mesh, solution, estimator }
    }

    pub fn estimator(&self) -> DiffuseEstimator {
        self.estimator
    }

    /// The estimator needs the direct irradiance at the hit (`radiance`'s `direct_irradiance`).
    pub fn needs_direct_light(&self) -> bool {
        self.estimator == DiffuseEstimator::PixelDirect
    }

    /// Exitance B(p) at the hit, Gouraud-interpolated from the solution's vertex values over the side
    /// hit: B(p) = Σ_k b_k B(v_k).
    pub fn radiosity_at(&self, hit: &SurfaceHit) -> Vec3 {
        hit.interpolate(&self.solution.vertex_exitance)
    }

    /// Diffuse radiance towards the eye at a hit on element `element` of reflectance ρ (the texel
    /// albedo ρ(x) on a textured surface), given its exitance B(p) (`radiosity_at`), the direct
    /// irradiance E_direct from shadow rays (used by `PixelDirect` only), the caustic detail ΔB_c
    /// (reflected caustic light at pixel minus element resolution) and, on a textured surface, the
    /// texture ratio r = ρ(x)/ρ̄ₑ (`material::texture_ratio`) that scales the reflected radiosity:
    ///
    /// Interpolated: L = max(B + ΔB_c, 0)/π, textured L = (E + r·max(B − E + ΔB_c, 0))/π;
    /// PixelDirect: L = (E + r·max(B − E − B_direct + ΔB_c, 0))/π + ρ/π·E_direct (r = 1 untextured).
    #[allow(clippy::too_many_arguments)]
    pub fn radiance(
        &self,
        hit: &SurfaceHit,
        element: usize,
        exitance: Vec3,
        reflectance: Vec3,
        texture_ratio: Option<Vec3>,
        direct_irradiance: Vec3,
        caustic: Vec3,
    ) -> Vec3 {
        match (self.estimator, texture_ratio) {
            (DiffuseEstimator::Interpolated, None) => (exitance + caustic).max(Vec3::ZERO) / PI,
            (DiffuseEstimator::Interpolated, Some(ratio)) => {
                let emission = self.mesh.elements.emission[element];
                (emission + ratio * (exitance - emission + caustic).max(Vec3::ZERO)) / PI
            }
            (DiffuseEstimator::PixelDirect, ratio) => {
                let emission = self.mesh.elements.emission[element];
                let direct = hit.interpolate(&self.solution.vertex_direct_exitance);
                let indirect = (exitance - emission - direct + caustic).max(Vec3::ZERO);
                let indirect = match ratio {
                    Some(r) => indirect * r,
                    None => indirect,
                };
                (emission + indirect) / PI + reflectance / PI * direct_irradiance
            }
        }
    }

    /// The radiosity view of a hit (`TraceMode::Radiosity`): B(p)/π, textured (E + r·(B − E))/π with the
    /// texture ratio r, so the view of pass one shows the texture too.
    pub fn radiosity_radiance(&self, element: usize, exitance: Vec3, texture_ratio: Option<Vec3>) -> Vec3 {
        match texture_ratio {
            None => exitance / PI,
            Some(ratio) => {
                let emission = self.mesh.elements.emission[element];
                (emission + ratio * (exitance - emission).max(Vec3::ZERO)) / PI
            }
        }
    }
}
