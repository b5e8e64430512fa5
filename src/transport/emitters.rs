//! Choosing points on the emitters: which emitting triangle (a warp tree by emitted power, which keeps
//! stratified points stratified over the triangles) and a uniform point on it. Pass two's shadow rays and the photons both draw from here.

use glam::Vec3;

use crate::mesh::{Mesh, NONE};
use crate::scene::Material;

/// Uniform point on triangle (v₀, v₁, v₂) from two uniform numbers (Turk 1990): with s' = √s,
/// x = (1 − s')·v₀ + s'(1 − r)·v₁ + s'r·v₂ (√s picks the distance from v₀).
pub fn uniform_triangle_point([v0, v1, v2]: [Vec3; 3], s: f32, r: f32) -> Vec3 {
    let su = s.sqrt();
    v0 * (1.0 - su) + v1 * (su * (1.0 - r)) + v2 * (su * r)
}

/// A point chosen on an emitter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmitterSample {
    /// Index into `Mesh::triangles`.
    pub triangle: u32,
    pub point: Vec3,
    /// 1/p_A, the inverse of the area density the point was drawn with (scene units²).
    pub inverse_density: f32,
}

/// A balanced binary tree over weighted entries with positions, for hierarchical sample warping
/// (McCool and Harwood 1997; Clarberg et al. 2005): each inner node splits its entries at the median
/// of their centroids along the axis of largest extent, and keeps the probability of its left half,
/// qₙ = W_left / (W_left + W_right). A 2-D uniform point (u, v) descends from the root: at depth d it
/// rescales coordinate c = d mod 2, going left with c ← c/qₙ when c < qₙ, right with
/// c ← (c − qₙ)/(1 − qₙ) otherwise. So entry i is reached with P(i) = Π qₙ along its path
/// = wᵢ / Σⱼ wⱼ, the leftover (u, v) is uniform, and, unlike a 1-D table, neighbouring regions of the
/// unit square land on neighbouring entries: a stratified pattern over (u, v) stays stratified over
/// the entries' union (the triangles of one meshed lamp are sampled like the lamp itself). O(log n)
/// per point; depth ⌈log₂ n⌉.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct WarpTree {
    nodes: Vec<WarpNode>,
    /// pᵢ = wᵢ / Σ w, as the product of the branch probabilities on entry i's path.
    probability: Vec<f64>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum WarpNode {
    Leaf(u32),
    Split { left_probability: f64, left: u32, right: u32 },
}

impl WarpTree {
    /// The tree for weights `weights` (non-negative, finite, with a positive sum) at points
    /// `centroids` (same length); `None` otherwise or when empty. Entries of zero weight are never
    /// drawn.
    pub fn new(weights: &[f64], centroids: &[Vec3]) -> Option<WarpTree> {
        let total: f64 = weights.iter().sum();
        let valid = weights.iter().all(|w| w.is_finite() && *w >= 0.0) && centroids.len() == weights.len();
        if weights.is_empty() || !valid || !(total.is_finite() && total > 0.0) {
            return None;
        }
        let mut tree = WarpTree { nodes: Vec::new(), probability: vec![0.0; weights.len()] };
        let mut entries: Vec<u32> = (0..weights.len() as u32).collect();
        tree.build(&mut entries, weights, centroids, 1.0);
        Some(tree)
    }

    /// Appends the subtree over `entries` (reached with probability `reach`) and returns its index.
    fn build(&mut self, entries: &mut [u32], weights: &[f64], centroids: &[Vec3], reach: f64) -> u32 {
        let index = self.nodes.len() as u32;
        if let [only] = entries {
            self.probability[*only as usize] = reach;
            self.nodes.push(WarpNode::Leaf(*only));
            return index;
        }
        let (lo, hi) = entries.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &i| {
            (lo.min(centroids[i as usize]), hi.max(centroids[i as usize]))
        });
        let axis = (hi - lo).max_position();
        let mid = entries.len() / 2;
        entries.select_nth_unstable_by(mid, |&a, &b| {
            centroids[a as usize][axis].total_cmp(&centroids[b as usize][axis]).then(a.cmp(&b))
        });
        let (left, right) = entries.split_at_mut(mid);
        let weight = |side: &[u32]| side.iter().map(|&i| weights[i as usize]).sum::<f64>();
        let (w_left, w_right) = (weight(left), weight(right));
        // A side of zero weight is never entered (q is 0 or 1 exactly).
        let left_probability = if w_left + w_right > 0.0 { w_left / (w_left + w_right) } else { 0.5 };
        self.nodes.push(WarpNode::Split { left_probability, left: 0, right: 0 });
        let l = self.build(left, weights, centroids, reach * left_probability);
        let r = self.build(right, weights, centroids, reach * (1.0 - left_probability));
        self.nodes[index as usize] = WarpNode::Split { left_probability, left: l, right: r };
        index
    }

    pub fn len(&self) -> usize {
        self.probability.len()
    }

    pub fn is_empty(&self) -> bool {
        self.probability.is_empty()
    }

    /// pᵢ, the probability of entry i.
    pub fn probability(&self, i: usize) -> f64 {
        self.probability[i]
    }

    /// The entry for (u, v) ∈ [0, 1)² and the point's leftover, rescaled to a fresh uniform point in
    /// [0, 1)² (see the type's documentation).
    pub fn select(&self, [u, v]: [f32; 2]) -> (usize, [f32; 2]) {
        let mut c = [u.clamp(0.0, 1.0) as f64, v.clamp(0.0, 1.0) as f64];
        let mut node = 0usize;
        let mut depth = 0usize;
        loop {
            match self.nodes[node] {
                WarpNode::Leaf(i) => {
                    let unit = |x: f64| (x.clamp(0.0, 1.0) as f32).min(ONE_BELOW);
                    return (i as usize, [unit(c[0]), unit(c[1])]);
                }
                WarpNode::Split { left_probability: q, left, right } => {
                    let x = &mut c[depth % 2];
                    if *x < q {
                        *x /= q;
                        node = left as usize;
                    } else {
                        *x = (*x - q) / (1.0 - q);
                        node = right as usize;
                    }
                    depth += 1;
                }
            }
        }
    }
}

const ONE_BELOW: f32 = 1.0 - f32::EPSILON / 2.0;

/// The triangles of emitting elements (by their front side's material), for direct light: a triangle
/// is chosen in proportion to its emitted power by warping a 2-D point down a `WarpTree` over the
/// triangles' centroids (O(log n) per sample), then the point's leftover places it uniformly on the
/// triangle, so stratified points stay stratified over the emitters however finely they are meshed.
#[derive(Clone, Debug, Default)]
pub struct Emitters {
    /// Mesh triangle of each entry, increasing.
    triangle: Vec<u32>,
    /// Aₜ/pₜ of each entry: the inverse area density of points drawn on it (scene units²).
    inverse_density: Vec<f32>,
    table: WarpTree,
    total_area: f32,
}

/// Power weight of an emitting triangle: Φ = A·(Ē_front + Ē_back), Ē the mean over the colour channels
/// of the exitance E = πL each side emits (the back counts only on a two-sided surface).
pub fn emitter_power(area: f64, front_emission: Vec3, back_emission: Option<Vec3>) -> f64 {
    let mean = |e: Vec3| (e.max(Vec3::ZERO).element_sum() / 3.0) as f64;
    area * (mean(front_emission) + back_emission.map_or(0.0, mean))
}

impl Emitters {
    /// The emitting triangles of `mesh` of positive area and power; `materials` must cover
    /// `Elements::material`.
    pub fn new(mesh: &Mesh, materials: &[Material]) -> Emitters {
        let e = &mesh.elements;
        let mut triangle = Vec::new();
        let mut area = Vec::new();
        let mut power = Vec::new();
        let mut centroid = Vec::new();
        for (t, tri) in mesh.triangles.iter().enumerate() {
            let front = mesh.triangle_element[t] as usize;
            if !materials[e.material[front] as usize].is_emitter() {
                continue;
            }
            let p = tri.map(|v| mesh.positions[v as usize]);
            let a = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length() as f64;
            let back = mesh.side_element(t, false).map(|b| e.emission[b]);
            let phi = emitter_power(a, e.emission[front], back);
            if a > 0.0 && phi > 0.0 {
                triangle.push(t as u32);
                area.push(a);
                power.push(phi);
                centroid.push((p[0] + p[1] + p[2]) / 3.0);
            }
        }
        let Some(table) = WarpTree::new(&power, &centroid) else {
            return Emitters::default();
        };
        let inverse_density = area.iter().enumerate().map(|(i, a)| (a / table.probability(i)) as f32).collect();
        Emitters { triangle, inverse_density, table, total_area: area.iter().sum::<f64>() as f32 }
    }

    pub fn is_empty(&self) -> bool {
        self.triangle.is_empty()
    }

    /// Number of emitting triangles.
    pub fn len(&self) -> usize {
        self.triangle.len()
    }

    /// Total area A of the emitting triangles (scene units²).
    pub fn total_area(&self) -> f32 {
        self.total_area
    }

    /// p_A(x) = pₜ/Aₜ, the area density with which `sample` draws a point on mesh triangle `t`
    /// (0 for a triangle that is not an emitter here). O(log n); for the MIS weights of rays that hit
    /// an emitter by chance.
    pub fn area_density(&self, t: u32) -> f32 {
        match self.triangle.binary_search(&t) {
            Ok(i) => 1.0 / self.inverse_density[i],
            Err(_) => 0.0,
        }
    }

    /// The point for uniform numbers (ξ, r): the `WarpTree` selects the triangle in proportion to its
    /// power and hands on (ξ, r) rescaled, which place the point on it (`uniform_triangle_point`).
    /// `None` without emitters.
    pub fn sample(&self, mesh: &Mesh, xi: f32, r: f32) -> Option<EmitterSample> {
        if self.triangle.is_empty() {
            return None;
        }
        let (i, [s, r]) = self.table.select([xi, r]);
        let t = self.triangle[i];
        let corners = mesh.triangles[t as usize].map(|v| mesh.positions[v as usize]);
        Some(EmitterSample {
            triangle: t,
            point: uniform_triangle_point(corners, s, r),
            inverse_density: self.inverse_density[i],
        })
    }
}

/// The triangles that emit on either side, which photons leave from, with cumulative areas in f64.
#[derive(Clone, Debug)]
pub struct PhotonSources {
    triangle: Vec<u32>,
    cumulative_area: Vec<f64>,
}

impl PhotonSources {
    /// `None` when no triangle of positive area emits.
    pub fn new(mesh: &Mesh) -> Option<PhotonSources> {
        let e = &mesh.elements;
        let triangle: Vec<u32> = (0..mesh.triangles.len() as u32)
            .filter(|&t| {
                let front = mesh.triangle_element[t as usize] as usize;
                let back = mesh.triangle_back_element[t as usize];
                e.emission[front].max_element() > 0.0 || (back != NONE && e.emission[back as usize].max_element() > 0.0)
            })
            .collect();
        let mut cumulative_area = Vec::with_capacity(triangle.len());
        let mut sum = 0.0f64;
        for &t in &triangle {
            let [a, b, c] = mesh.triangles[t as usize].map(|v| mesh.positions[v as usize]);
            sum += 0.5 * (b - a).cross(c - a).length() as f64;
            cumulative_area.push(sum);
        }
        (sum > 0.0).then_some(PhotonSources { triangle, cumulative_area })
    }

    /// Total emitting area A (scene units²).
    pub fn total_area(&self) -> f64 {
        self.cumulative_area.last().copied().unwrap_or(0.0)
    }

    /// The point for uniform numbers: `xi` ∈ [0, 1) selects the triangle by area, (s, r) place the
    /// point on it (`uniform_triangle_point`).
    pub fn sample(&self, mesh: &Mesh, xi: f64, s: f32, r: f32) -> EmitterSample {
        let total = self.total_area();
        let x = xi * total;
        let k = self.cumulative_area.partition_point(|&c| c <= x).min(self.cumulative_area.len() - 1);
        let t = self.triangle[k];
        let corners = mesh.triangles[t as usize].map(|v| mesh.positions[v as usize]);
        EmitterSample { triangle: t, point: uniform_triangle_point(corners, s, r), inverse_density: total as f32 }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Entries on a line, at x = i (the tree's splits follow them).
    fn on_a_line(n: usize) -> Vec<Vec3> {
        (0..n).map(|i| Vec3::new(i as f32, 0.5 * (i % 3) as f32, 0.0)).collect()
    }

    /// Frequencies of each entry over the m × m midpoint grid of the unit square. Every entry owns one
    /// axis-aligned rectangle of the square (each split cuts one coordinate's interval in two), and a
    /// rectangle's count differs from m² × its area by at most the cells its border crosses, 2m + 2.
    fn frequencies(tree: &WarpTree, m: usize) -> Vec<f64> {
        let mut count = vec![0usize; tree.len()];
        for i in 0..m {
            for j in 0..m {
                let uv = [(i as f64 + 0.5) / m as f64, (j as f64 + 0.5) / m as f64].map(|x| x as f32);
                count[tree.select(uv).0] += 1;
            }
        }
        count.iter().map(|&c| c as f64 / (m * m) as f64).collect()
    }

    proptest! {
        #[test]
        fn warp_tree_picks_each_entry_with_probability_power_over_total(
            weights in prop::collection::vec(0.0f64..100.0, 1..40),
        ) {
            prop_assume!(weights.iter().sum::<f64>() > 1e-3);
            let tree = WarpTree::new(&weights, &on_a_line(weights.len())).unwrap();
            let total: f64 = weights.iter().sum();
            let m = 1024;
            let f = frequencies(&tree, m);
            let bound = (2 * m + 2) as f64 / (m * m) as f64;
            for (j, w) in weights.iter().enumerate() {
                prop_assert!((tree.probability(j) - w / total).abs() < 1e-12);
                prop_assert!((f[j] - w / total).abs() <= bound, "entry {}: {} vs {}", j, f[j], w / total);
            }
        }

        #[test]
        fn warp_leftover_stays_in_the_unit_square(weights in prop::collection::vec(0.1f64..10.0, 1..8)) {
            let tree = WarpTree::new(&weights, &on_a_line(weights.len())).unwrap();
            for k in 0..1000 {
                let (_, rest) = tree.select([k as f32 / 1000.0, (k * 7 % 1000) as f32 / 1000.0]);
                prop_assert!(rest.iter().all(|x| (0.0..1.0).contains(x)));
            }
        }
    }

    #[test]
    fn warp_tree_refuses_empty_negative_and_zero_weights() {
        assert!(WarpTree::new(&[], &[]).is_none());
        assert!(WarpTree::new(&[0.0, 0.0], &on_a_line(2)).is_none());
        assert!(WarpTree::new(&[1.0, -1.0], &on_a_line(2)).is_none());
        assert!(WarpTree::new(&[1.0, f64::NAN], &on_a_line(2)).is_none());
        assert!(WarpTree::new(&[1.0, 1.0], &on_a_line(1)).is_none());
    }

    #[test]
    fn warp_leftover_of_one_entry_is_the_point_itself() {
        let tree = WarpTree::new(&[3.0], &on_a_line(1)).unwrap();
        for uv in [[0.0, 0.5], [0.25, 0.125], [0.7, 0.0]] {
            assert_eq!(tree.select(uv), (0, uv));
        }
    }

    /// Equal entries on a 4 × 4 grid: the 16 cells of the unit square's 4 × 4 grid land on 16
    /// different entries (two splits per coordinate), so one stratified point per cell is one point
    /// per entry.
    #[test]
    fn warp_tree_maps_strata_of_the_square_onto_distinct_entries() {
        let centroids: Vec<Vec3> = (0..16).map(|i| Vec3::new((i % 4) as f32, (i / 4) as f32, 0.0)).collect();
        let tree = WarpTree::new(&[1.0; 16], &centroids).unwrap();
        let mut hit = [false; 16];
        for i in 0..4 {
            for j in 0..4 {
                let (entry, _) = tree.select([(i as f32 + 0.5) / 4.0, (j as f32 + 0.5) / 4.0]);
                assert!(!std::mem::replace(&mut hit[entry], true), "cell ({i}, {j}) repeats entry {entry}");
            }
        }
    }
}
