//! `bench accuracy` and `bench bvh`: the reports behind docs/performance.md and docs/accuracy.md.

use std::path::PathBuf;

use anyhow::Result;
use clap::Subcommand;
use vastocean::app::{self, AppError};
use vastocean::config::SceneConfig;

use crate::emit;

#[derive(Subcommand)]
pub enum BenchCommand {
    /// The speed / accuracy frontier of one scene: tessellation x normals x spp, each timed
    /// and its error measured against a converged reference (frontier.csv, frontier.png,
    /// summary.json).
    Accuracy {
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
        /// Scene file (TOML); without one, the default scene with the sun clipped to radiance
        /// 100 (docs/accuracy.md, "Run time against error"). Its camera becomes a panorama.
        #[arg(long)]
        config: Option<PathBuf>,
        /// A reduced sweep (256 px, 4 tessellations, 8 to 128 spp): about a minute on 2 cores.
        #[arg(long)]
        quick: bool,
        /// Also render every tessellation with filtered normals (docs/filtered.md), a third
        /// group on the frontier.
        #[arg(long)]
        filtered: bool,
        /// Also render the exact surface (docs/exact.md) inside paper-low's prisms, with mapped
        /// normals (and with filtered ones under --filtered), at the sweep's samples per pixel
        /// up to 64: a group each (slow: some 7 minutes more at 1024 px for mapped normals).
        #[arg(long)]
        exact: bool,
        /// What to do when a shading normal would send a ray to the wrong side of its triangle,
        /// in every render of the sweep and its reference (default: the scene's, terminate
        /// unless its file says otherwise; docs/accuracy.md, "The wrong-side policy").
        #[arg(long, value_parser = super::choice::<vastocean::config::WrongSide>())]
        wrong_side: Option<vastocean::config::WrongSide>,
        /// How every render of the sweep and its reference reads the ocean's layers (default:
        /// the scene's, prefiltered unless its file says otherwise; docs/ocean.md, "Reading the
        /// layers").
        #[arg(long, value_parser = super::choice::<vastocean::ocean::Interp>())]
        interp: Option<vastocean::ocean::Interp>,
        /// Worker threads (0 = all cores).
        #[arg(long, default_value_t = 0, value_parser = super::threads_arg)]
        threads: usize,
        /// Print the result as one JSON object on stdout instead of the report.
        #[arg(long)]
        json: bool,
    },
    /// BVH build time against triangle count for every backend and build quality, and trace
    /// speed, on ocean meshes from 10^3 to 22.3 M triangles (bvh.csv, bvh.png, summary.json).
    #[cfg(feature = "embree")]
    Bvh {
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
        /// 10^3 to 10^6 triangles only.
        #[arg(long)]
        quick: bool,
        /// Worker threads (0 = all cores).
        #[arg(long, default_value_t = 0, value_parser = super::threads_arg)]
        threads: usize,
        /// Print the result as one JSON object on stdout instead of the report.
        #[arg(long)]
        json: bool,
    },
}

pub fn run(c: BenchCommand) -> Result<()> {
    match c {
        #[rustfmt::skip]
        BenchCommand::Accuracy { out, config, quick, filtered, exact, wrong_side, interp, threads, json } => {
            let mut scene = match &config {
                Some(path) => SceneConfig::load(path).map_err(AppError::from)?,
                None => app::bench::accuracy::AccuracyJob::default_scene(),
            };
            scene.render.threads = threads;
            scene.render.wrong_side = wrong_side.unwrap_or(scene.render.wrong_side);
            scene.ocean.interp = interp.unwrap_or(scene.ocean.interp);
            let mut job = if quick {
                app::bench::accuracy::AccuracyJob::quick(scene, out)
            } else {
                app::bench::accuracy::AccuracyJob::full(scene, out)
            };
            job.progress = true;
            if filtered {
                job.normals.push(vastocean::config::NormalMode::Filtered);
            }
            if exact {
                job = job.with_exact();
            }
            emit(&app::bench::accuracy::run(&job)?, json)
        }
        #[cfg(feature = "embree")]
        BenchCommand::Bvh {
            out,
            quick,
            threads,
            json,
        } => {
            let job = if quick {
                app::bench::bvh::BvhBenchJob::quick(out, threads)
            } else {
                app::bench::bvh::BvhBenchJob::full(out, threads)
            };
            emit(&app::bench::bvh::run(&job)?, json)
        }
    }
}
