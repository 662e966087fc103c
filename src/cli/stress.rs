//! `stress [--quick] [--interp I] [--json]`: the numerical-stability matrix (see `vastocean::app::stress`).

use std::path::PathBuf;

use anyhow::Result;
use vastocean::app::stress::{StressJob, run};

use crate::emit;

#[derive(clap::Args)]
pub struct StressArgs {
    /// The quick matrix (256 px, 8 spp, no paper-high): seconds on 2 cores. Without it, the full
    /// matrix (1024 px, 16 spp, more values, paper-high): minutes.
    #[arg(long)]
    quick: bool,
    /// Only these cells (comma-separated names, as the table prints them; cells they compare
    /// with are added).
    #[arg(long, value_delimiter = ',')]
    only: Vec<String>,
    /// What the rays meet in every cell: the mesh, or the exact displaced surface inside the
    /// coarse tessellation's triangles (cells it cannot render, vertex normals and
    /// paper-high, are left out; docs/exact.md).
    #[arg(long, value_parser = super::choice::<vastocean::config::SurfaceKind>(), default_value = "mesh")]
    surface: vastocean::config::SurfaceKind,
    /// How every cell's ocean is read between grid points (docs/ocean.md, "Reading the
    /// layers"); the exact surface takes bilinear or prefiltered.
    #[arg(long, value_parser = super::choice::<vastocean::ocean::Interp>(), default_value_t = vastocean::ocean::Interp::default())]
    interp: vastocean::ocean::Interp,
    /// Folder for stress.csv.
    #[arg(long, default_value = "out/stress")]
    out: PathBuf,
    /// Worker threads (0 = all cores).
    #[arg(long, default_value_t = 0, value_parser = super::threads_arg)]
    threads: usize,
    /// Print the report as JSON.
    #[arg(long)]
    json: bool,
}

pub fn stress(a: StressArgs) -> Result<()> {
    let mut job = if a.quick {
        StressJob::quick(a.out)
    } else {
        StressJob::full(a.out)
    };
    job.progress = true;
    job.reading(a.interp);
    if a.surface == vastocean::config::SurfaceKind::Exact {
        job.on_exact_surface();
    }
    if !a.only.is_empty() {
        job.select(&a.only)?;
    }
    for c in &mut job.cells {
        c.scene.render.threads = a.threads;
    }
    let r = run(&job)?;
    emit(&r, a.json)?;
    anyhow::ensure!(
        r.failed == 0,
        "{} of {} stress cells failed (see {})",
        r.failed,
        r.cells,
        r.csv.display()
    );
    Ok(())
}
