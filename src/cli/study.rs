//! `study plan | run | summarize`: the paper's study of many random cases.

use std::path::PathBuf;

use anyhow::Result;
use clap::Subcommand;
use vastocean::app::{self, AppError};
use vastocean::config::{LodChoice, LodConfig, SceneConfig, WrongSide};

use super::{BadInput, choice};
use crate::emit;

#[derive(Subcommand)]
pub enum StudyCommand {
    /// Draw the cases from a seed and write the study folder: plan.toml (what every case
    /// shares), cases/K/scene.toml (one per case; edit one to change that case) and a copy of
    /// the skies.
    Plan {
        /// Study folder (must not hold a plan yet).
        #[arg(long)]
        out: PathBuf,
        /// How many cases (the paper: 93).
        #[arg(long, default_value_t = 93)]
        cases: usize,
        /// Seed the cases are drawn from.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Scene every case starts from (camera, render settings); without one, the default.
        #[arg(long)]
        config: Option<PathBuf>,
        /// Panorama width in pixels.
        #[arg(long)]
        width: Option<usize>,
        /// Samples per pixel.
        #[arg(long)]
        spp: Option<u32>,
        /// The baseline tessellation.
        #[arg(long, value_parser = choice::<LodChoice>(), default_value = "paper-high")]
        high: LodChoice,
        /// The low tessellation.
        #[arg(long, value_parser = choice::<LodChoice>(), default_value = "paper-low")]
        low: LodChoice,
        /// Make the baseline a custom tessellation with triangles this wide near the camera, m
        /// (double distance 18 m, as the paper's).
        #[arg(long)]
        high_near_size: Option<f64>,
        /// Make the low tessellation a custom one with triangles this wide near the camera, m.
        #[arg(long)]
        low_near_size: Option<f64>,
        /// What to do when a shading normal points a ray to the wrong side of its triangle
        /// (default terminate, as `compare --wrong-side`).
        #[arg(long, value_parser = choice::<WrongSide>())]
        wrong_side: Option<WrongSide>,
        /// How every case reads the ocean's layers (default prefiltered, as `compare --interp`).
        #[arg(long, value_parser = choice::<vastocean::ocean::Interp>())]
        interp: Option<vastocean::ocean::Interp>,
        /// Clip every sky's sun at this multiple of the sky's median luminance, as the paper's
        /// photographs clipped theirs (sky.clip_relative in each case's scene).
        #[arg(long)]
        clip_sun: Option<f32>,
        /// Most samples a noisy pixel may take in each case's comparison, in multiples of
        /// --spp (see `compare --max-boost`; 1 renders every pixel alike).
        #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u16).range(1..=1024))]
        max_boost: u16,
        /// Ocean realizations per case: with N > 1 each case is run for N ocean seeds and
        /// pooled (see `compare --realizations`), N times the work.
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u16).range(1..=64))]
        realizations: u16,
        /// The sky collection to draw from.
        #[arg(long, default_value = "skies")]
        skies: PathBuf,
        /// Print the result as one JSON object on stdout instead of the report.
        #[arg(long)]
        json: bool,
    },
    /// Run one case (or all) into DIR/cases/K/; a case with a summary.json is finished and is
    /// skipped. Exit code 0 when the case ran or was skipped, 1 or 2 when it failed.
    Run {
        /// Study folder (holds plan.toml).
        dir: PathBuf,
        /// The case to run, 1-based (as $SLURM_ARRAY_TASK_ID or GNU parallel's {}).
        #[arg(long, required_unless_present = "all", conflicts_with = "all")]
        case: Option<usize>,
        /// Run every unfinished case, one after the other.
        #[arg(long)]
        all: bool,
        /// Rerun finished cases.
        #[arg(long)]
        force: bool,
        /// Worker threads per case (0 = all cores; with GNU parallel -j 2 on 2 cores, 1).
        #[arg(long, value_parser = super::threads_arg)]
        threads: Option<usize>,
        /// Print the result as one JSON object on stdout instead of the report.
        #[arg(long)]
        json: bool,
    },
    /// Gather the finished cases into cases.csv, per_sky.csv, scatter.png and summary.json
    /// (missing cases are listed, not fatal).
    Summarize {
        /// Study folder.
        dir: PathBuf,
        /// Print the result as one JSON object on stdout instead of the report.
        #[arg(long)]
        json: bool,
    },
}

/// A tessellation from its preset and an optional near size (which makes it custom).
fn lod(preset: LodChoice, near_size: Option<f64>) -> LodConfig {
    match near_size {
        Some(s) => LodConfig {
            preset: LodChoice::Custom,
            near_size_m: Some(s),
            double_distance_m: Some(18.0),
            ..LodConfig::default()
        },
        None => LodConfig {
            preset,
            ..LodConfig::default()
        },
    }
}

pub fn run(c: StudyCommand) -> Result<()> {
    match c {
        StudyCommand::Plan {
            out,
            cases,
            seed,
            config,
            width,
            spp,
            high,
            low,
            high_near_size,
            low_near_size,
            wrong_side,
            interp,
            clip_sun,
            max_boost,
            realizations,
            skies,
            json,
        } => {
            if (high == LodChoice::Custom && high_near_size.is_none())
                || (low == LodChoice::Custom && low_near_size.is_none())
            {
                return Err(BadInput(
                    "a custom tessellation needs its --high-near-size / --low-near-size".into(),
                )
                .into());
            }
            let mut base = match &config {
                Some(path) => SceneConfig::load(path).map_err(AppError::from)?,
                None => SceneConfig::default(),
            };
            base.camera.width = width.unwrap_or(base.camera.width);
            base.render.spp = spp.unwrap_or(base.render.spp);
            base.render.wrong_side = wrong_side.unwrap_or(base.render.wrong_side);
            base.ocean.interp = interp.unwrap_or(base.ocean.interp);
            base.sky.clip_relative = clip_sun.or(base.sky.clip_relative);
            let job = app::study::PlanJob {
                out,
                cases,
                seed,
                base,
                high: lod(high, high_near_size),
                low: lod(low, low_near_size),
                max_boost,
                realizations,
                skies_dir: skies,
            };
            emit(&app::study::plan(&job)?, json)
        }
        StudyCommand::Run {
            dir,
            case,
            all,
            force,
            threads,
            json,
        } => {
            let Some(k) = case.filter(|_| !all) else {
                // Every case in turn; one that fails is reported and the rest still run.
                let n = app::study::read_plan(&dir)?.cases;
                let mut failed = Vec::new();
                for k in 1..=n {
                    match app::study::run_case(&dir, k, force, threads, true) {
                        Ok(outcome) => emit(&outcome, json)?,
                        Err(e) => {
                            eprintln!("case {k}: error: {e}");
                            failed.push(k);
                        }
                    }
                }
                if failed.is_empty() {
                    return Ok(());
                }
                return Err(AppError::Run(
                    format!("{} of {n} cases failed: {failed:?}", failed.len()).into(),
                )
                .into());
            };
            emit(&app::study::run_case(&dir, k, force, threads, true)?, json)
        }
        StudyCommand::Summarize { dir, json } => emit(&app::study::summarize(&dir)?, json),
    }
}
