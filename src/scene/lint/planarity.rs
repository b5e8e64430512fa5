//! Non-planar polygons: corners off the polygon's best plane, so that its two triangles bend.

use super::{to_f32, NonPlanar, Poly, SurfaceRef};
use crate::scene::Surface;

/// Every polygon with a corner farther than `tolerance` from its best plane, in surface order; the
/// point is the farthest corner.
pub fn non_planar(surfaces: &[Surface], polys: &[Option<Poly>], tolerance: f64) -> Vec<NonPlanar> {
    polys
        .iter()
        .enumerate()
        .filter_map(|(i, p)| Some((i, p.as_ref()?)))
        .filter(|(_, p)| p.deviation > tolerance)
        .map(|(i, p)| {
            let far = p
                .vertices
                .iter()
                .copied()
                .max_by(|a, b| p.distance(*a).abs().total_cmp(&p.distance(*b).abs()))
                .unwrap_or(p.lo);
            NonPlanar { surface: SurfaceRef::of(surfaces, i), deviation: p.deviation, point: to_f32(far) }
        })
        .collect()
}
