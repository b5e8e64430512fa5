//! The scene's principal frame: the orthonormal axes that its large planes line up with. The scene's
//! size (`SceneDescription::diagonal`, from which the presets' element sizes come) is its bounding
//! box's diagonal in this frame, and the hierarchy's cluster tree splits along these axes and boxes
//! its clusters in them (`radiosity::hierarchy::clusters`, `Nodes::frame`): a room built at an angle
//! to the world axes is meshed and clustered as it is when built along them.
//!
//! Why: a world-axis box grows with the angle (alcove_hall turned 30° about y: diagonal 9.08 →
//! 11.11 m, so 29% fewer elements at every preset). And the cluster build splits at the median along an axis and keeps a plane of equal coordinates
//! (one face of a wall) on one side (`clusters::median_split`). Off the world axes no coordinates tie,
//! the median cuts walls, and clusters mix pieces of both sides of a wall and of the objects against
//! it; the clusters' world-axis boxes also grow with the angle (a thin wall at 45° gets a box as deep
//! as it is long). docs/accuracy.md, session 20.

use std::collections::BTreeMap;

use glam::{DVec3, Vec3};

/// An orthonormal frame (three unit axes, not necessarily right-handed: only coordinates along them
/// are read). The default is the world's axes, and coordinates in it are the world's, bit for bit.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Frame {
    /// `None`: the world axes.
    axes: Option<[Vec3; 3]>,
}

/// Normals closer than this (per component, unit normals) share a bin of `principal`: about 0.9°.
const BIN_STEP: f64 = 1.0 / 64.0;

/// A second axis must be within this of perpendicular to the first (|cos|, about 1.1°).
const PERPENDICULAR_COS: f64 = 0.02;

/// A frame other than the world's is taken only when its alignment score is higher than the world's
/// by more than this (relative; rounding): a scene whose planes line up with the world's axes as
/// well as with another frame's (an octagonal hall) keeps the world's. (2% kept a room turned 7°
/// on the world axes: cos⁴ 7° = 0.97 on its walls.)
const PREFER_WORLD: f64 = 1.0 + 1e-4;

impl Frame {
    /// The world's axes.
    pub fn world() -> Frame {
        Frame { axes: None }
    }

    /// Whether this is the world's frame.
    pub fn is_world(&self) -> bool {
        self.axes.is_none()
    }

    /// The coordinates of world point `p` along the frame's axes (`p` itself in the world frame).
    pub fn to_frame(&self, p: Vec3) -> Vec3 {
        match self.axes {
            None => p,
            Some([a, b, c]) => Vec3::new(a.dot(p), b.dot(p), c.dot(p)),
        }
    }

    /// The world point with frame coordinates `q` (the inverse of `to_frame`).
    pub fn from_frame(&self, q: Vec3) -> Vec3 {
        match self.axes {
            None => q,
            Some([a, b, c]) => a * q.x + b * q.y + c * q.z,
        }
    }

    /// `to_frame` in f64 (`p` itself in the world frame): for boxes measured in f64 (the geometry lint).
    pub fn to_frame_f64(&self, p: DVec3) -> DVec3 {
        match self.axes {
            None => p,
            Some([a, b, c]) => DVec3::new(a.as_dvec3().dot(p), b.as_dvec3().dot(p), c.as_dvec3().dot(p)),
        }
    }

    /// The frame's axes as world vectors.
    pub fn axes(&self) -> [Vec3; 3] {
        self.axes.unwrap_or([Vec3::X, Vec3::Y, Vec3::Z])
    }
}

/// The principal frame of a set of triangles (`(unit normal, area)` each): the normal direction
/// (up to sign) that carries the most area, a₁; the direction within `PERPENDICULAR_COS` of
/// perpendicular to it that carries the most, projected, a₂; and a₃ = a₁ × a₂. Normals are binned
/// `BIN_STEP` apart and each bin stands for its area-weighted mean direction. The frame is taken
/// over the world's only when its alignment score
///
/// S = Σ_bins A_b · max_k (d_b · a_k)⁴
///
/// (1 for area on a plane of the frame, ¼ at 45° to two of its axes) is `PREFER_WORLD` times the
/// world's; so a scene built along the world axes keeps them exactly, and so does one with no
/// dominant perpendicular planes (a sphere). Deterministic: bins are visited in key order.
pub fn principal(triangles: impl Iterator<Item = (Vec3, f32)>) -> Frame {
    // Bin key → (area, area-weighted direction), the normal's sign made canonical (largest
    // component positive) so that opposite walls share a bin.
    let mut bins: BTreeMap<[i32; 3], (f64, DVec3)> = BTreeMap::new();
    for (normal, area) in triangles {
        let n = normal.as_dvec3();
        if !(area > 0.0) || !n.is_finite() || !(n.length_squared() > 0.5) {
            continue;
        }
        let largest = if n.x.abs() >= n.y.abs() && n.x.abs() >= n.z.abs() {
            n.x
        } else if n.y.abs() >= n.z.abs() {
            n.y
        } else {
            n.z
        };
        let d = if largest < 0.0 { -n } else { n };
        let key = [d.x, d.y, d.z].map(|c| (c / BIN_STEP).round() as i32);
        let bin = bins.entry(key).or_insert((0.0, DVec3::ZERO));
        bin.0 += area as f64;
        bin.1 += d * area as f64;
    }
    let bins: Vec<(f64, DVec3)> =
        bins.into_values().filter_map(|(a, sum)| sum.try_normalize().map(|d| (a, d))).collect();
    let heaviest = |accept: &dyn Fn(DVec3) -> bool| {
        bins.iter().filter(|(_, d)| accept(*d)).fold(None, |best: Option<(f64, DVec3)>, &(a, d)| match best {
            Some((best_a, _)) if best_a >= a => best,
            _ => Some((a, d)),
        })
    };
    let Some((_, a1)) = heaviest(&|_| true) else {
        return Frame::world();
    };
    let Some((_, d2)) = heaviest(&|d| d.dot(a1).abs() < PERPENDICULAR_COS) else {
        return Frame::world();
    };
    let Some(a2) = (d2 - a1 * d2.dot(a1)).try_normalize() else {
        return Frame::world();
    };
    let a3 = a1.cross(a2);
    let score = |axes: [DVec3; 3]| -> f64 {
        bins.iter().map(|&(a, d)| a * axes.iter().map(|k| d.dot(*k).powi(4)).fold(0.0, f64::max)).sum()
    };
    let world = score([DVec3::X, DVec3::Y, DVec3::Z]);
    if score([a1, a2, a3]) <= world * PREFER_WORLD {
        return Frame::world();
    }
    Frame { axes: Some(nearest_to_world([a1, a2, a3]).map(|a| a.as_vec3())) }
}

/// The principal frame of planar polygons (`principal` over each one's Newell normal and area):
/// the frame of a scene's surfaces (`SceneDescription::frame`, the geometry lint's size).
pub fn of_polygons<'a>(polygons: impl Iterator<Item = &'a [Vec3]>) -> Frame {
    principal(polygons.map(|v| {
        let newell = (0..v.len()).fold(Vec3::ZERO, |n, i| n + v[i].cross(v[(i + 1) % v.len()]));
        (newell.normalize_or_zero(), 0.5 * newell.length())
    }))
}

/// The axes reordered and signed to lie nearest the world's x, y and z: of the six orders, the one
/// with the largest Σ_k |a_k · e_k| (the first of equals), each axis then turned to a_k · e_k ≥ 0. A
/// room turned by less than 45° then has frame coordinates equal to its unturned world coordinates
/// (up to rounding), so it is split in the same order and gets the same cluster tree.
fn nearest_to_world(axes: [DVec3; 3]) -> [DVec3; 3] {
    const ORDERS: [[usize; 3]; 6] = [[0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0]];
    let fit = |order: &[usize; 3]| (0..3).map(|k| axes[order[k]][k].abs()).sum::<f64>();
    let best = ORDERS.iter().fold(ORDERS[0], |best, order| if fit(order) > fit(&best) { *order } else { best });
    std::array::from_fn(|k| {
        let a = axes[best[k]];
        if a[k] < 0.0 {
            -a
        } else {
            a
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Quat;

    /// The six faces of a box room (floor and ceiling 6 × 4, long walls 6 × 3, short walls 4 × 3)
    /// as (normal, area), turned by `rotation`, with a few small tilted triangles besides.
    fn room(rotation: Quat) -> Vec<(Vec3, f32)> {
        let mut faces = vec![
            (Vec3::Y, 24.0),
            (-Vec3::Y, 24.0),
            (Vec3::Z, 18.0),
            (-Vec3::Z, 18.0),
            (Vec3::X, 12.0),
            (-Vec3::X, 12.0),
            (Vec3::new(1.0, 1.0, 0.3).normalize(), 0.5),
            (Vec3::new(-0.2, 1.0, 0.7).normalize(), 0.5),
        ];
        for f in &mut faces {
            f.0 = rotation * f.0;
        }
        faces
    }

    /// A room along the world axes keeps the world frame exactly (so its tree is unchanged).
    #[test]
    fn a_room_along_the_world_axes_keeps_the_world_frame() {
        assert!(principal(room(Quat::IDENTITY).into_iter()).is_world());
    }

    /// A room turned 30° about y gets its own axes back, in the order and with the signs of the
    /// world axes they came from (so it is split as it is unturned), within 1e-5.
    #[test]
    fn a_turned_room_gets_its_own_axes() {
        let turn = Quat::from_rotation_y(30f32.to_radians());
        let frame = principal(room(turn).into_iter());
        assert!(!frame.is_world());
        let room_axes = [turn * Vec3::X, turn * Vec3::Y, turn * Vec3::Z];
        for (axis, room_axis) in frame.axes().into_iter().zip(room_axes) {
            assert!(axis.dot(room_axis) > 1.0 - 1e-5, "frame axis {axis}, room axis {room_axis}");
        }
        // Coordinates round-trip.
        let p = Vec3::new(1.5, -2.0, 7.25);
        assert!(frame.from_frame(frame.to_frame(p)).distance(p) < 1e-5);
    }

    /// Walls in eight directions 45° apart (an octagonal hall) fit the world's axes as well as any
    /// other frame: the world frame is kept.
    #[test]
    fn an_octagonal_hall_keeps_the_world_frame() {
        let mut faces = vec![(Vec3::Y, 50.0), (-Vec3::Y, 50.0)];
        for k in 0..8 {
            let angle = (k as f32 * 45.0).to_radians();
            faces.push((Vec3::new(angle.cos(), 0.0, angle.sin()), 10.0));
        }
        assert!(principal(faces.into_iter()).is_world());
    }

    /// Nothing with an area, or planes in one direction only (no second axis): the world frame.
    #[test]
    fn a_scene_without_two_perpendicular_planes_keeps_the_world_frame() {
        assert!(principal(std::iter::empty()).is_world());
        assert!(principal([(Vec3::new(0.3, 0.9, 0.1).normalize(), 2.0), (Vec3::ZERO, 1.0)].into_iter()).is_world());
    }

    /// A room turned by a small angle (7°) is not mistaken for one along the world axes.
    #[test]
    fn a_room_turned_a_little_gets_its_own_axes() {
        let turn = Quat::from_rotation_y(7f32.to_radians());
        let frame = principal(room(turn).into_iter());
        let x = frame.axes().iter().map(|a| a.dot(turn * Vec3::X).abs()).fold(0.0, f32::max);
        assert!(x > 1.0 - 1e-5, "{frame:?}");
    }
}
