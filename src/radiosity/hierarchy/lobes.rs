//! What a cluster sends in one direction: its exitance in six axis lobes (session 26).
//!
//! A far link (R ← S) from a cluster S carries F_RS = V·P_S(ω)·P_R/(π d² A_R)
//! (`form_factor::cluster_form_factor`), P_S(ω) = Σ_m A_open,m max(0, n_m·ω) the source's projected
//! open area towards the receiver (ω the unit vector from S's centre to R's). The power it brings is
//! that of the members' radiance B_m/π seen from R, so the exitance it should send is the mean over the
//! members *weighted by how much of each R sees*,
//!
//! B_S(ω) = Σ_m A_open,m max(0, n_m·ω) B_m / Σ_m A_open,m max(0, n_m·ω),
//!
//! not the area mean B_S (`gather::pulled`), which also averages in the members that face away: the
//! back copy of a two-sided wall, the far side of a column, the top of an arch seen from the floor
//! below it. On Sponza's nave floor the far cluster links brought 16% less than cosine rays reading the
//! same leaf exitance through the same links (`examples/hierarchy_links --gathered`, session 26).
//!
//! The exact sum walks the members on every sweep, so each cluster keeps it in six lobes about the
//! axes e_a (±x, ±y, ±z), an "ambient cube":
//!
//! Φ_a = Σ_m A_open,m max(0, n_m·e_a) B_m,  P_a = Σ_m A_open,m max(0, n_m·e_a),
//!
//! B̂_S(ω) = Σ_a w_a Φ_a / Σ_a w_a P_a,  w_a = max(0, ω·e_a)² (Σ_a w_a = 1),
//!
//! both pulled up the tree with the exitance (Φ of a cluster is the sum of its children's, an element
//! child's is its own term). It is exact when the members' normals lie along the axes or the exitance
//! is uniform (B̂ = B for any ω, so a uniform cluster sends what it did before), and sends B_S where
//! no member faces the lobes of ω (P = 0).
//!
//! Links whose ends' bounding spheres overlap (self-links, a cluster around its receiver) keep the
//! area mean: there the direction between the centres says nothing of which members the receiver
//! sees (with lobes on every near link cornell_empty went from 3.24e-5 to 5.33e-5 in relMSE). Near
//! links with disjoint spheres (within `links::FAR_DISTANCE_FACTOR` sums of the radii, or a cluster
//! straddling an element's plane) use the lobes like far ones: Sponza 0.0729 → 0.0720 and gap_room
//! −2.6%, the other rooms within 0.6% (session 26, docs/accuracy.md).

use glam::{DVec3, Vec3};

use super::links::Links;
use super::nodes::Nodes;

/// The lobes' axes e_a.
const AXES: [Vec3; 6] = [Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::NEG_Y, Vec3::Z, Vec3::NEG_Z];

/// No lobes (an element).
const NO_SLOT: u32 = u32::MAX;

/// w_a = max(0, ω·e_a)² for a unit ω: Σ_a w_a = 1.
pub fn lobe_weights(omega: Vec3) -> [f64; 6] {
    AXES.map(|e| (omega.dot(e).max(0.0) as f64).powi(2))
}

/// Whether link (receiver ← source) sends B̂_S(ω): its source is a cluster and the ends' bounding
/// spheres are disjoint (every far link, `links::admissible`, and the near ones between 1 and
/// `links::FAR_DISTANCE_FACTOR` sums of the radii apart).
pub fn sends_directionally(nodes: &Nodes, receiver: usize, source: usize) -> bool {
    nodes.is_cluster[source]
        && nodes.centre[receiver].distance(nodes.centre[source]) > nodes.radius[receiver] + nodes.radius[source]
}

/// One element's lobes: A_open max(0, n·e_a), a projected open area per axis.
fn element_projection(nodes: &Nodes, element: usize) -> [f64; 6] {
    let (open, normal) = (nodes.open_area[element] as f64, nodes.normal[element]);
    AXES.map(|e| open * normal.dot(e).max(0.0) as f64)
}

/// Φ_a and P_a of every cluster (see the module's doc), in structs of arrays by cluster slot.
#[derive(Clone, Debug, Default)]
pub struct Lobes {
    /// Per node: its cluster slot, or `NO_SLOT` for an element.
    slot: Vec<u32>,
    /// Per cluster: P_a (m²).
    projected: Vec<[f64; 6]>,
    /// Per cluster: Φ_a (W).
    radiant: Vec<[DVec3; 6]>,
    /// Per link: its source is a cluster and the ends' spheres are disjoint (it sends B̂_S(ω)).
    directional: Vec<bool>,
}

impl Lobes {
    /// The lobes of every cluster below `root` from the nodes' current exitance, for `links`.
    pub fn new(nodes: &Nodes, links: &Links, root: usize) -> Lobes {
        let mut slot = vec![NO_SLOT; nodes.len()];
        let mut order = Vec::new();
        let mut stack = vec![root];
        while let Some(n) = stack.pop() {
            if nodes.is_cluster[n] {
                slot[n] = order.len() as u32;
                order.push(n);
                stack.extend(nodes.children(n));
            }
        }
        let count = order.len();
        let node_count = links.offsets.len().saturating_sub(1);
        let mut directional = vec![false; links.len()];
        for r in 0..node_count {
            for k in links.range(r) {
                let s = links.source[k] as usize;
                directional[k] = sends_directionally(nodes, r, s);
            }
        }
        let mut lobes =
            Lobes { slot, projected: vec![[0.0; 6]; count], radiant: vec![[DVec3::ZERO; 6]; count], directional };
        // Children before parents: the reverse of a pre-order.
        for &n in order.iter().rev() {
            lobes.projected[lobes.slot[n] as usize] = lobes.project(nodes, n);
            lobes.pull(nodes, n);
        }
        lobes
    }

    /// P_a of cluster `n` from its children's (set before it).
    fn project(&self, nodes: &Nodes, n: usize) -> [f64; 6] {
        let mut projected = [0.0f64; 6];
        for c in nodes.children(n) {
            let child = match self.slot_of(c) {
                Some(j) => self.projected[j],
                None => element_projection(nodes, c),
            };
            for (p, x) in projected.iter_mut().zip(child) {
                *p += x;
            }
        }
        projected
    }

    /// Φ_a of cluster `n` again from its children's (after they changed): called where the sweep
    /// pulls its exitance. Nothing for an element.
    pub fn pull(&mut self, nodes: &Nodes, n: usize) {
        let Some(i) = self.slot_of(n) else { return };
        let mut radiant = [DVec3::ZERO; 6];
        for c in nodes.children(n) {
            match self.slot_of(c) {
                Some(j) => {
                    for (r, x) in radiant.iter_mut().zip(&self.radiant[j]) {
                        *r += *x;
                    }
                }
                None => {
                    let b = nodes.exitance[c];
                    for (r, p) in radiant.iter_mut().zip(element_projection(nodes, c)) {
                        *r += b * p;
                    }
                }
            }
        }
        self.radiant[i] = radiant;
    }

    fn slot_of(&self, n: usize) -> Option<usize> {
        self.slot.get(n).copied().filter(|&s| s != NO_SLOT).map(|s| s as usize)
    }

    /// What link `k` (receiver ← source) sends when its source is a cluster and the two ends'
    /// spheres are disjoint: B̂_S(ω) towards the receiver; `None` for other links (and where no
    /// member faces ω's lobes).
    pub fn sent_over(&self, nodes: &Nodes, k: usize, receiver: usize, source: usize) -> Option<DVec3> {
        if !self.directional.get(k).copied().unwrap_or(false) {
            return None;
        }
        let omega = (nodes.centre[receiver] - nodes.centre[source]).normalize_or_zero();
        self.sent(source, omega)
    }

    /// The projected open area of cluster `source` seen from unit direction `omega` (from the cluster
    /// to the viewer) by its lobes, P̃(ω) = Σ_a max(0, ω·e_a)·P_a = Σ_m A_open,m Σ_a max(0, ω·e_a)
    /// max(0, n_m·e_a): exact (Σ_m A_open,m n_m·ω) for members whose normals lie in ω's octant, larger
    /// for the others. `None` for an element.
    pub fn projected_towards(&self, source: usize, omega: Vec3) -> Option<f64> {
        let i = self.slot_of(source)?;
        Some(AXES.iter().zip(&self.projected[i]).map(|(e, &p)| omega.dot(*e).max(0.0) as f64 * p).sum())
    }

    /// B̂_S(ω) of cluster `source` towards the unit direction `omega` (from the source to the
    /// receiver), or `None` when the source is not a cluster or no member faces ω's lobes.
    pub fn sent(&self, source: usize, omega: Vec3) -> Option<DVec3> {
        let i = self.slot_of(source)?;
        let w = lobe_weights(omega);
        let (mut radiant, mut projected) = (DVec3::ZERO, 0.0f64);
        for ((&w, &phi), &p) in w.iter().zip(&self.radiant[i]).zip(&self.projected[i]) {
            radiant += phi * w;
            projected += p * w;
        }
        (projected > 0.0).then(|| radiant / projected)
    }
}
