//! Where a pixel's samples go: the per-pixel `Sampler` that the film hands on to the shader, and the
//! multi-jittered pattern of the film's sample positions drawn from it.

use crate::rng::Pcg32;

/// The random numbers one pixel's samples draw, seeded per pixel so that the image does not depend on
/// the thread schedule. Stratified or low-discrepancy sequences would be further kinds.
#[derive(Clone, Debug)]
pub enum Sampler {
    /// Independent uniform numbers from a PCG32 stream (`Pcg32::new(seed, stream)`).
    Independent(Pcg32),
}

impl Sampler {
    /// Independent numbers for stream `stream` (a pixel index) of seed `seed`.
    pub fn independent(seed: u64, stream: u64) -> Sampler {
        Sampler::Independent(Pcg32::new(seed, stream))
    }

    /// The next number, uniform in [0, 1).
    pub fn next_1d(&mut self) -> f32 {
        match self {
            Sampler::Independent(rng) => rng.next_f32(),
        }
    }

    /// The next 32 uniform bits (for shuffles).
    pub fn next_u32(&mut self) -> u32 {
        match self {
            Sampler::Independent(rng) => rng.next_u32(),
        }
    }
}

/// The stratum grid (columns, rows) for `count` samples: columns·rows = count with columns the largest
/// divisor ≤ √count, so square counts give square grids and a prime p gives 1×p (which multi-jittering
/// still stratifies into p strata along each axis).
pub fn stratum_grid(count: u32) -> (u32, u32) {
    let count = count.max(1);
    let mut columns = (count as f64).sqrt() as u32;
    while columns > 1 && !count.is_multiple_of(columns) {
        columns -= 1;
    }
    let columns = columns.max(1);
    (columns, count / columns)
}

/// Multi-jittered sampling (Chiu, Shirley & Wang 1994): `columns × rows` points in [0, 1)², exactly one
/// in each cell of the columns×rows grid AND exactly one in each of the N = columns·rows strata of
/// width 1/N along each axis (N-rooks). Cell (i, j) starts at the canonical
/// x = (i + (j + ξ)/rows)/columns, y = (j + (i + ξ')/columns)/rows; x values are then shuffled among the
/// cells of a column and y values among the cells of a row, which keeps both properties.
/// Points are appended to `out` row by row.
pub fn multi_jittered(columns: u32, rows: u32, sampler: &mut Sampler, out: &mut Vec<[f32; 2]>) {
    let (nc, nr) = (columns as usize, rows as usize);
    let start = out.len();
    for j in 0..nr {
        for i in 0..nc {
            let x = (i as f32 + (j as f32 + sampler.next_1d()) / nr as f32) / nc as f32;
            let y = (j as f32 + (i as f32 + sampler.next_1d()) / nc as f32) / nr as f32;
            // f32 rounding of values just below 1 must not escape the unit square.
            out.push([x.min(ONE_BELOW), y.min(ONE_BELOW)]);
        }
    }
    let cells = &mut out[start..];
    for i in 0..nc {
        for j in (1..nr).rev() {
            let k = ((sampler.next_u32() as u64 * (j as u64 + 1)) >> 32) as usize;
            let (a, b) = (j * nc + i, k * nc + i);
            let tmp = cells[a][0];
            cells[a][0] = cells[b][0];
            cells[b][0] = tmp;
        }
    }
    for j in 0..nr {
        for i in (1..nc).rev() {
            let k = ((sampler.next_u32() as u64 * (i as u64 + 1)) >> 32) as usize;
            let (a, b) = (j * nc + i, j * nc + k);
            let tmp = cells[a][1];
            cells[a][1] = cells[b][1];
            cells[b][1] = tmp;
        }
    }
}

const ONE_BELOW: f32 = 1.0 - f32::EPSILON / 2.0;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stratum_grid_is_as_square_as_the_count_allows() {
        assert_eq!(stratum_grid(16), (4, 4));
        assert_eq!(stratum_grid(8), (2, 4));
        assert_eq!(stratum_grid(12), (3, 4));
        assert_eq!(stratum_grid(7), (1, 7));
        assert_eq!(stratum_grid(1), (1, 1));
        assert_eq!(stratum_grid(0), (1, 1));
    }
}
