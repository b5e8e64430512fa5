//! Gathering over links and push-pull (Hanrahan, Salzman and Aupperle 1991): a node's irradiance is
//! what it gathers over its own links plus what its ancestors gathered (pushed down, as irradiance);
//! an inner node's exitance is the area-weighted mean of its children's (pulled up). A cluster
//! receiver's links arrive from one direction each (`Arrival`), and each member takes that link's
//! light by its own cosine to the direction (Sillion 1995's "immediate" push, here carried down the
//! tree as a list of arrivals and evaluated once per member).

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use super::form_factor::point_to_polygon;
use super::links::{is_near, Links};
use super::lobes::Lobes;
use super::nodes::Nodes;
use super::row_sums::{row_sums, LeafGains};
use super::source_weights::{Cursor, SourceWeights};
use super::visibility::sample_element;

/// Light a cluster receives over one link: a member of unit normal n at position x takes the
/// irradiance `irradiance`·g(n, x), g = `Arrival::weight`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Arrival {
    /// ω: unit direction from the receiver's centre to the source's.
    pub towards: Vec3,
    /// w_l = P_l / D_open,R (W/m²): the link's power P_l = A_R·F_l·B_S over the receiver's members'
    /// open area weighted by g (`ArrivalScales`), the irradiance on a member facing ω head-on at the
    /// receiver's centre.
    pub irradiance: DVec3,
    /// A far link's source as a point (`PointSource`), so that each member takes the light by its
    /// own position; `None`: by its orientation only, g = max(0, n·ω) (a near link, whose ends
    /// overlap).
    pub source: Option<PointSource>,
}

impl Arrival {
    /// An arrival from direction ω only (g = max(0, n·ω) on every member, wherever it is).
    pub fn directional(towards: Vec3, irradiance: DVec3) -> Arrival {
        Arrival { towards, irradiance, source: None }
    }

    /// g of a member of unit normal `normal` at `position`: `PointSource::weight` for a far link,
    /// else max(0, n·ω).
    pub fn weight(&self, normal: Vec3, position: Vec3) -> f64 {
        match &self.source {
            Some(source) => source.weight(normal, position),
            None => normal.dot(self.towards).max(0.0) as f64,
        }
    }

    /// The irradiance this arrival gives a member of unit normal `normal` at `position`: w·g.
    pub fn on_element(&self, normal: Vec3, position: Vec3) -> DVec3 {
        self.irradiance * self.weight(normal, position)
    }
}

/// The source of a far link as seen from its receiver's members: a point at the source's centre
/// c_S, of intensity ∝ max(0, −n_S·ω) when the source is flat (all its members share the unit
/// normal n_S: an element, a window of two triangles), isotropic otherwise. A member at x with
/// unit normal n takes, relative to a member facing the source head-on at the receiver's centre,
///
/// g(n, x) = max(0, n·ω_x) · (d² / d_x²) · s(ω_x) / s(ω),  ω_x = (c_S − x)/d_x, d_x = |c_S − x|,
///
/// d and ω the centres' distance and direction, s(ω) = max(0, −n_S·ω) (1 for a source that is not
/// flat): the point-source irradiance at each member's centroid. With g = max(0, n·ω) (the same on
/// every coplanar member) a cluster of long thin coplanar members (the slivers of a fan-triangulated
/// lunette, each spanning its radius) received one value per cluster, and neighbouring clusters'
/// values stepped by up to 20% (session 16, docs/accuracy.md).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointSource {
    pub centre: Vec3,
    /// n_S of a flat source, zero when the source is not flat (or faces the receiver's centre
    /// edge-on, s(ω) = 0).
    pub normal: Vec3,
    /// d².
    pub distance_sq: f32,
    /// s(ω) (1 when `normal` is zero).
    pub facing: f32,
}

impl PointSource {
    /// The point source of link (receiver ← source) with `flat_normal` the source's common member
    /// normal (zero when it has none, `flat_normals`).
    pub fn of_link(nodes: &Nodes, receiver: usize, source: usize, flat_normal: Vec3) -> PointSource {
        let centre = nodes.centre[source];
        let offset = centre - nodes.centre[receiver];
        PointSource::facing(centre, offset.normalize_or_zero(), offset.length_squared(), flat_normal)
    }

    /// The point source at `centre`, seen from the receiver's centre in unit direction `towards` at
    /// squared distance `distance_sq`, of flat normal `flat_normal` (zero: not flat).
    pub fn facing(centre: Vec3, towards: Vec3, distance_sq: f32, flat_normal: Vec3) -> PointSource {
        let facing = (-flat_normal.dot(towards)).max(0.0);
        if facing > 1e-3 {
            PointSource { centre, normal: flat_normal, distance_sq, facing }
        } else {
            PointSource { centre, normal: Vec3::ZERO, distance_sq, facing: 1.0 }
        }
    }

    /// g(n, x) (see the type); 0 at the source's centre. With o = c_S − x: g = (n·o)·(−n_S·o)·d² /
    /// (s(ω)·|o|⁴) for a flat source, (n·o)·d² / |o|³ otherwise; a member facing away (n·o ≤ 0), or
    /// behind a flat source's plane, gets 0 before any square root (the push evaluates this for
    /// every member and pending arrival at every sweep).
    pub fn weight(&self, normal: Vec3, position: Vec3) -> f64 {
        let offset = self.centre - position;
        let cos_receiver = normal.dot(offset);
        if !(cos_receiver > 0.0) {
            return 0.0;
        }
        let d2 = offset.length_squared() as f64;
        if self.normal == Vec3::ZERO {
            return cos_receiver as f64 * self.distance_sq as f64 / (d2 * d2.sqrt());
        }
        let cos_source = -self.normal.dot(offset);
        if !(cos_source > 0.0) {
            return 0.0;
        }
        cos_receiver as f64 * cos_source as f64 * self.distance_sq as f64 / (self.facing as f64 * d2 * d2)
    }
}

/// Per node, the unit normal all its members share (`Nodes::members`; an element's own normal), or
/// zero when they do not (normals within 1e-4 of each other count as one). Children come after their
/// parent, so one pass in reverse index order suffices.
pub fn flat_normals(nodes: &Nodes) -> Vec<Vec3> {
    let mut out = vec![Vec3::ZERO; nodes.len()];
    for n in (0..nodes.len()).rev() {
        out[n] = if !nodes.is_cluster[n] {
            nodes.normal[n]
        } else {
            let mut children = nodes.children(n);
            let first = children.next().map_or(Vec3::ZERO, |c| out[c]);
            let shared = first != Vec3::ZERO && children.all(|c| out[c].dot(first) > 1.0 - 1e-4);
            if shared {
                first
            } else {
                Vec3::ZERO
            }
        };
    }
    out
}

/// Irradiance (W/m², before reflection) a node gathers over its own links, in two parts:
/// - `uniform`: the same on every member (links to an element, a cluster's self-link, a link whose
///   direction no member faces);
/// - `arrivals`: a cluster receiver's other links, one `Arrival` each;
/// - `direct`: (member, irradiance on its open part) of a cluster receiver's links with member
///   shares (`ArrivalScales`), power-conserving like arrivals.
///
/// A member i (area A_i, open area A_open,i, unit normal n_i) of a cluster R gets
///
/// G_i = (A_R/A_open,R)·uniform + Σ_l w_l·max(0, n_i·ω_l),  w_l = P_l / D_open,R(ω_l),
/// D_open,R(ω) = Σ_j A_open,j·max(0, n_j·ω),
///
/// so each link's power is conserved exactly, Σ_i A_open,i·max(0, n_i·ω_l)·w_l = P_l, and a member
/// facing away from ω_l gets nothing from link l. `mean` = Σ_l F_l·B_S, the node's power over its area.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Irradiance {
    pub uniform: DVec3,
    pub arrivals: Vec<Arrival>,
    pub direct: Vec<(usize, DVec3)>,
    pub mean: DVec3,
}

impl Irradiance {
    pub fn uniform(g: DVec3) -> Irradiance {
        Irradiance { uniform: g, arrivals: Vec::new(), direct: Vec::new(), mean: g }
    }
}

/// How each link of a cluster receiver reaches the receiver's members, per link (`Irradiance`; read
/// through `ArrivalScales::receiver`):
///
/// - scale s_l = A_R / D_open,R: the link becomes an `Arrival` of head-on irradiance
///   w_l = s_l·F_l·B_S, each member taking w_l·g_i; for a far link (not `links::is_near`)
///   g_i = `PointSource::weight` at the member's centroid (its own direction and distance to the
///   source, and the source's cosine toward it when the source is flat), D_open,R = Σ_j A_open,j·g_j
///   (`positional`); for a near one, and a far one no member sees by position, g_i = max(0,
///   n_i·ω_l) and D_open,R(ω_l) = Σ_j A_open,j·max(0, n_j·ω_l);
/// - shares, when the link's ends hold at most `SHARE_PAIRS` (member, source member) pairs
///   (`Nodes::members`): its power goes to each member i by the member's own unoccluded form factor
///   to the source, F_i = Σ_σ F(x_i → σ) (Lambert's exact `form_factor::point_to_polygon` from the
///   member's centroid x_i to each source member σ): G_i += F_l·B_S·c_i, c_i = A_R·F_i / Σ_j
///   A_open,j·F_j, which conserves the link's power exactly and follows each member's own distance
///   and orientation where ω between the centres is a poor stand-in (a near link, a far one at a
///   grazing angle). (The 3-point rule per member cost 2.5× the CPU-s of the scales on
///   procedural:16000 for no measurable gain on cornell_original; 64 pairs instead of 16 cost +5
///   CPU-s there, session 13);
/// - near links (`links::is_near`) to a receiver of at most `NEAR_SHARE_MEMBERS` members with more
///   pairs: member shares too, c_i = A_R·F̂_i / Σ_j A_open,j·F̂_j with F̂_i member i's form factor to
///   `NEAR_SHARE_SAMPLES` source elements sampled by area (`sampled_member_shares`). The ends of a near
///   link overlap, so ω between their centres may point anywhere: on the rotunda a cluster of the
///   torus and the column took a plinth cluster's light on the torus's underside (G 0.38 where the
///   exact transfer is 0.002), the torus's downward facets gathered 1.94× and the plinth's facets up to
///   1.37× what rays give (`examples/hierarchy_links --gathered`), session 14;
/// - neither (s_l = 0): the transfer is uniform over the receiver: receivers that are elements, a
///   cluster's self-link, and links whose direction no open member faces.
///
/// Depends on the geometry only (the two ends), so a solve computes it once per link and hands the
/// links that survive a refinement pass on (`reusing`). Stored compactly (session 15): only cluster
/// receivers' links have entries, and a share names its member by its index in the receiver's member
/// list (a byte: at most `NEAR_SHARE_MEMBERS` = 256 members), held once per receiver; on
/// procedural:16000 6.5 M shares of 0.47 M links take 5 bytes each instead of 8 plus a heap vector.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ArrivalScales {
    /// Per node (and one past the last): the first of its links' entries in `source`, `scale` and
    /// `share_offsets`, in the order of its `Links` row; only cluster receivers have entries.
    link_offsets: Vec<u32>,
    /// Per entry: the link's source (to find a surviving link's entry, `reusing`).
    source: Vec<u32>,
    /// Per entry: s_l, 0 when the link has shares or is uniform.
    scale: Vec<f32>,
    /// Per entry: the arrival is evaluated by the member's position (`PointSource`).
    positional: Vec<bool>,
    /// Per node: `flat_normals`, the `PointSource::normal` of a link from it.
    flat_normal: Vec<Vec3>,
    /// Per entry (and one past the last): the first of its shares in `share_member` / `share_factor`.
    share_offsets: Vec<u32>,
    /// Per node (and one past the last): the first of its members in `members`; only receivers with
    /// a link with shares hold them.
    member_offsets: Vec<u32>,
    /// The members (`Nodes::members`, in that order) of receivers with shares.
    members: Vec<u32>,
    /// Per share: its member's index in the receiver's `members`.
    share_member: Vec<u8>,
    /// Per share: c_i.
    share_factor: Vec<f32>,
    /// What each link reads from a subdivided element source (`source_weights`).
    sent: SourceWeights,
    /// Per node: the gain on what a leaf gathers, 1 unless its row sum R breaks ρ·R < 1 (`row_sums`);
    /// empty (every gain 1) until `bound_rows`.
    leaf_gain: Vec<f32>,
    /// Leaves whose gain is below 1, and the largest row sum of any leaf (0 until `bound_rows`).
    bounded_leaves: usize,
    max_row_sum: f64,
    /// The leaves' indirect irradiance corrected by cosine rays (`ray_correction`); none until set.
    correction: Option<super::ray_correction::IndirectCorrection>,
}

// A share's member index is a byte.
const _: () = assert!(NEAR_SHARE_MEMBERS <= 256 && SHARE_PAIRS <= 256);

/// The `ArrivalScales` of one receiver's links, by the link's position i in the receiver's `Links`
/// row (link k = `links.range(r).start + i`); empty (every link uniform) for an element receiver.
#[derive(Clone, Copy, Debug)]
pub struct ReceiverScales<'a> {
    scale: &'a [f32],
    positional: &'a [bool],
    share_offsets: &'a [u32],
    members: &'a [u32],
    share_member: &'a [u8],
    share_factor: &'a [f32],
}

impl<'a> ReceiverScales<'a> {
    /// s of the receiver's link i (0: shares or uniform).
    pub fn scale(&self, i: usize) -> f32 {
        self.scale.get(i).copied().unwrap_or(0.0)
    }

    /// Whether the receiver's link i (an arrival) is evaluated by each member's position.
    pub fn positional(&self, i: usize) -> bool {
        self.positional.get(i).copied().unwrap_or(false)
    }

    /// Whether the receiver's link i reaches its members by shares.
    pub fn has_shares(&self, i: usize) -> bool {
        i < self.scale.len() && self.share_offsets[i] < self.share_offsets[i + 1]
    }

    /// The (member node, c_i) shares of the receiver's link i, empty when it has none.
    pub fn shares(&self, i: usize) -> impl Iterator<Item = (usize, f32)> + 'a {
        let range = if i < self.scale.len() {
            self.share_offsets[i] as usize..self.share_offsets[i + 1] as usize
        } else {
            0..0
        };
        let (members, member, factor) = (self.members, self.share_member, self.share_factor);
        range.map(move |j| (members[member[j] as usize] as usize, factor[j]))
    }
}

/// What `receiver_reach` gives for one cluster receiver, in the layout of `ArrivalScales` over its
/// links.
#[derive(Default)]
struct ReceiverReach {
    scale: Vec<f32>,
    positional: Vec<bool>,
    share_count: Vec<u32>,
    members: Vec<u32>,
    share_member: Vec<u8>,
    share_factor: Vec<f32>,
}

/// Cluster receivers whose `ReceiverReach` are computed in parallel at a time: what is held twice
/// (in the receivers' own vectors and in the flat arrays) is at most one block's.
const RECEIVER_BLOCK: usize = 512;

impl ArrivalScales {
    /// The scales or shares of every link: per cluster receiver, one walk over its members summing
    /// A_open,j·max(0, n_j·ω_l) for all its links at once (O(members × links) per receiver), and the
    /// member form factors of links with at most `SHARE_PAIRS` pairs or near ones
    /// (`sampled_member_shares`); receivers in parallel, each in a fixed order, so the result does
    /// not depend on threads.
    pub fn new(nodes: &Nodes, links: &Links) -> ArrivalScales {
        ArrivalScales::reusing(nodes, links, None)
    }

    /// `new`, taking each link's scale or shares from `previous` (the scales of earlier links over
    /// the same nodes) when it holds a link of the same receiver and source. A link's scale and
    /// shares depend on its two ends' geometry only (members, their open areas, normals and
    /// corners, and the source elements sampled by area), which refinement never changes:
    /// subdivision appends pieces below input triangles, and members stop at input triangles. So
    /// the result is bit for bit `new`'s, and a refinement pass computes only the links it made.
    pub fn reusing(nodes: &Nodes, links: &Links, previous: Option<&ArrivalScales>) -> ArrivalScales {
        let node_count = links.offsets.len().saturating_sub(1);
        let receivers: Vec<usize> =
            (0..node_count).filter(|&r| nodes.is_cluster[r] && !links.range(r).is_empty()).collect();
        let mut link_offsets = vec![0u32; node_count + 1];
        for &r in &receivers {
            link_offsets[r + 1] = links.range(r).len() as u32;
        }
        for r in 0..node_count {
            link_offsets[r + 1] += link_offsets[r];
        }
        let entries = link_offsets[node_count] as usize;
        let mut out = ArrivalScales {
            link_offsets,
            source: Vec::with_capacity(entries),
            scale: Vec::with_capacity(entries),
            positional: Vec::with_capacity(entries),
            flat_normal: flat_normals(nodes),
            share_offsets: Vec::with_capacity(entries + 1),
            member_offsets: vec![0u32; node_count + 1],
            ..Default::default()
        };
        out.share_offsets.push(0);
        for block in receivers.chunks(RECEIVER_BLOCK) {
            let rows: Vec<ReceiverReach> =
                block.par_iter().map(|&r| receiver_reach(nodes, links, r, previous, &out.flat_normal)).collect();
            let shares: usize = rows.iter().map(|row| row.share_member.len()).sum();
            reserve_growing(&mut out.share_member, shares);
            reserve_growing(&mut out.share_factor, shares);
            for (&r, row) in block.iter().zip(rows) {
                out.source.extend(links.range(r).map(|k| links.source[k]));
                out.scale.extend_from_slice(&row.scale);
                out.positional.extend_from_slice(&row.positional);
                for c in row.share_count {
                    let last = *out.share_offsets.last().expect("starts with 0");
                    out.share_offsets.push(last + c);
                }
                out.member_offsets[r + 1] = row.members.len() as u32;
                out.members.extend_from_slice(&row.members);
                out.share_member.extend_from_slice(&row.share_member);
                out.share_factor.extend_from_slice(&row.share_factor);
            }
        }
        for r in 0..node_count {
            out.member_offsets[r + 1] += out.member_offsets[r];
        }
        out.members.shrink_to_fit();
        out.share_member.shrink_to_fit();
        out.share_factor.shrink_to_fit();
        out.sent = SourceWeights::reusing(nodes, links, previous.map(|p| &p.sent));
        if previous.is_some_and(ArrivalScales::rows_bounded) {
            out.bound_rows(nodes, links);
        }
        out
    }

    /// Gives every leaf whose row sum R would have it reflect at least all it gathers (ρ·R ≥ 1) the
    /// gain 1/R on its gathering (`row_sums`): called by `solve::solve_until` once the sweeps
    /// diverge, and kept by the scales `reusing` these.
    pub fn bound_rows(&mut self, nodes: &Nodes, links: &Links) {
        let gains = LeafGains::new(nodes, &row_sums(nodes, links, self));
        self.leaf_gain = gains.per_node(nodes.len());
        self.bounded_leaves = gains.scaled.len();
        self.max_row_sum = gains.max_row_sum;
    }

    /// Sets (or clears) the leaves' ray-measured correction of their indirect irradiance.
    pub fn set_correction(&mut self, correction: Option<super::ray_correction::IndirectCorrection>) {
        self.correction = correction;
    }

    /// Leaf `n`'s irradiance `gathered` (after its gain) with its indirect part corrected
    /// (`ray_correction::IndirectCorrection::apply`); `gathered` itself when nothing is set.
    pub fn corrected(&self, n: usize, gathered: DVec3) -> DVec3 {
        self.correction.as_ref().map_or(gathered, |c| c.apply(n, gathered))
    }

    /// Whether `bound_rows` has been called.
    pub fn rows_bounded(&self) -> bool {
        !self.leaf_gain.is_empty()
    }

    /// What leaf `n`'s gathered irradiance is multiplied by: after `bound_rows`, 1 / R where its
    /// row sum R would have it reflect at least all it gathers (ρ·R ≥ 1); otherwise 1.
    pub fn leaf_gain(&self, n: usize) -> f64 {
        self.leaf_gain.get(n).map_or(1.0, |&g| g as f64)
    }

    /// The leaves whose gain is below 1, and the largest row sum R of any leaf; (0, 0) until
    /// `bound_rows`.
    pub fn row_bound(&self) -> (usize, f64) {
        (self.bounded_leaves, self.max_row_sum)
    }

    /// What the links of receiver `r` send, asked link by link in order (`source_weights`).
    pub fn sent_cursor(&self, r: usize) -> Cursor<'_> {
        self.sent.cursor(r)
    }

    /// What link k of receiver `r` sends, values being the nodes' exitance (or a part of it).
    pub fn sent(&self, nodes: &Nodes, links: &Links, r: usize, k: usize, values: &[DVec3]) -> DVec3 {
        self.sent.sent(nodes, links, r, k, values)
    }

    /// The `Arrival` of cluster receiver `receiver`'s link i (from `source`) for a unit transfer
    /// F·B_S = 1 (its `irradiance` is the scale s_l); `None` when the link is not an arrival (it has
    /// shares, is uniform, or the receiver is an element).
    pub fn unit_arrival(&self, nodes: &Nodes, receiver: usize, i: usize, source: usize) -> Option<Arrival> {
        let reach = self.receiver(receiver);
        if !nodes.is_cluster[receiver] || reach.has_shares(i) || !(reach.scale(i) > 0.0) {
            return None;
        }
        let towards = arrival_direction(nodes, receiver, source)?;
        let point = reach.positional(i).then(|| self.point_source(nodes, receiver, source, towards));
        Some(Arrival { towards, irradiance: DVec3::splat(reach.scale(i) as f64), source: point })
    }

    /// The `PointSource` of link (receiver ← source) of direction `towards` (`arrival_direction`).
    fn point_source(&self, nodes: &Nodes, receiver: usize, source: usize, towards: Vec3) -> PointSource {
        let centre = nodes.centre[source];
        PointSource::facing(centre, towards, centre.distance_squared(nodes.centre[receiver]), self.flat_normal[source])
    }

    /// The scales of receiver `r`'s links.
    pub fn receiver(&self, r: usize) -> ReceiverScales<'_> {
        if r + 1 >= self.link_offsets.len() {
            return ReceiverScales {
                scale: &[],
                positional: &[],
                share_offsets: &[0],
                members: &[],
                share_member: &[],
                share_factor: &[],
            };
        }
        let entries = self.link_offsets[r] as usize..self.link_offsets[r + 1] as usize;
        let members = self.member_offsets[r] as usize..self.member_offsets[r + 1] as usize;
        ReceiverScales {
            scale: &self.scale[entries.clone()],
            positional: &self.positional[entries.clone()],
            share_offsets: &self.share_offsets[entries.start..entries.end + 1],
            members: &self.members[members],
            share_member: &self.share_member,
            share_factor: &self.share_factor,
        }
    }
}

/// Room for `more` elements in `v`, growing it by at least a quarter of its length: a few
/// reallocations in all (not one per block of receivers), at most a quarter unused before the
/// caller's `shrink_to_fit`.
fn reserve_growing<T>(v: &mut Vec<T>, more: usize) {
    if v.capacity() - v.len() < more {
        v.reserve_exact(more.max(v.len() / 4));
    }
}

/// `ArrivalScales` of the links of cluster receiver `r`, in link order; a link of the same source in
/// `previous` is copied, the others are computed.
fn receiver_reach(
    nodes: &Nodes,
    links: &Links,
    r: usize,
    previous: Option<&ArrivalScales>,
    flat_normal: &[Vec3],
) -> ReceiverReach {
    let range = links.range(r);
    let mut out = ReceiverReach {
        scale: vec![0.0; range.len()],
        positional: vec![false; range.len()],
        share_count: vec![0; range.len()],
        ..Default::default()
    };
    // The previous entries of this receiver by source.
    let old = previous.filter(|p| r + 1 < p.link_offsets.len());
    let mut known: Vec<(u32, usize)> = match old {
        Some(p) => (p.link_offsets[r] as usize..p.link_offsets[r + 1] as usize).map(|e| (p.source[e], e)).collect(),
        None => Vec::new(),
    };
    known.sort_unstable();
    let reused = |s: u32| known.binary_search_by_key(&s, |&(source, _)| source).ok().map(|i| known[i].1);
    let fresh: Vec<usize> = range.clone().filter(|&k| reused(links.source[k]).is_none()).collect();
    let mut members = Vec::new();
    nodes.members(r, &mut members);
    let mut computed = compute_reach(nodes, links, r, &members, &fresh, flat_normal).into_iter();
    for (i, k) in range.enumerate() {
        match reused(links.source[k]) {
            Some(e) => {
                let old = old.expect("known entries come from previous");
                out.scale[i] = old.scale[e];
                out.positional[i] = old.positional[e];
                let shares = old.share_offsets[e] as usize..old.share_offsets[e + 1] as usize;
                out.share_count[i] = shares.len() as u32;
                out.share_member.extend_from_slice(&old.share_member[shares.clone()]);
                out.share_factor.extend_from_slice(&old.share_factor[shares]);
            }
            None => match computed.next().expect("one reach per fresh link") {
                Reach::Uniform => {}
                Reach::Arrival(s) => out.scale[i] = s,
                Reach::Positional(s) => {
                    out.scale[i] = s;
                    out.positional[i] = true;
                }
                Reach::Shares(shares) => {
                    out.share_count[i] = shares.len() as u32;
                    for (m, c) in shares {
                        out.share_member.push(m);
                        out.share_factor.push(c);
                    }
                }
            },
        }
    }
    if !out.share_member.is_empty() {
        out.members = members.iter().map(|&m| m as u32).collect();
    }
    out
}

/// What one link of a cluster receiver becomes (see `ArrivalScales`); shares as (index in the
/// receiver's members, c_i).
enum Reach {
    Uniform,
    /// An arrival by orientation only, of scale s.
    Arrival(f32),
    /// An arrival by each member's position (`PointSource`), of scale s.
    Positional(f32),
    Shares(Vec<(u8, f32)>),
}

/// The reach of links `fresh` (indices into `links`, all of receiver `r` of members `members`), in
/// that order.
fn compute_reach(
    nodes: &Nodes,
    links: &Links,
    r: usize,
    members: &[usize],
    fresh: &[usize],
    flat_normal: &[Vec3],
) -> Vec<Reach> {
    if fresh.is_empty() {
        return Vec::new();
    }
    let directions: Vec<Option<Vec3>> =
        fresh.iter().map(|&k| arrival_direction(nodes, r, links.source[k] as usize)).collect();
    // Far links' sources as points (`PointSource`); near links are evaluated by orientation only.
    let points: Vec<Option<PointSource>> = fresh
        .iter()
        .zip(&directions)
        .map(|(&k, d)| {
            let s = links.source[k] as usize;
            (d.is_some() && !is_near(nodes, r, s)).then(|| PointSource::of_link(nodes, r, s, flat_normal[s]))
        })
        .collect();
    let mut sums = vec![0.0f64; directions.len()];
    let mut positional_sums = vec![0.0f64; directions.len()];
    for &m in members {
        let (a, n, x) = (nodes.open_area[m] as f64, nodes.normal[m], nodes.centre[m]);
        if !(a > 0.0) {
            continue;
        }
        for ((sum, positional), (d, point)) in
            sums.iter_mut().zip(&mut positional_sums).zip(directions.iter().zip(&points))
        {
            if let Some(d) = d {
                *sum += a * n.dot(*d).max(0.0) as f64;
            }
            if let Some(point) = point {
                *positional += a * point.weight(n, x);
            }
        }
    }
    let area = nodes.area[r] as f64;
    let (mut sources, mut picks) = (Vec::new(), Vec::new());
    fresh
        .iter()
        .zip(directions.iter().zip(sums.into_iter().zip(positional_sums)))
        .map(|(&k, (d, (sum, positional)))| {
            let s = links.source[k] as usize;
            if d.is_none() {
                return Reach::Uniform;
            }
            if members.len() <= SHARE_PAIRS && nodes.member_count_within(s, SHARE_PAIRS / members.len().max(1)) {
                nodes.members(s, &mut sources);
                if let Some(shares) = member_shares(nodes, members, &sources, area) {
                    return Reach::Shares(shares);
                }
            }
            if members.len() <= NEAR_SHARE_MEMBERS && is_near(nodes, r, s) {
                sampled_source_elements(nodes, s, &mut picks);
                if let Some(shares) = sampled_member_shares(nodes, members, &picks, area) {
                    return Reach::Shares(shares);
                }
            }
            if positional > 0.0 {
                Reach::Positional((area / positional) as f32)
            } else if sum > 0.0 {
                Reach::Arrival((area / sum) as f32)
            } else {
                Reach::Uniform
            }
        })
        .collect()
}

/// Links of a cluster receiver whose ends hold at most this many (member, source member) pairs are
/// spread by member shares (`ArrivalScales`).
pub const SHARE_PAIRS: usize = 16;

/// Near links (`links::is_near`) of a cluster receiver with at most this many members are spread by
/// member shares from `NEAR_SHARE_SAMPLES` sampled source elements (`sampled_member_shares`).
pub const NEAR_SHARE_MEMBERS: usize = 256;

/// Source elements a near link's member shares are estimated with (`sampled_source_elements`). Four,
/// measured in one window (session 14, docs/accuracy.md): the rotunda 0.00361 at 4, 0.00361 at 8 and
/// 16; procedural:16000 24.4 / 33.4 / 42.2 CPU-s (19.95 without member shares for near links).
pub const NEAR_SHARE_SAMPLES: usize = 4;

/// `NEAR_SHARE_SAMPLES` elements below `source` (down to input triangles), each picked with
/// probability proportional to its area at the fixed stratified points u_k = (k + ½)/K, v = ½
/// (`visibility::sample_element`), with its weight A_S/(K·A_t): Σ_k w_k·f(t_k) estimates
/// Σ_t f(t) over the source's elements without bias for any f, exactly when there are K or fewer
/// elements of equal area. Deterministic (no random numbers), so the shares do not depend on seeds
/// or threads. Writes (element, weight) pairs into `out`.
pub fn sampled_source_elements(nodes: &Nodes, source: usize, out: &mut Vec<(usize, f64)>) {
    out.clear();
    let k = NEAR_SHARE_SAMPLES;
    let area = nodes.area[source] as f64;
    for i in 0..k {
        let (t, _) = sample_element(nodes, source, [(i as f64 + 0.5) / k as f64, 0.5]);
        let a = nodes.area[t] as f64;
        if a > 0.0 {
            out.push((t, area / (k as f64 * a)));
        }
    }
}

/// Member shares of a near link (`links::is_near`: overlapping bounding spheres, where ω between
/// the centres says little about which members face the source; on the rotunda a torus-and-column
/// cluster's link from a plinth cluster lit the torus's underside, whose members face the floor):
///
/// c_i = A_R·F̂_i / Σ_j A_open,j·F̂_j,  F̂_i = Σ_k w_k·F(x_i → t_k),
///
/// F(x → t) Lambert's exact `point_to_polygon` from member i's centroid x_i (normal n_i) to the
/// sampled source element t_k with weight w_k (`sampled_source_elements`): F̂_i estimates member
/// i's unoccluded form factor to the source, so each member takes the link's power by its own
/// position and orientation (a member facing away from every sampled element gets nothing), and the
/// link's power A_R·F_RS·B_S is kept exactly. Pairs within one input triangle are skipped. `None`
/// when no open member sees a sampled element (the caller falls back to the arrival).
fn sampled_member_shares(
    nodes: &Nodes,
    members: &[usize],
    picks: &[(usize, f64)],
    receiver_area: f64,
) -> Option<Vec<(u8, f32)>> {
    shares_by_form_factor(nodes, members, receiver_area, |m| {
        picks
            .iter()
            .filter(|&&(t, _)| nodes.input[t] != nodes.input[m])
            .map(|&(t, w)| w * point_to_polygon(nodes.centre[m], nodes.normal[m], &nodes.corners[t]))
            .sum()
    })
}

/// c_i = A_R·F_i / Σ_j A_open,j·F_j over the open members (`open_area` > 0) with F_i =
/// `form_factor(i)` > 0, as (index i in `members`, at most 256 of them, c_i); `None` when every F_i
/// is 0. Σ_i A_open,i·c_i = A_R: the shares keep the link's power.
fn shares_by_form_factor(
    nodes: &Nodes,
    members: &[usize],
    receiver_area: f64,
    form_factor: impl Fn(usize) -> f64,
) -> Option<Vec<(u8, f32)>> {
    debug_assert!(members.len() <= 256);
    let mut form_factors = Vec::with_capacity(members.len());
    let mut total = 0.0f64;
    for (i, &m) in members.iter().enumerate() {
        let open = nodes.open_area[m] as f64;
        if !(open > 0.0) {
            continue;
        }
        let f = form_factor(m);
        if f > 0.0 {
            form_factors.push((i as u8, f));
            total += open * f;
        }
    }
    (total > 0.0).then(|| form_factors.into_iter().map(|(m, f)| (m, (receiver_area * f / total) as f32)).collect())
}

/// (member index, c_i = A_R·F_i / Σ_j A_open,j·F_j) for the open members with F_i > 0, F_i = Σ_σ F(x_i →
/// σ) from the member's centroid over the source's members `leaves` (`Nodes::members`: its own
/// triangle for an element, exact in the source; pairs within one input triangle skipped); `None`
/// when no open member sees the source.
fn member_shares(nodes: &Nodes, members: &[usize], leaves: &[usize], receiver_area: f64) -> Option<Vec<(u8, f32)>> {
    shares_by_form_factor(nodes, members, receiver_area, |m| {
        leaves
            .iter()
            .filter(|&&l| nodes.input[l] != nodes.input[m])
            .map(|&l| point_to_polygon(nodes.centre[m], nodes.normal[m], &nodes.corners[l]))
            .sum()
    })
}

/// ω of link (receiver ← source) when the receiver is a cluster and the link has a direction: the
/// unit vector between the centres; `None` for a self-link or coincident centres.
pub fn arrival_direction(nodes: &Nodes, receiver: usize, source: usize) -> Option<Vec3> {
    if receiver == source {
        return None;
    }
    let omega = (nodes.centre[source] - nodes.centre[receiver]).normalize_or_zero();
    (omega != Vec3::ZERO).then_some(omega)
}

/// Irradiance a receiver gathers over its links, before reflection:
///
/// G_R = Σ_{S linked to R} F_RS · B̂_S  (W/m², as a mean over R: the returned `mean`),
///
/// B̂_S the exitance the link sends: its source's pieces weighted by how the receiver sees them when
/// the source is a subdivided element (`source_weights`); the exitance of the members facing the
/// receiver when the link is far, its source a cluster and `lobes` are given (`lobes`, the sweeps
/// give them); else B_S. Summed in link order (a fixed order, so the sum is reproducible). For a
/// cluster receiver
/// (`ArrivalScales`): a link with member shares adds F_RS·B_S·c_i to member i (pushed to `direct`);
/// a link with a direction ω (`arrival_direction`) and a scale s becomes an `Arrival` of head-on
/// irradiance w = s·F_RS·B_S appended to `arrivals`; the rest adds to the returned uniform part. For
/// a far link F_RS = V·P_S·D_R(ω)/(π d² A_R) (`form_factor::cluster_form_factor`), so with nothing
/// hidden w = V·P_S·B_S/(π d²); for a near link, whose ends overlap, ω between the centres is an
/// approximation (shares serve most near links) and the power is still the link's.
///
/// Returns (uniform, mean).
#[allow(clippy::too_many_arguments)]
pub fn gather_into(
    nodes: &Nodes,
    links: &Links,
    scales: &ArrivalScales,
    receiver: usize,
    exitance: &[DVec3],
    lobes: Option<&Lobes>,
    arrivals: &mut Vec<Arrival>,
    direct: &mut Vec<(usize, DVec3)>,
) -> (DVec3, DVec3) {
    let (mut uniform, mut mean) = (DVec3::ZERO, DVec3::ZERO);
    let cluster = nodes.is_cluster[receiver];
    let reach = scales.receiver(receiver);
    let mut sent = scales.sent_cursor(receiver);
    for (i, k) in links.range(receiver).enumerate() {
        let s = links.source[k] as usize;
        let directional = lobes.and_then(|l| l.sent_over(nodes, k, receiver, s));
        let b = match directional {
            Some(b) => b,
            None => sent.sent(nodes, receiver, s, exitance),
        };
        let transfer = b * links.form_factor[k] as f64;
        mean += transfer;
        if !cluster {
            uniform += transfer;
        } else if reach.has_shares(i) {
            direct.extend(reach.shares(i).map(|(m, c)| (m, transfer * c as f64)));
        } else if let (Some(towards), true) = (arrival_direction(nodes, receiver, s), reach.scale(i) > 0.0) {
            let source = reach.positional(i).then(|| scales.point_source(nodes, receiver, s, towards));
            arrivals.push(Arrival { towards, irradiance: transfer * reach.scale(i) as f64, source });
        } else {
            uniform += transfer;
        }
    }
    (uniform, mean)
}

/// `gather_into` as one value.
pub fn gather(nodes: &Nodes, links: &Links, scales: &ArrivalScales, receiver: usize, exitance: &[DVec3]) -> Irradiance {
    let (mut arrivals, mut direct) = (Vec::new(), Vec::new());
    let (uniform, mean) = gather_into(nodes, links, scales, receiver, exitance, None, &mut arrivals, &mut direct);
    Irradiance { uniform, arrivals, direct, mean }
}

/// What a node passes to its children in the push: the uniform irradiance from above and the range
/// `lo..hi` of the shared arrival stack (its ancestors' and its own arrivals) still to be evaluated.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Pushed {
    pub uniform: DVec3,
    pub lo: usize,
    pub hi: usize,
}

/// One node's step of the push (used by `push_pull` and `solve::sweep`): `arrivals` holds the
/// ancestors' arrivals at `down.lo..down.hi` followed by the node's own (`own_uniform` its own
/// uniform part, `direct` what its ancestors' member shares put on it, already on its open part).
/// A node with no open area gets nothing (and neither does anything below it); else its own uniform
/// part lands on its open part (×`Nodes::open_gain`). An element evaluates every pending arrival at
/// its normal, G = uniform + direct + Σ w·max(0, n·ω), and passes a plain uniform value down (its
/// pieces share its normal). Returns what the children get.
pub fn push_step(
    nodes: &Nodes,
    node: usize,
    down: Pushed,
    own_uniform: DVec3,
    direct: DVec3,
    arrivals: &[Arrival],
) -> Pushed {
    let hi = arrivals.len();
    if !(nodes.open_area[node] > 0.0) {
        return Pushed { uniform: DVec3::ZERO, lo: hi, hi };
    }
    let uniform = down.uniform + own_uniform * nodes.open_gain(node) + direct;
    if nodes.is_cluster[node] {
        return Pushed { uniform, lo: down.lo, hi };
    }
    let (normal, position) = (nodes.normal[node], nodes.centre[node]);
    let oriented: DVec3 = arrivals[down.lo..hi].iter().map(|a| a.on_element(normal, position)).sum();
    Pushed { uniform: uniform + oriented, lo: hi, hi }
}

/// A leaf's overrelaxed update: B ← B + ω·(S + ρ·G − B), clamped at 0 (ω > 1 may overshoot below
/// zero on the first sweeps), S its emission and reflected caustic light (`Nodes::source_exitance`).
/// ω = 1 is the plain Gauss-Seidel/Jacobi update B = S + ρG.
pub fn leaf_exitance(source: DVec3, reflectance: DVec3, irradiance: DVec3, old: DVec3, relaxation: f64) -> DVec3 {
    let target = source + reflectance * irradiance;
    (old + (target - old) * relaxation).max(DVec3::ZERO)
}

/// Push-pull over the tree below `root` (one Jacobi step of the hierarchical system): pushes
/// `own_irradiance` down (`push_step`: a node's uniform part lands on its open part, a cluster's
/// arrivals reach each member by its own cosine; a node with no open area gets nothing), sets each
/// leaf to S + ρ·G_total (S = E + ρ·E_c, `Nodes::source_exitance`) and pulls open-area-weighted means up (`pulled`):
///
/// B_leaf = S + ρ·Σ_{a ∈ ancestors(leaf) ∪ {leaf}} [(A_a/A_open,a)·U_a + Σ_{l ∈ arrivals(a)} w_l·max(0,
/// n_leaf·ω_l)],  B_inner = Σ_c A_open,c B_c / Σ_c A_open,c.
///
/// Writes `exitance` for every node below `root` and returns the irradiance per node as pushed: for an
/// element, the irradiance on its open part; for a cluster, what lands on its members over its area,
/// (U·A_open + Σ_l w_l·D_open(ω_l))/A for its total uniform part U and pending arrivals (member
/// shares are counted on the members). Power is conserved: Σ_leaves A_open·G_total = Σ_nodes
/// A·mean(G_own) when every arrival's scale is A/D_open(ω) and every share set is `ArrivalScales`'.
pub fn push_pull(nodes: &Nodes, root: usize, own_irradiance: &[Irradiance], exitance: &mut [DVec3]) -> Vec<DVec3> {
    let mut total = vec![DVec3::ZERO; nodes.len()];
    // Pre-order push with an explicit stack and one arrival stack, then a post-order pull over the
    // same order reversed.
    let mut order = Vec::new();
    let mut arrivals: Vec<Arrival> = Vec::new();
    let mut direct = vec![DVec3::ZERO; nodes.len()];
    let mut stack = vec![(root, Pushed::default())];
    while let Some((n, down)) = stack.pop() {
        arrivals.truncate(down.hi);
        arrivals.extend_from_slice(&own_irradiance[n].arrivals);
        for &(m, g) in &own_irradiance[n].direct {
            direct[m] += g;
        }
        let g = push_step(nodes, n, down, own_irradiance[n].uniform, direct[n], &arrivals);
        arrivals.truncate(g.hi);
        total[n] = if nodes.is_cluster[n] && nodes.area[n] > 0.0 {
            let power: DVec3 = arrivals[g.lo..g.hi]
                .iter()
                .map(|a| {
                    a.irradiance
                        * nodes
                            .member_sum(n, |m| nodes.open_area[m] as f64 * a.weight(nodes.normal[m], nodes.centre[m]))
                })
                .sum::<DVec3>()
                + g.uniform * nodes.open_area[n] as f64;
            power / nodes.area[n] as f64
        } else {
            g.uniform
        };
        order.push(n);
        for c in nodes.children(n).rev() {
            stack.push((c, g));
        }
    }
    for &n in order.iter().rev() {
        exitance[n] = if nodes.is_leaf(n) {
            leaf_exitance(nodes.source_exitance(n), nodes.reflectance[n].as_dvec3(), total[n], exitance[n], 1.0)
        } else {
            pulled(nodes, n, exitance)
        };
    }
    total
}

/// The mean of a node's children's exitance over their open area (`Nodes::open_area`):
/// B = Σ_c A_open,c B_c / Σ_c A_open,c, the area-weighted mean when nothing is hidden. The exitance a
/// source sends over a link is that of its open part: the link's visibility already counts the
/// hidden part as blocked, and averaging its darkness in as well would count it twice. A node with
/// no open area takes the plain area-weighted mean.
pub fn pulled(nodes: &Nodes, node: usize, exitance: &[DVec3]) -> DVec3 {
    let (mut open_sum, mut open) = (DVec3::ZERO, 0.0f64);
    let (mut sum, mut area) = (DVec3::ZERO, 0.0f64);
    for c in nodes.children(node) {
        open_sum += exitance[c] * nodes.open_area[c] as f64;
        open += nodes.open_area[c] as f64;
        sum += exitance[c] * nodes.area[c] as f64;
        area += nodes.area[c] as f64;
    }
    if open > 0.0 {
        open_sum / open
    } else if area > 0.0 {
        sum / area
    } else {
        DVec3::ZERO
    }
}
