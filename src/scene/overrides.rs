//! Settings laid over a scene file's by the command line or a batch job: image size, samples, seed,
//! direct-light estimator, quality preset, camera and materials. `Overrides::apply` is the one place
//! they are applied.

use glam::Vec3;

use super::{check_camera, check_material, DirectMode, FinalGatherMode, MethodChoice, Quality, SceneDescription};

/// A batch job's new camera values (each optional).
#[derive(Clone, Debug, Default, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraOverride {
    pub eye: Option<[f32; 3]>,
    pub look_at: Option<[f32; 3]>,
    pub up: Option<[f32; 3]>,
    pub vfov_deg: Option<f32>,
}

/// A batch job's new `kd`, `ke` or `ks` for one material.
#[derive(Clone, Debug, Default, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialOverride {
    pub kd: Option<[f32; 3]>,
    pub ke: Option<[f32; 3]>,
    pub ks: Option<[f32; 3]>,
}

/// Settings laid over a scene's; `None` keeps the scene's value.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Overrides {
    pub width_px: Option<u32>,
    pub height_px: Option<u32>,
    pub samples_per_pixel: Option<u32>,
    /// Seed of the film's and the hemicubes' random numbers.
    pub seed: Option<u64>,
    pub direct: Option<DirectMode>,
    /// Final gather on or off (`[render] final_gather`).
    pub final_gather: Option<FinalGatherMode>,
    /// A named preset, applied before the single values.
    pub quality: Option<Quality>,
    /// The pass-one method (`[radiosity] method`).
    pub method: Option<MethodChoice>,
    pub camera: Option<CameraOverride>,
    /// Per material name (in the order given).
    pub materials: Vec<(String, MaterialOverride)>,
}

/// Why overrides cannot be applied: the result would be an invalid scene.
#[derive(Debug, thiserror::Error)]
pub enum OverrideError {
    #[error("camera override: {0}")]
    Camera(String),
    #[error("materials.{name}: the scene has no material `{name}`")]
    UnknownMaterial { name: String },
    #[error("materials.{name}: {reason}")]
    Material { name: String, reason: String },
}

impl Overrides {
    /// Lays the overrides over `scene`: the quality preset first, then the single values, then the
    /// camera and materials, each checked as the scene parser checks them.
    pub fn apply(&self, scene: &mut SceneDescription) -> Result<(), OverrideError> {
        if let Some(q) = self.quality {
            scene.apply_quality(q);
        }
        if let Some(w) = self.width_px {
            scene.image.width_px = w;
        }
        if let Some(h) = self.height_px {
            scene.image.height_px = h;
        }
        if let Some(spp) = self.samples_per_pixel {
            scene.image.samples_per_pixel = spp;
            scene.image.adaptive_max_samples = scene.image.adaptive_max_samples.max(spp);
        }
        if let Some(seed) = self.seed {
            scene.image.seed = seed;
            scene.radiosity.seed = seed;
        }
        if let Some(d) = self.direct {
            scene.render.direct = d;
        }
        if let Some(m) = self.method {
            scene.radiosity.method = m;
        }
        if let Some(g) = self.final_gather {
            scene.render.final_gather = g;
        }
        if let Some(c) = &self.camera {
            let cam = &mut scene.camera;
            if let Some(v) = c.eye {
                cam.eye = Vec3::from(v);
            }
            if let Some(v) = c.look_at {
                cam.look_at = Vec3::from(v);
            }
            if let Some(v) = c.up {
                cam.up = Vec3::from(v);
            }
            if let Some(v) = c.vfov_deg {
                cam.vfov_deg = v;
            }
            check_camera(cam).map_err(|(_, e)| OverrideError::Camera(e))?;
        }
        for (name, o) in &self.materials {
            let Some(m) = scene.materials.iter_mut().find(|m| &m.name == name) else {
                return Err(OverrideError::UnknownMaterial { name: name.clone() });
            };
            if let Some(v) = o.kd {
                m.diffuse_reflectance = Vec3::from(v);
            }
            if let Some(v) = o.ke {
                m.emitted_radiance = Vec3::from(v);
            }
            if let Some(v) = o.ks {
                m.specular_reflectance = Vec3::from(v);
            }
            check_material(m).map_err(|(_, reason)| OverrideError::Material { name: name.clone(), reason })?;
        }
        Ok(())
    }
}
