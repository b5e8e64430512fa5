//! The form-factor matrix, stored sparsely: one row per element, f32 values with u32 column indices
//! (compressed sparse rows). Row i holds F_ij for the elements j that element i's hemicube sees, then
//! (in scenes with mirrors or glass) the extended entries Fˢ_ij through specular surfaces.
//! `compute` builds it from a mesh, one hemicube per element in parallel; `estimate` predicts its cost.

use glam::Vec3;
use rayon::prelude::*;
use std::sync::Mutex;

use super::patch_cut::PatchCut;
use super::PartialRows;
use crate::mesh::Mesh;
use crate::radiosity::hemicube::{BackItems, Hemicube, HemicubeFrame, ItemBuffer};
use crate::radiosity::specular::{SpecularPaths, SpecularStats};
use crate::scene::RadiosityParams;

/// Sparse form factors F_ij (compressed sparse rows).
///
/// Row i is its plain (straight-line) entries `row_start[i]..plain_end[i]` followed by its extended
/// entries `plain_end[i]..row_start[i + 1]` through specular surfaces (Wallace, Cohen and Greenberg
/// 1987). A column may appear in both parts; solvers sum over the whole row (`row`), the direct part
/// of B uses only the plain part (`row_plain`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FormFactors {
    /// Row i occupies `row_start[i]..row_start[i + 1]` of `column` and `value`; length n + 1.
    pub row_start: Vec<usize>,
    pub column: Vec<u32>,
    pub value: Vec<f32>,
    /// End of row i's plain part (`row_start[i] ≤ plain_end[i] ≤ row_start[i + 1]`); length n. When
    /// empty (a matrix built by hand), every entry is plain.
    pub plain_end: Vec<usize>,
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

    fn plain_end_of(&self, i: usize) -> usize {
        self.plain_end.get(i).copied().unwrap_or(self.row_start[i + 1])
    }

    /// Columns and values of row i's plain part: the straight-line form factors of the hemicube.
    pub fn row_plain(&self, i: usize) -> (&[u32], &[f32]) {
        let r = self.row_start[i]..self.plain_end_of(i);
        (&self.column[r.clone()], &self.value[r])
    }

    /// Columns and values of row i's extended part: form factors through specular surfaces (empty in
    /// a scene without them).
    pub fn row_extended(&self, i: usize) -> (&[u32], &[f32]) {
        let r = self.plain_end_of(i)..self.row_start[i + 1];
        (&self.column[r.clone()], &self.value[r])
    }

    /// Σ_j (F_ij + Fˢ_ij): 1 for an element inside a closed diffuse enclosure (within the hemicube's
    /// quadrature error); below 1 when part of the light arrives through mirrors or glass (Ks ≤ 1).
    pub fn row_sum(&self, i: usize) -> f64 {
        self.row(i).1.iter().map(|&v| v as f64).sum()
    }

    /// F_ij + Fˢ_ij (0 when not stored; every stored entry of column j counts). Linear in the row
    /// length: for tests and diagnostics.
    pub fn get(&self, i: usize, j: usize) -> f64 {
        let (c, v) = self.row(i);
        c.iter().zip(v).filter(|(&k, _)| k as usize == j).map(|(_, &f)| f as f64).sum()
    }

    /// Bytes held by the matrix.
    pub fn memory_bytes(&self) -> usize {
        (self.row_start.len() + self.plain_end.len()) * std::mem::size_of::<usize>()
            + self.column.len() * 4
            + self.value.len() * 4
    }

    /// The transpose: row j of the result lists (i, F_ij) for every stored F_ij — who receives from j,
    /// with the receivers' own (gathering) factors. Plain and extended entries are merged.
    pub fn transpose(&self) -> FormFactors {
        let n = self.len();
        let mut count = vec![0usize; n + 1];
        for &c in &self.column {
            count[c as usize + 1] += 1;
        }
        for k in 0..n {
            count[k + 1] += count[k];
        }
        let mut next = count.clone();
        let mut column = vec![0u32; self.nnz()];
        let mut value = vec![0f32; self.nnz()];
        for i in 0..n {
            let (cols, vals) = self.row(i);
            for (&j, &f) in cols.iter().zip(vals) {
                let at = &mut next[j as usize];
                column[*at] = i as u32;
                value[*at] = f;
                *at += 1;
            }
        }
        let plain_end = count[1..].to_vec();
        FormFactors { row_start: count, column, value, plain_end }
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
        ff.plain_end = ff.row_start[1..].to_vec();
        ff
    }

    /// Builds the sparse matrix from a dense one (tests, validation data).
    pub fn from_dense(dense: &[Vec<f64>]) -> Self {
        Self::from_rows(
            dense.iter().map(|r| r.iter().enumerate().map(|(j, &v)| (j as u32, v as f32)).collect()).collect(),
        )
    }
}

/// Contiguous elements of one surface (at most `CHUNK_ELEMENTS`), culled together per hemicube.
#[derive(Clone, Debug)]
struct Chunk {
    elements: std::ops::Range<usize>,
    min: Vec3,
    max: Vec3,
    /// Shared plane (normal, offset n·x) when every element lies in it: then the whole chunk is
    /// back-facing exactly when one element is.
    plane: Option<(Vec3, f32)>,
    /// The chunk's surface is one side of a two-sided surface: its other side lies in the same plane
    /// facing the other way, so seen from behind it needs no occluder (the twin is drawn).
    two_sided: bool,
}

const CHUNK_ELEMENTS: usize = 64;

/// Groups the mesh's elements into chunks of one surface with bounding boxes (a two-level hierarchy:
/// chunks, then elements) for per-hemicube frustum and back-face culling.
fn build_chunks(mesh: &Mesh) -> Vec<Chunk> {
    let e = &mesh.elements;
    // Scene surfaces that were meshed on both sides (two mesh surfaces share the source).
    let mut sides = vec![0u8; mesh.surface_source.iter().map(|&s| s as usize + 1).max().unwrap_or(0)];
    for &source in &mesh.surface_source {
        sides[source as usize] = sides[source as usize].saturating_add(1);
    }
    let two_sided =
        |surface: u32| mesh.surface_source.get(surface as usize).is_some_and(|&source| sides[source as usize] >= 2);
    let mut chunks = Vec::new();
    let mut start = 0;
    while start < e.len() {
        let mut end = start + 1;
        while end < e.len() && end - start < CHUNK_ELEMENTS && e.surface[end] == e.surface[start] {
            end += 1;
        }
        let (mut min, mut max) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for i in start..end {
            for p in e.polygon(&mesh.positions, i) {
                min = min.min(p);
                max = max.max(p);
            }
        }
        let n0 = e.normal[start];
        let offset = n0.dot(e.centre[start]);
        let tolerance = 1e-5 * (max - min).max_element().max(offset.abs());
        let planar = (start..end).all(|i| {
            e.normal[i].dot(n0) > 1.0 - 1e-6
                && e.polygon(&mesh.positions, i).all(|p| (n0.dot(p) - offset).abs() <= tolerance)
        });
        chunks.push(Chunk {
            elements: start..end,
            min,
            max,
            plane: planar.then_some((n0, offset)),
            two_sided: two_sided(e.surface[start]),
        });
        start = end;
    }
    chunks
}

/// True when element i needs its row of F: it reflects or emits diffusely. Other elements (black,
/// mirrors and glass with Kd = 0) only occlude.
pub(crate) fn needs_row(mesh: &Mesh, i: usize) -> bool {
    mesh.elements.reflectance[i].max_element() > 0.0 || mesh.elements.emission[i].max_element() > 0.0
}

/// Distance the hemicube's eye is lifted off its element along the normal (a fraction of the
/// element's size), so that the element's coplanar neighbours fall below the base plane.
fn eye_offset(area: f32) -> f32 {
    1e-3 * area.sqrt()
}

/// The rotation of element i's hemicube about its normal: a seeded uniform angle in [0, 2π) from
/// `Pcg32::new(seed, i)` when `rotate_hemicubes`, else 0.
pub fn hemicube_rotation_rad(params: &RadiosityParams, element: usize) -> f32 {
    if params.rotate_hemicubes {
        crate::rng::Pcg32::new(params.seed, element as u64).next_f32() * std::f32::consts::TAU
    } else {
        0.0
    }
}

/// The mesh's elements grouped for culling: contiguous runs of one surface with bounding boxes and,
/// when planar, their shared plane. Built once per mesh, shared by every hemicube.
#[derive(Clone, Debug)]
pub struct ElementHierarchy {
    chunks: Vec<Chunk>,
}

impl ElementHierarchy {
    pub fn new(mesh: &Mesh) -> Self {
        ElementHierarchy { chunks: build_chunks(mesh) }
    }

    /// Row i of F: a hemicube at element i's centre (lifted by a thousandth of the element's size along
    /// its normal), aligned with the normal and rotated by `hemicube_rotation_rad`, seeing every other
    /// element (Cohen and Greenberg 1985). One-sided elements seen from behind are drawn as occluders
    /// (no form factor: `BackItems`), opaque as pass two sees them, or refracting for a one-sided
    /// dielectric (`Mesh::back_refracts`), whose pixels extended form factors follow; back-facing sides of two-sided surfaces,
    /// chunks outside all five face frusta and mostly cut-out elements (`Mesh::hidden_from_hemicubes`)
    /// are skipped. Appends (j, F_ij) with increasing j to `row`.
    pub fn element_row(
        &self,
        mesh: &Mesh,
        params: &RadiosityParams,
        hc: &Hemicube,
        buffers: &mut ItemBuffer,
        i: usize,
        row: &mut Vec<(u32, f32)>,
    ) {
        self.element_row_cut(mesh, params, hc, buffers, i, None, row);
    }

    /// `element_row`, with the split patches of `cut` that are far from the eye drawn whole, each
    /// as one item whose form factor its leaves share by area (`PatchCut`).
    #[allow(clippy::too_many_arguments)]
    pub fn element_row_cut(
        &self,
        mesh: &Mesh,
        params: &RadiosityParams,
        hc: &Hemicube,
        buffers: &mut ItemBuffer,
        i: usize,
        cut: Option<&PatchCut>,
        row: &mut Vec<(u32, f32)>,
    ) {
        let e = &mesh.elements;
        let normal = e.normal[i];
        let eye = mesh.eye(i) + normal * eye_offset(e.area[i]);
        buffers.begin(hc, HemicubeFrame::new(eye, normal, hemicube_rotation_rad(params, i)));
        let backs = BackItems::past(e.len());
        // Items of patches drawn whole come after the elements' and the two back items.
        let first_patch_item = backs.refracting + 1;
        let mut drawn_whole_until = 0usize;
        for chunk in &self.chunks {
            if let Some((n, offset)) = chunk.plane {
                if chunk.two_sided && n.dot(eye) <= offset {
                    continue; // behind (or in) the plane of a two-sided side: its twin is drawn instead
                }
            }
            if buffers.box_is_invisible(chunk.min, chunk.max) {
                continue;
            }
            for j in chunk.elements.clone() {
                if j < drawn_whole_until {
                    continue; // a leaf of a patch drawn whole
                }
                if let Some((cut, p)) = cut.and_then(|c| c.drawn_whole(j, eye, i).map(|p| (c, p))) {
                    drawn_whole_until = cut.leaves[p].end as usize;
                    let occluder = if mesh.back_refracts(j) { backs.refracting } else { backs.opaque };
                    buffers.add_indexed_polygon_or_occluder(
                        hc,
                        first_patch_item + p as u32,
                        occluder,
                        &mesh.positions,
                        cut.outline(p),
                        cut.normal[p],
                        cut.centre[p],
                    );
                    continue;
                }
                if j == i || mesh.hidden_from_hemicubes(j) {
                    continue;
                }
                let corners = &e.corners[j][..e.corner_count(j)];
                if chunk.two_sided {
                    buffers.add_indexed_polygon(hc, j as u32, &mesh.positions, corners, e.normal[j], e.centre[j]);
                } else {
                    let (normal, centre) = (e.normal[j], e.centre[j]);
                    let occluder = if mesh.back_refracts(j) { backs.refracting } else { backs.opaque };
                    buffers.add_indexed_polygon_or_occluder(
                        hc,
                        j as u32,
                        occluder,
                        &mesh.positions,
                        corners,
                        normal,
                        centre,
                    );
                }
            }
        }
        let start = row.len();
        let mut shared = false;
        buffers.finish(hc, |j, f| {
            if j >= first_patch_item {
                let Some(cut) = cut else { return };
                let p = (j - first_patch_item) as usize;
                for c in cut.leaves[p].clone() {
                    row.push((c, (f * f64::from(e.area[c as usize] / cut.area[p])) as f32));
                }
                shared = true;
            } else if !backs.contains(j) {
                row.push((j, f as f32))
            }
        });
        if shared {
            row[start..].sort_unstable_by_key(|&(j, _)| j);
        }
    }
}

/// Elements per parallel batch: rows of a batch are computed in parallel, then appended to the matrix,
/// so that peak memory is the matrix plus one batch of rows.
const BATCH_ROWS: usize = 1024;

/// Where a computation of rows starts and how far it goes: rows finished earlier are copied, rows
/// not selected are left undone, and no row is started once `stop` says so. `RowPlan::all()` computes
/// every row.
pub struct RowPlan<'a> {
    /// Rows finished earlier (a checkpoint, or the merged parts of a sharded run): copied, not
    /// recomputed. Must have one entry per element.
    pub known: Option<&'a PartialRows>,
    /// Whether this run computes row i (every row, or one shard's).
    pub selected: &'a (dyn Fn(usize) -> bool + Sync),
    /// Polled before every row: once true, no further row is computed (known rows are still copied).
    pub stop: &'a (dyn Fn() -> bool + Sync),
    /// Sees the rows so far (a prefix of the matrix) after every batch, on one thread while the next
    /// batch is computed: the place to write a checkpoint.
    pub after_batch: Option<&'a mut (dyn FnMut(&PartialRows) + Send)>,
    /// Split patches that hemicubes far from them draw whole (`PatchCut`); `None` draws every element.
    /// Only for plain rows: extended form factors read the item buffer's elements.
    pub cut: Option<&'a PatchCut>,
}

impl RowPlan<'_> {
    /// Every row, from scratch, to the end.
    pub fn all() -> RowPlan<'static> {
        RowPlan { known: None, selected: &|_| true, stop: &|| false, after_batch: None, cut: None }
    }
}

/// The form-factor matrix of a mesh by one hemicube per element (Cohen and Greenberg 1985):
/// F_ij = Σ ΔF over the pixels of element i's hemicube where element j is the nearest surface.
///
/// The hemicube sits at element i's centre, lifted by `eye_offset` along its normal, aligned with the
/// normal and rotated by `hemicube_rotation_rad`; its resolution is `params.hemicube_resolution_px`.
/// Rows are computed only for elements that reflect or emit diffusely (others stay empty). Parallel
/// over elements (rayon, one item buffer per worker); every row depends only on the inputs, so the
/// result is the same whatever the thread count. `on_element_done` is called once per element.
pub fn compute(mesh: &Mesh, params: &RadiosityParams, on_element_done: &(dyn Fn() + Sync)) -> FormFactors {
    compute_rows(mesh, params, None, RowPlan::all(), on_element_done).ff
}

/// `compute` plus the extended form factors through specular surfaces (Wallace, Cohen and Greenberg
/// 1987; Sillion and Puech 1989): after each hemicube, the pixels that show a specular element are
/// followed by rays (`SpecularPaths::extend_row`) and their row gets extended entries Fˢ_ij after its
/// plain ones, so that B = E + ρ(F + Fˢ)B carries light that reaches diffuse surfaces through
/// mirrors and glass. The plain entries of pure specular elements (Kd = 0, E = 0, so B = 0) are
/// dropped: the paths through them replace them, and a row then sums to at most 1 (mirrors with
/// Ks ≤ 1 create no energy). When the mesh has no specular element the result is `compute`'s, bit
/// for bit.
pub fn compute_extended(
    mesh: &Mesh,
    params: &RadiosityParams,
    specular: &SpecularPaths,
    on_element_done: &(dyn Fn() + Sync),
) -> (FormFactors, SpecularStats) {
    let rows = compute_planned(mesh, params, Some(specular), RowPlan::all(), on_element_done);
    (rows.ff, rows.specular)
}

/// The rows `plan` asks for, plain (`specular` = `None`) or extended through specular surfaces as in
/// `compute_extended`. A row is the same bits whether computed here, in another process, or in
/// pieces over several runs, so a matrix assembled from checkpoints or shards equals `compute`'s.
pub fn compute_planned(
    mesh: &Mesh,
    params: &RadiosityParams,
    specular: Option<&SpecularPaths>,
    plan: RowPlan,
    on_element_done: &(dyn Fn() + Sync),
) -> PartialRows {
    let any = specular.filter(|s| (0..mesh.elements.len()).any(|j| s.is_specular(j)));
    compute_rows(mesh, params, any, plan, on_element_done)
}

/// One computed row: entries (plain, then extended), the length of the plain part, the ray cost, and
/// whether it is done.
type ComputedRow = (Vec<(u32, f32)>, usize, SpecularStats, bool);

fn compute_rows(
    mesh: &Mesh,
    params: &RadiosityParams,
    specular: Option<&SpecularPaths>,
    mut plan: RowPlan,
    on_element_done: &(dyn Fn() + Sync),
) -> PartialRows {
    let hc = Hemicube::new(params.hemicube_resolution_px);
    let hierarchy = ElementHierarchy::new(mesh);
    let n = mesh.elements.len();
    if let Some(known) = plan.known {
        assert_eq!(known.len(), n, "known rows of this mesh");
    }
    let mut rows = PartialRows {
        ff: FormFactors {
            row_start: Vec::with_capacity(n + 1),
            plain_end: Vec::with_capacity(n),
            ..Default::default()
        },
        done: Vec::with_capacity(n),
        specular: plan.known.map_or_else(SpecularStats::default, |k| k.specular),
    };
    rows.ff.row_start.push(0);
    let pool = BufferPool { hc: &hc, free: Mutex::new(Vec::new()) };
    let (known, selected, stop) = (plan.known, plan.selected, plan.stop);
    let cut = plan.cut.filter(|_| specular.is_none());
    let compute_batch = |batch: std::ops::Range<usize>| -> Vec<ComputedRow> {
        batch
            .into_par_iter()
            .map_init(
                || pool.take(),
                |buffers, i| {
                    let computed = if let Some(known) = known.filter(|k| k.done[i]) {
                        let (row, plain) = known.row_entries(i);
                        (row, plain, SpecularStats::default(), true)
                    } else if !needs_row(mesh, i) {
                        (Vec::new(), 0, SpecularStats::default(), true)
                    } else if selected(i) && !stop() {
                        let buffers = buffers.get();
                        let mut row = Vec::new();
                        let mut row_stats = SpecularStats::default();
                        hierarchy.element_row_cut(mesh, params, &hc, buffers, i, cut, &mut row);
                        if let Some(specular) = specular {
                            row.retain(|&(j, _)| !specular.is_pure_specular(j as usize));
                        }
                        let plain = row.len();
                        if let Some(specular) = specular {
                            // The item buffer still holds this hemicube's pixels.
                            row_stats = specular.extend_row(&hc, buffers, params.seed, i, &mut row);
                        }
                        (row, plain, row_stats, true)
                    } else {
                        (Vec::new(), 0, SpecularStats::default(), false)
                    };
                    on_element_done();
                    computed
                },
            )
            .collect()
    };
    // Batch k + 1 is computed while batch k is appended (serially, on one thread), so that no core
    // waits for the append.
    let mut pending = Vec::new();
    let mut append = |rows: &mut PartialRows, pending: Vec<ComputedRow>| {
        append_rows(rows, pending);
        if let Some(after_batch) = plan.after_batch.as_deref_mut() {
            after_batch(rows);
        }
    };
    for batch_start in (0..n).step_by(BATCH_ROWS) {
        let batch = batch_start..(batch_start + BATCH_ROWS).min(n);
        let (computed, ()) = rayon::join(|| compute_batch(batch), || append(&mut rows, pending));
        pending = computed;
    }
    append(&mut rows, pending);
    rows.ff.column.shrink_to_fit();
    rows.ff.value.shrink_to_fit();
    rows
}

/// Appends computed rows to the matrix (dropping zeros) and adds up their ray statistics.
fn append_rows(rows: &mut PartialRows, computed: Vec<ComputedRow>) {
    let ff = &mut rows.ff;
    let entries: usize = computed.iter().map(|(row, _, _, _)| row.len()).sum();
    ff.column.reserve(entries);
    ff.value.reserve(entries);
    for (row, plain, row_stats, done) in computed {
        rows.specular += row_stats;
        rows.done.push(done);
        for (k, (c, v)) in row.into_iter().enumerate() {
            if k == plain {
                ff.plain_end.push(ff.column.len());
            }
            if v != 0.0 {
                ff.column.push(c);
                ff.value.push(v);
            }
        }
        if ff.plain_end.len() < ff.row_start.len() {
            ff.plain_end.push(ff.column.len());
        }
        ff.row_start.push(ff.column.len());
    }
}

/// Item buffers kept across rayon jobs and batches: a job borrows one (`take`) and gives it back when
/// done, so the 3N² pixel buffers are allocated (and page-faulted in) once per thread, not per job.
struct BufferPool<'a> {
    hc: &'a Hemicube,
    free: Mutex<Vec<ItemBuffer>>,
}

impl BufferPool<'_> {
    fn take(&self) -> PooledBuffer<'_> {
        let buffer = self.free.lock().ok().and_then(|mut free| free.pop());
        PooledBuffer { buffer: Some(buffer.unwrap_or_else(|| ItemBuffer::new(self.hc))), free: &self.free }
    }
}

/// An item buffer on loan from a `BufferPool`; returned to it on drop.
struct PooledBuffer<'a> {
    buffer: Option<ItemBuffer>,
    free: &'a Mutex<Vec<ItemBuffer>>,
}

impl PooledBuffer<'_> {
    fn get(&mut self) -> &mut ItemBuffer {
        self.buffer.as_mut().expect("present until drop")
    }
}

impl Drop for PooledBuffer<'_> {
    fn drop(&mut self) {
        if let (Some(buffer), Ok(mut free)) = (self.buffer.take(), self.free.lock()) {
            free.push(buffer);
        }
    }
}

/// A prediction of `compute`'s cost, for `radray info` and `method = "auto"`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FormFactorEstimate {
    /// Rows that will be computed (elements that reflect or emit).
    pub rows: usize,
    /// Predicted stored entries.
    pub nnz: u64,
    /// Predicted bytes of the matrix (`FormFactors::memory_bytes`).
    pub matrix_bytes: u64,
    /// Predicted CPU seconds of the hemicubes (one core).
    pub cpu_seconds: f64,
    /// Predicted wall-clock seconds on `threads` threads (`cpu_seconds / threads`).
    pub seconds: f64,
    pub threads: usize,
}

/// Predicts the matrix of `mesh` from `cost::SAMPLE_ROWS` of its hemicubes, drawn and counted
/// (`cost::sampled_work`): entries as counted, time by `HemicubeWork::cpu_seconds`. Drawing the sample
/// costs about `SAMPLE_ROWS / rows` of the matrix. With `specular`, the rows are extended through
/// mirrors and glass as `compute_extended` does, and the rays are counted and charged.
pub fn estimate(mesh: &Mesh, params: &RadiosityParams, specular: Option<&SpecularPaths>) -> FormFactorEstimate {
    let (work, rows) = super::cost::sampled_work(mesh, params, specular);
    let n = mesh.elements.len();
    let threads = rayon::current_num_threads().max(1);
    let cpu_seconds = work.cpu_seconds(params.hemicube_resolution_px);
    FormFactorEstimate {
        rows,
        nnz: work.entries,
        matrix_bytes: work.entries * 8 + (n as u64 + 1) * std::mem::size_of::<usize>() as u64,
        cpu_seconds,
        seconds: cpu_seconds / threads as f64,
        threads,
    }
}

/// The matrix's size from the counts alone (no mesh), n elements of which `rows` reflect or emit:
///
/// entries per row ≈ min(n/2, 0.85·N²)
///
/// (an interior element sees roughly half of the others, and a hemicube resolves at most a fraction of
/// its 3N² pixels into distinct items). An upper guide for open rooms; occluded scenes hold far fewer
/// (the showcase: 805 per row at 27.8k elements and N = 128, against 13.9k predicted).
pub fn matrix_bytes_from_counts(n: usize, rows: usize, params: &RadiosityParams) -> u64 {
    let res = Hemicube::new(params.hemicube_resolution_px).resolution_px() as f64;
    let per_row = (n as f64 / 2.0).min(0.85 * res * res);
    let nnz = (rows as f64 * per_row) as u64;
    nnz * 8 + (n as u64 + 1) * std::mem::size_of::<usize>() as u64
}
