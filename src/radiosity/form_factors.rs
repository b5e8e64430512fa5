//! The form-factor matrix, stored sparsely: one row per element, f32 values with u32 column indices
//! (compressed sparse rows). Row i holds F_ij for the elements j that element i's hemicube sees.

/// Sparse form factors F_ij (compressed sparse rows).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FormFactors {
    /// Row i occupies `row_start[i]..row_start[i + 1]` of `column` and `value`; length n + 1.
    pub row_start: Vec<usize>,
    pub column: Vec<u32>,
    pub value: Vec<f32>,
}

impl FormFactors {
    /// Number of rows (elements).
    pub fn len(&self) -> usize {
        self.row_start.len().saturating_sub(1)
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Stored non-zero entries.
    pub fn nnz(&self) -> usize {
        self.value.len()
    }

    /// Columns and values of row i.
    pub fn row(&self, i: usize) -> (&[u32], &[f32]) {
        let r = self.row_start[i]..self.row_start[i + 1];
        (&self.column[r.clone()], &self.value[r])
    }

    /// Σ_j F_ij: 1 for an element inside a closed enclosure (within the hemicube's quadrature error).
    pub fn row_sum(&self, i: usize) -> f64 {
        self.row(i).1.iter().map(|&v| v as f64).sum()
    }

    /// F_ij (0 when not stored). Linear in the row length: for tests and diagnostics.
    pub fn get(&self, i: usize, j: usize) -> f64 {
        let (c, v) = self.row(i);
        c.iter().position(|&k| k as usize == j).map_or(0.0, |p| v[p] as f64)
    }

    /// Bytes held by the matrix.
    pub fn memory_bytes(&self) -> usize {
        self.row_start.len() * std::mem::size_of::<usize>() + self.column.len() * 4 + self.value.len() * 4
    }

    /// Builds the sparse matrix from sparse rows (column, value), dropping zeros.
    pub fn from_rows(rows: Vec<Vec<(u32, f32)>>) -> Self {
        let mut ff = FormFactors { row_start: Vec::with_capacity(rows.len() + 1), ..Default::default() };
        ff.row_start.push(0);
        for row in rows {
            for (c, v) in row {
                if v != 0.0 {
                    ff.column.push(c);
                    ff.value.push(v);
                }
            }
            ff.row_start.push(ff.column.len());
        }
        ff
    }

    /// Builds the sparse matrix from a dense one (tests, validation data).
    pub fn from_dense(dense: &[Vec<f64>]) -> Self {
        Self::from_rows(
            dense.iter().map(|r| r.iter().enumerate().map(|(j, &v)| (j as u32, v as f32)).collect()).collect(),
        )
    }
}
