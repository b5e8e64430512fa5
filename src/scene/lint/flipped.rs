//! Flipped faces: faces whose winding disagrees with the neighbours they share edges with, so that
//! their fronts look the wrong way.

use super::weld::edge_key;
use super::{to_f32, FlippedFace, FlippedFaces, ObjectCount, Poly, SurfaceRef};
use crate::scene::Surface;
use std::collections::HashMap;

/// One face's use of a welded edge.
#[derive(Clone, Copy)]
struct EdgeUse {
    face: usize,
    /// Traversed from the lower corner id to the higher.
    ascending: bool,
    /// Index of the edge in the face (from corner k to corner k + 1).
    edge: usize,
}

/// A face sharing an edge with another.
#[derive(Clone, Copy)]
struct Neighbour {
    face: usize,
    /// Both faces traverse the shared edge the same way: their windings disagree.
    same_direction: bool,
    /// Index of the shared edge in the face whose neighbour this is.
    edge: usize,
}

/// Faces whose winding disagrees with their edge neighbours. Two one-sided faces sharing an edge (and
/// no third face sharing it) are consistent when they traverse it in opposite directions. Each
/// edge-connected patch is 2-coloured by orientation from its lowest-index face; the smaller colour
/// class (on a tie, the one without that face) is reported as flipped.
pub fn flipped_faces(
    surfaces: &[Surface],
    polys: &[Option<Poly>],
    ids: &[Vec<u32>],
    max_examples: usize,
) -> FlippedFaces {
    let mut edges: HashMap<(u32, u32), Vec<EdgeUse>> = HashMap::new();
    for (s, p) in polys.iter().enumerate() {
        let Some(p) = p else { continue };
        if surfaces[s].two_sided {
            continue;
        }
        let n = p.vertices.len();
        for k in 0..n {
            let (a, b) = (ids[s][k], ids[s][(k + 1) % n]);
            if a != b {
                edges.entry(edge_key(a, b)).or_default().push(EdgeUse { face: s, ascending: a < b, edge: k });
            }
        }
    }
    let mut neighbours: Vec<Vec<Neighbour>> = vec![Vec::new(); surfaces.len()];
    let mut inconsistent_edges = 0;
    let mut keys: Vec<&(u32, u32)> = edges.keys().collect();
    keys.sort();
    for key in keys {
        let users = &edges[key];
        if let [u, v] = users[..] {
            if u.face != v.face {
                let same_direction = u.ascending == v.ascending;
                neighbours[u.face].push(Neighbour { face: v.face, same_direction, edge: u.edge });
                neighbours[v.face].push(Neighbour { face: u.face, same_direction, edge: v.edge });
                inconsistent_edges += usize::from(same_direction);
            }
        }
    }
    let mut colour: Vec<Option<bool>> = vec![None; surfaces.len()];
    let mut flipped: Vec<usize> = Vec::new();
    for root in 0..surfaces.len() {
        if colour[root].is_some() || neighbours[root].is_empty() {
            continue;
        }
        colour[root] = Some(false);
        let mut patch = vec![root];
        let mut k = 0;
        while k < patch.len() {
            let s = patch[k];
            k += 1;
            let cs = colour[s].expect("coloured when queued");
            for &Neighbour { face: t, same_direction, .. } in &neighbours[s] {
                if colour[t].is_none() {
                    colour[t] = Some(cs ^ same_direction);
                    patch.push(t);
                }
            }
        }
        let odd = patch.iter().filter(|&&s| colour[s] == Some(true)).count();
        let minority = odd * 2 <= patch.len();
        flipped.extend(patch.into_iter().filter(|&s| colour[s] == Some(minority)));
    }
    flipped.sort_unstable();
    let mut per_object: Vec<ObjectCount> = Vec::new();
    for &s in &flipped {
        match per_object.iter_mut().find(|o| o.object == surfaces[s].object) {
            Some(o) => o.count += 1,
            None => per_object.push(ObjectCount { object: surfaces[s].object.clone(), count: 1 }),
        }
    }
    let examples = flipped
        .iter()
        .filter_map(|&s| {
            let &Neighbour { face: t, edge: k, .. } = neighbours[s].iter().find(|n| n.same_direction)?;
            let p = polys[s].as_ref()?;
            let mid = 0.5 * (p.vertices[k] + p.vertices[(k + 1) % p.vertices.len()]);
            Some(FlippedFace {
                surface: SurfaceRef::of(surfaces, s),
                neighbour: SurfaceRef::of(surfaces, t),
                point: to_f32(mid),
            })
        })
        .take(max_examples)
        .collect();
    FlippedFaces { count: flipped.len(), inconsistent_edges, per_object, examples }
}
