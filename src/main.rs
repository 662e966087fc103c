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
    /// Render a scene: ocean -> LOD tessellation -> BVH (Embree or Rust) -> path tracing -> EXR + PNG + JSON.
    Render(RenderArgs),
    /// The paper's four scenarios (high/low tessellation x with/without normal mapping) and the
    /// near-horizon statistics against the baseline.
    Compare(CompareArgs),
    /// Trace the same rays through Embree and the pure-Rust BVH and report where they disagree;
    /// also render a small scene with both.
    #[cfg(feature = "embree")]
    Crosscheck(CrosscheckArgs),
    /// Tessellate the ocean with the LOD doubling method and report (or export) the mesh.
    Mesh(MeshArgs),
    /// Generate the ocean layers (TMA spectrum, FFT) and report their statistics.
    Ocean(OceanArgs),
    /// Sky maps: generate (Preetham clear, CIE overcast, partly cloudy), import an HDR
    /// photograph with the ground removed, report statistics, make a contact sheet.
    Sky(SkyArgs),
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

/// Scene flags shared by `render` and `compare`: a scene file and the settings most often
/// changed on the command line, which override it.
#[derive(clap::Args)]
struct SceneFlags {
    /// Scene file (TOML); the flags below override it. Without one, the default scene.
    #[arg(long)]
    config: Option<std::path::PathBuf>,
    /// Wind speed at 10 m, m/s.
    #[arg(long)]
    wind: Option<f64>,
    /// Fetch, km.
    #[arg(long)]
    fetch: Option<f64>,
    /// Water depth, m.
    #[arg(long)]
    depth: Option<f64>,
    /// Scale the ocean to this RMS wave height, m.
    #[arg(long)]
    rms: Option<f64>,
    /// Equirectangular EXR sky map (instead of the built-in analytic sky).
    #[arg(long)]
    sky: Option<std::path::PathBuf>,
    /// Image width in pixels (the full 360 degree width for the equirectangular camera).
    #[arg(long)]
    width: Option<usize>,
    /// Samples per pixel.
    #[arg(long)]
    spp: Option<u32>,
    /// Sample seed (the ocean's realization is `render.ocean_seed` in the scene file).
    #[arg(long)]
    seed: Option<u64>,
    /// Camera height above the sea, m.
    #[arg(long)]
    camera_height: Option<f64>,
    /// Worker threads (0 = all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// The BVH: Debian's Embree or the pure-Rust one.
    #[arg(long, value_enum)]
    backend: Option<vastocean::config::Backend>,
}

impl SceneFlags {
    /// The scene file (or the default scene) with the flags applied.
    fn scene(&self) -> Result<vastocean::config::SceneConfig> {
        let mut s = match &self.config {
            Some(path) => {
                vastocean::config::SceneConfig::load(path).map_err(|e| BadInput(e.to_string()))?
            }
            None => vastocean::config::SceneConfig::default(),
        };
        let set = |field: &mut f64, v: Option<f64>| {
            if let Some(v) = v {
                *field = v;
            }
        };
        set(&mut s.ocean.wind_speed, self.wind);
        set(&mut s.ocean.fetch_km, self.fetch);
        set(&mut s.ocean.depth_m, self.depth);
        set(&mut s.camera.height_m, self.camera_height);
        if self.rms.is_some() {
            s.ocean.rms_m = self.rms;
        }
        if self.sky.is_some() {
            s.sky.file = self.sky.clone();
        }
        s.camera.width = self.width.unwrap_or(s.camera.width);
        s.render.spp = self.spp.unwrap_or(s.render.spp);
        s.render.seed = self.seed.unwrap_or(s.render.seed);
        s.render.threads = self.threads.unwrap_or(s.render.threads);
        s.render.backend = self.backend.unwrap_or(s.render.backend);
        Ok(s)
    }
}

#[derive(clap::Args)]
#[command(allow_negative_numbers = true)]
struct RenderArgs {
    #[command(flatten)]
    scene: SceneFlags,
    /// Tessellation: the paper's presets, or chosen from the pixel footprint.
    #[arg(long, value_enum)]
    lod: Option<vastocean::config::LodChoice>,
    /// Shading normals: interpolated vertex normals, or recomputed from the ocean (normal mapping).
    #[arg(long, value_enum)]
    normals: Option<vastocean::render::NormalMode>,
    /// Render only the elevations TOP:BOTTOM in degrees, e.g. +1:-6 (equirectangular camera).
    #[arg(long, value_parser = parse_band, allow_hyphen_values = true)]
    band: Option<(f64, f64)>,
    /// Output prefix: writes PREFIX.exr, PREFIX.png and PREFIX.json.
    #[arg(long, default_value = "out/render")]
    out: std::path::PathBuf,
    /// Print the JSON sidecar on stdout.
    #[arg(long)]
    json: bool,
}

#[derive(clap::Args)]
#[command(allow_negative_numbers = true)]
struct CompareArgs {
    #[command(flatten)]
    scene: SceneFlags,
    /// Rendered elevations TOP:BOTTOM in degrees (default +1:-6).
    #[arg(long, value_parser = parse_band, allow_hyphen_values = true)]
    band: Option<(f64, f64)>,
    /// Analysed elevations TOP:BOTTOM (the paper: 0:-5).
    #[arg(long, value_parser = parse_band, allow_hyphen_values = true, default_value = "0:-5")]
    rows: (f64, f64),
    /// The high tessellation (baseline).
    #[arg(long, value_enum, default_value_t = vastocean::config::LodChoice::PaperHigh)]
    high: vastocean::config::LodChoice,
    /// The low tessellation.
    #[arg(long, value_enum, default_value_t = vastocean::config::LodChoice::PaperLow)]
    low: vastocean::config::LodChoice,
    /// Output folder.
    #[arg(long)]
    out: std::path::PathBuf,
    /// Print summary.json on stdout.
    #[arg(long)]
    json: bool,
}

fn compare(a: CompareArgs) -> Result<()> {
    use vastocean::analysis::{CompareError, CompareOptions, compare};
    use vastocean::config::LodConfig;
    use vastocean::render::Projection;

    let mut scene = a.scene.scene()?;
    let band = match (a.band, scene.camera.projection) {
        (Some(b), _) => b,
        (None, Projection::Equirect { band_deg: Some(b) }) => b,
        _ => (1.0, -6.0),
    };
    scene.camera.projection = Projection::Equirect {
        band_deg: Some(band),
    };
    let lod = |preset| LodConfig {
        preset,
        ..scene.lod.clone()
    };
    let opts = CompareOptions {
        high: lod(a.high),
        low: lod(a.low),
        scene,
        rows_deg: a.rows,
    };
    for lod in [&opts.high, &opts.low] {
        let mut c = opts.scene.clone();
        c.lod = lod.clone();
        c.validate().map_err(|e| BadInput(e.to_string()))?;
    }
    let s = compare(&opts, &a.out, true).map_err(|e| match e {
        CompareError::Invalid(m) => anyhow::Error::new(BadInput(m)),
        e => e.into(),
    })?;
    if a.json {
        println!("{}", serde_json::to_string_pretty(&s)?);
        return Ok(());
    }
    println!(
        "compare: {} rows from {} to {} degrees; band-averaged std of the luminance difference from the baseline:",
        s.rows, s.rows_deg.0, s.rows_deg.1
    );
    println!("  high tessellation, unmapped  {:.5}", s.std_high_unmapped);
    println!("  low tessellation, mapped     {:.5}", s.std_low_mapped);
    println!("  low tessellation, unmapped   {:.5}", s.std_low_unmapped);
    println!("  noise floor                  {:.5}", s.std_noise_floor);
    println!(
        "  improvement ratio (low unmapped / low mapped): {:.2}",
        s.improvement_ratio
    );
    for sc in &s.scenarios {
        println!(
            "  {:<14} {:>9} triangles  tessellation {:.2} s  BVH {:.2} s  render {:.2} s",
            sc.name, sc.triangles, sc.seconds_tessellation, sc.seconds_build, sc.seconds_render
        );
    }
    println!(
        "  wrote {} {} {} and the renders in {}",
        s.stats_csv.display(),
        s.stats_png.display(),
        s.sheet_png.display(),
        a.out.display()
    );
    Ok(())
}

#[cfg(feature = "embree")]
#[derive(clap::Args)]
struct CrosscheckArgs {
    /// The ocean mesh to trace (the default case-22 ocean, camera 2 m up).
    #[arg(long, value_enum, default_value_t = vastocean::config::LodChoice::PaperLow)]
    lod: vastocean::config::LodChoice,
    /// Random rays aimed into the mesh's bounds (the camera rays of the small render come on top).
    #[arg(long, default_value_t = 1_000_000)]
    rays: usize,
    /// Width of the small 360 degree render whose camera rays are traced too and which is
    /// rendered with both backends.
    #[arg(long, default_value_t = 256)]
    width: usize,
    /// Samples per pixel of the small render.
    #[arg(long, default_value_t = 2)]
    spp: u32,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Worker threads (0 = all cores).
    #[arg(long, default_value_t = 0)]
    threads: usize,
    /// Print one JSON object on stdout instead of text.
    #[arg(long)]
    json: bool,
}

#[cfg(feature = "embree")]
fn crosscheck(a: CrosscheckArgs) -> Result<()> {
    use std::sync::Arc;
    use vastocean::accel::Ray;
    use vastocean::accel::crosscheck::{crosscheck, random_rays_over};
    use vastocean::config::{Backend, SceneConfig};
    use vastocean::render::pipeline::render_scene;
    use vastocean::render::{Camera, Projection};

    let mut cfg = SceneConfig::default();
    cfg.lod.preset = a.lod;
    cfg.camera.width = a.width;
    cfg.render.spp = a.spp;
    cfg.render.seed = a.seed;
    cfg.render.threads = a.threads;
    cfg.validate().map_err(|e| BadInput(e.to_string()))?;
    let ocean = Surface::new(&cfg.ocean, cfg.render.ocean_seed)?;
    let (mesh, _) =
        vastocean::lod::tessellate(&cfg.lod_params()?, &ocean.sampler(cfg.camera.position_m))?;
    let mut rays = random_rays_over(&mesh, a.rays, a.seed);
    let camera = Camera::new(Projection::Equirect { band_deg: None }, a.width, 2.0);
    let eye = [0.0, cfg.camera.height_m as f32, 0.0];
    for y in 0..camera.height {
        for x in 0..camera.width {
            rays.push(Ray::new(
                eye,
                camera.direction(x as f32 + 0.5, y as f32 + 0.5).to_array(),
            ));
        }
    }
    let report = crosscheck(Arc::new(mesh), &rays, a.threads)?;

    // The same small render through each backend, same seed: which pixels differ, and by how much.
    let mut images = Vec::new();
    for backend in [Backend::Embree, Backend::Rust] {
        let mut c = cfg.clone();
        c.render.backend = backend;
        images.push(render_scene(&c, false)?.image);
    }
    let lum = vastocean::analysis::luminance;
    let pairs = images[0].pixels.iter().zip(&images[1].pixels);
    let differing = pairs
        .clone()
        .filter(|(p, q)| p.map(f32::to_bits) != q.map(f32::to_bits))
        .count();
    let max_diff = pairs
        .clone()
        .map(|(p, q)| (lum(*p) - lum(*q)).abs())
        .fold(0f32, f32::max);
    let mean_abs_diff = pairs
        .map(|(p, q)| (lum(*p) - lum(*q)).abs() as f64)
        .sum::<f64>()
        / images[0].pixels.len() as f64;
    let mean_lum = images[0].pixels.iter().map(|p| lum(*p) as f64).sum::<f64>()
        / images[0].pixels.len() as f64;
    let pixels = images[0].pixels.len();

    if a.json {
        let mut v = serde_json::to_value(&report)?;
        v["camera_rays"] = serde_json::json!(camera.width * camera.height);
        v["render_pixels"] = serde_json::json!(pixels);
        v["render_differing_fraction"] = serde_json::json!(differing as f64 / pixels as f64);
        v["render_max_luminance_difference"] = serde_json::json!(max_diff);
        v["render_mean_luminance"] = serde_json::json!(mean_lum);
        v["render_mean_abs_luminance_difference"] = serde_json::json!(mean_abs_diff);
        println!("{}", serde_json::to_string_pretty(&v)?);
        return Ok(());
    }
    println!(
        "crosscheck on {:?} ({} rays, {} of them camera rays):",
        a.lod,
        report.rays,
        camera.width * camera.height
    );
    println!(
        "  agree {:.6} (same triangle {}, both miss {}), disagreements {}: {} explained (edge/vertex or tie), {} unexplained",
        report.agree_fraction,
        report.same_prim,
        report.both_miss,
        report.disagreements,
        report.explained_disagreements,
        report.unexplained_disagreements
    );
    println!(
        "  max relative t difference on agreeing hits {:.2e}",
        report.max_rel_dt
    );
    println!(
        "  build: Embree {:.3} s, Rust {:.3} s; trace: Embree {:.2} Mrays/s, Rust {:.2} Mrays/s",
        report.embree_build_s,
        report.rust_build_s,
        report.embree_mrays_per_s,
        report.rust_mrays_per_s
    );
    println!(
        "  render {} x {} at {} spp with each backend: {} of {} pixels differ ({:.4}%), mean absolute luminance difference {:.3e}, largest {:.3e} (mean luminance {:.3e})",
        camera.width,
        camera.height,
        a.spp,
        differing,
        pixels,
        100.0 * differing as f64 / pixels as f64,
        mean_abs_diff,
        max_diff,
        mean_lum
    );
    println!(
        "  (rays that agree up to rounding can still flip a Fresnel-weighted random branch or graze a sun glint, so single pixels of a few-sample render may differ a lot)"
    );
    if report.unexplained_disagreements > 0 {
        anyhow::bail!(
            "{} unexplained disagreements between Embree and the Rust BVH",
            report.unexplained_disagreements
        );
    }
    Ok(())
}

fn parse_band(s: &str) -> Result<(f64, f64), String> {
    let (a, b) = s
        .split_once(':')
        .ok_or_else(|| format!("band {s:?} is not TOP:BOTTOM (degrees, e.g. +1:-6)"))?;
    let num = |x: &str| {
        x.trim()
            .trim_start_matches('+')
            .parse::<f64>()
            .map_err(|e| format!("band {s:?}: {e}"))
    };
    Ok((num(a)?, num(b)?))
}

fn render(a: RenderArgs) -> Result<()> {
    use vastocean::render::Projection;
    use vastocean::render::pipeline::{RenderError, render_scene, write_outputs};

    let mut cfg = a.scene.scene()?;
    if let Some(l) = a.lod {
        cfg.lod.preset = l;
    }
    if let Some(n) = a.normals {
        cfg.render.normals = n;
    }
    if let Some(b) = a.band {
        cfg.camera.projection = match cfg.camera.projection {
            Projection::Equirect { .. } => Projection::Equirect { band_deg: Some(b) },
            Projection::Pinhole { .. } => {
                return Err(
                    BadInput("--band applies to the equirectangular camera only".into()).into(),
                );
            }
        };
    }
    cfg.validate().map_err(|e| BadInput(e.to_string()))?;
    let mut r = render_scene(&cfg, true).map_err(|e| match e {
        // A sky file that is missing or not a sky map is bad input, not a crash.
        RenderError::Image(e) => anyhow::Error::new(BadInput(e.to_string())),
        RenderError::NoEmbree => anyhow::Error::new(BadInput(RenderError::NoEmbree.to_string())),
        e => e.into(),
    })?;
    write_outputs(&mut r, &a.out)?;
    let rep = &r.report;
    if a.json {
        println!("{}", serde_json::to_string_pretty(rep)?);
    } else {
        println!(
            "rendered {} x {} at {} spp: {} triangles ({}), {:.1} M rays at {:.2} Mrays/s",
            rep.width,
            rep.height,
            rep.spp,
            rep.triangles,
            rep.embree_version
                .as_deref()
                .map_or_else(|| "Rust BVH".to_string(), |v| format!("Embree {v}")),
            rep.rays as f64 / 1e6,
            rep.mrays_per_s
        );
        println!(
            "  seconds: ocean {:.2}, tessellation {:.2}, BVH {:.2}, trace {:.2} (normal mapping ~{:.2}, {:.1}%), total {:.2}",
            rep.seconds_ocean,
            rep.seconds_tessellation,
            rep.seconds_build,
            rep.seconds_trace,
            rep.seconds_normal_map,
            100.0 * rep.normal_map_share,
            rep.seconds_total
        );
        println!(
            "  NaN samples {}, wrong-side directions {}, truncated paths {}",
            rep.nan_count, rep.wrong_side_count, rep.truncated_paths
        );
        println!(
            "  wrote {} {} {}",
            rep.exr.display(),
            rep.png.display(),
            rep.json.display()
        );
    }
    Ok(())
}

#[derive(clap::Args)]
#[command(allow_negative_numbers = true)]
struct MeshArgs {
    /// Start from one of the paper's tessellations (flags below override it).
    #[arg(long, value_enum, default_value_t = vastocean::lod::Preset::PaperLow)]
    lod: vastocean::lod::Preset,
    /// Triangle size next to the camera, m.
    #[arg(long)]
    near_size: Option<f64>,
    /// Double distance, m.
    #[arg(long)]
    double_distance: Option<f64>,
    /// Most doublings (generations).
    #[arg(long)]
    generations: Option<u32>,
    /// Where the tessellation ends, m (default: just past the horizon).
    #[arg(long)]
    max_distance: Option<f64>,
    /// Camera height above the sea, m.
    #[arg(long, default_value_t = 2.0)]
    camera_height: f64,
    /// `square` (all directions) or `frustum:YAW_DEG:HFOV_DEG` (a perspective camera's view).
    #[arg(long, default_value = "square")]
    pattern: vastocean::lod::Pattern,
    /// How the paper's doubling rule is read (see the README).
    #[arg(long, value_enum)]
    reading: Option<vastocean::lod::Reading>,
    /// Seed of the ocean sampled at every vertex (the default case-22 ocean).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Count the triangles without building the mesh.
    #[arg(long)]
    count_only: bool,
    /// Write the mesh as binary PLY (positions, normals, texture coordinates).
    #[arg(long)]
    ply: Option<std::path::PathBuf>,
    /// Print one JSON object on stdout instead of text.
    #[arg(long)]
    json: bool,
}

fn mesh(a: MeshArgs) -> Result<()> {
    let mut p = a.lod.params(a.camera_height);
    if let Some(v) = a.near_size {
        p.near_size_m = v;
    }
    if let Some(v) = a.double_distance {
        p.double_distance_m = v;
    }
    if a.generations.is_some() {
        p.generations = a.generations;
    }
    if a.max_distance.is_some() {
        p.max_distance_m = a.max_distance;
    }
    if let Some(r) = a.reading {
        p.reading = r;
    }
    p.pattern = a.pattern;
    p.validate().map_err(|e| BadInput(e.to_string()))?;
    if a.count_only {
        let (triangles, vertices) =
            vastocean::lod::try_count(&p).map_err(|e| BadInput(e.to_string()))?;
        let out = serde_json::json!({ "triangles": triangles, "vertices": vertices, "max_distance_m": p.max_distance(), "params": p });
        if a.json {
            println!("{}", serde_json::to_string_pretty(&out)?);
        } else {
            println!(
                "{triangles} triangles, {vertices} vertices out to {:.0} m",
                p.max_distance()
            );
        }
        return Ok(());
    }
    let ocean = Surface::new(&OceanParams::default(), a.seed)?;
    let (mesh, stats) = vastocean::lod::tessellate(&p, &ocean.sampler([0.0, 0.0]))?;
    if let Some(path) = &a.ply {
        vastocean::mesh::write_ply(&mesh, path)?;
    }
    if a.json {
        println!(
            "{}",
            serde_json::to_string_pretty(
                &serde_json::json!({ "stats": &stats, "triangles": stats.triangles, "vertices": stats.vertices, "rings": stats.rings, "max_distance_m": stats.max_distance_m, "seconds": stats.seconds, "bytes": stats.bytes, "params": p })
            )?
        );
        return Ok(());
    }
    println!(
        "LOD {:?}, reading {:?}, pattern {}: {} triangles, {} vertices, {} rings out to {:.0} m, {:.1} MB, {:.2} s",
        a.lod,
        p.reading,
        p.pattern,
        stats.triangles,
        stats.vertices,
        stats.rings,
        stats.max_distance_m,
        stats.bytes as f64 / 1e6,
        stats.seconds
    );
    println!("  ring   triangle size (m)   from (m)     to (m)   triangles");
    for (i, r) in stats.per_ring.iter().enumerate() {
        println!(
            "  {i:>4} {:>19.3} {:>10.1} {:>10.1} {:>11}",
            r.size_m, r.inner_m, r.outer_m, r.triangles
        );
    }
    if let Some(path) = &a.ply {
        println!("  wrote {}", path.display());
    }
    Ok(())
}

#[derive(clap::Args)]
struct SkyArgs {
    #[command(subcommand)]
    command: SkyCommand,
}

#[derive(Subcommand)]
enum SkyCommand {
    /// Generate a sky map (half-float EXR).
    Generate(SkyGenerateArgs),
    /// Import an equirectangular HDR photograph: remove the ground, optionally rotate the sun.
    Import(SkyImportArgs),
    /// Resolution, mean and peak luminance, sun direction, energy near the horizon.
    Info {
        /// Equirectangular EXR sky map.
        file: std::path::PathBuf,
        /// Print one JSON object on stdout instead of text.
        #[arg(long)]
        json: bool,
    },
    /// A tone-mapped PNG contact sheet of sky maps, in the order given.
    Sheet {
        /// Equirectangular EXR sky maps.
        #[arg(required = true)]
        files: Vec<std::path::PathBuf>,
        /// Width of each thumbnail, pixels.
        #[arg(long, default_value_t = 384)]
        thumb_width: usize,
        /// Thumbnails per row.
        #[arg(long, default_value_t = 3)]
        columns: usize,
        #[arg(long)]
        out: std::path::PathBuf,
    },
}

#[derive(clap::Args)]
#[command(allow_negative_numbers = true)]
struct SkyGenerateArgs {
    #[arg(long, value_enum)]
    kind: vastocean::render::sky_gen::SkyKind,
    /// Sun elevation above the horizon, degrees (0..=90; sets the overcast sky's brightness).
    #[arg(long)]
    sun_elevation: f64,
    /// Sun azimuth, degrees (0 = +x, 90 = +z).
    #[arg(long, default_value_t = 180.0)]
    sun_azimuth: f64,
    /// Atmospheric turbidity (Preetham: 2 very clear, 6 hazy).
    #[arg(long, default_value_t = 2.5)]
    turbidity: f64,
    /// Covered fraction of the cloud layer (partly cloudy).
    #[arg(long, default_value_t = 0.4)]
    cloud_cover: f64,
    /// Seed of the clouds (partly cloudy).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Map width, texels (height = width / 2).
    #[arg(long, default_value_t = 1024)]
    width: usize,
    #[arg(long)]
    out: std::path::PathBuf,
}

#[derive(clap::Args)]
#[command(allow_negative_numbers = true)]
struct SkyImportArgs {
    /// Equirectangular HDR photograph (EXR, horizon at the middle row).
    photo: std::path::PathBuf,
    #[arg(long)]
    out: std::path::PathBuf,
    /// What to put below the horizon.
    #[arg(long, value_enum, default_value_t = vastocean::render::sky_tools::Ground::Fill)]
    ground: vastocean::render::sky_tools::Ground,
    /// Rotate the map in azimuth so the brightest region (the sun) lands here, degrees.
    #[arg(long)]
    sun_azimuth: Option<f64>,
    /// Set negative components (left by colour-space conversions) to zero instead of refusing.
    #[arg(long)]
    clamp_negative: bool,
}

fn sky(a: SkyArgs) -> Result<()> {
    use vastocean::image_io::{read_exr, write_exr_half, write_png_rgb8};
    use vastocean::render::{sky::validate_map, sky_gen, sky_tools};
    let load = |path: &std::path::Path| -> Result<vastocean::image_io::RgbImage> {
        let img = read_exr(path).map_err(|e| BadInput(e.to_string()))?;
        validate_map(path, &img).map_err(|e| BadInput(e.to_string()))?;
        Ok(img)
    };
    match a.command {
        SkyCommand::Generate(g) => {
            let params = sky_gen::SkyParams {
                kind: g.kind,
                sun_elevation_deg: g.sun_elevation,
                sun_azimuth_deg: g.sun_azimuth,
                turbidity: g.turbidity,
                cloud_cover: g.cloud_cover,
                seed: g.seed,
            };
            let img = sky_gen::generate(&params, g.width).map_err(|e| BadInput(e.to_string()))?;
            write_exr_half(&g.out, &img)?;
            eprintln!("wrote {} ({} x {})", g.out.display(), img.width, img.height);
        }
        SkyCommand::Import(i) => {
            let mut img = read_exr(&i.photo).map_err(|e| BadInput(e.to_string()))?;
            if i.clamp_negative {
                let (n, worst) = sky_tools::clamp_negative(&mut img);
                if n > 0 {
                    eprintln!(
                        "{}: set {n} negative components (down to {worst:e}) to zero",
                        i.photo.display()
                    );
                }
            }
            validate_map(&i.photo, &img).map_err(|e| BadInput(e.to_string()))?;
            if let Some(az) = i.sun_azimuth {
                if !az.is_finite() {
                    return Err(BadInput(format!("--sun-azimuth {az} is not finite")).into());
                }
                let r = sky_tools::rotate_sun_to(&mut img, az);
                eprintln!("rotated {} by {r:.2} degrees in azimuth", i.photo.display());
            }
            sky_tools::remove_ground(&mut img, i.ground);
            write_exr_half(&i.out, &img)?;
            eprintln!("wrote {} ({} x {})", i.out.display(), img.width, img.height);
        }
        SkyCommand::Info { file, json } => {
            let s = sky_tools::info(&load(&file)?);
            if json {
                println!("{}", serde_json::to_string_pretty(&s)?);
            } else {
                println!("{}: {} x {}", file.display(), s.width, s.height);
                println!("  mean luminance          {:.6}", s.mean_radiance);
                println!("  peak luminance          {:.6}", s.peak_radiance);
                println!(
                    "  sun (brightest region)  elevation {:.2} deg, azimuth {:.2} deg",
                    s.sun_elevation_deg, s.sun_azimuth_deg
                );
                println!(
                    "  energy within 5 deg of the horizon  {:.4}",
                    s.horizon_energy_fraction
                );
            }
        }
        SkyCommand::Sheet {
            files,
            thumb_width,
            columns,
            out,
        } => {
            if thumb_width < 2 || !thumb_width.is_multiple_of(2) || columns == 0 {
                return Err(BadInput(format!(
                    "--thumb-width must be even and >= 2 and --columns >= 1 (got {thumb_width}, {columns})"
                ))
                .into());
            }
            let maps = files.iter().map(|f| load(f)).collect::<Result<Vec<_>>>()?;
            let (w, h, rgb) = sky_tools::contact_sheet(&maps, thumb_width, columns);
            write_png_rgb8(&out, w, h, &rgb)?;
            eprintln!("wrote {} ({w} x {h})", out.display());
        }
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
            "rust",
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
        Command::Mesh(a) => mesh(a),
        #[cfg(feature = "embree")]
        Command::Crosscheck(a) => crosscheck(a),
        Command::Sky(a) => sky(a),
        Command::Compare(a) => compare(a),
        Command::Render(a) => render(a),
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
