//! The plain scene description: camera, image and solver settings, materials and surfaces, as parsed
//! from a scene file. Nothing here builds meshes or acceleration structures (see `mesh` and `accel`).

pub mod frame;
pub mod instance;
pub mod lint;
pub mod locate;
pub mod obj;
pub mod overrides;
pub mod parse;
pub mod shapes;
pub mod validate;

use glam::{Vec2, Vec3};
use std::path::{Path, PathBuf};

pub use overrides::Overrides;
pub use parse::{load, parse_str, SceneError};
pub use validate::{check_camera, check_material};

/// Where a piece of scene data came from, for error messages and warnings (pbrt's `FileLoc`).
#[derive(Clone, Debug, PartialEq, Eq, Default)]
pub struct SourceLoc {
    pub path: PathBuf,
    /// 1-based line, 0 when unknown.
    pub line: usize,
}

impl std::fmt::Display for SourceLoc {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.line > 0 {
            write!(f, "{}:{}", self.path.display(), self.line)
        } else {
            write!(f, "{}", self.path.display())
        }
    }
}

/// A pinhole camera. `vfov_deg` is the full vertical field of view.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    pub eye: Vec3,
    pub look_at: Vec3,
    pub up: Vec3,
    pub vfov_deg: f32,
}

/// Pixel reconstruction filter of the film.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FilterKind {
    Box,
    Tent,
    Gaussian,
    Mitchell,
}

#[derive(Clone, Debug, PartialEq)]
pub struct ImageSettings {
    pub width_px: u32,
    pub height_px: u32,
    pub samples_per_pixel: u32,
    pub filter: FilterKind,
    /// Filter radius in pixels.
    pub filter_radius_px: f32,
    /// Adaptive supersampling: extra samples where a pixel's samples disagree by more than this
    /// relative contrast; `None` disables it.
    pub adaptive_threshold: Option<f32>,
    /// Adaptive supersampling: extra samples where one sample of the luminance seen in the pixel or
    /// its neighbours could change the pixel by more than this relative error
    /// (`film::one_sample_error`); `None` disables it.
    pub adaptive_error: Option<f32>,
    /// Most samples an adaptive pixel may take.
    pub adaptive_max_samples: u32,
    /// Most adaptive samples the whole image may take, as a multiple of its base samples
    /// (`film::within_budget`).
    pub adaptive_budget: f32,
    pub seed: u64,
    /// PNG exposure (`[image] exposure`: stops or "auto"); `--exposure` overrides it.
    pub exposure: crate::output::Exposure,
}

/// `adaptive_error` of the default preset (and of a scene with no preset): measured on l_room,
/// alcove_hall and cornell_box (docs/accuracy.md, "Seeds").
pub const DEFAULT_ADAPTIVE_ERROR: f32 = 0.05;

/// `adaptive_max_samples` of the default preset.
pub const DEFAULT_ADAPTIVE_MAX_SAMPLES: u32 = 256;

impl Default for ImageSettings {
    fn default() -> Self {
        ImageSettings {
            width_px: 256,
            height_px: 256,
            samples_per_pixel: 16,
            filter: FilterKind::Box,
            filter_radius_px: 0.5,
            adaptive_threshold: None,
            adaptive_error: Some(DEFAULT_ADAPTIVE_ERROR),
            adaptive_max_samples: DEFAULT_ADAPTIVE_MAX_SAMPLES,
            adaptive_budget: crate::film::DEFAULT_ADAPTIVE_BUDGET,
            seed: 0,
            exposure: crate::output::Exposure::default(),
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SolverKind {
    GaussSeidel,
    Jacobi,
    Progressive,
}

impl SolverKind {
    pub fn name(self) -> &'static str {
        match self {
            SolverKind::GaussSeidel => "gauss-seidel",
            SolverKind::Jacobi => "jacobi",
            SolverKind::Progressive => "progressive",
        }
    }
}

/// Settings of pass one.
#[derive(Clone, Debug, PartialEq)]
pub struct RadiosityParams {
    /// Surfaces are subdivided until no element edge is longer (scene units).
    pub max_element_edge: f32,
    /// Pixels across the hemicube's top face; side faces are this wide and half as high.
    pub hemicube_resolution_px: u32,
    pub solver: SolverKind,
    /// Overrelaxation factor ω of Gauss-Seidel (1 = plain Gauss-Seidel).
    pub relaxation: f64,
    /// Stop when the largest relative change (gathering) or unshot fraction (shooting) is below it.
    pub tolerance: f64,
    /// Cap on sweeps (gathering) or shots / element count (shooting).
    pub max_iterations: u32,
    /// Keep the form-factor matrix (true, the default). False, allowed only with the progressive
    /// solver, computes each shooter's row when it shoots and never stores the matrix: O(n) memory,
    /// for scenes whose matrix would not fit.
    pub store_form_factors: bool,
    /// Rotate each hemicube by a seeded random angle about its normal (against aliasing).
    pub rotate_hemicubes: bool,
    pub seed: u64,
    /// Which pass-one method solves the scene (`method`).
    pub method: MethodChoice,
    /// Settings of the hierarchical method (`memory`, `error_threshold`, `min_element_size`, …).
    pub hierarchy: HierarchySettings,
    /// Settings of the adaptive-mesh method (`adaptive_levels`, `adaptive_threshold`).
    pub adaptive: AdaptiveSettings,
}

/// The scene-level settings of `method = "adaptive"` (`radiosity::adaptive`): the uniform matrix on
/// patches of `max_element_edge`, then up to `levels` rounds that split the elements whose solution
/// varies across them by more than `threshold` of their own exitance.
#[derive(Clone, Debug, PartialEq)]
pub struct AdaptiveSettings {
    /// Rounds of subdivision after the patch solve (`adaptive_levels`); each halves an element's edges.
    pub levels: u32,
    /// Split when an element's corner exitance differs from its own by more than this fraction of its
    /// own exitance, or of a floor relative to the brightest reflected exitance (`adaptive_threshold`).
    pub threshold: f64,
    /// Whether `method = "auto"` picks the adaptive mesh for scenes the matrix can take
    /// (`auto_adaptive`); `None` when the scene does not say: then it depends on what the solution is
    /// read for (`auto_for`; `radiosity::method::auto_method_for`).
    pub auto: Option<bool>,
}

/// `adaptive_levels` of a scene without a preset and of the `default` and `high` presets (`preview`
/// keeps one level). Measured on nine rooms in radiosity mode (session 33, docs/accuracy.md): a second
/// level cost 1.6–2.3× the CPU time and lowered relMSE on eight, by 14–64% on seven (the rotunda
/// 9.25e-4 → 3.32e-4, alcove_hall 3.61e-4 → 1.45e-4, fixture_room 1.66e-3 → 7.11e-4; stair_hall
/// −3%), raising it on cornell_empty (2.47e-5 → 3.04e-5); a third level moved living_room and the
/// rotunda by 2% or less.
pub const DEFAULT_ADAPTIVE_LEVELS: u32 = 2;

impl Default for AdaptiveSettings {
    fn default() -> Self {
        AdaptiveSettings { levels: DEFAULT_ADAPTIVE_LEVELS, threshold: 0.1, auto: None }
    }
}

impl AdaptiveSettings {
    /// Whether `method = "auto"` prefers the adaptive mesh for a solution read for `reader`: the
    /// scene's `auto_adaptive` when it says, else `AUTO_PREFERS_ADAPTIVE` for final images and solution
    /// files and `AUTO_PREFERS_ADAPTIVE_FOR_RADIOSITY_IMAGES` for radiosity-mode images.
    pub fn auto_for(&self, reader: SolutionReader) -> bool {
        self.auto.unwrap_or(match reader {
            SolutionReader::FinalImages => AUTO_PREFERS_ADAPTIVE,
            SolutionReader::RadiosityImages => AUTO_PREFERS_ADAPTIVE_FOR_RADIOSITY_IMAGES,
        })
    }
}

/// What a run's pass-one solution will be read for, which `method = "auto"` weighs when the scene does
/// not set `auto_adaptive` (`AdaptiveSettings::auto_for`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SolutionReader {
    /// Final images (also `--mode both` and `--layers`), or a solution file (`radray solve`) that any
    /// later render may read: the final image reads the solution through its final gather and takes
    /// direct light per pixel, so a finer mesh buys it little.
    #[default]
    FinalImages,
    /// Only radiosity-mode images (`render --mode radiosity`, a batch job with `mode = "radiosity"`):
    /// each pixel is the interpolated solution itself, so its mesh is the image's error.
    RadiosityImages,
}

/// Whether `method = "auto"` solves scenes that stay off the hierarchy, have no mirrors or glass,
/// store their matrix and predict at most `AUTO_ADAPTIVE_CPU_SECONDS` of uniform hemicubes on the
/// adaptive mesh instead of the uniform one, for final images and solution files, when the scene does
/// not say (`auto_adaptive`). Off: since the uniform mesh extrapolates its boundary vertices too
/// (session 10), its final images are as good for less time — alcove_hall default final, seed 1, one
/// window: uniform 0.000158 in 22.9 CPU-s, adaptive 0.000167 in 30.1 (the path tracer's half-time
/// there is 22) (docs/performance.md, "Adaptive mesh made auto's choice").
pub const AUTO_PREFERS_ADAPTIVE: bool = false;

/// `AUTO_PREFERS_ADAPTIVE` for runs that draw only radiosity-mode images. On: there the adaptive mesh
/// beats a finer uniform mesh of the same CPU time by 35–50% on the rooms that are not boxes
/// (docs/performance.md, "Adaptive mesh against the uniform mesh at equal time").
pub const AUTO_PREFERS_ADAPTIVE_FOR_RADIOSITY_IMAGES: bool = true;

/// Predicted CPU seconds of the uniform matrix's hemicubes (`radiosity::matrix::cost`) above which
/// `method = "auto"` keeps the uniform matrix rather than the adaptive mesh. The adaptive method keeps
/// no checkpoint (each level needs the whole solve of the one before), so auto gives it only scenes
/// that solve in well under a minute; the matrix checkpoints its rows. The shipped diffuse scenes
/// predict 2–8 CPU-s at `default`.
pub const AUTO_ADAPTIVE_CPU_SECONDS: f64 = 20.0;

/// Which pass-one method solves the scene (`[radiosity] method`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MethodChoice {
    /// The full matrix (or matrix-free shooting with `store_form_factors = false`) when its predicted
    /// matrix fits the memory budget and its predicted hemicube CPU time is under
    /// `AUTO_MATRIX_CPU_SECONDS`; the hierarchy otherwise (`radiosity::method::auto_prefers_hierarchy`).
    /// For runs that draw only radiosity-mode images, or with `auto_adaptive = true`
    /// (`AdaptiveSettings::auto_for`), the matrix's small diffuse scenes (`AUTO_ADAPTIVE_CPU_SECONDS`)
    /// go to the adaptive mesh (`radiosity::method::auto_method_for`), except under
    /// `--shard`/`--merge` (`radiosity::method::shard_method`).
    #[default]
    Auto,
    /// The uniform mesh and the full matrix (or matrix-free shooting), whatever the scene's size.
    Matrix,
    /// Hierarchical radiosity with clustering and adaptive subdivision.
    Hierarchical,
    /// The full matrix on a mesh subdivided where its solution varies (`radiosity::adaptive`).
    Adaptive,
}

/// Predicted CPU seconds of the full matrix's hemicubes (`radiosity::matrix::cost`) above which
/// `method = "auto"` leaves it for the hierarchy (three minutes of CPU, 1.5 min on two cores). Where
/// both were measured the matrix is the more accurate, and no slower up to here: cornell_original
/// relMSE 0.000361 against the hierarchy's 0.00122 (session 9); the rotunda at `high` (19,248
/// elements, predicted 87 CPU-s) 0.00073 in 58 CPU-s against the hierarchy's 0.0030 in 86 CPU-s
/// (session 13, after the member-exact push). Was 60 CPU-s, which sent that rotunda to the hierarchy.
pub const AUTO_MATRIX_CPU_SECONDS: f64 = 180.0;

/// `AUTO_MATRIX_CPU_SECONDS` for scenes with mirrors or glass: the matrix carries the light that
/// reaches diffuse surfaces through them at every element (its extended form factors); the hierarchy
/// carries it by photons binned into its leaves and one round of light between diffuse surfaces
/// through them (session 23: within 0.0001–0.0025 relMSE of the matrix's final images on the shipped and
/// McGuire scenes with mirrors or glass), not yet measured against a reference in this range, so the
/// matrix is kept up to ten minutes of CPU time.
pub const AUTO_MATRIX_CPU_SECONDS_SPECULAR: f64 = 600.0;

/// The scene-level settings of the hierarchical method. The solver's own parameter struct is built
/// from these by the method (`radiosity::hierarchical::hierarchy_params`): the preset's parameters
/// (`HierarchyParams::preview()`, `default()`, `final_quality()`), then the keys the scene sets.
#[derive(Clone, Debug, PartialEq)]
pub struct HierarchySettings {
    /// Memory budget of pass one in bytes (`memory = "8GB"`); also the budget `auto` holds the full
    /// matrix to. The hierarchy's nodes and links get three quarters of it.
    pub memory_bytes: u64,
    /// The preset the hierarchy's parameters start from (`quality`; `Default` without one).
    pub preset: Quality,
    /// ε (`error_threshold`), or the preset's.
    pub error_threshold: Option<f64>,
    /// Elements are not subdivided below this edge length (scene units); `None`: diagonal / 200.
    pub min_element_size: Option<f32>,
    /// Rays per link for visibility, or the preset's.
    pub visibility_rays: Option<u32>,
    /// Refine-and-solve passes, or the preset's.
    pub refinement_passes: Option<u32>,
    /// δ (`dark_receiver_floor`): from the second pass on, a receiver darker than the mean emitted
    /// exitance is held to an error relative to its own exitance, down to δ·ε; `None`: the preset's
    /// (1, off).
    pub dark_receiver_floor: Option<f64>,
    /// Cosine rays per leaf for the hierarchy's ray correction of the indirect light (0: off);
    /// `None`: the preset's.
    pub correction_rays: Option<u32>,
    /// How the correction measures the leaves' indirect light; `None`: rays.
    pub correction: Option<CorrectionEstimator>,
    /// What measures the form factors of element receivers' far links; `None`: the formulas.
    pub link_form_factors: Option<LinkFormFactors>,
}

/// What measures the form factors of the hierarchy's links (`[radiosity] link_form_factors`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LinkFormFactors {
    /// Every link by its type's estimator (`radiosity::hierarchy::links::estimate`; the default).
    #[default]
    Formulas,
    /// The far links of element receivers by a hemicube at the receiver that draws the tree as a
    /// cut (`radiosity::hierarchy::hemicube_links`); the other links by their estimators.
    Hemicube,
}

/// How the hierarchy's correction measures the indirect light its links bring (`[radiosity]
/// correction`, `radiosity::hierarchy::ray_correction`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum CorrectionEstimator {
    /// `correction_rays` cosine rays from every leaf (the default).
    #[default]
    Rays,
    /// A hemicube at some leaves that draws the cluster hierarchy as a cut
    /// (`radiosity::hierarchy::hemicube_cut`).
    Hemicube,
}

/// 8 GB, the budget for pass one.
pub const DEFAULT_MEMORY_BYTES: u64 = 8_000_000_000;

impl Default for HierarchySettings {
    fn default() -> Self {
        HierarchySettings {
            memory_bytes: DEFAULT_MEMORY_BYTES,
            preset: Quality::Default,
            error_threshold: None,
            min_element_size: None,
            visibility_rays: None,
            refinement_passes: None,
            dark_receiver_floor: None,
            correction_rays: None,
            correction: None,
            link_form_factors: None,
        }
    }
}

/// Parses a memory size: a whole number of bytes, or a number with a unit: `KB`, `MB`, `GB`, `TB`
/// (powers of 1000), `KiB`, `MiB`, `GiB`, `TiB` (powers of 1024); `K`, `M`, `G`, `T` alone mean the
/// decimal ones. Case and a space before the unit do not matter. `None` if it is not such a size or
/// is zero.
pub fn parse_memory_size(text: &str) -> Option<u64> {
    let t = text.trim();
    let split = t.find(|c: char| !(c.is_ascii_digit() || c == '.')).unwrap_or(t.len());
    let (number, unit) = t.split_at(split);
    let number: f64 = number.parse().ok()?;
    let scale: f64 = match unit.trim().to_ascii_lowercase().as_str() {
        "" | "b" => 1.0,
        "k" | "kb" => 1e3,
        "m" | "mb" => 1e6,
        "g" | "gb" => 1e9,
        "t" | "tb" => 1e12,
        "kib" => 1024.0,
        "mib" => 1024f64.powi(2),
        "gib" => 1024f64.powi(3),
        "tib" => 1024f64.powi(4),
        _ => return None,
    };
    let bytes = number * scale;
    (1.0..1.8e19).contains(&bytes).then_some(bytes as u64)
}

impl Default for RadiosityParams {
    fn default() -> Self {
        RadiosityParams {
            max_element_edge: f32::INFINITY,
            hemicube_resolution_px: 128,
            solver: SolverKind::GaussSeidel,
            relaxation: 1.2,
            tolerance: 1e-4,
            max_iterations: 1000,
            store_form_factors: true,
            rotate_hemicubes: true,
            seed: 0,
            method: MethodChoice::Auto,
            hierarchy: HierarchySettings::default(),
            adaptive: AdaptiveSettings::default(),
        }
    }
}

/// How pass two obtains direct light at diffuse hits.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum DirectMode {
    /// The radiosity solution's diffuse term holds direct light (meshed shadows).
    Radiosity,
    /// Direct light sampled per pixel with shadow rays; only the indirect radiosity is added.
    Pixel,
}

/// Whether pass two gathers the indirect light at the diffuse points it shows (`trace::gather`), or
/// reads it from the interpolated solution.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FinalGatherMode {
    /// The indirect light is the solution's, Gouraud-interpolated over the elements.
    Off,
    /// A final gather over the solution at every diffuse point, through the irradiance cache.
    On,
}

/// Settings of pass two.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderParams {
    pub direct: DirectMode,
    /// Final gather of the indirect light in the final image.
    pub final_gather: FinalGatherMode,
    /// Rays per gather (stratified over the cosine-weighted hemisphere); on a hierarchical solution
    /// `RenderParams::gather_rays_for` takes fewer unless `gather_rays_set`.
    pub gather_rays: u32,
    /// The scene sets `gather_rays` itself: every solution gathers with it.
    pub gather_rays_set: bool,
    /// The irradiance cache's accuracy a (Ward's largest error weight); 0 gathers at every diffuse hit
    /// with no cache.
    pub cache_accuracy: f32,
    /// The gather's second bounce: a gather ray's hit closer than this many of the hit element's
    /// sizes (√area) has its exitance estimated at the point (`trace::gather::near`) instead of
    /// interpolated; 0 turns it off, infinity applies it everywhere. `None` (the scene leaves
    /// `near_bounce` unset): by the solution pass two reads (`RenderParams::near_bounce_for`).
    pub near_bounce: Option<f32>,
    /// Rays of the secondary gather at a near hit; `None`: by the solution, as `near_bounce`.
    pub near_bounce_rays: Option<u32>,
    /// A cache record whose pilot gather predicts a relative standard error above this gathers
    /// `REFINE_FACTOR` × `gather_rays` (`trace::gather::refine`); 0 keeps every record at `gather_rays`.
    pub gather_refine_error: f32,
    /// Shadow rays per diffuse hit when `direct = Pixel` (and per Phong highlight), shared by all
    /// emitters: each ray goes to a point chosen over the emitters' total area, not one per emitter.
    pub light_samples: u32,
    pub max_depth: u32,
    /// Paths whose throughput falls below this (max channel) are dropped.
    pub min_throughput: f32,
}

/// `near_bounce` by default, in hit-element sizes (√area). Was 1: on gap_room (a room lit through a
/// door gap, default preset, 256²) the gather then read interpolated exitance of elements that
/// straddle the direct light's sharp edges through the gap 0.3–0.6 m away, and the floor beside the
/// door jamb came out 5% too bright, the wall beside the back corner 2%; 2.5 re-estimates those hits
/// at the point (docs/accuracy.md, "gap_room against a converged reference").
pub const DEFAULT_NEAR_BOUNCE: f32 = 2.5;

/// `near_bounce` by default on a hierarchical solution: every gather ray's hit gets the second
/// bounce. The hierarchy's indirect light is short on large interiors (its links cover less of a
/// leaf's hemisphere than rays do: Sponza's row sums 0.57 against 0.87, docs/accuracy.md sessions
/// 24–30), and a gather that reads it at the first bounce carries that deficit into the final image;
/// re-estimated at every hit it enters one bounce later, damped by ρ. Sponza (untextured capped
/// copy, 320×180, one solution, `HIERARCHY_NEAR_BOUNCE_RAYS`, `HIERARCHY_SHADOW_FACTOR`): final
/// relMSE 0.0154 → 0.0109, median pixel ratio to the reference 0.872 → 0.940, pass two 160 → 295
/// CPU-s; vault_hall (40k triangles) 0.000422 → 0.000321, pass two 14.8 → 23.4 CPU-s
/// (docs/accuracy.md, session 31). The uniform and
/// adaptive meshes keep `DEFAULT_NEAR_BOUNCE`: their solutions carry no such bias, only their
/// elements' corner bias, and every hit there cost 2.7–3.5× the time for no gain (session 5).
pub const HIERARCHY_NEAR_BOUNCE: f32 = f32::INFINITY;

/// Over a hierarchical solution, by default, re-estimated gather hits closer than this many element
/// sizes take their direct light from a shadow ray (session 5's near rule); the others read the
/// solution's direct part, which the hierarchy gets right (its deficit is in the indirect light).
/// Sponza's final image, one solution: shadow rays at every hit 0.0110 in 347 CPU-s of pass two,
/// within 2.5 sizes 0.0109 in 295, none 0.0111 in 271 (docs/accuracy.md, session 31).
pub const HIERARCHY_SHADOW_FACTOR: f32 = DEFAULT_NEAR_BOUNCE;

/// The share of the preset's `gather_rays` a hierarchical solution gathers with when the scene sets
/// neither `gather_rays` nor `near_bounce` (`RenderParams::gather_rays_for`): there every hit of a
/// gather ray is re-estimated by a secondary ray (`HIERARCHY_NEAR_BOUNCE`), and fewer primary rays
/// lose little. Session 44 (docs/accuracy.md), final images against the references, one thread:
/// untextured Crytek Sponza at 320×180 from one solution, 1,024 rays 0.01011 in 535 CPU-s of pass
/// two, 768 0.01013 in 385, 512 0.01018 in 295; vault_hall (256², seed 0) 1,024 2.346e-4 (seed 1:
/// 2.277e-4), 768 2.183e-4, 512 2.472e-4. Three quarters: issue 10's textured Sponza at 640×360, whole
/// process, took 1,040 s wall against its 900 with 1,024 (pass two 856 s of it).
pub const HIERARCHY_GATHER_SHARE: (u32, u32) = (3, 4);

/// `near_bounce_rays` by default on the uniform and adaptive meshes.
pub const DEFAULT_NEAR_BOUNCE_RAYS: u32 = 2;

/// `near_bounce_rays` by default on a hierarchical solution: one. Every hit of a gather bounces, so
/// its 1,024 cells average the secondary estimates: Sponza's final image 0.0110 with one ray against
/// 0.0111 with two (shadow rays at every hit), pass two 347 against 487 CPU-s (docs/accuracy.md,
/// session 31).
pub const HIERARCHY_NEAR_BOUNCE_RAYS: u32 = 1;

/// `gather_refine_error` by default. On gap_room (default preset, 256², seeds 1–4, relMSE against
/// the converged image) off gives mean 0.00056 (0.00061 at worst); 0.04 refines 30% of the records
/// and gives 0.00044 / 0.00044 / 0.00041 / 0.00038 for +16% rays; 0.03 the same mean for +20%, 0.06
/// misses 0.0005 on seed 2 (docs/accuracy.md, "The pilot on its own stream").
pub const DEFAULT_GATHER_REFINE_ERROR: f32 = 0.04;

/// `cache_accuracy` of the default preset (and of a scene with no preset). Measured on alcove_hall at
/// the default preset, 256², in one run (docs/accuracy.md, "A cheaper default preset"): 0.25 gives
/// relMSE 0.00020–0.00022 in 17.4–18.2 CPU-s with seeds differing by 0.00011; 0.15 gave 0.00012–0.00013
/// in 28.0–29.3 CPU-s (seeds 0.00011); 512 gather rays instead would cost as little but double the
/// seed difference's cache part (0.00014). Measured again in session 35 with the records' radii
/// limited by the nearest surface (`trace::gather::cache::near_radius`), final images of nine rooms:
/// 0.35 is 9–45% worse for 3–15% less CPU, 0.2 is 2–13% better for 5–12% more.
pub const DEFAULT_CACHE_ACCURACY: f32 = 0.25;

/// Shadow rays per diffuse hit by default (`[render] light_samples` and the default preset). Was 4:
/// on alcove_hall (default preset, 256², one shared solution) two film seeds then differed by relMSE
/// 1.05e-4, 70% of it in the direct-light layer; 8 rays make it 6.5e-5 (direct 3.0e-5: the pixel's
/// stratified pattern of spp·N points gains more than 1/N) for +6% CPU-s of the whole render.
pub const DEFAULT_LIGHT_SAMPLES: u32 = 8;

/// The gather's second bounce a render uses (`RenderParams::near_bounce_for`, `trace::gather::near`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GatherBounce {
    /// Hits closer than this many element sizes (√area) are re-estimated at the point; 0: none.
    pub distance_factor: f32,
    /// Of those, hits closer than this many element sizes take their direct light from a shadow ray,
    /// the others the solution's direct part.
    pub shadow_factor: f32,
    /// Rays of the secondary gather at a re-estimated hit.
    pub rays: u32,
}

impl RenderParams {
    /// Rays per gather for a solution that is hierarchical or not: `gather_rays`, or on a
    /// hierarchical solution whose gathers bounce at every hit (the scene sets neither `gather_rays`
    /// nor `near_bounce`) `HIERARCHY_GATHER_SHARE` of it, at least 16.
    pub fn gather_rays_for(&self, hierarchical_solution: bool) -> u32 {
        if hierarchical_solution && !self.gather_rays_set && self.near_bounce.is_none() {
            let (part, whole) = HIERARCHY_GATHER_SHARE;
            (self.gather_rays * part / whole).max(16)
        } else {
            self.gather_rays
        }
    }

    /// The gather's second bounce for a solution that is hierarchical or not: the scene's
    /// `near_bounce` and `near_bounce_rays` where it sets them (every re-estimated hit then takes a
    /// shadow ray, as before session 31); else on a hierarchical solution every hit
    /// (`HIERARCHY_NEAR_BOUNCE`) with `HIERARCHY_NEAR_BOUNCE_RAYS`, shadow rays within
    /// `DEFAULT_NEAR_BOUNCE`; on the uniform and adaptive meshes `DEFAULT_NEAR_BOUNCE` with
    /// `DEFAULT_NEAR_BOUNCE_RAYS`.
    pub fn near_bounce_for(&self, hierarchical_solution: bool) -> GatherBounce {
        let (factor, rays) = if hierarchical_solution {
            (HIERARCHY_NEAR_BOUNCE, HIERARCHY_NEAR_BOUNCE_RAYS)
        } else {
            (DEFAULT_NEAR_BOUNCE, DEFAULT_NEAR_BOUNCE_RAYS)
        };
        let distance_factor = self.near_bounce.unwrap_or(factor);
        let shadow_factor = match (self.near_bounce, hierarchical_solution) {
            (Some(_), _) => distance_factor,
            (None, true) => HIERARCHY_SHADOW_FACTOR,
            (None, false) => DEFAULT_NEAR_BOUNCE,
        };
        GatherBounce {
            distance_factor,
            shadow_factor: shadow_factor.min(distance_factor),
            rays: self.near_bounce_rays.unwrap_or(rays),
        }
    }
}

impl Default for RenderParams {
    fn default() -> Self {
        RenderParams {
            direct: DirectMode::Pixel,
            final_gather: FinalGatherMode::On,
            gather_rays: 1024,
            gather_rays_set: false,
            cache_accuracy: DEFAULT_CACHE_ACCURACY,
            near_bounce: None,
            near_bounce_rays: None,
            gather_refine_error: DEFAULT_GATHER_REFINE_ERROR,
            light_samples: DEFAULT_LIGHT_SAMPLES,
            max_depth: 8,
            min_throughput: 1e-3,
        }
    }
}

/// A surface material, in the MTL meanings radray uses. How each MTL statement (including `illum`,
/// `Tr` and `Tf`) lands in these fields is documented in `material::mtl` and the README's table.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    /// `Kd`: Lambertian reflectance per channel, in [0, 1): already clamped to
    /// `material::ALBEDO_CEILING`. With a `map_Kd` texture this is the fallback used when the
    /// texture cannot be read; the texture itself is multiplied by `textures.diffuse.factor`.
    pub diffuse_reflectance: Vec3,
    /// `Ke`: emitted radiance (W·sr⁻¹·m⁻², or the scene's units), from the front side only.
    pub emitted_radiance: Vec3,
    /// `Ks`: mirror reflectance (for a dielectric, a tint on its Fresnel reflection).
    pub specular_reflectance: Vec3,
    /// `Ns`: Phong exponent of a highlight from each emitter; `None` for no highlight.
    pub phong_exponent: Option<f32>,
    /// `Ni`: index of refraction (used when transmittance > 0).
    pub ior: f32,
    /// Transmittance of a smooth dielectric (`1 − d`, `Tr`, or a transparent `illum` model); 0 for
    /// opaque.
    pub transmittance: f32,
    /// Colour that multiplies the light a dielectric transmits, per channel, with its largest channel
    /// 1 (white = clear); the overall amount is `transmittance`. From `Tf` (see `material::mtl`).
    pub transmission_filter: Vec3,
    /// The MTL `illum` model as written, `None` when absent (or for a TOML material). Its meaning is
    /// already folded into the fields above; kept for reports.
    pub illum: Option<u8>,
    /// Texture maps (`map_Kd`, `map_d`, `map_Ke`); empty for TOML materials.
    pub textures: MaterialTextures,
}

/// One texture map statement of a material: the file (resolved against the MTL's folder, not yet
/// read) and the constant it is multiplied by.
#[derive(Clone, Debug, PartialEq)]
pub struct TextureMap {
    pub path: PathBuf,
    /// `Kd` for `map_Kd`, `Ke` (or 1 when `Ke` is absent or black) for `map_Ke`, 1 for `map_d`.
    pub factor: Vec3,
    /// The MTL statement that named it.
    pub source: SourceLoc,
}

/// The texture maps of a material. Loading and filtering them is `material::texture`'s job.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct MaterialTextures {
    /// `map_Kd`: diffuse albedo (sRGB-encoded colour); its alpha channel, if any, cuts out the surface
    /// when there is no `map_d`.
    pub diffuse: Option<TextureMap>,
    /// `map_d`: opacity (linear; the file's alpha channel if it has one, else its first channel).
    pub opacity: Option<TextureMap>,
    /// `map_Ke`: emitted radiance (sRGB-encoded colour).
    pub emission: Option<TextureMap>,
}

impl MaterialTextures {
    pub fn is_empty(&self) -> bool {
        self.diffuse.is_none() && self.opacity.is_none() && self.emission.is_none()
    }
}

impl Material {
    pub fn diffuse(name: &str, reflectance: Vec3) -> Self {
        Material {
            name: name.to_string(),
            diffuse_reflectance: reflectance,
            emitted_radiance: Vec3::ZERO,
            specular_reflectance: Vec3::ZERO,
            phong_exponent: None,
            ior: 1.0,
            transmittance: 0.0,
            transmission_filter: Vec3::ONE,
            illum: None,
            textures: MaterialTextures::default(),
        }
    }

    /// Emitted exitance E = π·Ke of a Lambertian emitter.
    pub fn emitted_exitance(&self) -> Vec3 {
        self.emitted_radiance * std::f32::consts::PI
    }

    /// Emits light: Ke > 0, or an emission texture (`map_Ke`, which multiplies Ke or 1).
    pub fn is_emitter(&self) -> bool {
        self.emitted_radiance.max_element() > 0.0 || self.textures.emission.is_some()
    }

    pub fn is_dielectric(&self) -> bool {
        self.transmittance > 0.0
    }

    pub fn is_specular(&self) -> bool {
        self.specular_reflectance.max_element() > 0.0 || self.is_dielectric()
    }
}

/// One planar convex polygon of the scene (a triangle or a quad), counter-clockwise seen from its
/// front.
#[derive(Clone, Debug, PartialEq)]
pub struct Surface {
    pub vertices: Vec<Vec3>,
    pub material: u32,
    /// Reflects and emits on both sides.
    pub two_sided: bool,
    /// Smooth-shading normals at the vertices (from the OBJ), for the specular term only.
    pub shading_normals: Option<Vec<Vec3>>,
    /// Texture coordinates at the vertices (OBJ `vt`), when the face has them; inline primitives
    /// have none.
    pub uvs: Option<Vec<Vec2>>,
    /// Name of the object or primitive the surface belongs to.
    pub object: String,
    pub source: SourceLoc,
}

/// A parsed scene: plain data, with the file it came from.
#[derive(Clone, Debug)]
pub struct SceneDescription {
    pub path: PathBuf,
    pub camera: Camera,
    pub image: ImageSettings,
    pub radiosity: RadiosityParams,
    pub render: RenderParams,
    pub materials: Vec<Material>,
    pub surfaces: Vec<Surface>,
    /// Non-fatal findings (degenerate faces skipped, no emitter, ...).
    pub warnings: Vec<String>,
}

impl SceneDescription {
    pub fn directory(&self) -> &Path {
        self.path.parent().unwrap_or(Path::new("."))
    }

    pub fn has_emitter(&self) -> bool {
        self.surfaces.iter().any(|s| self.materials[s.material as usize].is_emitter())
    }
}

/// Named presets that fix element size, hemicube resolution, samples per pixel and light samples
/// together. Element size is relative to the scene's bounding-box diagonal, so a preset means the
/// same on a scene in millimetres and one in metres.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Quality {
    /// Diagonal / 20 elements, 64² hemicubes, 4 spp, 1 light sample: seconds, blotchy shadows.
    Preview,
    /// Diagonal / 40, 128², 16 spp, 8 light samples, 1024 gather rays, cache accuracy 0.25.
    Default,
    /// Diagonal / 55 (about 6.5k elements in the Cornell box), 128², 32 spp, 8 light samples, adaptive
    /// to 512 at error 0.035, 1024 gather rays, cache accuracy 0.18: a step of about 3× default's
    /// time. (It was diagonal / 70, 256², 64 spp, 16 light samples, adaptive to 1024 at 0.025, 2048
    /// rays at 0.1: 17× default's time, 417.5 CPU-s on the Cornell box, where pass one took 65 CPU-s
    /// and every pass-two setting grew its cost 4–16×.)
    High,
}

impl Quality {
    /// (diagonal divisor, hemicube resolution, samples per pixel, light samples)
    pub fn settings(self) -> (f32, u32, u32, u32) {
        match self {
            Quality::Preview => (20.0, 64, 4, 1),
            Quality::Default => (40.0, 128, 16, DEFAULT_LIGHT_SAMPLES),
            Quality::High => (55.0, 128, 32, 8),
        }
    }

    /// (adaptive error bound, most samples per adaptive pixel): `[image] adaptive_error` and
    /// `adaptive_max_samples`. Preview leaves adaptive sampling off.
    pub fn adaptive_settings(self) -> (Option<f32>, u32) {
        match self {
            Quality::Preview => (None, 64),
            Quality::Default => (Some(DEFAULT_ADAPTIVE_ERROR), DEFAULT_ADAPTIVE_MAX_SAMPLES),
            Quality::High => (Some(0.7 * DEFAULT_ADAPTIVE_ERROR), 2 * DEFAULT_ADAPTIVE_MAX_SAMPLES),
        }
    }

    /// `adaptive_levels`: rounds of adaptive-mesh subdivision after the patch solve.
    pub fn adaptive_mesh_levels(self) -> u32 {
        match self {
            Quality::Preview => 1,
            Quality::Default | Quality::High => DEFAULT_ADAPTIVE_LEVELS,
        }
    }

    /// (final gather, gather rays, cache accuracy)
    pub fn gather_settings(self) -> (FinalGatherMode, u32, f32) {
        match self {
            Quality::Preview => (FinalGatherMode::Off, 64, 0.3),
            Quality::Default => (FinalGatherMode::On, 1024, DEFAULT_CACHE_ACCURACY),
            Quality::High => (FinalGatherMode::On, 1024, 0.18),
        }
    }
}

impl SceneDescription {
    /// Length of the diagonal of the scene's bounding box along its principal frame (`frame`): the
    /// scene's size, the same however the scene is turned (the world axes' box for a scene built
    /// along them).
    pub fn diagonal(&self) -> f32 {
        let frame = self.frame();
        let (lo, hi) = self.surfaces.iter().flat_map(|s| s.vertices.iter()).fold(
            (Vec3::INFINITY, Vec3::NEG_INFINITY),
            |(lo, hi), &v| {
                let q = frame.to_frame(v);
                (lo.min(q), hi.max(q))
            },
        );
        (hi - lo).length()
    }

    /// The axes the scene's large planes line up with (`frame::principal` over its surfaces, each
    /// with its Newell normal and area).
    pub fn frame(&self) -> frame::Frame {
        frame::of_polygons(self.surfaces.iter().map(|s| s.vertices.as_slice()))
    }

    /// Sets element size, hemicube resolution, samples, light samples and the final gather from a preset.
    pub fn apply_quality(&mut self, quality: Quality) {
        let (divisor, resolution, spp, light_samples) = quality.settings();
        self.radiosity.max_element_edge = self.diagonal() / divisor;
        self.radiosity.hemicube_resolution_px = resolution;
        self.image.samples_per_pixel = spp;
        let (adaptive_error, adaptive_max_samples) = quality.adaptive_settings();
        self.image.adaptive_error = adaptive_error;
        self.image.adaptive_max_samples = adaptive_max_samples.max(spp);
        self.render.light_samples = light_samples;
        self.radiosity.hierarchy.preset = quality;
        self.radiosity.adaptive.levels = quality.adaptive_mesh_levels();
        let (final_gather, gather_rays, cache_accuracy) = quality.gather_settings();
        self.render.final_gather = final_gather;
        self.render.gather_rays = gather_rays;
        self.render.gather_rays_set = false;
        self.render.cache_accuracy = cache_accuracy;
    }
}
