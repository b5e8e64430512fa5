//! Gathering over links and push-pull (Hanrahan, Salzman and Aupperle 1991): a node's irradiance is
//! what it gathers over its own links plus what its ancestors gathered (pushed down unchanged, as
//! irradiance); an inner node's exitance is the area-weighted mean of its children's (pulled up).

use glam::DVec3;

use super::links::Links;
use super::nodes::Nodes;

/// Irradiance a receiver gathers over its links, before reflection:
///
/// G_R = Σ_{S linked to R} F_RS · B_S  (W/m²),
///
/// summed in link order (a fixed order, so the sum is reproducible).
pub fn gather(links: &Links, receiver: usize, exitance: &[DVec3]) -> DVec3 {
    let mut sum = DVec3::ZERO;
    for k in links.range(receiver) {
        sum += exitance[links.source[k] as usize] * links.form_factor[k] as f64;
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
/// `own_irradiance` down (a node's total is its own plus its ancestors'), sets each leaf to
/// E + ρ·G_total and pulls area-weighted means up:
///
/// B_leaf = E + ρ·Σ_{a ∈ ancestors(leaf) ∪ {leaf}} G_a,  B_inner = Σ_c A_c B_c / Σ_c A_c.
///
/// Writes `exitance` for every node below `root` and returns the total irradiance per node as pushed.
/// Power is conserved: Σ_leaves A·G_total = Σ_nodes A·G_own, and A_root·B_root = Σ_leaves A·B.
pub fn push_pull(nodes: &Nodes, root: usize, own_irradiance: &[DVec3], exitance: &mut [DVec3]) -> Vec<DVec3> {
    let mut total = vec![DVec3::ZERO; nodes.len()];
    // Pre-order push with an explicit stack, then a post-order pull over the same order reversed.
    let mut order = Vec::new();
    let mut stack = vec![(root, DVec3::ZERO)];
    while let Some((n, down)) = stack.pop() {
        let g = down + own_irradiance[n];
        total[n] = g;
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

/// The area-weighted mean of a node's children's exitance: B = Σ_c A_c B_c / Σ_c A_c.
pub fn pulled(nodes: &Nodes, node: usize, exitance: &[DVec3]) -> DVec3 {
    let mut sum = DVec3::ZERO;
    let mut area = 0.0f64;
    for c in nodes.children(node) {
        sum += exitance[c] * nodes.area[c] as f64;
        area += nodes.area[c] as f64;
    }
    if area > 0.0 {
        sum / area
    } else {
        DVec3::ZERO
    }
}
