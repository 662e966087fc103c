//! `vastocean bench accuracy`: the speed / accuracy frontier of one scene. Every point is a
//! configuration (tessellation, shading normals, samples per pixel), rendered as a user would
//! render it (the full panorama) and timed phase by phase. Its error is measured against a
//! reference over the rows the statistic reads (0 to -5 degrees): the finest tessellation
//! with normal mapping, rendered over those rows only, with as many samples as it takes for
//! its own noise to be at most a quarter of the smallest error it ranks (checked, not
//! assumed: the samples are quadrupled until it is, or until a cap, and the share is
//! reported). Errors come from the estimator of `crate::analysis::error`:
//! - `error`: the band std of the render's difference from the converged image, its own noise
//!   included (what a user of that render sees): sqrt(measured variance - the reference's
//!   noise), row by row; it falls with samples towards the configuration's
//! - `bias`: the same without the render's noise (its systematic difference), unbiased.
//!
//! Each tessellation is built once and traced for every point that uses it. Writes
//! `frontier.csv`, `frontier.png` and `summary.json` (with the Pareto front) into `out`.

mod report;
mod sweep;

use sweep::{band_luminance, band_noise, measure, render_points, render_reference};

use std::path::PathBuf;
use std::time::Instant;

use serde::Serialize;

use super::{Progress, near_size_lod};
use crate::analysis::error::{Interval, MIN_BATCHES};
use crate::app::AppError;
use crate::app::compare::sampling;
use crate::config::{LodChoice, LodConfig, NormalMode, Projection, SceneConfig, SurfaceKind};
use crate::render::Camera;
use crate::render::film::MAX_BATCHES;
use crate::render::pipeline::prepare_with;

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

/// The largest share of the smallest error the reference's own noise may be.
pub const REFERENCE_NOISE_SHARE: f64 = 0.25;

/// Added to the sample seed for the reference (independent of the points' samples).
const REFERENCE_SEED: u64 = 0x7265_6665_7265_6e63;

/// What to sweep.
#[derive(Clone, Debug)]
pub struct AccuracyJob {
    /// The scene (its camera becomes a full panorama `width` wide).
    pub scene: SceneConfig,
    pub width: usize,
    pub tessellations: Vec<Tessellation>,
    /// Each a multiple of the film's batch count (8).
    pub spp: Vec<u32>,
    /// The normal modes every tessellation is rendered with (the paper's two; `--filtered`
    /// adds filtered normals).
    pub normals: Vec<NormalMode>,
    pub reference: Tessellation,
    /// The reference's first sample count, and the most it may take.
    pub reference_spp: u32,
    pub reference_spp_max: u32,
    /// Most samples a noisy reference pixel may take, in multiples of its spp (see
    /// `crate::app::compare::sampling`).
    pub reference_max_boost: u16,
    /// Also the exact surface (docs/exact.md) inside one tessellation's prisms, with mapped
    /// normals, at these samples per pixel: a fourth group (`--exact`).
    pub exact: Option<ExactSweep>,
    pub out: PathBuf,
    pub progress: bool,
}

/// The exact surface's points of the sweep: its coarse tessellation and samples per pixel.
#[derive(Clone, Debug)]
pub struct ExactSweep {
    pub tessellation: Tessellation,
    pub spp: Vec<u32>,
}

/// Most samples per pixel `--exact` renders the exact surface at: its trace is some 30x
/// paper-high's per sample (docs/exact.md), so 8 to 64 spp at 1024 px take some 7 minutes.
pub const EXACT_MAX_SPP: u32 = 64;

impl AccuracyJob {
    /// The scene the benchmark measures unless told otherwise: the default scene's ocean and
    /// camera under the hand-made clear sky with the sun 4 degrees up, its radiance clipped to
    /// 100 as a photographic sky map clips it (with a sun of 2000, the errors of every
    /// configuration are those of its noise at the sun's glitter; `--config` measures any scene).
    pub fn default_scene() -> SceneConfig {
        let mut s = SceneConfig::default();
        s.sky.analytic = crate::config::AnalyticSky::HandMadeClear {
            sun_elevation_deg: 4.0,
            sun_azimuth_deg: 180.0,
            sun_radiance: 100.0,
            sky_scale: 1.0,
        };
        s
    }

    /// The full sweep: 1024 px, seven tessellations from 3 cm to 1.8 m and `auto`, both normal
    /// modes, 8 to 256 spp, against paper-high starting at 4096 spp.
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
            normals: vec![NormalMode::Mapped, NormalMode::Vertex],
            reference: Tessellation::preset(LodChoice::PaperHigh),
            reference_spp: 4096,
            reference_spp_max: 65536,
            reference_max_boost: 64,
            exact: None,
            out,
            progress: true,
        }
    }

    /// This sweep with the exact surface in paper-low's prisms at its sample counts up to
    /// [`EXACT_MAX_SPP`] (`--exact`).
    pub fn with_exact(self) -> AccuracyJob {
        let spp = self
            .spp
            .iter()
            .copied()
            .filter(|&n| n <= EXACT_MAX_SPP)
            .collect();
        AccuracyJob {
            exact: Some(ExactSweep {
                tessellation: Tessellation::preset(LodChoice::PaperLow),
                spp,
            }),
            ..self
        }
    }

    /// A reduced sweep that runs in about a minute on 2 cores: 256 px, four tessellations,
    /// 8 to 128 spp, against a 6 cm tessellation starting at 2048 spp.
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
            reference_spp: 2048,
            reference_spp_max: 32768,
            ..AccuracyJob::full(scene, out)
        }
    }
}

/// One configuration's cost and error.
#[derive(Clone, Debug, Serialize)]
pub struct Point {
    pub lod: String,
    pub normals: NormalMode,
    /// The mesh's triangles, or the exact surface inside their prisms.
    pub surface: SurfaceKind,
    pub spp: u32,
    pub triangles: usize,
    pub seconds_ocean: f64,
    pub seconds_tessellation: f64,
    pub seconds_build: f64,
    /// Filtered normals' levels and slope tables: built once on the sweep's ocean and, like
    /// the ocean, counted in every filtered point as a render of its own would build them (0
    /// for the other normals).
    pub seconds_levels: f64,
    pub seconds_trace: f64,
    /// Estimated share of the trace spent on normal mapping.
    pub seconds_normal_map: f64,
    /// Ocean + tessellation + BVH + levels + trace: what rendering this configuration alone
    /// costs.
    pub seconds_total: f64,
    /// Bytes of the point's data: ocean layers, mesh, BVH, film.
    pub memory_bytes: u64,
    pub rays: u64,
    /// The band std (RMS over rows 0 to -5 degrees of the azimuthal std) of the luminance
    /// difference from the converged image, the render's own noise included, and its interval.
    pub error: f64,
    pub error_ci: [f64; 2],
    /// Its systematic part: the same std of the expected difference, noise taken out.
    pub bias: f64,
    pub bias_ci: [f64; 2],
    /// The bias's interval lies above 0 (else the table says "< upper bound").
    pub bias_resolved: bool,
    /// The paper's statistic against the reference (both renders' noise included).
    pub error_plain: f64,
    /// RMS standard error of the render's pixel luminance over the band (its noise alone).
    pub noise: f64,
    /// RMS over the band's pixels of the difference from the converged image (mean included,
    /// own noise included), relative to the reference's mean luminance there.
    pub rmse_relative: f64,
    pub rmse_relative_ci: [f64; 2],
    /// On the Pareto front of (seconds_total, error): no point is both faster and closer.
    pub pareto: bool,
}

/// A mapped render at the sweep's most samples, and the cheapest render of another method (on
/// any mesh) whose error is at most its error, and the cheapest whose error lies inside its
/// interval (at most its upper bound): the run-time-vs-error frontier read at that error.
#[derive(Clone, Debug, Serialize)]
pub struct Match {
    /// "lod spp" of the mapped render.
    pub mapped: String,
    pub mapped_error: f64,
    pub mapped_seconds: f64,
    /// The other method's normals and surface ("filtered mesh", "mapped exact").
    pub method: String,
    /// "lod spp", error and seconds of its cheapest render at most at the mapped error.
    pub at_most: Option<(String, f64, f64)>,
    /// The same, inside the mapped render's interval.
    pub within: Option<(String, f64, f64)>,
}

/// The reference the points are measured against.
#[derive(Clone, Debug, Serialize)]
pub struct Reference {
    pub lod: String,
    pub normals: NormalMode,
    /// Samples per pixel of the reference used, and of each reference rendered until its noise
    /// was small enough.
    pub spp: u32,
    pub spp_tried: Vec<u32>,
    pub triangles: usize,
    /// Time of every reference render, pilots included.
    pub seconds_total: f64,
    /// How its samples were spent (the pilot and the boosted pixels).
    pub sampling: sampling::SamplingReport,
    /// RMS standard error of its pixel luminance over the analysed rows, the smallest error it
    /// ranks, and the one over the other.
    pub noise_band: f64,
    pub smallest_error: f64,
    pub noise_share: f64,
    pub mean_luminance: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct AccuracyReport {
    /// The commit of the vastocean that measured this.
    pub commit: &'static str,
    pub points: Vec<Point>,
    pub reference: Reference,
    /// The reference's noise over the smallest error in the table (at most
    /// [`REFERENCE_NOISE_SHARE`] unless the reference's sample cap was reached).
    pub reference_noise_share: f64,
    /// Every configuration's error falls (or stays, within its interval) as its spp grows.
    pub monotone_within_intervals: bool,
    /// The pairs that do not: "lod normals spp -> spp".
    pub not_monotone: Vec<String>,
    /// The Pareto front, fastest first.
    pub front: Vec<Point>,
    /// Each mapped render at the most samples against the cheapest render of a new method
    /// (filtered normals, the exact surface), on any mesh, that reaches its error.
    pub matches: Vec<Match>,
    pub width: usize,
    pub rows_deg: (f64, f64),
    /// The wrong-side policy of every render, the reference's included.
    pub wrong_side: crate::config::WrongSide,
    /// How every render, the reference's included, reads the ocean's layers.
    pub interp: crate::ocean::Interp,
    /// Oceans built: one, which every tessellation and the reference render.
    pub oceans_built: usize,
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

/// The exact surface's scene: `t`'s prisms, mapped normals.
fn exact_scene(job: &AccuracyJob, t: &Tessellation, normals: NormalMode) -> SceneConfig {
    let mut s = scene_with(job, t);
    s.render.surface = SurfaceKind::Exact;
    s.render.normals = normals;
    s
}

/// The reference's scene: the analysed rows only, its own sample seeds.
fn reference_scene(job: &AccuracyJob) -> SceneConfig {
    let mut s = scene_with(job, &job.reference);
    s.camera.projection = Projection::Equirect {
        band_deg: Some(ROWS),
    };
    s.render.normals = NormalMode::Mapped;
    s.render.seed = s.render.seed.wrapping_add(REFERENCE_SEED);
    s
}

fn check(job: &AccuracyJob) -> Result<(), AppError> {
    for t in job.tessellations.iter().chain([&job.reference]) {
        let s = scene_with(job, t);
        s.validate()?;
        crate::lod::params_for(&s.lod, &s.camera)?;
    }
    if let Some(x) = &job.exact {
        let s = exact_scene(job, &x.tessellation, NormalMode::Mapped);
        s.validate()?;
        crate::lod::params_for(&s.lod, &s.camera)?;
    }
    let k = MAX_BATCHES as u32;
    let exact_spp = job.exact.iter().flat_map(|x| &x.spp);
    if let Some(bad) = job
        .spp
        .iter()
        .chain(exact_spp)
        .chain([&job.reference_spp])
        .find(|&&n| n < MIN_BATCHES as u32 || n % k != 0)
    {
        return Err(AppError::input(format!(
            "every spp must be a positive multiple of {k} (the film's batches): got {bad}"
        )));
    }
    if job.reference_spp_max < job.reference_spp {
        return Err(AppError::input(format!(
            "the reference's sample cap {} is below its first sample count {}",
            job.reference_spp_max, job.reference_spp
        )));
    }
    if job.spp.is_empty() || job.tessellations.is_empty() {
        return Err(AppError::input("nothing to sweep"));
    }
    Ok(())
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

/// The configurations whose error at more samples lies significantly above their error at
/// fewer (the lower end of its interval above the upper end of the other's).
fn not_monotone(points: &[Point]) -> Vec<String> {
    let mut out = Vec::new();
    for (i, a) in points.iter().enumerate() {
        let next = points[i + 1..]
            .iter()
            .filter(|b| {
                b.lod == a.lod && b.normals == a.normals && b.surface == a.surface && b.spp > a.spp
            })
            .min_by_key(|b| b.spp);
        if let Some(b) = next
            && b.error_ci[0] > a.error_ci[1]
        {
            let exact = if a.surface == SurfaceKind::Exact {
                " exact"
            } else {
                ""
            };
            out.push(format!(
                "{}{exact} {} {} -> {} spp",
                a.lod, a.normals, a.spp, b.spp
            ));
        }
    }
    out
}

pub fn run(job: &AccuracyJob) -> Result<AccuracyReport, AppError> {
    check(job)?;
    crate::app::check_output_dir(&job.out)?;
    let t0 = Instant::now();
    let per_tess = (job.normals.len() * job.spp.len()) as u64;
    // (the exact surface with mapped normals, and with filtered ones where the sweep has them)
    let exact_modes = 1 + u64::from(job.normals.contains(&NormalMode::Filtered));
    let exact = job.exact.as_ref().map_or(0, |x| x.spp.len()) as u64 * exact_modes;
    let progress = Progress::new(
        job.progress,
        job.tessellations.len() as u64 * per_tess + exact + 1,
        "bench accuracy",
    );
    let ref_cfg = reference_scene(job);
    let band = Camera::new(ref_cfg.camera.projection, job.width, 2.0);
    let (mut points, mut shared) = render_points(job, &band, &progress)?;

    // The reference: quadrupled until its noise is at most the share of the smallest error.
    let p = prepare_with(&ref_cfg, sweep::Shared::setup(Some(&shared)))?;
    shared.count(&p);
    let (seconds_ocean, oceans_built) = (shared.seconds_ocean, shared.oceans_built);
    drop(shared);
    let (mut spp, mut tried, mut seconds) = (job.reference_spp, Vec::new(), seconds_ocean);
    seconds += p.seconds_tessellation + p.seconds_build;
    let (film, sampling, noise_band, smallest) = loop {
        let (film, sampling, s) = render_reference(&p, &ref_cfg, spp, job.reference_max_boost)?;
        seconds += s;
        tried.push(spp);
        measure(&mut points, &film, &band, job.scene.render.seed)?;
        let noise_band = band_noise(&film, &band).1.sqrt();
        let smallest = points
            .iter()
            .map(|r| r.point.error)
            .fold(f64::INFINITY, f64::min);
        if noise_band <= REFERENCE_NOISE_SHARE * smallest || spp * 4 > job.reference_spp_max {
            break (film, sampling, noise_band, smallest);
        }
        progress.step(format!(
            "reference {} spp: noise {:.2}x the smallest error, more samples",
            spp,
            noise_band / smallest
        ));
        spp *= 4;
    };
    progress.step(format!(
        "reference {} mapped, {spp} spp",
        job.reference.name
    ));
    progress.finish();
    let reference = Reference {
        lod: job.reference.name.clone(),
        normals: NormalMode::Mapped,
        spp,
        spp_tried: tried,
        triangles: p.accel.mesh().triangle_count(),
        seconds_total: seconds,
        sampling,
        noise_band,
        smallest_error: smallest,
        noise_share: noise_band / smallest,
        mean_luminance: band_luminance(&film, &band),
    };
    drop(p);
    let mut points: Vec<Point> = points.into_iter().map(|r| r.point).collect();
    mark_pareto(&mut points);
    report::write(job, points, reference, oceans_built, t0)
}

/// An error figure as the table prints it: "< upper bound" when its interval reaches 0.
pub fn figure(value: f64, ci: [f64; 2], resolved: bool) -> String {
    if resolved {
        format!("{value:.4} [{:.4}, {:.4}]", ci[0], ci[1])
    } else {
        format!("< {:.4}", ci[1])
    }
}

impl Point {
    /// The error and its interval.
    pub fn error_interval(&self) -> Interval {
        Interval {
            value: self.error,
            ci: self.error_ci,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(lod: &str, spp: u32, error: f64, ci: [f64; 2]) -> Point {
        Point {
            lod: lod.into(),
            normals: NormalMode::Mapped,
            surface: SurfaceKind::Mesh,
            spp,
            triangles: 0,
            seconds_ocean: 0.0,
            seconds_tessellation: 0.0,
            seconds_build: 0.0,
            seconds_levels: 0.0,
            seconds_trace: 0.0,
            seconds_normal_map: 0.0,
            seconds_total: spp as f64,
            memory_bytes: 0,
            rays: 0,
            error,
            error_ci: ci,
            bias: 0.0,
            bias_ci: [0.0; 2],
            bias_resolved: false,
            error_plain: 0.0,
            noise: 0.0,
            rmse_relative: 0.0,
            rmse_relative_ci: [0.0; 2],
            pareto: false,
        }
    }

    #[test]
    fn monotone_within_intervals_and_pareto() {
        let mut pts = vec![
            point("a", 8, 0.30, [0.25, 0.35]),
            point("a", 16, 0.33, [0.28, 0.38]), // within the intervals: fine
            point("a", 32, 0.50, [0.45, 0.55]), // significantly worse than 16
            point("b", 8, 0.10, [0.05, 0.15]),
        ];
        assert_eq!(
            not_monotone(&pts),
            vec!["a mapped 16 -> 32 spp".to_string()]
        );
        mark_pareto(&mut pts);
        // b at 8 spp is as fast as a at 8 and closer: a's points are all beaten.
        assert_eq!(
            pts.iter().map(|p| p.pareto).collect::<Vec<_>>(),
            [false, false, false, true]
        );
        assert_eq!(figure(0.1, [0.05, 0.15], true), "0.1000 [0.0500, 0.1500]");
        assert_eq!(figure(0.0, [0.0, 0.02], false), "< 0.0200");
    }

    #[test]
    fn another_method_is_matched_at_each_mapped_error_on_any_mesh() {
        let with = |mut p: Point, normals: NormalMode, seconds: f64| {
            (p.normals, p.seconds_total) = (normals, seconds);
            p
        };
        let pts = vec![
            point("a", 8, 0.30, [0.25, 0.35]),
            point("a", 16, 0.20, [0.15, 0.25]),
            point("b", 16, 0.10, [0.08, 0.12]),
            // filtered: on a at 0.22 (inside a's interval only), on b at 0.19 (at most a's
            // error, but dearer), and nothing near b's
            with(point("a", 8, 0.22, [0.21, 0.23]), NormalMode::Filtered, 2.0),
            with(point("b", 8, 0.19, [0.18, 0.20]), NormalMode::Filtered, 5.0),
            with(
                point("b", 16, 0.15, [0.14, 0.16]),
                NormalMode::Filtered,
                9.0,
            ),
        ];
        let m = report::matches(&pts);
        // a's and b's renders at their most samples (16), one method
        assert_eq!(m.len(), 2, "{m:?}");
        assert_eq!(
            (m[0].mapped.as_str(), m[0].method.as_str()),
            ("a 16", "filtered mesh")
        );
        assert_eq!(m[0].at_most.as_ref().map(|r| r.0.as_str()), Some("b 8"));
        assert_eq!(m[0].within.as_ref().map(|r| r.0.as_str()), Some("a 8"));
        assert_eq!(m[1].mapped, "b 16");
        assert!(m[1].at_most.is_none() && m[1].within.is_none());
    }
}
