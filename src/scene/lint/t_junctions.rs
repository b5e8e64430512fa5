//! T-junctions: a corner of one face lying inside an edge of another, which cracks interpolated
//! radiosity along that edge.

use super::weld::edge_key;
use super::{to_f32, Poly, SurfaceRef, TJunction};
use crate::scene::Surface;
use glam::DVec3;

/// T-junctions of `vertices` on the edges of `polygon`: `(vertex index, vertex, edge index)` for each
/// vertex closer than `tolerance` to edge k (from corner k to corner k+1) whose foot lies strictly
/// inside the edge and which is farther than `tolerance` from both of the edge's endpoints.
pub fn between(vertices: &[DVec3], polygon: &[DVec3], tolerance: f64) -> Vec<(usize, DVec3, usize)> {
    let mut found = Vec::new();
    for (v, &x) in vertices.iter().enumerate() {
        for k in 0..polygon.len() {
            let (p, q) = (polygon[k], polygon[(k + 1) % polygon.len()]);
            let d = q - p;
            let len2 = d.length_squared();
            if !(len2 > 0.0) {
                continue;
            }
            let t = (x - p).dot(d) / len2;
            if !(t > 0.0 && t < 1.0) {
                continue;
            }
            if (x - (p + d * t)).length() < tolerance && (x - p).length() > tolerance && (x - q).length() > tolerance {
                found.push((v, x, k));
            }
        }
    }
    found
}

/// A T-junction found between one pair of faces, with the welded corner and edge it stands for (the
/// same corner on the same geometric edge is found again from every face sharing either).
pub(super) struct Candidate {
    finding: TJunction,
    vertex: u32,
    edge: (u32, u32),
}

/// Gathers the T-junctions of every candidate pair, then reports each (corner, edge) once.
pub(super) struct Collector<'a> {
    surfaces: &'a [Surface],
    vertex_ids: &'a [Vec<u32>],
    tolerance: f64,
    found: Vec<Candidate>,
}

impl<'a> Collector<'a> {
    pub(super) fn new(surfaces: &'a [Surface], vertex_ids: &'a [Vec<u32>], tolerance: f64) -> Self {
        Collector { surfaces, vertex_ids, tolerance, found: Vec::new() }
    }

    /// The corners of face `i` inside edges of face `j`, then the other way round. Reads only, so
    /// pairs can be examined in parallel and their candidates [`extend`](Self::extend)ed in order.
    pub(super) fn pair(&self, (i, pi): (usize, &Poly), (j, pj): (usize, &Poly)) -> Vec<Candidate> {
        let mut found = Vec::new();
        self.one_way((i, pi), (j, pj), &mut found);
        self.one_way((j, pj), (i, pi), &mut found);
        found
    }

    /// Adds the candidates of one pair.
    pub(super) fn extend(&mut self, candidates: Vec<Candidate>) {
        self.found.extend(candidates);
    }

    fn one_way(&self, (v_surface, vp): (usize, &Poly), (e_surface, ep): (usize, &Poly), found: &mut Vec<Candidate>) {
        let ids = self.vertex_ids;
        for (v, point, edge) in between(&vp.vertices, &ep.vertices, self.tolerance) {
            let n = ep.vertices.len();
            found.push(Candidate {
                finding: TJunction {
                    edge_surface: SurfaceRef::of(self.surfaces, e_surface),
                    vertex_surface: SurfaceRef::of(self.surfaces, v_surface),
                    point: to_f32(point),
                },
                vertex: ids[v_surface][v],
                edge: edge_key(ids[e_surface][edge], ids[e_surface][(edge + 1) % n]),
            });
        }
    }

    /// One T-junction per (vertex position, geometric edge): an edge shared by two faces counts once.
    /// Ordered by edge surface, then vertex surface, then corner.
    pub(super) fn finish(mut self) -> Vec<TJunction> {
        let surfaces = |c: &Candidate| (c.finding.edge_surface.index, c.finding.vertex_surface.index);
        self.found.sort_by_key(|c| (c.vertex, c.edge, surfaces(c)));
        self.found.dedup_by(|x, y| x.vertex == y.vertex && x.edge == y.edge);
        self.found.sort_by_key(|c| (surfaces(c), c.vertex));
        self.found.into_iter().map(|c| c.finding).collect()
    }
}
