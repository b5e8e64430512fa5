//! The two normals of a diffuse point (the facet's geometric one and the smooth shading one) and the
//! cosine weight a Lambertian surface gives a direction with both: smooth shading of tessellated curved
//! surfaces, guarded so that no light arrives through the facet itself.

use glam::Vec3;

/// The normals of a diffuse point on the side being shaded: `geometric` (the facet's, which decides
/// which side light may arrive from and where rays leave) and `shading` (the surface's interpolated
/// vertex normal, `SurfaceHit::smooth_normal`, turned to the same side; equal to `geometric` on a flat
/// surface).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceNormals {
    pub geometric: Vec3,
    pub shading: Vec3,
}

impl From<Vec3> for SurfaceNormals {
    /// A flat point: both normals `n`.
    fn from(n: Vec3) -> SurfaceNormals {
        SurfaceNormals::flat(n)
    }
}

impl SurfaceNormals {
    pub fn flat(n: Vec3) -> SurfaceNormals {
        SurfaceNormals { geometric: n, shading: n }
    }

    /// Both normals are the same vector (bit for bit): every weight below then takes the flat
    /// surface's own arithmetic, so flat scenes render the same bytes as before smooth shading.
    pub fn is_flat(&self) -> bool {
        self.geometric == self.shading
    }

    /// c = (1 + n_s·n_g)/2: the share of the shading normal's clipped cosine lobe that lies above the
    /// geometric plane, c = (1/π) ∫_{n_g·ω>0} max(0, n_s·ω) dω. It is the view factor of a plane
    /// tilted by α = ∠(n_s, n_g) to a uniform hemisphere, (1 + cos α)/2 (the isotropic-sky formula:
    /// a tilted plane under a sky of radiance L receives πL(1 + cos α)/2). Between 1/2 and 1, since
    /// `shading` is turned to the geometric side; exactly 1 when flat.
    pub fn lobe_above_geometric(&self) -> f32 {
        if self.is_flat() {
            1.0
        } else {
            (0.5 * (1.0 + self.shading.dot(self.geometric))).clamp(0.5, 1.0)
        }
    }

    /// Direction ω (unit, leaving the surface) can carry light to the point: it lies above the
    /// geometric plane, n_g·ω > 0. On a flat point every direction its callers draw counts (they draw
    /// around the one normal), so the flat path does not test it.
    pub fn admits(&self, w: Vec3) -> bool {
        self.is_flat() || self.geometric.dot(w) > 0.0
    }

    /// The cosine weight of the Lambertian term for light arriving from ω (unit, leaving the surface):
    ///
    /// w(ω) = [n_g·ω > 0] · max(0, n_s·ω) / c,   c = (1 + n_s·n_g)/2 (`lobe_above_geometric`),
    ///
    /// and w(ω) = n·ω on a flat point (callers skip w ≤ 0). The shading normal gives the cosine, as in
    /// PBRT and Mitsuba; the geometric guard keeps light from below the facet out whatever the
    /// shading normal says (it would leak through the surface). Dividing by c restores the lobe's
    /// mass the guard cuts off, ∫ w(ω) dω = π for every tilt, so a Lambertian surface of albedo ρ
    /// under uniform radiance L still reflects ρL (a white furnace stays exact); without it a tilted
    /// shading normal would darken such a point by (1 − cos α)/2.
    pub fn cosine(&self, w: Vec3) -> f32 {
        if self.is_flat() {
            return self.shading.dot(w);
        }
        if self.geometric.dot(w) <= 0.0 {
            return 0.0;
        }
        self.shading.dot(w).max(0.0) / self.lobe_above_geometric()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f32::consts::PI;

    /// ∫ w(ω) dω over the sphere by the midpoint rule on a (cos θ, φ) grid around n_g (equal-area
    /// cells of 4π/(2m·m)).
    fn integral_of_weight(normals: SurfaceNormals, m: usize) -> f64 {
        let (t, b) = normals.geometric.any_orthonormal_pair();
        let cell = 4.0 * std::f64::consts::PI / (2 * m * m) as f64;
        let mut sum = 0.0f64;
        for i in 0..2 * m {
            let z = -1.0 + (i as f32 + 0.5) / m as f32;
            let r = (1.0 - z * z).max(0.0).sqrt();
            for j in 0..m {
                let phi = 2.0 * PI * (j as f32 + 0.5) / m as f32;
                let w = t * (r * phi.cos()) + b * (r * phi.sin()) + normals.geometric * z;
                sum += normals.cosine(w).max(0.0) as f64 * cell;
            }
        }
        sum
    }

    #[test]
    fn the_normalised_cosine_integrates_to_pi_at_every_tilt() {
        // The midpoint rule on 2·400 × 400 cells is good to about 1e-5 for these kinked integrands
        // (the kinks at both horizons cost O(1/m²)); 2e-4 is their sum with margin.
        let geometric = Vec3::new(0.2, 0.9, -0.3).normalize();
        for tilt_deg in [0.0f32, 5.0, 20.0, 45.0, 80.0] {
            let axis = geometric.any_orthonormal_vector();
            let shading = glam::Quat::from_axis_angle(axis, tilt_deg.to_radians()) * geometric;
            let normals = SurfaceNormals { geometric, shading };
            let integral = integral_of_weight(normals, 400);
            assert!((integral - std::f64::consts::PI).abs() < 2e-4, "tilt {tilt_deg}°: {integral}");
        }
    }

    #[test]
    fn light_below_the_facet_has_no_weight_whatever_the_shading_normal() {
        let geometric = Vec3::Z;
        let shading = Vec3::new(0.6, 0.0, 0.8);
        let normals = SurfaceNormals { geometric, shading };
        // 5° below the facet's plane, 37° from the shading normal: lit by the shading normal alone.
        let below = Vec3::new(5f32.to_radians().cos(), 0.0, -5f32.to_radians().sin());
        assert!(shading.dot(below) > 0.5);
        assert_eq!(normals.cosine(below), 0.0);
        assert!(!normals.admits(below));
    }

    #[test]
    fn a_flat_point_keeps_the_plain_cosine_bit_for_bit() {
        let n = Vec3::new(0.3, -0.5, 0.81).normalize();
        let w = Vec3::new(-0.1, 0.4, 0.9).normalize();
        let normals = SurfaceNormals::from(n);
        assert!(normals.is_flat());
        assert_eq!(normals.cosine(w).to_bits(), n.dot(w).to_bits());
        assert_eq!(normals.lobe_above_geometric(), 1.0);
    }
}
