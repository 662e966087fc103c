//! Flags (clap derive) and how each command's flags become an `app` job: one file per
//! command group, each with its flags, their mapping onto the job and nothing else.

mod bench;
#[cfg(feature = "embree")]
mod embree;
mod mesh;
mod ocean;
mod scene;
mod sky;
mod stress;
mod study;

use anyhow::Result;
use clap::builder::{PossibleValuesParser, TypedValueParser};
use clap::{Parser, Subcommand};
use vastocean::app;
use vastocean::config::Choice;

use crate::emit;

#[derive(Parser)]
#[command(
    name = "vastocean",
    version,
    about = "Renderer for vast ocean scenes (FFT ocean layers, LOD to the horizon, Embree, normal mapping)"
)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// Errors in the flags themselves (exit code 2).
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub struct BadInput(pub String);

/// A flag whose values are the names of a [`Choice`] enum (listed in `--help`).
pub(crate) fn choice<T: Choice + Clone + Send + Sync>() -> impl TypedValueParser<Value = T> {
    PossibleValuesParser::new(T::ALL.iter().map(|v| v.name())).map(|s| {
        s.parse::<T>()
            .unwrap_or_else(|_| unreachable!("clap checked the name"))
    })
}

#[derive(Subcommand)]
enum Command {
    /// Print what this build has: versions, Embree's ISA and thread count.
    Info {
        /// Threads Embree may use (0 = all cores).
        #[arg(long, default_value_t = 0, value_parser = crate::cli::threads_arg)]
        threads: usize,
        #[arg(long)]
        json: bool,
    },
    /// Benchmarks that write reports: `accuracy` (run time against error) and `bvh` (BVH build
    /// time against triangle count).
    #[command(subcommand)]
    Bench(bench::BenchCommand),
    /// Render a scene: ocean -> LOD tessellation -> BVH (Embree or Rust) -> path tracing -> EXR + PNG + JSON.
    Render(scene::RenderArgs),
    /// Merge the sample passes of one render (`render --pass K/N`) into its EXR, PNG and JSON,
    /// exactly as a single render would have written them.
    Merge(scene::MergeArgs),
    /// The paper's four scenarios (high/low tessellation x with/without normal mapping) and the
    /// near-horizon statistics against the baseline.
    Compare(scene::CompareArgs),
    /// Trace the same rays through Embree and the pure-Rust BVH and report where they disagree;
    /// also render a small scene with both.
    #[cfg(feature = "embree")]
    Crosscheck(embree::CrosscheckArgs),
    /// Tessellate the ocean with the LOD doubling method and report (or export) the mesh.
    Mesh(mesh::MeshArgs),
    /// Generate the ocean layers (TMA spectrum, FFT) and report their statistics.
    Ocean(ocean::OceanArgs),
    /// Sky maps: generate (Preetham clear, CIE overcast, partly cloudy), import an HDR
    /// photograph with the ground removed, report statistics, make a contact sheet.
    #[command(subcommand)]
    Sky(sky::SkyCommand),
    /// The paper's study of many random cases (its 93): plan them into a folder, run each
    /// (GNU parallel, a Slurm job array), summarize (its Figure 10 and counts).
    #[command(subcommand)]
    Study(study::StudyCommand),
    /// Numerical-stability stress matrix: extreme cameras, positions, seas, suns and backends,
    /// with invariants checked on every cell (NaN, holes, self-intersection, white furnace,
    /// periodicity, backend agreement); exit 1 if any fails.
    Stress(stress::StressArgs),
    /// Embree smoke run: build a BVH over a wavy grid and trace random rays down onto it.
    #[cfg(feature = "embree")]
    Smoke(embree::SmokeArgs),
}

pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Info { threads, json } => emit(&app::info::run(threads)?, json),
        Command::Bench(c) => bench::run(c),
        Command::Render(a) => match a.frames {
            Some(frames) => emit(&app::frames::run(&a.frames_job(frames)?)?, a.json),
            None => emit(&app::render::run(&a.job()?)?, a.json),
        },
        Command::Merge(a) => emit(&app::passes::Merged(app::passes::merge(&a.job())?), a.json),
        Command::Compare(a) if a.realizations > 1 => emit(
            &app::compare::realizations::run(&a.job()?, a.realizations.into())?,
            a.json,
        ),
        Command::Compare(a) => emit(&app::compare::run(&a.job()?)?, a.json),
        #[cfg(feature = "embree")]
        Command::Crosscheck(a) => embree::crosscheck(a),
        Command::Mesh(a) => emit(&app::mesh::run(&a.job())?, a.json),
        Command::Ocean(a) => {
            let r = app::ocean::run(&a.job())?;
            r.warnings().iter().for_each(|w| eprintln!("warning: {w}"));
            emit(&r, a.json)
        }
        Command::Sky(c) => sky::run(c),
        Command::Study(c) => study::run(c),
        Command::Stress(a) => stress::stress(a),
        #[cfg(feature = "embree")]
        Command::Smoke(a) => emit(&app::smoke::run(&a.job())?, a.json),
    }
}

/// Parses `--threads` and bounds it (see [`vastocean::config::max_threads`]).
pub fn threads_arg(s: &str) -> Result<usize, String> {
    let n: usize = s
        .parse()
        .map_err(|_| format!("`{s}` is not a thread count"))?;
    vastocean::config::check_threads("--threads", n).map_err(|e| e.to_string())?;
    Ok(n)
}
