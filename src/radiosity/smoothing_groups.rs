//! Smoothing groups: the pieces of one smooth surface that a tessellation cut into flat facets. Two
//! facets belong to one group when they share an edge, have the same material and side, and their
//! normals differ by less than acos(`SMOOTHING_COS`) ≈ 25.8° (the group is the transitive closure of
//! that relation). A sphere's or a statue's facets form one group, so vertex values are shared and
//! blend across their edges; a box's faces (90° creases), a material change or the two sides of a
//! two-sided surface part groups, so each keeps its own values. Every element mesh's vertex step uses
//! them: the hierarchy's leaf mesh (`hierarchy::interpolate`) over its input triangles, the uniform
//! and adaptive meshes (`smooth_mesh::SmoothMesh`) over their elements.

use std::hash::Hash;

use glam::Vec3;
use rustc_hash::FxHashMap;

/// Normals of facets in one smoothing group differ by less than acos(0.9) ≈ 25.8°.
pub const SMOOTHING_COS: f32 = 0.9;

/// One flat facet as the grouping sees it: its corners as position keys (`K`: equal keys are the same
/// point), its unit normal, its material and its side.
#[derive(Clone, Copy, Debug)]
pub struct Facet<K> {
    /// The first `corner_count` entries are the corners in order around the facet.
    pub corners: [K; 4],
    pub corner_count: usize,
    pub normal: Vec3,
    pub material: u32,
    /// The reversed back copy of a two-sided surface.
    pub back: bool,
}

impl<K> Facet<K> {
    /// Facets `self` and `other`, which share an edge, may be one smooth surface: same material, same
    /// side, n₁·n₂ > `SMOOTHING_COS`.
    pub fn smooth_with(&self, other: &Facet<K>) -> bool {
        self.material == other.material && self.back == other.back && self.normal.dot(other.normal) > SMOOTHING_COS
    }
}

/// Union-find root with path halving.
pub fn root(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        let up = parent[parent[i as usize] as usize];
        parent[i as usize] = up;
        i = up;
    }
    i
}

/// Union-find: joins the sets of `a` and `b`, the smaller root becoming the set's name.
pub fn join(parent: &mut [u32], a: u32, b: u32) {
    let (ra, rb) = (root(parent, a), root(parent, b));
    if ra != rb {
        parent[ra.max(rb) as usize] = ra.min(rb);
    }
}

/// The smoothing group of each of `count` facets (`facet(i)`): the smallest facet index in its group.
/// An edge joins the first facet seen on it with every later one it is smooth with
/// (`Facet::smooth_with`).
pub fn smoothing_groups<K: Copy + Ord + Hash>(count: usize, facet: impl Fn(usize) -> Facet<K>) -> Vec<u32> {
    let mut parent: Vec<u32> = (0..count as u32).collect();
    let mut first_on_edge: FxHashMap<(K, K), u32> = FxHashMap::default();
    for i in 0..count {
        let f = facet(i);
        for e in 0..f.corner_count {
            let (a, b) = (f.corners[e], f.corners[(e + 1) % f.corner_count]);
            let edge = if a <= b { (a, b) } else { (b, a) };
            match first_on_edge.get(&edge) {
                None => {
                    first_on_edge.insert(edge, i as u32);
                }
                Some(&j) => {
                    if j as usize != i && f.smooth_with(&facet(j as usize)) {
                        join(&mut parent, i as u32, j);
                    }
                }
            }
        }
    }
    (0..count as u32).map(|i| root(&mut parent, i)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri(corners: [u32; 3], normal: Vec3, material: u32) -> Facet<u32> {
        Facet {
            corners: [corners[0], corners[1], corners[2], u32::MAX],
            corner_count: 3,
            normal,
            material,
            back: false,
        }
    }

    /// Unit normal of a facet tilted by `deg` about the x axis from +y.
    fn tilted(deg: f32) -> Vec3 {
        let r = deg.to_radians();
        Vec3::new(0.0, r.cos(), r.sin())
    }

    #[test]
    fn facets_of_a_gentle_curve_form_one_group() {
        // A strip of four triangles bending by 10° at every shared edge: 30° end to end, more than
        // the threshold, but each edge is smooth, so the closure is one group.
        let facets = [
            tri([0, 1, 2], tilted(0.0), 0),
            tri([1, 2, 3], tilted(10.0), 0),
            tri([2, 3, 4], tilted(20.0), 0),
            tri([3, 4, 5], tilted(30.0), 0),
        ];
        assert_eq!(smoothing_groups(facets.len(), |i| facets[i]), vec![0, 0, 0, 0]);
    }

    #[test]
    fn a_right_angle_crease_parts_groups() {
        let facets = [tri([0, 1, 2], tilted(0.0), 0), tri([1, 2, 3], tilted(90.0), 0)];
        assert_eq!(smoothing_groups(facets.len(), |i| facets[i]), vec![0, 1]);
        // 26° is just past acos(0.9) ≈ 25.8°; 25° is just inside.
        let facets = [tri([0, 1, 2], tilted(0.0), 0), tri([1, 2, 3], tilted(26.0), 0)];
        assert_eq!(smoothing_groups(facets.len(), |i| facets[i]), vec![0, 1]);
        let facets = [tri([0, 1, 2], tilted(0.0), 0), tri([1, 2, 3], tilted(25.0), 0)];
        assert_eq!(smoothing_groups(facets.len(), |i| facets[i]), vec![0, 0]);
    }

    #[test]
    fn a_material_change_or_the_other_side_parts_groups() {
        let facets = [tri([0, 1, 2], tilted(0.0), 0), tri([1, 2, 3], tilted(5.0), 1)];
        assert_eq!(smoothing_groups(facets.len(), |i| facets[i]), vec![0, 1]);
        let mut back = tri([1, 2, 3], tilted(5.0), 0);
        back.back = true;
        let facets = [tri([0, 1, 2], tilted(0.0), 0), back];
        assert_eq!(smoothing_groups(facets.len(), |i| facets[i]), vec![0, 1]);
    }

    #[test]
    fn facets_meeting_at_a_corner_only_stay_apart() {
        // Sharing one vertex is not sharing an edge.
        let facets = [tri([0, 1, 2], tilted(0.0), 0), tri([2, 3, 4], tilted(0.0), 0)];
        assert_eq!(smoothing_groups(facets.len(), |i| facets[i]), vec![0, 1]);
    }
}
