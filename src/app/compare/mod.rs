//! `vastocean compare`: the scenario comparison of the paper's section 5. The four scenarios
//! (high/low tessellation x with/without normal mapping) and a noise floor are rendered from
//! one ocean, one sky and one camera, each tessellation built once and traced for every
//! scenario that uses it; then the per-row statistics against the baseline (scenario 1), the
//! renders, `stats.csv`, the plots and `summary.json`. With `--against truth` every scenario is
//! also measured against a truth free of wrong-side events ([`truth`]).

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use super::AppError;
use crate::analysis::error::{
    EstimateError, Estimates, Estimator, Inputs, Interval, MIN_BATCHES, RatioEstimate,
};
use crate::analysis::plot;
use crate::config::{LodConfig, NormalMode, Projection, SceneConfig, SurfaceKind};
use crate::image_io::{png_exposure, write_exr_with, write_json, write_png};
use render::{exact_scene, render_scenarios, with_lod};

/// What to compare: one scene (ocean, sky, camera, samples) and the two tessellations.
#[derive(Clone, Debug, Serialize)]
pub struct CompareJob {
    pub scene: SceneConfig,
    pub high: LodConfig,
    pub low: LodConfig,
    /// Elevation rows analysed: from `rows_deg.0` down to `rows_deg.1` (the paper: 0 to -5).
    pub rows_deg: (f64, f64),
    /// Most samples a noisy analysed pixel may take, in multiples of the scene's spp; 1
    /// renders every pixel alike (see [`sampling`]).
    pub max_boost: u16,
    /// Also render the low tessellation with filtered normals (scenario `low_filtered`, after
    /// the noise floor; docs/filtered.md).
    #[serde(default)]
    pub filtered: bool,
    /// Also render the low tessellation's exact displaced surface with mapped normals
    /// (scenario `low_exact`; docs/exact.md), and with `filtered` with filtered normals as well
    /// (`low_exact_filtered`, last).
    #[serde(default)]
    pub exact: bool,
    /// What the scenarios are measured against: the paper's baseline, or that and the truth.
    #[serde(default)]
    pub against: Against,
    /// The truth's samples per analysed pixel, in multiples of the scenarios'.
    pub truth_boost: u16,
    /// Reuse the truth an earlier comparison of the same scene wrote into this folder instead
    /// of rendering one (with `against` = truth).
    #[serde(default)]
    pub truth_from: Option<PathBuf>,
    /// Output folder.
    pub out: PathBuf,
    /// Progress on stderr.
    #[serde(skip)]
    pub progress: bool,
}

/// The paper's scenarios, in its order (1, the baseline, first), and the noise floor: the
/// baseline again with independent sample seeds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Scenario {
    HighMapped,
    HighUnmapped,
    LowMapped,
    LowUnmapped,
    NoiseFloor,
    /// Beyond the paper, with `--filtered`: the low tessellation with filtered normals.
    LowFiltered,
    /// Beyond the paper, with `--exact`: the exact displaced surface inside the low
    /// tessellation's triangles, mapped normals.
    LowExact,
    /// With `--exact --filtered`: the exact surface with filtered normals (each path meets the
    /// waves its footprint resolves; docs/exact.md).
    LowExactFiltered,
}

impl Scenario {
    pub const ALL: [Scenario; 5] = [
        Scenario::HighMapped,
        Scenario::HighUnmapped,
        Scenario::LowMapped,
        Scenario::LowUnmapped,
        Scenario::NoiseFloor,
    ];

    /// File stem and JSON name.
    pub fn name(self) -> &'static str {
        match self {
            Scenario::HighMapped => "high_mapped",
            Scenario::HighUnmapped => "high_unmapped",
            Scenario::LowMapped => "low_mapped",
            Scenario::LowUnmapped => "low_unmapped",
            Scenario::NoiseFloor => "noise_floor",
            Scenario::LowFiltered => "low_filtered",
            Scenario::LowExact => "low_exact",
            Scenario::LowExactFiltered => "low_exact_filtered",
        }
    }

    fn high(self) -> bool {
        !matches!(
            self,
            Scenario::LowMapped
                | Scenario::LowUnmapped
                | Scenario::LowFiltered
                | Scenario::LowExact
                | Scenario::LowExactFiltered
        )
    }

    /// Whether the scenario renders the exact surface (in the low tessellation).
    fn exact(self) -> bool {
        matches!(self, Scenario::LowExact | Scenario::LowExactFiltered)
    }

    fn normals(self) -> NormalMode {
        match self {
            Scenario::HighUnmapped | Scenario::LowUnmapped => NormalMode::Vertex,
            Scenario::LowFiltered | Scenario::LowExactFiltered => NormalMode::Filtered,
            _ => NormalMode::Mapped,
        }
    }

    /// Added to the scene's sample seed.
    fn seed_offset(self) -> u64 {
        if self == Scenario::NoiseFloor {
            0x9e37_79b9
        } else {
            0
        }
    }
}

impl CompareJob {
    /// The scenarios this job renders: the paper's four and the noise floor, then
    /// `low_filtered`, `low_exact` and `low_exact_filtered` if asked for.
    pub fn scenarios(&self) -> Vec<Scenario> {
        let mut s = Scenario::ALL.to_vec();
        if self.filtered {
            s.push(Scenario::LowFiltered);
        }
        if self.exact {
            s.push(Scenario::LowExact);
        }
        if self.exact && self.filtered {
            s.push(Scenario::LowExactFiltered);
        }
        s
    }
}

/// One rendered scenario.
#[derive(Clone, Debug, Serialize)]
pub struct ScenarioInfo {
    pub name: Scenario,
    pub tessellation: String,
    pub normals: NormalMode,
    pub seed: u64,
    pub triangles: usize,
    pub seconds_tessellation: f64,
    pub seconds_build: f64,
    pub seconds_render: f64,
    pub wrong_side_count: u64,
    pub nan_count: u64,
    /// Every counter of the render (hits, normals facing away, bent, ended branches, ...).
    pub counters: crate::render::Counters,
    pub exr: PathBuf,
    pub png: PathBuf,
    /// With `--against truth`: the corrected band std of this scenario's difference from the
    /// truth, and the band mean of that difference, with their intervals (the noise floor,
    /// a second draw of the baseline, is not measured against it).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub std_vs_truth: Option<Interval>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mean_vs_truth: Option<Interval>,
}

/// `summary.json`: band averages (the paper's, and noise-corrected with 95 % intervals), the
/// improvement ratio and its verdict, and what each scenario cost. JSON has no infinity: an
/// unbounded interval end (a ratio whose denominator fell to 0 in some replicates) is null.
#[derive(Clone, Debug, Serialize)]
pub struct CompareSummary {
    /// The commit of the vastocean that measured this (see [`crate::app::commit`]).
    pub commit: &'static str,
    /// The paper's statistic: band average of the rows' std of Y(scenario) - Y(baseline),
    /// Monte Carlo noise included.
    pub std_high_unmapped: f64,
    pub std_low_mapped: f64,
    pub std_low_unmapped: f64,
    pub std_noise_floor: f64,
    pub mean_high_unmapped: f64,
    pub mean_low_mapped: f64,
    pub mean_low_unmapped: f64,
    pub mean_noise_floor: f64,
    /// With `--filtered`: the paper's statistic and its noise-corrected value for
    /// `low_filtered` (its intervals are in `estimates`).
    pub std_low_filtered: Option<f64>,
    pub std_low_filtered_corrected: Option<f64>,
    pub mean_low_filtered: Option<f64>,
    /// With `--exact`: the same for `low_exact`.
    pub std_low_exact: Option<f64>,
    pub std_low_exact_corrected: Option<f64>,
    pub mean_low_exact: Option<f64>,
    /// With `--exact --filtered`: the same for `low_exact_filtered`.
    pub std_low_exact_filtered: Option<f64>,
    pub std_low_exact_filtered_corrected: Option<f64>,
    pub mean_low_exact_filtered: Option<f64>,
    /// std(low unmapped) / std(low mapped) of the paper's statistic (the paper: 5 to 10 for
    /// its case 87).
    pub improvement_ratio: f64,
    /// The same statistics with the noise taken out (see `crate::analysis::error`).
    pub std_high_unmapped_corrected: f64,
    pub std_low_mapped_corrected: f64,
    pub std_low_unmapped_corrected: f64,
    pub std_noise_floor_corrected: f64,
    pub improvement_ratio_corrected: f64,
    pub improvement_ratio_ci: [f64; 2],
    /// The interval excludes 1.
    pub improvement_significant: bool,
    /// The same ratio of the median and of the trimmed mean over rows, and without glint rows.
    pub improvement_ratio_median_rows: Interval,
    pub improvement_ratio_trimmed: Interval,
    pub improvement_ratio_without_glint: Interval,
    /// When not significant: the spp that would resolve it if the ratio stayed put.
    pub improvement_spp_to_resolve: Option<u64>,
    /// Of the trend and of the residual detail.
    pub improvement_ratio_trend: Interval,
    pub improvement_ratio_residual: Interval,
    /// The noise floor's measured over predicted variance: about 1 if the noise model holds.
    pub noise_model_check: Interval,
    /// The baseline's own noise: the RMS standard error of its pixel luminance over the analysed
    /// rows, and that over the smallest corrected std it ranks (of the three scenarios; at most
    /// [`BASELINE_NOISE_SHARE`] for the baseline to resolve every difference it ranks).
    pub baseline_noise: f64,
    pub baseline_noise_share: f64,
    pub rows: usize,
    pub rows_deg: (f64, f64),
    pub spp: u32,
    /// Where the samples went: the pilot, the boosted pixels, the cost.
    pub sampling: SamplingReport,
    pub wrong_side: crate::config::WrongSide,
    /// How every scenario (and the truth) reads the ocean's layers.
    pub interp: crate::ocean::Interp,
    /// Every scenario against the baseline: per-row and band estimates with intervals.
    pub estimates: Estimates,
    pub improvement: RatioEstimate,
    pub scenarios: Vec<ScenarioInfo>,
    pub seconds_total: f64,
    pub stats_csv: PathBuf,
    pub stats_png: PathBuf,
    pub sheet_png: PathBuf,
    pub against: Against,
    /// With `--against truth`: how the truth was rendered and its wrong-side share, its
    /// analysed rows, every scenario against it (per scenario `std_vs_truth` in `scenarios`)
    /// and the per-row statistics in `stats_vs_truth.csv`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub truth: Option<Truth>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub truth_rows: Option<Vec<TruthRow>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub estimates_vs_truth: Option<Estimates>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stats_vs_truth_csv: Option<PathBuf>,
}

/// Checks everything that can be checked before any work: the scene with each tessellation,
/// the camera, and that the analysed rows lie inside the rendered band.
fn check(job: &CompareJob) -> Result<(), AppError> {
    if job.scene.render.surface != SurfaceKind::Mesh {
        return Err(AppError::input(
            "compare renders the paper's scenarios on the mesh (render.surface = \"mesh\", \
             --surface mesh); --exact adds the exact surface as scenario low_exact",
        ));
    }
    for lod in [&job.high, &job.low] {
        let scene = with_lod(&job.scene, lod);
        scene.validate()?;
        crate::lod::params_for(&scene.lod, &scene.camera)?;
    }
    if job.exact || job.against == Against::Truth {
        exact_scene(job).validate()?;
    }
    if job.truth_from.is_some() && job.against != Against::Truth {
        return Err(AppError::input(
            "--truth-from reuses a truth: it goes with --against truth",
        ));
    }
    if job.truth_boost == 0 {
        return Err(AppError::input(
            "the truth's boost (--truth-boost) is at least 1",
        ));
    }
    let spp = job.scene.render.spp;
    if (spp as usize) < MIN_BATCHES || !(spp as usize).is_multiple_of(MIN_BATCHES) {
        return Err(AppError::input(format!(
            "compare needs a multiple of {MIN_BATCHES} samples per pixel (--spp), as many in each of the {MIN_BATCHES} independent batches its error estimate reads (got {spp})"
        )));
    }
    if job.max_boost == 0 {
        return Err(AppError::input(
            "the most boost (--max-boost) is at least 1",
        ));
    }
    let (top, bottom) = job.rows_deg;
    if !(top.is_finite() && bottom.is_finite() && top > bottom) {
        return Err(AppError::input(format!(
            "rows must run from a higher to a lower elevation (got {top}:{bottom})"
        )));
    }
    let Projection::Equirect { band_deg } = job.scene.camera.projection else {
        return Err(AppError::input(
            "compare needs the equirectangular camera (elevation rows)",
        ));
    };
    if let Some((bt, bb)) = band_deg
        && (top > bt || bottom < bb)
    {
        return Err(AppError::input(format!(
            "the analysed rows {top}:{bottom} must lie inside the rendered band {bt}:{bb}"
        )));
    }
    // The output folder, before minutes of work.
    super::check_output_dir(&job.out)
}

/// The largest share of the smallest difference a baseline's own noise may be for `compare`
/// not to warn.
pub const BASELINE_NOISE_SHARE: f64 = 0.25;

/// A render as `compare` writes it: the EXR with the channels the estimator reads, and the
/// PNG preview at the common `exposure`.
fn write_film(
    exr: &Path,
    png: &Path,
    film: &crate::render::film::Film,
    exposure: f32,
    compression: crate::image_io::ExrCompression,
) -> Result<(), AppError> {
    let channels = film_channels(film);
    let extra: Vec<(&str, &[f32])> = channels
        .iter()
        .map(|(n, v)| (n.as_str(), v.as_slice()))
        .collect();
    write_exr_with(exr, &film.image, &extra, compression)?;
    write_png(png, &film.image, exposure)?;
    Ok(())
}

/// Runs the comparison into `job.out`.
pub fn run(job: &CompareJob) -> Result<CompareSummary, AppError> {
    check(job)?;
    let t_total = Instant::now();
    let reused = match &job.truth_from {
        Some(dir) => Some(truth::load(job, dir)?),
        None => None,
    };
    let render::Renders {
        mut runs,
        truth,
        sampling,
    } = render_scenarios(job)?;
    let (top, bottom) = job.rows_deg;

    // One exposure for all, so the sheet compares like with like.
    let (exposure, _) = png_exposure(job.scene.render.exposure, &runs[0].1.film.image);
    let compression = job.scene.render.exr_compression;
    let pool = super::output_pool(job.scene.render.threads)?;
    for (info, r) in &runs {
        pool.install(|| write_film(&info.exr, &info.png, &r.film, exposure, compression))?;
    }
    if let Some((t, r)) = &truth {
        let png = t.exr.with_extension("png");
        pool.install(|| write_film(&t.exr, &png, &r.film, exposure, compression))?;
        let record = truth::TruthFile {
            scene: truth::scene(job),
            rows_deg: job.rows_deg,
            truth: t.clone(),
        };
        write_json(&job.out.join("truth.json"), &record)?;
    }
    let truth = truth.map(|(t, r)| (t, r.film)).or(reused);

    let compared: Vec<(String, &crate::render::film::Film)> = runs[1..]
        .iter()
        .map(|(info, r)| (info.name.name().to_string(), &r.film))
        .collect();
    let inputs = Inputs {
        camera: &runs[0].1.camera,
        baseline: &runs[0].1.film,
        scenarios: compared,
        rows_deg: (top, bottom),
        seed: job.scene.render.seed,
    };
    let estimator = Estimator::new(&inputs).map_err(|e| match e {
        EstimateError::Mismatch => AppError::Run(e.into()),
        _ => AppError::Input(e.into()),
    })?;
    let estimates = estimator.scenarios();
    // Indices into `compared`: high_unmapped, low_mapped, low_unmapped, noise_floor.
    let improvement = estimator.ratio(2, 1);
    let stats_csv = job.out.join("stats.csv");
    write_stats_csv(&stats_csv, &estimates)?;
    let plot_error = |path: &Path| {
        let path = path.to_path_buf();
        move |message: String| {
            AppError::Run(format!("cannot draw {}: {message}", path.display()).into())
        }
    };
    let stats_png = job.out.join("stats.png");
    plot::stats_plot(&stats_png, &estimates.scenarios, (top, bottom))
        .map_err(plot_error(&stats_png))?;
    let sheet_png = job.out.join("sheet.png");
    let labels: Vec<String> = runs[..4]
        .iter()
        .map(|(s, _)| {
            format!(
                "{}: {}, {} normals",
                s.name.name(),
                s.tessellation,
                s.normals
            )
        })
        .collect();
    let images: Vec<_> = runs[..4].iter().map(|(_, r)| &r.film.image).collect();
    plot::contact_sheet(&sheet_png, &images, &labels, exposure).map_err(plot_error(&sheet_png))?;

    let e = &estimates.scenarios;
    // the optional scenarios' estimates, by name
    let optional = |sc: Scenario| e.iter().find(|s| s.name == sc.name());
    let (filtered, exact, exact_filtered) = (
        optional(Scenario::LowFiltered),
        optional(Scenario::LowExact),
        optional(Scenario::LowExactFiltered),
    );
    // RMS over the analysed rows of the standard error of the baseline's pixel luminance.
    let rows = runs[0].1.camera.rows_between(job.rows_deg);
    let row_noise = runs[0].1.film.row_noise(&rows);
    let baseline_noise = (row_noise.iter().sum::<f64>() / row_noise.len().max(1) as f64).sqrt();
    let smallest = e[..3]
        .iter()
        .map(|s| s.std_corrected.value)
        .fold(f64::INFINITY, f64::min);
    // Every scenario against the truth, each scenario's figures beside the paper's.
    let vs_truth = match &truth {
        Some((_, film)) => Some(truth::estimates(job, &runs, film)?),
        None => None,
    };
    let stats_vs_truth_csv = match &vs_truth {
        Some(est) => {
            let path = job.out.join("stats_vs_truth.csv");
            write_stats_csv(&path, est)?;
            for (info, _) in runs.iter_mut() {
                let e = est.scenarios.iter().find(|s| s.name == info.name.name());
                info.std_vs_truth = e.map(|e| e.std_corrected);
                info.mean_vs_truth = e.map(|e| e.mean);
            }
            Some(path)
        }
        None => None,
    };
    let truth_rows = truth
        .as_ref()
        .map(|(_, film)| truth::rows(&runs[0].1.camera, film, job.rows_deg));
    let summary = CompareSummary {
        commit: super::commit(),
        std_high_unmapped: e[0].std,
        std_low_mapped: e[1].std,
        std_low_unmapped: e[2].std,
        std_noise_floor: e[3].std,
        mean_high_unmapped: e[0].mean.value,
        mean_low_mapped: e[1].mean.value,
        mean_low_unmapped: e[2].mean.value,
        mean_noise_floor: e[3].mean.value,
        std_low_filtered: filtered.map(|s| s.std),
        std_low_filtered_corrected: filtered.map(|s| s.std_corrected.value),
        mean_low_filtered: filtered.map(|s| s.mean.value),
        std_low_exact: exact.map(|s| s.std),
        std_low_exact_corrected: exact.map(|s| s.std_corrected.value),
        mean_low_exact: exact.map(|s| s.mean.value),
        std_low_exact_filtered: exact_filtered.map(|s| s.std),
        std_low_exact_filtered_corrected: exact_filtered.map(|s| s.std_corrected.value),
        mean_low_exact_filtered: exact_filtered.map(|s| s.mean.value),
        improvement_ratio: improvement.plain,
        std_high_unmapped_corrected: e[0].std_corrected.value,
        std_low_mapped_corrected: e[1].std_corrected.value,
        std_low_unmapped_corrected: e[2].std_corrected.value,
        std_noise_floor_corrected: e[3].std_corrected.value,
        improvement_ratio_corrected: improvement.corrected.value,
        improvement_ratio_ci: improvement.corrected.ci,
        improvement_significant: improvement.significant,
        improvement_ratio_median_rows: improvement.median_rows,
        improvement_ratio_trimmed: improvement.trimmed,
        improvement_ratio_without_glint: improvement.without_glint,
        improvement_spp_to_resolve: improvement.spp_to_resolve,
        improvement_ratio_trend: improvement.trend,
        improvement_ratio_residual: improvement.residual,
        noise_model_check: e[3].variance_over_noise,
        baseline_noise,
        baseline_noise_share: baseline_noise / smallest,
        rows: estimates.rows,
        rows_deg: (top, bottom),
        spp: job.scene.render.spp,
        sampling,
        wrong_side: job.scene.render.wrong_side,
        interp: job.scene.ocean.interp,
        scenarios: runs.into_iter().map(|(info, _)| info).collect(),
        estimates,
        improvement,
        seconds_total: t_total.elapsed().as_secs_f64(),
        stats_csv,
        stats_png,
        sheet_png,
        against: job.against,
        truth: truth.map(|(t, _)| t),
        truth_rows,
        estimates_vs_truth: vs_truth,
        stats_vs_truth_csv,
    };
    write_json(&job.out.join("summary.json"), &summary)?;
    Ok(summary)
}

pub mod realizations;
mod render;
mod report;
pub mod sampling;
pub mod truth;
pub use report::NOISE_CHECK_RANGE;
use report::{film_channels, write_stats_csv};
pub use sampling::SamplingReport;
pub use truth::{Against, DEFAULT_TRUTH_BOOST, Truth, TruthRow};
