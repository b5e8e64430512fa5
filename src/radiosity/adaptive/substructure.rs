//! Substructuring (Cohen, Greenberg, Immel and Brock 1986): a refined mesh keeps the form-factor rows
//! of the elements that were not split, so that a level computes hemicubes only for the new children.
//! A kept row saw each split element whole; its form factor to it is shared among the children by
//! area, so the unsplit receiver gathers the split element's area-mean exitance, as the patch it saw
//! — the patch-level interaction of substructuring — while the children gather from the refined mesh.
//! Only the open children share it: the receiver's hemicube saw the patch's open part, since the part
//! under an object resting on it was hidden by that object, and a buried child's exitance is not the
//! light the receiver saw. Shared over all children, the buried ones' dark share was lost:
//! fixture_room's radiosity view was 2% dark, cornell_box's floor under the boxes too (docs/accuracy.md,
//! session 38).

use std::ops::Range;

use crate::mesh::Mesh;
use crate::radiosity::matrix::{FormFactors, PartialRows};

/// Where each element of a mesh went in its split (`subdivide::split` keeps element order and puts
/// a split element's four children in its place): the range of its indices in the refined mesh.
pub fn new_indices(split: &[bool]) -> Vec<Range<u32>> {
    let mut next = 0u32;
    split
        .iter()
        .map(|&s| {
            let count = if s { 4 } else { 1 };
            next += count;
            next - count..next
        })
        .collect()
}

/// The rows of `refined` (the split of `coarse` by `split`) that can be kept from `coarse_ff`: done for
/// every element that was not split, with
///   F'_{i c} = F_{i p} · A_c / A_open(p)   for each open child c of a split element p (0 for a buried
///   one; A_open the open children's area, A_p where every child is buried), F'_{i j'} = F_{i j}
///   otherwise;
/// the children's rows are left to compute (not done). Rows carry only plain entries: the caller keeps
/// rows only when the scene has no mirrors or glass.
pub fn kept_rows(coarse: &Mesh, coarse_ff: &FormFactors, split: &[bool], refined: &Mesh) -> PartialRows {
    let index = new_indices(split);
    assert_eq!(index.last().map_or(0, |r| r.end) as usize, refined.elements.len());
    let mut ff = FormFactors { row_start: vec![0], ..Default::default() };
    let mut done = Vec::with_capacity(refined.elements.len());
    for (i, range) in index.iter().enumerate() {
        if split[i] {
            for _ in range.clone() {
                ff.plain_end.push(ff.column.len());
                ff.row_start.push(ff.column.len());
                done.push(false);
            }
            continue;
        }
        let (columns, values) = coarse_ff.row(i);
        for (&j, &f) in columns.iter().zip(values) {
            let to = index[j as usize].clone();
            if split[j as usize] {
                let buried = |c: u32| refined.element_buried.get(c as usize).copied().unwrap_or(false);
                let area = |c: u32| refined.elements.area[c as usize];
                let open_area: f32 = to.clone().filter(|&c| !buried(c)).map(area).sum();
                let (sharing, shared_area) =
                    if open_area > 0.0 { (true, open_area) } else { (false, coarse.elements.area[j as usize]) };
                for c in to {
                    ff.column.push(c);
                    ff.value.push(if sharing && buried(c) { 0.0 } else { f * (area(c) / shared_area) });
                }
            } else {
                ff.column.push(to.start);
                ff.value.push(f);
            }
        }
        ff.plain_end.push(ff.column.len());
        ff.row_start.push(ff.column.len());
        done.push(true);
    }
    PartialRows { ff, done, specular: Default::default() }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn new_indices_put_four_children_in_place_of_each_split_element() {
        assert_eq!(new_indices(&[false, true, false]), vec![0..1, 1..5, 5..6]);
    }
}
