//! The record of an adaptive refinement: which elements each level split. A solution file carries it
//! (format version 4) in place of the refined mesh, and `replay` rebuilds that mesh from the scene's
//! patch mesh with the same code the solve used (`split_level`), so pass two reads a loaded adaptive
//! solution on exactly the mesh it was solved on: same elements, parents, hanging vertices and bytes.

use std::sync::Arc;

use super::subdivide::{self, EdgeMidpoints};
use crate::material::SceneTextures;
use crate::mesh::Mesh;
use crate::scene::SceneDescription;

/// The elements one level split, on a mesh of `elements` elements.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LevelSplits {
    /// Elements of the mesh this level split (the previous level's result, or the patch mesh).
    pub elements: u64,
    /// Indices of the split elements, ascending.
    pub split: Vec<u32>,
}

/// Every level of an adaptive refinement, first to last (empty: the patch mesh was not split).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Refinement {
    pub levels: Vec<LevelSplits>,
}

/// Why a recorded refinement does not fit the scene it is replayed on (the scene changed since).
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum RefinementError {
    #[error("level {level} was recorded on {recorded} elements, but the scene meshes to {found} there")]
    ElementCount { level: usize, recorded: u64, found: u64 },
    #[error("level {level} splits element {element}, but its mesh has {elements} elements")]
    ElementOutOfRange { level: usize, element: u32, elements: u64 },
}

impl Refinement {
    /// Appends the level that split every element `e` with `split[e]`.
    pub fn record(&mut self, split: &[bool]) {
        let chosen = split.iter().enumerate().filter(|(_, &s)| s).map(|(e, _)| e as u32).collect();
        self.levels.push(LevelSplits { elements: split.len() as u64, split: chosen });
    }

    /// Total split indices over all levels.
    pub fn split_count(&self) -> usize {
        self.levels.iter().map(|l| l.split.len()).sum()
    }

    /// Whether the levels are consistent on their own: indices ascending and within their level's
    /// mesh, and each level's element count that of the level before with every split element
    /// replaced by four (n_{k+1} = n_k + 3·s_k). A file that breaks this is corrupted.
    pub fn is_consistent(&self) -> bool {
        let ascending = |l: &LevelSplits| {
            l.split.windows(2).all(|w| w[0] < w[1]) && l.split.last().is_none_or(|&e| (e as u64) < l.elements)
        };
        self.levels.iter().all(ascending)
            && self.levels.windows(2).all(|w| w[1].elements == w[0].elements + 3 * w[0].split.len() as u64)
    }

    /// The refined mesh: `patches` (the scene's patch mesh, `patch_mesh`) split level by level as
    /// recorded, with `split_level`, exactly as the solve did.
    pub fn replay(&self, patches: Mesh) -> Result<Mesh, RefinementError> {
        let mut mesh = patches;
        let mut midpoints = EdgeMidpoints::default();
        for (level, splits) in self.levels.iter().enumerate() {
            let found = mesh.elements.len() as u64;
            if splits.elements != found {
                return Err(RefinementError::ElementCount { level, recorded: splits.elements, found });
            }
            let mut split = vec![false; mesh.elements.len()];
            for &e in &splits.split {
                let slot = split.get_mut(e as usize).ok_or(RefinementError::ElementOutOfRange {
                    level,
                    element: e,
                    elements: found,
                })?;
                *slot = true;
            }
            mesh = split_level(&mesh, &split, &mut midpoints);
        }
        Ok(mesh)
    }
}

/// The patch mesh of `scene`: its uniform mesh at `max_element_edge` with `textures`, and its buried
/// elements marked (what the adaptive solve starts from).
pub fn patch_mesh(scene: &SceneDescription, textures: Arc<SceneTextures>) -> Mesh {
    let mut mesh = Mesh::build_with_textures(scene, scene.radiosity.max_element_edge, textures);
    (mesh.element_buried, mesh.element_eye) = crate::burial::bury(&mesh);
    mesh
}

/// One level of refinement: `mesh` with the elements where `split` is true split into four
/// (`subdivide::split`), and the new mesh's buried elements marked.
pub fn split_level(mesh: &Mesh, split: &[bool], midpoints: &mut EdgeMidpoints) -> Mesh {
    let mut refined = subdivide::split(mesh, split, midpoints);
    (refined.element_buried, refined.element_eye) = crate::burial::bury(&refined);
    refined
}

/// The mesh a loaded adaptive solution lives on: the scene's patch mesh refined as `refinement` says.
pub fn mesh_of(
    scene: &SceneDescription,
    refinement: &Refinement,
    textures: Arc<SceneTextures>,
) -> Result<Mesh, RefinementError> {
    refinement.replay(patch_mesh(scene, textures))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn level(elements: u64, split: &[u32]) -> LevelSplits {
        LevelSplits { elements, split: split.to_vec() }
    }

    #[test]
    fn levels_are_consistent_only_when_each_counts_the_splits_before_it() {
        let good = Refinement { levels: vec![level(4, &[0, 3]), level(10, &[9])] };
        assert!(good.is_consistent());
        assert!(!Refinement { levels: vec![level(4, &[0, 3]), level(9, &[])] }.is_consistent());
        assert!(!Refinement { levels: vec![level(4, &[3, 0])] }.is_consistent(), "not ascending");
        assert!(!Refinement { levels: vec![level(4, &[4])] }.is_consistent(), "past the mesh");
        assert!(Refinement::default().is_consistent());
    }

    #[test]
    fn recording_keeps_the_chosen_elements_in_order() {
        let mut r = Refinement::default();
        r.record(&[false, true, false, true]);
        assert_eq!(r.levels, vec![level(4, &[1, 3])]);
        assert_eq!(r.split_count(), 2);
    }
}
