//! Gathering over links and push-pull (Hanrahan, Salzman and Aupperle 1991): a node's irradiance is
//! what it gathers over its own links plus what its ancestors gathered (pushed down, as irradiance);
//! an inner node's exitance is the area-weighted mean of its children's (pulled up). A cluster
//! receiver's far links arrive from one direction each, so what they bring is kept per orientation
//! (`Irradiance::oriented`) and each element below takes its own cosine's share (Sillion 1995).

use glam::{DVec3, Vec3};

use super::form_factor::{projected_area, projected_area_bins};
use super::links::Links;
use super::nodes::Nodes;

/// Irradiance (W/m², before reflection) on the members of a node, in two parts:
/// - `uniform`: the same on every member (links to an element, near links of a cluster);
/// - `oriented[b]`: irradiance on the part of a cluster that faces bin b of the six-bin model
///   (`form_factor::projected_area_bins`: ±x, ±y, ±z). An element of unit normal n takes
///   Σ_b w_b(n)·oriented[b], w_b(n) = max(0, ±n_k)² its bin weights, which sum to 1.
///
/// Power is conserved: Σ_members A_i (uniform + Σ_b w_b(n_i) oriented[b]) = A·uniform + Σ_b P_b
/// oriented[b], P_b = Σ_i A_i w_b(n_i) the node's bins.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Irradiance {
    pub uniform: DVec3,
    pub oriented: [DVec3; 6],
}

impl Irradiance {
    pub fn uniform(g: DVec3) -> Irradiance {
        Irradiance { uniform: g, oriented: [DVec3::ZERO; 6] }
    }

    pub fn plus(&self, other: &Irradiance) -> Irradiance {
        let mut oriented = self.oriented;
        for (o, x) in oriented.iter_mut().zip(other.oriented) {
            *o += x;
        }
        Irradiance { uniform: self.uniform + other.uniform, oriented }
    }

    /// The irradiance on an element of unit normal `normal`: uniform + Σ_b w_b(n)·oriented[b].
    pub fn on_element(&self, normal: Vec3) -> DVec3 {
        let w = projected_area_bins(normal, 1.0);
        let mut g = self.uniform;
        for (o, wb) in self.oriented.iter().zip(w) {
            g += *o * wb as f64;
        }
        g
    }

    /// Mean irradiance over a node of area `area` and bins `bins` (its received power / area).
    pub fn mean(&self, area: f32, bins: &[f32; 6]) -> DVec3 {
        if !(area > 0.0) {
            return self.uniform;
        }
        let mut power = self.uniform * area as f64;
        for (o, b) in self.oriented.iter().zip(bins) {
            power += *o * *b as f64;
        }
        power / area as f64
    }
}

/// Irradiance a receiver gathers over its links, before reflection:
///
/// G_R = Σ_{S linked to R} F_RS · B_S  (W/m², as a mean over R),
///
/// summed in link order (a fixed order, so the sum is reproducible). For a cluster receiver, a link's
/// transfer arrives from ω = (c_S − c_R)/|c_S − c_R|, and only the members facing ω receive it: its
/// power A_R·F_RS·B_S goes to the bins facing ω in proportion to their projected area,
/// oriented[b(k)] += F_RS·A_R·B_S·|ω_k| / P_R(ω), P_R(ω) = Σ_k |ω_k|·bin(k, sign ω_k) the receiver's
/// projected area toward ω (for a far link, the same model that gave F_RS; for a near one, whose ends
/// overlap, the centre direction is an approximation, still better than the uniform push: cornell_box
/// radiosity relMSE 0.00182 with far links only, 0.00179 with near ones too). A cluster's self-link
/// has no direction and adds to `uniform`, as do links to elements. The power is the link's either way.
pub fn gather(nodes: &Nodes, links: &Links, receiver: usize, exitance: &[DVec3]) -> Irradiance {
    let mut sum = Irradiance::default();
    let cluster = nodes.is_cluster[receiver];
    for k in links.range(receiver) {
        let s = links.source[k] as usize;
        let transfer = exitance[s] * links.form_factor[k] as f64;
        if !cluster || s == receiver {
            sum.uniform += transfer;
            continue;
        }
        let omega = (nodes.centre[s] - nodes.centre[receiver]).normalize_or_zero();
        let bins = &nodes.projected_bins[receiver];
        let projected = projected_area(bins, omega);
        if !(projected > 0.0) {
            sum.uniform += transfer;
            continue;
        }
        let scale = nodes.area[receiver] as f64 / projected as f64;
        for axis in 0..3 {
            let w = omega[axis];
            let bin = 2 * axis + usize::from(w < 0.0);
            if bins[bin] > 0.0 && w != 0.0 {
                sum.oriented[bin] += transfer * (scale * w.abs() as f64);
            }
        }
    }
    sum
}

/// A leaf's overrelaxed update: B ← B + ω·(E + ρ·G − B), clamped at 0 (ω > 1 may overshoot below
/// zero on the first sweeps). ω = 1 is the plain Gauss-Seidel/Jacobi update B = E + ρG.
pub fn leaf_exitance(emission: DVec3, reflectance: DVec3, irradiance: DVec3, old: DVec3, relaxation: f64) -> DVec3 {
    let target = emission + reflectance * irradiance;
    (old + (target - old) * relaxation).max(DVec3::ZERO)
}

/// Push-pull over the tree below `root` (one Jacobi step of the hierarchical system): pushes
/// `own_irradiance` down (a node's total is its own, as it lands on its open part (`on_open_part`),
/// plus its ancestors', each element taking its own normal's share of the oriented part, see
/// `Irradiance::on_element`; a node with no open area gets nothing), sets each leaf to E + ρ·G_total
/// and pulls open-area-weighted means up (`pulled`):
///
/// B_leaf = E + ρ·Σ_{a ∈ ancestors(leaf) ∪ {leaf}} (A_a/A_open,a)·G_a(n_leaf),
/// B_inner = Σ_c A_open,c B_c / Σ_c A_open,c.
///
/// Writes `exitance` for every node below `root` and returns the total irradiance per node as pushed
/// (the mean over the node, `Irradiance::mean`). Power is conserved below elements: Σ_leaves
/// A_open·G_total = Σ_nodes A·mean(G_own), and A_open,root·B_root = Σ_leaves A_open·B (with nothing
/// hidden, A_open = A).
pub fn push_pull(nodes: &Nodes, root: usize, own_irradiance: &[Irradiance], exitance: &mut [DVec3]) -> Vec<DVec3> {
    let mut total = vec![DVec3::ZERO; nodes.len()];
    // Pre-order push with an explicit stack, then a post-order pull over the same order reversed.
    let mut order = Vec::new();
    let mut stack = vec![(root, Irradiance::default())];
    while let Some((n, down)) = stack.pop() {
        let mut g = if nodes.open_area[n] > 0.0 {
            down.plus(&on_open_part(nodes, n, own_irradiance[n]))
        } else {
            Irradiance::default() // all of it hidden: nothing lands
        };
        if !nodes.is_cluster[n] {
            g = Irradiance::uniform(g.on_element(nodes.normal[n]));
        }
        total[n] = g.mean(nodes.area[n], &nodes.projected_bins[n]);
        order.push(n);
        for c in nodes.children(n).rev() {
            stack.push((c, g));
        }
    }
    for &n in order.iter().rev() {
        exitance[n] = if nodes.is_leaf(n) {
            leaf_exitance(nodes.emission[n].as_dvec3(), nodes.reflectance[n].as_dvec3(), total[n], exitance[n], 1.0)
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

/// A node's own gathered irradiance as it lands on its open part: ×`Nodes::open_gain` (the power
/// its links bring, A·G, spread over A_open; nothing on a node with no open area).
pub fn on_open_part(nodes: &Nodes, node: usize, own: Irradiance) -> Irradiance {
    let gain = nodes.open_gain(node);
    if gain == 1.0 {
        return own;
    }
    Irradiance { uniform: own.uniform * gain, oriented: own.oriented.map(|o| o * gain) }
}
