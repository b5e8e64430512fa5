//! Choosing points on the emitters: which emitting triangle (an alias table by emitted power) and a
//! uniform point on it. Pass two's shadow rays and the photons both draw from here.

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

/// Walker's alias table built by Vose's method (Walker 1977; Vose 1991): n entries with
/// probabilities pᵢ = wᵢ / Σⱼ wⱼ, one of which is drawn in O(1) from one uniform number, whatever n.
///
/// Construction: scale qᵢ = n·pᵢ; while some qₛ < 1 and some q_l ≥ 1, cell s keeps qₛ and takes l as
/// its alias, and q_l ← q_l − (1 − qₛ); cells left over keep probability 1. Selection from u ∈ [0, 1):
/// x = n·u, cell i = ⌊x⌋, f = x − i; entry i if f < qᵢ, else alias(i). Then
/// P(entry j) = (qⱼ + Σ_{i: alias(i) = j} (1 − qᵢ))/n = pⱼ.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AliasTable {
    /// qᵢ, the chance that cell i keeps its own entry.
    keep: Vec<f64>,
    alias: Vec<u32>,
    /// pᵢ = wᵢ / Σ w.
    probability: Vec<f64>,
}

impl AliasTable {
    /// The table for weights `weights` (non-negative, finite, with a positive sum); `None` otherwise
    /// or when empty.
    pub fn new(weights: &[f64]) -> Option<AliasTable> {
        let total: f64 = weights.iter().sum();
        let valid = weights.iter().all(|w| w.is_finite() && *w >= 0.0);
        if weights.is_empty() || !valid || !(total.is_finite() && total > 0.0) {
            return None;
        }
        let n = weights.len();
        let probability: Vec<f64> = weights.iter().map(|w| w / total).collect();
        let mut scaled: Vec<f64> = probability.iter().map(|p| p * n as f64).collect();
        let mut keep = vec![1.0; n];
        let mut alias: Vec<u32> = (0..n as u32).collect();
        let (mut small, mut large): (Vec<usize>, Vec<usize>) = (0..n).partition(|&i| scaled[i] < 1.0);
        while let (Some(&s), Some(&l)) = (small.last(), large.last()) {
            small.pop();
            keep[s] = scaled[s];
            alias[s] = l as u32;
            scaled[l] -= 1.0 - scaled[s];
            if scaled[l] < 1.0 {
                large.pop();
                small.push(l);
            }
        }
        // Whatever is left over (rounding) keeps its own entry with certainty: keep = 1, alias = itself.
        Some(AliasTable { keep, alias, probability })
    }

    pub fn len(&self) -> usize {
        self.keep.len()
    }

    pub fn is_empty(&self) -> bool {
        self.keep.is_empty()
    }

    /// pᵢ, the probability of entry i.
    pub fn probability(&self, i: usize) -> f64 {
        self.probability[i]
    }

    /// The entry for u ∈ [0, 1), and u's leftover precision rescaled to a fresh uniform number in
    /// [0, 1) (f/qᵢ or (f − qᵢ)/(1 − qᵢ)), so one number both selects and places the sample.
    pub fn select(&self, u: f32) -> (usize, f32) {
        let n = self.keep.len();
        let x = (u.clamp(0.0, 1.0) as f64) * n as f64;
        let cell = (x as usize).min(n - 1);
        let f = (x - cell as f64).clamp(0.0, 1.0);
        let q = self.keep[cell];
        let (entry, rest) = if f < q { (cell, f / q) } else { (self.alias[cell] as usize, (f - q) / (1.0 - q)) };
        (entry, (rest as f32).min(ONE_BELOW))
    }
}

const ONE_BELOW: f32 = 1.0 - f32::EPSILON / 2.0;

/// The triangles of emitting elements (by their front side's material), for direct light: a triangle
/// is chosen in proportion to its emitted power (`AliasTable`, O(1) per sample however many emit),
/// then a point uniformly on it.
#[derive(Clone, Debug, Default)]
pub struct Emitters {
    /// Mesh triangle of each entry, increasing.
    triangle: Vec<u32>,
    /// Aₜ/pₜ of each entry: the inverse area density of points drawn on it (scene units²).
    inverse_density: Vec<f32>,
    table: AliasTable,
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
        let Some(table) = AliasTable::new(&power) else {
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

    /// The point for uniform numbers (ξ, r): ξ selects the triangle in proportion to its power (the
    /// alias table) and, rescaled, the distance from its first corner; r the position across
    /// (`uniform_triangle_point`). `None` without emitters.
    pub fn sample(&self, mesh: &Mesh, xi: f32, r: f32) -> Option<EmitterSample> {
        if self.triangle.is_empty() {
            return None;
        }
        let (i, s) = self.table.select(xi);
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

    /// Frequencies of each entry over a regular grid of m values of u. An entry owns at most a few
    /// intervals of u (its own cell's kept part and the aliased parts of other cells), and each
    /// interval's count differs from m × its length by less than 1; the bound allows 2 per cell.
    fn frequencies(table: &AliasTable, m: usize) -> Vec<f64> {
        let mut count = vec![0usize; table.len()];
        for k in 0..m {
            count[table.select(((k as f64 + 0.5) / m as f64) as f32).0] += 1;
        }
        count.iter().map(|&c| c as f64 / m as f64).collect()
    }

    proptest! {
        #[test]
        fn alias_table_picks_each_entry_with_probability_power_over_total(
            weights in prop::collection::vec(0.0f64..100.0, 1..40),
        ) {
            prop_assume!(weights.iter().sum::<f64>() > 1e-3);
            let table = AliasTable::new(&weights).unwrap();
            let total: f64 = weights.iter().sum();
            let m = 1 << 20;
            let f = frequencies(&table, m);
            let bound = 2.0 * weights.len() as f64 / m as f64 + 1e-6;
            for (j, w) in weights.iter().enumerate() {
                prop_assert!((table.probability(j) - w / total).abs() < 1e-12);
                prop_assert!((f[j] - w / total).abs() <= bound, "entry {}: {} vs {}", j, f[j], w / total);
            }
        }

        #[test]
        fn alias_leftover_stays_in_the_unit_interval(weights in prop::collection::vec(0.1f64..10.0, 1..8)) {
            let table = AliasTable::new(&weights).unwrap();
            for k in 0..1000 {
                let (_, rest) = table.select(k as f32 / 1000.0);
                prop_assert!((0.0..1.0).contains(&rest));
            }
        }
    }

    #[test]
    fn alias_table_refuses_empty_negative_and_zero_weights() {
        assert!(AliasTable::new(&[]).is_none());
        assert!(AliasTable::new(&[0.0, 0.0]).is_none());
        assert!(AliasTable::new(&[1.0, -1.0]).is_none());
        assert!(AliasTable::new(&[1.0, f64::NAN]).is_none());
    }

    #[test]
    fn alias_leftover_of_one_entry_is_the_number_itself() {
        let table = AliasTable::new(&[3.0]).unwrap();
        for u in [0.0, 0.25, 0.7] {
            assert_eq!(table.select(u), (0, u));
        }
    }
}
