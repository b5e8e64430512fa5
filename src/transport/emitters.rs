//! Choosing points on the emitters: which emitting polygon (a warp tree by emitted power, which keeps
//! stratified points stratified over the polygons), a point on it (uniform by area, or uniform in
//! solid angle from a receiver close to it), and the triangle under it. Pass two's shadow rays, pass
//! one's sampled direct part and the photons all draw from here.

use glam::{DVec3, Vec3};

use super::emitter_polygon::EmitterPolygon;
use super::solid_angle;
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

/// The triangles of emitting elements (by their front side's material), for direct light, gathered
/// into emitting polygons: the triangles one scene surface was cut into, when they tile a convex
/// planar polygon (`EmitterPolygon`), else each triangle alone. A polygon is chosen in proportion to
/// its emitted power by warping a 2-D point down a `WarpTree` over the polygons' centroids
/// (O(log n) per sample); the point's leftover places it uniformly on the polygon by one continuous
/// map, and only then is the mesh triangle under it looked up. So a stratified pattern stays stratified
/// over a lamp however finely it is meshed (a lamp cut into 50 triangles is sampled exactly as the same
/// lamp in 2). Within a polygon the density is uniform by area, p_A = P_polygon/A_polygon, except
/// that `sample_from` a receiver point close to the polygon (within `NEAR_RADII` of its bounding
/// radius) draws the point uniformly in the solid angle the polygon subtends there.
#[derive(Clone, Debug, Default)]
pub struct Emitters {
    /// Mesh triangle of each entry, increasing.
    triangle: Vec<u32>,
    /// Polygon of each entry.
    polygon_of: Vec<u32>,
    polygons: Vec<Polygon>,
    table: WarpTree,
    total_area: f32,
}

#[derive(Clone, Debug)]
struct Polygon {
    /// Its entries (indices into `Emitters::triangle`), in the order `shape` knows its triangles.
    entries: Vec<u32>,
    /// The tiled polygon, or `None` for a single triangle sampled by itself.
    shape: Option<EmitterPolygon>,
    /// A/P, the inverse area density of points drawn on it (scene units²).
    inverse_density: f32,
    /// P, the probability the `WarpTree` selects it with.
    probability: f64,
    /// Its outline (the convex hull, or the lone triangle), in order around it, for sampling by
    /// solid angle over the fan (c₀, cₖ₊₁, cₖ₊₂).
    outline: Vec<DVec3>,
    /// Unit normal of its plane (either orientation).
    normal: DVec3,
    /// Centre and radius of a sphere around it (scene units): receivers inside `NEAR_RADII` radii
    /// sample it by solid angle.
    centre: Vec3,
    radius: f32,
}

/// A receiver point closer than this many bounding radii R to an emitting polygon's centre samples
/// it uniformly in solid angle (`Emitters::sample_from`), where sampling by area would weigh the few
/// points drawn near the receiver by cos θ cos θ'/r². A square lamp, 8 shadow rays, 4,000 pixels,
/// relative standard deviation by area → by solid angle: a receiver beside it facing it 0.22 → 0.021
/// at 1.2 R, 0.039 → 0.0041 at 2.2 R, 0.015 → 0.0010 at 3.9 R; one below it 0.023 → 0.012 at 1.2 R,
/// 0.0024 → 0.0016 at 3.9 R (docs/accuracy.md, session 31). The singular case is a receiver within
/// about one radius (touching the lamp); beyond 2 R, 1/r² varies over the polygon by less than 9×
/// and the area sample's variance is bounded. At 4 R the solid-angle sample cost cornell_box's
/// whole default render +9% CPU-s and the six rooms +0–9% for no change in their relMSE (±1%); at
/// 2 R the rooms' pixels are those of the area sample, and the furnace and a lamp against a wall
/// keep the gain.
pub const NEAR_RADII: f32 = 2.0;

/// How a polygon is sampled from a receiver point.
enum Strategy {
    /// Uniformly by area.
    Area,
    /// Uniformly in solid angle: Ω = Σ Ωₖ over the fan triangles (steradians).
    SolidAngle { total_sr: f64 },
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
            }
        }
        let corners = |i: usize| mesh.triangles[triangle[i] as usize].map(|v| mesh.positions[v as usize]);
        // Entries of one mesh surface are contiguous (the mesher emits a surface's triangles together).
        let mut polygons = Vec::new();
        let mut weights = Vec::new();
        let mut centroids = Vec::new();
        let mut start = 0;
        while start < triangle.len() {
            let surface = |i: usize| e.surface[mesh.triangle_element[triangle[i] as usize] as usize];
            let end = (start..triangle.len()).find(|&i| surface(i) != surface(start)).unwrap_or(triangle.len());
            let tris: Vec<[Vec3; 3]> = (start..end).map(corners).collect();
            let normal = e.normal[mesh.triangle_element[triangle[start] as usize] as usize];
            let groups: Vec<(Vec<u32>, Option<EmitterPolygon>)> = match EmitterPolygon::new(&tris, normal) {
                Some(shape) if end - start > 1 => vec![((start as u32..end as u32).collect(), Some(shape))],
                _ => (start as u32..end as u32).map(|i| (vec![i], None)).collect(),
            };
            for (entries, shape) in groups {
                let a: f64 = entries.iter().map(|&i| area[i as usize]).sum();
                weights.push(entries.iter().map(|&i| power[i as usize]).sum::<f64>());
                let c =
                    entries.iter().map(|&i| corners(i as usize).iter().sum::<Vec3>() / 3.0 * area[i as usize] as f32);
                centroids.push(c.sum::<Vec3>() / a as f32);
                let outline: Vec<Vec3> = match &shape {
                    Some(shape) => shape.corners().to_vec(),
                    None => corners(entries[0] as usize).to_vec(),
                };
                let centre = outline.iter().sum::<Vec3>() / outline.len() as f32;
                let radius = outline.iter().map(|&c| c.distance(centre)).fold(0.0, f32::max);
                let outline: Vec<DVec3> = outline.iter().map(|c| c.as_dvec3()).collect();
                let normal = (outline[1] - outline[0]).cross(outline[2] - outline[0]).normalize_or_zero();
                polygons.push(Polygon {
                    entries,
                    shape,
                    inverse_density: a as f32,
                    probability: 0.0,
                    outline,
                    normal,
                    centre,
                    radius,
                });
            }
            start = end;
        }
        let Some(table) = WarpTree::new(&weights, &centroids) else {
            return Emitters::default();
        };
        let mut polygon_of = vec![0u32; triangle.len()];
        for (k, polygon) in polygons.iter_mut().enumerate() {
            polygon.probability = table.probability(k);
            polygon.inverse_density = (polygon.inverse_density as f64 / polygon.probability) as f32;
            for &i in &polygon.entries {
                polygon_of[i as usize] = k as u32;
            }
        }
        Emitters { triangle, polygon_of, polygons, table, total_area: area.iter().sum::<f64>() as f32 }
    }

    pub fn is_empty(&self) -> bool {
        self.triangle.is_empty()
    }

    /// Number of emitting triangles.
    pub fn len(&self) -> usize {
        self.triangle.len()
    }

    /// Number of emitting polygons (sets of triangles sampled as one surface, or single triangles).
    pub fn polygon_count(&self) -> usize {
        self.polygons.len()
    }

    /// Total area A of the emitting triangles (scene units²).
    pub fn total_area(&self) -> f32 {
        self.total_area
    }

    /// The area density p_A(y) with which `sample_from(x, …)` draws point `y` of mesh triangle `t` (0
    /// for a triangle that is not an emitter here): P/A where the polygon is sampled by area from x,
    /// else P·cos θ'/(Ω r²), the solid-angle density P/Ω carried to the area at y
    /// (r = |y − x|, θ' between the polygon's normal and y − x). For the MIS weights of rays from x
    /// that hit an emitter by chance.
    pub fn area_density_from(&self, t: u32, x: Vec3, y: Vec3) -> f32 {
        let Ok(i) = self.triangle.binary_search(&t) else {
            return 0.0;
        };
        let polygon = &self.polygons[self.polygon_of[i] as usize];
        match polygon.strategy(x) {
            Strategy::Area => 1.0 / polygon.inverse_density,
            Strategy::SolidAngle { total_sr, .. } => {
                let to = (y - x).as_dvec3();
                let r2 = to.length_squared();
                let cos_light = polygon.normal.dot(to).abs() / r2.sqrt();
                (polygon.probability * cos_light / (total_sr * r2)) as f32
            }
        }
    }

    /// The point for uniform numbers (ξ, r) as seen from receiver point `x`: the `WarpTree` selects
    /// the polygon in proportion to its power and hands on (ξ, r) rescaled, which place the point on
    /// it: uniformly in the solid angle it subtends from x when x is within `NEAR_RADII` of it (the
    /// fan triangle by its solid angle Ωₖ, then Arvo's map, `solid_angle::sample_towards`), else
    /// uniformly by area (`on_polygon`); the triangle is the one under the point. `inverse_density` is then
    /// 1/p_A = Ω r²/(P cos θ'), so that the caller's cos θ cos θ'/r² · 1/p_A = cos θ · Ω/P is bounded
    /// however close the polygon. `None` without emitters.
    pub fn sample_from(&self, mesh: &Mesh, x: Vec3, xi: f32, r: f32) -> Option<EmitterSample> {
        if self.triangle.is_empty() {
            return None;
        }
        let (k, rest) = self.table.select([xi, r]);
        let polygon = &self.polygons[k];
        let Strategy::SolidAngle { total_sr } = polygon.strategy(x) else {
            return Some(self.on_polygon(mesh, k, rest));
        };
        // The fan triangle whose share of Ω holds ξ'·Ω, and ξ' rescaled within it.
        let (xd, o) = (x.as_dvec3(), &polygon.outline);
        let target = rest[0] as f64 * total_sr;
        let last = o.len() - 3;
        let (mut below, mut fan, mut omega) = (0.0, 0, 0.0);
        for j in 0..=last {
            (fan, omega) = (j, polygon.fan_sr(xd, j));
            if target < below + omega || j == last {
                break;
            }
            below += omega;
        }
        let u = ((target - below) / omega).clamp(0.0, 1.0 - f64::EPSILON);
        let towards = solid_angle::sample_towards(xd, &[o[0], o[fan + 1], o[fan + 2]], [u, rest[1] as f64]);
        let Some(towards) = towards else {
            return Some(self.on_polygon(mesh, k, rest));
        };
        let point = towards.point.as_vec3();
        let r2 = (towards.point - xd).length_squared();
        let cos_light = polygon.normal.dot(towards.direction).abs();
        let inverse_density =
            if cos_light > 1e-9 { (total_sr * r2 / (polygon.probability * cos_light)) as f32 } else { 0.0 };
        let entry = match &polygon.shape {
            Some(shape) => polygon.entries[shape.triangle_at(point)],
            None => polygon.entries[0],
        };
        Some(EmitterSample { triangle: self.triangle[entry as usize], point, inverse_density })
    }

    /// The point uniform by area on polygon `k` for the warp's leftover `rest` (`EmitterPolygon::point`, or
    /// `uniform_triangle_point` for a lone triangle).
    fn on_polygon(&self, mesh: &Mesh, k: usize, rest: [f32; 2]) -> EmitterSample {
        let polygon = &self.polygons[k];
        let (entry, point) = match &polygon.shape {
            Some(shape) => {
                let point = shape.point(rest);
                (polygon.entries[shape.triangle_at(point)], point)
            }
            None => {
                let entry = polygon.entries[0];
                let corners =
                    mesh.triangles[self.triangle[entry as usize] as usize].map(|v| mesh.positions[v as usize]);
                (entry, uniform_triangle_point(corners, rest[0], rest[1]))
            }
        };
        EmitterSample { triangle: self.triangle[entry as usize], point, inverse_density: polygon.inverse_density }
    }
}

impl Polygon {
    /// Ωₖ, the solid angle of fan triangle (c₀, cₖ₊₁, cₖ₊₂) from `x` (steradians).
    fn fan_sr(&self, x: DVec3, k: usize) -> f64 {
        let o = &self.outline;
        solid_angle::solid_angle_sr(x, &[o[0], o[k + 1], o[k + 2]])
    }

    /// How it is sampled from receiver point `x`: by solid angle within `NEAR_RADII` radii when every
    /// fan triangle subtends at least `solid_angle::MIN_SOLID_ANGLE_SR` (else, and for x on its
    /// plane, by area: a speck is seen alike from all its points).
    fn strategy(&self, x: Vec3) -> Strategy {
        if x.distance(self.centre) >= NEAR_RADII * self.radius {
            return Strategy::Area;
        }
        let xd = x.as_dvec3();
        let mut total_sr = 0.0;
        for k in 0..self.outline.len() - 2 {
            let omega = self.fan_sr(xd, k);
            if !(omega >= solid_angle::MIN_SOLID_ANGLE_SR) {
                return Strategy::Area;
            }
            total_sr += omega;
        }
        Strategy::SolidAngle { total_sr }
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
