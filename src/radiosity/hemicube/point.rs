//! Point-to-polygon form factors by one hemicube, and the plane of a polygon (Newell).

use glam::Vec3;

use super::{Hemicube, HemicubeFrame, ItemBuffer};

/// Form factors from a point to each polygon of a scene by one hemicube (Nusselt analog, Cohen and
/// Greenberg 1985): F_j = Σ ΔF over the hemicube pixels where polygon j is the nearest surface.
///
/// `eye` is the differential area's position, `normal` its unit normal; the hemicube is rotated by
/// `rotation_rad` about the normal (see `HemicubeFrame::new`). Each polygon is convex, planar and
/// counter-clockwise about its front; it is seen only from the front and occludes the others. Returns
/// F_j per polygon (their sum ≈ the visible fraction of the hemisphere).
pub fn point_form_factors(
    hc: &Hemicube,
    eye: Vec3,
    normal: Vec3,
    rotation_rad: f32,
    polygons: &[&[Vec3]],
    buffers: &mut ItemBuffer,
) -> Vec<f64> {
    buffers.begin(hc, HemicubeFrame::new(eye, normal, rotation_rad));
    for (j, poly) in polygons.iter().enumerate() {
        if poly.len() < 3 {
            continue;
        }
        let (poly_normal, centre) = newell_plane(poly);
        buffers.add_polygon(hc, j as u32, poly, poly_normal, centre);
    }
    let mut out = vec![0.0; polygons.len()];
    buffers.finish(hc, |j, f| out[j as usize] = f);
    out
}

/// Unit normal (Newell's method: n ∝ Σ (v_k − v₀) × (v_{k+1} − v₀), on the polygon's own edges so
/// that it keeps its precision far from the origin) and vertex centroid of a polygon.
pub fn newell_plane(poly: &[Vec3]) -> (Vec3, Vec3) {
    let mut n = Vec3::ZERO;
    let mut c = Vec3::ZERO;
    for (k, &v) in poly.iter().enumerate() {
        n += (v - poly[0]).cross(poly[(k + 1) % poly.len()] - poly[0]);
        c += v;
    }
    (n.normalize_or_zero(), c / poly.len() as f32)
}
