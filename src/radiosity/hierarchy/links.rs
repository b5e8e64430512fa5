//! Links between nodes (Hanrahan, Salzman and Aupperle 1991): a receiver gathers F·B from each source
//! it is linked to. Stored by receiver in compressed rows; `estimate` picks the estimator by link type
//! (see `form_factor` for which one serves which).

use super::form_factor::{
    cluster_form_factor, cluster_form_factor_bound, element_projected_area, element_to_element, projected_area,
};
use super::nodes::Nodes;
use super::visibility::{visible_fraction, VisibilityContext};

/// A link while refining: receiver, source, form factor and its error spread.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinkRecord {
    pub receiver: u32,
    pub source: u32,
    /// F_RS: the gathering coefficient, B_R gets ρ_R·F_RS·B_S.
    pub form_factor: f32,
    /// Estimated error of `form_factor` (dimensionless, same unit as F).
    pub spread: f32,
}

/// Bytes one stored link costs (its record while refining), for the memory budget.
pub const LINK_BYTES: usize = std::mem::size_of::<LinkRecord>();

/// The links of the hierarchy by receiver (compressed rows): the links of receiver r are
/// `offsets[r] .. offsets[r + 1]`.
#[derive(Clone, Debug, Default)]
pub struct Links {
    pub offsets: Vec<u32>,
    pub source: Vec<u32>,
    pub form_factor: Vec<f32>,
    pub spread: Vec<f32>,
}

impl Links {
    /// Rows from records, grouped by receiver; the order within a receiver is the records' order, so
    /// equal inputs give equal rows.
    pub fn from_records(node_count: usize, mut records: Vec<LinkRecord>) -> Links {
        records.sort_by_key(|l| l.receiver);
        let mut offsets = vec![0u32; node_count + 1];
        for l in &records {
            offsets[l.receiver as usize + 1] += 1;
        }
        for i in 0..node_count {
            offsets[i + 1] += offsets[i];
        }
        Links {
            offsets,
            source: records.iter().map(|l| l.source).collect(),
            form_factor: records.iter().map(|l| l.form_factor).collect(),
            spread: records.iter().map(|l| l.spread).collect(),
        }
    }

    pub fn len(&self) -> usize {
        self.source.len()
    }

    pub fn is_empty(&self) -> bool {
        self.source.is_empty()
    }

    pub fn range(&self, receiver: usize) -> std::ops::Range<usize> {
        if receiver + 1 >= self.offsets.len() {
            return 0..0;
        }
        self.offsets[receiver] as usize..self.offsets[receiver + 1] as usize
    }

    /// The records back, receiver by receiver.
    pub fn to_records(&self) -> Vec<LinkRecord> {
        let mut out = Vec::with_capacity(self.len());
        for r in 0..self.offsets.len().saturating_sub(1) {
            for k in self.range(r) {
                out.push(LinkRecord {
                    receiver: r as u32,
                    source: self.source[k],
                    form_factor: self.form_factor[k],
                    spread: self.spread[k],
                });
            }
        }
        out
    }

    pub fn memory_bytes(&self) -> usize {
        self.offsets.len() * 4 + self.len() * 12
    }
}

/// The error of a link's transfer, in exitance units (W/m²): ε_RS = ρ_R · B_S · ΔF_RS, the BF criterion
/// of Hanrahan, Salzman and Aupperle (1991) with the form factor replaced by its error estimate ΔF.
/// ρ is the receiver's area-averaged largest channel and B the mean channel of the source's exitance.
/// Refinement compares it with ε × the brightest emitter's exitance, so every receiver is resolved to
/// the same relative accuracy whatever its size (down to the minimum element area).
pub fn link_error(nodes: &Nodes, receiver: usize, source: usize, spread: f32) -> f64 {
    nodes.reflectance_max[receiver] as f64 * nodes.exitance_mean[source] * spread as f64
}

/// The power a link's error stands for (W): A_R · `link_error`. Summed over all links it is the
/// global error estimate; refinement never raises that sum at a fixed exitance, because a child link's
/// spread is capped by its parent's (receiver split, Σ A_r = A_R and ρ is area-averaged) or by its
/// share A_s/A_S of it (source split, B_S is the area-weighted mean of the children's B).
pub fn link_error_power(nodes: &Nodes, receiver: usize, source: usize, spread: f32) -> f64 {
    nodes.area[receiver] as f64 * link_error(nodes, receiver, source, spread)
}

/// Whether the point-to-point cluster formula may stand for link (receiver ← source) at all: always
/// for two elements (their estimator is exact in the source); with a cluster end, only when the ends'
/// bounding spheres are disjoint and neither sphere crosses an element end's plane. Refinement splits
/// an inadmissible link whatever its error, so that no near pair of clusters is ever linked with a
/// meaningless form factor (their sum could exceed 1 and the sweeps diverge).
pub fn admissible(nodes: &Nodes, receiver: usize, source: usize) -> bool {
    if !nodes.is_cluster[receiver] && !nodes.is_cluster[source] {
        return true;
    }
    let d = nodes.centre[receiver].distance(nodes.centre[source]);
    if !(d > nodes.radius[receiver] + nodes.radius[source]) {
        return false;
    }
    let straddles = |element: usize, other: usize| {
        !nodes.is_cluster[element]
            && nodes.normal[element].dot(nodes.centre[other] - nodes.centre[element]).abs() < nodes.radius[other]
    };
    !(straddles(receiver, source) || straddles(source, receiver))
}

/// Estimates the form factor of link (receiver ← source) and its error spread; `None` when nothing can
/// pass (the ends face away from each other, or no ray gets through and the estimate is reliable).
///
/// - Element ← element: F = V · (1/3) Σ_k F_Lambert(x_k → S) over the receiver's quadrature points;
///   ΔF = V·ΔF_quadrature + 2·F̄·min(V, 1 − V) (receiver quadrature error, see
///   `form_factor::element_to_element`, plus partial visibility).
/// - With a cluster at either end: F = V · P_S P_R / (π d² A_R) (Sillion 1995), ΔF = the bound
///   `cluster_form_factor_bound` times max(V, 1/(N+1)): the approximation itself is the error, as in
///   the BF criterion; the bound is 1 when the ends' bounding spheres overlap or a sphere crosses an
///   element end's plane.
pub fn estimate(nodes: &Nodes, ctx: &VisibilityContext, receiver: usize, source: usize) -> Option<(f32, f32)> {
    if !nodes.is_cluster[receiver] && !nodes.is_cluster[source] {
        let (mean, error) =
            element_to_element(&nodes.corners[receiver], nodes.normal[receiver], &nodes.corners[source]);
        if !(mean > 0.0 || error > 0.0) {
            return None;
        }
        let v = visible_fraction(ctx, nodes, receiver, source) as f64;
        if v == 0.0 {
            return None;
        }
        let f = mean * v;
        let spread = error * v + 2.0 * mean * v.min(1.0 - v);
        return Some((f as f32, spread as f32));
    }
    let (cr, cs) = (nodes.centre[receiver], nodes.centre[source]);
    let offset = cr - cs;
    let d = offset.length();
    let towards_receiver = if d > 0.0 { offset / d } else { glam::Vec3::ZERO };
    let projected = |node: usize, towards| {
        if nodes.is_cluster[node] {
            projected_area(&nodes.projected_bins[node], towards)
        } else {
            element_projected_area(nodes.normal[node], nodes.area[node], towards)
        }
    };
    let ps = projected(source, towards_receiver);
    let pr = projected(receiver, -towards_receiver);
    let f = cluster_form_factor(ps, pr, nodes.area[receiver], d);
    let bound = if !admissible(nodes, receiver, source) {
        1.0
    } else {
        cluster_form_factor_bound(f, d, nodes.radius[receiver] + nodes.radius[source])
    };
    if !(bound > 0.0) {
        return None;
    }
    let v = visible_fraction(ctx, nodes, receiver, source) as f64;
    if v == 0.0 && bound < 1.0 {
        return None;
    }
    let spread = bound * v.max(1.0 / (ctx.rays as f64 + 1.0));
    Some(((f * v) as f32, spread as f32))
}
