//! Materials as real scene files write them: MTL statements read into the plain `scene::Material`
//! (`mtl`), textures (`texture`), a material's loaded maps and their lookups (`maps`), and the albedo
//! ceiling that replaces refusing reflectances of 1 or more.
//!
//! # Textures in the two passes (the classic two-pass texture ratio)
//! Radiosity is solved per element, so pass one cannot see texture detail finer than an element.
//! - **Pass one** uses each element's *mean albedo* ρ̄ₑ: the exact area average of Kd × texture over
//!   the element's uv triangle, in linear space, on the mip level matched to the triangle's footprint
//!   (`MaterialMaps::mean_albedo_over`, `Texture::mean_over_triangle`). The solver is
//!   unchanged: it sees ρ̄ₑ where it saw Kd.
//! - **Pass two** shows the texture. At a diffuse hit with texel albedo ρ(x) (`MaterialMaps::albedo_at`,
//!   trilinear with the ray's footprint):
//!   - the interpolated radiosity's *reflected* part is scaled by ρ(x)/ρ̄ₑ (`texture_ratio`):
//!     L = E/π + (B − E)/π · ρ(x)/ρ̄ₑ, since B − E = ρ̄ₑ·H and the irradiance H varies slowly;
//!   - with per-pixel direct light, the direct term is ρ(x)/π · E_direct(x) and only the indirect
//!     radiosity is scaled by the ratio.
//! - Cut-outs (`map_d`, or the alpha of `map_Kd`) let pass two's camera, specular and shadow rays pass
//!   where opacity < ½; pass one leaves elements of mean opacity < ½ out of every hemicube
//!   (`Mesh::hidden_from_hemicubes`, which states the error).
//! - `map_Ke` multiplies `Ke` per texel. Pass one emits each element's exact mean π·Ke·t̄ₑ
//!   (`mesh::mean_element_emission`); pass two shows Ke·t(uv) where a ray sees the emitter and lights
//!   with the element means (shadow rays and photons read `Elements::emission`).
//!
//! A missing or unreadable texture file is a warning naming the file (`MapWarning`), and the material
//! keeps its constant (`Kd`, `Ke`, opaque).

pub mod maps;
pub mod mtl;
pub mod scene_textures;
pub mod texture;

pub use maps::{MapWarning, MaterialMaps, OpacityChannel};
pub use scene_textures::SceneTextures;
pub use texture::{ColorEncoding, Texture, TextureCache, TextureError};

use crate::scene::Material;
use glam::Vec3;

/// The highest diffuse reflectance (albedo) radray uses, per channel. A white of 1 would make a closed
/// room's radiosity system singular (no absorption, infinite bounces); 0.98 keeps it solvable in a few
/// hundred sweeps, and is about the albedo of the whitest real paints and of Spectralon.
pub const ALBEDO_CEILING: f32 = 0.98;

/// Per-channel albedo ceiling: ρ′ = min(ρ, ρ_max) with ρ_max = `ALBEDO_CEILING`.
pub fn ceiling(reflectance: Vec3) -> Vec3 {
    reflectance.min(Vec3::splat(ALBEDO_CEILING))
}

/// Albedo of a textured surface at one texel: ρ = min(Kd · t, ρ_max) per channel (Kd multiplies the
/// texture; the product, not Kd, meets the ceiling).
pub fn textured_albedo(kd: Vec3, texel: Vec3) -> Vec3 {
    ceiling(kd * texel)
}

/// The two-pass texture ratio ρ(x)/ρ̄ₑ per channel, by which pass two scales the reflected radiosity
/// of element e at a point x. A channel with ρ̄ₑ = 0 reflects nothing in pass one, so its ratio is 0
/// (never a division by zero).
pub fn texture_ratio(texel_albedo: Vec3, element_mean_albedo: Vec3) -> Vec3 {
    let ratio = |t: f32, m: f32| if m > 0.0 { t / m } else { 0.0 };
    Vec3::new(
        ratio(texel_albedo.x, element_mean_albedo.x),
        ratio(texel_albedo.y, element_mean_albedo.y),
        ratio(texel_albedo.z, element_mean_albedo.z),
    )
}

/// A reflectance that was lowered to the ceiling, for the one warning that names it.
#[derive(Clone, Debug, PartialEq)]
pub struct AlbedoClamp {
    pub material: String,
    /// What reached 1 or more: "Kd", "Kd + Ks" or "Kd + max(Ks, 1 - d)".
    pub quantity: &'static str,
    /// Its value before clamping, per channel.
    pub value: Vec3,
    /// The ceiling it was clamped to (`ALBEDO_CEILING`, or 1 for a mirror's Ks alone).
    pub ceiling: f32,
}

impl std::fmt::Display for AlbedoClamp {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        // Four decimals: sums such as 0.486 + 0.9 print as 1.386, not 1.3859999.
        let short = |x: f32| {
            let text = format!("{x:.4}");
            text.trim_end_matches('0').trim_end_matches('.').to_string()
        };
        let [r, g, b] = self.value.to_array().map(short);
        write!(
            f,
            "material `{}`: {} = [{r}, {g}, {b}] reaches 1 or more; clamped to {} (radray's albedo ceiling)",
            self.material, self.quantity, self.ceiling
        )
    }
}

/// Clamps a material's diffuse reflectance Kd to `ALBEDO_CEILING` per channel when a channel is 1 or
/// more, and says so. With a `map_Kd` texture, Kd ≥ 1 is legal (it multiplies the texture and the
/// product is clamped at lookup, see `textured_albedo`); only its untextured fallback is lowered,
/// without a warning. Negative or non-finite values are left for `scene::check_material` to refuse.
pub fn clamp_albedo(m: &mut Material) -> Option<AlbedoClamp> {
    let kd = m.diffuse_reflectance;
    if !(kd.is_finite() && kd.min_element() >= 0.0) || kd.max_element() < 1.0 {
        return None;
    }
    m.diffuse_reflectance = ceiling(kd);
    m.textures.diffuse.is_none().then(|| AlbedoClamp {
        material: m.name.clone(),
        quantity: "Kd",
        value: kd,
        ceiling: ALBEDO_CEILING,
    })
}

/// Clamps a material whose total reflectance exceeds 1 — Kd + Ks, or Kd + max(Ks, 1 − d) for a
/// dielectric (the rule of `scene::check_material`) — by scaling its specular part (Ks, and the
/// transmittance of a dielectric) by s so that the largest channel of the total is `ALBEDO_CEILING`:
/// s = minₖ (ρ_max − Kdₖ) / specₖ over the channels that exceed 1. Kd (the colour pass one sees) is
/// kept. A Ks above 1 on its own is first lowered to 1 (a perfect mirror). Used for MTL files, whose
/// `illum 2` Ks is often a highlight strength that was never meant to add up with Kd; TOML materials
/// are radray's own and stay errors.
pub fn clamp_energy(m: &mut Material) -> Option<AlbedoClamp> {
    let ks = m.specular_reflectance;
    if !(ks.is_finite() && m.diffuse_reflectance.is_finite() && m.transmittance.is_finite()) {
        return None;
    }
    let ks_clamp = (ks.max_element() > 1.0).then(|| {
        m.specular_reflectance = ks.min(Vec3::ONE);
        AlbedoClamp { material: m.name.clone(), quantity: "Ks", value: ks, ceiling: 1.0 }
    });
    let dielectric = m.is_dielectric();
    let t = Vec3::splat(if dielectric { m.transmittance } else { 0.0 });
    let specular = m.specular_reflectance.max(t);
    let total = m.diffuse_reflectance + specular;
    if total.max_element() <= 1.0 + 1e-6 {
        return ks_clamp;
    }
    let mut s = 1.0f32;
    for k in 0..3 {
        if total[k] > 1.0 + 1e-6 && specular[k] > 0.0 {
            s = s.min(((ALBEDO_CEILING - m.diffuse_reflectance[k]) / specular[k]).max(0.0));
        }
    }
    m.specular_reflectance *= s;
    if dielectric {
        m.transmittance *= s;
    }
    let quantity = if dielectric { "Kd + max(Ks, 1 - d)" } else { "Kd + Ks" };
    Some(AlbedoClamp { material: m.name.clone(), quantity, value: total, ceiling: ALBEDO_CEILING })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{SourceLoc, TextureMap};
    use approx::assert_relative_eq;

    #[test]
    fn kd_of_one_or_more_is_clamped_once_and_named() {
        let mut m = Material::diffuse("paint", Vec3::new(1.2, 0.5, 1.0));
        let note = clamp_albedo(&mut m).expect("clamped");
        assert_eq!(m.diffuse_reflectance, Vec3::new(ALBEDO_CEILING, 0.5, ALBEDO_CEILING));
        let text = note.to_string();
        assert!(text.contains("`paint`") && text.contains("1.2") && text.contains("0.98"), "{text}");
        assert_eq!(clamp_albedo(&mut m), None, "a clamped material is not clamped again");
    }

    #[test]
    fn kd_below_one_and_invalid_kd_are_left_alone() {
        let mut m = Material::diffuse("grey", Vec3::splat(0.99));
        assert_eq!(clamp_albedo(&mut m), None);
        assert_eq!(m.diffuse_reflectance, Vec3::splat(0.99));
        let mut bad = Material::diffuse("bad", Vec3::new(-0.1, 2.0, 0.5));
        assert_eq!(clamp_albedo(&mut bad), None);
        assert_eq!(bad.diffuse_reflectance, Vec3::new(-0.1, 2.0, 0.5), "left for check_material to refuse");
    }

    #[test]
    fn textured_kd_of_one_is_legal_and_clamped_at_lookup() {
        let mut m = Material::diffuse("wood", Vec3::ONE);
        m.textures.diffuse =
            Some(TextureMap { path: "wood.jpg".into(), factor: Vec3::ONE, source: SourceLoc::default() });
        assert_eq!(clamp_albedo(&mut m), None, "no warning");
        assert_eq!(m.diffuse_reflectance, Vec3::splat(ALBEDO_CEILING), "fallback lowered");
        assert_eq!(textured_albedo(Vec3::ONE, Vec3::new(1.0, 0.5, 0.0)), Vec3::new(ALBEDO_CEILING, 0.5, 0.0));
    }

    #[test]
    fn energy_excess_scales_the_specular_part_to_the_ceiling() {
        // McGuire's Glossy sphere: Kd 0.486 0.631 0.663, Ks 0.9 (illum 2).
        let mut m = Material {
            specular_reflectance: Vec3::splat(0.9),
            ..Material::diffuse("sphere", Vec3::new(0.486, 0.631, 0.663))
        };
        let note = clamp_energy(&mut m).expect("clamped");
        assert_eq!(note.quantity, "Kd + Ks");
        let total = m.diffuse_reflectance + m.specular_reflectance;
        assert_relative_eq!(total.max_element(), ALBEDO_CEILING, max_relative = 1e-6);
        assert_eq!(m.diffuse_reflectance, Vec3::new(0.486, 0.631, 0.663), "Kd kept");
        assert!(crate::scene::check_material(&m).is_ok());
    }

    #[test]
    fn texture_ratio_is_texel_over_mean_and_zero_where_the_mean_is() {
        let r = texture_ratio(Vec3::new(0.8, 0.2, 0.3), Vec3::new(0.4, 0.4, 0.0));
        assert_eq!(r, Vec3::new(2.0, 0.5, 0.0));
    }
}
