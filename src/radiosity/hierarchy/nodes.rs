//! The nodes of the hierarchy as structs of arrays: clusters (groups of input triangles), input
//! triangles, and the elements that 1→4 midpoint subdivision makes below them on demand.

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use std::sync::Arc;

use super::texels::InputTexels;
use crate::scene::frame::Frame;

/// "No node": a leaf's `first_child`, the root's `parent`, a cluster's `input`.
pub const NONE: u32 = u32::MAX;

/// Bytes one node costs in `Nodes` (the sum of its per-node fields), for the memory budget.
pub const NODE_BYTES: usize = std::mem::size_of::<bool>()
    + 3 * std::mem::size_of::<u32>()
    + std::mem::size_of::<u8>() * 2
    + std::mem::size_of::<[Vec3; 3]>()
    + 5 * std::mem::size_of::<Vec3>()
    + 4 * std::mem::size_of::<f32>()
    + 2 * std::mem::size_of::<DVec3>()
    + std::mem::size_of::<f64>();

/// All nodes of the hierarchy. Children of a node are contiguous: `first_child .. first_child +
/// child_count`. Clusters have two children (clusters or input triangles); a subdivided element has
/// four. Hot per-node data (geometry, reflectance, exitance) is kept in parallel arrays.
#[derive(Clone, Debug, Default)]
pub struct Nodes {
    pub is_cluster: Vec<bool>,
    pub parent: Vec<u32>,
    pub first_child: Vec<u32>,
    pub child_count: Vec<u8>,
    /// Subdivision depth below the input triangle (0 for input triangles and clusters).
    pub level: Vec<u8>,
    /// Input triangle an element lies in (`NONE` for clusters).
    pub input: Vec<u32>,
    /// Element corners, counter-clockwise seen from the front; zero for clusters.
    pub corners: Vec<[Vec3; 3]>,
    /// Unit front normal of an element; zero for clusters.
    pub normal: Vec<Vec3>,
    /// Centroid of an element, centre of the bounding box of a cluster's members' corners.
    pub centre: Vec<Vec3>,
    /// Diffuse reflectance (area-weighted mean for a cluster).
    pub reflectance: Vec<Vec3>,
    /// Emitted exitance E = π·Ke, W/m² (area-weighted mean for a cluster).
    pub emission: Vec<Vec3>,
    /// Caustic irradiance E_c (W/m², before reflection): light that reached the node's open part
    /// through mirrors and glass rather than over links (`caustics`); zero for clusters and without
    /// caustic light. Set by `set_caustic_irradiance`; new pieces start at zero until it is set again.
    pub caustic_irradiance: Vec<Vec3>,
    /// Surface area (sum over the contents for a cluster).
    pub area: Vec<f32>,
    /// The part of `area` that is open (m²): not inside a closed object resting on it (`contact`),
    /// so light can reach it. Equal to `area` unless `contact::split_at_contacts` found otherwise;
    /// a sum over the children for an inner node. Pulled exitance is weighted by it, and a node's
    /// gathered power lands on it only.
    pub open_area: Vec<f32>,
    /// Radius of a sphere about `centre` holding the node (a cluster's: half its box's diagonal).
    pub radius: Vec<f32>,
    /// Largest channel of the reflectance, area-averaged over a cluster's children (the ρ of the
    /// error estimate; area-averaging keeps refinement's error sums from growing).
    pub reflectance_max: Vec<f32>,
    /// Exitance B (W/m²); for an inner node, the area-weighted mean of its children's.
    pub exitance: Vec<DVec3>,
    /// Irradiance gathered over the node's own links in the last sweep (W/m², before ρ).
    pub gathered: Vec<DVec3>,
    /// Mean channel of `exitance`, the B of the error estimate (linear, so pulling commutes with it).
    pub exitance_mean: Vec<f64>,
    /// A textured scene's texture means (`texels`): pieces made by `subdivide` take the means over
    /// their own uv image. `None`: pieces inherit their parent's reflectance and emission.
    pub texels: Option<Arc<InputTexels>>,
    /// The axes clusters are boxed along (the scene's principal frame, set by the cluster
    /// build): a cluster's `centre` and `radius` are its members' box in this frame.
    pub frame: Frame,
}

impl Nodes {
    pub fn len(&self) -> usize {
        self.is_cluster.len()
    }

    pub fn is_empty(&self) -> bool {
        self.is_cluster.is_empty()
    }

    pub fn children(&self, node: usize) -> std::ops::Range<usize> {
        let first = self.first_child[node];
        if first == NONE {
            0..0
        } else {
            first as usize..first as usize + self.child_count[node] as usize
        }
    }

    pub fn is_leaf(&self, node: usize) -> bool {
        self.first_child[node] == NONE
    }

    /// What a leaf sends out of light that does not arrive over its links: S = E + ρ·E_c, its
    /// emission and its reflected caustic light (W/m²). The sweeps solve B = S + ρ·G.
    pub fn source_exitance(&self, node: usize) -> DVec3 {
        (self.emission[node] + self.reflectance[node] * self.caustic_irradiance[node]).as_dvec3()
    }

    /// Sets every node's caustic irradiance (`caustics::CausticLight::node_irradiance`, one value
    /// per node).
    pub fn set_caustic_irradiance(&mut self, irradiance: Vec<Vec3>) {
        assert_eq!(irradiance.len(), self.len(), "one caustic irradiance per node");
        self.caustic_irradiance = irradiance;
    }

    /// A/A_open: what the irradiance a node's links bring (a mean over all of it, the hidden part
    /// included, since visibility rays from that part are blocked) is multiplied by on its open part,
    /// so that the gathered power A·G lands on the open area only; 0 for a node with no open area.
    pub fn open_gain(&self, node: usize) -> f64 {
        let open = self.open_area[node];
        if open > 0.0 {
            self.area[node] as f64 / open as f64
        } else {
            0.0
        }
    }

    /// Sets every inner node's `open_area` to the sum over its children (children always come after
    /// their parent, so one pass in reverse index order suffices).
    pub fn sum_open_areas(&mut self) {
        for n in (0..self.len()).rev() {
            if !self.is_leaf(n) {
                let all_open = self.children(n).all(|c| self.open_area[c] == self.area[c]);
                // All open: keep the node's own area bit for bit (a sum of quarters may round).
                self.open_area[n] =
                    if all_open { self.area[n] } else { self.children(n).map(|c| self.open_area[c]).sum() };
            }
        }
    }

    /// The projected area of a node seen from unit direction `towards` (from the node to the viewer),
    /// exact for its members:
    ///
    /// D(ω) = Σ_i A_i · max(0, n_i·ω)
    ///
    /// over the elements of the node (itself for an element; for a cluster, its input triangles, the
    /// first elements below it, whose pieces share their normal). One-sided, like the elements. For
    /// a cluster it walks the members: O(members).
    pub fn projected_area(&self, node: usize, towards: Vec3) -> f64 {
        self.member_sum(node, |m| self.area[m] as f64 * self.normal[m].dot(towards).max(0.0) as f64)
    }

    /// `projected_area` over the members' open areas (`open_area`): D_open(ω) = Σ_i A_open,i ·
    /// max(0, n_i·ω), the area a cluster's incoming light from ω lands on (`gather::arrival_scales`).
    pub fn open_projected_area(&self, node: usize, towards: Vec3) -> f64 {
        self.member_sum(node, |m| self.open_area[m] as f64 * self.normal[m].dot(towards).max(0.0) as f64)
    }

    /// Σ f(m) over the members m of `node`: the node itself for an element, the first elements below
    /// it for a cluster, in a fixed depth-first order (so the f64 sum is reproducible).
    pub fn member_sum(&self, node: usize, f: impl Fn(usize) -> f64) -> f64 {
        if !self.is_cluster[node] {
            return f(node);
        }
        let mut sum = 0.0;
        let mut stack = Vec::with_capacity(64);
        stack.push(node);
        while let Some(n) = stack.pop() {
            if self.is_cluster[n] {
                stack.extend(self.children(n).rev());
            } else {
                sum += f(n);
            }
        }
        sum
    }

    /// Whether `node` has at most `limit` members (see `member_sum`); stops counting past the limit.
    pub fn member_count_within(&self, node: usize, limit: usize) -> bool {
        let mut count = 0;
        let mut stack = vec![node];
        while let Some(n) = stack.pop() {
            if self.is_cluster[n] {
                stack.extend(self.children(n));
            } else {
                count += 1;
                if count > limit {
                    return false;
                }
            }
        }
        true
    }

    /// The members of `node` (see `member_sum`) in the same order.
    pub fn members(&self, node: usize, out: &mut Vec<usize>) {
        out.clear();
        let mut stack = vec![node];
        while let Some(n) = stack.pop() {
            if self.is_cluster[n] {
                stack.extend(self.children(n).rev());
            } else {
                out.push(n);
            }
        }
    }

    /// Appends an element (input triangle or a piece of one) and returns its index.
    pub fn push_element(
        &mut self,
        corners: [Vec3; 3],
        input: u32,
        level: u8,
        reflectance: Vec3,
        emission: Vec3,
    ) -> u32 {
        let cross = (corners[1] - corners[0]).cross(corners[2] - corners[0]);
        let area = 0.5 * cross.length();
        let normal = cross.normalize_or_zero();
        let centre = (corners[0] + corners[1] + corners[2]) / 3.0;
        let radius = corners.iter().map(|c| c.distance(centre)).fold(0.0f32, f32::max);
        self.push(Pushed {
            is_cluster: false,
            input,
            level,
            corners,
            normal,
            centre,
            reflectance,
            emission,
            area,
            radius,
            reflectance_max: reflectance.max_element(),
        })
    }

    /// Appends a cluster with no children yet (see `set_cluster_children`).
    pub fn push_cluster_slot(&mut self) -> u32 {
        self.push(Pushed {
            is_cluster: true,
            input: NONE,
            level: 0,
            corners: [Vec3::ZERO; 3],
            normal: Vec3::ZERO,
            centre: Vec3::ZERO,
            reflectance: Vec3::ZERO,
            emission: Vec3::ZERO,
            area: 0.0,
            radius: 0.0,
            reflectance_max: 0.0,
        })
    }

    fn push(&mut self, n: Pushed) -> u32 {
        let index = self.len() as u32;
        self.is_cluster.push(n.is_cluster);
        self.parent.push(NONE);
        self.first_child.push(NONE);
        self.child_count.push(0);
        self.level.push(n.level);
        self.input.push(n.input);
        self.corners.push(n.corners);
        self.normal.push(n.normal);
        self.centre.push(n.centre);
        self.reflectance.push(n.reflectance);
        self.emission.push(n.emission);
        self.caustic_irradiance.push(Vec3::ZERO);
        self.area.push(n.area);
        self.open_area.push(n.area);
        self.radius.push(n.radius);
        self.reflectance_max.push(n.reflectance_max);
        self.exitance.push(n.emission.as_dvec3());
        self.gathered.push(DVec3::ZERO);
        self.exitance_mean.push(mean_channel(n.emission.as_dvec3()));
        index
    }

    /// Makes the contiguous nodes `first .. first + count` the children of cluster `cluster` and sets
    /// the cluster's aggregate fields from them (area sums, area-weighted means, bounding box).
    pub fn set_cluster_children(&mut self, cluster: usize, first: u32, count: u8) {
        self.first_child[cluster] = first;
        self.child_count[cluster] = count;
        let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        let (mut area, mut open_area) = (0.0f32, 0.0f32);
        let (mut rho, mut emission, mut rho_max) = (Vec3::ZERO, Vec3::ZERO, 0.0f32);
        let mut exitance = DVec3::ZERO;
        for c in first as usize..first as usize + count as usize {
            self.parent[c] = cluster as u32;
            let a = self.area[c];
            area += a;
            open_area += self.open_area[c];
            rho += self.reflectance[c] * a;
            emission += self.emission[c] * a;
            rho_max += self.reflectance_max[c] * a;
            exitance += self.exitance[c] * a as f64;
        }
        // The members' exact corner box (a child cluster's sphere box would grow the radius by up to
        // √3 per level: a 19.6 m² cluster of the rotunda had a 263 m sphere in a 12 m room), along
        // the scene's frame (a wall at an angle to the world axes keeps a thin box).
        let frame = self.frame;
        let mut stack = vec![cluster];
        while let Some(n) = stack.pop() {
            if self.is_cluster[n] {
                stack.extend(self.children(n));
            } else {
                for p in self.corners[n] {
                    let q = frame.to_frame(p);
                    lo = lo.min(q);
                    hi = hi.max(q);
                }
            }
        }
        let inv = if area > 0.0 { 1.0 / area } else { 0.0 };
        self.area[cluster] = area;
        self.open_area[cluster] = open_area;
        self.reflectance[cluster] = rho * inv;
        self.emission[cluster] = emission * inv;
        self.reflectance_max[cluster] = rho_max * inv;
        self.exitance[cluster] = exitance * inv as f64;
        self.exitance_mean[cluster] = mean_channel(self.exitance[cluster]);
        self.centre[cluster] = frame.from_frame((lo + hi) * 0.5);
        self.radius[cluster] = (hi - lo).length() * 0.5;
    }

    /// Splits leaf element `node` 1→4 at its edge midpoints and returns the first child. Children
    /// inherit the parent's exitance (so its pulled value is unchanged) and its reflectance and
    /// emission; with `texels`, the caller then gives the new pieces their own texture means with
    /// `assign_texture_means` (in parallel, once per refinement round). The midpoint of edge (a, b) is
    /// computed as (a + b)·0.5, which is symmetric in a and b, so neighbours compute bit-identical
    /// vertices.
    pub fn subdivide(&mut self, node: usize) -> u32 {
        assert!(!self.is_cluster[node] && self.is_leaf(node), "only leaf elements subdivide");
        let (input, level) = (self.input[node], self.level[node].saturating_add(1));
        let (rho, e) = (self.reflectance[node], self.emission[node]);
        let parent_area = self.area[node];
        let open_quarter = self.open_area[node] * 0.25;
        let exitance = self.exitance[node];
        let first = self.len() as u32;
        for tri in quarters(&self.corners[node]) {
            let child = self.push_element(tri, input, level, rho, e) as usize;
            // Exact quarter areas and the parent's normal keep push-pull exactly conservative; a
            // piece inherits its parent's open share (only `contact` measures it).
            self.area[child] = parent_area * 0.25;
            self.open_area[child] = open_quarter;
            self.normal[child] = self.normal[node];
            self.exitance[child] = exitance;
            self.exitance_mean[child] = mean_channel(exitance);
            self.parent[child] = node as u32;
        }
        self.first_child[node] = first;
        self.child_count[node] = 4;
        first
    }

    /// With `texels`, gives every element from `first` on (the pieces `subdivide` made since the caller
    /// noted `len()`) its own texture means (`assign_element_materials`). Without `texels`, nothing
    /// changes.
    pub fn assign_texture_means(&mut self, first: usize) {
        if let Some(texels) = self.texels.clone() {
            self.assign_element_materials(&texels, first);
        }
    }

    /// Gives every element from `first` on its materials from `texels` (`InputTexels::solved_materials`:
    /// reflectance, emission and the error estimate's ρ); clusters are left as they are. Each is a pure
    /// function of the element's input triangle and corners, so they are computed in parallel and
    /// stored in index order: the same bytes for any thread count. Pieces' texture means
    /// area-average to their parent's up to the pyramid level each is taken at
    /// (`Texture::mean_over_triangle`).
    pub fn assign_element_materials(&mut self, texels: &InputTexels, first: usize) {
        let materials: Vec<Option<(Vec3, Vec3)>> = (first..self.len())
            .into_par_iter()
            .map(|n| (!self.is_cluster[n]).then(|| texels.solved_materials(self.input[n], self.corners[n])))
            .collect();
        for (n, m) in (first..).zip(materials) {
            if let Some((reflectance, emission)) = m {
                self.reflectance[n] = reflectance;
                self.emission[n] = emission;
                self.reflectance_max[n] = reflectance.max_element();
            }
        }
    }
}

/// The four pieces of 1→4 midpoint subdivision, in `Nodes::subdivide`'s child order: the three
/// corner triangles, then the middle one. The midpoint of edge (a, b) is (a + b)·0.5, symmetric in a
/// and b, so neighbours compute bit-identical vertices.
pub fn quarters(corners: &[Vec3; 3]) -> [[Vec3; 3]; 4] {
    let [a, b, c] = *corners;
    let (ab, bc, ca) = ((a + b) * 0.5, (b + c) * 0.5, (c + a) * 0.5);
    [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
}

/// Fields of one new node.
struct Pushed {
    is_cluster: bool,
    input: u32,
    level: u8,
    corners: [Vec3; 3],
    normal: Vec3,
    centre: Vec3,
    reflectance: Vec3,
    emission: Vec3,
    area: f32,
    radius: f32,
    reflectance_max: f32,
}

/// (r + g + b) / 3: the scalar exitance of the error estimate.
pub fn mean_channel(v: DVec3) -> f64 {
    (v.x + v.y + v.z) / 3.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::vec3;

    #[test]
    fn subdivision_makes_four_counter_clockwise_quarters() {
        let mut nodes = Nodes::default();
        let tri = [vec3(0.0, 0.0, 0.0), vec3(2.0, 0.0, 0.0), vec3(0.0, 2.0, 0.0)];
        let root = nodes.push_element(tri, 0, 0, Vec3::splat(0.5), Vec3::ZERO) as usize;
        let first = nodes.subdivide(root) as usize;
        for c in first..first + 4 {
            let k = nodes.corners[c];
            let n = (k[1] - k[0]).cross(k[2] - k[0]);
            assert!(n.z > 0.0, "child {c} is clockwise");
            assert_eq!(nodes.area[c], 0.5);
            assert_eq!(nodes.level[c], 1);
            assert_eq!(nodes.parent[c], root as u32);
        }
    }
}
