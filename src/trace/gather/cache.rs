//! The irradiance cache (Ward, Rubinstein and Clear 1988; Ward and Heckbert 1992): gathered records
//! with their gradients, the error-bounded weights that decide which records may serve a point, and
//! the interpolation between them, with the radii limited by the nearest surface seen (`near_radius`)
//! so that no record reaches into a concave edge, and clamped to their neighbours' (Křivánek et al.
//! 2006) so that none reaches across a contact. Filled once before the image (`prepass`), read-only
//! after, so that every lookup sums the same records in the same order whatever the thread count.

use std::collections::HashMap;

use glam::{IVec3, Vec3};

use super::hemisphere::HemisphereEstimate;

/// One gathered point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IrradianceRecord {
    pub position: Vec3,
    /// Unit normal of the side gathered.
    pub normal: Vec3,
    /// The gather's indirect irradiance and gradients (`hemisphere::estimate`).
    pub estimate: HemisphereEstimate,
    /// R_i: the validity radius, the harmonic mean distance clamped (`IrradianceCache::insert`).
    pub radius: f32,
}

impl IrradianceRecord {
    /// Ward's error weight at (p, n): w_i = 1 / (|p − p_i|/R_i + √(1 − n·n_i)). The split-sphere model
    /// bounds the relative error of using record i at (p, n) by about 1/w_i (Ward et al. 1988, eq. 3),
    /// so a record serves where w_i > 1/a, a the accuracy.
    pub fn weight(&self, p: Vec3, n: Vec3) -> f32 {
        let distance = (p - self.position).length() / self.radius;
        let turn = (1.0 - n.dot(self.normal)).max(0.0).sqrt();
        1.0 / (distance + turn).max(1e-12)
    }

    /// The record moved to (p, n) by its gradients: E_i + (n_i × n)·∇_r E_i + (p − p_i)·∇_t E_i, per
    /// channel, clamped at 0.
    pub fn extrapolate(&self, p: Vec3, n: Vec3) -> Vec3 {
        let axis = self.normal.cross(n);
        let step = p - self.position;
        let e = &self.estimate;
        let change = |c: usize| axis.dot(e.rotation_gradient[c]) + step.dot(e.translation_gradient[c]);
        (e.irradiance + Vec3::new(change(0), change(1), change(2))).max(Vec3::ZERO)
    }

    /// Ward's "in front" test: a record whose point lies in front of p (d_i = (p − p_i)·(n + n_i)/2 <
    /// −ε) sees a different neighbourhood and is not used.
    fn behind_or_level(&self, p: Vec3, n: Vec3, tolerance: f32) -> bool {
        (p - self.position).dot((n + self.normal) * 0.5) >= -tolerance
    }
}

/// Records in insertion order, with nested uniform grids over their spheres of validity (radius
/// a·R_i), rebuilt by `index`.
#[derive(Clone, Debug)]
pub struct IrradianceCache {
    /// a: the largest error weight 1/w accepted (0.1–0.3 is Ward's usual range).
    accuracy: f32,
    records: Vec<IrradianceRecord>,
    /// Records `index` has put in the grids (the first `indexed` of `records`).
    indexed: usize,
    /// Cell size of grid level 0; level l has cells GRID_LEVEL_RATIO^l times larger.
    cell_size: f32,
    /// (level, cell) → records whose sphere overlaps the cell, in insertion order. A record goes to the
    /// finest level on which it spans at most MAX_CELLS_PER_AXIS cells per axis.
    grid: HashMap<(u32, IVec3), Vec<u32>>,
    levels: u32,
    /// Each record's smallest radius (`insert`'s `min_radius`), which neighbour clamping keeps.
    min_radius: Vec<f32>,
}

/// A record's radius is at most this many times the nearest surface its gather saw within 60° of the
/// normal (`HemisphereEstimate::near_distance`); see `near_radius`.
pub const NEAR_RADIUS_RATIO: f32 = 2.0;

/// R = min(R_harmonic, 2·r_near): Ward's harmonic mean distance, limited by the nearest surface seen.
///
/// The harmonic mean is dominated by the open half of the hemisphere wherever a wall stands on one
/// side: a point x from a wall sees it in half its hemisphere at distance x/(sin θ cos φ), so
/// 1/R = (1/π)∫ cos θ sin θ cos φ / x dω = 2/(3πx) and R = 3πx/2 ≈ 4.7x. A record there reaches
/// a·R ≈ 1.2x at a = 0.25: past the corner, where the irradiance bends down within a few x (a darker
/// wall fills ever more of the hemisphere), and its linear extrapolation overshoots (the Cornell box's
/// ceiling beside the back wall came out up to 3.5% bright). Beside a wall r_near ≈ x/sin 60°, so
/// the limit gives R ≈ 2.3x and a reach of 0.58x at a = 0.25. Measured on the final images at
/// default settings (docs/accuracy.md, session 35): relMSE −15% cornell_box, −28% cornell_empty,
/// −34% l_room, −36% rotunda (with 44% less CPU: fewer samples left uncovered), −1 to −10% on the
/// other rooms. A ratio of 1.5 gained another 1–8% for 8–16% more CPU.
pub fn near_radius(estimate: &HemisphereEstimate) -> f32 {
    estimate.harmonic_distance.min(NEAR_RADIUS_RATIO * estimate.near_distance)
}

/// A record spans at most this many cells per axis on its grid level.
const MAX_CELLS_PER_AXIS: i32 = 4;
/// Cell size ratio between grid levels.
const GRID_LEVEL_RATIO: f32 = 4.0;

/// The "in front" test's tolerance, as a fraction of the record's reach a·R_i.
const FRONT_TOLERANCE: f32 = 0.05;

impl IrradianceCache {
    /// An empty cache of accuracy a ∈ (0, 1].
    pub fn new(accuracy: f32) -> IrradianceCache {
        assert!(accuracy > 0.0 && accuracy <= 1.0, "the accuracy is validated by the scene parser");
        IrradianceCache {
            accuracy,
            records: Vec::new(),
            indexed: 0,
            cell_size: 1.0,
            grid: HashMap::new(),
            levels: 0,
            min_radius: Vec::new(),
        }
    }

    pub fn len(&self) -> usize {
        self.records.len()
    }

    pub fn is_empty(&self) -> bool {
        self.records.is_empty()
    }

    pub fn records(&self) -> &[IrradianceRecord] {
        &self.records
    }

    pub fn accuracy(&self) -> f32 {
        self.accuracy
    }

    /// Adds the gather at (p, n); lookups see it after the next `index`. Its radius is the harmonic
    /// mean distance, limited to `NEAR_RADIUS_RATIO` times the nearest surface seen (`near_radius`)
    /// and by the translation gradient (R ≤ E/|∇_t E|, Křivánek et al. 2005: the linear extrapolation
    /// must not change the value by more than itself within R), and clamped to [min_radius,
    /// max_radius] (scene units; the prepass sets them from the pixel footprint). Where
    /// the clamp raises R above E/|∇_t E| (a gather right against other geometry, whose nearest cells
    /// make the gradient huge), the gradient is scaled down to |∇_t E| = E/R, so that no extrapolation
    /// within the record's reach more than doubles or zeroes it.
    pub fn insert(
        &mut self,
        position: Vec3,
        normal: Vec3,
        mut estimate: HemisphereEstimate,
        min_radius: f32,
        max_radius: f32,
    ) {
        let mut radius = near_radius(&estimate);
        for c in 0..3 {
            let slope = estimate.translation_gradient[c].length();
            if slope > 0.0 && estimate.irradiance[c] > 0.0 {
                radius = radius.min(estimate.irradiance[c] / slope);
            }
        }
        let radius = radius.min(max_radius).max(min_radius).max(f32::MIN_POSITIVE);
        for c in 0..3 {
            let slope = estimate.translation_gradient[c].length();
            let limit = estimate.irradiance[c].max(0.0) / radius;
            if slope > limit {
                estimate.translation_gradient[c] *= limit / slope;
            }
        }
        self.records.push(IrradianceRecord { position, normal, estimate, radius });
        self.min_radius.push(min_radius.max(f32::MIN_POSITIVE));
    }

    /// Clamps the radii to their neighbours' (`clamp_to_neighbours`), then rebuilds the grids over all
    /// records, level 0's cell twice the smallest reach a·R_i. Deterministic: records enter every list
    /// in insertion order, and the clamp reads the radii as they were before it.
    pub fn index(&mut self) {
        self.build_grids();
        if self.clamp_to_neighbours() {
            self.build_grids();
        }
        self.indexed = self.records.len();
    }

    /// Neighbour clamping (Křivánek, Bouatouch, Pattanaik and Žára 2006, "Making radiance and
    /// irradiance caching practical: adaptive caching and neighbor clamping"):
    ///
    /// R_i ← max(min(R_i, min_j (R_j + |p_i − p_j|)), R_i,min)
    ///
    /// over the records j whose point lies within record i's reach (|p_i − p_j| < a·R_i), R_i,min the
    /// radius `insert` clamped to from below. R_i is the harmonic mean distance to the surfaces record
    /// i's gather saw, a stand-in for the distance to the nearest geometry, and that distance is
    /// 1-Lipschitz in the point: a record that saw no surface nearer than R_i cannot be right if a
    /// neighbour d away saw one at R_j < R_i − d. Such records come from gathers a little away from a
    /// contact (the floor beside a torus lying on it, the torus's underside, a crease's other side):
    /// their hemisphere holds the contact only as a few cells, so their R and their gradients say
    /// little about it, yet their reach a·R_i spans it, and the prepass (`prepass::fill`) then finds
    /// the points at the contact covered and never gathers there. Clamped, they stop short of it and
    /// the next level's points there gather their own records. Returns whether a radius changed.
    fn clamp_to_neighbours(&mut self) -> bool {
        let mut clamped: Vec<f32> = self.records.iter().map(|r| r.radius).collect();
        for (j, neighbour) in self.records.iter().enumerate() {
            for level in 0..self.levels {
                let Some(list) = self.grid.get(&(level, self.cell(level, neighbour.position))) else {
                    continue;
                };
                for &i in list.iter().filter(|&&i| i as usize != j) {
                    let record = &self.records[i as usize];
                    let distance = (record.position - neighbour.position).length();
                    if distance < self.accuracy * record.radius {
                        let limit = (neighbour.radius + distance).max(self.min_radius[i as usize]);
                        clamped[i as usize] = clamped[i as usize].min(limit);
                    }
                }
            }
        }
        let mut changed = false;
        for (record, radius) in self.records.iter_mut().zip(clamped) {
            changed |= radius < record.radius;
            record.radius = radius;
        }
        changed
    }

    /// The nested grids over all records' spheres of validity (radius a·R_i).
    fn build_grids(&mut self) {
        let Some(smallest) = self.records.iter().map(|r| self.accuracy * r.radius).min_by(f32::total_cmp) else {
            return;
        };
        self.cell_size = (2.0 * smallest).max(f32::MIN_POSITIVE);
        self.grid.clear();
        self.levels = 0;
        for (index, record) in self.records.iter().enumerate() {
            let reach = Vec3::splat(self.accuracy * record.radius);
            let mut level = 0;
            let (lo, hi) = loop {
                let (lo, hi) = (self.cell(level, record.position - reach), self.cell(level, record.position + reach));
                if (hi - lo).max_element() < MAX_CELLS_PER_AXIS || level >= 30 {
                    break (lo, hi);
                }
                level += 1;
            };
            self.levels = self.levels.max(level + 1);
            for x in lo.x..=hi.x {
                for y in lo.y..=hi.y {
                    for z in lo.z..=hi.z {
                        self.grid.entry((level, IVec3::new(x, y, z))).or_default().push(index as u32);
                    }
                }
            }
        }
    }

    fn cell(&self, level: u32, p: Vec3) -> IVec3 {
        (p / (self.cell_size * GRID_LEVEL_RATIO.powi(level as i32))).floor().as_ivec3()
    }

    /// Whether some indexed record serves (p, n): w_i > 1/a and not in front.
    pub fn covers(&self, p: Vec3, n: Vec3) -> bool {
        let mut covered = false;
        self.for_each_serving(p, n, |_, _| covered = true);
        covered
    }

    /// The interpolated irradiance at (p, n), E(p) = Σ w_i E_i(p) / Σ w_i over the indexed records
    /// serving it (E_i(p) = `IrradianceRecord::extrapolate`), with w_i Ward's weight less its threshold
    /// 1/a so that a record fades out at the edge of its validity instead of stopping short; `None`
    /// when none serves. Records are summed level by level, each cell in insertion order, so the
    /// value does not depend on who asks.
    pub fn lookup(&self, p: Vec3, n: Vec3) -> Option<Vec3> {
        let mut weighted = Vec3::ZERO;
        let mut weight_sum = 0.0f32;
        self.for_each_serving(p, n, |record, w| {
            let w = w - 1.0 / self.accuracy;
            weighted += record.extrapolate(p, n) * w;
            weight_sum += w;
        });
        (weight_sum > 0.0).then(|| weighted / weight_sum)
    }

    fn for_each_serving(&self, p: Vec3, n: Vec3, mut visit: impl FnMut(&IrradianceRecord, f32)) {
        let threshold = 1.0 / self.accuracy;
        let mut consider = |i: u32| {
            let record = &self.records[i as usize];
            let w = record.weight(p, n);
            if w > threshold && record.behind_or_level(p, n, FRONT_TOLERANCE * self.accuracy * record.radius) {
                visit(record, w);
            }
        };
        for level in 0..self.levels {
            if let Some(list) = self.grid.get(&(level, self.cell(level, p))) {
                list.iter().for_each(|&i| consider(i));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flat(irradiance: f32, distance: f32) -> HemisphereEstimate {
        HemisphereEstimate {
            irradiance: Vec3::splat(irradiance),
            harmonic_distance: distance,
            near_distance: distance,
            rotation_gradient: [Vec3::ZERO; 3],
            translation_gradient: [Vec3::ZERO; 3],
        }
    }

    #[test]
    fn a_record_serves_within_a_times_its_radius_and_not_beyond() {
        let mut cache = IrradianceCache::new(0.2);
        cache.insert(Vec3::ZERO, Vec3::Z, flat(1.0, 1.0), 0.01, 10.0);
        cache.index();
        assert!(cache.covers(Vec3::new(0.19, 0.0, 0.0), Vec3::Z));
        assert!(!cache.covers(Vec3::new(0.21, 0.0, 0.0), Vec3::Z));
        // A normal turned by more than a² in 1 − cos falls outside too.
        let turned = Vec3::new(0.3, 0.0, 1.0).normalize();
        assert!(!cache.covers(Vec3::ZERO, turned));
        assert_eq!(cache.lookup(Vec3::new(0.1, 0.0, 0.0), Vec3::Z), Some(Vec3::ONE));
        assert_eq!(cache.lookup(Vec3::new(2.0, 0.0, 0.0), Vec3::Z), None);
    }

    #[test]
    fn the_translation_gradient_limits_the_radius_and_moves_the_value() {
        let mut cache = IrradianceCache::new(0.5);
        let mut e = flat(1.0, 4.0);
        e.translation_gradient = [Vec3::X * 2.0; 3];
        cache.insert(Vec3::ZERO, Vec3::Z, e, 0.01, 10.0);
        cache.index();
        assert!((cache.records()[0].radius - 0.5).abs() < 1e-6, "R = min(4, 1/2)");
        let v = cache.lookup(Vec3::new(0.1, 0.0, 0.0), Vec3::Z).unwrap();
        assert!((v.x - 1.2).abs() < 1e-5);
    }

    #[test]
    fn a_record_beside_a_wall_stops_well_short_of_it() {
        // A gather x = 0.1 from a wall that fills half its hemisphere (`hemisphere`'s analytic case):
        // the harmonic mean alone (3πx/2 ≈ 4.7x) would reach a·R ≈ 1.2x at a = 0.25, past the
        // corner; limited to 2·r_near (r_near ≈ x/sin 60°) it reaches 0.58x.
        use crate::trace::gather::hemisphere::{estimate, wall_beside, Strata};
        let strata = Strata::for_rays(1024);
        let x = 0.1f32;
        let (l, r) = wall_beside(strata, x);
        let e = estimate(strata, &l, &r, Vec3::Z);
        assert!(e.harmonic_distance > 4.5 * x);
        let mut cache = IrradianceCache::new(0.25);
        cache.insert(Vec3::ZERO, Vec3::Z, e, 1e-4, 10.0);
        cache.index();
        let reach = 0.25 * cache.records()[0].radius;
        assert!(reach < 0.6 * x, "reach {reach}");
        assert!(cache.covers(Vec3::new(0.5 * x, 0.0, 0.0), Vec3::Z));
        assert!(!cache.covers(Vec3::new(0.6 * x, 0.0, 0.0), Vec3::Z));
    }

    #[test]
    fn records_in_front_of_the_point_are_not_used() {
        let mut cache = IrradianceCache::new(0.5);
        cache.insert(Vec3::new(0.0, 0.0, 0.1), Vec3::Z, flat(1.0, 1.0), 0.01, 10.0);
        cache.index();
        assert!(cache.lookup(Vec3::ZERO, Vec3::Z).is_none());
        assert!(cache.lookup(Vec3::new(0.0, 0.0, 0.2), Vec3::Z).is_some());
    }

    #[test]
    fn neighbour_clamping_keeps_a_record_from_reaching_past_a_nearby_small_one() {
        // Record 0 saw surfaces 2 away on average (reach 1 at a = 0.5); record 1, 0.4 from it, saw one
        // 0.1 away. R_0 becomes 0.1 + 0.4 = 0.5 (reach 0.25): the point 0.38 from record 0 towards
        // record 1 (within record 1's reach 0.05) is no longer record 0's to serve, and record 1's
        // radius stays as it was.
        let mut cache = IrradianceCache::new(0.5);
        cache.insert(Vec3::ZERO, Vec3::Z, flat(1.0, 2.0), 0.01, 10.0);
        cache.insert(Vec3::new(0.4, 0.0, 0.0), Vec3::Z, flat(3.0, 0.1), 0.01, 10.0);
        cache.index();
        assert!((cache.records()[0].radius - 0.5).abs() < 1e-6, "R_0 = {}", cache.records()[0].radius);
        assert_eq!(cache.records()[1].radius, 0.1);
        let p = Vec3::new(0.38, 0.0, 0.0);
        assert_eq!(cache.lookup(p, Vec3::Z), Some(Vec3::splat(3.0)));
        // The clamp keeps the radius `insert` was given as its smallest.
        let mut cache = IrradianceCache::new(0.5);
        cache.insert(Vec3::ZERO, Vec3::Z, flat(1.0, 2.0), 0.8, 10.0);
        cache.insert(Vec3::new(0.4, 0.0, 0.0), Vec3::Z, flat(3.0, 0.1), 0.01, 10.0);
        cache.index();
        assert_eq!(cache.records()[0].radius, 0.8);
    }
}
