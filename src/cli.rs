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
