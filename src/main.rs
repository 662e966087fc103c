//! The `vastocean` command line: parse (clap) -> validated configuration -> run. Exit codes:
//! 0 success, 2 bad input (arguments, configuration, files), 1 failure while running.

use std::process::ExitCode;

use anyhow::Result;
use clap::{Parser, Subcommand};
use serde::Serialize;
#[cfg(feature = "embree")]
use vastocean::accel::embree::Quality;
use vastocean::ocean::{LayerSpec, OceanParams, Surface};

#[derive(Parser)]
#[command(
    name = "vastocean",
    version,
    about = "Renderer for vast ocean scenes (FFT ocean layers, LOD to the horizon, Embree, normal mapping)"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Print what this build has: versions, Embree's ISA and thread count.
    Info {
        /// Threads Embree may use (0 = all cores).
        #[arg(long, default_value_t = 0)]
        threads: usize,
        /// Print one JSON object on stdout instead of text.
        #[arg(long)]
        json: bool,
    },
    /// Generate the ocean layers (TMA spectrum, FFT) and report their statistics.
    Ocean(OceanArgs),
    /// Embree smoke run: build a BVH over a wavy grid and trace random rays down onto it.
    #[cfg(feature = "embree")]
    Smoke {
        /// Grid cells per side (two triangles per cell).
        #[arg(long, default_value_t = 1000)]
        cells: u32,
        /// Number of rays to trace.
        #[arg(long, default_value_t = 1_000_000)]
        rays: usize,
        /// BVH build quality.
        #[arg(long, value_enum, default_value_t = Quality::Medium)]
        quality: Quality,
        /// Threads for Embree and the tracer (0 = all cores).
        #[arg(long, default_value_t = 0)]
        threads: usize,
        /// Print one JSON object on stdout instead of text.
        #[arg(long)]
        json: bool,
    },
}

#[derive(clap::Args)]
// Negative numbers are values, so that `--wind -1` reaches validation and its named error.
#[command(allow_negative_numbers = true)]
struct OceanArgs {
    /// Wind speed at 10 m, m/s.
    #[arg(long, default_value_t = OceanParams::default().wind_speed)]
    wind: f64,
    /// Fetch, km.
    #[arg(long, default_value_t = OceanParams::default().fetch_km)]
    fetch: f64,
    /// Water depth, m.
    #[arg(long, default_value_t = OceanParams::default().depth_m)]
    depth: f64,
    /// Scale the realization to this RMS height, m (the paper's Table 1 gives one per case).
    #[arg(long)]
    rms: Option<f64>,
    /// Layers as SIZE_M:N pairs, coarsest first, e.g. 400:512,47.3:512,5.83:256.
    #[arg(long, value_parser = parse_layers)]
    layers: Option<Layers>,
    /// Horizontal displacement scale f_d (paper eq. 3); 0 = pure height field.
    #[arg(long, default_value_t = OceanParams::default().choppiness)]
    choppiness: f64,
    /// Time t of paper eq. 2, s.
    #[arg(long, default_value_t = 0.0)]
    time: f64,
    /// Random seed of the realization.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Write a height / shaded-normal preview PNG here.
    #[arg(long)]
    png: Option<std::path::PathBuf>,
    /// Preview extent, metres (default: the coarsest layer's size).
    #[arg(long)]
    png_extent: Option<f64>,
    /// Print one JSON object on stdout instead of text.
    #[arg(long)]
    json: bool,
}

/// A newtype so clap treats the whole list as one value.
#[derive(Clone, Debug)]
struct Layers(Vec<LayerSpec>);

fn parse_layers(s: &str) -> Result<Layers, String> {
    s.split(',')
        .map(|pair| {
            let (size, n) = pair
                .split_once(':')
                .ok_or_else(|| format!("layer {pair:?} is not SIZE_M:N"))?;
            let size_m = size
                .trim()
                .parse::<f64>()
                .map_err(|e| format!("layer size {size:?}: {e}"))?;
            let n = n
                .trim()
                .parse::<usize>()
                .map_err(|e| format!("layer grid {n:?}: {e}"))?;
            Ok(LayerSpec { size_m, n })
        })
        .collect::<Result<_, _>>()
        .map(Layers)
}

fn ocean(a: OceanArgs) -> Result<()> {
    let defaults = OceanParams::default();
    let params = OceanParams {
        wind_speed: a.wind,
        fetch_km: a.fetch,
        depth_m: a.depth,
        rms_m: a.rms,
        choppiness: a.choppiness,
        time_s: a.time,
        layers: a.layers.map_or(defaults.layers.clone(), |l| l.0),
        ..defaults
    };
    params.validate().map_err(|e| BadInput(e.to_string()))?;
    let surface = Surface::new(&params, a.seed)?;
    let s = surface.summary();
    if let Some(path) = &a.png {
        let extent = a.png_extent.unwrap_or(params.layers[0].size_m);
        vastocean::ocean::write_preview_png(&surface, path, 1024, extent)?;
    }
    if a.json {
        println!("{}", serde_json::to_string_pretty(&s)?);
        return Ok(());
    }
    println!(
        "ocean: wind {} m/s, fetch {} km, depth {} m, seed {}",
        params.wind_speed, params.fetch_km, params.depth_m, a.seed
    );
    println!(
        "  layer   size (m)     n   spacing (m)   band k (rad/m)      spectrum RMS   realization RMS"
    );
    for (i, l) in s.layers.iter().enumerate() {
        println!(
            "  {i:>5} {:>10.2} {:>5} {:>13.4} {:>9.3} - {:<9.3} {:>11.4} m {:>15.4} m",
            l.size_m, l.n, l.spacing_m, l.k_min, l.k_max, l.spectrum_rms_m, l.realization_rms_m
        );
    }
    println!(
        "  spectrum RMS      {:.4} m (over the layers' bands; model spectrum {:.4} m, amplitude scale {:.4})",
        s.spectrum_rms_m, s.model_rms_m, s.amplitude_scale
    );
    println!(
        "  realization RMS   {:.4} m (sampled surface {:.4} m)",
        s.realization_rms_m, s.sampled_rms_m
    );
    println!("  Hs                {:.3} m", s.hs_m);
    println!("  peak wavelength   {:.2} m", s.peak_wavelength_m);
    println!("  folded fraction   {:.5}", s.folded_fraction);
    println!("  generated in      {:.3} s", s.seconds);
    if s.folded_fraction > 0.0 {
        eprintln!(
            "warning: {:.3}% of the surface folds over itself (Jacobian <= 0); lower --choppiness to avoid it",
            100.0 * s.folded_fraction
        );
    }
    if let Some(p) = &a.png {
        println!("  preview           {}", p.display());
    }
    Ok(())
}

/// Errors in what the user gave us (exit code 2), as opposed to failures while running.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
struct BadInput(String);

#[derive(Serialize)]
struct Info {
    vastocean: &'static str,
    backends: Vec<&'static str>,
    #[cfg(feature = "embree")]
    embree: vastocean::accel::embree::EmbreeInfo,
    cores: usize,
}

#[cfg_attr(not(feature = "embree"), allow(unused_variables))]
fn info(threads: usize, json: bool) -> Result<()> {
    let info = Info {
        vastocean: env!("CARGO_PKG_VERSION"),
        backends: vec![
            #[cfg(feature = "embree")]
            "embree",
            "brute",
        ],
        #[cfg(feature = "embree")]
        embree: vastocean::accel::embree::describe(threads)?,
        cores: std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1),
    };
    if json {
        println!("{}", serde_json::to_string_pretty(&info)?);
    } else {
        println!("vastocean {}", info.vastocean);
        println!("backends:  {}", info.backends.join(", "));
        #[cfg(feature = "embree")]
        {
            let e = &info.embree;
            println!(
                "embree:    {} (compiled against {} headers)",
                e.version, e.compiled_against
            );
            println!("isa:       {}", e.targets);
            println!(
                "threads:   {}",
                e.threads.map_or("?".into(), |t| t.to_string())
            );
            println!("tasking:   {}", e.tasking);
        }
        println!("cores:     {}", info.cores);
    }
    Ok(())
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Info { threads, json } => info(threads, json),
        Command::Ocean(a) => ocean(a),
        #[cfg(feature = "embree")]
        Command::Smoke {
            cells,
            rays,
            quality,
            threads,
            json,
        } => smoke(cells, rays, quality, threads, json),
    }
}

#[cfg(feature = "embree")]
fn smoke(cells: u32, rays: usize, quality: Quality, threads: usize, json: bool) -> Result<()> {
    use rayon::prelude::*;
    use std::sync::Arc;
    use std::time::Instant;
    use vastocean::accel::embree::{BuildOptions, Device, Scene, flush_denormals_on_this_thread};
    use vastocean::accel::{Accel, Ray};
    use vastocean::rng::Rng;

    if cells == 0 || cells > 20_000 {
        return Err(BadInput(format!("--cells must be in 1..=20000 (got {cells})")).into());
    }
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .start_handler(|_| flush_denormals_on_this_thread())
        .build()?;
    let t0 = Instant::now();
    let flat = vastocean::mesh::Mesh::grid(cells, cells, 1.0);
    // A gentle swell so rays meet sloped triangles, not one plane.
    let positions: Vec<[f32; 3]> = flat
        .positions()
        .iter()
        .map(|p| [p[0], 0.3 * (0.37 * p[0]).sin() * (0.23 * p[2]).cos(), p[2]])
        .collect();
    let mesh = Arc::new(vastocean::mesh::Mesh::new(
        positions,
        vec![],
        flat.uvs().to_vec(),
        flat.indices().to_vec(),
    )?);
    let mesh_s = t0.elapsed().as_secs_f64();
    let device = Device::new(threads)?;
    let scene = Scene::new(
        &device,
        mesh.clone(),
        BuildOptions {
            quality,
            ..Default::default()
        },
    )?;
    let extent = cells as f32;
    let mut batch: Vec<Ray> = (0..rays)
        .map(|i| {
            let mut r = Rng::keyed(&[42, i as u64]);
            let org = [
                r.range(-0.1, 1.1) * extent,
                5.0,
                r.range(-0.1, 1.1) * extent,
            ];
            let d = [r.range(-0.5, 0.5), -1.0, r.range(-0.5, 0.5)];
            let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            Ray::new(org, [d[0] / n, d[1] / n, d[2] / n])
        })
        .collect();
    let mut hits = vec![None; rays];
    let t1 = Instant::now();
    pool.install(|| {
        batch
            .par_chunks_mut(4096)
            .zip(hits.par_chunks_mut(4096))
            .for_each(|(r, h)| scene.intersect_many(r, h));
    });
    let trace_s = t1.elapsed().as_secs_f64();
    let hit_count = hits.iter().flatten().count();
    let mean_t = hits.iter().flatten().map(|h| h.t as f64).sum::<f64>() / hit_count.max(1) as f64;
    let summary = serde_json::json!({
        "embree_version": device.version(),
        "triangles": mesh.triangle_count(),
        "vertices": mesh.vertex_count(),
        "bytes": mesh.bytes(),
        "quality": quality,
        "seconds_mesh": mesh_s,
        "seconds_build": scene.build_seconds(),
        "build_mtris_per_s": mesh.triangle_count() as f64 / scene.build_seconds() / 1e6,
        "rays": rays,
        "hits": hit_count,
        "mean_hit_distance_m": mean_t,
        "seconds_trace": trace_s,
        "mrays_per_s": rays as f64 / trace_s / 1e6,
    });
    if json {
        println!("{}", serde_json::to_string_pretty(&summary)?);
    } else {
        println!(
            "Embree {}: {} triangles built in {:.3} s ({:.1} M triangles/s, {:?} quality)",
            device.version(),
            mesh.triangle_count(),
            scene.build_seconds(),
            summary["build_mtris_per_s"].as_f64().unwrap_or(0.0),
            quality
        );
        println!(
            "{rays} rays: {hit_count} hits ({:.1}%), mean distance {mean_t:.2} m, {:.2} Mrays/s",
            100.0 * hit_count as f64 / rays.max(1) as f64,
            summary["mrays_per_s"].as_f64().unwrap_or(0.0)
        );
    }
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprint!("error: {e}");
            for cause in e.chain().skip(1) {
                eprint!(": {cause}");
            }
            eprintln!();
            if e.chain().any(|c| c.is::<BadInput>()) {
                ExitCode::from(2)
            } else {
                ExitCode::from(1)
            }
        }
    }
}
