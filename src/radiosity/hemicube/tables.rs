//! The hemicube's delta form factors (Cohen and Greenberg 1985, eqs. 7 and 8): one table per
//! resolution, with per-row running sums for the accumulation.

/// Precomputed delta form factors of one hemicube resolution.
#[derive(Clone, Debug)]
pub struct Hemicube {
    pub(super) resolution_px: usize,
    /// ΔF of every pixel of the five faces, in buffer order (top face, then +x, −x, +y, −y).
    pub(super) delta: Vec<f32>,
    /// Per buffer row (N pixels), the running sums Σ ΔF from the row's first pixel through each pixel,
    /// in f64: a run of pixels i..=k of one row sums to prefix[k] − prefix[i − 1] (`accumulate_row`).
    pub(super) delta_row_prefix: Vec<f64>,
}

impl Hemicube {
    /// Delta form factors for a top face of `resolution_px` × `resolution_px` pixels (odd values are
    /// rounded up to even so that side faces are exactly N/2 high; at least 2).
    ///
    /// With ΔA = (2/N)² and pixel centres (x, y) on the top face z = 1, or (u, z) on a side face:
    /// top ΔF = ΔA / (π (x² + y² + 1)²), side ΔF = z·ΔA / (π (u² + z² + 1)²)
    /// (Cohen and Greenberg 1985, eqs. 7 and 8). They sum to 1 up to the midpoint rule's O(1/N²) error.
    pub fn new(resolution_px: u32) -> Self {
        let n = (resolution_px.max(2) as usize).next_multiple_of(2);
        let half = n / 2;
        let da = (2.0 / n as f64).powi(2);
        let centre = |i: usize| -1.0 + (i as f64 + 0.5) * 2.0 / n as f64;
        let mut delta = Vec::with_capacity(3 * n * n);
        for j in 0..n {
            let y = centre(j);
            for i in 0..n {
                let x = centre(i);
                delta.push((da / (std::f64::consts::PI * (x * x + y * y + 1.0).powi(2))) as f32);
            }
        }
        for _face in 0..4 {
            for j in 0..half {
                let z = (j as f64 + 0.5) * 2.0 / n as f64;
                for i in 0..n {
                    let u = centre(i);
                    delta.push((z * da / (std::f64::consts::PI * (u * u + z * z + 1.0).powi(2))) as f32);
                }
            }
        }
        let mut delta_row_prefix = Vec::with_capacity(delta.len());
        for row in delta.chunks_exact(n) {
            let mut sum = 0f64;
            for &d in row {
                sum += d as f64;
                delta_row_prefix.push(sum);
            }
        }
        Hemicube { resolution_px: n, delta, delta_row_prefix }
    }

    /// N: pixels across the top face.
    pub fn resolution_px(&self) -> u32 {
        self.resolution_px as u32
    }

    /// Pixels of all five faces (3N²).
    pub fn pixel_count(&self) -> usize {
        self.delta.len()
    }

    /// ΔF of every pixel in buffer order (top face N×N, then four side faces N/2 rows × N).
    pub fn delta_form_factors(&self) -> &[f32] {
        &self.delta
    }

    /// Σ ΔF over the hemicube (≈ 1), in double precision.
    pub fn delta_sum(&self) -> f64 {
        self.delta.iter().map(|&d| d as f64).sum()
    }

    /// (offset in the buffer, width_px, height_px) of face `f` (0 top, 1 +x, 2 −x, 3 +y, 4 −y).
    pub(super) fn face_rect(&self, f: usize) -> (usize, usize, usize) {
        let n = self.resolution_px;
        if f == 0 {
            (0, n, n)
        } else {
            (n * n + (f - 1) * n * (n / 2), n, n / 2)
        }
    }
}
