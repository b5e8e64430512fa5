//! A material's texture maps once loaded (`map_Kd`, `map_d`, `map_Ke`) and the lookups both passes
//! make through them: mean albedo over an element's uv triangle (pass one), filtered albedo, opacity
//! and emission at a hit (pass two). Each map falls back to the material's constant when absent or
//! unreadable.

use super::texture::{ColorEncoding, Texture, TextureCache, TextureError};
use super::{ceiling, textured_albedo};
use crate::scene::Material;
use glam::{Vec2, Vec3, Vec4};
use std::sync::Arc;

/// Which channel of an opacity texture holds the opacity.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OpacityChannel {
    /// The file's alpha channel (`map_d` with alpha, or the alpha of `map_Kd`).
    Alpha,
    /// The first channel, read linearly (`map_d` stored as a grey image without alpha).
    First,
}

/// A texture map that could not be used: the material keeps its constant.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{location}: material `{material}`: {statement}: {error}; using its {fallback} instead")]
pub struct MapWarning {
    /// The MTL line of the map statement.
    pub location: crate::scene::SourceLoc,
    pub material: String,
    /// `map_Kd`, `map_d` or `map_Ke`.
    pub statement: &'static str,
    /// The constant used instead: `Kd`, `d` or `Ke`.
    pub fallback: &'static str,
    pub error: TextureError,
}

/// The loaded maps of one material, with the constants they multiply.
#[derive(Clone, Debug)]
pub struct MaterialMaps {
    diffuse: Option<Arc<Texture>>,
    diffuse_factor: Vec3,
    /// Kd (already under the ceiling) when there is no usable `map_Kd`.
    diffuse_constant: Vec3,
    opacity: Option<(Arc<Texture>, OpacityChannel)>,
    emission: Option<Arc<Texture>>,
    emission_factor: Vec3,
    emission_constant: Vec3,
}

impl MaterialMaps {
    /// Loads a material's maps through the cache (each file once per cache). A file that cannot be
    /// used gives a `MapWarning` the first time the cache sees it, and that map falls back to the
    /// constant. Opacity comes from `map_d` (its alpha if it has one, else its first channel), or else
    /// from the alpha channel of `map_Kd` when that file has one.
    pub fn resolve(m: &Material, cache: &mut TextureCache) -> (MaterialMaps, Vec<MapWarning>) {
        let mut warnings = Vec::new();
        let mut load = |map: &Option<crate::scene::TextureMap>, encoding, statement, fallback| {
            let map = map.as_ref()?;
            match cache.get(&map.path, encoding) {
                (Ok(t), _) => Some((t, map.factor)),
                (Err(error), first) => {
                    if first {
                        warnings.push(MapWarning {
                            location: map.source.clone(),
                            material: m.name.clone(),
                            statement,
                            fallback,
                            error,
                        });
                    }
                    None
                }
            }
        };
        let diffuse = load(&m.textures.diffuse, ColorEncoding::Srgb, "map_Kd", "Kd");
        let opacity_map = load(&m.textures.opacity, ColorEncoding::Linear, "map_d", "d");
        let emission = load(&m.textures.emission, ColorEncoding::Srgb, "map_Ke", "Ke");
        let opacity = match (&opacity_map, &diffuse) {
            (Some((t, _)), _) => {
                Some((t.clone(), if t.has_alpha { OpacityChannel::Alpha } else { OpacityChannel::First }))
            }
            (None, Some((t, _))) if t.has_alpha => Some((t.clone(), OpacityChannel::Alpha)),
            _ => None,
        };
        let maps = MaterialMaps {
            diffuse_factor: diffuse.as_ref().map_or(Vec3::ONE, |d| d.1),
            diffuse: diffuse.map(|d| d.0),
            diffuse_constant: ceiling(m.diffuse_reflectance),
            opacity,
            emission_factor: emission.as_ref().map_or(Vec3::ONE, |e| e.1),
            emission: emission.map(|e| e.0),
            emission_constant: m.emitted_radiance,
        };
        (maps, warnings)
    }

    /// FNV-1a 64 over the decoded level-0 texels of every loaded map (0 for none).
    pub fn content_digest(&self) -> u64 {
        let mut h = crate::radiosity::fingerprint::Fnv1a64::default();
        let textures = [self.diffuse.as_ref(), self.opacity.as_ref().map(|o| &o.0), self.emission.as_ref()];
        for t in textures.into_iter().flatten() {
            let level = &t.levels[0];
            h.write_u64(((level.width_px as u64) << 32) | level.height_px as u64);
            h.write_f32s(level.texels.iter().flat_map(|x| x.to_array()));
        }
        h.finish()
    }

    /// True when any map is in use (untextured materials need no uv).
    pub fn is_textured(&self) -> bool {
        self.diffuse.is_some() || self.opacity.is_some() || self.emission.is_some()
    }

    pub fn has_diffuse_texture(&self) -> bool {
        self.diffuse.is_some()
    }

    pub fn has_opacity(&self) -> bool {
        self.opacity.is_some()
    }

    pub fn has_emission_texture(&self) -> bool {
        self.emission.is_some()
    }

    /// Pass one: an element's mean albedo ρ̄ₑ = (1/A) ∫_△ min(Kd · t(u), ρ_max) du over its uv
    /// triangle (exact area average on the mip level matched to its footprint, see
    /// `Texture::mean_over_triangle_of`); Kd without a texture.
    pub fn mean_albedo_over(&self, uv0: Vec2, uv1: Vec2, uv2: Vec2) -> Vec3 {
        match &self.diffuse {
            Some(t) => {
                let kd = self.diffuse_factor;
                t.mean_over_triangle_of(uv0, uv1, uv2, |texel| textured_albedo(kd, texel.truncate()).extend(1.0))
                    .truncate()
            }
            None => self.diffuse_constant,
        }
    }

    /// Pass two: albedo at a hit, ρ(x) = min(Kd · t(uv), ρ_max), trilinear with the footprint.
    pub fn albedo_at(&self, uv: Vec2, footprint_uv: f32) -> Vec3 {
        match &self.diffuse {
            Some(t) => textured_albedo(self.diffuse_factor, t.trilinear(uv, footprint_uv).truncate()),
            None => self.diffuse_constant,
        }
    }

    /// Opacity in [0, 1] at a hit (1 without a cut-out map); a ray passes where it is below ½.
    pub fn opacity_at(&self, uv: Vec2, footprint_uv: f32) -> f32 {
        match &self.opacity {
            Some((t, channel)) => {
                let texel: Vec4 = t.trilinear(uv, footprint_uv);
                let value = match channel {
                    OpacityChannel::Alpha => texel.w,
                    OpacityChannel::First => texel.x,
                };
                value.clamp(0.0, 1.0)
            }
            None => 1.0,
        }
    }

    /// Pass one: mean opacity ᾱ = (1/A) ∫_△ clamp(α(u), 0, 1) du over a uv triangle (exact area
    /// average on the footprint's mip level, `Texture::mean_over_triangle_of`); 1 without a cut-out map.
    pub fn mean_opacity_over(&self, uv0: Vec2, uv1: Vec2, uv2: Vec2) -> f32 {
        match &self.opacity {
            Some((t, channel)) => {
                let channel = *channel;
                t.mean_over_triangle_of(uv0, uv1, uv2, |texel| {
                    let value = match channel {
                        OpacityChannel::Alpha => texel.w,
                        OpacityChannel::First => texel.x,
                    };
                    Vec4::splat(value.clamp(0.0, 1.0))
                })
                .x
            }
            None => 1.0,
        }
    }

    /// Emitted radiance at a hit: Ke · t(uv) with `map_Ke`, else Ke.
    pub fn emission_at(&self, uv: Vec2, footprint_uv: f32) -> Vec3 {
        match &self.emission {
            Some(t) => self.emission_factor * t.trilinear(uv, footprint_uv).truncate(),
            None => self.emission_constant,
        }
    }

    /// Mean emitted radiance over an element's uv triangle (what pass one emits from it).
    pub fn mean_emission_over(&self, uv0: Vec2, uv1: Vec2, uv2: Vec2) -> Vec3 {
        match &self.emission {
            Some(t) => self.emission_factor * t.mean_over_triangle(uv0, uv1, uv2).truncate(),
            None => self.emission_constant,
        }
    }
}
