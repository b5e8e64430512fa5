//! The command line: subcommands and their flags (clap), validated into the stages' settings, and the
//! runners that turn a command into files and an exit code.

use clap::{Args, Parser, Subcommand, ValueEnum};
use std::path::PathBuf;

const EXAMPLES: &str = "\
Examples:
  radray render scenes/cornell_box.toml -o cornell.png -o cornell.exr
  radray render scenes/cornell_specular.toml -o spec.png --mode both --direct pixel --spp 64
  radray solve scenes/cornell_box.toml -o cornell.radsol
  radray render scenes/cornell_box.toml --solution cornell.radsol -o view.exr --width 512 --height 512
  radray compare out.exr references/cornell_original/reference.exr --diff diff.png --json
  radray batch jobs.toml --manifest jobs.manifest.json --shard 0/4
  radray info scenes/cornell_box.toml

Exit codes: 0 success, 2 bad input or usage, 1 internal error.";

#[derive(Parser, Debug)]
#[command(name = "radray", version, about = "Two-pass renderer: hemicube radiosity, then Whitted ray tracing", after_help = EXAMPLES)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
    /// Print nothing but errors.
    #[arg(short, long, global = true)]
    pub quiet: bool,
    /// Print a one-line summary of every stage.
    #[arg(short, long, global = true, conflicts_with = "quiet")]
    pub verbose: bool,
    /// Worker threads (default: all cores).
    #[arg(long, global = true, value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub threads: Option<u32>,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Render a scene to PNG and/or EXR (solving its radiosity first unless --solution is given).
    #[command(
        after_help = "Example:\n  radray render scenes/cornell_box.toml -o cornell.png -o cornell.exr --mode both"
    )]
    Render(RenderArgs),
    /// Solve a scene's radiosity (pass one) and save the solution for later renders.
    #[command(after_help = "Example:\n  radray solve scenes/cornell_box.toml -o cornell.radsol --stats solve.json")]
    Solve(SolveArgs),
    /// Compare two images (EXR, or PNG read as sRGB): RMSE, relative MSE, mean relative error.
    #[command(
        after_help = "Example:\n  radray compare test.exr reference.exr --diff diff.png --side-by-side pair.png --json"
    )]
    Compare(CompareArgs),
    /// Run a batch of render jobs from a TOML file, writing a JSON manifest.
    #[command(after_help = "Example:\n  radray batch jobs.toml --shard $SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT")]
    Batch(BatchArgs),
    /// Describe a scene before solving it: surfaces, elements, emitters, cost, suspicious geometry.
    #[command(after_help = "Example:\n  radray info scenes/cornell_box.toml")]
    Info(InfoArgs),
}

/// What pass two draws.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Mode {
    /// The two-pass image: radiosity diffuse term plus Whitted specular transport.
    Final,
    /// The pure radiosity output: first hit's interpolated radiosity / π.
    Radiosity,
    /// Both, as NAME.final.EXT and NAME.radiosity.EXT.
    Both,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum DirectArg {
    Radiosity,
    Pixel,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum QualityArg {
    Preview,
    Default,
    High,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ToneArg {
    Clamp,
    Reinhard,
    Aces,
}

/// Settings that the command line (or a batch job) lays over the scene file's.
#[derive(Args, Debug, Clone, Default, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Overrides {
    /// Image width in pixels.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=16384))]
    pub width: Option<u32>,
    /// Image height in pixels.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=16384))]
    pub height: Option<u32>,
    /// Samples per pixel.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub spp: Option<u32>,
    /// Seed of the film's and the hemicubes' random numbers.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Direct light from the radiosity mesh, or sampled per pixel with shadow rays.
    #[arg(long, value_enum)]
    pub direct: Option<DirectArg>,
    /// A named preset of element size, hemicube resolution, samples and light samples.
    #[arg(long, value_enum)]
    pub quality: Option<QualityArg>,
    /// PNG exposure in stops (radiance × 2^stops before encoding).
    #[arg(long, allow_negative_numbers = true)]
    pub exposure: Option<f32>,
    /// PNG tone curve applied after the exposure.
    #[arg(long, value_enum)]
    pub tone: Option<ToneArg>,
}

#[derive(Args, Debug)]
pub struct RenderArgs {
    /// Scene file (TOML).
    pub scene: PathBuf,
    /// Output image(s): .png (8-bit sRGB) and/or .exr (linear radiance). Repeat for several.
    #[arg(short, long, required = true)]
    pub output: Vec<PathBuf>,
    #[arg(long, value_enum, default_value_t = Mode::Final)]
    pub mode: Mode,
    /// Load this solution (from `radray solve`) instead of solving again.
    #[arg(long)]
    pub solution: Option<PathBuf>,
    /// Write what the run measured as JSON.
    #[arg(long)]
    pub stats: Option<PathBuf>,
    #[command(flatten)]
    pub overrides: Overrides,
}

#[derive(Args, Debug)]
pub struct SolveArgs {
    /// Scene file (TOML).
    pub scene: PathBuf,
    /// Solution file to write.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Write what the run measured as JSON.
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// Seed of the hemicube rotations.
    #[arg(long)]
    pub seed: Option<u64>,
    #[arg(long, value_enum)]
    pub quality: Option<QualityArg>,
}

#[derive(Args, Debug)]
pub struct CompareArgs {
    /// Test image.
    pub a: PathBuf,
    /// Reference image.
    pub b: PathBuf,
    /// Write a false-colour difference image (PNG).
    #[arg(long)]
    pub diff: Option<PathBuf>,
    /// Write A, B and the difference side by side (PNG).
    #[arg(long)]
    pub side_by_side: Option<PathBuf>,
    /// Print the metrics as JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args, Debug)]
pub struct BatchArgs {
    /// Jobs file (TOML with [[job]] entries).
    pub jobs: PathBuf,
    /// Manifest to write (default: <jobs>.manifest.json beside the jobs file).
    #[arg(long)]
    pub manifest: Option<PathBuf>,
    /// Run every N-th job starting at K (0-based): K/N.
    #[arg(long)]
    pub shard: Option<String>,
}

#[derive(Args, Debug)]
pub struct InfoArgs {
    /// Scene file (TOML).
    pub scene: PathBuf,
    #[arg(long, value_enum)]
    pub quality: Option<QualityArg>,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
}

// ---------------------------------------------------------------------------------------------------
// Runners

use crate::accel::Accel;
use crate::compare;
use crate::output::{self, ToneCurve};
use crate::pipeline::{self, RunStats};
use crate::progress::{Progress, Verbosity};
use crate::radiosity::{solution, Solution};
use crate::scene::{self, DirectMode, Quality, SceneDescription};
use crate::trace::whitted::TraceMode;
use anyhow::Context;
use std::path::Path;

/// A failed run: the error chain to print and the exit code (2: bad input or usage, 1: internal).
#[derive(Debug)]
pub struct Failure {
    pub exit_code: i32,
    pub error: anyhow::Error,
}

impl Failure {
    pub fn input(error: impl Into<anyhow::Error>) -> Self {
        Failure { exit_code: 2, error: error.into() }
    }

    pub fn internal(error: impl Into<anyhow::Error>) -> Self {
        Failure { exit_code: 1, error: error.into() }
    }
}

impl std::fmt::Display for Failure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:#}", self.error)
    }
}

impl From<QualityArg> for Quality {
    fn from(q: QualityArg) -> Self {
        match q {
            QualityArg::Preview => Quality::Preview,
            QualityArg::Default => Quality::Default,
            QualityArg::High => Quality::High,
        }
    }
}

impl From<ToneArg> for ToneCurve {
    fn from(t: ToneArg) -> Self {
        match t {
            ToneArg::Clamp => ToneCurve::Clamp,
            ToneArg::Reinhard => ToneCurve::Reinhard,
            ToneArg::Aces => ToneCurve::Aces,
        }
    }
}

/// Runs a parsed command line.
pub fn run(cli: Cli) -> Result<(), Failure> {
    let verbosity = if cli.quiet {
        Verbosity::Quiet
    } else if cli.verbose {
        Verbosity::Verbose
    } else {
        Verbosity::Normal
    };
    let progress = Progress::new(verbosity);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(cli.threads.unwrap_or(0) as usize)
        .build()
        .map_err(|e| Failure::internal(anyhow::anyhow!("cannot start worker threads: {e}")))?;
    pool.install(|| match cli.command {
        Command::Render(args) => render_command(&args, &progress),
        Command::Solve(args) => solve_command(&args, &progress),
        Command::Compare(args) => compare_command(&args),
        Command::Batch(args) => crate::batch::run(&args, &progress),
        Command::Info(args) => info_command(&args),
    })
}

/// Loads a scene, prints its warnings, and lays the overrides over it.
pub fn load_scene(path: &Path, overrides: &Overrides, progress: &Progress) -> Result<SceneDescription, Failure> {
    let mut scene = scene::load(path).map_err(Failure::input)?;
    for w in &scene.warnings {
        progress.note(&format!("warning: {w}"));
    }
    apply_overrides(&mut scene, overrides);
    Ok(scene)
}

/// Lays command-line (or batch job) settings over a scene's: the preset first, then single values.
pub fn apply_overrides(scene: &mut SceneDescription, o: &Overrides) {
    if let Some(q) = o.quality {
        scene.apply_quality(q.into());
    }
    if let Some(w) = o.width {
        scene.image.width_px = w;
    }
    if let Some(h) = o.height {
        scene.image.height_px = h;
    }
    if let Some(spp) = o.spp {
        scene.image.samples_per_pixel = spp;
        scene.image.adaptive_max_samples = scene.image.adaptive_max_samples.max(spp);
    }
    if let Some(seed) = o.seed {
        scene.image.seed = seed;
        scene.radiosity.seed = seed;
    }
    if let Some(d) = o.direct {
        scene.render.direct = match d {
            DirectArg::Radiosity => DirectMode::Radiosity,
            DirectArg::Pixel => DirectMode::Pixel,
        };
    }
}

/// The files a render writes: `-o` as given, or NAME.final.EXT and NAME.radiosity.EXT for `both`.
pub fn output_plan(outputs: &[PathBuf], mode: Mode) -> Result<Vec<(TraceMode, PathBuf)>, Failure> {
    let mut plan = Vec::new();
    for out in outputs {
        let ext = out.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).unwrap_or_default();
        if ext != "png" && ext != "exr" {
            return Err(Failure::input(anyhow::anyhow!("{}: output must end in .png or .exr", out.display())));
        }
        let dir = out.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
        if !dir.is_dir() {
            return Err(Failure::input(anyhow::anyhow!(
                "{}: directory {} does not exist",
                out.display(),
                dir.display()
            )));
        }
        let tagged = |tag: &str| {
            let stem = out.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
            out.with_file_name(format!("{stem}.{tag}.{ext}"))
        };
        match mode {
            Mode::Final => plan.push((TraceMode::Final, out.clone())),
            Mode::Radiosity => plan.push((TraceMode::Radiosity, out.clone())),
            Mode::Both => {
                plan.push((TraceMode::Final, tagged("final")));
                plan.push((TraceMode::Radiosity, tagged("radiosity")));
            }
        }
    }
    Ok(plan)
}

/// Pass one for a scene: mesh, form factors and solution (or a loaded solution).
pub fn pass_one(
    scene: &SceneDescription,
    solution_file: Option<&Path>,
    photons: &pipeline::RunPhotons,
    progress: &Progress,
    stats: &mut RunStats,
) -> Result<(crate::mesh::Mesh, Solution), Failure> {
    let mesh = pipeline::build_mesh(scene, progress).map_err(Failure::input)?;
    stats.elements = mesh.elements.len();
    if let Some(path) = solution_file {
        let solution = Solution::load(path, solution::fingerprint(&mesh, &scene.materials)).map_err(Failure::input)?;
        return Ok((mesh, solution));
    }
    if !scene.has_emitter() {
        let black = Solution::black(&mesh, &scene.materials);
        return Ok((mesh, black));
    }
    if !scene.radiosity.store_form_factors {
        let accel = pipeline::specular_accel(scene, &mesh);
        let solution = pipeline::solve_matrix_free(scene, &mesh, accel.as_ref(), progress, stats);
        return Ok((mesh, solution));
    }
    pipeline::check_memory(scene, &mesh).map_err(Failure::input)?;
    let accel = pipeline::specular_accel(scene, &mesh);
    let ff = pipeline::compute_form_factors(scene, &mesh, accel.as_ref(), photons, progress, stats);
    let solution = pipeline::solve(scene, &mesh, &ff, progress, stats);
    Ok((mesh, solution))
}

/// Writes an image as PNG or EXR by its extension.
pub fn write_image(image: &crate::film::Image, path: &Path, overrides: &Overrides) -> Result<(), Failure> {
    let is_exr = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    let result = if is_exr {
        output::write_exr(image, path)
    } else {
        output::write_png(
            image,
            path,
            overrides.exposure.unwrap_or(0.0),
            overrides.tone.map(Into::into).unwrap_or(ToneCurve::Clamp),
        )
    };
    result.map_err(Failure::input)
}

/// Renders every planned output of one scene.
#[allow(clippy::too_many_arguments)]
pub fn render_scene(
    scene: &SceneDescription,
    mesh: &crate::mesh::Mesh,
    solution: &Solution,
    plan: &[(TraceMode, PathBuf)],
    overrides: &Overrides,
    photons: &pipeline::RunPhotons,
    progress: &Progress,
    stats: &mut RunStats,
) -> Result<Vec<PathBuf>, Failure> {
    let accel = Accel::build(&mesh.positions, &mesh.triangles);
    let mut written = Vec::new();
    let mut rendered: Vec<(TraceMode, crate::film::Image)> = Vec::new();
    for (mode, path) in plan {
        if !rendered.iter().any(|(m, _)| m == mode) {
            let image = pipeline::render(scene, mesh, &accel, solution, *mode, photons, progress, stats)
                .map_err(Failure::internal)?;
            rendered.push((*mode, image));
        }
        let image = &rendered
            .iter()
            .find(|(m, _)| m == mode)
            .map(|(_, i)| i)
            .ok_or_else(|| Failure::internal(anyhow::anyhow!("image missing")))?;
        write_image(image, path, overrides)?;
        written.push(path.clone());
    }
    Ok(written)
}

fn write_stats(path: Option<&PathBuf>, stats: &mut RunStats) -> Result<(), Failure> {
    let Some(path) = path else { return Ok(()) };
    stats.peak_memory_bytes = pipeline::peak_memory_bytes();
    let text = serde_json::to_string_pretty(stats).map_err(Failure::internal)?;
    output::write_atomically(path, text.as_bytes())
        .with_context(|| format!("{}: cannot write stats", path.display()))
        .map_err(Failure::input)
}

fn render_command(args: &RenderArgs, progress: &Progress) -> Result<(), Failure> {
    let plan = output_plan(&args.output, args.mode)?;
    let scene = load_scene(&args.scene, &args.overrides, progress)?;
    let mut stats = RunStats::default();
    let photons = pipeline::RunPhotons::default();
    let (mesh, solution) = pass_one(&scene, args.solution.as_deref(), &photons, progress, &mut stats)?;
    let written = render_scene(&scene, &mesh, &solution, &plan, &args.overrides, &photons, progress, &mut stats)?;
    for path in written {
        if progress.verbosity() == Verbosity::Verbose {
            eprintln!("wrote {}", path.display());
        }
    }
    write_stats(args.stats.as_ref(), &mut stats)
}

fn solve_command(args: &SolveArgs, progress: &Progress) -> Result<(), Failure> {
    let overrides = Overrides { seed: args.seed, quality: args.quality, ..Default::default() };
    let dir = args.output.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    if !dir.is_dir() {
        return Err(Failure::input(anyhow::anyhow!(
            "{}: directory {} does not exist",
            args.output.display(),
            dir.display()
        )));
    }
    let scene = load_scene(&args.scene, &overrides, progress)?;
    let mut stats = RunStats::default();
    let (_mesh, solution) = pass_one(&scene, None, &pipeline::RunPhotons::default(), progress, &mut stats)?;
    solution.save(&args.output).map_err(Failure::input)?;
    write_stats(args.stats.as_ref(), &mut stats)
}

fn compare_command(args: &CompareArgs) -> Result<(), Failure> {
    let a = output::read_image(&args.a).map_err(Failure::input)?;
    let b = output::read_image(&args.b).map_err(Failure::input)?;
    let metrics = compare::metrics(&a, &b, None).map_err(Failure::input)?;
    let neutral = Overrides::default();
    if args.diff.is_some() || args.side_by_side.is_some() {
        let diff = compare::difference_image(&a, &b).map_err(Failure::input)?;
        if let Some(path) = &args.diff {
            write_image(&diff, path, &neutral)?;
        }
        if let Some(path) = &args.side_by_side {
            write_image(&compare::side_by_side(&[&a, &b, &diff]), path, &neutral)?;
        }
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&metrics).map_err(Failure::internal)?);
    } else {
        let at = &metrics.max_abs_diff_at;
        println!("pixels            {}", metrics.pixels);
        println!("rmse              {:.6e}", metrics.errors.rmse);
        println!("relMSE            {:.6e}", metrics.errors.rel_mse);
        println!("mean_abs_rel_err  {:.6e}", metrics.errors.mean_abs_rel_err);
        println!("max_abs_diff      {:.6e} at pixel ({}, {}) channel {}", metrics.max_abs_diff, at.x, at.y, at.channel);
        println!("mean (a, b)       {:.6e}, {:.6e}", metrics.mean_test, metrics.mean_ref);
        println!("best scale        {:.6} (relMSE after scaling {:.6e})", metrics.scale, metrics.scaled.rel_mse);
    }
    Ok(())
}

fn info_command(args: &InfoArgs) -> Result<(), Failure> {
    let overrides = Overrides { quality: args.quality, ..Default::default() };
    let scene = load_scene(&args.scene, &overrides, &Progress::hidden())?;
    let report = crate::info::describe(&scene);
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report).map_err(Failure::internal)?);
    } else {
        print!("{report}");
    }
    Ok(())
}
