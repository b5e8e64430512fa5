//! Emitters resting on a face: an edge of an emitting surface lying in another face's plane and
//! inside it, away from its edges, with the emitter standing at an angle to it (a fixture against a
//! ceiling, a glowing cube on a floor). A uniform mesh of that face does not follow the emitter's
//! outline, so its elements straddle the seam where the face is brightest: an element whose centre
//! falls under the emitter sees only the backs of its faces and reflects nothing, though half of it
//! lies in that bright strip. On `scenes/rooms/fixture_room` the uniform matrix lost 3.7% of the
//! light that way (docs/accuracy.md, session 31); `radiosity::method`'s `auto` leaves such scenes to
//! the hierarchy, which subdivides there.

use super::{frame_diagonal, nearby_pairs, to_f32, Poly, SurfaceRef};
use crate::scene::{Material, Surface};
use glam::DVec3;
use serde::Serialize;

/// An emitter's edge resting inside another face.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EmitterContact {
    pub emitter: SurfaceRef,
    /// The face the edge rests on.
    pub face: SurfaceRef,
    /// A point of the edge inside the face.
    pub point: [f32; 3],
}

/// Emitters at an angle of more than this to a face (|n_e·n_f| below its cosine) can rest on it; a
/// coplanar emitter lying on a face covers it (a coplanar overlap, `overlaps`), straddles nothing.
const MIN_ANGLE_COS: f64 = 0.999;

/// A point of edge (p, q) inside `face`, farther than `tolerance` from each of its edges, when both
/// endpoints lie within `tolerance` of its plane; the edge is probed at ¼, ½ and ¾ of its length (a
/// face cut into a grid of cells may hold only part of it).
pub fn edge_inside(p: DVec3, q: DVec3, face: &Poly, tolerance: f64) -> Option<DVec3> {
    if face.distance(p).abs() > tolerance || face.distance(q).abs() > tolerance {
        return None;
    }
    let v = &face.vertices;
    [0.25, 0.5, 0.75].into_iter().map(|t| p + (q - p) * t).find(|&x| {
        (0..v.len()).all(|k| {
            let (a, b) = (v[k], v[(k + 1) % v.len()]);
            let edge = b - a;
            let len = edge.length();
            len > 0.0 && edge.cross(x - a).dot(face.normal) / len > tolerance
        })
    })
}

/// Every (emitter, face) pair where an edge of an emitting surface rests inside a non-emitting face
/// at an angle to it (`edge_inside`), ordered by emitter then face; lengths are compared with the
/// lint's tolerance (`LintOptions::default`'s 1e-5 of the scene's diagonal). Candidate pairs come from
/// the lint's grid over the faces' bounding boxes (`nearby_pairs`), so the cost grows with
/// the number of nearby pairs, not with emitters × faces.
pub fn emitter_contacts(surfaces: &[Surface], materials: &[Material]) -> Vec<EmitterContact> {
    let emits = |i: usize| materials[surfaces[i].material as usize].is_emitter();
    if !(0..surfaces.len()).any(emits) {
        return Vec::new();
    }
    let polys: Vec<Option<Poly>> = surfaces.iter().map(|s| Poly::new(&s.vertices)).collect();
    let tolerance =
        (super::LintOptions::default().relative_tolerance * frame_diagonal(surfaces, &polys)).max(f32::EPSILON as f64);
    let mut found: Vec<EmitterContact> = nearby_pairs(&polys, tolerance)
        .into_iter()
        .filter_map(|(i, j)| {
            let (e, f) = match (emits(i), emits(j)) {
                (true, false) => (i, j),
                (false, true) => (j, i),
                _ => return None,
            };
            let (pe, pf) = (polys[e].as_ref()?, polys[f].as_ref()?);
            if pe.normal.dot(pf.normal).abs() > MIN_ANGLE_COS {
                return None;
            }
            let v = &pe.vertices;
            let point = (0..v.len()).find_map(|k| edge_inside(v[k], v[(k + 1) % v.len()], pf, tolerance))?;
            Some(EmitterContact {
                emitter: SurfaceRef::of(surfaces, e),
                face: SurfaceRef::of(surfaces, f),
                point: to_f32(point),
            })
        })
        .collect();
    found.sort_by_key(|c| (c.emitter.index, c.face.index));
    found
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{vec3, Vec3};

    fn poly(v: &[Vec3]) -> Poly {
        Poly::new(v).unwrap()
    }

    /// The ceiling y = 2 (facing down) and a fixture side standing on it at x = 0.5, from z = 0.2 to
    /// 0.8: resting inside. Moved to the ceiling's edge (x = 0), lowered by 1 mm, or lying flat in the
    /// ceiling's plane, it does not.
    #[test]
    fn an_edge_rests_inside_only_in_the_plane_and_away_from_the_edges() {
        let ceiling = poly(&[vec3(0.0, 2.0, 0.0), vec3(1.0, 2.0, 0.0), vec3(1.0, 2.0, 1.0), vec3(0.0, 2.0, 1.0)]);
        let t = 1e-5;
        let on = |x: f64, y: f64| edge_inside(DVec3::new(x, y, 0.2), DVec3::new(x, y, 0.8), &ceiling, t);
        let near = |found: Option<DVec3>, want: DVec3| found.is_some_and(|x| (x - want).length() < 1e-12);
        assert!(near(on(0.5, 2.0), DVec3::new(0.5, 2.0, 0.35)));
        assert_eq!(on(0.0, 2.0), None);
        assert_eq!(on(0.5, 1.999), None);
        // an edge from outside the face into it is found by its inner probes
        let crossing = edge_inside(DVec3::new(0.5, 2.0, -0.5), DVec3::new(0.5, 2.0, 0.5), &ceiling, t);
        assert!(near(crossing, DVec3::new(0.5, 2.0, 0.25)));
    }
}
