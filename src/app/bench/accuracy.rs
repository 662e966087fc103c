//! `vastocean bench accuracy`: the speed / accuracy frontier of one scene. Every point is a
//! configuration (tessellation, shading normals, samples per pixel); each is timed phase by
//! phase and its error measured against a converged reference (the finest tessellation, with
//! normal mapping, at many samples) with the noise-corrected estimator: the near-horizon band
//! std of the luminance difference (rows 0 to -5 degrees, the paper's statistic) and the
//! full-image relative RMS error of luminance, each with a 95 % interval. Each tessellation is
//! built once and traced for every point that uses it. Writes `frontier.csv`, `frontier.png`
//! and `summary.json` (with the Pareto front) into `out`.

use std::fmt;
use std::path::PathBuf;
use std::time::Instant;

use serde::Serialize;

use super::{Progress, near_size_lod};
use crate::analysis::charts::{FrontierPoint, frontier};
use crate::analysis::error::{Estimator, Inputs};
use crate::app::AppError;
use crate::color::luminance;
use crate::config::{LodChoice, LodConfig, NormalMode, Projection, SceneConfig};
use crate::image_io::{stage, write_json};
use crate::render::film::{Film, MAX_BATCHES};
use crate::render::pipeline::{Prepared, prepare};

/// A tessellation of the sweep.
#[derive(Clone, Debug, Serialize)]
pub struct Tessellation {
    /// "paper-high", "paper-low", "auto" or "near-0.12m".
    pub name: String,
    pub lod: LodConfig,
}

impl Tessellation {
    pub fn preset(choice: LodChoice) -> Tessellation {
        Tessellation {
            name: choice.to_string(),
            lod: LodConfig {
                preset: choice,
                ..LodConfig::default()
            },
        }
    }
    pub fn near(size_m: f64) -> Tessellation {
        Tessellation {
            name: format!("near-{size_m}m"),
            lod: near_size_lod(size_m),
        }
    }
}

/// What to sweep.
#[derive(Clone, Debug)]
pub struct AccuracyJob {
    /// The scene (its camera becomes a full panorama `width` wide).
    pub scene: SceneConfig,
    pub width: usize,
    pub tessellations: Vec<Tessellation>,
    /// Each a multiple of the film's batch count (8).
    pub spp: Vec<u32>,
    pub reference: Tessellation,
    pub reference_spp: u32,
    pub out: PathBuf,
    pub progress: bool,
}

impl AccuracyJob {
    /// The scene the benchmark measures unless told otherwise: the default scene's ocean and
    /// camera under the built-in clear sky with the sun 4 degrees up, its radiance clipped to
    /// 100 as a photographic sky map clips it. With the physical sun (2000) every error here is
    /// the noise of a few sun-glint samples: the reference's own noise was 2.2 times the
    /// smallest error of the quick sweep, and intervals spanned 0 to 4 (README).
    pub fn default_scene() -> SceneConfig {
        let mut s = SceneConfig::default();
        s.sky.analytic = crate::config::AnalyticSky::Clear {
            sun_elevation_deg: 4.0,
            sun_azimuth_deg: 180.0,
            sun_radiance: 100.0,
            sky_scale: 1.0,
        };
        s
    }

    /// The full sweep of the README: 1024 px, seven tessellations from 3 cm to 1.8 m and
    /// `auto`, both normal modes, 8 to 256 spp, against paper-high at 1024 spp.
    pub fn full(scene: SceneConfig, out: PathBuf) -> AccuracyJob {
        AccuracyJob {
            scene,
            width: 1024,
            tessellations: vec![
                Tessellation::preset(LodChoice::PaperHigh),
                Tessellation::near(0.06),
                Tessellation::near(0.12),
                Tessellation::near(0.3),
                Tessellation::preset(LodChoice::PaperLow),
                Tessellation::near(1.8),
                Tessellation::preset(LodChoice::Auto),
            ],
            spp: vec![8, 16, 32, 64, 128, 256],
            reference: Tessellation::preset(LodChoice::PaperHigh),
            reference_spp: 1024,
            out,
            progress: true,
        }
    }

    /// A reduced sweep that runs in about a minute on 2 cores: 256 px, four tessellations,
    /// 8 to 128 spp, against a 6 cm tessellation at 512 spp.
    pub fn quick(scene: SceneConfig, out: PathBuf) -> AccuracyJob {
        AccuracyJob {
            width: 256,
            tessellations: vec![
                Tessellation::near(0.12),
                Tessellation::near(0.3),
                Tessellation::preset(LodChoice::PaperLow),
                Tessellation::preset(LodChoice::Auto),
            ],
            spp: vec![8, 32, 128],
            reference: Tessellation::near(0.06),
            reference_spp: 512,
            ..AccuracyJob::full(scene, out)
        }
    }
}

/// One configuration's cost and error.
#[derive(Clone, Debug, Serialize)]
pub struct Point {
    pub lod: String,
    pub normals: NormalMode,
    pub spp: u32,
    pub triangles: usize,
    pub seconds_ocean: f64,
    pub seconds_tessellation: f64,
    pub seconds_build: f64,
    pub seconds_trace: f64,
    /// Estimated share of the trace spent on normal mapping.
    pub seconds_normal_map: f64,
    /// Ocean + tessellation + BVH + trace: what rendering this configuration alone costs.
    pub seconds_total: f64,
    /// Bytes of the point's data: ocean layers, mesh, BVH, film.
    pub memory_bytes: u64,
    pub rays: u64,
    /// Noise-corrected band std of the luminance difference from the reference, rows 0 to -5
    /// degrees, and its interval.
    pub error: f64,
    pub error_ci: [f64; 2],
    /// The same with the noise in it (the paper's statistic).
    pub error_plain: f64,
    /// Noise-corrected relative RMS error of luminance over the whole image.
    pub rmse_relative: f64,
    pub rmse_relative_ci: [f64; 2],
    /// On the Pareto front of (seconds_total, error): no point is both faster and closer.
    pub pareto: bool,
}

/// The reference the points are measured against.
#[derive(Clone, Debug, Serialize)]
pub struct Reference {
    pub lod: String,
    pub normals: NormalMode,
    pub spp: u32,
    pub triangles: usize,
    pub seconds_total: f64,
    /// RMS standard error of its pixel luminance in the analysed rows, and that over the
    /// smallest error measured (it is subtracted from every error, but it widens intervals).
    pub noise_band: f64,
    pub noise_over_smallest_error: f64,
    pub mean_luminance: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct AccuracyReport {
    pub points: Vec<Point>,
    pub reference: Reference,
    /// The Pareto front, fastest first.
    pub front: Vec<Point>,
    pub width: usize,
    pub rows_deg: (f64, f64),
    pub seconds_total: f64,
    pub csv: PathBuf,
    pub png: PathBuf,
    pub json: PathBuf,
}

/// Analysed rows, the paper's.
const ROWS: (f64, f64) = (0.0, -5.0);

fn scene_with(job: &AccuracyJob, t: &Tessellation) -> SceneConfig {
    let mut s = job.scene.clone();
    s.camera.width = job.width;
    s.camera.projection = Projection::Equirect { band_deg: None };
    s.lod = t.lod.clone();
    s
}

fn check(job: &AccuracyJob) -> Result<(), AppError> {
    for t in job.tessellations.iter().chain([&job.reference]) {
        let s = scene_with(job, t);
        s.validate()?;
        crate::lod::params_for(&s.lod, &s.camera)?;
    }
    let k = MAX_BATCHES as u32;
    if let Some(bad) = job
        .spp
        .iter()
        .chain([&job.reference_spp])
        .find(|&&n| n == 0 || n % k != 0)
    {
        return Err(AppError::input(format!(
            "every spp must be a positive multiple of {k} (the film's batches): got {bad}"
        )));
    }
    if job.spp.is_empty() || job.tessellations.is_empty() {
        return Err(AppError::input("nothing to sweep"));
    }
    Ok(())
}

/// Renders one configuration through a prepared tessellation.
fn render(
    p: &Prepared,
    cfg: &SceneConfig,
    normals: NormalMode,
    spp: u32,
) -> Result<(Film, crate::render::pipeline::RenderReport), AppError> {
    let mut c = cfg.clone();
    c.render.normals = normals;
    c.render.spp = spp;
    let r = p.render_batches(&c, MAX_BATCHES, false)?;
    Ok((r.film, r.report))
}

fn mean_luminance(film: &Film) -> f64 {
    let px = &film.image.pixels;
    px.iter().map(|&c| luminance(c) as f64).sum::<f64>() / px.len().max(1) as f64
}

/// Marks the points no other point beats in both time and error.
fn mark_pareto(points: &mut [Point]) {
    let all: Vec<(f64, f64)> = points.iter().map(|p| (p.seconds_total, p.error)).collect();
    for (i, p) in points.iter_mut().enumerate() {
        p.pareto = !all.iter().enumerate().any(|(j, &(t, e))| {
            j != i && t <= p.seconds_total && e <= p.error && (t < p.seconds_total || e < p.error)
        });
    }
}

pub fn run(job: &AccuracyJob) -> Result<AccuracyReport, AppError> {
    check(job)?;
    crate::app::check_output_dir(&job.out)?;
    let t0 = Instant::now();
    let per_tess = 2 * job.spp.len() as u64;
    let progress = Progress::new(
        job.progress,
        1 + job.tessellations.len() as u64 * per_tess,
        "bench accuracy",
    );
    // The reference, rendered alone and its BVH freed before the sweep.
    let ref_cfg = scene_with(job, &job.reference);
    let (ref_film, ref_report) = {
        let p = prepare(&ref_cfg)?;
        render(&p, &ref_cfg, NormalMode::Mapped, job.reference_spp)?
    };
    progress.step(format!(
        "reference {} mapped, {} spp",
        job.reference.name, job.reference_spp
    ));
    let camera = crate::render::Camera::new(ref_cfg.camera.projection, job.width, 2.0);
    let scale = mean_luminance(&ref_film);
    let mut points = Vec::new();
    for t in &job.tessellations {
        let cfg = scene_with(job, t);
        let p = prepare(&cfg)?;
        let shared = p.seconds_ocean + p.seconds_tessellation + p.seconds_build;
        let structures = (p.ocean.bytes() + p.accel.mesh().bytes()) as u64 + p.accel.bytes();
        for normals in [NormalMode::Mapped, NormalMode::Vertex] {
            for &spp in &job.spp {
                let (film, rep) = render(&p, &cfg, normals, spp)?;
                let film_bytes = (film.image.pixels.len() * 12
                    + film.batches.as_ref().map_or(0, |b| b.luminance.len() * 4))
                    as u64;
                let errors = |rows_deg| -> Result<Estimator, AppError> {
                    Estimator::new(&Inputs {
                        camera: &camera,
                        baseline: &ref_film,
                        scenarios: vec![(t.name.clone(), &film)],
                        rows_deg,
                        seed: cfg.render.seed,
                    })
                    .map_err(|e| AppError::Run(e.into()))
                };
                let band = errors(ROWS)?.scenarios().scenarios.remove(0);
                let rmse = errors((90.0, -90.0))?.rms_difference(0, scale);
                points.push(Point {
                    lod: t.name.clone(),
                    normals,
                    spp,
                    triangles: rep.triangles,
                    seconds_ocean: rep.seconds_ocean,
                    seconds_tessellation: rep.seconds_tessellation,
                    seconds_build: rep.seconds_build,
                    seconds_trace: rep.seconds_trace,
                    seconds_normal_map: rep.seconds_normal_map,
                    seconds_total: shared + rep.seconds_trace,
                    memory_bytes: structures + film_bytes,
                    rays: rep.rays,
                    error: band.std_corrected.value,
                    error_ci: band.std_corrected.ci,
                    error_plain: band.std,
                    rmse_relative: rmse.value,
                    rmse_relative_ci: rmse.ci,
                    pareto: false,
                });
                progress.step(format!("{} {normals} {spp} spp", t.name));
            }
        }
    }
    progress.finish();
    mark_pareto(&mut points);
    let smallest = points
        .iter()
        .map(|p| p.error)
        .filter(|e| *e > 0.0)
        .fold(f64::INFINITY, f64::min);
    let noise_band = band_noise(&ref_film, &camera);
    let reference = Reference {
        lod: job.reference.name.clone(),
        normals: NormalMode::Mapped,
        spp: job.reference_spp,
        triangles: ref_report.triangles,
        seconds_total: ref_report.seconds_total,
        noise_band,
        noise_over_smallest_error: noise_band / smallest,
        mean_luminance: scale,
    };
    write(job, points, reference, t0)
}

/// RMS standard error of the film's pixel luminance over the analysed rows.
fn band_noise(film: &Film, camera: &crate::render::Camera) -> f64 {
    let w = film.image.width;
    let (mut sum, mut n) = (0.0, 0.0);
    for y in 0..film.image.height {
        let e = camera.row_elevation_deg(y);
        if e <= ROWS.0 && e >= ROWS.1 {
            sum += film.var_y[y * w..(y + 1) * w]
                .iter()
                .map(|&v| v as f64)
                .sum::<f64>();
            n += w as f64;
        }
    }
    (sum / n.max(1.0)).sqrt()
}

fn write(
    job: &AccuracyJob,
    points: Vec<Point>,
    reference: Reference,
    t0: Instant,
) -> Result<AccuracyReport, AppError> {
    let (csv, png, json) = (
        job.out.join("frontier.csv"),
        job.out.join("frontier.png"),
        job.out.join("summary.json"),
    );
    let staged = stage(&csv, |w| {
        use std::io::Write;
        writeln!(
            w,
            "lod,normals,spp,triangles,seconds_ocean,seconds_tessellation,seconds_build,seconds_trace,seconds_normal_map,seconds_total,memory_bytes,rays,error,error_lo,error_hi,error_plain,rmse_relative,rmse_relative_lo,rmse_relative_hi,pareto"
        )?;
        for p in &points {
            writeln!(
                w,
                "{},{},{},{},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{},{},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{}",
                p.lod,
                p.normals,
                p.spp,
                p.triangles,
                p.seconds_ocean,
                p.seconds_tessellation,
                p.seconds_build,
                p.seconds_trace,
                p.seconds_normal_map,
                p.seconds_total,
                p.memory_bytes,
                p.rays,
                p.error,
                p.error_ci[0],
                p.error_ci[1],
                p.error_plain,
                p.rmse_relative,
                p.rmse_relative_ci[0],
                p.rmse_relative_ci[1],
                p.pareto
            )?;
        }
        Ok(())
    })?;
    let chart: Vec<FrontierPoint> = points
        .iter()
        .map(|p| FrontierPoint {
            seconds: p.seconds_total,
            error: p.error,
            error_ci: p.error_ci,
            group: usize::from(p.normals == NormalMode::Vertex),
            pareto: p.pareto,
            label: (p.lod.starts_with("paper") && p.spp == *job.spp.last().unwrap_or(&0))
                .then(|| format!("  {} {}", p.lod, p.normals)),
        })
        .collect();
    frontier(
        &png,
        &format!(
            "error against {} mapped at {} spp ({} px): band std of the luminance difference, rows 0 to -5 degrees",
            reference.lod, reference.spp, job.width
        ),
        "noise-corrected std of luminance difference",
        &["mapped normals", "vertex normals"],
        &chart,
    )
    .map_err(|m| AppError::Run(format!("cannot draw {}: {m}", png.display()).into()))?;
    let mut front: Vec<Point> = points.iter().filter(|p| p.pareto).cloned().collect();
    front.sort_by(|a, b| a.seconds_total.total_cmp(&b.seconds_total));
    let report = AccuracyReport {
        points,
        reference,
        front,
        width: job.width,
        rows_deg: ROWS,
        seconds_total: t0.elapsed().as_secs_f64(),
        csv,
        png,
        json: json.clone(),
    };
    staged.commit()?;
    write_json(&json, &report)?;
    Ok(report)
}

impl fmt::Display for AccuracyReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let r = &self.reference;
        writeln!(
            f,
            "speed / accuracy at {} px against {} mapped at {} spp ({} triangles; its noise {:.2e}, {:.0}% of the smallest error)",
            self.width,
            r.lod,
            r.spp,
            r.triangles,
            r.noise_band,
            100.0 * r.noise_over_smallest_error
        )?;
        writeln!(
            f,
            "  lod          normals  spp   triangles   seconds   error [95%]                    rel. RMSE [95%]           front"
        )?;
        for p in &self.points {
            writeln!(
                f,
                "  {:<12} {:<7} {:>4} {:>11} {:>9.2}   {:.4} [{:.4}, {:.4}]   {:.4} [{:.4}, {:.4}]   {}",
                p.lod,
                p.normals.to_string(),
                p.spp,
                p.triangles,
                p.seconds_total,
                p.error,
                p.error_ci[0],
                p.error_ci[1],
                p.rmse_relative,
                p.rmse_relative_ci[0],
                p.rmse_relative_ci[1],
                if p.pareto { "*" } else { "" }
            )?;
        }
        write!(
            f,
            "  wrote {} {} {} in {:.0} s",
            self.csv.display(),
            self.png.display(),
            self.json.display(),
            self.seconds_total
        )
    }
}
