//! Far patches drawn whole: the cut of a refined mesh that a hemicube draws (Hanrahan, Salzman and
//! Aupperle 1991: interact with a coarse node where it looks small from the receiver). The adaptive
//! mesh splits patches into four, level by level, and keeps each patch's leaves contiguous in element
//! order; a hemicube whose eye is far from a split patch draws the patch's outline as one item and
//! shares the form factor it wins among its leaves by area,
//!   F_{i c} = F_{i p} · A_c / A_p   for every leaf c of patch p,
//! the sharing substructuring already applies to the rows it keeps (`adaptive::substructure`). "Far"
//! is where the patch would cover fewer than `FAR_PATCH_RADIUS_PX` hemicube pixels of radius: there its
//! leaves are a few pixels each and their own form factors mostly aliasing, and what the receiver
//! gathers from them is their area-mean exitance either way, to first order. A hemicube then draws
//! about as many polygons as there are patches plus the leaves near it, not every leaf of the refined
//! mesh. Patches with a buried leaf (under something resting on them) are always drawn as their
//! leaves: sharing by area would give the hidden leaves light that the visible ones gather.

use std::ops::Range;

use glam::Vec3;

use crate::mesh::{Mesh, NONE};

/// A split patch is drawn whole from an eye where its radius r (centre to farthest corner) at
/// distance d covers fewer than this many hemicube pixels at the top face's centre, (r/d)·N/2 for a
/// hemicube N pixels across: from d > r·N/(2·8), 8 radii at the default N = 128.
pub const FAR_PATCH_RADIUS_PX: f32 = 8.0;

/// The split patches of a refined mesh, in element order.
#[derive(Clone, Debug, Default)]
pub struct PatchCut {
    /// The leaves (elements of the refined mesh) of each split patch: contiguous and ascending.
    pub leaves: Vec<Range<u32>>,
    /// Each patch's outline: its corner vertices (`NONE` past a triangle's third), in the refined
    /// mesh's positions.
    pub corners: Vec<[u32; 4]>,
    pub centre: Vec<Vec3>,
    pub normal: Vec<Vec3>,
    pub area: Vec<f32>,
    /// Distance from the centre beyond which an eye draws the patch whole (`FAR_PATCH_RADIUS_PX`).
    pub far_distance: Vec<f32>,
    /// Per element of the refined mesh: the split patch whose first leaf it is, or `NONE`.
    pub first_leaf_of: Vec<u32>,
}

impl PatchCut {
    /// The cut of `refined`, whose elements are the leaves of `patches` (patch p's leaves are
    /// `leaves[p]`, contiguous and in order), for hemicubes `resolution_px` pixels across. Patches
    /// with one leaf, a buried leaf or a leaf that hemicubes do not draw (mostly cut out) are always
    /// drawn as their leaves.
    pub fn new(patches: &Mesh, leaves: &[Range<u32>], refined: &Mesh, resolution_px: u32) -> PatchCut {
        assert_eq!(leaves.len(), patches.elements.len());
        let e = &patches.elements;
        let mut cut = PatchCut { first_leaf_of: vec![NONE; refined.elements.len()], ..Default::default() };
        let drawn_apart = |c: u32| {
            let c = c as usize;
            refined.hidden_from_hemicubes(c) || refined.element_buried.get(c).copied().unwrap_or(false)
        };
        let radii = resolution_px as f32 / (2.0 * FAR_PATCH_RADIUS_PX);
        for (p, range) in leaves.iter().enumerate() {
            if range.len() < 2 || range.clone().any(drawn_apart) {
                continue;
            }
            let radius = e.polygon(&patches.positions, p).map(|x| (x - e.centre[p]).length()).fold(0.0, f32::max);
            cut.first_leaf_of[range.start as usize] = cut.leaves.len() as u32;
            cut.leaves.push(range.clone());
            cut.corners.push(e.corners[p]);
            cut.centre.push(e.centre[p]);
            cut.normal.push(e.normal[p]);
            cut.area.push(e.area[p]);
            cut.far_distance.push(radii * radius);
        }
        cut
    }

    /// Patch p's corner vertices, counter-clockwise: three or four.
    pub fn outline(&self, p: usize) -> &[u32] {
        let corners = &self.corners[p];
        &corners[..if corners[3] == NONE { 3 } else { 4 }]
    }

    /// Number of split patches.
    pub fn len(&self) -> usize {
        self.leaves.len()
    }

    pub fn is_empty(&self) -> bool {
        self.leaves.is_empty()
    }

    /// The split patch starting at element `j`, if one does and `eye` is far enough from it to draw
    /// it whole (and `receiver` is not one of its leaves).
    #[inline]
    pub fn drawn_whole(&self, j: usize, eye: Vec3, receiver: usize) -> Option<usize> {
        let p = *self.first_leaf_of.get(j)?;
        if p == NONE {
            return None;
        }
        let p = p as usize;
        let far = (self.centre[p] - eye).length_squared() > self.far_distance[p] * self.far_distance[p];
        (far && !self.leaves[p].contains(&(receiver as u32))).then_some(p)
    }
}
