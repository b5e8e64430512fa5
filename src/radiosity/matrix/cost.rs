//! What the full matrix costs before it is computed: the hemicube work of a sample of rows, counted
//! (polygons offered and drawn, pixels depth-tested, entries), and the time model fitted on it.

use rayon::prelude::*;

use super::form_factors::{needs_row, ElementHierarchy};
use crate::mesh::Mesh;
use crate::radiosity::hemicube::{Hemicube, ItemBuffer};
use crate::radiosity::specular::{SpecularPaths, SpecularStats};
use crate::scene::RadiosityParams;

/// Rows whose hemicubes `sampled_work` draws to predict the whole matrix.
pub const SAMPLE_ROWS: usize = 96;

/// The work of drawing some hemicubes, counted: the same integers whatever the thread count.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct HemicubeWork {
    pub hemicubes: u64,
    /// Elements handed to the item buffer (those in chunks that survived frustum culling).
    pub polygons_offered: u64,
    /// Polygons that passed back-face and base-plane culling and were scan-converted.
    pub polygons_rasterised: u64,
    /// Pixels the scan converters depth-tested (overdraw included).
    pub pixels_tested: u64,
    /// Row entries (distinct elements with a form factor; extended entries included).
    pub entries: u64,
    /// Hemicube pixels that showed a mirror or glass and were followed by rays.
    pub specular_pixels: u64,
    /// Rays traced for the extended form factors through mirrors and glass.
    pub specular_rays: u64,
}

impl HemicubeWork {
    fn add(self, o: HemicubeWork) -> HemicubeWork {
        HemicubeWork {
            hemicubes: self.hemicubes + o.hemicubes,
            polygons_offered: self.polygons_offered + o.polygons_offered,
            polygons_rasterised: self.polygons_rasterised + o.polygons_rasterised,
            pixels_tested: self.pixels_tested + o.pixels_tested,
            entries: self.entries + o.entries,
            specular_pixels: self.specular_pixels + o.specular_pixels,
            specular_rays: self.specular_rays + o.specular_rays,
        }
    }

    /// This work scaled by `factor` (a sample's work extrapolated to all rows).
    pub fn scaled(self, factor: f64) -> HemicubeWork {
        let s = |x: u64| (x as f64 * factor).round() as u64;
        HemicubeWork {
            hemicubes: s(self.hemicubes),
            polygons_offered: s(self.polygons_offered),
            polygons_rasterised: s(self.polygons_rasterised),
            pixels_tested: s(self.pixels_tested),
            entries: s(self.entries),
            specular_pixels: s(self.specular_pixels),
            specular_rays: s(self.specular_rays),
        }
    }

    /// Predicted CPU seconds of this work at hemicube resolution N (one core):
    ///
    /// t ≈ 5.6 ns · 3N² · hemicubes + 300 ns · offered + 2 ns · pixels tested + 1.5 µs · specular rays
    ///
    /// (clearing, accumulating and reading back the 3N² pixels of each hemicube; culling, transforming,
    /// clipping and setting up every element offered to it, which makes the plain matrix O(n²); the
    /// depth test of every pixel a span or narrow block covers; the rays of the extended form factors
    /// through mirrors and glass). Fitted on CPU seconds of 300 sampled hemicubes of the Cornell box
    /// and the showcase, 3.3k–35k elements, N = 64–256, one thread: within 0.79–1.31 of the measured
    /// time on all 15 runs (docs/performance.md, "Form-factor cost model"). The pixel coefficient is
    /// set, not fitted (the runs cannot tell it from the per-hemicube one).
    pub fn cpu_seconds(&self, resolution_px: u32) -> f64 {
        let pixels = 3.0 * (resolution_px as f64).powi(2);
        (5.6 * pixels * self.hemicubes as f64
            + 300.0 * self.polygons_offered as f64
            + 2.0 * self.pixels_tested as f64
            + 1500.0 * self.specular_rays as f64)
            * 1e-9
    }
}

/// Draws the hemicubes of `rows` (as `form_factors::compute_planned` would, in parallel, following the
/// pixels that show a mirror or glass through `specular` when given) and counts their work; the rows
/// themselves are dropped.
pub fn measure_work(
    mesh: &Mesh,
    params: &RadiosityParams,
    specular: Option<&SpecularPaths>,
    rows: &[usize],
) -> HemicubeWork {
    let hc = Hemicube::new(params.hemicube_resolution_px);
    let hierarchy = ElementHierarchy::new(mesh);
    rows.par_iter()
        .map_init(
            || (ItemBuffer::new(&hc), Vec::new()),
            |(buffers, row), &i| {
                let before = (buffers.polygons_offered, buffers.polygons_rasterised, buffers.pixels_tested);
                row.clear();
                hierarchy.element_row(mesh, params, &hc, buffers, i, row);
                let mut rays = SpecularStats::default();
                if let Some(specular) = specular {
                    row.retain(|&(j, _)| !specular.is_pure_specular(j as usize));
                    rays = specular.extend_row(&hc, buffers, params.seed, i, row);
                }
                HemicubeWork {
                    hemicubes: 1,
                    polygons_offered: buffers.polygons_offered - before.0,
                    polygons_rasterised: buffers.polygons_rasterised - before.1,
                    pixels_tested: buffers.pixels_tested - before.2,
                    entries: row.len() as u64,
                    specular_pixels: rays.pixels,
                    specular_rays: rays.rays,
                }
            },
        )
        .reduce(HemicubeWork::default, HemicubeWork::add)
}

/// The rows `form_factors::compute` draws (elements that reflect or emit).
pub fn rows_needed(mesh: &Mesh) -> Vec<usize> {
    (0..mesh.elements.len()).filter(|&i| needs_row(mesh, i)).collect()
}

/// At most `count` of `rows`, evenly spaced in element order (so every surface of a large scene is
/// represented in proportion to its elements); all of them when there are no more.
pub fn sample_rows(rows: &[usize], count: usize) -> Vec<usize> {
    if rows.len() <= count {
        return rows.to_vec();
    }
    (0..count).map(|k| rows[k * rows.len() / count + rows.len() / (2 * count)]).collect()
}

/// The work of all the matrix's rows, predicted from `SAMPLE_ROWS` of them, and the number of rows.
pub fn sampled_work(mesh: &Mesh, params: &RadiosityParams, specular: Option<&SpecularPaths>) -> (HemicubeWork, usize) {
    let rows = rows_needed(mesh);
    let sample = sample_rows(&rows, SAMPLE_ROWS);
    let work = measure_work(mesh, params, specular, &sample);
    (work.scaled(rows.len() as f64 / sample.len().max(1) as f64), rows.len())
}
