//! A surface's polygon in f64 with its best plane (Newell's normal through the centroid): what every
//! check measures against.

use glam::DVec3;

/// A surface's polygon in f64 with its best plane.
#[derive(Clone, Debug)]
pub struct Poly {
    pub vertices: Vec<DVec3>,
    /// Unit normal (Newell's method), by the right-hand rule.
    pub normal: DVec3,
    /// Plane offset: `normal · x = offset` through the corners' centroid.
    pub offset: f64,
    /// Largest distance of a corner from that plane (0 for a triangle, up to rounding).
    pub deviation: f64,
    pub lo: DVec3,
    pub hi: DVec3,
}

impl Poly {
    /// `None` for fewer than 3 corners, non-finite corners or zero area.
    pub fn new(vertices: &[glam::Vec3]) -> Option<Poly> {
        if vertices.len() < 3 || !vertices.iter().all(|v| v.is_finite()) {
            return None;
        }
        let vertices: Vec<DVec3> = vertices.iter().map(|v| v.as_dvec3()).collect();
        let n = vertices.len();
        let centroid = vertices.iter().sum::<DVec3>() / n as f64;
        // Newell's normal about the centroid (better conditioned far from the origin).
        let newell: DVec3 = (0..n).map(|k| (vertices[k] - centroid).cross(vertices[(k + 1) % n] - centroid)).sum();
        let normal = newell.try_normalize()?;
        let offset = normal.dot(centroid);
        let deviation = vertices.iter().map(|v| (normal.dot(*v) - offset).abs()).fold(0.0, f64::max);
        let lo = vertices.iter().fold(DVec3::INFINITY, |a, &v| a.min(v));
        let hi = vertices.iter().fold(DVec3::NEG_INFINITY, |a, &v| a.max(v));
        Some(Poly { vertices, normal, offset, deviation, lo, hi })
    }

    /// Signed distance of `x` from the polygon's plane (positive in front).
    pub fn distance(&self, x: DVec3) -> f64 {
        self.normal.dot(x) - self.offset
    }

    pub(super) fn centroid(&self) -> DVec3 {
        self.vertices.iter().sum::<DVec3>() / self.vertices.len() as f64
    }
}
