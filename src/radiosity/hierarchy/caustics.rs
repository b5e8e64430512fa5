//! Caustic light in the hierarchy: light that reached diffuse surfaces through mirrors and glass
//! (LS+D paths), which no link carries (specular surfaces take part in the links with their Kd and
//! block them). It arrives as photons traced from the emitters (`transport::photons`, by the caller:
//! `hierarchical::caustic_tracer`) over the input triangles, and each leaf takes the photons that
//! landed in it as a source term beside its emission:
//!
//! B_leaf = E + ρ·(G + E_c),  E_c = Σ_k Φ_k / A_open
//!
//! over the photons k in the leaf (or, where they are too sparse to tell the light from even, in the
//! node above that holds enough: `CausticLight::node_irradiance`),
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

    /// Per node, the caustic irradiance E_c (W/m², before reflection) on the open part of its
    /// receiving members (elements that reflect, ρ > 0: only they catch photons). Each photon is
    /// followed from its input triangle's node down the 1→4 subdivisions to the leaf that holds it
    /// (`child_holding`), and counted on every node from there up to `root`. Going down from `root`,
    /// a node's children take their own estimates when each of them that receives holds at least
    /// `NODE_PHOTONS` photons, or when their counts say the light is not even over the node (a child
    /// holds n_c photons where an even density would give m_c = n·A_c/A, and |n_c − m_c| >
    /// 3·√(m_c + 1), a Poisson count's 3σ, as the caustic map's kernels decide); otherwise the node
    /// is cut there, and every receiving leaf below it takes Φ_cut / A_receiving,cut.
    ///
    /// Weak, spread light (a mirror ball's over a room, the light reflected through glass, photons a
    /// few per input triangle of a finely tessellated wall) is then spread over a cluster of
    /// neighbours rather than grain on single triangles, while a dense focus, or a patch of light
    /// beside a dim corner, keeps its edge. The clusters split the two sides of two-sided surfaces
    /// first (`clusters`), so light never crosses to a back side. Power is kept exactly: Σ over the
    /// receiving leaves of A_open·E_c = Σ Φ.
    pub fn node_irradiance(&self, nodes: &Nodes, inputs: &InputTriangles, root: usize) -> Vec<Vec3> {
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
        // Receiving open area per node, and the clusters' photons: children come after their
        // parent, so one pass in reverse index order sees every child first.
        let mut receiving = vec![0.0f64; nodes.len()];
        for n in (0..nodes.len()).rev() {
            if nodes.is_leaf(n) {
                let open = if nodes.open_area[n] > 0.0 { nodes.open_area[n] } else { nodes.area[n] };
                receiving[n] = if nodes.reflectance_max[n] > 0.0 { open as f64 } else { 0.0 };
            } else {
                receiving[n] = nodes.children(n).map(|c| receiving[c]).sum();
                if nodes.is_cluster[n] {
                    flux[n] = nodes.children(n).map(|c| flux[c]).sum();
                    count[n] = nodes.children(n).map(|c| count[c]).sum();
                }
            }
        }
        let irradiance = |n: usize| if receiving[n] > 0.0 { (flux[n] / receiving[n]).as_vec3() } else { Vec3::ZERO };
        // Whether node n's receiving children take their own estimates: each holds `NODE_PHOTONS`, or
        // one holds a count that a density even over n would give with Poisson odds beyond 3σ.
        let children_resolve = |n: usize| {
            let mut receivers = nodes.children(n).filter(|&c| receiving[c] > 0.0).peekable();
            receivers.peek().is_none()
                || nodes.children(n).filter(|&c| receiving[c] > 0.0).all(|c| count[c] >= NODE_PHOTONS)
                || receivers.any(|c| {
                    let expected = count[n] as f64 * receiving[c] / receiving[n];
                    (count[c] as f64 - expected).abs() > 3.0 * (expected + 1.0).sqrt()
                })
        };
        let mut out = vec![Vec3::ZERO; nodes.len()];
        // Top-down: (node, the cut node above it, if any); subtrees without photons stay dark.
        let mut stack: Vec<(usize, Option<usize>)> = vec![(root, None)];
        while let Some((n, cut)) = stack.pop() {
            if cut.is_none() && count[n] == 0 {
                continue;
            }
            let cut = cut.or_else(|| (!children_resolve(n)).then_some(n));
            let receives = !nodes.is_leaf(n) || receiving[n] > 0.0;
            out[n] = if receives { irradiance(cut.unwrap_or(n)) } else { Vec3::ZERO };
            stack.extend(nodes.children(n).map(|c| (c, cut)));
        }
        out
    }
}

/// Photons each receiving child of a node must hold for the children to take their own caustic
/// irradiance (`CausticLight::node_irradiance`): a relative noise of about 1/√32 ≈ 18 % at most.
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
        let e = light.node_irradiance(&nodes, &inputs, root);
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
        let e = light.node_irradiance(&nodes, &inputs, root);
        let mean = Vec3::new(3.0, 6.0, 9.0) / nodes.area[root];
        for n in [root, corner, grand, grand + 3] {
            assert!((e[n] - mean).abs().max_element() < 1e-6, "node {n}: {} against {mean}", e[n]);
        }
        assert!((leaf_power(&nodes, &e) - Vec3::new(3.0, 6.0, 9.0)).abs().max_element() < 1e-4);
    }

    /// A cluster of two grey triangles and a black one, with photons on one grey triangle only: five
    /// are too few to tell the light from even (expected 2.5 on each, 5 and 0 are within 3σ), so the
    /// cluster is cut, both grey triangles take the same irradiance and the black one none; twenty
    /// are not even (20 and 0 against 10), so each triangle keeps its own. The grey ones' power is
    /// the photons' either way.
    #[test]
    fn photons_spread_over_a_clusters_receiving_members_only_where_the_light_looks_even() {
        let mut nodes = Nodes::default();
        let root = nodes.push_cluster_slot() as usize;
        let grey = Vec3::splat(0.5);
        let tri = |x: f32| [Vec3::new(x, 0.0, 0.0), Vec3::new(x + 1.0, 0.0, 0.0), Vec3::new(x, 1.0, 0.0)];
        let first = nodes.push_element(tri(0.0), 0, 0, grey, Vec3::ZERO);
        nodes.push_element(tri(2.0), 1, 0, grey, Vec3::ZERO);
        nodes.push_element(tri(4.0), 2, 0, Vec3::ZERO, Vec3::ZERO);
        nodes.set_cluster_children(root, first, 3);
        let inputs = InputTriangles {
            surface: vec![0, 1, 2],
            back: vec![false; 3],
            material: vec![0, 0, 1],
            node: vec![first, first + 1, first + 2],
        };
        let (a, b, black) = (first as usize, first as usize + 1, first as usize + 2);
        let power = Vec3::new(1.0, 2.0, 3.0);
        for (photons, spread) in [(5, true), (20, false)] {
            let light = CausticLight::new(vec![(0, Vec3::new(0.2, 0.2, 0.0), power); photons], 0);
            let e = light.node_irradiance(&nodes, &inputs, root);
            assert_eq!(e[a] == e[b], spread, "{photons} photons: {} and {}", e[a], e[b]);
            assert_eq!(e[black], Vec3::ZERO);
            let total = e[a] * nodes.area[a] + e[b] * nodes.area[b];
            assert!((total - power * photons as f32).abs().max_element() < 1e-4, "{total}");
        }
    }

    /// No photons: nothing lights anything.
    #[test]
    fn no_photons_give_no_caustic_light() {
        let mut nodes = Nodes::default();
        let root = nodes.push_element([Vec3::ZERO, Vec3::X, Vec3::Y], 0, 0, Vec3::ONE, Vec3::ZERO);
        let inputs = InputTriangles { surface: vec![0], back: vec![false], material: vec![0], node: vec![root] };
        let e = CausticLight::default().node_irradiance(&nodes, &inputs, root as usize);
        assert_eq!(e, vec![Vec3::ZERO]);
    }
}
