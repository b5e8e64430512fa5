//! The hemicube's frame and what happens to a polygon before it is drawn: the local frame, the
//! face coordinates, trivial rejection by outcodes and Sutherland–Hodgman clipping to a face's frustum.

use glam::Vec3;

/// Guard band: polygons are clipped to |u|, |v| ≤ GUARD·w in face coordinates (the face is |u| ≤ w),
/// so projected coordinates stay small and the integer edge functions exact.
pub(super) const GUARD: f32 = 2.0;
/// Most input corners rasterised as one polygon; larger convex polygons are fanned into triangles.
pub(super) const MAX_INPUT_CORNERS: usize = 8;
/// Most vertices after clipping a polygon of `MAX_INPUT_CORNERS` against the 5 clip planes.
pub(super) const MAX_CLIPPED: usize = MAX_INPUT_CORNERS + 6;

/// The orthonormal frame of one hemicube: `normal` is the top face's axis, `tangent` and `bitangent`
/// the local x and y axes (side faces ±x, ±y).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HemicubeFrame {
    pub eye: Vec3,
    pub tangent: Vec3,
    pub bitangent: Vec3,
    pub normal: Vec3,
}

impl HemicubeFrame {
    /// The frame at `eye` around unit `normal`, rotated by `rotation_rad` about it. With no rotation the
    /// tangent is the world x axis projected onto the tangent plane (the world y axis when |n_x| ≥ 0.9),
    /// and bitangent = normal × tangent.
    pub fn new(eye: Vec3, normal: Vec3, rotation_rad: f32) -> Self {
        let normal = normal.normalize();
        let axis = if normal.x.abs() >= 0.9 { Vec3::Y } else { Vec3::X };
        let t0 = (axis - axis.dot(normal) * normal).normalize();
        let b0 = normal.cross(t0);
        let (s, c) = rotation_rad.sin_cos();
        let tangent = (c * t0 + s * b0).normalize();
        let bitangent = normal.cross(tangent);
        HemicubeFrame { eye, tangent, bitangent, normal }
    }

    /// World point → local (x, y, z) relative to the eye.
    #[inline]
    pub(super) fn local(&self, p: Vec3) -> Vec3 {
        let d = p - self.eye;
        Vec3::new(d.dot(self.tangent), d.dot(self.bitangent), d.dot(self.normal))
    }

    /// World direction → local.
    #[inline]
    pub(super) fn local_dir(&self, d: Vec3) -> Vec3 {
        Vec3::new(d.dot(self.tangent), d.dot(self.bitangent), d.dot(self.normal))
    }
}

/// Local (x, y, z) → face coordinates (u, v, w): w along the face's axis, the projection is (u/w, v/w).
#[inline]
pub(super) fn to_face(f: usize, p: Vec3) -> [f32; 3] {
    match f {
        0 => [p.x, p.y, p.z],
        1 => [p.y, p.z, p.x],
        2 => [p.y, p.z, -p.x],
        3 => [p.x, p.z, p.y],
        _ => [p.x, p.z, -p.y],
    }
}

/// Bit f set when face f (0 top, 1 +x, 2 −x, 3 +y, 4 −y) may see part of the points' convex hull: for
/// each face, the hull is rejected when every point lies outside one of its frustum planes (|u| ≤ w,
/// v ≤ w, and v ≥ −w on top or v ≥ 0 on a side) or behind it (w ≤ 0).
pub(super) fn face_mask(local: &[Vec3]) -> u8 {
    faces_of_code(local.iter().fold(!0, |code, &p| code & outcode(p)))
}

/// Outcode bit of `outcode`: the point lies on or behind the hemicube's base plane (z ≤ 0, or NaN).
pub(super) const BEHIND_BASE: u32 = 1 << 25;

/// Outcode of a local point: bit 5f + k set when it lies outside frustum plane k of face f (the planes
/// of `face_mask`), and `BEHIND_BASE`. The AND of a polygon's corner outcodes has a plane's bit set
/// exactly when every corner lies outside that plane (Cohen–Sutherland style trivial rejection).
#[inline]
pub(super) fn outcode(p: Vec3) -> u32 {
    let Vec3 { x, y, z } = p;
    let below = z < 0.0;
    let bits = |u: f32, v: f32, w: f32, v_low: bool| -> u32 {
        (u < -w) as u32 | ((u > w) as u32) << 1 | ((v > w) as u32) << 2 | (v_low as u32) << 3 | ((w <= 0.0) as u32) << 4
    };
    bits(x, y, z, y < -z)
        | bits(y, z, x, below) << 5
        | bits(y, z, -x, below) << 10
        | bits(x, z, y, below) << 15
        | bits(x, z, -y, below) << 20
        | ((z > 0.0) as u32 ^ 1) << 25
}

/// The faces (bit f) that a polygon with combined outcode `code` may cover: those with no plane
/// that all its corners lie outside.
#[inline]
pub(super) fn faces_of_code(code: u32) -> u8 {
    let mut mask = 0;
    for f in 0..5 {
        if (code >> (5 * f)) & 0x1f == 0 {
            mask |= 1 << f;
        }
    }
    mask
}

/// Sutherland–Hodgman: clips polygon `poly[..count]` (face coordinates) to the half-space
/// a·u + b·v + c·w + e ≥ 0 in place; returns the new vertex count.
pub(super) fn clip_polygon(poly: &mut [[f32; 3]; MAX_CLIPPED], count: usize, plane: &[f32; 4]) -> usize {
    let dist = |p: &[f32; 3]| plane[0] * p[0] + plane[1] * p[1] + plane[2] * p[2] + plane[3];
    let input = *poly;
    let mut out = 0;
    for k in 0..count {
        let a = input[k];
        let b = input[(k + 1) % count];
        let (da, db) = (dist(&a), dist(&b));
        if da >= 0.0 {
            poly[out] = a;
            out += 1;
        }
        if (da >= 0.0) != (db >= 0.0) {
            let t = da / (da - db);
            poly[out] = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2])];
            out += 1;
        }
        if out >= MAX_CLIPPED {
            break; // cannot happen for convex input; keeps indices in bounds regardless
        }
    }
    out
}
