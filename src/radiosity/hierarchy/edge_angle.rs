//! The angle γ between two vectors from |a × b| and a · b, as Lambert's polygon form factor needs it
//! once per clipped edge (`form_factor::point_to_source`): a range-reduced polynomial arctangent in
//! place of libm's `atan2`, which took about a fifth of cornell_original's hierarchical profile.

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

/// tan(π/8): above it the arctangent's argument is reduced by atan t = π/4 + atan((t − 1)/(t + 1)).
const TAN_PI_8: f64 = 0.414_213_562_373_095_03;

/// Q(s) of atan u = u + u·s·Q(s), s = u², for |u| ≤ tan(π/8) (s ≤ 0.1716): a least-squares fit of
/// the relative error on 2,000 Chebyshev nodes (`docs/performance.md`, session 16), lowest degree
/// first. Its relative error is at most 1.1e-15 on that interval (measured in 40-digit arithmetic).
const ATAN_Q: [f64; 9] = [
    -0.333_333_333_332_569_65,
    0.199_999_999_821_981_88,
    -0.142_857_128_453_889_56,
    0.111_110_536_261_626_98,
    -0.090_896_024_349_854_4,
    0.076_741_982_621_602_62,
    -0.065_095_750_786_815_26,
    0.050_353_837_457_436_2,
    -0.025_448_477_223_404_625,
];

/// The largest relative error of `edge_angle_rad` against the correctly rounded angle over its
/// whole domain: the polynomial's 1.1e-15 plus the rounding of the quotient, the reduction and the
/// polynomial's evaluation (a few ulps each). `tests` check it on a dense grid of angles and magnitudes.
pub const EDGE_ANGLE_RELATIVE_ERROR: f64 = 4e-15;

/// γ = atan2(y, x) ∈ [0, π] for y = |a × b| ≥ 0 and x = a · b, the angle between a and b:
///
/// γ = α for x ≥ y,  π/2 − sign(x)·atan(|x|/y) for y > |x|,  π − α for −x ≥ y,  α = atan(y/|x|),
///
/// with atan t on t ∈ [0, 1] reduced to |u| ≤ tan(π/8) (u = t, or u = (t − 1)/(t + 1) and π/4 added)
/// and atan u = u + u·u²·Q(u²), Q the degree-8 polynomial `ATAN_Q` evaluated by Estrin's scheme (Cody
/// and Waite's reduction, 1980). Relative error at most `EDGE_ANGLE_RELATIVE_ERROR`; plain multiplies and adds (no fused
/// multiply-add), so the value is the same on every machine. 0 when y = x = 0.
#[inline]
pub fn edge_angle_rad(y: f64, x: f64) -> f64 {
    debug_assert!(y >= 0.0, "edge_angle_rad takes y = |a × b| ≥ 0, got {y}");
    let ax = x.abs();
    if y > ax {
        let a = atan_unit(ax / y);
        if x >= 0.0 {
            FRAC_PI_2 - a
        } else {
            FRAC_PI_2 + a
        }
    } else if ax == 0.0 {
        0.0
    } else {
        let a = atan_unit(y / ax);
        if x >= 0.0 {
            a
        } else {
            PI - a
        }
    }
}

/// atan t for t ∈ [0, 1] (see `edge_angle_rad`).
#[inline]
fn atan_unit(t: f64) -> f64 {
    let (u, base) = if t > TAN_PI_8 { ((t - 1.0) / (t + 1.0), FRAC_PI_4) } else { (t, 0.0) };
    // Q(s) by Estrin's scheme: four dependent steps instead of Horner's eight (the chain of adds
    // was the kernel's cost).
    let c = &ATAN_Q;
    let s = u * u;
    let s2 = s * s;
    let s4 = s2 * s2;
    let low = (c[0] + c[1] * s) + s2 * (c[2] + c[3] * s);
    let high = ((c[4] + c[5] * s) + s2 * (c[6] + c[7] * s)) + s4 * c[8];
    let q = low + s4 * high;
    base + (u + u * s * q)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// |γ − atan2(y, x)| / atan2(y, x), with libm's atan2 (correctly rounded in practice) as truth.
    fn relative_error(y: f64, x: f64) -> f64 {
        let truth = y.atan2(x);
        let got = edge_angle_rad(y, x);
        if truth == 0.0 {
            got.abs()
        } else {
            ((got - truth) / truth).abs()
        }
    }

    #[test]
    fn the_angle_is_within_its_stated_relative_error_over_the_whole_domain() {
        // 400,001 angles over [0, π] (both reduction boundaries, π/4 and π/2 and 3π/4 included, as
        // are angles down to 1e-12 near 0 and π) at magnitudes from 1e-30 to 1e30.
        let mut worst: f64 = 0.0;
        let steps = 400_000;
        for k in 0..=steps {
            let theta = PI * k as f64 / steps as f64;
            for scale in [1e-30, 1e-3, 1.0, 7.5, 560.0, 1e30] {
                let (y, x) = (theta.sin().abs() * scale, theta.cos() * scale);
                worst = worst.max(relative_error(y, x));
            }
        }
        for e in 1..=12 {
            let small = 10f64.powi(-e);
            for (y, x) in [(small, 1.0), (small, -1.0), (1.0, small), (1.0, -small)] {
                worst = worst.max(relative_error(y, x));
            }
        }
        assert!(worst <= EDGE_ANGLE_RELATIVE_ERROR, "worst relative error {worst:e}");
    }

    #[test]
    fn the_axes_give_their_exact_angles() {
        assert_eq!(edge_angle_rad(0.0, 2.0), 0.0);
        assert_eq!(edge_angle_rad(0.0, -2.0), PI);
        assert_eq!(edge_angle_rad(3.0, 0.0), FRAC_PI_2);
        assert_eq!(edge_angle_rad(3.0, 3.0), FRAC_PI_4);
        assert_eq!(edge_angle_rad(0.0, 0.0), 0.0);
    }
}
