//! The cluster tree over the input triangles (Smits, Arvo and Greenberg 1994; Sillion 1995): scene
//! surfaces become triangles (quads split in two, two-sided surfaces get a reversed back copy), and a
//! binary tree of clusters over them is built by spatial-median splits, so that initial linking starts
//! from one root self-link instead of O(s²) surface pairs.

use glam::Vec3;
use rayon::prelude::*;

use super::nodes::{Nodes, NONE};
use super::texels::{ElementMaterial, SurfaceTexels};
use super::HierarchyError;
use crate::scene::SceneDescription;

/// Cold data of the input triangles (index = input triangle).
#[derive(Clone, Debug, Default)]
pub struct InputTriangles {
    /// Scene surface the triangle comes from.
    pub surface: Vec<u32>,
    /// The reversed back copy of a two-sided surface.
    pub back: Vec<bool>,
    pub material: Vec<u32>,
    /// Node of the triangle in `Nodes`.
    pub node: Vec<u32>,
}

/// Triangles for the ray accelerator: one per front input triangle that occludes (not a cut-out:
/// `texels::ElementMaterial::is_cut_out`).
#[derive(Clone, Debug, Default)]
pub struct TracingTriangles {
    pub positions: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
    /// Per triangle: its surface is two-sided (its back is a front too; `contact` needs this).
    pub two_sided: Vec<bool>,
}

/// The built tree: nodes (root = the index), input triangles and tracing triangles.
pub type Built = (Nodes, u32, InputTriangles, TracingTriangles);

/// `build_textured` for an untextured scene: every input triangle takes its material's Kd and π·Ke.
pub fn build(scene: &SceneDescription) -> Result<Built, HierarchyError> {
    build_textured(scene, &SurfaceTexels::new(scene, std::sync::Arc::default()))
}

/// Turns the scene's surfaces into input-triangle nodes and builds the cluster tree over them. Each
/// input triangle reflects and emits what `texels` gives it (its texture means; `ElementMaterial::
/// solved`), and front triangles that are cut-outs are left out of the tracing triangles.
/// Returns the nodes (root = the returned index), the input triangles and the tracing triangles.
pub fn build_textured(scene: &SceneDescription, texels: &SurfaceTexels) -> Result<Built, HierarchyError> {
    let mut nodes = Nodes::default();
    let mut inputs = InputTriangles::default();
    let mut tracing = TracingTriangles::default();
    // The non-degenerate triangles of every surface (quads fanned), with their surface: their texture
    // means are computed in parallel below, in this order.
    let mut fans: Vec<(u32, [Vec3; 3])> = Vec::new();
    for (s, surface) in scene.surfaces.iter().enumerate() {
        if scene.materials.get(surface.material as usize).is_none() {
            return Err(HierarchyError::UnknownMaterial {
                surface: s,
                material: surface.material,
                location: surface.source.to_string(),
            });
        }
        let v = &surface.vertices;
        let fan: Vec<[Vec3; 3]> = match v.len() {
            3 => vec![[v[0], v[1], v[2]]],
            4 => vec![[v[0], v[1], v[2]], [v[0], v[2], v[3]]],
            n => {
                return Err(HierarchyError::NotTriangleOrQuad {
                    surface: s,
                    vertices: n,
                    location: surface.source.to_string(),
                })
            }
        };
        for tri in fan {
            let area = 0.5 * (tri[1] - tri[0]).cross(tri[2] - tri[0]).length();
            if !(area > 0.0) || !area.is_finite() {
                continue; // degenerate: carries no energy, and the parser already warned
            }
            fans.push((s as u32, tri));
        }
    }
    let materials: Vec<(ElementMaterial, Option<ElementMaterial>)> = fans
        .par_iter()
        .map(|&(s, tri)| {
            let back =
                scene.surfaces[s as usize].two_sided.then(|| texels.element_materials(s, [tri[0], tri[2], tri[1]]));
            (texels.element_materials(s, tri), back)
        })
        .collect();
    let mut corners_of: Vec<[Vec3; 3]> = Vec::new();
    let mut meta: Vec<(u32, bool, u32)> = Vec::new();
    let mut solved: Vec<(Vec3, Vec3)> = Vec::new();
    for (&(s, tri), (front, back)) in fans.iter().zip(materials) {
        let material = scene.surfaces[s as usize].material;
        if !front.is_cut_out() {
            let base = tracing.positions.len() as u32;
            tracing.positions.extend_from_slice(&tri);
            tracing.triangles.push([base, base + 1, base + 2]);
            tracing.two_sided.push(scene.surfaces[s as usize].two_sided);
        }
        corners_of.push(tri);
        meta.push((s, false, material));
        solved.push(front.solved());
        if let Some(back) = back {
            corners_of.push([tri[0], tri[2], tri[1]]);
            meta.push((s, true, material));
            solved.push(back.solved());
        }
    }
    if corners_of.is_empty() {
        return Err(HierarchyError::NoSurfaces);
    }
    let count = corners_of.len();
    inputs.surface = meta.iter().map(|m| m.0).collect();
    inputs.back = meta.iter().map(|m| m.1).collect();
    inputs.material = meta.iter().map(|m| m.2).collect();
    inputs.node = vec![NONE; count];
    // The tree is split and boxed along the scene's own axes (`SceneDescription::frame`): a room
    // built at an angle to the world's gets the tree it would get along them.
    nodes.frame = scene.frame();
    let centroid: Vec<Vec3> = corners_of.iter().map(|t| nodes.frame.to_frame((t[0] + t[1] + t[2]) / 3.0)).collect();
    let mut push_input = |nodes: &mut Nodes, i: usize| -> u32 {
        let (reflectance, emission) = solved[i];
        let node = nodes.push_element(corners_of[i], i as u32, 0, reflectance, emission);
        inputs.node[i] = node;
        node
    };
    let all: Vec<u32> = (0..count as u32).collect();
    if count == 1 {
        let root = push_input(&mut nodes, 0);
        return Ok((nodes, root, inputs, tracing));
    }
    // Breadth-first: each cluster's two children are pushed together, so they are contiguous.
    let root = nodes.push_cluster_slot();
    let mut queue = std::collections::VecDeque::from([(root, all)]);
    let mut aggregate = Vec::new();
    while let Some((cluster, items)) = queue.pop_front() {
        let (left, right) = match split_sides(&inputs.back, &items) {
            Some(sides) => sides,
            None => median_split(&centroid, items),
        };
        let first = nodes.len() as u32;
        for part in [left, right] {
            if part.len() == 1 {
                push_input(&mut nodes, part[0] as usize);
            } else {
                let slot = nodes.push_cluster_slot();
                queue.push_back((slot, part));
            }
        }
        aggregate.push((cluster, first));
    }
    // Children were created after their parents: aggregate in reverse creation order.
    for &(cluster, first) in aggregate.iter().rev() {
        nodes.set_cluster_children(cluster as usize, first, 2);
    }
    Ok((nodes, root, inputs, tracing))
}

/// Splits `items` into the front sides and the back sides of their input triangles (`back`), or
/// `None` when they are all on one side. The root of a scene with two-sided surfaces is split this
/// way, so that no cluster holds both sides of a sheet.
///
/// Why: the two sides of a two-sided triangle share its centroid, so every centroid split kept them
/// together down to clusters of one front and its back, and a cluster sends the area-weighted mean of
/// its members' exitance (`gather::pulled`): a wall lit on its front and dark behind sent half its
/// light over every cluster link. The same rooms with `two_sided = true` (backs never lit) came out
/// 3–5% darker on average and blotchy (alcove_hall relMSE 0.00157 → 0.0294; docs/accuracy.md,
/// session 17); the full matrix was unchanged.
fn split_sides(back: &[bool], items: &[u32]) -> Option<(Vec<u32>, Vec<u32>)> {
    let (backs, fronts): (Vec<u32>, Vec<u32>) = items.iter().partition(|&&i| back[i as usize]);
    (!fronts.is_empty() && !backs.is_empty()).then_some((fronts, backs))
}

/// Centroid coordinates closer than this times the largest magnitude along the split axis tie in
/// `median_split` (about 34 f32 ulps: a wall of a room turned 30° about y, written to an OBJ and
/// turned back, scatters its centroids by a few).
pub const TIE_TOLERANCE: f32 = 4e-6;

/// Splits `items` (at least two) at the median of their centroids (in the scene's frame) along the
/// longest axis of the centroids' bounds, without cutting through a group of centroids at the
/// median's coordinate: the group (often one plane of coplanar triangles, such as one face of a
/// wall) goes whole to the side that keeps the halves closer to equal, so the split plane falls
/// between distinct coordinates. Coordinates within `TIE_TOLERANCE` of the axis's magnitude count as
/// equal: a wall at an angle to the world axes has its coordinates along the frame's axis rounded
/// by its vertices' f32 positions and the rotation. Only when every centroid shares the coordinate
/// are ties broken by index. Deterministic.
///
/// Why: a plain count median cut the lit face of a two-room wall (all its centroids on z = 4) by
/// index, and one lit triangle joined the cluster of the whole dark room behind it, whose links then
/// averaged its exitance into what the dark room received (tests/hierarchy.rs
/// `light_does_not_leak_through_a_wall_into_a_dark_room`; docs/accuracy.md, session 16).
fn median_split(centroid: &[Vec3], mut items: Vec<u32>) -> (Vec<u32>, Vec<u32>) {
    let (lo, hi) = items
        .iter()
        .map(|&i| centroid[i as usize])
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), c| (lo.min(c), hi.max(c)));
    let extent = hi - lo;
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let key = |i: u32| centroid[i as usize][axis];
    let tolerance = TIE_TOLERANCE * lo[axis].abs().max(hi[axis].abs());
    let mid = items.len() / 2;
    items.select_nth_unstable_by(mid, |&a, &b| key(a).total_cmp(&key(b)).then(a.cmp(&b)));
    let at = key(items[mid]);
    // items[..mid] ≤ at ≤ items[mid..]: those within `tolerance` of `at` are the tie group across
    // the cut.
    let below = items[..mid].iter().filter(|&&i| key(i) < at - tolerance).count();
    let above = items[mid..].iter().filter(|&&i| key(i) > at + tolerance).count();
    let n = items.len();
    // Cut before the group (left = `below` items) or after it (left = n − `above`), whichever is
    // nearer the median; neither when it would leave a side empty.
    let candidates = [below, n - above].into_iter().filter(|&k| k > 0 && k < n);
    let Some(cut) = candidates.min_by_key(|&k| k.abs_diff(mid)) else {
        let right = items.split_off(mid);
        return (items, right);
    };
    if cut != mid {
        // Strictly below `at` first, then the group, then strictly above: a stable order by (key, index).
        items.sort_unstable_by(|&a, &b| key(a).total_cmp(&key(b)).then(a.cmp(&b)));
    }
    let right = items.split_off(cut);
    (items, right)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Five centroids on the plane z = 4 (one face of a wall) and four on each side: the count
    /// median (index 6 of 13) falls inside the plane's group, and the whole group goes to the side
    /// that keeps the halves nearer equal: the cut before the group (4 | 9) is 2 from the median,
    /// the one after it (9 | 4) 3.
    #[test]
    fn a_median_split_keeps_a_plane_of_equal_coordinates_on_one_side() {
        let mut centroid = Vec::new();
        for z in [0.0, 1.0, 2.0, 3.0] {
            centroid.push(Vec3::new(0.5, 0.5, z));
        }
        for k in 0..5 {
            centroid.push(Vec3::new(k as f32 * 0.1, 0.3, 4.0));
        }
        for z in [5.0, 6.0, 7.0, 8.0] {
            centroid.push(Vec3::new(0.5, 0.5, z));
        }
        let (left, right) = median_split(&centroid, (0..centroid.len() as u32).collect());
        let on_plane = |side: &[u32]| side.iter().filter(|&&i| centroid[i as usize].z == 4.0).count();
        assert!(on_plane(&left) == 5 || on_plane(&right) == 5, "the plane was cut: {left:?} | {right:?}");
        assert_eq!((left.len(), right.len()), (4, 9));
        assert!(left.iter().all(|&i| centroid[i as usize].z <= 4.0));
        assert!(right.iter().all(|&i| centroid[i as usize].z >= 4.0));
    }

    /// Fronts and backs go to different sides, whatever their centroids; one side alone is not split.
    #[test]
    fn the_two_sides_of_a_sheet_are_split_apart() {
        let back = [false, true, false, true, false];
        let (fronts, backs) = split_sides(&back, &[0, 1, 2, 3, 4]).expect("both sides present");
        assert_eq!((fronts, backs), (vec![0, 2, 4], vec![1, 3]));
        assert_eq!(split_sides(&back, &[0, 2, 4]), None);
        assert_eq!(split_sides(&back, &[1, 3]), None);
    }

    /// Without ties the split is the plain count median.
    #[test]
    fn a_median_split_without_ties_halves_the_items() {
        let centroid: Vec<Vec3> = (0..9).map(|k| Vec3::new(k as f32, 0.0, 0.0)).collect();
        let (left, right) = median_split(&centroid, (0..9).collect());
        assert_eq!((left.len(), right.len()), (4, 5));
        assert!(left.iter().all(|&i| i < 4));
    }

    /// All centroids equal along every axis: ties are broken by index, both sides non-empty.
    #[test]
    fn a_median_split_of_coincident_centroids_still_splits() {
        let centroid = vec![Vec3::ONE; 6];
        let (left, right) = median_split(&centroid, (0..6).collect());
        assert_eq!((left.len(), right.len()), (3, 3));
    }
}
