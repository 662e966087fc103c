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

use crate::{emit, emit_remarked};

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
        /// Print the result as one JSON object on stdout instead of the report.
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
    ///
    /// A scene without a sky map is lit by the built-in sky (`[sky.analytic]` in the scene
    /// file): by default the clear sky of Preetham, Shirley & Smits 1999 ("A Practical Analytic
    /// Model for Daylight"), turbidity 2.5, the sun 3 degrees up at azimuth 180, evaluated for
    /// every ray with its 0.53 degree sun disc at the radiance the model's atmosphere transmits.
    /// It is the model `sky generate --kind clear` renders into maps, in the same unit (1 = 100
    /// kcd/m^2). `hand-made-clear` is a hand-made sky with no physical model behind it.
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
    /// Print a shell completion script, e.g. `vastocean completions bash >
    /// ~/.local/share/bash-completion/completions/vastocean`.
    Completions {
        /// The shell.
        shell: clap_complete::Shell,
    },
    /// Write man pages, one per command (vastocean.1, vastocean-render.1, ...), into a folder;
    /// `man -l DIR/vastocean.1` reads one without installing it.
    Man {
        /// Folder for the pages (created if missing).
        #[arg(long)]
        out: std::path::PathBuf,
    },
}

pub fn run(cli: Cli) -> Result<()> {
    let given = match &cli.command {
        Command::Render(a) => a.given(),
        Command::Compare(a) => a.given(),
        Command::Ocean(a) => a.given(),
        _ => Vec::new(),
    };
    run_command(cli.command).map_err(|e| name_flags(e, &given))
}

/// Bad input about a scene key that a flag set names the flag the user typed, with the key
/// beside it for scene files: `--width (camera.width) must be in 2..=65536 (got 1)`. Other
/// errors pass unchanged.
pub fn name_flags(e: anyhow::Error, given: &[(&str, &str)]) -> anyhow::Error {
    let input = e
        .downcast_ref::<app::AppError>()
        .is_some_and(|a| a.exit_code() == 2);
    if !input || given.is_empty() {
        return e;
    }
    let mut msg = e.to_string();
    for cause in e.chain().skip(1) {
        msg.push_str(&format!(": {cause}"));
    }
    let mut renamed = false;
    for (key, flag) in given {
        let mut out = String::with_capacity(msg.len());
        let mut rest = msg.as_str();
        while let Some(at) = rest.find(key) {
            let after = &rest[at + key.len()..];
            let before_ok =
                !rest[..at].ends_with(|c: char| c.is_alphanumeric() || c == '_' || c == '.');
            let after_ok =
                !after.starts_with(|c: char| c.is_alphanumeric() || c == '_' || c == '.');
            out.push_str(&rest[..at]);
            if before_ok && after_ok {
                out.push_str(&format!("{flag} ({key})"));
                renamed = true;
            } else {
                out.push_str(key);
            }
            rest = after;
        }
        out.push_str(rest);
        msg = out;
    }
    if renamed { BadInput(msg).into() } else { e }
}

fn run_command(command: Command) -> Result<()> {
    match command {
        Command::Info { threads, json } => emit(&app::info::run(threads)?, json),
        Command::Bench(c) => bench::run(c),
        Command::Render(a) if a.dump_config => {
            let scene = a.job()?.scene;
            scene.validate().map_err(app::AppError::from)?;
            let text = scene.to_toml().map_err(|e| app::AppError::Run(e.into()))?;
            // Written, not print!ed: a reader that stops early is not a panic (main exits 0).
            std::io::Write::write_all(&mut std::io::stdout().lock(), text.as_bytes())?;
            Ok(())
        }
        Command::Render(a) => match a.frames {
            Some(frames) => emit_remarked(&app::frames::run(&a.frames_job(frames)?)?, a.json),
            None => emit_remarked(&app::render::run(&a.job()?)?, a.json),
        },
        Command::Merge(a) => {
            emit_remarked(&app::passes::Merged(app::passes::merge(&a.job())?), a.json)
        }
        Command::Compare(a) if a.realizations > 1 => emit(
            &app::compare::realizations::run(&a.job()?, a.realizations.into())?,
            a.json,
        ),
        Command::Compare(a) => emit_remarked(&app::compare::run(&a.job()?)?, a.json),
        #[cfg(feature = "embree")]
        Command::Crosscheck(a) => embree::crosscheck(a),
        Command::Mesh(a) => emit(&app::mesh::run(&a.job())?, a.json),
        Command::Ocean(a) => emit_remarked(&app::ocean::run(&a.job())?, a.json),
        Command::Sky(c) => sky::run(c),
        Command::Study(c) => study::run(c),
        Command::Stress(a) => stress::stress(a),
        #[cfg(feature = "embree")]
        Command::Smoke(a) => emit(&app::smoke::run(&a.job())?, a.json),
        Command::Completions { shell } => {
            // Into a buffer first: clap_complete panics on a write error, and a reader that
            // stops early (`| head`) is not a failure.
            let mut cmd = <Cli as clap::CommandFactory>::command();
            let mut script = Vec::new();
            clap_complete::generate(shell, &mut cmd, "vastocean", &mut script);
            std::io::Write::write_all(&mut std::io::stdout().lock(), &script)?;
            Ok(())
        }
        Command::Man { out } => write_man_pages(&out),
    }
}

/// Writes a man page for the program and one for each command (`vastocean-sky-generate.1` for
/// `vastocean sky generate`) into `out`.
fn write_man_pages(out: &std::path::Path) -> Result<()> {
    vastocean::app::check_output_dir(out)?;
    let cmd = <Cli as clap::CommandFactory>::command();
    clap_mangen::generate_to(cmd, out).map_err(|e| app::AppError::Run(e.into()))?;
    let pages = std::fs::read_dir(out)?
        .filter_map(|e| e.ok())
        .filter(|e| e.path().extension().is_some_and(|x| x == "1"))
        .count();
    println!(
        "wrote {pages} man pages to {} (read one with `man -l {}`)",
        out.display(),
        out.join("vastocean.1").display()
    );
    Ok(())
}

/// Parses `--threads` and bounds it (see [`vastocean::config::max_threads`]).
pub fn threads_arg(s: &str) -> Result<usize, String> {
    let n: usize = s
        .parse()
        .map_err(|_| format!("`{s}` is not a thread count"))?;
    vastocean::config::check_threads("--threads", n).map_err(|e| e.to_string())?;
    Ok(n)
}

/// Parses `--swell HS:TP[:DIR[:S]]` (the ranges are the scene's validation's to check).
pub fn parse_swell(s: &str) -> Result<vastocean::ocean::SwellParams, String> {
    let bad = || format!("a swell is HS:TP[:DIR[:S]], e.g. 1.5:11:90 (got `{s}`)");
    let v = s
        .split(':')
        .map(|x| x.trim().parse::<f64>().map_err(|_| bad()))
        .collect::<Result<Vec<f64>, String>>()?;
    if !(2..=4).contains(&v.len()) {
        return Err(bad());
    }
    let mut swell =
        vastocean::ocean::SwellParams::new(v[0], v[1], v.get(2).copied().unwrap_or(0.0));
    if let Some(&spread) = v.get(3) {
        swell.spreading_s = spread;
    }
    Ok(swell)
}

/// The sea-state flags of `ocean`, `render` and `compare`: a preset and swells.
#[derive(clap::Args)]
pub struct SeaFlags {
    /// A Beaufort force 1-12: sets the wind, fetch and height (docs/ocean.md, "Sea states").
    #[arg(long, conflicts_with_all = ["wind", "fetch", "rms", "hs", "tp", "douglas"])]
    pub beaufort: Option<u8>,
    /// A Douglas sea state 1-9: sets the wind, fetch and height (docs/ocean.md, "Sea states").
    #[arg(long, conflicts_with_all = ["wind", "fetch", "rms", "hs", "tp"])]
    pub douglas: Option<u8>,
    /// A swell HS:TP[:DIR[:S]] (m, s, degrees it travels towards, cos-2s exponent; default 0
    /// and 25) added to the wind sea (in render and compare replacing the scene's own); repeat
    /// for more.
    #[arg(long, value_parser = parse_swell, allow_hyphen_values = true)]
    pub swell: Vec<vastocean::ocean::SwellParams>,
}
