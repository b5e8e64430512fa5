//! Welded corners: one id for all corners within the tolerance of each other, so that edges shared by
//! neighbouring faces are recognised even when their coordinates differ by rounding.

use super::Poly;
use glam::DVec3;
use std::collections::HashMap;

/// Gives every corner an id shared by all corners within `tolerance` of the first one seen (a spatial
/// hash with cells of the tolerance's size, searching the 27 cells around).
pub(super) fn weld_vertices(polys: &[Option<Poly>], tolerance: f64) -> Vec<Vec<u32>> {
    let mut cells: HashMap<[i64; 3], Vec<(DVec3, u32)>> = HashMap::new();
    let mut next = 0u32;
    let key = |v: DVec3| (v / tolerance).floor().to_array().map(|x| x as i64);
    polys
        .iter()
        .map(|p| {
            let Some(p) = p else { return Vec::new() };
            p.vertices
                .iter()
                .map(|&v| {
                    let k = key(v);
                    for dz in -1..=1i64 {
                        for dy in -1..=1i64 {
                            for dx in -1..=1i64 {
                                let c = [k[0].saturating_add(dx), k[1].saturating_add(dy), k[2].saturating_add(dz)];
                                if let Some(list) = cells.get(&c) {
                                    if let Some(&(_, id)) = list.iter().find(|(w, _)| (*w - v).length() <= tolerance) {
                                        return id;
                                    }
                                }
                            }
                        }
                    }
                    let id = next;
                    next += 1;
                    cells.entry(k).or_default().push((v, id));
                    id
                })
                .collect()
        })
        .collect()
}

/// A welded edge's key: its two corner ids, the lower first (so both directions give one key).
pub(super) fn edge_key(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}
