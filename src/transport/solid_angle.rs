//! Directions uniform in the solid angle a triangle subtends from a point (Arvo 1995, "Stratified
//! sampling of spherical triangles"). Direct light from an emitter close beside the receiver (a lamp
//! against the ceiling it hangs from, the walls of a furnace) sampled uniformly by area has variance
//! growing as 1/r² at the seam: the few points drawn near the receiver weigh cos θ cos θ'/r² each.
//! Drawn uniformly in solid angle instead, a sample weighs L·cos θ·Ω, bounded by L·Ω.

use glam::DVec3;

/// Below this solid angle (steradians) a triangle is not sampled by direction (`sample_towards`
/// returns `None`): its angles then carry more rounding than Arvo's map tolerates, and a triangle
/// that small is seen alike from all its points, so sampling it by area serves as well.
pub const MIN_SOLID_ANGLE_SR: f64 = 1e-4;

/// The solid angle Ω (steradians) triangle `t` subtends from `x`, by Van Oosterom and Strackee
/// (1983): tan(Ω/2) = |a·(b × c)| / (1 + a·b + b·c + c·a), with a, b, c the unit vectors from x to
/// the corners. 0 for x on the triangle's plane.
pub fn solid_angle_sr(x: DVec3, t: &[DVec3; 3]) -> f64 {
    let [a, b, c] = t.map(|p| (p - x).normalize_or_zero());
    let numerator = a.dot(b.cross(c)).abs();
    if !(numerator > 0.0) {
        return 0.0;
    }
    2.0 * numerator.atan2(1.0 + a.dot(b) + b.dot(c) + c.dot(a))
}

/// A point of a triangle drawn uniformly in the solid angle it subtends from x.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TowardsPoint {
    /// The point on the triangle's plane (inside the triangle up to rounding).
    pub point: DVec3,
    /// Unit direction from x to `point`.
    pub direction: DVec3,
}

/// Arvo's (1995) map from (u, v) ∈ [0, 1)² to a direction uniform in the spherical triangle ABC
/// (the triangle's corners projected onto the unit sphere around x), continued to the triangle's
/// plane. With α, β, γ the spherical triangle's angles and Ω = α + β + γ − π:
///
/// Â = u·Ω, s = sin(Â − α), t = cos(Â − α), p = t − cos α, q' = s + sin α cos c,
/// q = ((q' t − p s) cos α − q') / ((q' s + p t) sin α), C' = q A + √(1 − q²) ⊥_A(C),
/// z = 1 − v (1 − C'·B), P = z B + √(1 − z²) ⊥_B(C'),
///
/// cos c = A·B and ⊥_A(C) the unit part of C orthogonal to A. The sub-triangle A B C' has area Â,
/// and P is uniform in solid angle along the arc from B to C'. The density is 1/Ω. `None` for a
/// triangle below `MIN_SOLID_ANGLE_SR` and for x on its plane.
pub fn sample_towards(x: DVec3, triangle: &[DVec3; 3], [u, v]: [f64; 2]) -> Option<TowardsPoint> {
    let a = (triangle[0] - x).try_normalize()?;
    let b = (triangle[1] - x).try_normalize()?;
    let c = (triangle[2] - x).try_normalize()?;
    let corner_angle = |p: DVec3, q: DVec3, r: DVec3| -> Option<f64> {
        let n_pq = p.cross(q).try_normalize()?;
        let n_pr = p.cross(r).try_normalize()?;
        Some(n_pq.dot(n_pr).clamp(-1.0, 1.0).acos())
    };
    let alpha = corner_angle(a, b, c)?;
    let beta = corner_angle(b, c, a)?;
    let gamma = corner_angle(c, a, b)?;
    let omega = alpha + beta + gamma - std::f64::consts::PI;
    if !(omega >= MIN_SOLID_ANGLE_SR) {
        return None;
    }
    let (s, t) = (u * omega - alpha).sin_cos();
    let p = t - alpha.cos();
    let q_prime = s + alpha.sin() * a.dot(b);
    let q = (((q_prime * t - p * s) * alpha.cos() - q_prime) / ((q_prime * s + p * t) * alpha.sin())).clamp(-1.0, 1.0);
    let c_hat = q * a + (1.0 - q * q).max(0.0).sqrt() * (c - c.dot(a) * a).try_normalize()?;
    let z = 1.0 - v * (1.0 - c_hat.dot(b));
    let direction = (z * b + (1.0 - z * z).max(0.0).sqrt() * (c_hat - c_hat.dot(b) * b).try_normalize()?).normalize();
    let normal = (triangle[1] - triangle[0]).cross(triangle[2] - triangle[0]);
    let along = normal.dot(direction);
    if along == 0.0 {
        return None;
    }
    let distance = normal.dot(triangle[0] - x) / along;
    if !(distance > 0.0) {
        return None;
    }
    Some(TowardsPoint { point: x + distance * direction, direction })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(n: u32) -> impl Iterator<Item = [f64; 2]> {
        (0..n * n).map(move |k| [((k % n) as f64 + 0.5) / n as f64, ((k / n) as f64 + 0.5) / n as f64])
    }

    /// Ω of the unit square's quarter-triangles seen from above its corner: the square subtends
    /// 4·arcsin(a·b / √((a² + h²)(b² + h²))) from a point at height h over its centre (a, b half
    /// sides), here a = b = h = 1: 4·arcsin(1/2) = 2π/3.
    #[test]
    fn the_solid_angle_of_a_square_from_above_its_centre_is_two_pi_over_three() {
        let x = DVec3::new(0.0, 0.0, 1.0);
        let c = [
            DVec3::new(-1.0, -1.0, 0.0),
            DVec3::new(1.0, -1.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(-1.0, 1.0, 0.0),
        ];
        let omega = solid_angle_sr(x, &[c[0], c[1], c[2]]) + solid_angle_sr(x, &[c[0], c[2], c[3]]);
        assert!((omega - 2.0 * std::f64::consts::PI / 3.0).abs() < 1e-12, "{omega}");
        assert_eq!(solid_angle_sr(DVec3::new(5.0, 0.0, 0.0), &[c[0], c[1], c[2]]), 0.0);
    }

    #[test]
    fn every_point_lies_on_the_triangle_in_its_direction() {
        let t = [DVec3::new(0.0, 0.0, 0.0), DVec3::new(4.0, 0.0, 0.0), DVec3::new(0.0, 0.0, -3.0)];
        let x = DVec3::new(0.3, 0.05, -0.2);
        for uv in grid(32) {
            let s = sample_towards(x, &t, uv).unwrap();
            let p = s.point;
            assert!(
                p.y.abs() < 1e-9 && p.x >= -1e-9 && p.z <= 1e-9 && p.x / 4.0 - p.z / 3.0 <= 1.0 + 1e-9,
                "{uv:?} {p}"
            );
            assert!((s.direction - (p - x).normalize()).length() < 1e-9);
        }
    }

    /// Uniform in solid angle: the mean of max(0, n·ω) times Ω/π is the point-to-triangle form factor,
    /// here against Lambert's closed form F = (1/2π) Σ γᵢ n·(Rᵢ × Rᵢ₊₁)/|Rᵢ × Rᵢ₊₁| — near (x under
    /// a corner), far, and with the point's plane cutting the triangle.
    #[test]
    fn the_mean_cosine_times_the_solid_angle_is_the_form_factor() {
        let t = [DVec3::new(0.0, 0.0, 1.0), DVec3::new(0.0, 3.0, 1.0), DVec3::new(2.0, 0.0, 1.0)];
        let lambert = |x: DVec3, n: DVec3| -> f64 {
            let r = t.map(|p| (p - x).normalize());
            (0..3)
                .map(|i| {
                    let (a, b) = (r[i], r[(i + 1) % 3]);
                    a.dot(b).clamp(-1.0, 1.0).acos() * n.dot(a.cross(b).normalize())
                })
                .sum::<f64>()
                .abs()
                / (2.0 * std::f64::consts::PI)
        };
        for (x, n) in [
            (DVec3::new(0.05, 0.05, 0.9), DVec3::Z),
            (DVec3::new(-1.0, 2.0, 0.0), DVec3::new(0.3, -0.2, 1.0).normalize()),
            (DVec3::new(5.0, 4.0, -6.0), DVec3::Z),
        ] {
            let mut mean = 0.0;
            for uv in grid(200) {
                mean += sample_towards(x, &t, uv).unwrap().direction.dot(n).max(0.0) / 40_000.0;
            }
            let estimate = mean * solid_angle_sr(x, &t) / std::f64::consts::PI;
            let exact = lambert(x, n);
            assert!((estimate - exact).abs() < 2e-3 * exact, "{x}: {estimate} against {exact}");
        }
    }

    #[test]
    fn a_point_on_the_plane_or_a_speck_is_not_sampled() {
        let t = [DVec3::ZERO, DVec3::X, DVec3::Y];
        assert_eq!(sample_towards(DVec3::new(2.0, 2.0, 0.0), &t, [0.5, 0.5]), None);
        assert_eq!(sample_towards(DVec3::new(0.2, 0.2, 1000.0), &t, [0.5, 0.5]), None);
    }
}
