//! Form-factor rows known so far: the matrix with empty rows where work is not done, and which rows
//! are done. A checkpoint holds one, so does each shard of a sharded pass one; `rows_file` stores it.

use super::FormFactors;
use crate::radiosity::specular::SpecularStats;

/// The rows of an n-element matrix that are finished (`done[i]`); a row not done is empty in `ff`.
/// Rows of elements that neither reflect nor emit are empty and done from the start.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PartialRows {
    pub ff: FormFactors,
    pub done: Vec<bool>,
    /// Ray statistics of the extended entries of the done rows.
    pub specular: SpecularStats,
}

impl PartialRows {
    /// Elements (rows, done or not).
    pub fn len(&self) -> usize {
        self.done.len()
    }

    pub fn is_empty(&self) -> bool {
        self.done.is_empty()
    }

    /// Rows done.
    pub fn done_count(&self) -> usize {
        self.done.iter().filter(|&&d| d).count()
    }

    /// Whether every row is done (then `ff` is the whole matrix).
    pub fn is_complete(&self) -> bool {
        self.done.iter().all(|&d| d)
    }

    /// Row i as computed: its entries (plain, then extended) and the length of the plain part.
    pub fn row_entries(&self, i: usize) -> (Vec<(u32, f32)>, usize) {
        let (plain_c, plain_v) = self.ff.row_plain(i);
        let (ext_c, ext_v) = self.ff.row_extended(i);
        let entries = plain_c.iter().zip(plain_v).chain(ext_c.iter().zip(ext_v)).map(|(&c, &v)| (c, v)).collect();
        (entries, plain_c.len())
    }

    /// Joins parts with disjoint done rows of the same matrix: each row comes from the part that has
    /// it done (empty if none). `None` when the parts disagree on the element count.
    pub fn union(parts: &[PartialRows]) -> Option<PartialRows> {
        let n = parts.first().map_or(0, PartialRows::len);
        if parts.iter().any(|p| p.len() != n) {
            return None;
        }
        let mut ff = FormFactors { row_start: vec![0], ..Default::default() };
        let mut done = vec![false; n];
        let mut specular = SpecularStats::default();
        for part in parts {
            specular += part.specular;
        }
        for (i, done_i) in done.iter_mut().enumerate() {
            if let Some(part) = parts.iter().find(|p| p.done[i]) {
                *done_i = true;
                let (plain_c, plain_v) = part.ff.row_plain(i);
                ff.column.extend_from_slice(plain_c);
                ff.value.extend_from_slice(plain_v);
                ff.plain_end.push(ff.column.len());
                let (ext_c, ext_v) = part.ff.row_extended(i);
                ff.column.extend_from_slice(ext_c);
                ff.value.extend_from_slice(ext_v);
            } else {
                ff.plain_end.push(ff.column.len());
            }
            ff.row_start.push(ff.column.len());
        }
        Some(PartialRows { ff, done, specular })
    }
}
