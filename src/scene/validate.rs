//! What a scene's values may be: the physical sense of materials and cameras (also applied to
//! overrides and OBJ materials), and the range checks of single keys, which report the key's file and
//! line through the parser's `Locator`.

use super::parse::{Locator, SceneError};
use super::{Camera, Material};
use glam::Vec3;
use toml::Spanned;

type S<T> = Spanned<T>;

impl Locator<'_> {
    /// `v` as a vector, or an error at `v` naming `what` if a component is not finite.
    pub(super) fn finite3(&self, v: &S<[f32; 3]>, what: &str) -> Result<Vec3, SceneError> {
        if v.get_ref().iter().all(|x| x.is_finite()) {
            Ok(Vec3::from(*v.get_ref()))
        } else {
            self.error(v.span(), format!("{what} must be finite numbers, got {:?}", v.get_ref()))
        }
    }

    /// An integer setting in `min..=max` (`default` when absent), or an error at its value.
    pub(super) fn positive_int(
        &self,
        v: &Option<S<i64>>,
        what: &str,
        min: i64,
        max: i64,
        default: u32,
    ) -> Result<u32, SceneError> {
        match v {
            None => Ok(default),
            Some(s) if (min..=max).contains(s.get_ref()) => Ok(*s.get_ref() as u32),
            Some(s) => self.error(s.span(), format!("{what} must be between {min} and {max}, got {}", s.get_ref())),
        }
    }

    /// A number setting accepted by `ok` (described by `expect` in the message), `None` when absent.
    pub(super) fn ranged<T: Copy + PartialOrd + std::fmt::Display + Into<f64>>(
        &self,
        v: &Option<S<T>>,
        what: &str,
        ok: impl Fn(f64) -> bool,
        expect: &str,
    ) -> Result<Option<T>, SceneError> {
        match v {
            None => Ok(None),
            Some(s) => {
                let x: f64 = (*s.get_ref()).into();
                if x.is_finite() && ok(x) {
                    Ok(Some(*s.get_ref()))
                } else {
                    self.error(s.span(), format!("{what} must be {expect}, got {}", s.get_ref()))
                }
            }
        }
    }

    /// The points of `v`, or an error at `v` if a coordinate is not finite.
    pub(super) fn finite_points<const N: usize>(&self, v: &S<[[f32; 3]; N]>) -> Result<Vec<Vec3>, SceneError> {
        if v.get_ref().iter().flatten().all(|x| x.is_finite()) {
            Ok(v.get_ref().iter().map(|&p| Vec3::from(p)).collect())
        } else {
            self.error(v.span(), "coordinates must be finite numbers")
        }
    }
}

/// Which part of a material `check_material` found wrong (to point at its line).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MaterialField {
    Kd,
    Ks,
    Ke,
    /// The material as a whole (energy, dissolve, index of refraction).
    Energy,
}

/// Checks a material's physical sense. Reflectances lie in [0, 1); emission is non-negative; and energy
/// is conserved: Kd + Ks + (1 − d) ≤ 1 per channel for an opaque or partly reflective surface. For a
/// dielectric, Fresnel splits what is not diffusely reflected between reflection (scaled by Ks) and
/// transmission (scaled by 1 − d), so there the bound is Kd + max(Ks, 1 − d) ≤ 1 — which admits the
/// standard MTL glass (Ks 1, d 0).
pub fn check_material(m: &Material) -> Result<(), (MaterialField, String)> {
    let in_unit = |v: Vec3, upper_open: bool| {
        v.is_finite()
            && v.min_element() >= 0.0
            && if upper_open { v.max_element() < 1.0 } else { v.max_element() <= 1.0 }
    };
    if !in_unit(m.diffuse_reflectance, true) {
        return Err((
            MaterialField::Kd,
            format!("diffuse reflectance Kd must lie in [0, 1), got {:?}", m.diffuse_reflectance.to_array()),
        ));
    }
    if !in_unit(m.specular_reflectance, false) {
        return Err((
            MaterialField::Ks,
            format!("mirror reflectance Ks must lie in [0, 1], got {:?}", m.specular_reflectance.to_array()),
        ));
    }
    if !(m.emitted_radiance.is_finite() && m.emitted_radiance.min_element() >= 0.0) {
        return Err((
            MaterialField::Ke,
            format!("emitted radiance Ke must be finite and non-negative, got {:?}", m.emitted_radiance.to_array()),
        ));
    }
    if !(m.transmittance.is_finite() && (0.0..=1.0).contains(&m.transmittance)) {
        return Err((MaterialField::Energy, format!("dissolve d must lie in [0, 1], got {}", 1.0 - m.transmittance)));
    }
    if !(m.ior.is_finite() && m.ior > 0.0) {
        return Err((MaterialField::Energy, format!("index of refraction Ni must be positive, got {}", m.ior)));
    }
    let t = Vec3::splat(m.transmittance);
    let (total, rule) = if m.is_dielectric() {
        (m.diffuse_reflectance + m.specular_reflectance.max(t), "Kd + max(Ks, 1 - d)")
    } else {
        (m.diffuse_reflectance + m.specular_reflectance, "Kd + Ks")
    };
    if total.max_element() > 1.0 + 1e-6 {
        return Err((
            MaterialField::Energy,
            format!("{rule} = {:?} exceeds 1: the material would create energy", total.to_array()),
        ));
    }
    Ok(())
}

/// Checks that a camera can form an image: a field of view in (0°, 180°), `eye` away from `look_at`,
/// and `up` neither zero nor parallel to the view direction.
pub fn check_camera(c: &Camera) -> Result<(), (CameraField, String)> {
    if !(c.vfov_deg.is_finite() && c.vfov_deg > 0.0 && c.vfov_deg < 180.0) {
        return Err((CameraField::VfovDeg, format!("vfov_deg must lie in (0, 180) degrees, got {}", c.vfov_deg)));
    }
    if !(c.eye.is_finite() && c.look_at.is_finite() && c.up.is_finite()) {
        return Err((CameraField::Eye, "eye, look_at and up must be finite".to_string()));
    }
    let forward = c.look_at - c.eye;
    if !(forward.length() > 1e-6 * c.eye.length().max(1.0)) {
        return Err((CameraField::LookAt, "look_at must differ from eye".to_string()));
    }
    if !(c.up.length() > 0.0) || forward.normalize().cross(c.up.normalize()).length() < 1e-4 {
        return Err((CameraField::Up, "up must not be zero or parallel to the view direction".to_string()));
    }
    Ok(())
}

/// Which camera key `check_camera` found wrong.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CameraField {
    Eye,
    LookAt,
    Up,
    VfovDeg,
}
