//! Candidate pairs for the pairwise checks: a uniform grid over the faces' bounding boxes that visits
//! each overlapping pair once.

use glam::DVec3;
use rayon::prelude::*;

/// Every pair `(i, j)` (i < j) of overlapping boxes `(lo, hi)`, once, ordered by grid cell and then by
/// index within the cell. A uniform grid of at most ~4n cells, sized from the boxes' mean extent; a pair
/// found in several cells is kept only in the cell holding the low corner of the boxes' intersection.
/// Cells are scanned in parallel; the order does not depend on the number of threads.
pub(super) fn candidate_pairs(boxes: &[(DVec3, DVec3)]) -> Vec<(u32, u32)> {
    let n = boxes.len();
    if n < 2 {
        return Vec::new();
    }
    let glo = boxes.iter().fold(DVec3::INFINITY, |a, b| a.min(b.0));
    let ghi = boxes.iter().fold(DVec3::NEG_INFINITY, |a, b| a.max(b.1));
    let extent = ghi - glo;
    let mean = boxes.iter().map(|b| (b.1 - b.0).max_element()).sum::<f64>() / n as f64;
    let max_cells = (4 * n).clamp(1, 1 << 22);
    let mut cell = if mean > 0.0 { mean } else { extent.max_element().max(1.0) };
    let resolution = |cell: f64| -> [usize; 3] {
        extent.to_array().map(|e| if cell > 0.0 { ((e / cell).ceil() as usize).clamp(1, 1024) } else { 1 })
    };
    let mut res = resolution(cell);
    while res.iter().product::<usize>() > max_cells {
        cell *= 1.25;
        res = resolution(cell);
    }
    let cell_of = |p: DVec3| -> [usize; 3] {
        let mut c = [0usize; 3];
        for a in 0..3 {
            if extent[a] > 0.0 {
                let f = ((p[a] - glo[a]) / extent[a] * res[a] as f64).floor();
                c[a] = if f > 0.0 { (f as usize).min(res[a] - 1) } else { 0 };
            }
        }
        c
    };
    let flat = |c: [usize; 3]| (c[2] * res[1] + c[1]) * res[0] + c[0];
    // Compressed cell lists: count, then fill (boxes in index order within each cell).
    let total = res.iter().product::<usize>();
    let mut start = vec![0usize; total + 1];
    let ranges: Vec<([usize; 3], [usize; 3])> = boxes.iter().map(|b| (cell_of(b.0), cell_of(b.1))).collect();
    let each_cell = |(c0, c1): ([usize; 3], [usize; 3]), f: &mut dyn FnMut(usize)| {
        for z in c0[2]..=c1[2] {
            for y in c0[1]..=c1[1] {
                for x in c0[0]..=c1[0] {
                    f(flat([x, y, z]));
                }
            }
        }
    };
    for &r in &ranges {
        each_cell(r, &mut |c| start[c + 1] += 1);
    }
    for c in 0..total {
        start[c + 1] += start[c];
    }
    let mut fill = start.clone();
    let mut members = vec![0u32; start[total]];
    for (i, &r) in ranges.iter().enumerate() {
        each_cell(r, &mut |c| {
            members[fill[c]] = i as u32;
            fill[c] += 1;
        });
    }
    (0..total)
        .into_par_iter()
        .flat_map_iter(|c| {
            let list = &members[start[c]..start[c + 1]];
            let mut pairs = Vec::new();
            for (k, &i) in list.iter().enumerate() {
                let (ilo, ihi) = boxes[i as usize];
                for &j in &list[k + 1..] {
                    let (jlo, jhi) = boxes[j as usize];
                    if ilo.cmple(jhi).all() && jlo.cmple(ihi).all() && flat(cell_of(ilo.max(jlo))) == c {
                        pairs.push((i, j));
                    }
                }
            }
            pairs
        })
        .collect()
}
