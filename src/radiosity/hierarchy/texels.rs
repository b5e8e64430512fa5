//! Pass one's texture means for the hierarchy's elements (issues 10 and 11): an element of any size
//! (an input triangle or a 1→4 piece of one) takes the area average of its own uv image, computed by
//! the same code as the uniform mesh's elements (`MaterialMaps::mean_albedo_over`,
//! `mean_emission_over`, `mean_opacity_over`), so a textured scene reflects its texture means rather
//! than `Kd`. `leaf_mesh` calls the same `SurfaceTexels::element_materials` for pass two's elements,
//! so pass two's texture ratio divides by exactly the albedo the hierarchy used.

use std::sync::Arc;

use glam::{Vec2, Vec3};

use crate::material::SceneTextures;
use crate::mesh::surface_uv;
use crate::scene::SceneDescription;

/// What one element reflects and emits in pass one.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ElementMaterial {
    /// Diffuse reflectance ρ: the mean albedo over the element's uv image with `map_Kd`, else Kd.
    pub reflectance: Vec3,
    /// Emitted exitance E = π·Ke (× the mean of `map_Ke` over the element's uv image).
    pub emission: Vec3,
    /// Mean opacity ᾱ over the uv image with a cut-out map, else 1.
    pub opacity: f32,
}

impl ElementMaterial {
    /// The element is a cut-out for pass one: ᾱ < ½, as `Mesh::hidden_from_hemicubes` decides for the
    /// uniform mesh.
    pub fn is_cut_out(&self) -> bool {
        self.opacity < 0.5
    }

    /// What the hierarchy solves with. A cut-out element is left out of the light exchange as the
    /// uniform mesh leaves it out of every hemicube: it reflects and emits nothing (so no link carries
    /// light from it) and its input triangle does not occlude (`clusters::build`). The error is the
    /// misclassified part, min(ᾱ, 1 − ᾱ) of its area (see `Mesh::hidden_from_hemicubes`). Unlike the
    /// uniform mesh's hidden elements, its own exitance is then 0, so the opaque texels of a mostly
    /// cut-out leaf show only per-pixel direct light in pass two.
    pub fn solved(&self) -> (Vec3, Vec3) {
        if self.is_cut_out() {
            (Vec3::ZERO, Vec3::ZERO)
        } else {
            (self.reflectance, self.emission)
        }
    }
}

/// A textured scene surface's corners and their uv, kept so that any triangle inside it can find
/// the uv of its corners (`mesh::surface_uv`: barycentric on a triangle, bilinear on a quad).
#[derive(Clone, Debug)]
struct SurfaceUv {
    corners: Vec<Vec3>,
    uvs: Vec<Vec2>,
}

/// The scene's materials with their loaded maps, and the uv polygons of the surfaces whose material
/// has a map: everything `element_materials` needs, without the scene (the hierarchy keeps it in
/// `Nodes` to give new pieces their own means).
#[derive(Clone, Debug, Default)]
pub struct SurfaceTexels {
    textures: Arc<SceneTextures>,
    /// Per material: (Kd, π·Ke).
    constants: Vec<(Vec3, Vec3)>,
    /// Per scene surface: its material.
    material: Vec<u32>,
    /// Per scene surface: its uv polygon when its material has a usable map and it has uv.
    uv: Vec<Option<SurfaceUv>>,
}

impl SurfaceTexels {
    /// The materials and uv polygons of `scene`, with its loaded `textures` (empty for none).
    pub fn new(scene: &SceneDescription, textures: Arc<SceneTextures>) -> SurfaceTexels {
        let constants = scene.materials.iter().map(|m| (m.diffuse_reflectance, m.emitted_exitance())).collect();
        let material = scene.surfaces.iter().map(|s| s.material).collect();
        let uv = scene
            .surfaces
            .iter()
            .map(|s| match (&s.uvs, textures.maps(s.material)) {
                (Some(uvs), Some(_)) if uvs.len() == s.vertices.len() => {
                    Some(SurfaceUv { corners: s.vertices.clone(), uvs: uvs.clone() })
                }
                _ => None,
            })
            .collect();
        SurfaceTexels { textures, constants, material, uv }
    }

    /// True when no surface is textured (every element takes its material's constants).
    pub fn is_untextured(&self) -> bool {
        self.uv.iter().all(Option::is_none)
    }

    /// Pass one's material of the triangle `corners` lying on scene surface `surface` (either side):
    /// the means over its uv image ρ̄ = (1/A)∫ min(Kd·t, ρ_max), Ē = π·Ke·t̄ and ᾱ (uv is taken at the
    /// corners with `surface_uv` and is affine over the triangle); Kd, π·Ke and 1 where a map is
    /// missing, as for the uniform mesh (`mesh::mean_element_albedo` and its siblings).
    pub fn element_materials(&self, surface: u32, corners: [Vec3; 3]) -> ElementMaterial {
        let s = surface as usize;
        let (kd, emitted) =
            self.material.get(s).and_then(|&m| self.constants.get(m as usize)).copied().unwrap_or_default();
        let mut out = ElementMaterial { reflectance: kd, emission: emitted, opacity: 1.0 };
        let (Some(Some(polygon)), Some(maps)) = (self.uv.get(s), self.textures.maps(self.material[s])) else {
            return out;
        };
        let [a, b, c] = corners.map(|p| surface_uv(&polygon.corners, &polygon.uvs, p));
        if maps.has_diffuse_texture() {
            out.reflectance = maps.mean_albedo_over(a, b, c);
        }
        if maps.has_emission_texture() {
            out.emission = maps.mean_emission_over(a, b, c) * std::f32::consts::PI;
        }
        if maps.has_opacity() {
            out.opacity = maps.mean_opacity_over(a, b, c);
        }
        out
    }
}

/// `SurfaceTexels` with the scene surface of every input triangle: what `Nodes::subdivide` needs to
/// give each new piece its own means.
#[derive(Clone, Debug, Default)]
pub struct InputTexels {
    pub surfaces: SurfaceTexels,
    /// Per input triangle: its scene surface.
    pub input_surface: Vec<u32>,
}

impl InputTexels {
    /// (ρ, E) the hierarchy solves with for the triangle `corners` inside input triangle `input`
    /// (`ElementMaterial::solved`).
    pub fn solved_materials(&self, input: u32, corners: [Vec3; 3]) -> (Vec3, Vec3) {
        let surface = self.input_surface.get(input as usize).copied().unwrap_or(u32::MAX);
        self.surfaces.element_materials(surface, corners).solved()
    }
}
