//! `crosscheck` and `smoke`: the commands that need Embree.

use anyhow::Result;
use clap::builder::RangedU64ValueParser;
use vastocean::app;
use vastocean::config::LodChoice;

use super::choice;
use crate::emit;

/// Most rays `crosscheck` and `smoke` take (their buffers are held whole: 100 M rays are a few GB).
const MAX_RAYS: u64 = 100_000_000;

#[derive(clap::Args)]
pub struct CrosscheckArgs {
    /// The ocean mesh to trace (the default case-22 ocean, camera 2 m up).
    #[arg(long, value_parser = choice::<LodChoice>(), default_value = "paper-low")]
    lod: LodChoice,
    /// Random rays aimed into the mesh's bounds (the camera rays of the small render come on
    /// top), at most 100 million.
    #[arg(long, default_value_t = 1_000_000, value_parser = RangedU64ValueParser::<usize>::new().range(1..=MAX_RAYS))]
    rays: usize,
    /// Width of the small 360 degree render whose camera rays are traced too and which is
    /// rendered with both backends.
    #[arg(long, default_value_t = 256, value_parser = RangedU64ValueParser::<usize>::new().range(8..=4096))]
    width: usize,
    /// Samples per pixel of the small render.
    #[arg(long, default_value_t = 2)]
    spp: u32,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Worker threads (0 = all cores).
    #[arg(long, default_value_t = 0, value_parser = super::threads_arg)]
    threads: usize,
    /// What the rays meet: the mesh's triangles, or the exact displaced surface inside them
    /// (Embree's user geometry against the Rust tree of prisms; docs/exact.md).
    #[arg(long, value_parser = choice::<vastocean::config::SurfaceKind>(), default_value = "mesh")]
    surface: vastocean::config::SurfaceKind,
    /// Print the result as one JSON object on stdout instead of the report.
    #[arg(long)]
    pub json: bool,
}

pub fn crosscheck(a: CrosscheckArgs) -> Result<()> {
    let job = app::crosscheck::CrosscheckJob {
        lod: a.lod,
        rays: a.rays,
        width: a.width,
        spp: a.spp,
        seed: a.seed,
        threads: a.threads,
        surface: a.surface,
    };
    let r = app::crosscheck::run(&job)?;
    emit(&r, a.json)?;
    let bad = r.rays.unexplained_disagreements;
    anyhow::ensure!(
        bad == 0,
        "{bad} unexplained disagreements between Embree and the Rust BVH"
    );
    Ok(())
}

#[derive(clap::Args)]
pub struct SmokeArgs {
    /// Grid cells per side (two triangles per cell), at most 4096 (33.5 M triangles).
    #[arg(long, default_value_t = 1000, value_parser = clap::value_parser!(u32).range(1..=4096))]
    cells: u32,
    /// Number of rays to trace, at most 100 million.
    #[arg(long, default_value_t = 1_000_000, value_parser = RangedU64ValueParser::<usize>::new().range(1..=MAX_RAYS))]
    rays: usize,
    /// BVH build quality.
    #[arg(long, value_parser = choice::<vastocean::accel::embree::Quality>(), default_value = "medium")]
    quality: vastocean::accel::embree::Quality,
    /// Threads for Embree and the tracer (0 = all cores).
    #[arg(long, default_value_t = 0, value_parser = super::threads_arg)]
    threads: usize,
    /// Print the result as one JSON object on stdout instead of the report.
    #[arg(long)]
    pub json: bool,
}

impl SmokeArgs {
    pub fn job(&self) -> app::smoke::SmokeJob {
        app::smoke::SmokeJob {
            cells: self.cells,
            rays: self.rays,
            quality: self.quality,
            threads: self.threads,
        }
    }
}
