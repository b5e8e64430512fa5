//! The texture maps of every material of one scene, loaded once per run through one `TextureCache`
//! and shared by both passes (pass one's element mean albedo, pass two's texel lookups), with a digest
//! of the decoded texels that the solution fingerprint includes.

use super::maps::{MapWarning, MaterialMaps};
use super::texture::TextureCache;
use crate::radiosity::fingerprint::Fnv1a64;
use crate::scene::Material;

/// Per-material maps of a scene; empty (and digest 0) for an untextured scene.
#[derive(Clone, Debug, Default)]
pub struct SceneTextures {
    /// One entry per material, `None` where the material uses no map (or none could be loaded).
    maps: Vec<Option<MaterialMaps>>,
    digest: u64,
}

impl SceneTextures {
    /// Loads the maps of `materials` (each file once). A map that cannot be loaded is a warning and
    /// its material keeps its constant.
    pub fn load(materials: &[Material]) -> (SceneTextures, Vec<MapWarning>) {
        let mut cache = TextureCache::new();
        let mut warnings = Vec::new();
        let mut h = Fnv1a64::default();
        let mut any = false;
        let mut maps = Vec::with_capacity(materials.len());
        for (index, m) in materials.iter().enumerate() {
            if m.textures.is_empty() {
                maps.push(None);
                continue;
            }
            let (resolved, w) = MaterialMaps::resolve(m, &mut cache);
            warnings.extend(w);
            // What pass one depends on: which material reads which file, and the file's decoded texels
            // (so an edited texture, or a material pointed at another file, makes a saved solution stale).
            for map in [&m.textures.diffuse, &m.textures.opacity, &m.textures.emission].into_iter().flatten() {
                h.write_u64(index as u64);
                h.write(map.path.to_string_lossy().as_bytes());
                h.write_f32s(map.factor.to_array());
            }
            h.write_u64(resolved.content_digest());
            any |= resolved.is_textured();
            maps.push(resolved.is_textured().then_some(resolved));
        }
        let digest = if any { h.finish() } else { 0 };
        (SceneTextures { maps, digest }, warnings)
    }

    /// The maps of material `material`, if it uses any.
    pub fn maps(&self, material: u32) -> Option<&MaterialMaps> {
        self.maps.get(material as usize).and_then(Option::as_ref)
    }

    /// True when some material has a usable cut-out map (`map_d`, or an alpha channel in `map_Kd`).
    pub fn has_cut_outs(&self) -> bool {
        self.maps.iter().flatten().any(MaterialMaps::has_opacity)
    }

    /// True when some material has a usable map.
    pub fn is_textured(&self) -> bool {
        self.maps.iter().any(Option::is_some)
    }

    /// FNV-1a 64 over the texture paths, factors and decoded texels; 0 for an untextured scene.
    pub fn digest(&self) -> u64 {
        self.digest
    }
}
