//! The scan converters: a convex polygon (pixel coordinates) into one face of the item buffer, with
//! exact integer edge functions and a top-left fill rule; a branch-free path for narrow polygons.

use super::clip::MAX_CLIPPED;

/// Fixed-point subpixel precision of the rasteriser: vertices snap to 1/256 pixel.
pub(super) const SUBPIXEL_BITS: u32 = 8;
pub(super) const SUBPIXEL: i64 = 1 << SUBPIXEL_BITS;

/// One edge of a polygon being scan-converted: q = ⌊K/e⌋ and r = K − e·q for the current row
/// (for a horizontal edge, sign 0 and q = K itself).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Edge {
    sign: i64,
    q: i64,
    r: i64,
    e: i64,
    step_q: i64,
    step_r: i64,
}

/// Pixel coordinate → fixed point (1/256 pixel), rounding half away from zero (no libm call).
#[inline]
pub(super) fn snap(x: f32) -> i64 {
    let scaled = x * SUBPIXEL as f32;
    (scaled + if scaled >= 0.0 { 0.5 } else { -0.5 }) as i64
}

/// Scan-converts a convex polygon (pixel coordinates, either winding) into one face of the item buffer.
///
/// Pixel (i, j) is sampled at its centre (i + ½, j + ½). Vertices snap to 1/256 pixel and the edge
/// functions E(p) = (b − a) × (p − a) are exact in i64; a sample exactly on an edge belongs to the
/// polygon only for "top-left" edges (dy > 0, or dy = 0 and dx < 0, for a counter-clockwise polygon),
/// so polygons sharing an edge never both cover a sample and leave no gap. Each row's span comes from
/// intersecting the edges' half-lines, so the inner loop is a plain depth test: the pixel takes `item`
/// when 1/w = plane·(i + ½, j + ½, 1) exceeds the stored value. Returns the pixels depth-tested (the
/// span lengths, or `NARROW_PX` per row on the narrow path): the work done, for the cost model.
pub(super) fn rasterise_convex(
    screen: &[[f32; 2]],
    width: usize,
    height: usize,
    plane: [f32; 3],
    item: u32,
    inverse_depth: &mut [f32],
    items: &mut [u32],
) -> u64 {
    let mut xs = [0i64; MAX_CLIPPED];
    let mut ys = [0i64; MAX_CLIPPED];
    let mut m = 0;
    for s in screen {
        let (x, y) = (snap(s[0]), snap(s[1]));
        if m == 0 || x != xs[m - 1] || y != ys[m - 1] {
            xs[m] = x;
            ys[m] = y;
            m += 1;
        }
    }
    while m > 1 && xs[m - 1] == xs[0] && ys[m - 1] == ys[0] {
        m -= 1;
    }
    if m < 3 {
        return 0;
    }
    let mut area2 = 0i64;
    for k in 0..m {
        let k1 = if k + 1 == m { 0 } else { k + 1 };
        area2 += xs[k] * ys[k1] - xs[k1] * ys[k];
    }
    if area2 == 0 {
        return 0;
    }
    if area2 < 0 {
        xs[..m].reverse();
        ys[..m].reverse();
    }
    let (xmin, xmax) = (xs[..m].iter().min().copied(), xs[..m].iter().max().copied());
    let (ymin, ymax) = (ys[..m].iter().min().copied(), ys[..m].iter().max().copied());
    let (Some(xmin), Some(xmax), Some(ymin), Some(ymax)) = (xmin, xmax, ymin, ymax) else { return 0 };
    let half = SUBPIXEL / 2;
    // Pixels whose centre i·S + S/2 lies in [min, max].
    let i_lo = (xmin - half + SUBPIXEL - 1).div_euclid(SUBPIXEL).max(0);
    let i_hi = (xmax - half).div_euclid(SUBPIXEL).min(width as i64 - 1);
    let j_lo = (ymin - half + SUBPIXEL - 1).div_euclid(SUBPIXEL).max(0);
    let j_hi = (ymax - half).div_euclid(SUBPIXEL).min(height as i64 - 1);
    if i_lo > i_hi || j_lo > j_hi {
        return 0;
    }
    // Edge k: E(px, py) = dx (py − ay) − dy (px − ax) ≥ bias, bias 0 on top-left edges, else 1.
    // At pixel centre px = i·S + S/2 on row py: E − bias = K(py) − D·i with D = dy·S and
    // K(py) = dx·py + (dy·ax − dx·ay − dy·S/2 − bias). With e = |D| and q = ⌊K/e⌋ the row's span is
    // i ≤ q (D > 0) or i ≥ −q (D < 0); K grows by dx·S per row, so q and the remainder K − e·q are
    // stepped exactly in integers (a DDA), one division per edge and polygon.
    if i_hi - i_lo < NARROW_PX as i64 && width >= NARROW_PX {
        let start = i_lo.min((width - NARROW_PX) as i64);
        let geometry = Outline { xs: &xs[..m], ys: &ys[..m] };
        let window = Window { start, i_lo, i_hi, j_lo, j_hi, width };
        if rasterise_narrow(&geometry, &window, plane, item, inverse_depth, items) {
            return (j_hi - j_lo + 1) as u64 * NARROW_PX as u64;
        }
    }
    let mut edges = [Edge::default(); MAX_CLIPPED];
    let py0 = j_lo * SUBPIXEL + half;
    for (k, edge) in edges.iter_mut().enumerate().take(m) {
        let k1 = if k + 1 == m { 0 } else { k + 1 };
        let (dx, dy) = (xs[k1] - xs[k], ys[k1] - ys[k]);
        let bias = if dy > 0 || (dy == 0 && dx < 0) { 0 } else { 1 };
        let k_row = dx * py0 + dy * xs[k] - dx * ys[k] - dy * half - bias;
        let step = dx * SUBPIXEL;
        let e = (dy * SUBPIXEL).abs();
        *edge = if e == 0 {
            Edge { sign: 0, q: k_row, r: 0, e: 1, step_q: step, step_r: 0 }
        } else {
            Edge {
                sign: dy.signum(),
                q: k_row.div_euclid(e),
                r: k_row.rem_euclid(e),
                e,
                step_q: step.div_euclid(e),
                step_r: step.rem_euclid(e),
            }
        };
    }
    let edges = &mut edges[..m];
    let [pa, pb, pc] = plane;
    let mut tested = 0u64;
    for j in j_lo..=j_hi {
        let (mut lo, mut hi) = (i_lo, i_hi);
        for edge in edges.iter_mut() {
            match edge.sign {
                1 => hi = hi.min(edge.q),
                -1 => lo = lo.max(-edge.q),
                _ => {
                    if edge.q < 0 {
                        hi = -1; // a horizontal edge with the row outside
                    }
                }
            }
            edge.q += edge.step_q;
            edge.r += edge.step_r;
            if edge.r >= edge.e {
                edge.r -= edge.e;
                edge.q += 1;
            }
        }
        if lo > hi {
            continue;
        }
        let (lo, hi) = (lo as usize, hi as usize);
        tested += (hi - lo + 1) as u64;
        let row = j as usize * width;
        let row_depth = pb * (j as f32 + 0.5) + pc + pa * 0.5;
        let depth = &mut inverse_depth[row + lo..=row + hi];
        let ids = &mut items[row + lo..=row + hi];
        for (k, (z, id)) in depth.iter_mut().zip(ids.iter_mut()).enumerate() {
            // i32 → f32 is exact here (i < 2²⁴) and, unlike usize → f32, a single instruction.
            let candidate = row_depth + pa * (lo as i32 + k as i32) as f32;
            // Branch-free so that it vectorises: a select for the depth (not f32::max, whose NaN rule
            // costs instructions; the stored depth is never NaN), a bit mask for the id.
            let wins = candidate > *z;
            let mask = (wins as u32).wrapping_neg();
            *z = if wins { candidate } else { *z };
            *id = (*id & !mask) | (item & mask);
        }
    }
    tested
}

/// Widest polygon (in pixels) drawn by `rasterise_narrow`: one row is one fixed-width block of lanes.
pub(super) const NARROW_PX: usize = 8;

/// A convex polygon's snapped vertices (1/256 pixel, counter-clockwise), for `rasterise_narrow`.
pub(super) struct Outline<'a> {
    pub(super) xs: &'a [i64],
    pub(super) ys: &'a [i64],
}

/// The pixels `rasterise_narrow` may cover: columns i_lo..=i_hi (drawn as the `NARROW_PX` columns from
/// `start` ≤ i_lo) of rows j_lo..=j_hi of a face `width` pixels wide.
pub(super) struct Window {
    pub(super) start: i64,
    pub(super) i_lo: i64,
    pub(super) i_hi: i64,
    pub(super) j_lo: i64,
    pub(super) j_hi: i64,
    pub(super) width: usize,
}

/// The fast path of `rasterise_convex` for polygons at most `NARROW_PX` pixels wide (most elements
/// seen from a hemicube cover a few pixels): each row is a fixed block of `NARROW_PX` lanes where every
/// edge function is evaluated directly, E_k(i) = K_k(py) − D_k·i ≥ 0 (the same exact predicate, with the
/// same top-left bias, as the span DDA, so the covered pixels are identical), in i32 because the values
/// are relative to the block. Branch-free per row, so short and ragged spans cost no mispredictions.
/// Returns false (drawing nothing) when an edge function could leave the i32 range over the block;
/// the caller then uses the general path.
pub(super) fn rasterise_narrow(
    outline: &Outline,
    window: &Window,
    plane: [f32; 3],
    item: u32,
    inverse_depth: &mut [f32],
    items: &mut [u32],
) -> bool {
    const LANES: usize = NARROW_PX;
    let (xs, ys) = (outline.xs, outline.ys);
    let m = xs.len();
    let half = SUBPIXEL / 2;
    let Window { start, i_lo, i_hi, j_lo, j_hi, width } = *window;
    let py0 = j_lo * SUBPIXEL + half;
    let rows = j_hi - j_lo;
    // Per edge: value at (start, j_lo), offset of each lane (−D·l) and step per row (dx·S).
    let mut value = [0i32; MAX_CLIPPED];
    let mut lane_step = [[0i32; LANES]; MAX_CLIPPED];
    let mut row_step = [0i32; MAX_CLIPPED];
    let limit = i32::MAX as i64 / 2;
    for k in 0..m {
        let k1 = if k + 1 == m { 0 } else { k + 1 };
        let (dx, dy) = (xs[k1] - xs[k], ys[k1] - ys[k]);
        let bias = if dy > 0 || (dy == 0 && dx < 0) { 0 } else { 1 };
        let d = dy * SUBPIXEL;
        let step = dx * SUBPIXEL;
        let v0 = dx * py0 + dy * xs[k] - dx * ys[k] - dy * half - bias - d * start;
        // Linear over the block: in range at its four corners means in range everywhere.
        let last_lane = -d * (LANES as i64 - 1);
        let last_row = step * rows;
        for corner in [v0, v0 + last_lane, v0 + last_row, v0 + last_lane + last_row] {
            if corner.abs() > limit {
                return false;
            }
        }
        if d.abs() > limit || step.abs() > limit {
            return false;
        }
        value[k] = v0 as i32;
        for (l, s) in lane_step[k].iter_mut().enumerate() {
            *s = (-d * l as i64) as i32;
        }
        row_step[k] = step as i32;
    }
    let mut lane_ok = [false; LANES];
    for (l, ok) in lane_ok.iter_mut().enumerate() {
        let i = start + l as i64;
        *ok = i >= i_lo && i <= i_hi;
    }
    let [pa, pb, pc] = plane;
    let start = start as usize;
    let mut lane_depth = [0f32; LANES];
    for (l, d) in lane_depth.iter_mut().enumerate() {
        // Same expression as the span loop (i32 → f32 exact), so the depths are bit-identical.
        *d = pa * (start as i32 + l as i32) as f32;
    }
    for j in j_lo..=j_hi {
        let mut inside = lane_ok;
        for k in 0..m {
            let v = value[k];
            for (inside, &s) in inside.iter_mut().zip(&lane_step[k]) {
                *inside &= v + s >= 0;
            }
            value[k] = v + row_step[k];
        }
        let row = j as usize * width + start;
        let row_depth = pb * (j as f32 + 0.5) + pc + pa * 0.5;
        let depth: &mut [f32; LANES] = (&mut inverse_depth[row..row + LANES]).try_into().expect("block in row");
        let ids: &mut [u32; LANES] = (&mut items[row..row + LANES]).try_into().expect("block in row");
        for l in 0..LANES {
            let candidate = row_depth + lane_depth[l];
            let wins = inside[l] & (candidate > depth[l]);
            let mask = (wins as u32).wrapping_neg();
            depth[l] = if wins { candidate } else { depth[l] };
            ids[l] = (ids[l] & !mask) | (item & mask);
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fill_rule_covers_each_pixel_of_a_split_square_once() {
        // Two triangles sharing a diagonal, rasterised with different ids: every covered pixel is won by
        // exactly one of them and the union equals the square's pixels (no gaps, no double cover).
        let (w, h) = (16usize, 16usize);
        let mut depth = vec![0f32; w * h];
        let mut ids = vec![u32::MAX; w * h];
        let sq = [[2.0f32, 2.0], [10.0, 2.0], [10.0, 10.0], [2.0, 10.0]];
        let mut count = vec![0u32; w * h];
        for (id, tri) in [[sq[0], sq[1], sq[2]], [sq[0], sq[2], sq[3]]].iter().enumerate() {
            depth.fill(0.0);
            ids.fill(u32::MAX);
            rasterise_convex(tri, w, h, [0.0, 0.0, 1.0], id as u32, &mut depth, &mut ids);
            for p in 0..w * h {
                if ids[p] != u32::MAX {
                    count[p] += 1;
                }
            }
        }
        assert!(count.iter().all(|&c| c <= 1));
        assert_eq!(count.iter().sum::<u32>(), 64);
    }
}
