//! Caustic light in the hierarchy: light that reached diffuse surfaces through mirrors and glass
//! (LS+D paths), which no link carries (specular surfaces take part in the links with their Kd and
//! block them). It arrives as photons traced from the emitters (`transport::photons`, by the caller:
//! `hierarchical::caustic_tracer`) over the input triangles, and each leaf takes the photons that
//! landed in it as a source term beside its emission:
//!
//! B_leaf = E + ρ·(G + E_c),  E_c = Σ_{photons k in the leaf} Φ_k / A_open,
//!
//! so that the caustic light is reflected on over the links (LS+DD* paths), as the full matrix's
//! extended form factors to the emitters carry it. Light between diffuse surfaces by way of mirrors and
//! glass (DS+D, which the full matrix's hemicubes follow) comes from a second set of photons once the
//! solve has converged: traced from every surface's reflected exitance B − E (`CausticSources`), added
//! to the first, and swept once more. That carries one specular passage of reflected light
//! (D S+ D, then on over the links); light that passes mirrors or glass twice with a diffuse bounce
//! between (DS+DS+D) is left out.

use glam::{DVec3, Vec3};

use super::clusters::InputTriangles;
use super::nodes::Nodes;

/// Photons that landed on input triangles after one or more specular bounces, as structs of arrays
/// sorted by input triangle (photon order kept within one), with their power.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CausticLight {
    /// Input triangle (index of `InputTriangles`, a side of a two-sided surface) each landed on.
    pub input: Vec<u32>,
    pub position: Vec<Vec3>,
    /// Flux Φ_k (W, per channel).
    pub power_w: Vec<Vec3>,
    /// Rays traced to make them.
    pub rays: u64,
}

/// Where the photons of a `CausticTracer` start.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CausticSources {
    /// The emitters, with their emitted exitance E (LS+D).
    Emitters,
    /// Every input triangle, with its reflected exitance B − E as the nodes hold it (its leaves'
    /// open-area mean; DS+D).
    ReflectedLight,
}

/// Builds the caustic light of the input triangles (`nodes` and `inputs` of `clusters::build`) from
/// `CausticSources`; `None` when the scene has no mirror or glass, or nothing to send. The hierarchy
/// does not trace rays itself: its caller supplies this.
pub type CausticTracer<'a> = dyn Fn(&Nodes, &InputTriangles, CausticSources) -> Option<CausticLight> + Sync + 'a;

impl CausticLight {
    /// From (input triangle, position, flux) landings, in any order (a stable sort keeps the order
    /// within each input triangle, so the sums are reproducible).
    pub fn new(mut landings: Vec<(u32, Vec3, Vec3)>, rays: u64) -> CausticLight {
        landings.sort_by_key(|l| l.0);
        CausticLight {
            input: landings.iter().map(|l| l.0).collect(),
            position: landings.iter().map(|l| l.1).collect(),
            power_w: landings.iter().map(|l| l.2).collect(),
            rays,
        }
    }

    /// Both sets of photons (sorted by input triangle again, `self`'s first within one).
    pub fn merged(self, other: CausticLight) -> CausticLight {
        let landings = (0..self.len())
            .map(|k| (self.input[k], self.position[k], self.power_w[k]))
            .chain((0..other.len()).map(|k| (other.input[k], other.position[k], other.power_w[k])))
            .collect();
        CausticLight::new(landings, self.rays + other.rays)
    }

    pub fn len(&self) -> usize {
        self.input.len()
    }

    pub fn is_empty(&self) -> bool {
        self.input.is_empty()
    }

    /// Per node, the caustic irradiance E_c (W/m², before reflection) on its open part: the flux of
    /// the photons inside it over its open area (`Nodes::open_area`; its area when none is open).
    /// Each photon is followed from its input triangle's node down the 1→4 subdivisions to the leaf
    /// that holds it (`child_holding`), counting on every node it passes. A node's children take
    /// their own estimates only when each holds at least `NODE_PHOTONS` photons; otherwise every node
    /// below it takes its irradiance, so that weak, spread light (a mirror ball's over a room, the
    /// light reflected through glass) is not grain on small leaves while a dense focus keeps the
    /// leaves' resolution. Either way each cut node's flux lands on its open area, Σ A_open·E_c over
    /// the leaves = Σ Φ. Clusters get zero.
    pub fn node_irradiance(&self, nodes: &Nodes, inputs: &InputTriangles) -> Vec<Vec3> {
        let mut flux = vec![DVec3::ZERO; nodes.len()];
        let mut count = vec![0u32; nodes.len()];
        for k in 0..self.len() {
            let Some(&start) = inputs.node.get(self.input[k] as usize) else { continue };
            let mut n = start as usize;
            loop {
                flux[n] += self.power_w[k].as_dvec3();
                count[n] += 1;
                match child_holding(nodes, n, self.position[k]) {
                    Some(c) => n = c,
                    None => break,
                }
            }
        }
        let irradiance = |n: usize| {
            let area = if nodes.open_area[n] > 0.0 { nodes.open_area[n] } else { nodes.area[n] };
            if flux[n] == DVec3::ZERO || !(area > 0.0) {
                Vec3::ZERO
            } else {
                (flux[n] / area as f64).as_vec3()
            }
        };
        let mut out = vec![Vec3::ZERO; nodes.len()];
        // Top-down from each input triangle that photons reached: (node, the cut node above it, if any).
        let mut stack: Vec<(usize, Option<usize>)> =
            inputs.node.iter().map(|&n| n as usize).filter(|&n| count[n] > 0).map(|n| (n, None)).collect();
        while let Some((n, cut)) = stack.pop() {
            let cut = cut.or_else(|| nodes.children(n).any(|c| count[c] < NODE_PHOTONS).then_some(n));
            out[n] = irradiance(cut.unwrap_or(n));
            stack.extend(nodes.children(n).map(|c| (c, cut)));
        }
        out
    }
}

/// Photons each child of a node must hold for the children to take their own caustic irradiance
/// (`CausticLight::node_irradiance`): a relative noise of about 1/√32 ≈ 18 % at most.
pub const NODE_PHOTONS: u32 = 32;

/// The child of element `node` whose triangle holds `p` (the largest smallest barycentric weight, so
/// a point on an edge, or just off the plane, still finds one); `None` for a leaf.
pub fn child_holding(nodes: &Nodes, node: usize, p: Vec3) -> Option<usize> {
    nodes
        .children(node)
        .map(|c| (c, smallest_barycentric(nodes.corners[c], p)))
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(c, _)| c)
}

/// min(w₀, w₁, w₂) of `p` projected into triangle `t`'s plane: ≥ 0 inside, negative outside.
fn smallest_barycentric(t: [Vec3; 3], p: Vec3) -> f32 {
    let n = (t[1] - t[0]).cross(t[2] - t[0]);
    let inv = 1.0 / n.length_squared();
    let w1 = (p - t[0]).cross(t[2] - t[0]).dot(n) * inv;
    let w2 = (t[1] - t[0]).cross(p - t[0]).dot(n) * inv;
    let w = (1.0 - w1 - w2).min(w1).min(w2);
    if w.is_finite() {
        w
    } else {
        f32::NEG_INFINITY
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One input triangle split 1→4 and its corner child split again, for `node_irradiance`'s tests:
    /// (nodes, inputs, root, corner child, its first child).
    fn split_triangle() -> (Nodes, InputTriangles, usize, usize, usize) {
        let mut nodes = Nodes::default();
        let corners = [Vec3::ZERO, Vec3::new(4.0, 0.0, 0.0), Vec3::new(0.0, 4.0, 0.0)];
        let root = nodes.push_element(corners, 0, 0, Vec3::splat(0.5), Vec3::ZERO) as usize;
        let first = nodes.subdivide(root) as usize;
        let corner = (first..first + 4).find(|&c| nodes.corners[c].contains(&Vec3::ZERO)).unwrap();
        let grand = nodes.subdivide(corner) as usize;
        let inputs = InputTriangles { surface: vec![0], back: vec![false], material: vec![0], node: vec![root as u32] };
        (nodes, inputs, root, corner, grand)
    }

    /// `per_leaf` photons of flux (1, 2, 3) W at the centroid of every leaf.
    fn photons_on_leaves(nodes: &Nodes, per_leaf: u32) -> CausticLight {
        let leaves = (0..nodes.len()).filter(|&n| nodes.is_leaf(n));
        let landings =
            leaves.flat_map(|n| (0..per_leaf).map(move |_| (0, nodes.centre[n], Vec3::new(1.0, 2.0, 3.0)))).collect();
        CausticLight::new(landings, 0)
    }

    fn leaf_power(nodes: &Nodes, e: &[Vec3]) -> Vec3 {
        (0..nodes.len()).filter(|&n| nodes.is_leaf(n)).map(|n| e[n] * nodes.area[n]).sum()
    }

    /// Photons dense enough on every leaf: each leaf takes its own photons (A·E_c = its flux), the
    /// root holds them all, and the leaves' power is the photons'.
    #[test]
    fn dense_photons_light_the_leaf_that_holds_them_and_keep_their_power() {
        let (nodes, inputs, root, _, grand) = split_triangle();
        let light = photons_on_leaves(&nodes, NODE_PHOTONS);
        let e = light.node_irradiance(&nodes, &inputs);
        let leaf_flux = Vec3::new(1.0, 2.0, 3.0) * NODE_PHOTONS as f32;
        for n in (0..nodes.len()).filter(|&n| nodes.is_leaf(n)) {
            assert!((e[n] * nodes.area[n] - leaf_flux).abs().max_element() < 1e-3, "leaf {n}: {}", e[n]);
        }
        // 7 leaves (3 children and the corner's 4).
        assert!((e[root] * nodes.area[root] - leaf_flux * 7.0).abs().max_element() < 1e-2);
        assert!((leaf_power(&nodes, &e) - leaf_flux * 7.0).abs().max_element() < 1e-2);
        assert_ne!(e[grand], e[root]);
    }

    /// Sparse photons (three, two of them near the corner): every leaf below the input triangle takes
    /// its mean irradiance, and the leaves' power is still the photons'.
    #[test]
    fn sparse_photons_spread_over_the_node_above_the_sparse_children() {
        let (nodes, inputs, root, corner, grand) = split_triangle();
        let points = [Vec3::new(0.2, 0.3, 0.0), Vec3::new(3.0, 0.5, 0.0), Vec3::new(0.5, 0.5, 0.0)];
        let light = CausticLight::new(points.iter().map(|&p| (0, p, Vec3::new(1.0, 2.0, 3.0))).collect(), 3);
        let e = light.node_irradiance(&nodes, &inputs);
        let mean = Vec3::new(3.0, 6.0, 9.0) / nodes.area[root];
        for n in [root, corner, grand, grand + 3] {
            assert!((e[n] - mean).abs().max_element() < 1e-6, "node {n}: {} against {mean}", e[n]);
        }
        assert!((leaf_power(&nodes, &e) - Vec3::new(3.0, 6.0, 9.0)).abs().max_element() < 1e-4);
    }

    /// No photons: nothing lights anything.
    #[test]
    fn no_photons_give_no_caustic_light() {
        let mut nodes = Nodes::default();
        let root = nodes.push_element([Vec3::ZERO, Vec3::X, Vec3::Y], 0, 0, Vec3::ONE, Vec3::ZERO);
        let inputs = InputTriangles { surface: vec![0], back: vec![false], material: vec![0], node: vec![root] };
        let e = CausticLight::default().node_irradiance(&nodes, &inputs);
        assert_eq!(e, vec![Vec3::ZERO]);
    }
}
