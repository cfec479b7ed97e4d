//! Command-line arguments (SPEC §4).

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};

#[derive(Parser, Debug)]
#[command(
    name = "tessera",
    version,
    about = "GPU tessellation of Bézier and Catmull-Clark surfaces"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Tessellate a surface and write the mesh and/or its statistics.
    Tessellate(TessellateArgs),
    /// Print what a surface file holds.
    Info { input: PathBuf },
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    Map2p,
    Map4p,
    Map8p,
    Flat,
    Uniform,
    Adaptive,
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Backend {
    Cpu,
}

#[derive(Args, Debug)]
pub struct TessellateArgs {
    /// Input surface: a Newell teaset file (Bézier patches).
    pub input: PathBuf,
    /// Tessellation method (Bézier inputs default to map4p).
    #[arg(long, value_enum)]
    pub method: Option<Method>,
    /// Edge-test threshold in model units (map tests: displacement difference; flat: chord
    /// deviation). Default: 0.002 of the bounding-box diagonal.
    #[arg(long)]
    pub threshold: Option<f32>,
    /// Levels of recursive edge bisection (at most 2^D segments per coarse edge).
    #[arg(long, default_value_t = 6)]
    pub max_depth: u32,
    /// Segments per patch side for `--method uniform`.
    #[arg(long, default_value_t = 8)]
    pub segments: u32,
    /// Search the threshold (or the uniform segment count) for this many triangles (±2%).
    #[arg(long, conflicts_with = "threshold")]
    pub target_triangles: Option<usize>,
    /// Where the tessellation runs.
    #[arg(long, value_enum, default_value = "cpu")]
    pub backend: Backend,
    /// Output mesh (.obj or .ply).
    #[arg(short = 'o', long = "output")]
    pub output: Option<PathBuf>,
    /// Write statistics as JSON to this file.
    #[arg(long)]
    pub stats: Option<PathBuf>,
    /// Measure the error against the exact surface (max, mean, p99).
    #[arg(long)]
    pub measure: bool,
    /// Surface samples per patch side for --measure.
    #[arg(long, default_value_t = tessera_core::measure::DEFAULT_SAMPLES_PER_SIDE)]
    pub measure_samples: usize,
}
