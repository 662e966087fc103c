//! Flags (clap derive) and how each command's flags become an `app` job.

use std::path::PathBuf;

use anyhow::Result;
use clap::builder::{PossibleValuesParser, TypedValueParser};
use clap::{Parser, Subcommand};
use vastocean::app;
use vastocean::config::{Choice, LodChoice, LodConfig, NormalMode, Projection, SceneConfig};
use vastocean::ocean::{LayerSpec, OceanParams};

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
pub struct BadInput(String);

/// A flag whose values are the names of a [`Choice`] enum (listed in `--help`).
fn choice<T: Choice + Clone + Send + Sync>() -> impl TypedValueParser<Value = T> {
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
        #[arg(long, default_value_t = 0)]
        threads: usize,
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
    #[command(subcommand)]
    Sky(SkyCommand),
    /// Embree smoke run: build a BVH over a wavy grid and trace random rays down onto it.
    #[cfg(feature = "embree")]
    Smoke(SmokeArgs),
}

pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Info { threads, json } => emit(&app::info::run(threads)?, json),
        Command::Render(a) => emit(&app::render::run(&a.job()?)?, a.json),
        Command::Compare(a) => emit(&app::compare::run(&a.job()?)?, a.json),
        #[cfg(feature = "embree")]
        Command::Crosscheck(a) => crosscheck(a),
        Command::Mesh(a) => emit(&app::mesh::run(&a.job())?, a.json),
        Command::Ocean(a) => {
            let r = app::ocean::run(&a.job())?;
            r.warnings().iter().for_each(|w| eprintln!("warning: {w}"));
            emit(&r, a.json)
        }
        Command::Sky(c) => sky(c),
        #[cfg(feature = "embree")]
        Command::Smoke(a) => emit(&app::smoke::run(&a.job())?, a.json),
    }
}

/// Scene flags shared by `render` and `compare`: a scene file and the settings most often
/// changed on the command line, which override it.
#[derive(clap::Args)]
struct SceneFlags {
    /// Scene file (TOML); the flags below override it. Without one, the default scene.
    #[arg(long)]
    config: Option<PathBuf>,
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
    sky: Option<PathBuf>,
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
    #[arg(long, value_parser = choice::<vastocean::config::Backend>())]
    backend: Option<vastocean::config::Backend>,
}

impl SceneFlags {
    /// The scene file (or the default scene) with the flags applied.
    fn scene(&self) -> Result<SceneConfig> {
        let mut s = match &self.config {
            Some(path) => SceneConfig::load(path).map_err(AppError::from)?,
            None => SceneConfig::default(),
        };
        let set = |field: &mut f64, v: Option<f64>| v.into_iter().for_each(|v| *field = v);
        set(&mut s.ocean.wind_speed, self.wind);
        set(&mut s.ocean.fetch_km, self.fetch);
        set(&mut s.ocean.depth_m, self.depth);
        set(&mut s.camera.height_m, self.camera_height);
        s.ocean.rms_m = self.rms.or(s.ocean.rms_m);
        s.sky.file = self.sky.clone().or(s.sky.file);
        s.camera.width = self.width.unwrap_or(s.camera.width);
        s.render.spp = self.spp.unwrap_or(s.render.spp);
        s.render.seed = self.seed.unwrap_or(s.render.seed);
        s.render.threads = self.threads.unwrap_or(s.render.threads);
        s.render.backend = self.backend.unwrap_or(s.render.backend);
        Ok(s)
    }
}

use app::AppError;

/// An elevation band TOP:BOTTOM in degrees, e.g. +1:-6.
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

#[derive(clap::Args)]
#[command(allow_negative_numbers = true)]
struct RenderArgs {
    #[command(flatten)]
    scene: SceneFlags,
    /// Tessellation: the paper's presets, or chosen from the pixel footprint.
    #[arg(long, value_parser = choice::<LodChoice>())]
    lod: Option<LodChoice>,
    /// Shading normals: interpolated vertex normals, or recomputed from the ocean (normal mapping).
    #[arg(long, value_parser = choice::<NormalMode>())]
    normals: Option<NormalMode>,
    /// Render only the elevations TOP:BOTTOM in degrees, e.g. +1:-6 (equirectangular camera).
    #[arg(long, value_parser = parse_band, allow_hyphen_values = true)]
    band: Option<(f64, f64)>,
    /// Output prefix: writes PREFIX.exr, PREFIX.png and PREFIX.json.
    #[arg(long, default_value = "out/render")]
    out: PathBuf,
    /// Print the JSON sidecar on stdout.
    #[arg(long)]
    json: bool,
}

impl RenderArgs {
    fn job(&self) -> Result<app::render::RenderJob> {
        let mut cfg = self.scene.scene()?;
        cfg.lod.preset = self.lod.unwrap_or(cfg.lod.preset);
        cfg.render.normals = self.normals.unwrap_or(cfg.render.normals);
        if let Some(b) = self.band {
            let Projection::Equirect { .. } = cfg.camera.projection else {
                return Err(
                    BadInput("--band applies to the equirectangular camera only".into()).into(),
                );
            };
            cfg.camera.projection = Projection::Equirect { band_deg: Some(b) };
        }
        Ok(app::render::RenderJob {
            scene: cfg,
            out: self.out.clone(),
            progress: true,
        })
    }
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
    #[arg(long, value_parser = choice::<LodChoice>(), default_value = "paper-high")]
    high: LodChoice,
    /// The low tessellation.
    #[arg(long, value_parser = choice::<LodChoice>(), default_value = "paper-low")]
    low: LodChoice,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
    /// Print summary.json on stdout.
    #[arg(long)]
    json: bool,
}

impl CompareArgs {
    fn job(&self) -> Result<app::compare::CompareJob> {
        let mut scene = self.scene.scene()?;
        let band = match (self.band, scene.camera.projection) {
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
        Ok(app::compare::CompareJob {
            high: lod(self.high),
            low: lod(self.low),
            scene,
            rows_deg: self.rows,
            out: self.out.clone(),
            progress: true,
        })
    }
}

#[cfg(feature = "embree")]
#[derive(clap::Args)]
struct CrosscheckArgs {
    /// The ocean mesh to trace (the default case-22 ocean, camera 2 m up).
    #[arg(long, value_parser = choice::<LodChoice>(), default_value = "paper-low")]
    lod: LodChoice,
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
    #[arg(long)]
    json: bool,
}

#[cfg(feature = "embree")]
fn crosscheck(a: CrosscheckArgs) -> Result<()> {
    let job = app::crosscheck::CrosscheckJob {
        lod: a.lod,
        rays: a.rays,
        width: a.width,
        spp: a.spp,
        seed: a.seed,
        threads: a.threads,
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
#[command(allow_negative_numbers = true)]
struct MeshArgs {
    /// Start from one of the paper's tessellations, or `auto` (flags below override it).
    #[arg(long, value_parser = choice::<LodChoice>(), default_value = "paper-low")]
    lod: LodChoice,
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
    /// Image width `auto` sizes the triangles for.
    #[arg(long, default_value_t = 2048)]
    width: usize,
    /// `square` (all directions) or `frustum:YAW_DEG:HFOV_DEG` (a perspective camera's view).
    #[arg(long, default_value = "square")]
    pattern: vastocean::config::Pattern,
    /// How the paper's doubling rule is read (see the README).
    #[arg(long, value_parser = choice::<vastocean::config::Reading>())]
    reading: Option<vastocean::config::Reading>,
    /// Seed of the ocean sampled at every vertex (the default case-22 ocean).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Count the triangles without building the mesh.
    #[arg(long)]
    count_only: bool,
    /// Write the mesh as binary PLY (positions, normals, texture coordinates).
    #[arg(long)]
    ply: Option<PathBuf>,
    #[arg(long)]
    json: bool,
}

impl MeshArgs {
    fn job(&self) -> app::mesh::MeshJob {
        app::mesh::MeshJob {
            lod: LodConfig {
                preset: self.lod,
                near_size_m: self.near_size,
                double_distance_m: self.double_distance,
                generations: self.generations,
                max_distance_m: self.max_distance,
                reading: self.reading,
            },
            camera: vastocean::config::CameraConfig {
                height_m: self.camera_height,
                width: self.width,
                ..Default::default()
            },
            pattern: self.pattern,
            seed: self.seed,
            count_only: self.count_only,
            ply: self.ply.clone(),
        }
    }
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
    /// Horizontal displacement scale (paper eq. 3's f_d with the crest-sharpening sign); 0 =
    /// pure height field.
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
    png: Option<PathBuf>,
    /// Preview extent, metres (default: the coarsest layer's size).
    #[arg(long)]
    png_extent: Option<f64>,
    #[arg(long)]
    json: bool,
}

/// A newtype so clap treats the whole list as one value.
#[derive(Clone, Debug)]
struct Layers(Vec<LayerSpec>);

fn parse_layers(s: &str) -> Result<Layers, String> {
    let layer = |pair: &str| {
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
    };
    s.split(',')
        .map(layer)
        .collect::<Result<_, String>>()
        .map(Layers)
}

impl OceanArgs {
    fn job(&self) -> app::ocean::OceanJob {
        let defaults = OceanParams::default();
        app::ocean::OceanJob {
            params: OceanParams {
                wind_speed: self.wind,
                fetch_km: self.fetch,
                depth_m: self.depth,
                rms_m: self.rms,
                choppiness: self.choppiness,
                time_s: self.time,
                layers: self.layers.clone().map_or(defaults.layers.clone(), |l| l.0),
                ..defaults
            },
            seed: self.seed,
            png: self.png.clone().map(|p| (p, self.png_extent)),
        }
    }
}

#[derive(Subcommand)]
enum SkyCommand {
    /// Generate a sky map (half-float EXR).
    #[command(allow_negative_numbers = true)]
    Generate {
        #[arg(long, value_parser = choice::<vastocean::sky::procedural::SkyKind>())]
        kind: vastocean::sky::procedural::SkyKind,
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
        out: PathBuf,
    },
    /// Import an equirectangular HDR photograph: remove the ground, optionally rotate the sun.
    #[command(allow_negative_numbers = true)]
    Import {
        /// Equirectangular HDR photograph (EXR, horizon at the middle row).
        photo: PathBuf,
        #[arg(long)]
        out: PathBuf,
        /// What to put below the horizon.
        #[arg(long, value_parser = choice::<vastocean::sky::tools::Ground>(), default_value = "fill")]
        ground: vastocean::sky::tools::Ground,
        /// Rotate the map in azimuth so the brightest region (the sun) lands here, degrees.
        #[arg(long)]
        sun_azimuth: Option<f64>,
        /// Set negative components (left by colour-space conversions) to zero instead of refusing.
        #[arg(long)]
        clamp_negative: bool,
    },
    /// Resolution, mean and peak luminance, sun direction, energy near the horizon.
    Info {
        /// Equirectangular EXR sky map.
        file: PathBuf,
        #[arg(long)]
        json: bool,
    },
    /// A tone-mapped PNG contact sheet of sky maps, in the order given.
    Sheet {
        /// Equirectangular EXR sky maps.
        #[arg(required = true)]
        files: Vec<PathBuf>,
        /// Width of each thumbnail, pixels.
        #[arg(long, default_value_t = 384)]
        thumb_width: usize,
        /// Thumbnails per row.
        #[arg(long, default_value_t = 3)]
        columns: usize,
        #[arg(long)]
        out: PathBuf,
    },
}

fn sky(c: SkyCommand) -> Result<()> {
    match c {
        #[rustfmt::skip]
        SkyCommand::Generate { kind, sun_elevation, sun_azimuth, turbidity, cloud_cover, seed, width, out } => {
            let params = vastocean::sky::procedural::SkyParams {
                kind,
                sun_elevation_deg: sun_elevation,
                sun_azimuth_deg: sun_azimuth,
                turbidity,
                cloud_cover,
                seed,
            };
            let (w, h) = app::sky::generate(&params, width, &out)?;
            eprintln!("wrote {} ({w} x {h})", out.display());
        }
        #[rustfmt::skip]
        SkyCommand::Import { photo, out, ground, sun_azimuth, clamp_negative } => {
            let job = app::sky::ImportJob { photo, out, ground, sun_azimuth_deg: sun_azimuth, clamp_negative };
            let r = app::sky::import(&job)?;
            r.notes.iter().for_each(|n| eprintln!("{n}"));
            eprintln!("wrote {} ({} x {})", job.out.display(), r.width, r.height);
        }
        SkyCommand::Info { file, json } => {
            let info = app::sky::info(&file)?;
            if json {
                emit(&info, true)?;
            } else {
                emit(&format!("{}: {info}", file.display()), false)?;
            }
        }
        #[rustfmt::skip]
        SkyCommand::Sheet { files, thumb_width, columns, out } => {
            let (w, h) = app::sky::sheet(&files, thumb_width, columns, &out)?;
            eprintln!("wrote {} ({w} x {h})", out.display());
        }
    }
    Ok(())
}

#[cfg(feature = "embree")]
#[derive(clap::Args)]
struct SmokeArgs {
    /// Grid cells per side (two triangles per cell).
    #[arg(long, default_value_t = 1000)]
    cells: u32,
    /// Number of rays to trace.
    #[arg(long, default_value_t = 1_000_000)]
    rays: usize,
    /// BVH build quality.
    #[arg(long, value_parser = choice::<vastocean::accel::embree::Quality>(), default_value = "medium")]
    quality: vastocean::accel::embree::Quality,
    /// Threads for Embree and the tracer (0 = all cores).
    #[arg(long, default_value_t = 0)]
    threads: usize,
    #[arg(long)]
    json: bool,
}

#[cfg(feature = "embree")]
impl SmokeArgs {
    fn job(&self) -> app::smoke::SmokeJob {
        app::smoke::SmokeJob {
            cells: self.cells,
            rays: self.rays,
            quality: self.quality,
            threads: self.threads,
        }
    }
}
