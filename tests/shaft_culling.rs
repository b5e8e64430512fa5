//! Shaft culling of link visibility (`radiosity::hierarchy::shaft`, Haines and Wallace 1994) is
//! conservative: a shaft it declares clear has no occluder on any segment between its two ends, so
//! skipping the rays changes no visibility estimate.

use glam::{DVec3, Vec3};
use radray::accel::Accel;
use radray::radiosity::hierarchy::shaft::{shaft_clear, EndHull};
use radray::rng::splitmix64;

/// Uniform numbers in [0, 1) from a counter-based hash (deterministic, no shared state).
struct Uniform(u64);

impl Uniform {
    fn next(&mut self) -> f32 {
        self.0 = self.0.wrapping_add(1);
        (splitmix64(self.0) >> 40) as f32 / (1u64 << 24) as f32
    }

    fn point(&mut self) -> Vec3 {
        Vec3::new(self.next(), self.next(), self.next())
    }
}

/// The 12 triangles of the box [lo, hi].
fn box_triangles(lo: Vec3, hi: Vec3, positions: &mut Vec<Vec3>, triangles: &mut Vec<[u32; 3]>) {
    let base = positions.len() as u32;
    for k in 0..8 {
        let pick = |bit: u32, l: f32, h: f32| if k & bit != 0 { h } else { l };
        positions.push(Vec3::new(pick(1, lo.x, hi.x), pick(2, lo.y, hi.y), pick(4, lo.z, hi.z)));
    }
    for [a, b, c, d] in [[0, 1, 3, 2], [4, 6, 7, 5], [0, 4, 5, 1], [2, 3, 7, 6], [0, 2, 6, 4], [1, 5, 7, 3]] {
        triangles.push([base + a, base + b, base + c]);
        triangles.push([base + a, base + c, base + d]);
    }
}

/// A point of triangle `t` from (u, v) in [0, 1)², corners and edges included when u or v is 0.
fn on_triangle(t: &[Vec3; 3], u: f32, v: f32) -> Vec3 {
    let su = u.sqrt();
    t[0] * (1.0 - su) + t[1] * (su * (1.0 - v)) + t[2] * (su * v)
}

/// Property over random scenes: one to three random boxes in the unit cube as occluders and two
/// random triangles as a link's ends. Whenever the shaft between the ends is declared clear, none
/// of 300 segments between the two triangles (their corners, and points spread over them) is
/// occluded. The test is not vacuous: both verdicts occur many times, and pairs with an occluded
/// segment are seen (each of them must have been declared not clear).
#[test]
fn a_shaft_declared_clear_has_no_occluded_segment_between_its_ends() {
    let (mut clear_count, mut blocked_pairs) = (0, 0);
    let cases = 1500;
    for case in 0..cases {
        let mut rng = Uniform(splitmix64(case));
        let (mut positions, mut triangles) = (Vec::new(), Vec::new());
        for _ in 0..1 + (rng.next() * 3.0) as usize {
            let centre = rng.point();
            let half = Vec3::splat(0.02) + rng.point() * 0.2;
            box_triangles(centre - half, centre + half, &mut positions, &mut triangles);
        }
        let accel = Accel::build(&positions, &triangles);
        let end = |rng: &mut Uniform| {
            let c = rng.point();
            [c, c + (rng.point() - 0.5) * 0.3, c + (rng.point() - 0.5) * 0.3]
        };
        let (a, b) = (end(&mut rng), end(&mut rng));
        let hull = |t: &[Vec3; 3]| EndHull::from_points(&t.map(|p| p.as_dvec3()));
        let clear = shaft_clear(&accel, &hull(&a), &hull(&b));
        let mut any_blocked = false;
        for k in 0..300 {
            let (x, y) = if k < 9 {
                (a[k / 3], b[k % 3])
            } else {
                (on_triangle(&a, rng.next(), rng.next()), on_triangle(&b, rng.next(), rng.next()))
            };
            let blocked = accel.occluded(x, y - x, 1.0);
            assert!(!(clear && blocked), "case {case}: declared clear, but {x} → {y} is occluded");
            any_blocked |= blocked;
        }
        clear_count += clear as usize;
        blocked_pairs += any_blocked as usize;
    }
    assert!(clear_count > cases as usize / 10, "only {clear_count} of {cases} shafts declared clear");
    assert!(blocked_pairs > cases as usize / 10, "only {blocked_pairs} of {cases} cases had an occluded segment");
}

/// Two facing squares' triangles with a wall of triangles between them are never clear; moved
/// beside the shaft, the same wall lets it be declared clear; a wall the ends rest on (the floor
/// under both) does not count as an occluder.
#[test]
fn an_occluder_between_the_ends_closes_the_shaft_and_one_beside_it_or_under_it_does_not() {
    let a = [DVec3::new(0.0, 0.1, 0.0), DVec3::new(1.0, 0.1, 0.0), DVec3::new(0.0, 1.0, 0.0)];
    let b = [DVec3::new(0.0, 0.1, 2.0), DVec3::new(0.0, 1.0, 2.0), DVec3::new(1.0, 0.1, 2.0)];
    let (ha, hb) = (EndHull::from_points(&a), EndHull::from_points(&b));
    let scene = |lo: Vec3, hi: Vec3| {
        let (mut positions, mut triangles) = (Vec::new(), Vec::new());
        box_triangles(lo, hi, &mut positions, &mut triangles);
        // The floor both ends stand on, at y = 0.1 (their lowest corners touch it).
        let base = positions.len() as u32;
        positions.extend([Vec3::new(-5.0, 0.1, -5.0), Vec3::new(5.0, 0.1, -5.0), Vec3::new(0.0, 0.1, 5.0)]);
        triangles.push([base, base + 1, base + 2]);
        Accel::build(&positions, &triangles)
    };
    let between = scene(Vec3::new(0.2, 0.3, 0.9), Vec3::new(0.6, 0.7, 1.1));
    assert!(!shaft_clear(&between, &ha, &hb));
    let beside = scene(Vec3::new(3.2, 0.3, 0.9), Vec3::new(3.6, 0.7, 1.1));
    assert!(shaft_clear(&beside, &ha, &hb));
}
