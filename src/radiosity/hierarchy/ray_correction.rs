//! The leaves' indirect irradiance measured by cosine rays, and the gain that corrects what the
//! links bring of it.
//!
//! A leaf i gathers G_i = Σ_j F_ij B_j over its links. The part D_i of it that the sources' own
//! light S = E + ρ·E_c brings (emission, reflected caustics) is what the links measure best: the
//! lamps' links are refined hardest. The rest, the interreflected light I_i = G_i − D_i, comes
//! from links between large, close clusters whose sampled form factors are noisy, and refinement
//! keeps the ones whose samples came out low (docs/accuracy.md, sessions 25–29): on Crytek Sponza
//! the leaves' links see 65% of the hemisphere the rays see, and the radiosity image is a quarter
//! too dark, the deficit compounding over the bounces of its high albedo.
//!
//! Cosine rays from a leaf that read the exitance of the leaf they hit, less its own light, give an
//! unbiased estimate of the same indirect irradiance,
//!
//! Î_i = (1/N) Σ_k (B − S)(hit_k),
//!
//! noisy per leaf but not by the links' selection. Over a group of neighbouring leaves (a node with
//! at most `GROUP_LEAVES` leaves below it) the ratio
//!
//! γ = Σ_i A_i w_i·Î_i / Σ_i A_i w_i·(G_i − D_i)
//!
//! (A_i the open area, w_i the leaf's reflectance as channel weights) says by how much the links
//! under- or overstate it there, and the sweeps then gather G'_i = D_i + γ·(G_i − D_i): the direct
//! light as the links measure it, the indirect light scaled to what the rays see. The same ratio
//! over regions `REGION_GROWTH` times larger, and larger again up to the whole tree, is measured
//! with ever less noise; from the top down each group's γ is shrunk towards its region's by its own
//! noise (σ_γ from the rays' sample variance, `shrunk_gain`), the whole tree's towards 1. A group
//! the rays cannot tell from its region takes the region's gain: where the links' deficit is
//! scene-wide, every group gets it, not only those whose own rays stand out (session 43: shrunk
//! towards 1, groups at 2–4σ kept a fraction of it and the rooms stayed 1–2% dark).
//!
//! `IndirectEstimator::Hemicube` measures Î instead with a hemicube at the centre of some leaves
//! that draws the tree as a cut (`hemicube_cut`); each group's σ is then its sampled leaves' spread
//! about the ratio (`sampling_variance`). It agrees with the rays and costs more (session 44).

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use super::clusters::InputTriangles;
use super::gather::ArrivalScales;
use super::hemicube_cut::{irradiance_at, two_sided_inputs, CutScene};
use super::links::Links;
use super::lobes::Lobes;
use super::nodes::{Nodes, NONE};
use super::solve::{leaf_irradiance, reset_to_emission, set_leaves};
use super::visibility::triangle_point;
use crate::accel::Accel;
use crate::radiosity::hemicube::{Hemicube, ItemBuffer};
use crate::transport::hit::leave_surface;

/// The most leaves below the node that groups them for one gain. Measured (session 42): groups of
/// 32 with k = 2 followed the links' local disagreements with the rays and made the rooms worse
/// (gap_room 8.33e-3 → 1.23e-2, l_room +55%); 256 with k = 3 leaves them within ±6% and corrects
/// Sponza as much (0.0439; 64 leaves and four rounds: 0.0449).
pub const GROUP_LEAVES: usize = 256;

/// How many times more leaves a region has than the groups or regions it holds (`shrunk_gain`).
pub const REGION_GROWTH: usize = 16;

/// k: how many standard errors σ a gain must stand from its region's γ_p to be kept whole (a
/// James–Stein-like shrinkage: γ = γ_p + δ·max(0, 1 − (k·σ/δ)²), δ = γ̂ − γ_p).
pub const SIGNIFICANCE: f64 = 3.0;

/// The largest ρ·γ·R a gain may give a leaf of row sum R.
pub const MAX_ROW_REFLECTION: f64 = 0.95;

/// The range a gain is clamped to.
pub const GAIN_RANGE: (f64, f64) = (0.25, 4.0);

/// A group's gain from its rays' Σ A·Î (`rays_sum`), its links' Σ A·(G − D) (`links_sum`) and the
/// variance of the former: γ̂ = rays_sum / links_sum, shrunk towards its region's gain γ_p by its
/// standard error σ, γ = γ_p + δ·max(0, 1 − (k·σ/δ)²) with δ = γ̂ − γ_p, and clamped to `GAIN_RANGE`.
pub fn shrunk_gain(rays_sum: f64, links_sum: f64, variance: f64, prior: f64) -> f64 {
    if !(links_sum > 0.0) {
        return prior;
    }
    let estimate = rays_sum / links_sum;
    let sigma = variance.sqrt() / links_sum;
    let delta = estimate - prior;
    let keep = if delta != 0.0 { (1.0 - (SIGNIFICANCE * sigma / delta).powi(2)).max(0.0) } else { 0.0 };
    (prior + delta * keep).clamp(GAIN_RANGE.0, GAIN_RANGE.1)
}

/// Per node: the irradiance the links bring of the sources' own light, and the gain on the rest.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct IndirectCorrection {
    /// D_i per node (leaves; zero elsewhere).
    pub direct: Vec<DVec3>,
    /// γ per node (1 where nothing is corrected).
    pub gain: Vec<f32>,
}

impl IndirectCorrection {
    /// G' = D + γ·(G − D) for leaf `n` that gathered G.
    pub fn apply(&self, n: usize, gathered: DVec3) -> DVec3 {
        let g = self.gain.get(n).copied().unwrap_or(1.0) as f64;
        if g == 1.0 {
            return gathered;
        }
        let d = self.direct[n];
        (d + (gathered - d) * g).max(DVec3::ZERO)
    }
}

/// What one measurement found.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct CorrectionStats {
    pub groups: usize,
    /// Groups whose gain is not 1 after shrinkage.
    pub corrected: usize,
    /// Σ A·γ / Σ A over the receiving leaves.
    pub mean_gain: f64,
    /// Rays traced (`IndirectEstimator::Rays`) or hemicubes drawn (`IndirectEstimator::Hemicube`).
    pub rays: u64,
    /// Leaves whose gain the row bound lowered.
    pub capped: usize,
}

/// Where a ray from a leaf ends.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayEnd {
    /// On leaf l, facing the ray.
    Facing(usize),
    /// On the back of a one-sided leaf.
    Behind,
    /// Nowhere: it left the scene.
    Escaped,
}

/// Rays against the leaves, one accelerator per sheet: a two-sided sheet's front and back leaves
/// coincide, and a ray sees the one that faces it.
pub struct LeafTracer {
    front: Vec<usize>,
    back: Vec<usize>,
    accel_front: Accel,
    accel_back: Accel,
}

impl LeafTracer {
    /// `back[input]`: whether an input triangle is the back sheet of a two-sided surface.
    pub fn new(nodes: &Nodes, back: &[bool], leaves: &[usize]) -> LeafTracer {
        let (back, front): (Vec<usize>, Vec<usize>) =
            leaves.iter().copied().partition(|&n| back[nodes.input[n] as usize]);
        let accel_of = |sheet: &[usize]| {
            let positions: Vec<Vec3> = sheet.iter().flat_map(|&n| nodes.corners[n]).collect();
            let triangles: Vec<[u32; 3]> = (0..sheet.len() as u32).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
            Accel::build(&positions, &triangles)
        };
        let (accel_front, accel_back) = (accel_of(&front), accel_of(&back));
        LeafTracer { front, back, accel_front, accel_back }
    }

    /// Where a ray from `origin` along `d` ends: the first occluder `occluders` (the scene's opaque
    /// triangles: a cut-out is no leaf a ray stops at) puts in its way, and there the leaf facing the
    /// ray (the two sheets of a two-sided surface coincide).
    pub fn cosine_ray(&self, nodes: &Nodes, occluders: &Accel, origin: Vec3, d: Vec3) -> RayEnd {
        let Some(hit) = occluders.closest_hit(origin, d, 0.0, f32::INFINITY) else {
            return RayEnd::Escaped;
        };
        let tolerance = (hit.t * 1e-3).max(1e-6);
        let (lo, hi) = ((hit.t - tolerance).max(0.0), hit.t + tolerance);
        let faces = |l: usize| nodes.normal[l].dot(d) < 0.0;
        let found = [(&self.accel_front, &self.front), (&self.accel_back, &self.back)].into_iter().find_map(
            |(accel, sheet)| {
                let l = sheet[accel.closest_hit(origin, d, lo, hi)?.triangle as usize];
                faces(l).then_some(l)
            },
        );
        match found {
            Some(l) => RayEnd::Facing(l),
            None => RayEnd::Behind,
        }
    }
}

/// A direction about unit normal `n` with density cos θ / π from two uniform numbers (Malley's
/// method): r = √u₁, φ = 2π·u₂, d = r cos φ·t + r sin φ·b + √(1 − u₁)·n, (t, b) any tangent frame.
pub fn cosine_direction(n: Vec3, u1: f32, u2: f32) -> Vec3 {
    let (t, b) = n.any_orthonormal_pair();
    let r = u1.sqrt();
    let phi = std::f32::consts::TAU * u2;
    t * (r * phi.cos()) + b * (r * phi.sin()) + n * (1.0 - u1).max(0.0).sqrt()
}

/// How `measure` estimates a leaf's indirect irradiance Î.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum IndirectEstimator {
    /// `rays` cosine rays from points spread over every leaf, reading the exitance of the leaf hit.
    Rays { rays: u32 },
    /// A hemicube of `resolution_px` at the centre of one leaf in `stride` (in tree order; larger
    /// where that would draw more than `max_hemicubes`), drawing the hierarchy as a cut whose nodes
    /// are at most `cut_pixels` pixels across (`hemicube_cut`).
    Hemicube { resolution_px: u32, stride: u32, cut_pixels: f32, max_hemicubes: u32 },
}

impl IndirectEstimator {
    /// The estimator for `leaves` leaves: the hemicubes' stride raised to keep to `max_hemicubes`.
    fn for_leaves(self, leaves: usize) -> IndirectEstimator {
        match self {
            IndirectEstimator::Hemicube { resolution_px, stride, cut_pixels, max_hemicubes } => {
                let needed = leaves.div_ceil(max_hemicubes.max(1) as usize) as u32;
                IndirectEstimator::Hemicube { resolution_px, stride: stride.max(needed), cut_pixels, max_hemicubes }
            }
            rays => rays,
        }
    }
}

/// One leaf's estimate: Î (its reflectance-weighted mean channel) and the variance the group sums
/// take from it.
#[derive(Clone, Copy, Debug, PartialEq)]
struct LeafRead {
    indirect: f64,
    variance: f64,
}

/// Per leaf, `estimator`'s Î, or `None` for a leaf it leaves out (no open area, black, not sampled).
/// The rays' variance is that of their mean; the hemicubes' is filled in later (`sampling_variance`).
#[allow(clippy::too_many_arguments)]
fn leaf_reads(
    nodes: &mut Nodes,
    inputs: &InputTriangles,
    occluders: &Accel,
    links: &Links,
    leaves: &[usize],
    root: usize,
    estimator: IndirectEstimator,
    seed: u64,
    offset: f32,
) -> Vec<Option<LeafRead>> {
    let weights = |nodes: &Nodes, e: usize| {
        let w = nodes.reflectance[e].as_dvec3();
        let w_sum = w.x + w.y + w.z;
        (nodes.open_area[e] > 0.0 && w_sum > 0.0).then_some((w, w_sum))
    };
    let rng = |e: usize| {
        let mut state = crate::rng::splitmix64(seed ^ (e as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15));
        move || {
            state = crate::rng::splitmix64(state);
            (state >> 40) as f32 / (1u64 << 24) as f32
        }
    };
    match estimator {
        IndirectEstimator::Rays { rays } => {
            let tracer = LeafTracer::new(nodes, &inputs.back, leaves);
            let nodes: &Nodes = nodes;
            leaves
                .par_iter()
                .map(|&e| {
                    let (w, w_sum) = weights(nodes, e)?;
                    let mut uniform = rng(e);
                    let n = nodes.normal[e];
                    let (mut sum, mut sum_sq, mut valid) = (0.0f64, 0.0f64, 0u32);
                    let partly_hidden = nodes.open_area[e] < nodes.area[e];
                    for _ in 0..rays {
                        let p = triangle_point(&nodes.corners[e], uniform(), uniform());
                        let d = cosine_direction(n, uniform(), uniform());
                        let origin = leave_surface(p, n, offset);
                        match tracer.cosine_ray(nodes, occluders, origin, d) {
                            RayEnd::Facing(l) => {
                                let read = (nodes.exitance[l] - nodes.source_exitance(l)).max(DVec3::ZERO);
                                let r = w.dot(read) / w_sum;
                                sum += r;
                                sum_sq += r * r;
                            }
                            // From the hidden part of a leaf partly inside an object resting on it: not a
                            // sample of the open part its links gather for.
                            RayEnd::Behind if partly_hidden => continue,
                            RayEnd::Behind | RayEnd::Escaped => {}
                        }
                        valid += 1;
                    }
                    if valid == 0 {
                        return None;
                    }
                    let count = valid as f64;
                    let mean = sum / count;
                    let variance = (sum_sq / count - mean * mean).max(0.0) / (count - 1.0).max(1.0);
                    Some(LeafRead { indirect: mean, variance })
                })
                .collect()
        }
        IndirectEstimator::Hemicube { resolution_px, stride, cut_pixels, .. } => {
            // The exitance a hemicube shows: B − S at the leaves, pulled up, and the lobes over it.
            let saved = nodes.exitance.clone();
            set_leaves(nodes, root, |nodes, n| (nodes.exitance[n] - nodes.source_exitance(n)).max(DVec3::ZERO));
            let lobes = Lobes::new(nodes, links, root);
            let shown = std::mem::replace(&mut nodes.exitance, saved);
            for n in 0..nodes.len() {
                nodes.exitance_mean[n] = super::nodes::mean_channel(nodes.exitance[n]);
            }
            let two_sided = two_sided_inputs(inputs);
            let nodes: &Nodes = nodes;
            let scene = CutScene { nodes, exitance: &shown, lobes: &lobes, two_sided: &two_sided, root };
            let hc = Hemicube::new(resolution_px);
            let stride = stride.max(1) as usize;
            let phase = (seed % stride as u64) as usize;
            leaves
                .par_iter()
                .enumerate()
                .map_init(
                    || ItemBuffer::new(&hc),
                    |buffers, (i, &e)| {
                        if i % stride != phase || nodes.open_area[e] < nodes.area[e] {
                            return None;
                        }
                        let (w, w_sum) = weights(nodes, e)?;
                        let mut uniform = rng(e);
                        let n = nodes.normal[e];
                        let eye = leave_surface(nodes.centre[e], n, offset);
                        let rotation = uniform() * std::f32::consts::TAU;
                        let seen = irradiance_at(&scene, &hc, buffers, eye, n, rotation, cut_pixels);
                        Some(LeafRead { indirect: w.dot(seen.irradiance) / w_sum, variance: 0.0 })
                    },
                )
                .collect()
        }
    }
}

/// Per leaf, the links' Σ w·(G − D)/Σ w, the indirect irradiance they bring.
fn links_indirect(nodes: &Nodes, leaves: &[usize], gathered: &[DVec3], direct: &[DVec3]) -> Vec<f64> {
    leaves
        .iter()
        .map(|&e| {
            let w = nodes.reflectance[e].as_dvec3();
            let w_sum = w.x + w.y + w.z;
            if w_sum > 0.0 {
                w.dot((gathered[e] - direct[e]).max(DVec3::ZERO)) / w_sum
            } else {
                0.0
            }
        })
        .collect()
}

/// The variance a sample of one leaf in `stride` adds to its group's ratio: the ratio estimator's
/// (Î_i − r·L_i)², r = Σ A·Î / Σ A·L over the whole sample, times the finite-population factor
/// 1 − 1/stride (a census has none).
fn sampling_variance(reads: &mut [Option<LeafRead>], links: &[f64], areas: &[f64], stride: u32) {
    let (mut rays_sum, mut links_sum) = (0.0f64, 0.0f64);
    for ((read, &l), &a) in reads.iter().zip(links).zip(areas) {
        if let Some(read) = read {
            rays_sum += a * read.indirect;
            links_sum += a * l;
        }
    }
    let ratio = if links_sum > 0.0 { rays_sum / links_sum } else { 1.0 };
    let factor = 1.0 - 1.0 / stride.max(1) as f64;
    for (read, &l) in reads.iter_mut().zip(links) {
        if let Some(read) = read {
            read.variance = factor * (read.indirect - ratio * l).powi(2);
        }
    }
}

/// Measures the correction at the nodes' current exitance (see the module): Î by `estimator` (its
/// rays or hemicubes seeded by `seed` and the leaf, their origins `offset` off the leaf). Leaves the
/// nodes' exitance as it found it.
#[allow(clippy::too_many_arguments)]
pub fn measure(
    nodes: &mut Nodes,
    inputs: &InputTriangles,
    occluders: &Accel,
    links: &Links,
    scales: &ArrivalScales,
    root: usize,
    estimator: IndirectEstimator,
    seed: u64,
    offset: f32,
) -> (IndirectCorrection, CorrectionStats) {
    let lobes = Lobes::new(nodes, links, root);
    let gathered = leaf_irradiance(nodes, links, scales, &nodes.exitance, Some(&lobes), root);
    drop(lobes);
    let saved: Vec<DVec3> = nodes.exitance.clone();
    reset_to_emission(nodes, root);
    let source_lobes = Lobes::new(nodes, links, root);
    let direct = leaf_irradiance(nodes, links, scales, &nodes.exitance, Some(&source_lobes), root);
    drop(source_lobes);
    for (n, b) in saved.into_iter().enumerate() {
        nodes.exitance[n] = b;
        nodes.exitance_mean[n] = super::nodes::mean_channel(b);
    }

    let leaves: Vec<usize> = (0..nodes.len()).filter(|&n| nodes.is_leaf(n) && !nodes.is_cluster[n]).collect();
    let estimator = estimator.for_leaves(leaves.len());
    let mut reads = leaf_reads(nodes, inputs, occluders, links, &leaves, root, estimator, seed, offset);
    let links_read = links_indirect(nodes, &leaves, &gathered, &direct);
    let areas: Vec<f64> = leaves.iter().map(|&e| nodes.open_area[e] as f64).collect();
    if let IndirectEstimator::Hemicube { stride, .. } = estimator {
        sampling_variance(&mut reads, &links_read, &areas, stride);
    }
    let rays = match estimator {
        IndirectEstimator::Rays { rays } => leaves.len() as u64 * rays as u64,
        IndirectEstimator::Hemicube { .. } => reads.iter().flatten().count() as u64,
    };

    // Leaves below each node; children have higher indices than their parent.
    let mut count = vec![0usize; nodes.len()];
    for &e in &leaves {
        count[e] = 1;
    }
    for n in (0..nodes.len()).rev() {
        let p = nodes.parent[n];
        if p != NONE {
            count[p as usize] += count[n];
        }
    }
    // A leaf's group at size `limit`: its highest ancestor with at most `limit` leaves below.
    let group_at = |e: usize, limit: usize| {
        let mut g = e;
        while nodes.parent[g] != NONE && count[nodes.parent[g] as usize] <= limit {
            g = nodes.parent[g] as usize;
        }
        g
    };
    let group_of = |e: usize| group_at(e, GROUP_LEAVES);
    // Groups of GROUP_LEAVES, then regions REGION_GROWTH times larger, up to the whole tree.
    let mut limits = vec![GROUP_LEAVES];
    while limits[limits.len() - 1] < leaves.len() {
        limits.push(limits[limits.len() - 1].saturating_mul(REGION_GROWTH));
    }
    // Per level and group: (Σ A·Î, Σ A·(G − D), Σ A²·var(Î)), and the group one level up.
    let mut sums: Vec<rustc_hash::FxHashMap<usize, (f64, f64, f64)>> = vec![Default::default(); limits.len()];
    let mut up: Vec<rustc_hash::FxHashMap<usize, usize>> = vec![Default::default(); limits.len()];
    for (i, &e) in leaves.iter().enumerate() {
        let a = areas[i];
        let Some(read) = reads[i] else { continue };
        let (mean, variance, links_indirect) = (read.indirect, read.variance, links_read[i]);
        let groups: Vec<usize> = limits.iter().map(|&limit| group_at(e, limit)).collect();
        for (level, &g) in groups.iter().enumerate() {
            let entry = sums[level].entry(g).or_insert((0.0, 0.0, 0.0));
            entry.0 += a * mean;
            entry.1 += a * links_indirect;
            entry.2 += a * a * variance;
            if let Some(&parent) = groups.get(level + 1) {
                up[level].insert(g, parent);
            }
        }
    }
    // From the whole tree down: each group's gain shrunk towards its region's (the top towards 1).
    let mut gains: Vec<rustc_hash::FxHashMap<usize, f64>> = vec![Default::default(); limits.len()];
    for level in (0..limits.len()).rev() {
        let shrunk: rustc_hash::FxHashMap<usize, f64> = sums[level]
            .iter()
            .map(|(&g, &(rays_sum, links_sum, variance))| {
                let prior = match up[level].get(&g) {
                    Some(parent) => gains[level + 1][parent],
                    None => 1.0,
                };
                (g, shrunk_gain(rays_sum, links_sum, variance, prior))
            })
            .collect();
        gains[level] = shrunk;
    }
    let gain_of_group: rustc_hash::FxHashMap<usize, f32> = gains[0].iter().map(|(&g, &v)| (g, v as f32)).collect();
    let mut stats = CorrectionStats {
        groups: gain_of_group.len(),
        corrected: gain_of_group.values().filter(|&&g| g != 1.0).count(),
        rays,
        ..Default::default()
    };
    // A gain never lets a leaf reflect all it gathers (ρ·γ·R < 1, R its row sum): the sweeps would
    // diverge (`row_sums`).
    let row = super::row_sums::row_sums(nodes, links, scales);
    let mut gain = vec![1.0f32; nodes.len()];
    let (mut weighted, mut area) = (0.0f64, 0.0f64);
    for &e in &leaves {
        let a = nodes.open_area[e] as f64;
        if let Some(&g) = gain_of_group.get(&group_of(e)) {
            let bound = MAX_ROW_REFLECTION / (nodes.reflectance_max[e] as f64 * row[e]).max(1e-12);
            let g = if g > 1.0 && (g as f64) > bound {
                stats.capped += 1;
                bound.max(1.0) as f32
            } else {
                g
            };
            gain[e] = g;
            weighted += a * g as f64;
            area += a;
        }
    }
    stats.mean_gain = if area > 0.0 { weighted / area } else { 1.0 };
    (IndirectCorrection { direct, gain }, stats)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_group_the_rays_cannot_tell_from_its_region_takes_the_regions_gain() {
        // The region's rays see 1.3 times what its links bring, to 1% (σ = 0.01): δ = 0.3 is 30σ,
        // kept to 1 − (3/30)² = 99%.
        let region = shrunk_gain(1.3e4, 1e4, 1e4f64.powi(2) * 0.01f64.powi(2), 1.0);
        assert!((region - 1.297).abs() < 1e-12, "{region}");
        // A group of it at 1.35 ± 0.1: 0.05 from its region is half a standard error, so it keeps
        // the region's gain. Shrunk towards 1 instead (before regions, session 42), it kept a quarter
        // of its δ = 0.35: 1 + 0.35·(1 − (0.3/0.35)²) = 1.093.
        let group = shrunk_gain(135.0, 100.0, 100f64.powi(2) * 0.1f64.powi(2), region);
        assert_eq!(group, region);
        let towards_one = shrunk_gain(135.0, 100.0, 100f64.powi(2) * 0.1f64.powi(2), 1.0);
        assert!((towards_one - (1.0 + 0.35 * (1.0 - (0.3f64 / 0.35).powi(2)))).abs() < 1e-12, "{towards_one}");
    }

    #[test]
    fn a_group_far_from_its_region_keeps_what_its_rays_measured() {
        // 0.8 ± 0.02 in a region at 1.3: δ = −0.5 is 25σ, kept to 1 − (3/25)² = 98.6%.
        let group = shrunk_gain(80.0, 100.0, 100f64.powi(2) * 0.02f64.powi(2), 1.3);
        assert!((group - (1.3 - 0.5 * (1.0 - (3.0f64 * 0.02 / 0.5).powi(2)))).abs() < 1e-12, "{group}");
        // Links that bring nothing: the region's gain; estimates beyond the range: clamped.
        assert_eq!(shrunk_gain(5.0, 0.0, 1.0, 1.2), 1.2);
        assert_eq!(shrunk_gain(1e6, 1.0, 0.0, 1.0), GAIN_RANGE.1);
    }
}
