//! Pass two's diffuse term: the radiosity solution read back at a hit, and the estimator that turns it
//! (with per-pixel direct light and caustic detail when asked for) into the radiance a diffuse surface
//! sends towards the eye.

use std::f32::consts::PI;

use glam::{DVec3, Vec3};

use crate::mesh::Mesh;
use crate::radiosity::adaptive::hanging::{conforming_vertex_values, hanging_vertices};
use crate::radiosity::adaptive::subdivide::EdgeMidpoints;
use crate::radiosity::irradiance::element_irradiance;
use crate::radiosity::smooth_mesh::SmoothMesh;
use crate::radiosity::Solution;
use crate::scene::DirectMode;
use crate::transport::SurfaceHit;

/// How the light a diffuse surface reflects is estimated: where direct light comes from. The indirect
/// light is the interpolated solution's, or a final gather's (`trace::gather`) when `radiance` is given
/// one.
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
    /// For textured scenes: per-vertex irradiance (total, direct) from `vertex_irradiance`; empty
    /// otherwise.
    vertex_irradiance: Vec<Vec3>,
    vertex_direct_irradiance: Vec<Vec3>,
}

/// Per-vertex irradiance of a solution: H_v = Σₑ Aₑ Hₑ / Σₑ Aₑ over the elements sharing v (as
/// `Mesh::vertex_average`), with Hₑ = (Bₑ − Eₑ)/ρₑ the irradiance element e reflected in pass one
/// (0 where ρₑ = 0), and the same for the direct part Hₑ,d = Bₑ,d/ρₑ. On a textured surface the
/// elements' mean albedos differ, so interpolating B and dividing by one element's ρ̄ₑ would carry the
/// neighbours' albedo into it; irradiance is smooth across them. On the uniform and adaptive meshes
/// the vertices are made as the solution's exitance is: welded within smoothing groups and the
/// outline extrapolated (`SmoothMesh`, a split edge's midpoint not taken for a boundary), and an
/// adaptive mesh's hanging vertices given their edge's value (`hanging::conform`, no T-vertex
/// cracks; the uniform mesh has none); the hierarchy's leaf mesh keeps the plain means.
pub fn vertex_irradiance(mesh: &Mesh, solution: &Solution) -> (Vec<Vec3>, Vec<Vec3>) {
    let total = element_irradiance(mesh, &solution.element_exitance, true);
    let direct = element_irradiance(mesh, &solution.element_direct_exitance, false);
    if solution.leaf_geometry.is_some() {
        let plain = |values: &[DVec3]| mesh.vertex_average(values).iter().map(|v| v.as_vec3()).collect();
        return (plain(&total), plain(&direct));
    }
    // The element meshes (uniform, adaptive): the vertex step of their exitance, T-vertices included.
    let vertex_step = SmoothMesh::new(mesh);
    let hanging = hanging_vertices(mesh, &EdgeMidpoints::of(mesh));
    (
        conforming_vertex_values(&vertex_step, &total, &hanging),
        conforming_vertex_values(&vertex_step, &direct, &hanging),
    )
}

impl<'a> Diffuse<'a> {
    /// `solution` must hold one vertex value per mesh vertex (checked by `Tracer::new`).
    pub fn new(mesh: &'a Mesh, solution: &'a Solution, estimator: DiffuseEstimator) -> Diffuse<'a> {
        let (vertex_irradiance, vertex_direct_irradiance) =
            if mesh.textures.is_textured() { vertex_irradiance(mesh, solution) } else { (Vec::new(), Vec::new()) };
        Diffuse { mesh, solution, estimator, vertex_irradiance, vertex_direct_irradiance }
    }

    pub fn estimator(&self) -> DiffuseEstimator {
        self.estimator
    }

    /// The estimator needs the direct irradiance at the hit (`radiance`'s `direct_irradiance`).
    /// Whether the solution holds the caustic light at element resolution (`Solution::holds_caustic_light`).
    pub fn holds_caustic_light(&self) -> bool {
        self.solution.holds_caustic_light
    }

    pub fn needs_direct_light(&self) -> bool {
        self.estimator == DiffuseEstimator::PixelDirect
    }

    /// Exitance B(p) at the hit, Gouraud-interpolated from the solution's vertex values over the side
    /// hit: B(p) = Σ_k b_k B(v_k).
    pub fn radiosity_at(&self, hit: &SurfaceHit) -> Vec3 {
        hit.interpolate(&self.solution.vertex_exitance)
    }

    /// The solution's direct part B_direct(p) at the hit (first-bounce exitance, emission excluded),
    /// interpolated as `radiosity_at`.
    pub fn direct_exitance_at(&self, hit: &SurfaceHit) -> Vec3 {
        hit.interpolate(&self.solution.vertex_direct_exitance)
    }

    /// Diffuse radiance towards the eye at a hit on element `element` of reflectance ρ (the texel
    /// albedo ρ(x) on a textured surface), given its exitance B(p) (`radiosity_at`), the direct
    /// irradiance E_direct from shadow rays (used by `PixelDirect` only) with the gathered indirect
    /// irradiance H_g (`trace::gather`, if any), the caustic detail ΔB_c (reflected caustic light at
    /// pixel minus element resolution, already × ρ) and whether the surface is textured. Untextured:
    ///
    /// Interpolated: L = max(B + ΔB_c, 0)/π;
    /// PixelDirect: L = (E + max(B − E − B_direct + ΔB_c, 0))/π + ρ/π·E_direct.
    ///
    /// Textured, the classic texture ratio ρ(x)/ρ̄ₑ applied to the reflected radiosity B − E = ρ̄ₑ·H,
    /// with the irradiance H(p) interpolated from `vertex_irradiance` (so neighbours' albedos do not
    /// leak in): L = (E + max(ρ(x)·H(p) + ΔB_c, 0))/π, and with per-pixel direct light
    /// L = (E + max(ρ(x)·(H − H_direct)(p) + ΔB_c, 0))/π + ρ(x)/π·E_direct.
    ///
    /// With a gather, H_g replaces the interpolated indirect irradiance (B − E − B_direct)/ρ̄ₑ, and ρ (the
    /// texel albedo where textured) multiplies it directly. The caustic term is then all of the
    /// reflected caustic light, ΔB_c = ρ·E_caustic(p), not its detail: the element-level share left
    /// with the interpolated solution, and the gather rays leave emitters seen through mirrors and
    /// glass to the map (`Tracer::gather_radiance`):
    /// Interpolated: L = (E + max(B_direct(p) + ρ·H_g + ΔB_c, 0))/π, where textured B_direct(p) is
    /// ρ(x)·H_direct(p); PixelDirect: L = (E + max(ρ·H_g + ΔB_c, 0))/π + ρ/π·E_direct.
    #[allow(clippy::too_many_arguments)]
    pub fn radiance(
        &self,
        hit: &SurfaceHit,
        element: usize,
        exitance: Vec3,
        reflectance: Vec3,
        textured: bool,
        (direct_irradiance, gathered): (Vec3, Option<Vec3>),
        caustic: Vec3,
    ) -> Vec3 {
        let textured = textured && !self.vertex_irradiance.is_empty();
        let emission = self.mesh.elements.emission[element];
        if let Some(indirect_irradiance) = gathered {
            let indirect = reflectance * indirect_irradiance + caustic;
            return match (self.estimator, textured) {
                (DiffuseEstimator::Interpolated, false) => {
                    let direct = hit.interpolate(&self.solution.vertex_direct_exitance);
                    (emission + (direct + indirect).max(Vec3::ZERO)) / PI
                }
                (DiffuseEstimator::Interpolated, true) => {
                    let direct = reflectance * hit.interpolate(&self.vertex_direct_irradiance);
                    (emission + (direct + indirect).max(Vec3::ZERO)) / PI
                }
                (DiffuseEstimator::PixelDirect, _) => {
                    (emission + indirect.max(Vec3::ZERO)) / PI + reflectance / PI * direct_irradiance
                }
            };
        }
        match (self.estimator, textured) {
            (DiffuseEstimator::Interpolated, false) => (exitance + caustic).max(Vec3::ZERO) / PI,
            (DiffuseEstimator::Interpolated, true) => {
                let irradiance = hit.interpolate(&self.vertex_irradiance);
                (emission + (reflectance * irradiance + caustic).max(Vec3::ZERO)) / PI
            }
            (DiffuseEstimator::PixelDirect, false) => {
                let direct = hit.interpolate(&self.solution.vertex_direct_exitance);
                let indirect = (exitance - emission - direct + caustic).max(Vec3::ZERO);
                (emission + indirect) / PI + reflectance / PI * direct_irradiance
            }
            (DiffuseEstimator::PixelDirect, true) => {
                let irradiance =
                    hit.interpolate(&self.vertex_irradiance) - hit.interpolate(&self.vertex_direct_irradiance);
                let indirect = (reflectance * irradiance + caustic).max(Vec3::ZERO);
                (emission + indirect) / PI + reflectance / PI * direct_irradiance
            }
        }
    }

    /// The part of `radiance` that arrived straight from the emitters (for layered output):
    /// PixelDirect: ρ/π·E_direct; Interpolated: B_direct(p)/π, or ρ(x)·H_direct(p)/π on a textured
    /// surface (B_direct the first-bounce exitance of pass one, H_direct its irradiance).
    pub fn direct_radiance(
        &self,
        hit: &SurfaceHit,
        reflectance: Vec3,
        textured: bool,
        direct_irradiance: Vec3,
    ) -> Vec3 {
        let textured = textured && !self.vertex_direct_irradiance.is_empty();
        match (self.estimator, textured) {
            (DiffuseEstimator::PixelDirect, _) => reflectance / PI * direct_irradiance,
            (DiffuseEstimator::Interpolated, false) => hit.interpolate(&self.solution.vertex_direct_exitance) / PI,
            (DiffuseEstimator::Interpolated, true) => {
                reflectance * hit.interpolate(&self.vertex_direct_irradiance) / PI
            }
        }
    }

    /// The radiosity view of a hit (`TraceMode::Radiosity`) on a surface of albedo ρ(x): B(p)/π, and on
    /// a textured surface (E + ρ(x)·H(p))/π with the interpolated irradiance H (see `radiance`), so
    /// the view of pass one shows the texture too.
    pub fn radiosity_radiance(
        &self,
        hit: &SurfaceHit,
        element: usize,
        exitance: Vec3,
        texel_albedo: Option<Vec3>,
    ) -> Vec3 {
        match texel_albedo {
            Some(rho) if !self.vertex_irradiance.is_empty() => {
                let emission = self.mesh.elements.emission[element];
                (emission + (rho * hit.interpolate(&self.vertex_irradiance)).max(Vec3::ZERO)) / PI
            }
            _ => exitance / PI,
        }
    }
}
