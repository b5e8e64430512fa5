//! Links between nodes (Hanrahan, Salzman and Aupperle 1991): a receiver gathers F·B from each source
//! it is linked to. Stored by receiver in compressed rows; `estimate` picks the estimator by link type
//! (see `form_factor` for which one serves which).

use super::form_factor::{
    cluster_form_factor, cluster_form_factor_bound, element_six_points, element_to_element, near_quadrature,
    triangle_to_polygon,
};
use super::nodes::Nodes;
use super::visibility::{
    link_visibility, link_visibility_with, sampled_form_factor, visibility_spread, Visibility, VisibilityContext,
    BLOCKED_CONFIRM_FACTOR,
};

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
    ///
    /// A stable counting sort by receiver (count, prefix sum, scatter): O(links + nodes) and no copy
    /// of the records beside the rows it fills (a parallel merge sort held one: +16 bytes per link).
    pub fn from_records(node_count: usize, records: Vec<LinkRecord>) -> Links {
        let mut offsets = vec![0u32; node_count + 1];
        for l in &records {
            offsets[l.receiver as usize + 1] += 1;
        }
        for i in 0..node_count {
            offsets[i + 1] += offsets[i];
        }
        let mut next = offsets[..node_count].to_vec();
        let (mut source, mut form_factor, mut spread) =
            (vec![0u32; records.len()], vec![0f32; records.len()], vec![0f32; records.len()]);
        for l in &records {
            let slot = &mut next[l.receiver as usize];
            let k = *slot as usize;
            *slot += 1;
            source[k] = l.source;
            form_factor[k] = l.form_factor;
            spread[k] = l.spread;
        }
        Links { offsets, source, form_factor, spread }
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

/// The error of a link's transfer in watts, the BF criterion of Hanrahan, Salzman and Aupperle (1991)
/// as a power:
///
/// ε_RS = A_R · ρ_R · B_S · ΔF_RS,
///
/// ρ_R the receiver's area-averaged largest reflectance channel, B_S the mean channel of the source's
/// (area-averaged) exitance, ΔF the form factor's error estimate (`LinkRecord::spread`). It is the
/// reflected power the link may get wrong. Refinement compares it with ε × the scene's emitted power,
/// so a dark link (B_S = 0 or ρ_R = 0) is never refined, and the number of links a scene needs does not
/// grow with its triangle count: small receivers carry little power.
///
/// Summed over all links it is the global error estimate. Splitting a far or element link does not
/// raise that sum at a fixed exitance, because a child link's spread is capped by its parent's
/// (receiver split: Σ A_r ρ_r = A_R ρ_R, ρ being area-averaged) or by its share A_s/A_S of it
/// (source split: B_S is the area-weighted mean of the children's B). A near child measures its
/// own deviation (`near_estimate`) and may raise it: its parent's spread understated the error.
///
/// A receiver with no open area (`Nodes::open_area`: all of it inside an object resting on it) has
/// error 0: nothing its links bring lands (`gather::on_open_part`), so it is never refined.
pub fn link_error_power(nodes: &Nodes, receiver: usize, source: usize, spread: f32) -> f64 {
    if !(nodes.open_area[receiver] > 0.0) {
        return 0.0;
    }
    nodes.area[receiver] as f64 * nodes.reflectance_max[receiver] as f64 * nodes.exitance_mean[source] * spread as f64
}

/// The part of a link's error that comes from the source's exitance varying over it (W):
/// A_R · ρ_R · c · max_k |B_k − B_S| over the source's children k (0 for a leaf source), with c the
/// form factor of a far link or the spread (bound) of a near one. Splitting the source removes it.
/// Children with no open area send nothing and do not count (their darkness is no variation of what
/// the source sends); a receiver with no open area has none (see `link_error_power`).
pub fn source_variation_power(nodes: &Nodes, receiver: usize, source: usize, coefficient: f32) -> f64 {
    if !(nodes.open_area[receiver] > 0.0) {
        return 0.0;
    }
    let b = nodes.exitance_mean[source];
    let spread = nodes
        .children(source)
        .filter(|&c| nodes.open_area[c] > 0.0)
        .map(|c| (nodes.exitance_mean[c] - b).abs())
        .fold(0.0, f64::max);
    if !(spread > 0.0) {
        // Also when the coefficient is not known (an element link left unestimated because it is
        // split, `estimate`: NaN).
        return 0.0;
    }
    nodes.area[receiver] as f64 * nodes.reflectance_max[receiver] as f64 * coefficient as f64 * spread
}

/// Whether a link is *near*: a cluster's self-link, or a link with a cluster end that is not
/// `admissible` for the cluster formula. Near links are estimated leaf pair by leaf pair or by
/// sampling (`near_estimate`); their error is the bound `near_spread` capped by the parent link's
/// share, or the estimate's deviation over the receiver where that is larger (`estimate`).
pub fn is_near(nodes: &Nodes, receiver: usize, source: usize) -> bool {
    receiver == source || !admissible(nodes, receiver, source)
}

/// The form-factor bound that stands for a near link's error: F_RS ≤ 1 (the irradiance from a
/// uniform source never exceeds its exitance) and F_RS = A_S F_SR / A_R ≤ A_S / A_R (reciprocity).
pub fn near_spread(nodes: &Nodes, receiver: usize, source: usize) -> f32 {
    if receiver == source {
        return 1.0;
    }
    let (ar, a_s) = (nodes.area[receiver], nodes.area[source]);
    if ar > 0.0 {
        (a_s / ar).min(1.0)
    } else {
        1.0
    }
}

/// The total error of a link as refinement judges it (W): `link_error_power` plus
/// `source_variation_power`, the latter with the form factor of a far link or the spread of a near one.
pub fn refinement_error(nodes: &Nodes, link: &LinkRecord) -> f64 {
    let (r, s) = (link.receiver as usize, link.source as usize);
    let coefficient = if is_near(nodes, r, s) { link.spread } else { link.form_factor };
    link_error_power(nodes, r, s, link.spread) + source_variation_power(nodes, r, s, coefficient)
}

/// For a near link (`is_near`) about to be split: its spread, the bound `near_spread` capped at
/// `spread_cap`, when the link's error with it exceeds `threshold_w` (`estimate` then leaves F
/// unestimated, NaN); `None` when the link would be kept and needs its form factor. Reads the
/// source's exitance, so unlike the estimate itself it depends on the pass.
pub fn near_split_pending(
    nodes: &Nodes,
    receiver: usize,
    source: usize,
    spread_cap: f32,
    threshold_w: f64,
) -> Option<f32> {
    let spread = near_spread(nodes, receiver, source).min(spread_cap);
    let record = LinkRecord { receiver: receiver as u32, source: source as u32, form_factor: 0.0, spread };
    (refinement_error(nodes, &record) > threshold_w).then_some(spread)
}

/// Whether refinement will split element link (receiver ← source) of spread `spread`, whatever its
/// form factor: its source's exitance does not vary over its children (`source_variation_power`
/// 0, always for a leaf, so the decision reads only the spread: `refine::decide`), its error
/// `link_error_power` is above `threshold_w`, and the receiver can be split (it has children, or
/// its quarters keep at least `min_element_area`: `refine::choose_split`). Reads the exitance, like
/// `near_split_pending`.
pub fn element_split_pending(
    nodes: &Nodes,
    receiver: usize,
    source: usize,
    spread: f32,
    threshold_w: f64,
    min_element_area: f32,
) -> bool {
    let receiver_splits = !nodes.is_leaf(receiver) || nodes.area[receiver] * 0.25 >= min_element_area;
    receiver_splits
        && source_variation_power(nodes, receiver, source, 1.0) == 0.0
        && link_error_power(nodes, receiver, source, spread) > threshold_w
}

/// How far apart (in sums of the ends' radii) a link with a cluster end must be to be far.
///
/// Until session 15 a cluster's sphere boxed its children's spheres, growing up to √3× per level, so
/// "disjoint spheres" meant far apart; with the members' exact box (`Nodes::set_cluster_children`)
/// disjointness alone handed close pairs to the far estimators (rotunda 0.00456 → 0.00444 / 0.00420 →
/// 0.00635, gap_room 0.0111 → 0.0197). Measured on the tight bounds (session 15, docs/accuracy.md):
/// 2 and 4 give the same rotunda and Cornell figures, so 2.
pub const FAR_DISTANCE_FACTOR: f32 = 2.0;

/// Whether the point-to-point cluster formula may stand for link (receiver ← source) at all: always
/// for two elements (their estimator is exact in the source); with a cluster end, only when the
/// centres are more than `FAR_DISTANCE_FACTOR` × the sum of the radii apart and neither sphere crosses
/// an element end's plane. Other links are near (`is_near`).
pub fn admissible(nodes: &Nodes, receiver: usize, source: usize) -> bool {
    if !nodes.is_cluster[receiver] && !nodes.is_cluster[source] {
        return true;
    }
    let d = nodes.centre[receiver].distance(nodes.centre[source]);
    if !(d > FAR_DISTANCE_FACTOR * (nodes.radius[receiver] + nodes.radius[source])) {
        return false;
    }
    let straddles = |element: usize, other: usize| {
        !nodes.is_cluster[element]
            && nodes.normal[element].dot(nodes.centre[other] - nodes.centre[element]).abs() < nodes.radius[other]
    };
    !(straddles(receiver, source) || straddles(source, receiver))
}

/// Estimates the form factor of link (receiver ← source) and its error spread, the spread capped at
/// `spread_cap` (the parent link's share); `None` when nothing can pass: the ends face away from each
/// other, or no ray gets through and the light the rays may have missed is below the threshold
/// (`worth_confirming`). Above it the link is measured again with `BLOCKED_CONFIRM_FACTOR` × N rays,
/// and if they are all blocked too it is kept with F = 0 and the spread of the share they may have
/// missed (`blocked_element_link`, and max(V, 1/(N+1)) below), to be split while that matters.
///
/// - Element ← element: F = V · (1/3) Σ_k F_Lambert(x_k → S) over the receiver's quadrature points;
///   ΔF = V·ΔF_quadrature + 2·F̄·min(V, 1 − V) (receiver quadrature error, see
///   `form_factor::element_to_element`, plus partial visibility, so a significant link in a penumbra
///   is refined); with V = 0, `blocked_element_link`.
/// - Far links with a cluster end: F = V · `member_pair_form_factor` when the ends hold at most
///   `EXACT_NEAR_PAIRS` member pairs, else V · P_S P_R / (π d² A_R) (Sillion 1995) with each end's
///   exact projected area P = Σ A_i max(0, n_i·ω) (`Nodes::projected_area`); ΔF = the bound
///   `cluster_form_factor_bound` times max(V, 1/(N+1)): the approximation itself is the error;
///   plus `push_spread` (a cluster receiver partly hidden from the source), not capped.
/// - Near links kept with an estimated F also add `near_push_spread`.
/// - Near links (`is_near`): the bound b = `near_spread` capped at `spread_cap`. When the link's
///   error with it is above `threshold_w` it is about to be split and F is not estimated (NaN, so
///   that a kept one is caught). Otherwise F and the deviation D over the receiver come from
///   `near_estimate` (leaf pairs or rays), and ΔF = max(min(b, cap), min(b, D)): until session 19
///   ΔF was the capped bound alone, and a near link under one whose spread was small inherited that
///   small error and was kept however much F varied over it (Sponza's nave floor under building-
///   sized clusters, docs/accuracy.md). D alone in place of the capped bound was worse in every
///   room measured (session 19). `None` when no sample pair faces each other.
pub fn estimate(
    nodes: &Nodes,
    ctx: &VisibilityContext,
    receiver: usize,
    source: usize,
    spread_cap: f32,
    threshold_w: f64,
    min_element_area: f32,
) -> Option<(f32, f32)> {
    if !nodes.is_cluster[receiver] && !nodes.is_cluster[source] {
        let (corners_r, normal_r, corners_s) =
            (&nodes.corners[receiver], nodes.normal[receiver], &nodes.corners[source]);
        let (q3, error, near) = element_six_points(corners_r, normal_r, corners_s);
        let near_mean = || if near { near_quadrature(corners_r, normal_r, corners_s) } else { q3 };
        // The mean is needed before the rays only when the six points agree exactly (often all 0).
        let early_mean = (!(error > 0.0)).then(near_mean);
        if early_mean.is_some_and(|mean| !(mean > 0.0)) {
            return None;
        }
        let mut visibility = link_visibility(ctx, nodes, receiver, source);
        if visibility.visible == 0.0 {
            let mean = early_mean.unwrap_or_else(near_mean);
            let (_, spread) = blocked_element_link(error, mean, visibility.rays, spread_cap)?;
            if !worth_confirming(nodes, receiver, source, spread, threshold_w) {
                return None;
            }
            visibility = link_visibility_with(ctx, nodes, receiver, source, ctx.rays * BLOCKED_CONFIRM_FACTOR);
            if visibility.visible == 0.0 {
                return blocked_element_link(error, mean, visibility.rays, spread_cap);
            }
        }
        let v = visibility.visible as f64;
        // The spread below is known without the mean when V = 1 (ΔF = error exactly) or when its
        // lower bound error·V already reaches the cap (the mean only adds to it, f32 rounding is
        // monotone). When it alone sends the link to be split, the 48-point rule is not computed:
        // F is left unestimated (NaN, as for near links about to split; a link kept after all,
        // over the memory budget, gets it from `near_form_factor`).
        let capped = (error * v) as f32 >= spread_cap;
        if near && early_mean.is_none() && (v == 1.0 || capped) {
            let spread = if capped { spread_cap } else { (error as f32).min(spread_cap) };
            if element_split_pending(nodes, receiver, source, spread, threshold_w, min_element_area) {
                return Some((f32::NAN, spread));
            }
        }
        let mean = early_mean.unwrap_or_else(near_mean);
        let f = mean * v;
        let spread = error * v + 2.0 * mean * v.min(1.0 - v);
        return Some((f as f32, (spread as f32).min(spread_cap)));
    }
    if is_near(nodes, receiver, source) {
        if let Some(spread) = near_split_pending(nodes, receiver, source, spread_cap, threshold_w) {
            return Some((f32::NAN, spread));
        }
        let bound = near_spread(nodes, receiver, source);
        let estimate = near_estimate(nodes, ctx, receiver, source)?;
        let spread = bound.min(spread_cap).max(estimate.deviation.min(bound));
        let f = estimate.form_factor;
        return Some((f, spread + near_push_spread(nodes, ctx, receiver, source, f)));
    }
    let (cr, cs) = (nodes.centre[receiver], nodes.centre[source]);
    let offset = cr - cs;
    let d = offset.length();
    let towards_receiver = if d > 0.0 { offset / d } else { glam::Vec3::ZERO };
    let f = match member_pair_form_factor(nodes, receiver, source) {
        Some(f) => f,
        None => {
            let ps = nodes.projected_area(source, towards_receiver);
            let pr = nodes.projected_area(receiver, -towards_receiver);
            cluster_form_factor(ps, pr, nodes.area[receiver], d)
        }
    };
    let bound = cluster_form_factor_bound(f, d, nodes.radius[receiver] + nodes.radius[source]);
    if !(bound > 0.0) {
        return None;
    }
    // Every ray blocked: V may still be up to about 1/(rays + 1), which the spread keeps (see
    // `blocked_element_link`).
    let spread_of = |visibility: Visibility| {
        let least = 1.0 / (visibility.rays.max(1) as f64 + 1.0);
        ((bound * (visibility.visible as f64).max(least)) as f32).min(spread_cap)
    };
    let mut visibility = link_visibility(ctx, nodes, receiver, source);
    if visibility.visible == 0.0 {
        if worth_confirming(nodes, receiver, source, spread_of(visibility), threshold_w) {
            visibility = link_visibility_with(ctx, nodes, receiver, source, ctx.rays * BLOCKED_CONFIRM_FACTOR);
        } else if bound < 1.0 {
            return None;
        }
    }
    let v = visibility.visible as f64;
    let spread = spread_of(visibility);
    Some(((f * v) as f32, spread + push_spread(nodes, receiver, f, visibility) as f32))
}

/// An element link none of whose `rays` visibility rays passed: F = 0, but a pair whose true share is
/// V passes none of them with probability (1 − V)^rays. Its spread is therefore that of V ≤
/// 1/(rays + 1), the share a clear shaft shows one ray in rays + 1 of:
///
/// ΔF = (ΔF₆ + 2·F_unoccluded) / (rays + 1),
///
/// ΔF₆ the six-point spread (`element_six_points`). `None` when there is no unoccluded transfer.
fn blocked_element_link(six_point_spread: f64, unoccluded: f64, rays: u32, spread_cap: f32) -> Option<(f32, f32)> {
    if !(unoccluded > 0.0) {
        return None;
    }
    let possible = 1.0 / (rays.max(1) as f64 + 1.0);
    let spread = (six_point_spread + 2.0 * unoccluded) * possible;
    Some((0.0, (spread as f32).min(spread_cap)))
}

/// Whether a link none of whose N rays passed is measured again with `BLOCKED_CONFIRM_FACTOR` × N
/// rays rather than dropped: when the light its rays may have missed, its spread `spread` for V ≤
/// 1/(N + 1), is an error refinement would act on (`link_error_power` above `threshold_w`). A link
/// still blocked after those is kept with F = 0 and the smaller spread of V ≤ 1/(4N + 1).
///
/// Until session 40 such a link was dropped after N rays: a pair whose true share V is a fifth
/// passes none of 8 rays one time in six, and its light was lost unsplit. vault_hall's walls took
/// 2.5% too little direct light over the links at 8 rays (11.4% at 4, 0.1% at 16); its radiosity-mode
/// relMSE (seed 0) went 2.49e-3 → 1.92e-3 and gap_room's 1.13e-2 → 8.33e-3, for +14% CPU-s and +8% links on Sponza.
/// Measuring every such link again gave 1.81e-3 and 8.65e-3 for +40% CPU-s on Sponza; keeping every
/// one unconfirmed with F = 0 (session 39's branch) cost 28% more links there and changed nothing in
/// the rooms (docs/accuracy.md, session 40).
fn worth_confirming(nodes: &Nodes, receiver: usize, source: usize, spread: f32, threshold_w: f64) -> bool {
    link_error_power(nodes, receiver, source, spread) > threshold_w
}

/// The unoccluded form factor of a far link whose ends hold at most `EXACT_NEAR_PAIRS` member pairs
/// (`Nodes::members`: a cluster's input triangles, an element itself):
///
/// F_RS = Σ_i A_i Σ_σ F_3(i ← σ) / A_R,
///
/// F_3 the element estimator's three-point receiver rule (`form_factor::triangle_to_polygon`, exact
/// in the source) over every pair: each member's own distance and orientation to the source, which
/// the point-to-point cluster formula misses when the ends are a few radii apart (the Cornell box's
/// short block's front face took 1.7× its light from red-wall elements at a grazing angle through
/// it, session 13). `None` for larger ends (the cluster formula serves them).
pub fn member_pair_form_factor(nodes: &Nodes, receiver: usize, source: usize) -> Option<f64> {
    let (mut rs, mut ss) = (Vec::new(), Vec::new());
    if !nodes.member_count_within(receiver, EXACT_NEAR_PAIRS) {
        return None;
    }
    nodes.members(receiver, &mut rs);
    if !nodes.member_count_within(source, EXACT_NEAR_PAIRS / rs.len().max(1)) {
        return None;
    }
    nodes.members(source, &mut ss);
    let mut sum = 0.0f64;
    for &r in &rs {
        for &s in &ss {
            if nodes.input[r] != nodes.input[s] {
                sum +=
                    nodes.area[r] as f64 * triangle_to_polygon(&nodes.corners[r], nodes.normal[r], &nodes.corners[s]);
            }
        }
    }
    Some((sum / nodes.area[receiver] as f64).min(1.0))
}

/// The error of pushing a link's irradiance to everything below its receiver that faces the source
/// when part of it is hidden from the source (ΔF, same unit as F; `unoccluded` is the link's form
/// factor before visibility, V = `Visibility::visible`, the unoccluded share of the sample pairs that
/// face each other):
///
/// - cluster receiver, 0 < V < 1: ΔF = F·max(1, (1 − V)/V), F = V·F_unoccluded. The gather already
///   sends a cluster's incoming light only to the members that face its direction, each by its own
///   cosine (`gather`), so members facing away are not wrong; but of the facing members only the share V is
///   reached, and the push lights the hidden ones too: their exitance is wrong by ρ·G and the
///   reached part's by ρ·G·(1 − V)/V. Applying the exitance criterion ρ·B_S·ΔF ≤ ε·Ē to the worse
///   part keeps light from leaking past a wall into members on its far side that face the source
///   (a floor behind a wall). 0 when V = 1;
/// - element receiver: ΔF = 2·F_unoccluded·min(V, 1 − V), the partial-visibility term of element
///   links (a penumbra across the element: blur, not a leak).
///
/// Measured with the link's own rays, it is added to the estimator's spread without the parent's
/// cap, so a partly hidden receiver is split while the error matters.
///
/// Until session 5 the cluster term used the share of *all* receiver samples reached (members facing
/// away counted as unreached), which refined every cluster of a convex object (about half its members
/// face away from any source): procedural:16000 took 44 CPU-s and 2.69 M links; with V, 20 CPU-s and
/// 1.56 M links, and gap_room's radiosity relMSE went 0.0595 → 0.0514 (docs/performance.md).
pub fn push_spread(nodes: &Nodes, receiver: usize, unoccluded: f64, visibility: Visibility) -> f64 {
    let v = visibility.visible as f64;
    if !nodes.is_cluster[receiver] {
        return 2.0 * unoccluded * v.min(1.0 - v);
    }
    if !(v > 0.0 && v < 1.0) {
        return 0.0;
    }
    unoccluded * v * ((1.0 - v) / v).max(1.0)
}

/// `push_spread` of a near link whose form factor `form_factor` is estimated (F after visibility):
/// 0 for an element receiver (the near bound already covers it), else measured with the link's rays.
pub fn near_push_spread(
    nodes: &Nodes,
    ctx: &VisibilityContext,
    receiver: usize,
    source: usize,
    form_factor: f32,
) -> f32 {
    if !nodes.is_cluster[receiver] || !(form_factor > 0.0) {
        return 0.0;
    }
    let visibility = link_visibility(ctx, nodes, receiver, source);
    if !(visibility.visible > 0.0) {
        return 0.0;
    }
    push_spread(nodes, receiver, form_factor as f64 / visibility.visible as f64, visibility) as f32
}

/// Near links whose ends hold at most this many leaf-element pairs are integrated pair by pair.
pub const EXACT_NEAR_PAIRS: usize = 64;

/// The form factor of a near link that is kept; `None` when its ends cannot exchange light.
///
/// - At most `EXACT_NEAR_PAIRS` leaf pairs: F = V · Σ_r A_r Σ_s F_elem(r ← s) / A_R, the element
///   estimator (Lambert exact in the source, three-point rule over the receiver) over every pair of
///   leaf elements below the two ends, times the ray visibility fraction of the link; `None` when
///   every pair's F is 0.
/// - Larger: `visibility::sampled_form_factor`; `None` when no sample pair faces each other.
pub fn near_form_factor(nodes: &Nodes, ctx: &VisibilityContext, receiver: usize, source: usize) -> Option<f32> {
    near_estimate(nodes, ctx, receiver, source).map(|e| e.form_factor)
}

/// A near link's form factor and its deviation over the receiver (what a uniform F_RS gets wrong).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NearEstimate {
    pub form_factor: f32,
    pub deviation: f32,
}

/// `near_form_factor` with the error a uniform F_RS makes over the receiver, as a form factor:
///
/// - leaf pairs: ΔF = V · Σ_r A_r (|F_r − F̄| + δF_r) / A_R + F̄ · `visibility_spread`(V), F_r =
///   Σ_s F_elem(r ← s) the unoccluded form factor of receiver leaf r, F̄ their area mean and δF_r the
///   element estimator's quadrature error (the variation inside a leaf is the leaf's own error);
/// - rays: `visibility::receiver_deviation` of the samples (`SampledFormFactor::deviation`).
///
/// Refinement reads it as the link's error where it is above the capped bound (`estimate`): a near
/// pair is split where F varies over the receiver (a concave corner inside a cluster, a floor
/// beneath building-sized clusters), however small a spread its parent link had.
pub fn near_estimate(nodes: &Nodes, ctx: &VisibilityContext, receiver: usize, source: usize) -> Option<NearEstimate> {
    let (mut rs, mut ss) = (Vec::new(), Vec::new());
    let small = leaves_below(nodes, receiver, EXACT_NEAR_PAIRS, &mut rs)
        && leaves_below(nodes, source, EXACT_NEAR_PAIRS, &mut ss)
        && rs.len() * ss.len() <= EXACT_NEAR_PAIRS;
    if !small {
        let sampled = sampled_form_factor(ctx, nodes, receiver, source);
        return (sampled.facing > 0)
            .then_some(NearEstimate { form_factor: sampled.form_factor as f32, deviation: sampled.deviation as f32 });
    }
    // Per receiver leaf: its area, Σ_s F_elem(r ← s) and Σ_s of the quadrature errors.
    let mut per_leaf = Vec::with_capacity(rs.len());
    for &r in &rs {
        let (mut f_r, mut error_r) = (0.0f64, 0.0f64);
        for &s in &ss {
            if r != s {
                let (f, error) = element_to_element(&nodes.corners[r], nodes.normal[r], &nodes.corners[s]);
                f_r += f;
                error_r += error;
            }
        }
        per_leaf.push((nodes.area[r] as f64, f_r, error_r));
    }
    let area = nodes.area[receiver] as f64;
    let sum: f64 = per_leaf.iter().map(|&(a, f, _)| a * f).sum();
    if !(sum > 0.0) || !(area > 0.0) {
        return None;
    }
    let mean = sum / area;
    let deviation: f64 = per_leaf.iter().map(|&(a, f, error)| a * ((f - mean).abs() + error)).sum::<f64>() / area;
    let visibility = link_visibility(ctx, nodes, receiver, source);
    let v = visibility.visible as f64;
    let deviation = v * deviation + mean * visibility_spread(v, visibility.rays);
    Some(NearEstimate { form_factor: (v * mean).min(1.0) as f32, deviation: deviation as f32 })
}

/// What `near_form_factor` of link (receiver ← source) reads of the subdivision below its ends: when
/// it integrates leaf pair by leaf pair (at most `EXACT_NEAR_PAIRS`), the `subdivision_shape` of each
/// end; otherwise `[0, 0]` (the ray-traced estimator samples input triangles, which subdivision does
/// not change). With the ends' tree paths it identifies the estimate exactly: a shard that split
/// fewer elements below an end than the whole solve gets another shape.
pub fn near_leaf_shapes(nodes: &Nodes, receiver: usize, source: usize) -> [u128; 2] {
    let (mut rs, mut ss) = (Vec::new(), Vec::new());
    let small = leaves_below(nodes, receiver, EXACT_NEAR_PAIRS, &mut rs)
        && leaves_below(nodes, source, EXACT_NEAR_PAIRS, &mut ss)
        && rs.len() * ss.len() <= EXACT_NEAR_PAIRS;
    if !small {
        return [0, 0];
    }
    [subdivision_shape(nodes, receiver), subdivision_shape(nodes, source)]
}

/// The 1→4 subdivisions below `node` (which holds at most `EXACT_NEAR_PAIRS` leaves) as a bit string:
/// every element below it in a fixed depth-first order, 1 if it is split and 0 if it is a leaf,
/// clusters passed through without a bit (their children are fixed by the build), then a closing 1.
/// A preorder code of a tree whose splits all have four children is prefix-free, so two shapes below
/// the same node never share a code; 64 leaves need at most 64 + 21 bits.
fn subdivision_shape(nodes: &Nodes, node: usize) -> u128 {
    let (mut code, mut bits) = (0u128, 0u32);
    let mut stack = vec![node];
    while let Some(n) = stack.pop() {
        if !nodes.is_cluster[n] {
            assert!(bits < 127, "more than {EXACT_NEAR_PAIRS} leaves below node {node}");
            code |= (!nodes.is_leaf(n) as u128) << bits;
            bits += 1;
        }
        stack.extend(nodes.children(n));
    }
    code | (1 << bits)
}

/// Collects the leaf elements below `node` into `out`; false (and stops) past `limit` leaves.
pub fn leaves_below(nodes: &Nodes, node: usize, limit: usize, out: &mut Vec<usize>) -> bool {
    let mut stack = vec![node];
    while let Some(n) = stack.pop() {
        if nodes.is_leaf(n) {
            if out.len() == limit {
                return false;
            }
            out.push(n);
        } else {
            stack.extend(nodes.children(n));
        }
    }
    true
}
