//! Accumulation and read-back: the form factors an item won (F_j = Σ ΔF over its pixels), summed
//! run by run, and read-only access to the finished item buffer for extended form factors.

use glam::Vec3;

use super::{Hemicube, ItemBuffer};

/// The key of an empty pixel in `accumulate_row` (`mesh::NONE`: never an item).
pub(super) const EMPTY: u32 = u32::MAX;

impl ItemBuffer {
    /// Ends the hemicube: F_j = Σ ΔF over the pixels item j won. Calls `emit(j, F_j)` for every item
    /// added since `begin` that won at least one pixel, in the order they were first added, and resets
    /// the accumulator.
    pub fn finish(&mut self, hc: &Hemicube, mut emit: impl FnMut(u32, f64)) {
        self.rasterise_queued(hc);
        let n = hc.resolution_px;
        self.row_keys.resize(n + 1, 0);
        let rows = self.inverse_depth.chunks_exact(n).zip(self.item.chunks_exact(n));
        for ((inverse_depth, items), prefix) in rows.zip(hc.delta_row_prefix.chunks_exact(n)) {
            accumulate_row(inverse_depth, items, prefix, &mut self.row_keys, &mut self.accumulator);
        }
        for &j in &self.touched {
            let f = std::mem::take(&mut self.accumulator[j as usize]);
            if f > 0.0 {
                emit(j, f);
            }
        }
    }
}

/// Adds one buffer row's ΔF to the items it shows: F_j += Σ ΔF over the row's pixels that show j.
///
/// The row is cut into runs of pixels with the same key (item, or `EMPTY` where 1/w = 0); a run i..=k
/// adds prefix[k] − prefix[i − 1] (`delta_row_prefix`), so the cost is one read-modify-write per run
/// instead of per pixel, and run ends are found 64 pixels at a time as a bit mask. Every ΔF is an f32
/// multiple of the smallest one's ulp, with max/min ΔF ≈ 4N, so any sum of them needs at most
/// 24 + log₂ 4N + log₂ 3N² bits: up to N = 256 every prefix, run and total is exact in f64 (53 bits)
/// and the result does not depend on how the sum is split; above, only the rounding order differs.
/// `keys` has room for the row plus one.
pub(super) fn accumulate_row(
    inverse_depth: &[f32],
    items: &[u32],
    prefix: &[f64],
    keys: &mut [u32],
    accumulator: &mut [f64],
) {
    let width = inverse_depth.len();
    for ((key, &z), &id) in keys.iter_mut().zip(inverse_depth).zip(items) {
        *key = if z > 0.0 { id } else { EMPTY };
    }
    keys[width] = !keys[width - 1]; // the row's last pixel always ends a run
    let mut before = 0f64; // prefix through the end of the previous run
    for base in (0..width).step_by(64) {
        let len = (width - base).min(64);
        // Run ends as bytes (vectorises), then packed eight at a time: with bytes b_i ∈ {0, 1},
        // x·0x0102040810204080 has b_i at bit 56 + i and no carries into those bits.
        let mut end_bytes = [0u8; 64];
        let (this, next) = (&keys[base..base + len], &keys[base + 1..base + len + 1]);
        for ((e, &a), &b) in end_bytes.iter_mut().zip(this).zip(next) {
            *e = (a != b) as u8;
        }
        let mut ends = 0u64;
        for (g, bytes) in end_bytes.chunks_exact(8).enumerate() {
            let x = u64::from_le_bytes(bytes.try_into().expect("8 bytes"));
            ends |= (x.wrapping_mul(0x0102_0408_1020_4080) >> 56) << (8 * g);
        }
        while ends != 0 {
            let end = base + ends.trailing_zeros() as usize;
            ends &= ends - 1;
            let through = prefix[end];
            if keys[end] != EMPTY {
                accumulator[keys[end] as usize] += through - before;
            }
            before = through;
        }
    }
}

/// Read-only access to the rasterised item buffer after a hemicube, for extended form factors through
/// specular surfaces (`radiosity::specular`): which item each pixel shows, through which direction and
/// with which delta form factor. Valid between `add_polygon` calls of one hemicube and the next `begin`
/// (`finish` leaves the pixels in place).
impl ItemBuffer {
    /// Calls `visit(pixel, item, ΔF)` for every pixel of the current hemicube that shows an item, in
    /// buffer order (top face, then +x, −x, +y, −y). `pixel` is the buffer index for `pixel_direction`.
    pub fn for_each_covered_pixel(&self, hc: &Hemicube, mut visit: impl FnMut(usize, u32, f32)) {
        for (pixel, ((&z, &id), &df)) in self.inverse_depth.iter().zip(&self.item).zip(&hc.delta).enumerate() {
            if z > 0.0 {
                visit(pixel, id, df);
            }
        }
    }

    /// The item shown by buffer pixel `pixel` of the current hemicube, if any.
    pub fn item_at(&self, pixel: usize) -> Option<u32> {
        (self.inverse_depth.get(pixel).is_some_and(|&z| z > 0.0)).then(|| self.item[pixel])
    }

    /// The world-space unit direction from the current hemicube's eye through the centre of buffer
    /// pixel `pixel`: on the top face local (x, y, 1) with x, y = −1 + (i + ½)·2/N; on a side face the
    /// face point (u, v, 1) with u = −1 + (i + ½)·2/N and height v = (j + ½)·2/N, mapped back from face
    /// coordinates (the inverse of `to_face`).
    pub fn pixel_direction(&self, hc: &Hemicube, pixel: usize) -> Vec3 {
        let n = hc.resolution_px;
        let top = n * n;
        let (f, local) =
            if pixel < top { (0, pixel) } else { (1 + (pixel - top) / (n * n / 2), (pixel - top) % (n * n / 2)) };
        let (i, j) = (local % n, local / n);
        let step = 2.0 / n as f32;
        let u = -1.0 + (i as f32 + 0.5) * step;
        let v = if f == 0 { -1.0 + (j as f32 + 0.5) * step } else { (j as f32 + 0.5) * step };
        let p = match f {
            0 => Vec3::new(u, v, 1.0),
            1 => Vec3::new(1.0, u, v),
            2 => Vec3::new(-1.0, u, v),
            3 => Vec3::new(u, 1.0, v),
            _ => Vec3::new(u, -1.0, v),
        };
        let frame = &self.frame;
        (frame.tangent * p.x + frame.bitangent * p.y + frame.normal * p.z).normalize()
    }
}
