//! The hierarchy seen from a point through a hemicube: a cut of the cluster tree drawn into an item
//! buffer, coarse nodes where they are small on the hemicube and fine ones where they are near.
//!
//! From the eye p (unit normal n) the tree is walked from the root. A node whose bounding sphere
//! (centre c, radius r) lies behind the base plane, (c − p)·n < −r, is skipped. A node seen at most
//! `cut_pixels` hemicube pixels across, r/|c − p| ≤ cut_pixels/N (a top-face pixel is 2/N wide at
//! unit distance), is drawn whole: an element as its own triangle, exact, showing the open-area mean
//! of its leaves; a cluster as a square facing p, at its centre, of its lobes' projected area
//! towards p (`Lobes::projected_towards`, at most its sphere's disc π r²), showing its lobes'
//! exitance B̂(ω) (`Lobes::sent`). Larger nodes are opened, down to the leaves. The item buffer keeps
//! the nearest surface in every pixel, and the irradiance at p is the Nusselt analog's sum
//!
//! E(p) = Σ_j F_j·B_j,  F_j = Σ ΔF over the pixels that show node j
//!
//! (Cohen and Greenberg 1985). A leaf seen from behind hides what lies behind it and shows nothing
//! (a one-sided surface is black from behind, as pass two sees it), unless its surface is two-sided:
//! then its back sheet faces p in its place.

use glam::{DVec3, Vec3};

use super::clusters::InputTriangles;
use super::lobes::Lobes;
use super::nodes::Nodes;
use crate::radiosity::hemicube::{Hemicube, HemicubeFrame, ItemBuffer};

/// The hierarchy as the hemicube draws it.
pub struct CutScene<'a> {
    pub nodes: &'a Nodes,
    /// Per node: the exitance it shows when drawn as its own polygon (W/m²).
    pub exitance: &'a [DVec3],
    /// The clusters' lobes over the same exitance.
    pub lobes: &'a Lobes,
    /// Per input triangle: its surface is two-sided (a front and a back sheet).
    pub two_sided: &'a [bool],
    pub root: usize,
}

/// Per input triangle: whether its surface is two-sided (it has a back sheet among the inputs).
pub fn two_sided_inputs(inputs: &InputTriangles) -> Vec<bool> {
    let surfaces = inputs.surface.iter().map(|&s| s as usize + 1).max().unwrap_or(0);
    let mut two_sided = vec![false; surfaces];
    for (&s, &back) in inputs.surface.iter().zip(&inputs.back) {
        two_sided[s as usize] |= back;
    }
    inputs.surface.iter().map(|&s| two_sided[s as usize]).collect()
}

/// What one hemicube saw.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CutIrradiance {
    /// E(p) = Σ_j F_j·B_j (W/m²).
    pub irradiance: DVec3,
    /// Σ_j F_j over the nodes seen (1 where every direction meets a surface, up to the hemicube's
    /// O(1/N²) error; the backs of one-sided surfaces count).
    pub coverage: f64,
    /// Polygons drawn: the cut's size.
    pub drawn: u32,
}

/// E(p) at `eye` (already off the surface) about unit `normal`, the hemicube turned by
/// `rotation_rad` about it (see the module's doc).
pub fn irradiance_at(
    scene: &CutScene,
    hc: &Hemicube,
    buffers: &mut ItemBuffer,
    eye: Vec3,
    normal: Vec3,
    rotation_rad: f32,
    cut_pixels: f32,
) -> CutIrradiance {
    let nodes = scene.nodes;
    let back_item = nodes.len() as u32;
    let small = cut_pixels / hc.resolution_px() as f32;
    buffers.begin(hc, HemicubeFrame::new(eye, normal, rotation_rad));
    let mut drawn = 0u32;
    let mut stack = vec![scene.root];
    while let Some(n) = stack.pop() {
        let (c, r) = (nodes.centre[n], nodes.radius[n]);
        let to = c - eye;
        if to.dot(normal) < -r {
            continue;
        }
        let d = to.length();
        let whole = nodes.is_leaf(n) || (d > r && r <= small * d);
        if !whole {
            stack.extend(nodes.children(n));
            continue;
        }
        drawn += 1;
        draw_whole(scene, hc, buffers, n, eye, n as u32, back_item);
    }
    let (mut irradiance, mut coverage) = (DVec3::ZERO, 0.0f64);
    buffers.finish(hc, |j, f| {
        coverage += f;
        let j = j as usize;
        if j == back_item as usize {
            return;
        }
        let b = if nodes.is_cluster[j] {
            let omega = (eye - nodes.centre[j]).normalize_or_zero();
            scene.lobes.sent(j, omega).unwrap_or(scene.exitance[j])
        } else {
            scene.exitance[j]
        };
        irradiance += b * f;
    });
    CutIrradiance { irradiance, coverage, drawn }
}

/// Draws node `n` whole into `buffers` as seen from `eye` (see the module's doc): an element as its
/// own triangle under `item` (its back, when p sees the back of a one-sided surface, under
/// `back_item`; nothing when the surface is two-sided, whose back sheet is another node); a cluster
/// as a square facing p of its lobes' projected area towards p, under `item`.
pub fn draw_whole(
    scene: &CutScene,
    hc: &Hemicube,
    buffers: &mut ItemBuffer,
    n: usize,
    eye: Vec3,
    item: u32,
    back_item: u32,
) {
    let nodes = scene.nodes;
    let (c, r) = (nodes.centre[n], nodes.radius[n]);
    if nodes.is_cluster[n] {
        let to = c - eye;
        let d = to.length();
        if d <= 0.0 {
            return;
        }
        let omega = -to / d;
        let area = scene.lobes.projected_towards(n, omega).unwrap_or(0.0).min(std::f64::consts::PI * (r * r) as f64);
        if area > 0.0 {
            let half = 0.5 * area.sqrt() as f32;
            let t = omega.any_orthonormal_vector();
            let b = omega.cross(t);
            let square = [c - half * (t + b), c + half * (t - b), c + half * (t + b), c - half * (t - b)];
            buffers.add_polygon(hc, item, &square, omega, c);
        }
        return;
    }
    let corners = nodes.corners[n];
    let facing = (c - eye).dot(nodes.normal[n]) < 0.0;
    if facing {
        buffers.add_polygon(hc, item, &corners, nodes.normal[n], c);
    } else if !scene.two_sided[nodes.input[n] as usize] {
        buffers.add_polygon(hc, back_item, &[corners[0], corners[2], corners[1]], -nodes.normal[n], c);
    }
}
