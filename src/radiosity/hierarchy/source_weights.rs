//! What a link reads from a subdivided element source (session 16): its source's children weighted by
//! how the receiver sees each of them, instead of their area mean.
//!
//! A link (R ← S) carries F_RS and, until session 16, sent S's open-area mean exitance B_S = Σ_k
//! A_open,k B_k / Σ_k A_open,k (`gather::pulled`). The exact transfer is Σ_leaves F(R → S_l)·B_l: the
//! mean gives each part of the source the weight of its area, the receiver sees each part by its
//! form factor. Where the exitance varies over S the two differ, and in a room the bright parts of a
//! source are the ones its receivers see best (a wall's strip along a lit floor): every element
//! link's bias was below its refinement threshold, but all had one sign, and the rotunda's room was
//! 1–2% short of cosine rays reading the same leaf exitance (session 15, docs/accuracy.md). So a link
//! whose source is a subdivided element sends
//!
//! B̂_S = Σ_k w_k·B_k,  w_k = F(R → S_k)·(A_open,k/A_k) / Σ_j F(R → S_j)·(A_open,j/A_j),
//!
//! over the source's four children S_k (one level: the variation below them stays averaged; two
//! levels, the grandchildren where a child is subdivided, were measured at +37% CPU-s on the vault
//! hall for 0.6% of relMSE more, session 16). The w_k are stored as bytes q_k/255 with Σ q_k = 255,
//! so a uniform source sends its exitance exactly (up to f64 rounding) and the link's power stays
//! A_R·F_RS·B̂_S, which push-pull conserves as before.
//!
//! F(R → S_k) by Lambert's exact `point_to_polygon` in the source, over receiver points
//! (`receiver_points`: the centroid of a far element receiver, 12 points of a near one; all four
//! children at once by `form_factor::point_to_quarters`, which shares their edges); for a
//! cluster receiver from its centre, turned towards the source's centre. Visibility is the link's,
//! shared by the children.
//!
//! Depends on the geometry only (the receiver, the source's children and their open areas), and a
//! subdivision is never undone, so a refinement pass copies the weights of the links it kept
//! (`SourceWeights::reusing`); the links files and solved states need no new field (the weights
//! are recomputed from the nodes after a load, like `gather::ArrivalScales`).

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use super::form_factor::{point_to_polygon, point_to_quarters, point_to_source, quadrature_points, Quarters, Source};
use super::links::Links;
use super::nodes::Nodes;

/// Whether link (receiver ← source) reads its source's children: the source is a subdivided element
/// (four children) and not the receiver.
pub fn weighs(nodes: &Nodes, receiver: usize, source: usize) -> bool {
    receiver != source && !nodes.is_cluster[source] && nodes.children(source).len() == 4
}

/// Whether two triangles are near each other as the element estimator judges it
/// (`form_factor::element_six_points`): centre distance below 1.5 × the sum of their bounding radii.
fn is_near_pair(a: &[Vec3; 3], b: &[Vec3; 3]) -> bool {
    let centre = |t: &[Vec3; 3]| (t[0] + t[1] + t[2]) / 3.0;
    let radius = |t: &[Vec3; 3], c: Vec3| t.iter().map(|p| p.distance(c)).fold(0.0f32, f32::max);
    let (ca, cb) = (centre(a), centre(b));
    ca.distance(cb) < 1.5 * (radius(a, ca) + radius(b, cb))
}

/// The receiver points the weights are taken at (equal weights: only ratios matter): its centroid
/// for a far pair, where the children's form factors vary little over the receiver; for a near pair
/// the three-point rule (`form_factor::quadrature_points`) on each of its four midpoint
/// sub-triangles (12 points), which follows a source piece along a shared edge, where the integrand
/// is log-singular, better than one point and at a quarter of the 48-point `near_quadrature`'s cost.
fn receiver_points<'a>(corners: &[Vec3; 3], near: bool, out: &'a mut [Vec3; 12]) -> &'a [Vec3] {
    if !near {
        out[0] = (corners[0] + corners[1] + corners[2]) / 3.0;
        return &out[..1];
    }
    let [a, b, c] = *corners;
    let (ab, bc, ca) = ((a + b) * 0.5, (b + c) * 0.5, (c + a) * 0.5);
    for (i, t) in [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]].iter().enumerate() {
        out[3 * i..3 * i + 3].copy_from_slice(&quadrature_points(t));
    }
    &out[..]
}

/// The weights q_k (Σ q_k = 255, or all 0 when the receiver sees no open child) of link (receiver ←
/// source) over the source's four children; see the module's doc.
pub fn child_weights(nodes: &Nodes, receiver: usize, source: usize) -> [u8; 4] {
    let first = nodes.first_child[source] as usize;
    let children = [first, first + 1, first + 2, first + 3];
    let mut f = [0.0f64; 4];
    if nodes.is_cluster[receiver] {
        let towards = (nodes.centre[source] - nodes.centre[receiver]).normalize_or_zero();
        if towards != Vec3::ZERO {
            for (fk, p) in f.iter_mut().zip(children) {
                *fk = point_to_polygon(nodes.centre[receiver], towards, &nodes.corners[p]);
            }
        }
    } else {
        let (corners, normal) = (&nodes.corners[receiver], nodes.normal[receiver]);
        let mut points = [Vec3::ZERO; 12];
        let points = receiver_points(corners, is_near_pair(corners, &nodes.corners[source]), &mut points);
        let corners_of = children.map(|p| nodes.corners[p]);
        match Quarters::new(&corners_of) {
            Some(quarters) => {
                // Σ over the points in the same order as one child at a time.
                for &x in points {
                    for (fk, value) in f.iter_mut().zip(point_to_quarters(x, normal, &quarters)) {
                        *fk += value;
                    }
                }
            }
            None => {
                for (fk, corners) in f.iter_mut().zip(&corners_of) {
                    let child = Source::new(corners);
                    *fk = points.iter().map(|&x| point_to_source(x, normal, &child)).sum();
                }
            }
        }
    }
    for (fk, p) in f.iter_mut().zip(children) {
        let (open, area) = (nodes.open_area[p] as f64, nodes.area[p] as f64);
        *fk = if open > 0.0 && area > 0.0 && fk.is_finite() { fk.max(0.0) * open / area } else { 0.0 };
    }
    quantised_shares(f)
}

/// q_k = round(255·f_k/Σf) with Σ q_k = 255 exactly (largest remainders, ties to the lower index), or
/// zeros when Σf is 0.
pub fn quantised_shares(f: [f64; 4]) -> [u8; 4] {
    let total: f64 = f.iter().sum();
    if !(total > 0.0) {
        return [0; 4];
    }
    let scaled = f.map(|x| 255.0 * x / total);
    let mut q = scaled.map(|x| x.floor().clamp(0.0, 255.0) as u8);
    let mut left = 255u32.saturating_sub(q.iter().map(|&x| x as u32).sum());
    while left > 0 {
        let remainder = |k: usize| scaled[k] - q[k] as f64;
        let best = (1..4).fold(0, |best, k| if remainder(k) > remainder(best) { k } else { best });
        q[best] += 1;
        left -= 1;
    }
    q
}

/// The weights of every link that `weighs`, by receiver in `Links` order: one entry per such link
/// (its source and its children's bytes). 4 bytes per node and 8 per weighed link.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SourceWeights {
    /// Per node (and one past the last): its first entry.
    offsets: Vec<u32>,
    /// Per entry: the link's source.
    source: Vec<u32>,
    /// Per entry: q_k of the source's children.
    weight: Vec<[u8; 4]>,
}

/// Receivers whose weights are computed in parallel at a time.
const BLOCK: usize = 1024;

impl SourceWeights {
    /// The weights of `links`, copying those of a link of the same receiver and source from
    /// `previous`; receivers in parallel, each in link order, so the result does not depend on
    /// threads.
    pub fn reusing(nodes: &Nodes, links: &Links, previous: Option<&SourceWeights>) -> SourceWeights {
        let node_count = links.offsets.len().saturating_sub(1);
        let mut out = SourceWeights { offsets: vec![0; node_count + 1], ..Default::default() };
        let receivers: Vec<usize> = (0..node_count).collect();
        for block in receivers.chunks(BLOCK) {
            let rows: Vec<(Vec<u32>, Vec<[u8; 4]>)> =
                block.par_iter().map(|&r| receiver_weights(nodes, links, r, previous)).collect();
            for (&r, (source, weight)) in block.iter().zip(rows) {
                out.offsets[r + 1] = source.len() as u32;
                out.source.extend_from_slice(&source);
                out.weight.extend_from_slice(&weight);
            }
        }
        for r in 0..node_count {
            out.offsets[r + 1] += out.offsets[r];
        }
        out.source.shrink_to_fit();
        out.weight.shrink_to_fit();
        out
    }

    /// The entries of receiver `r`.
    fn entries(&self, r: usize) -> std::ops::Range<usize> {
        if r + 1 >= self.offsets.len() {
            return 0..0;
        }
        self.offsets[r] as usize..self.offsets[r + 1] as usize
    }

    /// The exitance entry `e` (source `source`) sends: Σ_k q_k·values[S_k]/255, or values[source]
    /// when its weights are all 0.
    pub fn sent_by_entry(&self, nodes: &Nodes, e: usize, source: usize, values: &[DVec3]) -> DVec3 {
        let q = self.weight[e];
        if q == [0; 4] {
            return values[source];
        }
        let first = nodes.first_child[source] as usize;
        let sum: DVec3 = q.iter().enumerate().map(|(k, &w)| values[first + k] * w as f64).sum();
        sum / 255.0
    }

    /// The exitance link `k` of receiver `r` sends (a linear search over the receiver's entries, for
    /// reports; `gather::gather_into` walks them in order).
    pub fn sent(&self, nodes: &Nodes, links: &Links, r: usize, k: usize, values: &[DVec3]) -> DVec3 {
        let s = links.source[k] as usize;
        if !weighs(nodes, r, s) {
            return values[s];
        }
        match self.entries(r).find(|&e| self.source[e] as usize == s) {
            Some(e) => self.sent_by_entry(nodes, e, s, values),
            None => values[s],
        }
    }

    /// A cursor over receiver `r`'s entries in link order: `gather::gather_into` asks it for each
    /// link in turn.
    pub fn cursor(&self, r: usize) -> Cursor<'_> {
        let entries = self.entries(r);
        Cursor { weights: self, next: entries.start, end: entries.end }
    }

    pub fn memory_bytes(&self) -> usize {
        self.offsets.len() * 4 + self.source.len() * 4 + self.weight.len() * 4
    }
}

/// The entries of one receiver, walked with its links in order (`SourceWeights::cursor`).
pub struct Cursor<'a> {
    weights: &'a SourceWeights,
    next: usize,
    end: usize,
}

impl Cursor<'_> {
    /// The exitance the receiver's next link (source `source`) sends: its children by the entry's
    /// weights when it `weighs` (the next entry), else values[source].
    pub fn sent(&mut self, nodes: &Nodes, receiver: usize, source: usize, values: &[DVec3]) -> DVec3 {
        if !weighs(nodes, receiver, source) || self.next >= self.end {
            return values[source];
        }
        let e = self.next;
        self.next += 1;
        debug_assert_eq!(self.weights.source[e] as usize, source);
        self.weights.sent_by_entry(nodes, e, source, values)
    }
}

/// (sources, weights) of receiver `r`'s weighed links.
fn receiver_weights(
    nodes: &Nodes,
    links: &Links,
    r: usize,
    previous: Option<&SourceWeights>,
) -> (Vec<u32>, Vec<[u8; 4]>) {
    let (mut sources, mut weights) = (Vec::new(), Vec::new());
    let mut known: Vec<(u32, usize)> = match previous {
        Some(p) => p.entries(r).map(|e| (p.source[e], e)).collect(),
        None => Vec::new(),
    };
    known.sort_unstable();
    for k in links.range(r) {
        let s = links.source[k] as usize;
        if !weighs(nodes, r, s) {
            continue;
        }
        let old = previous.and_then(|p| {
            let i = known.binary_search_by_key(&(s as u32), |&(source, _)| source).ok()?;
            Some(p.weight[known[i].1])
        });
        weights.push(old.unwrap_or_else(|| child_weights(nodes, r, s)));
        sources.push(s as u32);
    }
    (sources, weights)
}
