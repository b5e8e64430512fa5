//! Geometric optics of smooth surfaces: mirror reflection, Snell refraction and the Fresnel
//! reflectance of a dielectric interface (Whitted 1980; Born and Wolf, Principles of Optics, §1.5).

use glam::Vec3;

/// Mirror reflection of direction `d` about unit normal `n` (either orientation):
/// r = d − 2 (d·n) n.
pub fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - 2.0 * d.dot(n) * n
}

/// Refraction of unit direction `d` through an interface with unit normal `n` on the incident side
/// (d·n < 0), with `eta` = η_i/η_t. Snell: η_i sin θ_i = η_t sin θ_t, so
/// sin²θ_t = eta²(1 − cos²θ_i) and t = eta·d + (eta·cos θ_i − cos θ_t)·n with cos θ_i = −d·n.
/// `None` on total internal reflection (sin²θ_t > 1).
pub fn refract(d: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = -d.dot(n);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t > 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some(eta * d + (eta * cos_i - cos_t) * n)
}

/// Fresnel reflectances (R_s, R_p) of a smooth dielectric interface for light arriving at cos θ_i from
/// the side of index `eta_i` onto index `eta_t`:
/// r_s = (η_i cos θ_i − η_t cos θ_t)/(η_i cos θ_i + η_t cos θ_t),
/// r_p = (η_t cos θ_i − η_i cos θ_t)/(η_t cos θ_i + η_i cos θ_t), R = r². Both are 1 under total
/// internal reflection.
pub fn fresnel_dielectric_sp(cos_i: f32, eta_i: f32, eta_t: f32) -> (f32, f32) {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin_t = eta_i / eta_t * (1.0 - cos_i * cos_i).max(0.0).sqrt();
    if sin_t >= 1.0 {
        return (1.0, 1.0);
    }
    let cos_t = (1.0 - sin_t * sin_t).sqrt();
    let r_s = (eta_i * cos_i - eta_t * cos_t) / (eta_i * cos_i + eta_t * cos_t);
    let r_p = (eta_t * cos_i - eta_i * cos_t) / (eta_t * cos_i + eta_i * cos_t);
    (r_s * r_s, r_p * r_p)
}

/// Unpolarised Fresnel reflectance R = (R_s + R_p)/2 (see `fresnel_dielectric_sp`); the transmitted
/// fraction is 1 − R.
pub fn fresnel_dielectric(cos_i: f32, eta_i: f32, eta_t: f32) -> f32 {
    let (r_s, r_p) = fresnel_dielectric_sp(cos_i, eta_i, eta_t);
    0.5 * (r_s + r_p)
}

/// Schlick's approximation (Schlick 1994): R ≈ R0 + (1 − R0)(1 − cos θ)⁵ with
/// R0 = ((η_i − η_t)/(η_i + η_t))², using the angle on the denser side; 1 under total internal
/// reflection.
pub fn fresnel_schlick(cos_i: f32, eta_i: f32, eta_t: f32) -> f32 {
    let r0 = ((eta_i - eta_t) / (eta_i + eta_t)).powi(2);
    let mut cos = cos_i.clamp(0.0, 1.0);
    if eta_i > eta_t {
        let sin2_t = (eta_i / eta_t).powi(2) * (1.0 - cos * cos);
        if sin2_t > 1.0 {
            return 1.0;
        }
        cos = (1.0 - sin2_t).sqrt();
    }
    r0 + (1.0 - r0) * (1.0 - cos).powi(5)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::vec3;

    // Single-precision evaluation of closed forms of order 1: tolerances of a few 1e-6.
    const EPS: f32 = 1e-6;

    #[test]
    fn normal_incidence_reflectance_is_four_percent_for_glass() {
        // ((1.5 − 1)/(1.5 + 1))² = 0.04, from either side.
        assert!((fresnel_dielectric(1.0, 1.0, 1.5) - 0.04).abs() < EPS);
        assert!((fresnel_dielectric(1.0, 1.5, 1.0) - 0.04).abs() < EPS);
        assert!((fresnel_schlick(1.0, 1.0, 1.5) - 0.04).abs() < EPS);
    }

    #[test]
    fn brewster_angle_reflects_no_p_polarisation() {
        // tan θ_B = η_t/η_i; there R_p = 0 so R = R_s/2.
        let theta_b = 1.5f32.atan();
        let (r_s, r_p) = fresnel_dielectric_sp(theta_b.cos(), 1.0, 1.5);
        assert!(r_p < 1e-7, "R_p = {r_p}");
        assert!((fresnel_dielectric(theta_b.cos(), 1.0, 1.5) - 0.5 * r_s).abs() < EPS);
        assert!(r_s > 0.1, "R_s = {r_s}"); // 0.148 at Brewster for n = 1.5.
    }

    #[test]
    fn total_internal_reflection_beyond_critical_angle() {
        let critical = (1.0f32 / 1.5).asin();
        for theta in [critical + 1e-3, 1.0, 1.4, std::f32::consts::FRAC_PI_2] {
            assert_eq!(fresnel_dielectric(theta.cos(), 1.5, 1.0), 1.0, "θ = {theta}");
            let d = vec3(theta.sin(), -theta.cos(), 0.0);
            assert!(refract(d, Vec3::Y, 1.5).is_none(), "θ = {theta}");
        }
        assert!(fresnel_dielectric((critical - 1e-3).cos(), 1.5, 1.0) < 1.0);
    }

    #[test]
    fn fresnel_is_reciprocal_and_transmission_completes_it() {
        // R(θ_i; η_i→η_t) = R(θ_t; η_t→η_i) (Stokes relations), and T = 1 − R by construction, so
        // R + T = 1 seen from either side.
        for k in 0..20 {
            let theta_i = k as f32 * 0.07;
            let sin_t = theta_i.sin() / 1.5;
            let cos_t = (1.0 - sin_t * sin_t).sqrt();
            let r_in = fresnel_dielectric(theta_i.cos(), 1.0, 1.5);
            let r_out = fresnel_dielectric(cos_t, 1.5, 1.0);
            assert!((r_in - r_out).abs() < 1e-5, "θ = {theta_i}: {r_in} vs {r_out}");
            assert!((0.0..=1.0).contains(&r_in));
        }
    }

    #[test]
    fn refraction_obeys_snell_and_reflection_mirrors() {
        let theta_i = 0.6f32;
        let d = vec3(theta_i.sin(), -theta_i.cos(), 0.0);
        let t = refract(d, Vec3::Y, 1.0 / 1.5).expect("no TIR entering glass");
        assert!((t.length() - 1.0).abs() < EPS);
        assert!((t.x - theta_i.sin() / 1.5).abs() < EPS, "sin θ_t = sin θ_i / 1.5");
        assert!(t.y < 0.0);
        let r = reflect(d, Vec3::Y);
        assert!((r - vec3(d.x, -d.y, 0.0)).length() < EPS);
    }
}
