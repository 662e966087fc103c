//! `render` and `compare`: a scene file plus the flags that override it.

use std::path::PathBuf;

use anyhow::Result;
use vastocean::app::{self, AppError};
use vastocean::config::{LodChoice, LodConfig, NormalMode, Projection, SceneConfig};

use super::{BadInput, choice};

/// Scene flags shared by `render` and `compare`: a scene file and the settings most often
/// changed on the command line, which override it.
#[derive(clap::Args)]
pub struct SceneFlags {
    /// Scene file (TOML; `-` reads it from stdin, its paths relative to the working directory);
    /// the flags below override it. Without one, the default scene (docs/scene-file.md).
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
    #[arg(long, conflicts_with = "hs")]
    rms: Option<f64>,
    /// Scale the ocean to this significant wave height Hs = 4 x RMS, m.
    #[arg(long)]
    hs: Option<f64>,
    /// Peak period of the wind sea, s, instead of the fetch law's (with a height target).
    #[arg(long)]
    tp: Option<f64>,
    #[command(flatten)]
    sea: super::SeaFlags,
    /// How the ocean's layers share the wavenumbers (docs/ocean.md).
    #[arg(long, value_parser = choice::<vastocean::ocean::Layering>())]
    layering: Option<vastocean::ocean::Layering>,
    /// Cap Mitsuyasu's spreading exponent (Goda: 10 wind sea, 25/75 short/long-travelled swell).
    #[arg(long)]
    spreading_cap: Option<f64>,
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
    #[arg(long, value_parser = super::threads_arg)]
    threads: Option<usize>,
    /// The BVH: Debian's Embree or the pure-Rust one.
    #[arg(long, value_parser = choice::<vastocean::config::Backend>())]
    backend: Option<vastocean::config::Backend>,
    /// What the rays meet: the tessellation's triangles (mesh), or the displaced ocean itself
    /// inside them (exact; docs/exact.md).
    #[arg(long, value_parser = choice::<vastocean::config::SurfaceKind>())]
    surface: Option<vastocean::config::SurfaceKind>,
    /// What to do when a shading normal would send a ray to the wrong side of its triangle
    /// (default terminate; docs/accuracy.md, "The wrong-side policy").
    #[arg(long, value_parser = choice::<vastocean::config::WrongSide>())]
    wrong_side: Option<vastocean::config::WrongSide>,
    /// How the ocean's layers are read between their grid points, for the mapped normals and the
    /// mesh's vertices: prefiltered (the default: bilinear reads of fields prefiltered so the
    /// normals and the surface keep the spectrum's slopes), bilinear (the paper's), bicubic, or
    /// variance-preserving (docs/ocean.md, "Reading the layers").
    #[arg(long, value_parser = choice::<vastocean::ocean::Interp>())]
    interp: Option<vastocean::ocean::Interp>,
    /// How the EXR is stored, losslessly: none (the default, the fastest to write and read),
    /// piz or zip (smaller; noisy renders shrink little: docs/performance.md, "Output").
    #[arg(long, value_parser = choice::<vastocean::config::ExrCompression>())]
    exr_compression: Option<vastocean::config::ExrCompression>,
    /// Embree: the ocean mesh's whole cells as grids or triangles (the same triangles);
    /// `auto` takes grids for meshes that are large against the samples traced
    #[arg(long, value_parser = choice::<vastocean::config::EmbreeGeometry>())]
    embree_geometry: Option<vastocean::config::EmbreeGeometry>,
}

impl SceneFlags {
    /// The scene keys these flags set, each with its flag: errors about a key that a flag set
    /// name the flag ([`super::name_flags`]).
    pub fn given(&self) -> Vec<(&'static str, &'static str)> {
        let set = [
            (self.wind.is_some(), "ocean.wind_speed", "--wind"),
            (self.fetch.is_some(), "ocean.fetch_km", "--fetch"),
            (self.depth.is_some(), "ocean.depth_m", "--depth"),
            (self.rms.is_some(), "ocean.rms_m", "--rms"),
            (self.hs.is_some(), "ocean.hs_m", "--hs"),
            (self.tp.is_some(), "ocean.tp_s", "--tp"),
            (self.sea.beaufort.is_some(), "ocean.beaufort", "--beaufort"),
            (self.sea.douglas.is_some(), "ocean.douglas", "--douglas"),
            (!self.sea.swell.is_empty(), "ocean.swell", "--swell"),
            (
                self.spreading_cap.is_some(),
                "ocean.spreading_cap",
                "--spreading-cap",
            ),
            (self.sky.is_some(), "sky.file", "--sky"),
            (self.width.is_some(), "camera.width", "--width"),
            (self.spp.is_some(), "render.spp", "--spp"),
            (self.seed.is_some(), "render.seed", "--seed"),
            (
                self.camera_height.is_some(),
                "camera.height_m",
                "--camera-height",
            ),
            (self.threads.is_some(), "render.threads", "--threads"),
            (self.interp.is_some(), "ocean.interp", "--interp"),
            (
                self.exr_compression.is_some(),
                "render.exr_compression",
                "--exr-compression",
            ),
            (
                self.embree_geometry.is_some(),
                "render.embree_geometry",
                "--embree-geometry",
            ),
        ];
        set.into_iter()
            .filter(|(given, ..)| *given)
            .map(|(_, key, flag)| (key, flag))
            .collect()
    }

    /// [`SceneFlags::given`], and `--band` if it was given.
    fn given_with_band(&self, band: bool) -> Vec<(&'static str, &'static str)> {
        let mut g = self.given();
        if band {
            g.push(("camera.projection.band_deg", "--band"));
        }
        g
    }

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
        // a height flag replaces the file's target, whichever way the file gave it
        if self.rms.is_some() || self.hs.is_some() {
            (s.ocean.rms_m, s.ocean.hs_m) = (self.rms, self.hs);
        }
        s.ocean.tp_s = self.tp.or(s.ocean.tp_s);
        // A preset flag replaces the scene's sea; swell flags replace the scene's own swells
        // (a scene preset's background swell stays first).
        if self.sea.beaufort.is_some() || self.sea.douglas.is_some() || !self.sea.swell.is_empty() {
            let mut preset = (s.ocean.beaufort, s.ocean.douglas);
            s.ocean.clear_preset();
            if self.sea.beaufort.is_some() || self.sea.douglas.is_some() {
                preset = (self.sea.beaufort, self.sea.douglas);
                (s.ocean.rms_m, s.ocean.hs_m, s.ocean.tp_s) = (None, None, None);
                // the preset's sea chooses its layers unless the file names its own
                s.ocean.layers_auto |=
                    s.ocean.layers == vastocean::config::OceanParams::default().layers;
            }
            if !self.sea.swell.is_empty() {
                s.ocean.swell = self.sea.swell.clone();
            }
            (s.ocean.beaufort, s.ocean.douglas) = preset;
            s.ocean.apply_preset();
        }
        // layers asked as "auto" follow the sea the flags made
        s.ocean.resolve_layers();
        s.ocean.layering = self.layering.unwrap_or(s.ocean.layering);
        s.ocean.spreading_cap = self.spreading_cap.or(s.ocean.spreading_cap);
        s.sky.file = self.sky.clone().or(s.sky.file);
        s.camera.width = self.width.unwrap_or(s.camera.width);
        s.render.spp = self.spp.unwrap_or(s.render.spp);
        s.render.seed = self.seed.unwrap_or(s.render.seed);
        s.render.threads = self.threads.unwrap_or(s.render.threads);
        s.render.backend = self.backend.unwrap_or(s.render.backend);
        s.render.surface = self.surface.unwrap_or(s.render.surface);
        s.render.wrong_side = self.wrong_side.unwrap_or(s.render.wrong_side);
        s.ocean.interp = self.interp.unwrap_or(s.ocean.interp);
        s.render.exr_compression = self.exr_compression.unwrap_or(s.render.exr_compression);
        s.render.embree_geometry = self.embree_geometry.unwrap_or(s.render.embree_geometry);
        Ok(s)
    }
}

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

/// `--exposure`'s value: stops, or `None` for auto (a type of its own: clap reads a bare
/// `Option<Option<_>>` as a flag whose value may be left out).
#[derive(Clone, Copy, Debug)]
struct Exposure(Option<f32>);

fn parse_exposure(s: &str) -> Result<Exposure, String> {
    vastocean::config::render::parse_exposure(s).map(Exposure)
}

#[derive(clap::Args)]
#[command(allow_negative_numbers = true)]
pub struct RenderArgs {
    #[command(flatten)]
    scene: SceneFlags,
    /// Tessellation: the paper's presets, or chosen from the pixel footprint.
    #[arg(long, value_parser = choice::<LodChoice>())]
    lod: Option<LodChoice>,
    /// Shading normals: interpolated vertex normals, recomputed from the ocean (normal mapping,
    /// the paper's), or filtered: the waves below the pixel's footprint as a rough surface, with
    /// the sun sampled (docs/filtered.md).
    #[arg(long, value_parser = choice::<NormalMode>())]
    normals: Option<NormalMode>,
    /// Filtered normals: the std of the Gaussian the waves are seen through, in pixel
    /// footprints (default 0.2887, a pixel's box; larger = less noise, less detail).
    #[arg(long)]
    filter_width: Option<f32>,
    /// Filtered normals: the lobe of the waves below the footprint: `mapped` draws them as the
    /// pixel's own points would have them and shades them as mapped normals (the paper's
    /// image, less noise), `smith` is the microfacet model with Smith's masking.
    #[arg(long, value_parser = choice::<vastocean::config::FilterLobe>())]
    filter_lobe: Option<vastocean::config::FilterLobe>,
    /// Filtered normals: the sun's samples at a rough hit whose lobe may reflect the sun (one
    /// at its faint edge, none where it reflects none), spread evenly over its disc with one
    /// shadow ray among them (1 to 16, default 8; more = less noise in the glitter).
    #[arg(long)]
    sun_samples: Option<u32>,
    /// Render only the elevations TOP:BOTTOM in degrees, e.g. +1:-6 (equirectangular camera).
    #[arg(long, value_parser = parse_band, allow_hyphen_values = true)]
    band: Option<(f64, f64)>,
    /// The PNG preview's exposure: `auto` (each image's median luminance to mid grey; an
    /// animation keeps its first frame's) or stops, radiance x 2^STOPS before the tone curve.
    /// The sidecar reports what was used as `png_exposure_stops`. The EXR is never scaled.
    #[arg(long, value_parser = parse_exposure, allow_hyphen_values = true)]
    exposure: Option<Exposure>,
    /// Layers for training data, comma-separated: `depth` (EXR channel Z, m), `normal`
    /// (N.X N.Y N.Z), `id` (-1 sky, 0 water, k the k-th object; the JSON gives each object's
    /// 2-D box). From each pixel's centre ray (docs/objects.md)
    #[arg(long, value_delimiter = ',', value_parser = choice::<vastocean::config::Aov>())]
    aov: Option<Vec<vastocean::config::Aov>>,
    /// Output prefix: writes PREFIX.exr, PREFIX.png and PREFIX.json.
    #[arg(long, default_value = "out/render")]
    out: PathBuf,
    /// Render only pass K of N (1-based: the samples s = K-1 mod N of every pixel) into
    /// PREFIX.pass; `vastocean merge` adds the passes up into the render
    /// (docs/many-machines.md).
    #[arg(long, value_parser = vastocean::app::passes::parse_pass, conflicts_with = "frames")]
    pass: Option<(usize, usize)>,
    /// Render an animation: ocean times START:END:STEP in seconds (e.g. 0:2:0.04), into
    /// PREFIX.0001.exr/.png ... and one PREFIX.json for the sequence; each frame after the first
    /// moves the vertices and refits the BVH instead of rebuilding (docs/many-machines.md).
    #[arg(long, value_parser = vastocean::app::frames::parse_frames, allow_hyphen_values = true)]
    pub frames: Option<vastocean::app::frames::FrameRange>,
    /// Print the JSON sidecar on stdout.
    #[arg(long)]
    pub json: bool,
    /// Print the scene this command would render, the file and every flag applied and checked,
    /// as TOML that `--config` reads back; render nothing.
    #[arg(long, conflicts_with_all = ["json", "pass", "frames"])]
    pub dump_config: bool,
}

/// `merge`: pass files into one render.
#[derive(clap::Args)]
pub struct MergeArgs {
    /// Pass files written by `vastocean render --pass K/N` (all of one render).
    #[arg(required = true)]
    passes: Vec<PathBuf>,
    /// Output prefix: writes PREFIX.exr, PREFIX.png and PREFIX.json, as a render does.
    #[arg(long)]
    out: PathBuf,
    /// Print the merged JSON sidecar on stdout.
    #[arg(long)]
    pub json: bool,
}

impl MergeArgs {
    pub fn job(&self) -> app::passes::MergeJob {
        app::passes::MergeJob {
            passes: self.passes.clone(),
            out: self.out.clone(),
        }
    }
}

impl RenderArgs {
    /// The scene keys the flags set, each with its flag (see [`SceneFlags::given`]).
    pub fn given(&self) -> Vec<(&'static str, &'static str)> {
        self.scene.given_with_band(self.band.is_some())
    }

    /// The animation job of `--frames`.
    pub fn frames_job(&self, frames: app::frames::FrameRange) -> Result<app::frames::FramesJob> {
        let r = self.job()?;
        Ok(app::frames::FramesJob {
            scene: r.scene,
            out: r.out,
            progress: r.progress,
            frames,
        })
    }

    pub fn job(&self) -> Result<app::render::RenderJob> {
        let mut cfg = self.scene.scene()?;
        cfg.lod.preset = self.lod.unwrap_or(cfg.lod.preset);
        cfg.render.normals = self.normals.unwrap_or(cfg.render.normals);
        cfg.render.filter_width = self.filter_width.unwrap_or(cfg.render.filter_width);
        cfg.render.filter_lobe = self.filter_lobe.unwrap_or(cfg.render.filter_lobe);
        cfg.render.sun_samples = self.sun_samples.unwrap_or(cfg.render.sun_samples);
        if let Some(aovs) = &self.aov {
            cfg.render.aovs = aovs.clone();
        }
        if let Some(Exposure(e)) = self.exposure {
            cfg.render.exposure = e;
        }
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
            pass: self.pass,
        })
    }
}

#[derive(clap::Args)]
#[command(allow_negative_numbers = true)]
pub struct CompareArgs {
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
    /// Most samples a noisy pixel may take, in multiples of --spp: a pilot render finds the
    /// analysed pixels whose noise dominates (sun glints) and they get up to this many times
    /// the samples, the extra at most doubling the work. 1 renders every pixel alike.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u16).range(1..=1024))]
    max_boost: u16,
    /// Ocean realizations: with N > 1 the comparison runs for ocean seeds render.ocean_seed,
    /// +1, ... +N-1 (each in OUT/ocean-seed-S), and OUT/summary.json pools them: the sea
    /// state's improvement ratio with an interval that holds the spread between seas too.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u16).range(1..=64))]
    pub realizations: u16,
    /// Also render the low tessellation with filtered normals: scenario `low_filtered`, with
    /// its statistics beside the paper's (docs/filtered.md).
    #[arg(long)]
    pub filtered: bool,
    /// Also render the exact displaced surface inside the low tessellation's triangles, mapped
    /// normals: scenario `low_exact`, with its statistics beside the paper's (docs/exact.md);
    /// with --filtered also with filtered normals, scenario `low_exact_filtered`.
    #[arg(long)]
    pub exact: bool,
    /// What every scenario is measured against: the paper's baseline (paper-high, its high
    /// tessellation with mapped normals), or that and beside it the truth: the exact displaced
    /// surface shaded with its own tangent plane, on which no wrong-side event arises,
    /// rendered on the analysed rows only (truth.exr; per scenario std_vs_truth in
    /// summary.json, stats_vs_truth.csv; docs/comparison.md).
    #[arg(long, value_parser = choice::<app::compare::Against>(), default_value = "paper-high")]
    pub against: app::compare::Against,
    /// The truth's samples per analysed pixel, in multiples of that pixel's samples in the
    /// scenarios (default 4; with --against truth, for a truth rendered here).
    #[arg(long, value_parser = clap::value_parser!(u16).range(1..=64))]
    pub truth_boost: Option<u16>,
    /// Reuse the truth an earlier `compare --against truth` of the same scene wrote into DIR
    /// (truth.exr, truth.json) instead of rendering it again: no wrong-side policy touches the
    /// truth, so a sweep over --wrong-side renders it once. Implies --against truth; refused
    /// when that truth's sea, tessellation, sky, camera, water, render settings or rows differ
    /// (the sample seed, the policy, threads, backend, exposure and EXR compression may).
    #[arg(long, value_name = "DIR")]
    pub truth_from: Option<PathBuf>,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
    /// Print summary.json on stdout.
    #[arg(long)]
    pub json: bool,
}

impl CompareArgs {
    /// The scene keys the flags set, each with its flag (see [`SceneFlags::given`]).
    pub fn given(&self) -> Vec<(&'static str, &'static str)> {
        self.scene.given_with_band(self.band.is_some())
    }

    pub fn job(&self) -> Result<app::compare::CompareJob> {
        if self.truth_boost.is_some() {
            if self.truth_from.is_some() {
                return Err(BadInput(
                    "--truth-boost sets the samples of a truth rendered here; a truth reused with --truth-from keeps its own".into(),
                )
                .into());
            }
            if self.against != app::compare::Against::Truth {
                return Err(BadInput(
                    "--truth-boost sets the truth's samples: it goes with --against truth".into(),
                )
                .into());
            }
        }
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
            max_boost: self.max_boost,
            filtered: self.filtered,
            exact: self.exact,
            against: if self.truth_from.is_some() {
                app::compare::Against::Truth
            } else {
                self.against
            },
            truth_from: self.truth_from.clone(),
            truth_boost: self
                .truth_boost
                .unwrap_or(app::compare::DEFAULT_TRUTH_BOOST),
            out: self.out.clone(),
            progress: true,
        })
    }
}
