//! The command line: subcommands and their flags (clap), turned into `run::Job`s (a render or a solve
//! is a batch of one) or a `batch::Settings`, and dispatched.

use clap::{Args, Parser, Subcommand, ValueEnum};
use std::path::PathBuf;

const EXAMPLES: &str = "\
Examples:
  radray render scenes/cornell_box.toml -o cornell.png -o cornell.exr
  radray render scenes/cornell_specular.toml -o spec.png --mode both --direct pixel --spp 64
  radray solve scenes/cornell_box.toml -o cornell.radsol
  radray solve scenes/cornell_box.toml --shard 0/3 -o part.0   (then 1/3, 2/3, on any machines)
  radray solve scenes/cornell_box.toml --merge part.0 part.1 part.2 -o cornell.radsol
  radray render scenes/cornell_box.toml --solution cornell.radsol -o view.exr --width 512 --height 512
  radray compare out.exr references/cornell_original/reference.exr --diff diff.png --json
  radray batch jobs.toml --manifest jobs.manifest.json --shard 0/4
  radray batch jobs.toml --report report.html --resume
  radray info scenes/cornell_box.toml

Exit codes: 0 success, 2 bad input or usage, 1 internal error, 130/143 interrupted by SIGINT/SIGTERM
(`render` and `solve` keep OUT.partial; rerun the same command to resume).";

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

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum DirectArg {
    Radiosity,
    Pixel,
}

/// The pass-one method (`[radiosity] method`).
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum MethodArg {
    Auto,
    Matrix,
    Hierarchical,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum FinalGatherArg {
    Off,
    On,
}

impl From<FinalGatherArg> for FinalGatherMode {
    fn from(g: FinalGatherArg) -> Self {
        match g {
            FinalGatherArg::Off => FinalGatherMode::Off,
            FinalGatherArg::On => FinalGatherMode::On,
        }
    }
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum QualityArg {
    Preview,
    Default,
    High,
}

/// Settings that the command line lays over the scene file's (`scene::Overrides`), and the PNG
/// encoding.
#[derive(Args, Debug, Clone, Default)]
pub struct OverrideArgs {
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
    /// Final gather of the indirect light over the radiosity solution in the final image.
    #[arg(long, value_enum)]
    pub final_gather: Option<FinalGatherArg>,
    /// A named preset of element size, hemicube resolution, samples and light samples.
    #[arg(long, value_enum)]
    pub quality: Option<QualityArg>,
    /// The pass-one method, as the scene's `[radiosity] method`.
    #[arg(long, value_enum)]
    pub method: Option<MethodArg>,
    /// PNG exposure in stops (radiance × 2^stops before encoding), or "auto" (log-average
    /// luminance brought to 0.18).
    #[arg(long, allow_negative_numbers = true)]
    pub exposure: Option<Exposure>,
    /// PNG tone curve applied after the exposure.
    #[arg(long, value_enum)]
    pub tone: Option<ToneCurve>,
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
    /// Also write a layered EXR: beauty RGB plus direct, indirect, specular, emitted, radiosity,
    /// albedo, normal and depth layers.
    #[arg(long)]
    pub layers: Option<PathBuf>,
    #[command(flatten)]
    pub overrides: OverrideArgs,
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
    /// The pass-one method, as the scene's `[radiosity] method`.
    #[arg(long, value_enum)]
    pub method: Option<MethodArg>,
    /// Compute only the form-factor rows of every N-th receiver group, starting at K (0-based), and
    /// write them to -o as a part for --merge (hierarchical method: refine the next refinement pass
    /// for this shard's receiver groups and write its link estimates; with --merge PARTS of the passes
    /// before it).
    #[arg(long, value_name = "K/N", value_parser = parse_shard_arg)]
    pub shard: Option<Shard>,
    /// Join the parts of `--shard 0/N` … `--shard N-1/N` (each exactly once) and solve (with --shard:
    /// the hierarchy's parts of the passes before the one to shard).
    #[arg(long, value_name = "PART", num_args = 1..)]
    pub merge: Vec<PathBuf>,
}

fn parse_shard_arg(text: &str) -> Result<Shard, String> {
    let (index, count) = run::parse_shard(text)?;
    let index = u32::try_from(index).map_err(|_| format!("--shard: {index} is too large"))?;
    let count = u32::try_from(count).map_err(|_| format!("--shard: {count} is too large"))?;
    Ok(Shard { index, count })
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
    /// Write an HTML page comparing each job's final, radiosity and reference images.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Skip the jobs the manifest records as finished (a killed batch's manifest lists them).
    #[arg(long)]
    pub resume: bool,
    /// Most memory the caches kept between jobs may hold, e.g. 512MiB (over the jobs file's
    /// cache_memory; default 2 GiB).
    #[arg(long, value_parser = crate::cache::parse_bytes)]
    pub cache_memory: Option<u64>,
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
// Dispatch

use crate::batch;
use crate::compare;
use crate::interrupt::Cancel;
use crate::output::{self, Exposure, ToneCurve};
use crate::progress::{Progress, Verbosity};
use crate::radiosity::resume::{self, Resume, Shard};
use crate::run::{self, Failure, Job, Mode, Outcome, PngSettings, Runner, Work};
use crate::scene::{DirectMode, FinalGatherMode, MethodChoice, Overrides, Quality};

impl From<QualityArg> for Quality {
    fn from(q: QualityArg) -> Self {
        match q {
            QualityArg::Preview => Quality::Preview,
            QualityArg::Default => Quality::Default,
            QualityArg::High => Quality::High,
        }
    }
}

impl From<MethodArg> for MethodChoice {
    fn from(m: MethodArg) -> Self {
        match m {
            MethodArg::Auto => MethodChoice::Auto,
            MethodArg::Matrix => MethodChoice::Matrix,
            MethodArg::Hierarchical => MethodChoice::Hierarchical,
        }
    }
}

impl From<DirectArg> for DirectMode {
    fn from(d: DirectArg) -> Self {
        match d {
            DirectArg::Radiosity => DirectMode::Radiosity,
            DirectArg::Pixel => DirectMode::Pixel,
        }
    }
}

impl OverrideArgs {
    /// The scene settings these flags override.
    pub fn scene_overrides(&self) -> Overrides {
        Overrides {
            width_px: self.width,
            height_px: self.height,
            samples_per_pixel: self.spp,
            seed: self.seed,
            direct: self.direct.map(Into::into),
            final_gather: self.final_gather.map(Into::into),
            quality: self.quality.map(Into::into),
            method: self.method.map(Into::into),
            ..Default::default()
        }
    }

    /// How PNGs are encoded.
    pub fn png(&self) -> PngSettings {
        PngSettings { exposure: self.exposure, tone: self.tone.unwrap_or_default() }
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
        Command::Batch(args) => {
            let settings = batch::Settings {
                jobs: args.jobs,
                manifest: args.manifest,
                shard: args.shard,
                report: args.report,
                resume: args.resume,
                cache_memory_bytes: args.cache_memory,
            };
            batch::run(&settings, &progress)
        }
        Command::Info(args) => info_command(&args),
    })
}

fn render_command(args: &RenderArgs, progress: &Progress) -> Result<(), Failure> {
    let plan = run::output_plan(&args.output, args.mode)?;
    if let Some(path) = &args.layers {
        run::check_layers_path(path)?;
    }
    let job = Job {
        scene: args.scene.clone(),
        overrides: args.overrides.scene_overrides(),
        work: Work::Render {
            plan,
            png: args.overrides.png(),
            solution: args.solution.clone(),
            layers: args.layers.clone(),
        },
    };
    let mut outcome = Outcome::default();
    let resume = resumable(args.output.first().map(|o| resume::checkpoint_path(o)))?;
    Runner::resumable(resume).run(&job, progress, &mut outcome)?;
    for path in &outcome.written {
        if progress.verbosity() == Verbosity::Verbose {
            eprintln!("wrote {}", path.display());
        }
    }
    run::write_stats(args.stats.as_deref(), &mut outcome.stats)
}

fn solve_command(args: &SolveArgs, progress: &Progress) -> Result<(), Failure> {
    run::check_output_directory(&args.output)?;
    let overrides = Overrides {
        seed: args.seed,
        quality: args.quality.map(Into::into),
        method: args.method.map(Into::into),
        ..Default::default()
    };
    let job = Job { scene: args.scene.clone(), overrides, work: Work::Solve { output: args.output.clone() } };
    let mut outcome = Outcome::default();
    // A merge computes no rows, so it keeps no checkpoint.
    let checkpoint = args.merge.is_empty().then(|| resume::checkpoint_path(&args.output));
    let resume = Resume { shard: args.shard, merge: args.merge.clone(), ..resumable(checkpoint)? };
    Runner::resumable(resume).run(&job, progress, &mut outcome)?;
    run::write_stats(args.stats.as_deref(), &mut outcome.stats)
}

/// A single run's `Resume`: the checkpoint beside its output, and a cancellation that SIGINT and
/// SIGTERM request.
fn resumable(checkpoint: Option<PathBuf>) -> Result<Resume, Failure> {
    let cancel = Cancel::default();
    cancel.install_signal_handlers().map_err(Failure::internal)?;
    Ok(Resume { checkpoint, interval: resume::CHECKPOINT_INTERVAL, cancel, ..Default::default() })
}

fn compare_command(args: &CompareArgs) -> Result<(), Failure> {
    let a = output::read_image(&args.a)?;
    let b = output::read_image(&args.b)?;
    let metrics = compare::metrics(&a, &b, None)?;
    let neutral = PngSettings::default();
    if args.diff.is_some() || args.side_by_side.is_some() {
        let diff = compare::difference_image(&a, &b)?;
        if let Some(path) = &args.diff {
            run::write_image(&diff, path, &neutral)?;
        }
        if let Some(path) = &args.side_by_side {
            run::write_image(&compare::side_by_side(&[&a, &b, &diff]), path, &neutral)?;
        }
    }
    let text = if args.json {
        format!("{}\n", serde_json::to_string_pretty(&metrics)?)
    } else {
        let at = &metrics.max_abs_diff_at;
        [
            format!("pixels            {}", metrics.pixels),
            format!("rmse              {:.6e}", metrics.errors.rmse),
            format!("relMSE            {:.6e}", metrics.errors.rel_mse),
            format!("mean_abs_rel_err  {:.6e}", metrics.errors.mean_abs_rel_err),
            format!(
                "max_abs_diff      {:.6e} at pixel ({}, {}) channel {}",
                metrics.max_abs_diff, at.x, at.y, at.channel
            ),
            format!("mean (a, b)       {:.6e}, {:.6e}", metrics.mean_test, metrics.mean_ref),
            format!("best scale        {:.6} (relMSE after scaling {:.6e})", metrics.scale, metrics.scaled.rel_mse),
            String::new(),
        ]
        .join("\n")
    };
    write_stdout(&text)
}

fn info_command(args: &InfoArgs) -> Result<(), Failure> {
    let overrides = Overrides { quality: args.quality.map(Into::into), ..Default::default() };
    let scene = run::load_scene(&args.scene, &overrides, &Progress::hidden())?;
    let report = crate::info::describe(&scene);
    let text = if args.json { format!("{}\n", serde_json::to_string_pretty(&report)?) } else { report.to_string() };
    write_stdout(&text)
}

/// Writes a command's report to standard output. A reader that closes the pipe early (`radray info
/// S.toml | head -3`) has all it wanted: a broken pipe ends the command cleanly instead of panicking
/// as `println!` does.
fn write_stdout(text: &str) -> Result<(), Failure> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
            Err(Failure::internal(anyhow::anyhow!("cannot write to standard output: {e}")))
        }
        _ => Ok(()),
    }
}
