//! Hierarchical radiosity with clustering and adaptive subdivision (issue 10): a cluster tree over the
//! input triangles (Smits, Arvo and Greenberg 1994; Sillion 1995), elements subdivided 1→4 below them
//! on demand, links refined by the BF criterion (Hanrahan, Salzman and Aupperle 1991) under a memory
//! budget, and Gauss-Seidel with overrelaxation over the hierarchy with push-pull.
//!
//! Entry point: [`solve`]. Refinement (see `refine`) compares each link's reflected-power error
//! A_R·ρ_R·B_S·ΔF with ε·Ē·max(A_R, A_min): dark links are never refined, tiny input triangles are
//! judged by power and served by their clusters, and near cluster pairs are linked lazily.
//!
//! Form factors per link type (see `links::estimate`):
//! - element ← element: Lambert's exact point-to-polygon formula over a receiver quadrature (three
//!   points; 48 when the two elements are near each other) times ray visibility;
//! - far links with a cluster end: the element rule over member pairs (at most 64), else Sillion's
//!   point-to-point cluster formula with exact projected areas, times ray visibility;
//! - near links (overlapping bounding spheres, a cluster straddling an element's plane, a cluster's
//!   self-link): the element estimator summed over all leaf pairs when there are at most 64, else
//!   a sampled estimator exact in each sampled source element (`visibility::sampled_form_factor`).
//!
//! With `link_form_factors = "hemicube"` (not the default) the far links of element receivers are
//! measured again after the last pass by a hemicube at each receiver that draws the tree as a cut
//! (`hemicube_links`); `hemicube_cut` draws that cut, and with `correction = "hemicube"` measures
//! with it the indirect light a leaf gathers, one of the correction's two estimators.
//!
//! Light through mirrors and glass, which no link carries, enters as photons landing in the leaves
//! (`caustics`), traced by the caller (`solve_logged`'s `CausticTracer`).
//!
//! A solve whose links overshoot some leaves' hemispheres so far that the sweeps diverge bounds those
//! rows and starts again (`row_sums`).

pub mod caustics;
pub mod clusters;
pub mod contact;
pub mod edge_angle;
pub mod estimates;
pub mod form_factor;
pub mod gather;
pub mod hemicube_cut;
pub mod hemicube_links;
pub mod interpolate;
pub mod links;
pub mod links_file;
pub mod lobes;
pub mod nodes;
pub mod part_file;
pub mod positional_spread;
pub mod procedural;
pub mod ray_correction;
pub mod refine;
pub mod row_sums;
pub mod shaft;
pub mod shards;
pub mod solve;
pub mod solved_state;
pub mod source_weights;
pub mod texels;
pub mod tree_path;
pub mod visibility;

use std::sync::Arc;

use glam::{DVec3, Vec3};

use crate::accel::Accel;
use crate::material::SceneTextures;
use crate::scene::{CorrectionEstimator, LinkFormFactors, Material, SceneDescription};
use caustics::{CausticLight, CausticSources, CausticTracer};
use contact::{split_at_contacts, ContactProbe};
use estimates::{EstimateHooks, EstimateLog, Stopped};
use gather::ArrivalScales;
use interpolate::LeafMesh;
use links::{refinement_error, LinkRecord, Links, LINK_BYTES};
use nodes::{Nodes, NODE_BYTES};
use refine::{refine_logged, RefineSettings};
use texels::{InputTexels, SurfaceTexels};
use visibility::VisibilityContext;

/// Errors of the hierarchical solver.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum HierarchyError {
    #[error("the scene has no surface with non-zero area")]
    NoSurfaces,
    #[error("{location}: surface {surface} has {vertices} vertices; the hierarchy takes triangles and quads")]
    NotTriangleOrQuad { surface: usize, vertices: usize, location: String },
    #[error("{location}: surface {surface} names material {material}, which does not exist")]
    UnknownMaterial { surface: usize, material: u32, location: String },
    #[error("hierarchy parameter `{name}` is {value}; {expected}")]
    InvalidParameter { name: &'static str, value: String, expected: &'static str },
    #[error(
        "the hierarchy needs at least {needed_bytes} bytes for {triangles} input triangles before any refinement, \
         over the memory budget of {budget_bytes} bytes; raise `memory` or simplify the scene"
    )]
    OverBudget { triangles: usize, needed_bytes: usize, budget_bytes: usize },
    #[error("stopped on request; the link estimates so far are in the solve's log")]
    Stopped,
    #[error(transparent)]
    State(#[from] solved_state::StateMismatch),
}

impl From<Stopped> for HierarchyError {
    fn from(_: Stopped) -> Self {
        HierarchyError::Stopped
    }
}

/// Settings of the hierarchical solver.
#[derive(Clone, Debug, PartialEq)]
pub struct HierarchyParams {
    /// ε: a link is refined while the power it may get wrong, A_R·ρ_R·B_S·ΔF_RS (W, see
    /// `links::link_error_power`), exceeds ε × Ē × max(A_R, A_min), Ē the scene's mean emitted
    /// exitance Σ A·E / Σ A (mean channel) and A_min the minimum element area: the exitance criterion
    /// ρ·B·ΔF ≤ ε·Ē for receivers above A_min, a power criterion below it (see
    /// `refine::RefineSettings::allowed_error_w`), so tiny input triangles do not multiply the links.
    pub error_threshold: f64,
    /// Elements are not subdivided below an area of (scene diagonal / this)². A scene's presets
    /// choose it with `scene_min_element_divisor` (between `COARSEST_MIN_ELEMENT_DIVISOR` and this
    /// default, `FINEST_MIN_ELEMENT_DIVISOR`) unless `min_element_size` is given.
    pub min_element_divisor: f32,
    /// Rays per link for visibility. A scene's presets double it below `FEW_INPUT_TRIANGLES`
    /// (`scene_visibility_rays`) unless `visibility_rays` is given.
    pub visibility_rays: u32,
    /// Overrelaxation factor ω of the Gauss-Seidel sweeps (1 = plain Gauss-Seidel).
    pub relaxation: f64,
    /// Gauss-Seidel (in place, the default) or Jacobi (from the previous sweep, for comparison).
    pub sweep_order: solve::SweepOrder,
    /// A solve stops when no leaf changes by more than this fraction of the largest leaf exitance.
    pub tolerance: f64,
    pub max_sweeps: u32,
    /// Solves in all: the first refinement uses B = E; each later pass re-refines with the solved B
    /// (where the error estimate moved), then solves again from the previous solution.
    pub refinement_passes: u32,
    /// Bytes nodes and links may take. Refinement stops (keeping coarser links) at the budget.
    pub memory_bytes: usize,
    pub seed: u64,
    /// δ: from the second pass on, a receiver darker than Ē keeps the share clamp(B_R/Ē, δ, 1) of
    /// the allowed error (`refine::dark_receiver_share`); 1 turns it off.
    pub dark_receiver_floor: f64,
    /// Cosine rays per leaf that measure the indirect light the links bring (`ray_correction`),
    /// after the last pass; 0 turns the correction off.
    pub correction_rays: u32,
    /// How the correction measures the leaves' indirect light: `correction_rays` cosine rays per
    /// leaf, or hemicubes that draw the tree as a cut (`hemicube_cut`, `CUT_RESOLUTION_PX`,
    /// `CUT_STRIDE`, `CUT_PIXELS`).
    pub correction: CorrectionEstimator,
    /// What measures the far links of element receivers after the last refinement pass: their
    /// estimators, or a hemicube at each such receiver (`hemicube_links`, `LINK_RESOLUTION_PX`,
    /// `LINK_CUT_PIXELS`).
    pub link_form_factors: LinkFormFactors,
}

/// The presets' rays per leaf of the ray correction (`HierarchyParams::correction_rays`, the scene
/// key `correction_rays`). Session 42 (docs/accuracy.md), radiosity mode, groups of 256 leaves,
/// 3σ shrinkage, two rounds: Crytek Sponza 0.0569 → 0.0439 (median pixel ratio 0.758 → 0.847) for
/// about 45 s of rays and 9 more sweeps; the rooms within ±6% (l_room −3.5%, rotunda −5.6%,
/// vault_hall −3.6%, gap_room +2.4%, fixture_room +3.6%, the rest unchanged) at +5–8% CPU-s.
pub const CORRECTION_RAYS: u32 = 16;

/// The hemicube correction's resolution (pixels across the top face), leaves per hemicube (one leaf
/// in `CUT_STRIDE`, in tree order: 16 per group of `ray_correction::GROUP_LEAVES`; fewer where that
/// would be more than `CUT_HEMICUBES` per measurement), and the largest size (pixels) of a node
/// drawn whole (`hemicube_cut`). Session 44 (docs/accuracy.md), radiosity
/// mode against the shipped references: l_room 1.781e-4 at 32 / 16 / 1 and 1.820e-4 at 32 / 16 / 2,
/// against the rays' 1.885e-4, for +40–75% CPU-s; every leaf (stride 1) 1.621e-4 for 15× the CPU-s.
/// Crytek Sponza at 32 / 64 / 2: 0.0427 against the rays' 0.0413, +43% CPU-s of pass one. Not the
/// default: it does not pay for its time.
pub const CUT_RESOLUTION_PX: u32 = 32;
pub const CUT_STRIDE: u32 = 16;
pub const CUT_PIXELS: f32 = 2.0;
pub const CUT_HEMICUBES: u32 = 10_000;

/// The hemicube that measures links (`LinkFormFactors::Hemicube`, `hemicube_links`): pixels across
/// its top face, and the largest size (pixels) of a cluster drawn whole as a square (elements are
/// always drawn whole unless a source lies below them: their triangles are exact). Session 45
/// (docs/accuracy.md): see the README's "Estimators".
pub const LINK_RESOLUTION_PX: u32 = 128;
pub const LINK_CUT_PIXELS: f32 = 2.0;

/// Mixed into the solve's seed for the turns of the links' hemicubes.
const LINK_HEMICUBE_SEED: u64 = 0x11c5_4e3a;

/// The correction's estimator for `params`.
fn correction_estimator(params: &HierarchyParams) -> ray_correction::IndirectEstimator {
    match params.correction {
        CorrectionEstimator::Rays => ray_correction::IndirectEstimator::Rays { rays: params.correction_rays },
        CorrectionEstimator::Hemicube => ray_correction::IndirectEstimator::Hemicube {
            resolution_px: CUT_RESOLUTION_PX,
            stride: CUT_STRIDE,
            cut_pixels: CUT_PIXELS,
            max_hemicubes: CUT_HEMICUBES,
        },
    }
}

/// Measure-and-sweep rounds of the ray correction.
pub const CORRECTION_ROUNDS: u32 = 2;

/// Mixed into the solve's seed for the correction's rays (round r adds r).
const CORRECTION_SEED: u64 = 0x5eed_0000;

/// Scenes with fewer input triangles than this get twice their preset's visibility rays.
pub const FEW_INPUT_TRIANGLES: usize = 10_000;

/// The visibility rays per link a preset with `preset_rays` uses for a scene of `input_triangles`:
/// 2 × `preset_rays` below `FEW_INPUT_TRIANGLES`, else `preset_rays`.
///
/// A link's visibility is a fraction of its rays, and its noise shows on a receiver about as
/// 1/√(links × rays) over the links the receiver gathers. In a scene of a few hundred input
/// polygons each receiver gathers over few links and every link is cheap next to the whole solve:
/// there, 16 rays instead of 8 took cornell_original's radiosity-mode relMSE from 0.00167 to 0.00099
/// (mean of seeds 0–3), alcove_hall's from 0.00432 to 0.00255, gap_room's from 0.050 to 0.037 against
/// the converged image (docs/performance.md). In a tessellated scene the links number millions, each
/// receiver gathers over many of them, and the rays are most of the cost (procedural:16000 at 16 rays:
/// about 1.6× the CPU time at 8), so it keeps the preset's.
pub fn scene_visibility_rays(preset_rays: u32, input_triangles: usize) -> u32 {
    if input_triangles < FEW_INPUT_TRIANGLES {
        preset_rays.saturating_mul(2)
    } else {
        preset_rays
    }
}

/// The finest minimum element edge a preset uses: diagonal / 200.
pub const FINEST_MIN_ELEMENT_DIVISOR: f32 = 200.0;

/// The coarsest minimum element edge a preset uses: diagonal / 80.
pub const COARSEST_MIN_ELEMENT_DIVISOR: f32 = 80.0;

/// Minimum elements per shortest input edge: a preset's minimum element edge is at least this many
/// times finer than the scene's shortest input polygon edge.
pub const MIN_ELEMENTS_PER_SHORTEST_EDGE: f32 = 8.0;

/// The minimum element divisor a preset uses for a scene of diagonal `diagonal` whose shortest input
/// polygon edge is `shortest_edge` (same units):
///
/// d = clamp(diagonal / (shortest_edge / 8), 80, 200), minimum element edge = diagonal / d.
///
/// The detail light makes on a surface (contact shadows, concave corners, penumbrae) is set by the
/// geometry around it, so elements need not be much finer than the smallest input feature. A scene
/// with small polygons anywhere (furniture, pillars, any tessellated mesh) keeps diagonal / 200; a
/// scene made only of large polygons (a Cornell box: shortest edge 105 mm of a 961 mm diagonal)
/// gets elements down to diagonal / 80: fewer and larger leaves (cornell_original radiosity mode at
/// 16 visibility rays: relMSE 0.00111 at diagonal / 80 in 8.6 CPU-s against 0.00108 at diagonal / 200
/// in 24.9, the full matrix 0.00036 in 11.2; docs/performance.md). A degenerate edge (0) gives
/// diagonal / 200.
pub fn scene_min_element_divisor(diagonal: f32, shortest_edge: f32) -> f32 {
    let divisor = diagonal * MIN_ELEMENTS_PER_SHORTEST_EDGE / shortest_edge;
    if divisor.is_finite() {
        divisor.clamp(COARSEST_MIN_ELEMENT_DIVISOR, FINEST_MIN_ELEMENT_DIVISOR)
    } else {
        FINEST_MIN_ELEMENT_DIVISOR
    }
}

/// The presets' δ (`HierarchyParams::dark_receiver_floor`, the scene key `dark_receiver_floor`): 1,
/// every receiver judged by ε·Ē alike. Session 41 (docs/accuracy.md), radiosity mode against the
/// references at equal CPU time (main's curve over ε interpolated): δ = 1/2 gap_room −20%,
/// stair_hall −8%, vault_hall −3%, l_room +2%, alcove_hall +2%, but Sponza +6% (0.0525 at 1006
/// CPU-s against ε = 3.5e-3's 0.0497 at 989); δ = 1/4 gap_room −27%, l_room +9%, alcove_hall +6%.
/// A scene seen mostly in light that came through an opening gains from 1/2; a lit interior does
/// not, so the presets keep 1.
pub const DARK_RECEIVER_FLOOR: f64 = 1.0;

impl Default for HierarchyParams {
    /// Six of the 8 GB the issue allows go to nodes and links; the rest is the scene, the BVH and the
    /// output mesh.
    fn default() -> Self {
        HierarchyParams {
            error_threshold: 5e-3,
            min_element_divisor: FINEST_MIN_ELEMENT_DIVISOR,
            visibility_rays: 8,
            relaxation: 1.1,
            sweep_order: solve::SweepOrder::GaussSeidel,
            tolerance: 1e-4,
            max_sweeps: 200,
            refinement_passes: 3,
            memory_bytes: 6 << 30,
            seed: 0,
            dark_receiver_floor: DARK_RECEIVER_FLOOR,
            correction_rays: CORRECTION_RAYS,
            correction: CorrectionEstimator::Rays,
            link_form_factors: LinkFormFactors::Formulas,
        }
    }
}

impl HierarchyParams {
    /// Coarser threshold, fewer rays and passes: seconds on a Cornell box.
    pub fn preview() -> Self {
        HierarchyParams { error_threshold: 2e-2, visibility_rays: 4, refinement_passes: 2, ..Default::default() }
    }

    /// Finer threshold and more visibility rays.
    pub fn final_quality() -> Self {
        HierarchyParams { error_threshold: 2e-3, visibility_rays: 16, ..Default::default() }
    }

    fn validate(&self) -> Result<(), HierarchyError> {
        let bad = |name, value: String, expected| Err(HierarchyError::InvalidParameter { name, value, expected });
        if !(self.error_threshold > 0.0) || !self.error_threshold.is_finite() {
            return bad("error_threshold", self.error_threshold.to_string(), "expected a positive number");
        }
        if !(self.dark_receiver_floor > 0.0 && self.dark_receiver_floor <= 1.0) {
            return bad("dark_receiver_floor", self.dark_receiver_floor.to_string(), "expected a number in (0, 1]");
        }
        if self.correction_rays > 4096 {
            return bad("correction_rays", self.correction_rays.to_string(), "expected 0 to 4096");
        }
        if !(self.min_element_divisor >= 1.0) || !self.min_element_divisor.is_finite() {
            return bad("min_element_divisor", self.min_element_divisor.to_string(), "expected a number ≥ 1");
        }
        if self.visibility_rays == 0 || self.visibility_rays > 4096 {
            return bad("visibility_rays", self.visibility_rays.to_string(), "expected 1 to 4096");
        }
        if !(self.relaxation > 0.0 && self.relaxation < 2.0) {
            return bad("relaxation", self.relaxation.to_string(), "expected 0 < ω < 2");
        }
        if !(self.tolerance > 0.0) {
            return bad("tolerance", self.tolerance.to_string(), "expected a positive number");
        }
        if self.max_sweeps == 0 {
            return bad("max_sweeps", "0".into(), "expected at least 1");
        }
        if self.refinement_passes == 0 {
            return bad("refinement_passes", "0".into(), "expected at least 1");
        }
        Ok(())
    }
}

/// What the solver did (also what `--stats` reports for a hierarchical pass one).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct HierarchyStats {
    pub input_triangles: usize,
    pub clusters: usize,
    /// All nodes: clusters, input triangles and their subdivisions.
    pub nodes: usize,
    /// Leaf elements (the output mesh's triangles).
    pub elements: usize,
    pub links: usize,
    pub refinement_passes: u32,
    /// Breadth-first refinement rounds over all passes.
    pub refinement_rounds: u32,
    /// Sweeps over all solves.
    pub sweeps: u32,
    /// How they gathered: "gauss-seidel" or "jacobi" (`solve::SweepOrder::name`).
    pub sweep_order: &'static str,
    /// The last solve converged to the tolerance.
    pub converged: bool,
    /// Links estimated over all passes (each with `visibility_rays` rays).
    pub links_estimated: u64,
    /// Largest bytes of nodes and links during the run (the budgeted part).
    pub peak_bytes: usize,
    /// Bytes of nodes and links at the end.
    pub bytes: usize,
    /// Some refinement was refused to stay within `memory_bytes`.
    pub budget_exceeded: bool,
    /// Σ of link errors (watts) after each refinement pass, at the exitance that pass saw.
    pub error_after_pass_w: Vec<f64>,
    /// The exitance ε is relative to: emitted power / total area (W/m², mean channel).
    pub reference_exitance: f64,
    /// Σ A·E over the input triangles (W, mean channel).
    pub reference_power_w: f64,
    /// Photons that brought caustic light (through mirrors and glass) to the input triangles, and
    /// the rays traced for them (`caustics`; zero without a tracer or specular surfaces).
    pub caustic_photons: usize,
    pub caustic_rays: u64,
    /// When the sweeps diverged and the rows were bounded (`row_sums`; 0 and 0 otherwise): the leaves
    /// whose links sum so far beyond their hemisphere that they would reflect all they gather (row
    /// sum R with ρ·R ≥ 1; their gathering is scaled by 1/R), and the largest row sum of any leaf,
    /// after the last refinement pass.
    pub bounded_leaves: usize,
    pub max_row_sum: f64,
    /// The last round of the ray correction (`ray_correction`; all zero when it is off).
    pub correction: ray_correction::CorrectionStats,
    /// What the links' hemicubes measured (`hemicube_links`; all zero unless they ran).
    pub link_hemicubes: hemicube_links::LinkHemicubeStats,
}

/// Progress of a solve, for a progress bar or log lines.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum HierarchyProgress {
    Refining {
        pass: u32,
        round: u32,
        links: usize,
        nodes: usize,
    },
    /// Photons are about to be traced through mirrors and glass (`caustics`), from `sources`; only
    /// for scenes with a specular material (the tracer returns at once for others).
    TracingPhotons {
        pass: u32,
        sources: CausticSources,
    },
    Sweeping {
        pass: u32,
        sweep: u32,
        max_change: f64,
        max_exitance: f64,
    },
    /// The far links of element receivers are about to be measured by hemicubes (`hemicube_links`).
    MeasuringLinks {
        pass: u32,
        receivers: usize,
    },
    /// Round `round` of the ray correction (`ray_correction`) is about to trace its rays.
    Correcting {
        pass: u32,
        round: u32,
    },
}

/// The result: the leaf elements with their exitance, and a conforming per-vertex interpolation.
#[derive(Clone, Debug, Default)]
pub struct HierarchicalSolution {
    /// Leaf elements as an indexed mesh with conforming vertex exitance.
    pub mesh: LeafMesh,
    /// Per leaf (index of `mesh.triangles`): exitance B = π·radiance (W/m²).
    pub leaf_exitance: Vec<Vec3>,
    /// Per leaf: emitted exitance E (W/m²).
    pub leaf_emission: Vec<Vec3>,
    pub leaf_reflectance: Vec<Vec3>,
    pub leaf_area: Vec<f32>,
    /// Per leaf: the scene surface it lies on, and whether it is the back side of a two-sided one.
    pub leaf_surface: Vec<u32>,
    pub leaf_back: Vec<bool>,
    pub stats: HierarchyStats,
}

impl HierarchicalSolution {
    /// Area-weighted mean exitance of the front side of each of `surface_count` scene surfaces.
    pub fn surface_mean_exitance(&self, surface_count: usize) -> Vec<DVec3> {
        let mut sum = vec![DVec3::ZERO; surface_count];
        let mut area = vec![0.0f64; surface_count];
        for i in 0..self.leaf_area.len() {
            let s = self.leaf_surface[i] as usize;
            if self.leaf_back[i] || s >= surface_count {
                continue;
            }
            sum[s] += self.leaf_exitance[i].as_dvec3() * self.leaf_area[i] as f64;
            area[s] += self.leaf_area[i] as f64;
        }
        sum.iter().zip(&area).map(|(s, &a)| if a > 0.0 { *s / a } else { DVec3::ZERO }).collect()
    }
}

/// Input triangles the scene makes (quads count two, two-sided surfaces twice), without building.
pub fn count_input_triangles(scene: &SceneDescription) -> usize {
    scene.surfaces.iter().map(|s| s.vertices.len().saturating_sub(2) * if s.two_sided { 2 } else { 1 }).sum()
}

/// The refined hierarchy a solve ends with: nodes (with their geometry and tree), links with their
/// form factors, the input triangles and the occluders. Form factors and visibility depend on the
/// geometry only (and on which triangles are cut-outs), so a later solve of the same geometry with
/// other materials may start from it (`solve_reusing`), as a batch does through `Reuse`.
#[derive(Clone, Debug)]
pub struct LinkStructure {
    /// With the materials and the final exitance of the solve that refined them.
    nodes: Nodes,
    links: Links,
    /// The allowed error per m² that solve refined against (`RefineSettings::threshold`, W/m²).
    threshold: f64,
    root: usize,
    inputs: clusters::InputTriangles,
    tracing: clusters::TracingTriangles,
}

impl LinkStructure {
    /// Bytes it holds (nodes, links, input and tracing triangles): what a cache keeping it is charged.
    pub fn memory_bytes(&self) -> u64 {
        let i = &self.inputs;
        let t = &self.tracing;
        (self.nodes.len() * NODE_BYTES
            + self.links.memory_bytes()
            + std::mem::size_of_val(&i.surface[..])
            + std::mem::size_of_val(&i.back[..])
            + std::mem::size_of_val(&i.material[..])
            + std::mem::size_of_val(&i.node[..])
            + std::mem::size_of_val(&t.positions[..])
            + std::mem::size_of_val(&t.triangles[..])) as u64
    }

    pub fn link_count(&self) -> usize {
        self.links.len()
    }

    /// The nodes, with the final exitance of the solve that refined them.
    pub fn nodes(&self) -> &Nodes {
        &self.nodes
    }

    /// The links by receiver.
    pub fn links(&self) -> &Links {
        &self.links
    }

    /// The input triangles (each one's scene surface, side and node).
    pub fn inputs(&self) -> &clusters::InputTriangles {
        &self.inputs
    }

    /// The root of the cluster tree.
    pub fn root(&self) -> usize {
        self.root
    }
}

/// Solves the scene's diffuse radiosity hierarchically, with every material's Kd and π·Ke (no
/// textures). Builds its own ray accelerator over the scene's triangles. Deterministic: the same scene
/// and parameters give the same values for any number of rayon threads.
pub fn solve(
    scene: &SceneDescription,
    params: &HierarchyParams,
    on_progress: &mut dyn FnMut(HierarchyProgress),
) -> Result<HierarchicalSolution, HierarchyError> {
    solve_reusing(scene, Arc::default(), params, None, on_progress).map(|(solution, _)| solution)
}

/// How much worse (relative) new materials must make a kept link's error ratio before a re-solve
/// splits it (see `solve_reusing`): changes below 10% are within what the solution's own
/// convergence and the visibility estimate move a ratio by, and are no reason to refine.
pub const REUSE_GROWTH: f64 = 0.1;

/// `solve` with the scene's loaded `textures` (each element reflects its texture means, see
/// `texels`), optionally starting from the links of an earlier solve of the same geometry and
/// parameters (`reuse`, which the caller matches by `hierarchical::link_key`). Returns the solution
/// and the link structure it ended with.
///
/// Reuse: the nodes and links are kept and take the new materials (every element its `texels`
/// means, every cluster the area-weighted aggregates of its children), and the first pass solves on
/// the kept links as they are. The power-driven refinement depends on the materials, so the later
/// passes re-refine, but only where the new materials made a link worse: a kept link is split only
/// when its new error ratio r′ = refinement_error / allowed error (new solution, new threshold)
/// exceeds both 1 and (1 + `REUSE_GROWTH`)·r, r its ratio under the solve that refined it (old
/// materials, its final solution). A materials change that scales every error like the threshold
/// (the same materials, or all emission scaled) therefore splits nothing and gives the fresh solve's
/// links, so the re-solve equals the fresh one within the solver tolerance. Only new links are
/// estimated (`HierarchyStats::links_estimated`); links the old materials needed finer are kept (never
/// coarsened, which only lowers the error estimate). Passes stop early when nothing needs splitting.
pub fn solve_reusing(
    scene: &SceneDescription,
    textures: Arc<SceneTextures>,
    params: &HierarchyParams,
    reuse: Option<&LinkStructure>,
    on_progress: &mut dyn FnMut(HierarchyProgress),
) -> Result<(HierarchicalSolution, LinkStructure), HierarchyError> {
    let mut log = EstimateLog::default();
    let mut hooks = EstimateHooks { log: &mut log, stop: &|| false, after_chunk: &mut |_, _| {}, shared: None };
    solve_logged(scene, textures, params, reuse, None, &mut hooks, on_progress)
}

/// `solve_reusing` with every link estimate going through `hooks.log` (`estimates`): a log from an
/// interrupted solve of the same scene and parameters is replayed (its estimates are not computed
/// again) and the solve ends with the bytes of an uninterrupted one. `hooks.stop` is polled between
/// chunks of estimates and between sweeps; when it asks, this returns `HierarchyError::Stopped` with
/// the log holding every estimate made so far (the caller's checkpoint). With `hooks.shared` it is a
/// shard (runs the passes before its own whole, refines its own for its receivers and stops, that
/// pass unswept) or a merge (the whole solve, with the shards' pure estimates; see `shards`).
/// With `caustics`, the light it traces through mirrors and glass to the input triangles is a source
/// term of every leaf it lands in (`caustics`: B = E + ρ·(G + E_c)); without, the solve carries
/// diffuse light only (`solve`, `solve_reusing`).
pub fn solve_logged(
    scene: &SceneDescription,
    textures: Arc<SceneTextures>,
    params: &HierarchyParams,
    reuse: Option<&LinkStructure>,
    caustics: Option<&CausticTracer>,
    hooks: &mut EstimateHooks,
    on_progress: &mut dyn FnMut(HierarchyProgress),
) -> Result<(HierarchicalSolution, LinkStructure), HierarchyError> {
    params.validate()?;
    let triangles = count_input_triangles(scene);
    // Before anything large: the input triangles, their clusters and the links of the self-link
    // expansion (four per cluster) must fit.
    let needed_bytes = 2 * triangles * NODE_BYTES + 4 * triangles * LINK_BYTES;
    if needed_bytes > params.memory_bytes {
        return Err(HierarchyError::OverBudget { triangles, needed_bytes, budget_bytes: params.memory_bytes });
    }
    let surfaces = SurfaceTexels::new(scene, textures);
    let (mut nodes, root, inputs, tracing, mut links) = match reuse {
        Some(kept) => {
            let mut nodes = kept.nodes.clone();
            let texels = InputTexels { surfaces, input_surface: kept.inputs.surface.clone() };
            assign_materials(&mut nodes, &texels);
            (nodes, kept.root, kept.inputs.clone(), kept.tracing.clone(), kept.links.clone())
        }
        None => {
            let (mut nodes, root, inputs, tracing) = clusters::build_textured(scene, &surfaces)?;
            if !surfaces.is_untextured() {
                nodes.texels = Some(Arc::new(InputTexels { surfaces, input_surface: inputs.surface.clone() }));
            }
            (nodes, root as usize, inputs, tracing, Links::default())
        }
    };
    let accel = Accel::build(&tracing.positions, &tracing.triangles);
    let diagonal = scene.diagonal();
    let ctx =
        VisibilityContext { accel: &accel, rays: params.visibility_rays, offset: diagonal * 1e-5, seed: params.seed };
    let (reference_power_w, reference_exitance) = emitted_power(&nodes, &inputs);
    let min_element_area = (diagonal / params.min_element_divisor).powi(2);
    let settings = RefineSettings {
        threshold: params.error_threshold * reference_exitance,
        floor_area: min_element_area,
        min_element_area,
        budget_bytes: params.memory_bytes,
        reference_exitance,
        dark_receiver_floor: 1.0,
    };
    // From the second pass on the exitance is solved, and dark receivers are held to a relative error.
    let solved_settings = RefineSettings { dark_receiver_floor: params.dark_receiver_floor, ..settings };
    if reuse.is_none() {
        // Where an object rests on an element, split it down to the minimum size along the contact
        // and keep the enclosed part out of what the element sends and shows (`contact`).
        let probe =
            ContactProbe { accel: &accel, tracing: &tracing, offset: ctx.offset, contact_distance: diagonal * 1e-4 };
        let first_piece = nodes.len();
        // At most half the budget's nodes, so refinement keeps room.
        let max_nodes = params.memory_bytes / 2 / (NODE_BYTES + std::mem::size_of::<u32>());
        split_at_contacts(&mut nodes, &inputs.node, &probe, min_element_area, max_nodes);
        nodes.assign_texture_means(first_piece);
    }
    let has_specular = scene.materials.iter().any(Material::is_specular);
    let caustic_light: Option<CausticLight> = caustics.and_then(|trace| {
        if has_specular {
            on_progress(HierarchyProgress::TracingPhotons { pass: 1, sources: CausticSources::Emitters });
        }
        trace(&nodes, &inputs, CausticSources::Emitters)
    });
    let mut stats = HierarchyStats {
        input_triangles: inputs.node.len(),
        clusters: nodes.is_cluster.iter().filter(|&&c| c).count(),
        reference_exitance,
        reference_power_w,
        caustic_photons: caustic_light.as_ref().map_or(0, CausticLight::len),
        caustic_rays: caustic_light.as_ref().map_or(0, |c| c.rays),
        sweep_order: params.sweep_order.name(),
        ..Default::default()
    };
    set_caustic_light(&mut nodes, &inputs, root, caustic_light.as_ref());
    solve::reset_to_emission(&mut nodes, root);
    let build_nodes = nodes.len();
    // A shard (`shards`) stops after refining its pass for its receivers.
    let shard_pass = hooks.shared.and_then(|s| s.shard_pass());
    // A shard or merge of a later round starts from the state the round before handed on.
    let mut first_pass = 1;
    if let Some(state) = hooks.shared.and_then(|s| s.take_start()) {
        links = state.restore(&mut nodes, &mut stats)?;
        first_pass = state.pass + 1;
    }
    // The `ArrivalScales` of `links` once computed; each pass's are computed from the pass before's.
    let mut scales: Option<ArrivalScales> = None;
    match reuse {
        None => {
            for pass in first_pass..=params.refinement_passes {
                if let Some(shared) = hooks.shared {
                    shared.begin_pass(pass);
                    if shard_pass == Some(pass) {
                        // By the links of the pass before, which this pass re-refines.
                        shared.assign_receivers(&nodes, root, &links);
                    }
                    if shard_pass == Some(pass) && pass > 1 {
                        shared.capture(solved_state::SolvedState::capture(
                            &nodes,
                            build_nodes,
                            &links,
                            &stats,
                            pass - 1,
                        ));
                    }
                }
                let (records, self_links) = if pass == 1 {
                    (Vec::new(), if nodes.is_cluster[root] { vec![root as u32] } else { Vec::new() })
                } else {
                    // The links as records only: refinement makes new ones (the scales keep their
                    // own sources, `ArrivalScales::reusing`).
                    (std::mem::take(&mut links).to_records(), Vec::new())
                };
                let outcome = refine_logged(
                    &mut nodes,
                    &ctx,
                    records,
                    self_links,
                    if pass == 1 { &settings } else { &solved_settings },
                    hooks,
                    &mut |round, kept, count| {
                        on_progress(HierarchyProgress::Refining { pass, round, links: kept, nodes: count })
                    },
                )?;
                stats.add_refinement(pass, &outcome, outcome.error_after_w);
                links = outcome.links;
                if shard_pass == Some(pass) {
                    // The scales belong to the previous pass's links: a shard's partial solve
                    // gets no positional spread (its merge solves again).
                    scales = None;
                    break;
                }
                let mut current = ArrivalScales::reusing(&nodes, &links, scales.take().as_ref());
                set_caustic_light(&mut nodes, &inputs, root, caustic_light.as_ref());
                sweep_pass(&mut nodes, &links, &mut current, root, params, pass, &mut stats, hooks.stop, on_progress)?;
                scales = Some(current);
            }
        }
        Some(kept) => {
            stats.refinement_passes = 1;
            stats.error_after_pass_w.push(refine::total_error(&nodes, &links.to_records()));
            let mut first = ArrivalScales::new(&nodes, &links);
            sweep_pass(&mut nodes, &links, &mut first, root, params, 1, &mut stats, hooks.stop, on_progress)?;
            scales = Some(first);
            for pass in 2..=params.refinement_passes {
                // The kept solve's settings: its threshold ε·Ē, with Ē from its own emission.
                let kept_settings = RefineSettings {
                    threshold: kept.threshold,
                    reference_exitance: kept.threshold / params.error_threshold,
                    ..solved_settings
                };
                let ratio = |n: &Nodes, l: &LinkRecord, settings: &RefineSettings| {
                    let r = l.receiver as usize;
                    refinement_error(n, l) / settings.allowed_error_w(n.area[r], n.exitance_mean[r])
                };
                let (active, frozen): (Vec<LinkRecord>, Vec<LinkRecord>) =
                    links.to_records().into_iter().partition(|l| {
                        let new = ratio(&nodes, l, &solved_settings);
                        new > 1.0 && new > (1.0 + REUSE_GROWTH) * ratio(&kept.nodes, l, &kept_settings)
                    });
                if active.is_empty() {
                    break;
                }
                let outcome = refine_logged(
                    &mut nodes,
                    &ctx,
                    active,
                    Vec::new(),
                    &solved_settings,
                    hooks,
                    &mut |round, kept, count| {
                        on_progress(HierarchyProgress::Refining { pass, round, links: kept, nodes: count })
                    },
                )?;
                let mut records = outcome.links.to_records();
                records.extend(frozen);
                let error_after_w = refine::total_error(&nodes, &records);
                links = Links::from_records(nodes.len(), records);
                stats.add_refinement(pass, &outcome, error_after_w);
                let mut current = ArrivalScales::reusing(&nodes, &links, scales.take().as_ref());
                set_caustic_light(&mut nodes, &inputs, root, caustic_light.as_ref());
                sweep_pass(&mut nodes, &links, &mut current, root, params, pass, &mut stats, hooks.stop, on_progress)?;
                scales = Some(current);
            }
        }
    }
    // The far links of element receivers measured again by hemicubes at the receivers
    // (`hemicube_links`), and the sweeps again; a shard, which stops unswept, leaves this to its merge.
    if let Some(current) = scales.as_mut().filter(|_| params.link_form_factors == LinkFormFactors::Hemicube) {
        let pass = stats.refinement_passes;
        on_progress(HierarchyProgress::MeasuringLinks {
            pass,
            receivers: hemicube_links::receivers(&nodes, &links).len(),
        });
        let two_sided = hemicube_cut::two_sided_inputs(&inputs);
        let lobes = lobes::Lobes::new(&nodes, &links, root);
        let settings = hemicube_links::LinkHemicubes { resolution_px: LINK_RESOLUTION_PX, cut_pixels: LINK_CUT_PIXELS };
        let scene = hemicube_cut::CutScene {
            nodes: &nodes,
            exitance: &nodes.exitance,
            lobes: &lobes,
            two_sided: &two_sided,
            root,
        };
        stats.link_hemicubes =
            hemicube_links::measure_links(&scene, &mut links, settings, params.seed ^ LINK_HEMICUBE_SEED, ctx.offset);
        sweep_pass(&mut nodes, &links, current, root, params, pass, &mut stats, hooks.stop, on_progress)?;
    }
    // Light between diffuse surfaces through mirrors and glass (`caustics`): once the solve has
    // converged, photons from every surface's reflected light join the emitters', and the last links
    // are swept again (a shard, which stops unswept, leaves this to its merge).
    if let (Some(trace), Some(current), Some(first)) = (caustics, scales.as_mut(), caustic_light) {
        let pass = stats.refinement_passes;
        on_progress(HierarchyProgress::TracingPhotons { pass, sources: CausticSources::ReflectedLight });
        if let Some(reflected) = trace(&nodes, &inputs, CausticSources::ReflectedLight) {
            stats.caustic_photons += reflected.len();
            stats.caustic_rays += reflected.rays;
            set_caustic_light(&mut nodes, &inputs, root, Some(&first.merged(reflected)));
            sweep_pass(&mut nodes, &links, current, root, params, pass, &mut stats, hooks.stop, on_progress)?;
        }
    }
    // The leaves' indirect light measured by cosine rays and the links' share of it corrected
    // (`ray_correction`), then the sweeps again; twice, the second at the corrected exitance. The
    // kept structure holds the exitance from before: a re-solve that reuses its links compares the
    // link errors of its own sweeps, which come before its correction, with those (`REUSE_GROWTH`).
    let mut uncorrected: Option<Vec<DVec3>> = None;
    if let Some(current) = scales.as_mut().filter(|s| params.correction_rays > 0 && !s.rows_bounded()) {
        uncorrected = Some(nodes.exitance.clone());
        for round in 0..CORRECTION_ROUNDS {
            let pass = stats.refinement_passes;
            on_progress(HierarchyProgress::Correcting { pass, round: round + 1 });
            let seed = params.seed ^ CORRECTION_SEED.wrapping_add(round as u64);
            let (correction, measured) = ray_correction::measure(
                &mut nodes,
                &inputs,
                ctx.accel,
                &links,
                current,
                root,
                correction_estimator(params),
                seed,
                ctx.offset,
            );
            stats.correction = measured;
            current.set_correction(Some(correction));
            sweep_pass(&mut nodes, &links, current, root, params, pass, &mut stats, hooks.stop, on_progress)?;
        }
    }
    // The leaves' exitance with each element receiver's links spread by position (the solved
    // exitance stays in the kept structure, for a re-solve to start from).
    let spread =
        scales.as_ref().map(|s| positional_spread::spread_leaf_exitance(&nodes, &links, s, root)).unwrap_or_default();
    // Not needed past the sweeps; freed before the leaf mesh is built.
    drop(scales);
    stats.nodes = nodes.len();
    stats.links = links.len();
    stats.bytes = nodes.len() * NODE_BYTES + links.memory_bytes();
    stats.peak_bytes = stats.peak_bytes.max(stats.bytes);
    let solved_exitance: Vec<(usize, DVec3)> = spread.iter().map(|&(n, _)| (n, nodes.exitance[n])).collect();
    for &(n, b) in &spread {
        nodes.exitance[n] = b;
    }
    let solved = solution(&nodes, &inputs, root, stats);
    for (n, b) in solved_exitance {
        nodes.exitance[n] = b;
    }
    if let Some(before) = uncorrected {
        for (n, b) in before.into_iter().enumerate() {
            nodes.exitance[n] = b;
            nodes.exitance_mean[n] = nodes::mean_channel(b);
        }
    }
    Ok((solved, LinkStructure { nodes, links, threshold: settings.threshold, root, inputs, tracing }))
}

impl HierarchyStats {
    /// Records refinement pass `pass` (with the Σ link error it left, W).
    fn add_refinement(&mut self, pass: u32, outcome: &refine::RefineOutcome, error_after_w: f64) {
        self.refinement_passes = pass;
        self.refinement_rounds += outcome.rounds;
        self.links_estimated += outcome.estimated;
        self.budget_exceeded |= outcome.budget_exceeded;
        self.peak_bytes = self.peak_bytes.max(outcome.peak_bytes);
        self.error_after_pass_w.push(error_after_w);
    }
}

/// Gives every node its caustic irradiance from `light` (`caustics`), or none: after each refinement,
/// since the photons fall into the new leaves.
fn set_caustic_light(nodes: &mut Nodes, inputs: &clusters::InputTriangles, root: usize, light: Option<&CausticLight>) {
    if let Some(light) = light {
        let irradiance = light.node_irradiance(nodes, inputs, root);
        nodes.set_caustic_irradiance(irradiance);
    }
}

/// The sweeps (`HierarchyParams::sweep_order`) of pass `pass` over `links` with their `scales`
/// (warm-started from the nodes' exitance), recorded in `stats`; `Stopped` when `stop` asks between
/// two sweeps.
#[allow(clippy::too_many_arguments)]
fn sweep_pass(
    nodes: &mut Nodes,
    links: &Links,
    scales: &mut ArrivalScales,
    root: usize,
    params: &HierarchyParams,
    pass: u32,
    stats: &mut HierarchyStats,
    stop: &dyn Fn() -> bool,
    on_progress: &mut dyn FnMut(HierarchyProgress),
) -> Result<(), Stopped> {
    let mut on_sweep = |sweep, c: solve::SweepChange| {
        on_progress(HierarchyProgress::Sweeping { pass, sweep, max_change: c.max_change, max_exitance: c.max_exitance })
    };
    let (p, sweeps) = (params, params.max_sweeps);
    let (sweeps, converged) = solve::solve_until(
        nodes,
        links,
        scales,
        root,
        p.sweep_order,
        p.relaxation,
        p.tolerance,
        sweeps,
        &mut on_sweep,
        stop,
    )
    .ok_or(Stopped)?;
    stats.sweeps += sweeps;
    stats.converged = converged;
    (stats.bounded_leaves, stats.max_row_sum) = scales.row_bound();
    Ok(())
}

/// Gives every node of a kept hierarchy the materials of `texels`: each element (input triangle or
/// piece) its own means (`InputTexels::solved_materials`), each cluster the area-weighted aggregates
/// of its children (`Nodes::set_cluster_children`). Children always have higher indices than their
/// parent, so one pass in reverse index order sees every child before its cluster.
fn assign_materials(nodes: &mut Nodes, texels: &InputTexels) {
    nodes.assign_element_materials(texels, 0);
    for n in (0..nodes.len()).rev() {
        let (first, count) = (nodes.first_child[n], nodes.child_count[n]);
        if nodes.is_cluster[n] && first != nodes::NONE {
            nodes.set_cluster_children(n, first, count);
        }
    }
    nodes.texels = (!texels.surfaces.is_untextured()).then(|| Arc::new(texels.clone()));
}

/// (Σ A·E, Σ A·E / Σ A_front) over the input triangles (mean channel; W and W/m²), the power of
/// both sides of a two-sided emitter but the area of each sheet once (its front): the threshold
/// ε·Ē is the same for a room whether its surfaces are two-sided or not (counting the backs halved
/// it and doubled the links, session 17); (1, 1) when nothing emits (then every link error is 0
/// anyway).
fn emitted_power(nodes: &Nodes, inputs: &clusters::InputTriangles) -> (f64, f64) {
    let (mut power, mut area) = (0.0f64, 0.0f64);
    for (i, &n) in inputs.node.iter().enumerate() {
        let n = n as usize;
        power += nodes.area[n] as f64 * nodes::mean_channel(nodes.emission[n].as_dvec3());
        if !inputs.back[i] {
            area += nodes.area[n] as f64;
        }
    }
    if power > 0.0 && area > 0.0 {
        (power, power / area)
    } else {
        (1.0, 1.0)
    }
}

fn solution(
    nodes: &Nodes,
    inputs: &clusters::InputTriangles,
    root: usize,
    mut stats: HierarchyStats,
) -> HierarchicalSolution {
    let mesh = interpolate::leaf_mesh(nodes, inputs, root);
    let leaves = &mesh.leaf_node;
    stats.elements = leaves.len();
    let per = |f: &dyn Fn(usize) -> Vec3| leaves.iter().map(|&n| f(n as usize)).collect::<Vec<Vec3>>();
    HierarchicalSolution {
        leaf_exitance: per(&|n| nodes.exitance[n].as_vec3()),
        leaf_emission: per(&|n| nodes.emission[n]),
        leaf_reflectance: per(&|n| nodes.reflectance[n]),
        leaf_area: leaves.iter().map(|&n| nodes.area[n as usize]).collect(),
        leaf_surface: leaves.iter().map(|&n| inputs.surface[nodes.input[n as usize] as usize]).collect(),
        leaf_back: leaves.iter().map(|&n| inputs.back[nodes.input[n as usize] as usize]).collect(),
        mesh,
        stats,
    }
}
