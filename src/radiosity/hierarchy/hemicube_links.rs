//! Links' form factors measured by a hemicube at the receiver (the issue's "the hemicube stays the
//! form-factor method"): the item buffer draws the hierarchy as a cut (`hemicube_cut`) and credits
//! each pixel to the link whose source holds the node drawn there.
//!
//! From a point p on an element receiver R (unit normal n) the tree is walked from the root, as
//! `hemicube_cut::irradiance_at` walks it, with one rule more: a node that holds one of R's link
//! sources below it is always opened, so that every source is drawn at or below its own level. A
//! source's subtree is drawn as the cut draws anything (whole where it is at most `cut_pixels`
//! across, opened towards the leaves where it is near) under the item of its link; every other node
//! is drawn as an occluder. By the Nusselt analog
//!
//! F_RS(p) = Σ ΔF over the pixels that show a node of S's subtree,
//!
//! visibility included: what lies between p and S hides it pixel by pixel. One hemicube at R's
//! centre measures all of R's far links (centres more than `links::FAR_DISTANCE_FACTOR` × the sum of
//! the bounding radii apart), F_RS = F_RS(centre): there the point form factor varies little over R,
//! unless something hides part of S from part of R. So where the centre's F differs from any link's
//! estimate by more than that estimate's stated error, R is supersampled (adaptive supersampling, as
//! pass two's pixels are): F_RS is the mean over the centroids of R's four midpoint sub-triangles
//! (the centre is the middle one's), three hemicubes more. Without it vault_hall came out 16% worse
//! than the estimators, darker on the floor beside a column's base (session 45).
//! The other links keep their estimators (`links::estimate`): near links, whose point form factor
//! varies over R (at four points per receiver the hemicube put a wall's strip along the ceiling 10%
//! below the 48-point quadrature, session 45), links of cluster receivers, which have no plane to put
//! a hemicube on, and links of receivers partly inside an object resting on them (the centre could be
//! inside it). Drawn near ends still hide what lies behind them.

use glam::Vec3;
use rayon::prelude::*;

use super::hemicube_cut::{draw_whole, CutScene};
use super::links::{Links, FAR_DISTANCE_FACTOR};
use super::nodes::{Nodes, NONE};
use crate::radiosity::hemicube::{Hemicube, HemicubeFrame, ItemBuffer};
use crate::transport::hit::leave_surface;

/// How links are measured by hemicubes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinkHemicubes {
    /// Pixels across the hemicube's top face.
    pub resolution_px: u32,
    /// Largest size (pixels) of a node drawn whole.
    pub cut_pixels: f32,
}

/// What one measurement did.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct LinkHemicubeStats {
    /// Receivers whose links were measured.
    pub receivers: u64,
    /// Links measured.
    pub links: u64,
    /// Hemicubes drawn.
    pub hemicubes: u64,
    /// Polygons drawn, over all hemicubes.
    pub polygons: u64,
}

/// Per-thread scratch of `source_form_factors_at`: the item buffer and the marks of the current
/// receiver's sources and their ancestors (valid where the stamp is the current generation).
pub struct LinkCutScratch {
    buffers: ItemBuffer,
    source_stamp: Vec<u32>,
    source_link: Vec<u32>,
    ancestor_stamp: Vec<u32>,
    generation: u32,
    stack: Vec<(usize, u32)>,
}

impl LinkCutScratch {
    pub fn new(hc: &Hemicube, node_count: usize) -> LinkCutScratch {
        LinkCutScratch {
            buffers: ItemBuffer::new(hc),
            source_stamp: vec![0; node_count],
            source_link: vec![0; node_count],
            ancestor_stamp: vec![0; node_count],
            generation: 0,
            stack: Vec::new(),
        }
    }

    /// Marks `sources` (link k's source is `sources[k]`) and every node above them.
    fn mark(&mut self, nodes: &Nodes, sources: &[u32]) {
        self.generation = self.generation.wrapping_add(1);
        if self.generation == 0 {
            self.source_stamp.fill(0);
            self.ancestor_stamp.fill(0);
            self.generation = 1;
        }
        let g = self.generation;
        for (k, &s) in sources.iter().enumerate() {
            self.source_stamp[s as usize] = g;
            self.source_link[s as usize] = k as u32;
            let mut a = nodes.parent[s as usize];
            while a != NONE && self.ancestor_stamp[a as usize] != g {
                self.ancestor_stamp[a as usize] = g;
                a = nodes.parent[a as usize];
            }
        }
    }
}

/// Adds to `out[k]` the point form factor F(p → sources[k]) that a hemicube at `eye` (already off the
/// surface) about unit `normal`, turned by `rotation_rad`, credits to link k (see the module's doc).
/// Returns the polygons drawn.
#[allow(clippy::too_many_arguments)]
pub fn source_form_factors_at(
    scene: &CutScene,
    hc: &Hemicube,
    scratch: &mut LinkCutScratch,
    eye: Vec3,
    normal: Vec3,
    rotation_rad: f32,
    cut_pixels: f32,
    sources: &[u32],
    out: &mut [f64],
) -> u32 {
    let nodes = scene.nodes;
    scratch.mark(nodes, sources);
    let g = scratch.generation;
    let (occluder, back) = (sources.len() as u32, sources.len() as u32 + 1);
    let small = cut_pixels / hc.resolution_px() as f32;
    scratch.buffers.begin(hc, HemicubeFrame::new(eye, normal, rotation_rad));
    let mut drawn = 0u32;
    let mut stack = std::mem::take(&mut scratch.stack);
    stack.clear();
    stack.push((scene.root, occluder));
    while let Some((n, above)) = stack.pop() {
        let label = if above == occluder && scratch.source_stamp[n] == g { scratch.source_link[n] } else { above };
        let (c, r) = (nodes.centre[n], nodes.radius[n]);
        let to = c - eye;
        if to.dot(normal) < -r {
            continue;
        }
        let d = to.length();
        let holds_source = label == occluder && scratch.ancestor_stamp[n] == g;
        // An element's triangle is exactly the union of its pieces: drawn whole at any size unless a
        // source lies below it. A cluster's square only stands for it when it is small.
        let whole = nodes.is_leaf(n) || (!holds_source && (!nodes.is_cluster[n] || (d > r && r <= small * d)));
        if !whole {
            stack.extend(nodes.children(n).map(|c| (c, label)));
            continue;
        }
        drawn += 1;
        draw_whole(scene, hc, &mut scratch.buffers, n, eye, label, back);
    }
    scratch.stack = stack;
    scratch.buffers.finish(hc, |j, f| {
        if (j as usize) < out.len() {
            out[j as usize] += f;
        }
    });
    drawn
}

/// The receivers whose far links `measure_links` measures: elements with links whose whole area is
/// open (no object rests on them: the centre could be inside it).
pub fn receivers(nodes: &Nodes, links: &Links) -> Vec<usize> {
    (0..nodes.len())
        .filter(|&r| {
            !nodes.is_cluster[r]
                && !links.range(r).is_empty()
                && nodes.area[r] > 0.0
                && nodes.open_area[r] >= nodes.area[r]
        })
        .collect()
}

/// Link (receiver `r` ← source `s`) is far: the centres are more than `FAR_DISTANCE_FACTOR` × the sum
/// of the bounding radii apart, as `links::admissible` judges cluster ends.
pub fn is_far(nodes: &Nodes, r: usize, s: usize) -> bool {
    nodes.centre[r].distance(nodes.centre[s]) > FAR_DISTANCE_FACTOR * (nodes.radius[r] + nodes.radius[s])
}

/// Replaces the form factor of every far link of every `receivers` element with the hemicube's at the
/// element's centre, or, where that disagrees with a link's estimate by more than the estimate's own
/// error (`Links::spread`, plus 0.1% and 10⁻⁵), with the mean over the centroids of its four
/// midpoint sub-triangles (see the module's doc). Each receiver is measured on its own, in parallel, and
/// written in place, so the result does not depend on threads. `seed` turns each hemicube about its
/// normal; `offset` lifts the eye off the surface.
pub fn measure_links(
    scene: &CutScene,
    links: &mut Links,
    settings: LinkHemicubes,
    seed: u64,
    offset: f32,
) -> LinkHemicubeStats {
    let nodes = scene.nodes;
    let hc = Hemicube::new(settings.resolution_px);
    let receivers = receivers(nodes, links);
    let links_ref: &Links = links;
    // Per receiver: (link, F) of its far links, polygons drawn, hemicubes drawn.
    type Measured = (Vec<(usize, f32)>, u32, u32);
    let measured: Vec<Measured> = receivers
        .par_iter()
        .map_init(
            || LinkCutScratch::new(&hc, nodes.len()),
            |scratch, &r| {
                let far: Vec<usize> =
                    links_ref.range(r).filter(|&k| is_far(nodes, r, links_ref.source[k] as usize)).collect();
                if far.is_empty() {
                    return (Vec::new(), 0, 0);
                }
                let sources: Vec<u32> = far.iter().map(|&k| links_ref.source[k]).collect();
                let turn = crate::rng::splitmix64(seed ^ (r as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15));
                let rotation = (turn >> 40) as f32 / (1u64 << 24) as f32 * std::f32::consts::TAU;
                let n = nodes.normal[r];
                let mut f = vec![0f64; sources.len()];
                let draw = |scratch: &mut LinkCutScratch, p: Vec3, rotation: f32, f: &mut [f64]| {
                    let eye = leave_surface(p, n, offset);
                    source_form_factors_at(scene, &hc, scratch, eye, n, rotation, settings.cut_pixels, &sources, f)
                };
                let mut drawn = draw(scratch, nodes.centre[r], rotation, &mut f);
                let mut hemicubes = 1u32;
                let disagrees = far.iter().zip(&f).any(|(&k, &fh)| {
                    let fo = links_ref.form_factor[k] as f64;
                    (fh - fo).abs() > links_ref.spread[k] as f64 + 1e-3 * fo.max(fh) + 1e-5
                });
                if disagrees {
                    let [a, b, c] = nodes.corners[r];
                    for p in [(4.0 * a + b + c) / 6.0, (a + 4.0 * b + c) / 6.0, (a + b + 4.0 * c) / 6.0] {
                        drawn += draw(scratch, p, rotation, &mut f);
                        hemicubes += 1;
                    }
                    f.iter_mut().for_each(|x| *x *= 0.25);
                }
                (far.into_iter().zip(f).map(|(k, f)| (k, f as f32)).collect(), drawn, hemicubes)
            },
        )
        .collect();
    let mut stats = LinkHemicubeStats::default();
    for (factors, drawn, hemicubes) in measured {
        if factors.is_empty() {
            continue;
        }
        stats.receivers += 1;
        stats.hemicubes += hemicubes as u64;
        stats.links += factors.len() as u64;
        stats.polygons += drawn as u64;
        for (k, f) in factors {
            links.form_factor[k] = f;
        }
    }
    stats
}
