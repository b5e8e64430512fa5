//! The hemicube (Cohen and Greenberg 1985): delta form factors and the item-buffer rasteriser that
//! turns "which polygon is seen through each hemicube pixel" into point-to-polygon form factors.
//!
//! Layout: a unit hemicube over the eye with its top face z = 1 covering [-1,1]² (N×N pixels) and four
//! side faces (±x, ±y) N pixels wide and N/2 high (height z ∈ [0,1]). All five faces live in one
//! buffer: the top face first, then the four side faces, row-major, row 0 of a side face at the base.

use glam::Vec3;

/// Fixed-point subpixel precision of the rasteriser: vertices snap to 1/256 pixel.
const SUBPIXEL_BITS: u32 = 8;
const SUBPIXEL: i64 = 1 << SUBPIXEL_BITS;
/// The key of an empty pixel in `accumulate_row` (`mesh::NONE`: never an item).
const EMPTY: u32 = u32::MAX;
/// Guard band: polygons are clipped to |u|, |v| ≤ GUARD·w in face coordinates (the face is |u| ≤ w),
/// so projected coordinates stay small and the integer edge functions exact.
const GUARD: f32 = 2.0;
/// Most input corners rasterised as one polygon; larger convex polygons are fanned into triangles.
const MAX_INPUT_CORNERS: usize = 8;
/// Most vertices after clipping a polygon of `MAX_INPUT_CORNERS` against the 5 clip planes.
const MAX_CLIPPED: usize = MAX_INPUT_CORNERS + 6;

/// Precomputed delta form factors of one hemicube resolution.
#[derive(Clone, Debug)]
pub struct Hemicube {
    resolution_px: usize,
    /// ΔF of every pixel of the five faces, in buffer order (top face, then +x, −x, +y, −y).
    delta: Vec<f32>,
    /// Per buffer row (N pixels), the running sums Σ ΔF from the row's first pixel through each pixel,
    /// in f64: a run of pixels i..=k of one row sums to prefix[k] − prefix[i − 1] (`accumulate_row`).
    delta_row_prefix: Vec<f64>,
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
    fn face_rect(&self, f: usize) -> (usize, usize, usize) {
        let n = self.resolution_px;
        if f == 0 {
            (0, n, n)
        } else {
            (n * n + (f - 1) * n * (n / 2), n, n / 2)
        }
    }
}

/// The orthonormal frame of one hemicube: `normal` is the top face's axis, `tangent` and `bitangent`
/// the local x and y axes (side faces ±x, ±y).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HemicubeFrame {
    pub eye: Vec3,
    pub tangent: Vec3,
    pub bitangent: Vec3,
    pub normal: Vec3,
}

impl HemicubeFrame {
    /// The frame at `eye` around unit `normal`, rotated by `rotation_rad` about it. With no rotation the
    /// tangent is the world x axis projected onto the tangent plane (the world y axis when |n_x| ≥ 0.9),
    /// and bitangent = normal × tangent.
    pub fn new(eye: Vec3, normal: Vec3, rotation_rad: f32) -> Self {
        let normal = normal.normalize();
        let axis = if normal.x.abs() >= 0.9 { Vec3::Y } else { Vec3::X };
        let t0 = (axis - axis.dot(normal) * normal).normalize();
        let b0 = normal.cross(t0);
        let (s, c) = rotation_rad.sin_cos();
        let tangent = (c * t0 + s * b0).normalize();
        let bitangent = normal.cross(tangent);
        HemicubeFrame { eye, tangent, bitangent, normal }
    }

    /// World point → local (x, y, z) relative to the eye.
    #[inline]
    fn local(&self, p: Vec3) -> Vec3 {
        let d = p - self.eye;
        Vec3::new(d.dot(self.tangent), d.dot(self.bitangent), d.dot(self.normal))
    }

    /// World direction → local.
    #[inline]
    fn local_dir(&self, d: Vec3) -> Vec3 {
        Vec3::new(d.dot(self.tangent), d.dot(self.bitangent), d.dot(self.normal))
    }
}

/// Local (x, y, z) → face coordinates (u, v, w): w along the face's axis, the projection is (u/w, v/w).
#[inline]
fn to_face(f: usize, p: Vec3) -> [f32; 3] {
    match f {
        0 => [p.x, p.y, p.z],
        1 => [p.y, p.z, p.x],
        2 => [p.y, p.z, -p.x],
        3 => [p.x, p.z, p.y],
        _ => [p.x, p.z, -p.y],
    }
}

/// Per-thread working memory of the rasteriser: the item buffer (item id and inverse depth 1/w per
/// pixel of the five faces) and a dense accumulator of form factors per item. Items are below
/// `mesh::NONE` (u32::MAX).
#[derive(Clone, Debug)]
pub struct ItemBuffer {
    /// 1/w of the nearest surface seen through each pixel (w: distance along the face axis); 0 = empty.
    inverse_depth: Vec<f32>,
    item: Vec<u32>,
    /// Σ ΔF per item for the current hemicube; zero between hemicubes.
    accumulator: Vec<f64>,
    /// One buffer row's pixel keys (item, or `EMPTY`) plus a sentinel: scratch for `accumulate_row`.
    row_keys: Vec<u32>,
    /// Items that passed culling in the current hemicube, in the order they were added.
    touched: Vec<u32>,
    /// Polygons queued by `add_polygon` since `begin`, not yet scan-converted.
    queued: Vec<QueuedPolygon>,
    /// Their local corners (`QueuedPolygon::first_corner`..+`corner_count`).
    queued_corners: Vec<Vec3>,
    /// Per face, the indices into `queued` of the polygons that may cover it, in queueing order.
    face_queue: [Vec<u32>; 5],
    frame: HemicubeFrame,
    /// Per-vertex cache for `add_indexed_polygon`: a mesh vertex shared by several polygons is
    /// transformed to the local frame and outcoded once per hemicube, the first time a polygon uses it.
    /// Entry v is valid when `vertex_stamp[v] == generation`.
    vertex_local: Vec<Vec3>,
    vertex_code: Vec<u32>,
    vertex_stamp: Vec<u32>,
    /// Counts hemicubes (`begin` calls); never 0, so a zeroed stamp is never current.
    generation: u32,
    /// Polygons that passed culling (and were scan-converted) since creation: for benchmarks.
    pub polygons_rasterised: u64,
}

impl ItemBuffer {
    pub fn new(hc: &Hemicube) -> Self {
        ItemBuffer {
            inverse_depth: vec![0.0; hc.pixel_count()],
            item: vec![0; hc.pixel_count()],
            accumulator: Vec::new(),
            row_keys: vec![0; hc.resolution_px + 1],
            touched: Vec::new(),
            queued: Vec::new(),
            queued_corners: Vec::new(),
            face_queue: Default::default(),
            frame: HemicubeFrame::new(Vec3::ZERO, Vec3::Z, 0.0),
            vertex_local: Vec::new(),
            vertex_code: Vec::new(),
            vertex_stamp: Vec::new(),
            generation: 1,
            polygons_rasterised: 0,
        }
    }

    /// Starts a hemicube: clears the depth buffer (the item ids need no clearing).
    pub fn begin(&mut self, hc: &Hemicube, frame: HemicubeFrame) {
        if self.inverse_depth.len() != hc.pixel_count() {
            *self = ItemBuffer::new(hc);
        }
        self.inverse_depth.fill(0.0);
        self.touched.clear();
        self.clear_queue();
        self.frame = frame;
        self.generation = self.generation.wrapping_add(1);
        if self.generation == 0 {
            self.vertex_stamp.fill(0);
            self.generation = 1;
        }
    }

    /// The current frame.
    pub fn frame(&self) -> &HemicubeFrame {
        &self.frame
    }

    /// True when a box (world min/max corners) lies entirely behind the hemicube's base plane or
    /// outside every face's view frustum: none of its contents can be seen. Conservative.
    pub fn box_is_invisible(&self, min: Vec3, max: Vec3) -> bool {
        let mut corners = [Vec3::ZERO; 8];
        for (k, c) in corners.iter_mut().enumerate() {
            let p = Vec3::new(
                if k & 1 == 0 { min.x } else { max.x },
                if k & 2 == 0 { min.y } else { max.y },
                if k & 4 == 0 { min.z } else { max.z },
            );
            *c = self.frame.local(p);
        }
        corners.iter().all(|p| p.z <= 0.0) || face_mask(&corners) == 0
    }

    /// Adds convex polygon `item` (world corners, counter-clockwise about its front `normal`; `centre`
    /// any point of its plane) to the current hemicube. Culled when it lies behind the base plane or is
    /// back-facing, i.e. unless (centre − eye)·normal < 0 (one-sided surfaces). Otherwise it is clipped
    /// against each face's near plane and guard band (Sutherland–Hodgman) and scan-converted into the
    /// item buffer with depth test, pixel-centre sampling and a top-left fill rule. The scan conversion
    /// is deferred to `rasterise_queued` (called by `finish`), which draws face by face.
    pub fn add_polygon(&mut self, hc: &Hemicube, item: u32, corners: &[Vec3], normal: Vec3, centre: Vec3) {
        debug_assert_eq!(self.inverse_depth.len(), hc.pixel_count(), "begin() was called with another hemicube");
        if corners.len() < 3 {
            return;
        }
        let frame = self.frame;
        let plane_offset = (centre - frame.eye).dot(normal);
        if plane_offset.is_nan() || plane_offset >= 0.0 {
            return; // back-facing, edge-on or NaN
        }
        if corners.len() > MAX_INPUT_CORNERS {
            // A convex polygon is the fan of its triangles; the fill rule keeps them from overlapping.
            for k in 1..corners.len() - 1 {
                self.add_polygon(hc, item, &[corners[0], corners[k], corners[k + 1]], normal, centre);
            }
            return;
        }
        let mut local = [Vec3::ZERO; MAX_INPUT_CORNERS];
        let mut code = !0;
        for (l, &c) in local.iter_mut().zip(corners) {
            *l = frame.local(c);
            code &= outcode(*l);
        }
        self.queue_polygon(item, &local[..corners.len()], code, normal, plane_offset);
    }

    /// `add_polygon` for a polygon given by indices into a vertex array (a mesh's `positions`, the
    /// same slice for every call of one hemicube): each vertex is transformed and outcoded once per
    /// hemicube however many polygons share it. Same culling, same pixels, same result.
    pub fn add_indexed_polygon(
        &mut self,
        hc: &Hemicube,
        item: u32,
        positions: &[Vec3],
        indices: &[u32],
        normal: Vec3,
        centre: Vec3,
    ) {
        if indices.len() < 3 {
            return;
        }
        if indices.len() > MAX_INPUT_CORNERS {
            let corners: Vec<Vec3> = indices.iter().map(|&v| positions[v as usize]).collect();
            self.add_polygon(hc, item, &corners, normal, centre);
            return;
        }
        debug_assert_eq!(self.inverse_depth.len(), hc.pixel_count(), "begin() was called with another hemicube");
        let plane_offset = (centre - self.frame.eye).dot(normal);
        if plane_offset.is_nan() || plane_offset >= 0.0 {
            return; // back-facing, edge-on or NaN
        }
        if self.vertex_stamp.len() < positions.len() {
            self.vertex_local.resize(positions.len(), Vec3::ZERO);
            self.vertex_code.resize(positions.len(), 0);
            self.vertex_stamp.resize(positions.len(), 0);
        }
        let mut local = [Vec3::ZERO; MAX_INPUT_CORNERS];
        let mut code = !0;
        for (l, &v) in local.iter_mut().zip(indices) {
            let v = v as usize;
            if self.vertex_stamp[v] != self.generation {
                let p = self.frame.local(positions[v]);
                self.vertex_local[v] = p;
                self.vertex_code[v] = outcode(p);
                self.vertex_stamp[v] = self.generation;
            }
            *l = self.vertex_local[v];
            code &= self.vertex_code[v];
        }
        self.queue_polygon(item, &local[..indices.len()], code, normal, plane_offset);
    }

    /// Queues a front-facing polygon (local corners, `code` the AND of their outcodes) for the faces
    /// it may cover, unless it lies entirely behind the base plane.
    fn queue_polygon(&mut self, item: u32, local: &[Vec3], code: u32, normal: Vec3, plane_offset: f32) {
        if code & BEHIND_BASE != 0 {
            return; // entirely behind the base plane
        }
        let plane_normal = self.frame.local_dir(normal);
        if item as usize >= self.accumulator.len() {
            self.accumulator.resize(item as usize + 1, 0.0);
        }
        if self.touched.last() != Some(&item) {
            self.touched.push(item);
        }
        self.polygons_rasterised += 1;
        let mask = faces_of_code(code);
        let index = self.queued.len() as u32;
        for (f, queue) in self.face_queue.iter_mut().enumerate() {
            if mask & (1 << f) != 0 {
                queue.push(index);
            }
        }
        self.queued.push(QueuedPolygon {
            item,
            first_corner: self.queued_corners.len() as u32,
            corner_count: local.len() as u32,
            plane_normal,
            plane_offset,
        });
        self.queued_corners.extend_from_slice(local);
    }

    fn clear_queue(&mut self) {
        self.queued.clear();
        self.queued_corners.clear();
        for queue in &mut self.face_queue {
            queue.clear();
        }
    }

    /// Scan-converts the polygons queued since `begin` (or the last call) into the item buffer, face
    /// by face, so that one face's part of the buffer stays in cache while all its polygons are drawn.
    /// Within a face the polygons are drawn in the order they were added, so the result is the same
    /// as drawing each polygon into every face as it arrives. `finish` calls it; call it directly to
    /// read the item buffer before `finish`.
    pub fn rasterise_queued(&mut self, hc: &Hemicube) {
        let queued = std::mem::take(&mut self.queued);
        let corners = std::mem::take(&mut self.queued_corners);
        let face_queue = std::mem::take(&mut self.face_queue);
        for (f, queue) in face_queue.iter().enumerate() {
            for &index in queue {
                let q = &queued[index as usize];
                let first = q.first_corner as usize;
                let local = &corners[first..first + q.corner_count as usize];
                self.rasterise_face(hc, f, q.item, local, q.plane_normal, q.plane_offset);
            }
        }
        // Hand the (cleared) allocations back for the next hemicube.
        self.queued = queued;
        self.queued_corners = corners;
        self.face_queue = face_queue;
        self.clear_queue();
    }

    fn rasterise_face(&mut self, hc: &Hemicube, f: usize, item: u32, local: &[Vec3], m: Vec3, d: f32) {
        let mut poly = [[0f32; 3]; MAX_CLIPPED];
        let mut count = local.len();
        let mut needs_clip = false;
        let mut scale = 0f32;
        for (q, &p) in poly.iter_mut().zip(local) {
            *q = to_face(f, p);
            let [u, v, w] = *q;
            needs_clip |= w.is_nan() || w <= 0.0 || u.abs() > GUARD * w || v.abs() > GUARD * w;
            scale = scale.max(u.abs()).max(v.abs()).max(w.abs());
        }
        if needs_clip {
            let near = 1e-6 * scale;
            let planes: [[f32; 4]; 5] = [
                [0.0, 0.0, 1.0, -near],
                [-1.0, 0.0, GUARD, 0.0],
                [1.0, 0.0, GUARD, 0.0],
                [0.0, -1.0, GUARD, 0.0],
                [0.0, 1.0, GUARD, 0.0],
            ];
            for plane in &planes {
                count = clip_polygon(&mut poly, count, plane);
                if count < 3 {
                    return;
                }
            }
        }
        let (offset, width, height) = hc.face_rect(f);
        let half = (hc.resolution_px / 2) as f32;
        let top = f == 0;
        let mut screen = [[0f32; 2]; MAX_CLIPPED];
        for (s, &[u, v, w]) in screen.iter_mut().zip(&poly[..count]) {
            let inv = 1.0 / w;
            *s = [(u * inv + 1.0) * half, if top { (v * inv + 1.0) * half } else { v * inv * half }];
        }
        // The polygon's plane m·(u, v, w) = d in face coordinates gives 1/w = (m_u u + m_v v + m_w)/d,
        // affine in the pixel coordinates (u = px/half − 1, v = py/half − 1 on top, py/half on sides).
        let [mu, mv, mw] = to_face(f, m);
        let plane = [mu / (half * d), mv / (half * d), (mw - mu - if top { mv } else { 0.0 }) / d];
        let end = offset + width * height;
        rasterise_convex(
            &screen[..count],
            width,
            height,
            plane,
            item,
            &mut self.inverse_depth[offset..end],
            &mut self.item[offset..end],
        );
    }

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
fn accumulate_row(inverse_depth: &[f32], items: &[u32], prefix: &[f64], keys: &mut [u32], accumulator: &mut [f64]) {
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

/// A polygon that passed culling, waiting in `ItemBuffer` to be scan-converted: its corners in the
/// hemicube's local frame and its plane m·p = d there (m the local normal, d = (centre − eye)·normal).
#[derive(Clone, Copy, Debug)]
struct QueuedPolygon {
    item: u32,
    first_corner: u32,
    corner_count: u32,
    plane_normal: Vec3,
    plane_offset: f32,
}

/// Bit f set when face f (0 top, 1 +x, 2 −x, 3 +y, 4 −y) may see part of the points' convex hull: for
/// each face, the hull is rejected when every point lies outside one of its frustum planes (|u| ≤ w,
/// v ≤ w, and v ≥ −w on top or v ≥ 0 on a side) or behind it (w ≤ 0).
fn face_mask(local: &[Vec3]) -> u8 {
    faces_of_code(local.iter().fold(!0, |code, &p| code & outcode(p)))
}

/// Outcode bit of `outcode`: the point lies on or behind the hemicube's base plane (z ≤ 0, or NaN).
const BEHIND_BASE: u32 = 1 << 25;

/// Outcode of a local point: bit 5f + k set when it lies outside frustum plane k of face f (the planes
/// of `face_mask`), and `BEHIND_BASE`. The AND of a polygon's corner outcodes has a plane's bit set
/// exactly when every corner lies outside that plane (Cohen–Sutherland style trivial rejection).
#[inline]
fn outcode(p: Vec3) -> u32 {
    let Vec3 { x, y, z } = p;
    let below = z < 0.0;
    let bits = |u: f32, v: f32, w: f32, v_low: bool| -> u32 {
        (u < -w) as u32 | ((u > w) as u32) << 1 | ((v > w) as u32) << 2 | (v_low as u32) << 3 | ((w <= 0.0) as u32) << 4
    };
    bits(x, y, z, y < -z)
        | bits(y, z, x, below) << 5
        | bits(y, z, -x, below) << 10
        | bits(x, z, y, below) << 15
        | bits(x, z, -y, below) << 20
        | ((z > 0.0) as u32 ^ 1) << 25
}

/// The faces (bit f) that a polygon with combined outcode `code` may cover: those with no plane
/// that all its corners lie outside.
#[inline]
fn faces_of_code(code: u32) -> u8 {
    let mut mask = 0;
    for f in 0..5 {
        if (code >> (5 * f)) & 0x1f == 0 {
            mask |= 1 << f;
        }
    }
    mask
}

/// One edge of a polygon being scan-converted: q = ⌊K/e⌋ and r = K − e·q for the current row
/// (for a horizontal edge, sign 0 and q = K itself).
#[derive(Clone, Copy, Debug, Default)]
struct Edge {
    sign: i64,
    q: i64,
    r: i64,
    e: i64,
    step_q: i64,
    step_r: i64,
}

/// Pixel coordinate → fixed point (1/256 pixel), rounding half away from zero (no libm call).
#[inline]
fn snap(x: f32) -> i64 {
    let scaled = x * SUBPIXEL as f32;
    (scaled + if scaled >= 0.0 { 0.5 } else { -0.5 }) as i64
}

/// Sutherland–Hodgman: clips polygon `poly[..count]` (face coordinates) to the half-space
/// a·u + b·v + c·w + e ≥ 0 in place; returns the new vertex count.
fn clip_polygon(poly: &mut [[f32; 3]; MAX_CLIPPED], count: usize, plane: &[f32; 4]) -> usize {
    let dist = |p: &[f32; 3]| plane[0] * p[0] + plane[1] * p[1] + plane[2] * p[2] + plane[3];
    let input = *poly;
    let mut out = 0;
    for k in 0..count {
        let a = input[k];
        let b = input[(k + 1) % count];
        let (da, db) = (dist(&a), dist(&b));
        if da >= 0.0 {
            poly[out] = a;
            out += 1;
        }
        if (da >= 0.0) != (db >= 0.0) {
            let t = da / (da - db);
            poly[out] = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2])];
            out += 1;
        }
        if out >= MAX_CLIPPED {
            break; // cannot happen for convex input; keeps indices in bounds regardless
        }
    }
    out
}

/// Scan-converts a convex polygon (pixel coordinates, either winding) into one face of the item buffer.
///
/// Pixel (i, j) is sampled at its centre (i + ½, j + ½). Vertices snap to 1/256 pixel and the edge
/// functions E(p) = (b − a) × (p − a) are exact in i64; a sample exactly on an edge belongs to the
/// polygon only for "top-left" edges (dy > 0, or dy = 0 and dx < 0, for a counter-clockwise polygon),
/// so polygons sharing an edge never both cover a sample and leave no gap. Each row's span comes from
/// intersecting the edges' half-lines, so the inner loop is a plain depth test: the pixel takes `item`
/// when 1/w = plane·(i + ½, j + ½, 1) exceeds the stored value.
fn rasterise_convex(
    screen: &[[f32; 2]],
    width: usize,
    height: usize,
    plane: [f32; 3],
    item: u32,
    inverse_depth: &mut [f32],
    items: &mut [u32],
) {
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
        return;
    }
    let mut area2 = 0i64;
    for k in 0..m {
        let k1 = if k + 1 == m { 0 } else { k + 1 };
        area2 += xs[k] * ys[k1] - xs[k1] * ys[k];
    }
    if area2 == 0 {
        return;
    }
    if area2 < 0 {
        xs[..m].reverse();
        ys[..m].reverse();
    }
    let (xmin, xmax) = (xs[..m].iter().min().copied(), xs[..m].iter().max().copied());
    let (ymin, ymax) = (ys[..m].iter().min().copied(), ys[..m].iter().max().copied());
    let (Some(xmin), Some(xmax), Some(ymin), Some(ymax)) = (xmin, xmax, ymin, ymax) else { return };
    let half = SUBPIXEL / 2;
    // Pixels whose centre i·S + S/2 lies in [min, max].
    let i_lo = (xmin - half + SUBPIXEL - 1).div_euclid(SUBPIXEL).max(0);
    let i_hi = (xmax - half).div_euclid(SUBPIXEL).min(width as i64 - 1);
    let j_lo = (ymin - half + SUBPIXEL - 1).div_euclid(SUBPIXEL).max(0);
    let j_hi = (ymax - half).div_euclid(SUBPIXEL).min(height as i64 - 1);
    if i_lo > i_hi || j_lo > j_hi {
        return;
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
            return;
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
}

/// Widest polygon (in pixels) drawn by `rasterise_narrow`: one row is one fixed-width block of lanes.
const NARROW_PX: usize = 8;

/// A convex polygon's snapped vertices (1/256 pixel, counter-clockwise), for `rasterise_narrow`.
struct Outline<'a> {
    xs: &'a [i64],
    ys: &'a [i64],
}

/// The pixels `rasterise_narrow` may cover: columns i_lo..=i_hi (drawn as the `NARROW_PX` columns from
/// `start` ≤ i_lo) of rows j_lo..=j_hi of a face `width` pixels wide.
struct Window {
    start: i64,
    i_lo: i64,
    i_hi: i64,
    j_lo: i64,
    j_hi: i64,
    width: usize,
}

/// The fast path of `rasterise_convex` for polygons at most `NARROW_PX` pixels wide (most elements
/// seen from a hemicube cover a few pixels): each row is a fixed block of `NARROW_PX` lanes where every
/// edge function is evaluated directly, E_k(i) = K_k(py) − D_k·i ≥ 0 (the same exact predicate, with the
/// same top-left bias, as the span DDA, so the covered pixels are identical), in i32 because the values
/// are relative to the block. Branch-free per row, so short and ragged spans cost no mispredictions.
/// Returns false (drawing nothing) when an edge function could leave the i32 range over the block;
/// the caller then uses the general path.
fn rasterise_narrow(
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

/// Form factors from a point to each polygon of a scene by one hemicube (Nusselt analog, Cohen and
/// Greenberg 1985): F_j = Σ ΔF over the hemicube pixels where polygon j is the nearest surface.
///
/// `eye` is the differential area's position, `normal` its unit normal; the hemicube is rotated by
/// `rotation_rad` about the normal (see `HemicubeFrame::new`). Each polygon is convex, planar and
/// counter-clockwise about its front; it is seen only from the front and occludes the others. Returns
/// F_j per polygon (their sum ≈ the visible fraction of the hemisphere).
pub fn point_form_factors(
    hc: &Hemicube,
    eye: Vec3,
    normal: Vec3,
    rotation_rad: f32,
    polygons: &[&[Vec3]],
    buffers: &mut ItemBuffer,
) -> Vec<f64> {
    buffers.begin(hc, HemicubeFrame::new(eye, normal, rotation_rad));
    for (j, poly) in polygons.iter().enumerate() {
        if poly.len() < 3 {
            continue;
        }
        let (poly_normal, centre) = newell_plane(poly);
        buffers.add_polygon(hc, j as u32, poly, poly_normal, centre);
    }
    let mut out = vec![0.0; polygons.len()];
    buffers.finish(hc, |j, f| out[j as usize] = f);
    out
}

/// Unit normal (Newell's method: n ∝ Σ v_k × v_{k+1}) and vertex centroid of a polygon.
pub fn newell_plane(poly: &[Vec3]) -> (Vec3, Vec3) {
    let mut n = Vec3::ZERO;
    let mut c = Vec3::ZERO;
    for (k, &v) in poly.iter().enumerate() {
        n += v.cross(poly[(k + 1) % poly.len()]);
        c += v;
    }
    (n.normalize_or_zero(), c / poly.len() as f32)
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
