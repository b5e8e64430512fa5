//! T-junctions: mesh vertices that lie inside another element's edge. Exporters write a wall beside a
//! staircase as upright strips, one per step, and a wall round a door as pieces: neighbouring pieces
//! of one plane whose corners lie inside each other's edges instead of meeting at shared corners.
//! Found here, geometrically, so that the vertex step (`smooth_mesh`) can fit each element across the
//! junction, and cut its outline at every vertex inside an edge: without it each strip is a surface of
//! its own, one element wide, whose fit across the strip has no neighbours and whose image is a flat
//! band.

use glam::Vec3;
use rustc_hash::FxHashMap;

use super::smoothing_groups::{join, root, Facet};
use crate::mesh::NONE;

/// A vertex lies on a segment when it is within this fraction of the positions' extent (per axis) of
/// the segment's line, and this far inside its ends: above the welding tolerance (`smooth_mesh`), since
/// a grid point on a long edge is interpolated from its ends in f32.
pub const ON_EDGE_TOLERANCE: f32 = 1e-5;

/// One element edge with vertices strictly inside it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct EdgeInside {
    pub element: u32,
    /// The edge's ends, in the element's corner order.
    pub ends: (u32, u32),
    /// The vertices inside it, ordered from `ends.0` to `ends.1`.
    pub inside: Vec<u32>,
}

/// Every element edge with vertices strictly inside it, and those vertices: only vertices of the
/// edge's element's class (`vertex_class(v) == element_class(e)`; both uses want vertices of surfaces
/// of the element's material and side, so the grid is kept per class and a long floor edge never
/// visits the dense vertices of a statue standing on it) for which `wanted(v, element)` holds.
///
/// A vertex p is inside the edge (a, b) when, with s = (p − a)·(b − a)/|b − a|², the distance
/// |p − (a + s(b − a))| is at most the tolerance t and t < s·|b − a| < |b − a| − t (t =
/// `ON_EDGE_TOLERANCE` × the extent). Only vertices some element uses are candidates; they come from
/// a hash grid of cells twice the mean edge length, so the search is linear in the mesh.
pub fn vertices_inside_edges(
    positions: &[Vec3],
    corners: &[[u32; 4]],
    vertex_class: impl Fn(u32) -> u32,
    element_class: impl Fn(usize) -> u32,
    wanted: impl Fn(u32, usize) -> bool,
) -> Vec<EdgeInside> {
    let mut inside = Vec::new();
    let edges = || {
        corners.iter().enumerate().flat_map(|(e, c)| {
            let n = c.iter().take_while(|&&v| v != NONE).count();
            (0..n).map(move |k| (e, c[k], c[(k + 1) % n]))
        })
    };
    let (mut length, mut count) = (0.0f64, 0usize);
    for (_, a, b) in edges() {
        length += positions[a as usize].distance(positions[b as usize]) as f64;
        count += 1;
    }
    if count == 0 {
        return inside;
    }
    let (lo, hi) =
        positions.iter().fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    let tolerance = ((hi - lo).max_element() * ON_EDGE_TOLERANCE).max(f32::MIN_POSITIVE);
    let cell = ((2.0 * length / count as f64) as f32).max(tolerance * 10.0);
    let key = |p: Vec3| ((p - lo) / cell).floor().as_ivec3().to_array();
    let mut used = vec![false; positions.len()];
    for c in corners {
        for &v in c.iter().filter(|&&v| v != NONE) {
            used[v as usize] = true;
        }
    }
    let mut grid: FxHashMap<(u32, [i32; 3]), Vec<u32>> = FxHashMap::default();
    for (v, &p) in positions.iter().enumerate().filter(|&(v, _)| used[v]) {
        grid.entry((vertex_class(v as u32), key(p))).or_default().push(v as u32);
    }
    let mut found: Vec<(f32, u32)> = Vec::new();
    let mut cells: Vec<[i32; 3]> = Vec::new();
    for (e, a, b) in edges() {
        let (pa, pb) = (positions[a as usize], positions[b as usize]);
        let d = pb - pa;
        let length = d.length();
        if !(length > 2.0 * tolerance) {
            continue;
        }
        // The cells the edge's tolerance tube touches, piece by piece (pieces at most half a cell
        // long, so each piece's box touches at most two cells per axis): a long diagonal edge (a
        // hierarchy's unsplit leaf on a building-sized wall) visits O(length / cell) cells, not the
        // O((length / cell)³) of its bounding box.
        cells.clear();
        let pieces = ((length / (0.5 * cell)).ceil() as usize).max(1);
        for k in 0..pieces {
            let (p0, p1) = (pa + d * (k as f32 / pieces as f32), pa + d * ((k + 1) as f32 / pieces as f32));
            let (first, last) = (key(p0.min(p1) - Vec3::splat(tolerance)), key(p0.max(p1) + Vec3::splat(tolerance)));
            for x in first[0]..=last[0] {
                for y in first[1]..=last[1] {
                    for z in first[2]..=last[2] {
                        cells.push([x, y, z]);
                    }
                }
            }
        }
        cells.sort_unstable();
        cells.dedup();
        found.clear();
        let class = element_class(e);
        for vertices in cells.iter().filter_map(|&c| grid.get(&(class, c))) {
            for &v in vertices.iter().filter(|&&v| v != a && v != b) {
                let p = positions[v as usize];
                let along = (p - pa).dot(d) / length;
                let off = (p - pa - d * (along / length)).length();
                if off <= tolerance && along > tolerance && along < length - tolerance && wanted(v, e) {
                    found.push((along, v));
                }
            }
        }
        if !found.is_empty() {
            found.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
            inside.push(EdgeInside {
                element: e as u32,
                ends: (a, b),
                inside: found.iter().map(|&(_, v)| v).collect(),
            });
        }
    }
    inside
}

/// Per surface (mesh surface or input triangle), its fit family: the smoothing groups
/// (`surface_group`, per surface: the smallest surface index of its group) joined where a vertex of
/// one surface (`vertex_surface`) lies inside an edge of an element of another (`element_surface`)
/// and their facets may be one smooth surface (`Facet::smooth_with`): the strips of a wall beside a
/// stair, the pieces of a wall round a door. Named by their smallest surface. Only the fits read
/// families. Welding them as groups too (the pieces' shared corners averaged and their T-junctions
/// counted in the vertex means) gave stair_hall the same gain but made l_room 3% worse, at the corners
/// where the pieces round its wall lamp meet the ceiling (docs/accuracy.md, session 38).
pub fn t_junction_families<K>(
    surface_group: &[u32],
    facets: &[Facet<K>],
    t_junctions: &[EdgeInside],
    vertex_surface: &[u32],
    element_surface: &[u32],
) -> Vec<u32> {
    let mut parent: Vec<u32> = surface_group.to_vec();
    for edge in t_junctions {
        let s = element_surface[edge.element as usize];
        for &v in &edge.inside {
            let t = vertex_surface[v as usize];
            if t != s && t != u32::MAX && facets[s as usize].smooth_with(&facets[t as usize]) {
                join(&mut parent, s, t);
            }
        }
    }
    (0..surface_group.len() as u32).map(|s| root(&mut parent, s)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_strip_beside_a_taller_strip_has_its_neighbours_corners_inside_its_edge() {
        // Two unit-wide strips side by side: the left one split at y = 1 and 2, the right one at
        // y = 0.5, 1.5 and 2.5 (vertices 8–9 in the middle of the shared line x = 1).
        let positions = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 3.0, 0.0),
            Vec3::new(0.0, 3.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(2.0, 3.0, 0.0),
            Vec3::new(1.0, 3.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(1.0, 2.0, 0.0),
        ];
        let corners = vec![[0, 1, 2, 3], [4, 5, 6, 7], [0, 8, 9, 3]];
        let inside = vertices_inside_edges(&positions, &corners, |_| 0, |_| 0, |_, e| e < 2);
        // The left strip's right edge (1, 2) holds 8 and 9 (4 and 7 sit on its ends: not inside); the
        // right strip's left edge (7, 4) holds them too, ordered from 7 down.
        let edge = |element: u32, ends: (u32, u32), inside: Vec<u32>| EdgeInside { element, ends, inside };
        assert_eq!(inside, vec![edge(0, (1, 2), vec![8, 9]), edge(1, (7, 4), vec![9, 8])]);
    }
}
