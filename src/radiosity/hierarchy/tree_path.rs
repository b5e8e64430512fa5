//! A node's identity that does not depend on the order of subdivision: its path from the node the
//! build made (a cluster or an input triangle, whose index the build fixes) down through the child
//! slots of 1→4 subdivision. Link seeds and the estimates a sharded pass one shares are keyed by it.

use super::nodes::Nodes;
use crate::rng::splitmix64;

/// Levels of subdivision a `TreePath` holds exactly (two bits per level).
pub const MAX_EXACT_DEPTH: u32 = 64;

/// The path of a node: the build node it lies in, how many subdivisions below it, and the child slot
/// (0..4) taken at each, deepest first, two bits each.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct TreePath {
    pub root: u32,
    pub depth: u32,
    pub steps: u128,
}

/// The path of `node`; `None` below `MAX_EXACT_DEPTH` levels of subdivision.
pub fn tree_path(nodes: &Nodes, node: usize) -> Option<TreePath> {
    let (mut at, mut depth, mut steps) = (node, 0u32, 0u128);
    while nodes.level[at] > 0 {
        if depth == MAX_EXACT_DEPTH {
            return None;
        }
        let parent = nodes.parent[at] as usize;
        let slot = (at - nodes.first_child[parent] as usize) as u128;
        steps |= slot << (2 * depth);
        depth += 1;
        at = parent;
    }
    Some(TreePath { root: at as u32, depth, steps })
}

/// A 64-bit hash of `node`'s path (any depth): equal paths give equal hashes, whatever the order in
/// which the nodes were subdivided.
pub fn path_hash(nodes: &Nodes, node: usize) -> u64 {
    let mut at = node;
    let mut hash = 0x7472_6565_7061_7468u64;
    while nodes.level[at] > 0 {
        let parent = nodes.parent[at] as usize;
        hash = splitmix64(hash ^ (at - nodes.first_child[parent] as usize + 1) as u64);
        at = parent;
    }
    splitmix64(hash ^ ((at as u64) << 3))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{vec3, Vec3};

    /// Two triangles subdivided in either order: each piece keeps its path and hash.
    #[test]
    fn a_piece_has_the_same_path_whichever_element_is_subdivided_first() {
        let build = || {
            let mut nodes = Nodes::default();
            for x in [0.0, 5.0] {
                let tri = [vec3(x, 0.0, 0.0), vec3(x + 2.0, 0.0, 0.0), vec3(x, 2.0, 0.0)];
                nodes.push_element(tri, x as u32, 0, Vec3::splat(0.5), Vec3::ZERO);
            }
            nodes
        };
        let (mut a, mut b) = (build(), build());
        let a0 = a.subdivide(0) as usize;
        let a1 = a.subdivide(1) as usize;
        let a2 = a.subdivide(a1 + 3) as usize;
        let b1 = b.subdivide(1) as usize;
        let b2 = b.subdivide(b1 + 3) as usize;
        let b0 = b.subdivide(0) as usize;
        for (x, y) in [(a0 + 2, b0 + 2), (a1 + 3, b1 + 3), (a2 + 1, b2 + 1)] {
            assert_ne!(x, y, "the indices differ");
            assert_eq!(tree_path(&a, x), tree_path(&b, y));
            assert_eq!(path_hash(&a, x), path_hash(&b, y));
        }
        assert_eq!(tree_path(&a, a2 + 1), Some(TreePath { root: 1, depth: 2, steps: 1 | (3 << 2) }));
        assert_ne!(path_hash(&a, a0 + 1), path_hash(&a, a0 + 2));
    }
}
