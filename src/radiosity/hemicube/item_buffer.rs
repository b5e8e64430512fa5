//! The item buffer: per-thread working memory of the rasteriser, which culls each polygon, queues
//! it for the faces it may cover and draws the faces one by one.

use glam::Vec3;

use super::clip::{
    clip_polygon, face_mask, faces_of_code, outcode, to_face, HemicubeFrame, BEHIND_BASE, GUARD, MAX_CLIPPED,
    MAX_INPUT_CORNERS,
};
use super::raster::rasterise_convex;
use super::Hemicube;

/// The items a hemicube of an element row (`ElementHierarchy::element_row`) draws for the backs of
/// one-sided surfaces, numbered just past the mesh's elements so that they never name one. Both hide
/// what lies behind them and get no form factor; the pixels of a `refracting` back (a one-sided
/// dielectric: water, an open glass sheet) are followed through it as a specular element's are
/// (`specular::SpecularPaths::extend_row`), while an `opaque` back absorbs, as pass two sees it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BackItems {
    pub opaque: u32,
    pub refracting: u32,
}

impl BackItems {
    /// The back items of a mesh of `element_count` elements.
    pub fn past(element_count: usize) -> BackItems {
        BackItems { opaque: element_count as u32, refracting: element_count as u32 + 1 }
    }

    /// `item` is one of the two.
    pub fn contains(&self, item: u32) -> bool {
        item == self.opaque || item == self.refracting
    }
}

/// Per-thread working memory of the rasteriser: the item buffer (item id and inverse depth 1/w per
/// pixel of the five faces) and a dense accumulator of form factors per item. Items are below
/// `mesh::NONE` (u32::MAX).
#[derive(Clone, Debug)]
pub struct ItemBuffer {
    /// 1/w of the nearest surface seen through each pixel (w: distance along the face axis); 0 = empty.
    pub(super) inverse_depth: Vec<f32>,
    pub(super) item: Vec<u32>,
    /// Σ ΔF per item for the current hemicube; zero between hemicubes.
    pub(super) accumulator: Vec<f64>,
    /// One buffer row's pixel keys (item, or `EMPTY`) plus a sentinel: scratch for `accumulate_row`.
    pub(super) row_keys: Vec<u32>,
    /// Items that passed culling in the current hemicube, in the order they were added.
    pub(super) touched: Vec<u32>,
    /// Polygons queued by `add_polygon` since `begin`, not yet scan-converted.
    pub(super) queued: Vec<QueuedPolygon>,
    /// Their local corners (`QueuedPolygon::first_corner`..+`corner_count`).
    pub(super) queued_corners: Vec<Vec3>,
    /// Per face, the indices into `queued` of the polygons that may cover it, in queueing order.
    pub(super) face_queue: [Vec<u32>; 5],
    pub(super) frame: HemicubeFrame,
    /// Per-vertex cache for `add_indexed_polygon`: a mesh vertex shared by several polygons is
    /// transformed to the local frame and outcoded once per hemicube, the first time a polygon uses it.
    /// Entry v is valid when `vertex_stamp[v] == generation`.
    pub(super) vertex_local: Vec<Vec3>,
    pub(super) vertex_code: Vec<u32>,
    pub(super) vertex_stamp: Vec<u32>,
    /// Counts hemicubes (`begin` calls); never 0, so a zeroed stamp is never current.
    pub(super) generation: u32,
    /// Polygons offered to the indexed adds since creation (before back-face and base-plane culling).
    pub polygons_offered: u64,
    /// Polygons that passed culling (and were scan-converted) since creation: for benchmarks.
    pub polygons_rasterised: u64,
    /// Pixels depth-tested by the scan converters since creation (`rasterise_convex`'s count).
    pub pixels_tested: u64,
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
            polygons_offered: 0,
            polygons_rasterised: 0,
            pixels_tested: 0,
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
        self.add_indexed(hc, item, None, positions, indices, normal, centre);
    }

    /// `add_indexed_polygon`, except that when the polygon is back-facing it is still drawn, as the
    /// item `occluder`: a one-sided surface seen from behind is opaque (pass two sees it black), so it
    /// must hide what lies behind it, or light leaks through closed solids and under furniture. The
    /// caller drops `occluder`'s form factor.
    #[allow(clippy::too_many_arguments)]
    pub fn add_indexed_polygon_or_occluder(
        &mut self,
        hc: &Hemicube,
        item: u32,
        occluder: u32,
        positions: &[Vec3],
        indices: &[u32],
        normal: Vec3,
        centre: Vec3,
    ) {
        self.add_indexed(hc, item, Some(occluder), positions, indices, normal, centre);
    }

    /// The shared body of the indexed adds: back-facing polygons are culled, or drawn (corners reversed,
    /// so that they face the eye) as `occluder` when one is given. Degenerate polygons are skipped.
    #[allow(clippy::too_many_arguments)]
    fn add_indexed(
        &mut self,
        hc: &Hemicube,
        item: u32,
        occluder: Option<u32>,
        positions: &[Vec3],
        indices: &[u32],
        normal: Vec3,
        centre: Vec3,
    ) {
        self.polygons_offered += 1;
        if indices.len() < 3 {
            return;
        }
        if indices.len() > MAX_INPUT_CORNERS {
            // Too many corners for the stack arrays: the unindexed path, which fans them into triangles.
            let corners: Vec<Vec3> = indices.iter().map(|&v| positions[v as usize]).collect();
            match occluder {
                Some(occluder) if (centre - self.frame.eye).dot(normal) > 0.0 => {
                    let reversed: Vec<Vec3> = corners.iter().rev().copied().collect();
                    self.add_polygon(hc, occluder, &reversed, -normal, centre);
                }
                _ => self.add_polygon(hc, item, &corners, normal, centre),
            }
            return;
        }
        debug_assert_eq!(self.inverse_depth.len(), hc.pixel_count(), "begin() was called with another hemicube");
        let mut plane_offset = (centre - self.frame.eye).dot(normal);
        let mut normal = normal;
        let mut item = item;
        let mut reversed = false;
        if plane_offset.is_nan() || plane_offset == 0.0 {
            return; // edge-on or NaN
        }
        if plane_offset > 0.0 {
            match occluder {
                // The same plane m·p = d seen from the other side: (−m, −d), corners reversed.
                Some(occluder) => {
                    item = occluder;
                    normal = -normal;
                    plane_offset = -plane_offset;
                    reversed = true;
                }
                None => return, // back-facing
            }
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
        if reversed {
            local[..indices.len()].reverse();
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
        self.pixels_tested += rasterise_convex(
            &screen[..count],
            width,
            height,
            plane,
            item,
            &mut self.inverse_depth[offset..end],
            &mut self.item[offset..end],
        );
    }
}

/// A polygon that passed culling, waiting in `ItemBuffer` to be scan-converted: its corners in the
/// hemicube's local frame and its plane m·p = d there (m the local normal, d = (centre − eye)·normal).
#[derive(Clone, Copy, Debug)]
pub(super) struct QueuedPolygon {
    pub(super) item: u32,
    pub(super) first_corner: u32,
    pub(super) corner_count: u32,
    pub(super) plane_normal: Vec3,
    pub(super) plane_offset: f32,
}
