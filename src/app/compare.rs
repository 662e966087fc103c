//! `vastocean compare`: the scenario comparison of the paper's section 5. The four scenarios
//! (high/low tessellation x with/without normal mapping) and a noise floor are rendered from
//! one ocean, one sky and one camera, each tessellation built once and traced for every
//! scenario that uses it; then the per-row statistics against the baseline (scenario 1), the
//! renders, `stats.csv`, the plots and `summary.json`.

use std::fmt;
use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use super::AppError;
use crate::analysis::error::{
    EstimateError, Estimates, Estimator, Inputs, Interval, RatioEstimate,
};
use crate::analysis::plot;
use crate::config::{LodConfig, NormalMode, Projection, SceneConfig};
use crate::image_io::{auto_exposure, write_atomically, write_exr_with, write_json, write_png};
use crate::render::film::MAX_BATCHES;
use crate::render::pipeline::{Rendered, prepare};

/// What to compare: one scene (ocean, sky, camera, samples) and the two tessellations.
#[derive(Clone, Debug, Serialize)]
pub struct CompareJob {
    pub scene: SceneConfig,
    pub high: LodConfig,
    pub low: LodConfig,
    /// Elevation rows analysed: from `rows_deg.0` down to `rows_deg.1` (the paper: 0 to -5).
    pub rows_deg: (f64, f64),
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
        }
    }

    fn high(self) -> bool {
        !matches!(self, Scenario::LowMapped | Scenario::LowUnmapped)
    }

    fn normals(self) -> NormalMode {
        match self {
            Scenario::HighUnmapped | Scenario::LowUnmapped => NormalMode::Vertex,
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
}

/// `summary.json`: band averages (the paper's, and noise-corrected with 95 % intervals), the
/// improvement ratio and its verdict, and what each scenario cost.
#[derive(Clone, Debug, Serialize)]
pub struct CompareSummary {
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
    pub improvement_ratio_median_rows: f64,
    pub improvement_ratio_without_glint: Interval,
    /// When not significant: the spp that would resolve it, if more samples can.
    pub improvement_spp_to_resolve: Option<u64>,
    /// Of the trend and of the residual detail.
    pub improvement_ratio_trend: Interval,
    pub improvement_ratio_residual: Interval,
    /// The noise floor's measured over predicted variance: about 1 if the noise model holds.
    pub noise_model_check: Interval,
    pub rows: usize,
    pub rows_deg: (f64, f64),
    pub spp: u32,
    pub wrong_side: crate::config::WrongSide,
    /// Every scenario against the baseline: per-row and band estimates with intervals.
    pub estimates: Estimates,
    pub improvement: RatioEstimate,
    pub scenarios: Vec<ScenarioInfo>,
    pub seconds_total: f64,
    pub stats_csv: PathBuf,
    pub stats_png: PathBuf,
    pub sheet_png: PathBuf,
}

/// The noise floor's measured over predicted variance beyond which (interval and all) the noise
/// estimate is reported as unreliable.
pub const NOISE_CHECK_RANGE: (f64, f64) = (0.8, 1.25);

/// The scene as one tessellation renders it.
fn with_lod(scene: &SceneConfig, lod: &LodConfig) -> SceneConfig {
    SceneConfig {
        lod: lod.clone(),
        ..scene.clone()
    }
}

/// Checks everything that can be checked before any work: the scene with each tessellation,
/// the camera, and that the analysed rows lie inside the rendered band.
fn check(job: &CompareJob) -> Result<(), AppError> {
    for lod in [&job.high, &job.low] {
        let scene = with_lod(&job.scene, lod);
        scene.validate()?;
        crate::lod::params_for(&scene.lod, &scene.camera)?;
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

/// Renders every scenario, each tessellation prepared once; returned in [`Scenario::ALL`]
/// order.
fn render_scenarios(job: &CompareJob) -> Result<Vec<(ScenarioInfo, Rendered)>, AppError> {
    let mut out = Vec::new();
    for (high, lod) in [(true, &job.high), (false, &job.low)] {
        let cfg = with_lod(&job.scene, lod);
        if job.progress {
            eprintln!(
                "compare: {} tessellation ({:?})",
                if high { "high" } else { "low" },
                lod.preset
            );
        }
        let prepared = prepare(&cfg)?;
        for sc in Scenario::ALL.into_iter().filter(|s| s.high() == high) {
            let mut c = cfg.clone();
            c.render.normals = sc.normals();
            c.render.seed = cfg.render.seed.wrapping_add(sc.seed_offset());
            let r = prepared.render_batches(&c, MAX_BATCHES, job.progress)?;
            let rep = &r.report;
            let info = ScenarioInfo {
                name: sc,
                tessellation: format!("{:?} ({} triangles)", lod.preset, rep.triangles),
                normals: sc.normals(),
                seed: c.render.seed,
                triangles: rep.triangles,
                seconds_tessellation: rep.seconds_tessellation,
                seconds_build: rep.seconds_build,
                seconds_render: rep.seconds_trace,
                wrong_side_count: rep.wrong_side_count,
                nan_count: rep.nan_count,
                counters: rep.counters,
                exr: job.out.join(format!("{}.exr", sc.name())),
                png: job.out.join(format!("{}.png", sc.name())),
            };
            out.push((info, r));
        }
    }
    out.sort_by_key(|(info, _)| Scenario::ALL.iter().position(|s| *s == info.name));
    Ok(out)
}

/// `stats.csv`: one line per analysed row; per scenario the paper's mean and std (the
/// columns of earlier versions, first), then the noise, the corrected std with its interval and
/// whether the row is a glint outlier.
fn write_stats_csv(path: &Path, e: &Estimates) -> Result<(), AppError> {
    Ok(write_atomically(path, |w| {
        use std::io::Write;
        write!(w, "elevation_deg")?;
        for sc in &e.scenarios {
            write!(w, ",mean_{0},std_{0}", sc.name)?;
        }
        for sc in &e.scenarios {
            write!(
                w,
                ",noise_{0},std_corrected_{0},std_corrected_lo_{0},std_corrected_hi_{0},glint_{0}",
                sc.name
            )?;
        }
        writeln!(w)?;
        for i in 0..e.rows {
            write!(w, "{:.6}", e.scenarios[0].rows[i].elevation_deg)?;
            for sc in &e.scenarios {
                let r = &sc.rows[i];
                write!(w, ",{:.9},{:.9}", r.mean, r.std)?;
            }
            for sc in &e.scenarios {
                let r = &sc.rows[i];
                write!(
                    w,
                    ",{:.9},{:.9},{:.9},{:.9},{}",
                    r.noise,
                    r.std_corrected,
                    r.std_corrected_ci[0],
                    r.std_corrected_ci[1],
                    u8::from(r.glint)
                )?;
            }
            writeln!(w)?;
        }
        Ok(())
    })?)
}

/// Runs the comparison into `job.out`.
pub fn run(job: &CompareJob) -> Result<CompareSummary, AppError> {
    check(job)?;
    let t_total = Instant::now();
    let runs = render_scenarios(job)?;
    let (top, bottom) = job.rows_deg;

    // One exposure for all, so the sheet compares like with like.
    let exposure = auto_exposure(&runs[0].1.film.image);
    for (info, r) in &runs {
        write_exr_with(&info.exr, &r.film.image, &[("Y.variance", &r.film.var_y)])?;
        write_png(&info.png, &r.film.image, exposure)?;
    }

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
    let summary = CompareSummary {
        std_high_unmapped: e[0].std,
        std_low_mapped: e[1].std,
        std_low_unmapped: e[2].std,
        std_noise_floor: e[3].std,
        mean_high_unmapped: e[0].mean.value,
        mean_low_mapped: e[1].mean.value,
        mean_low_unmapped: e[2].mean.value,
        mean_noise_floor: e[3].mean.value,
        improvement_ratio: improvement.plain,
        std_high_unmapped_corrected: e[0].std_corrected.value,
        std_low_mapped_corrected: e[1].std_corrected.value,
        std_low_unmapped_corrected: e[2].std_corrected.value,
        std_noise_floor_corrected: e[3].std_corrected.value,
        improvement_ratio_corrected: improvement.corrected.value,
        improvement_ratio_ci: improvement.corrected.ci,
        improvement_significant: improvement.significant,
        improvement_ratio_median_rows: improvement.median_rows,
        improvement_ratio_without_glint: improvement.without_glint,
        improvement_spp_to_resolve: improvement.spp_to_resolve,
        improvement_ratio_trend: improvement.trend,
        improvement_ratio_residual: improvement.residual,
        noise_model_check: e[3].variance_over_noise,
        rows: estimates.rows,
        rows_deg: (top, bottom),
        spp: job.scene.render.spp,
        wrong_side: job.scene.render.wrong_side,
        scenarios: runs.into_iter().map(|(info, _)| info).collect(),
        estimates,
        improvement,
        seconds_total: t_total.elapsed().as_secs_f64(),
        stats_csv,
        stats_png,
        sheet_png,
    };
    write_json(&job.out.join("summary.json"), &summary)?;
    Ok(summary)
}

impl fmt::Display for CompareSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let ci = |i: &Interval| format!("{:.5} [{:.5}, {:.5}]", i.value, i.ci[0], i.ci[1]);
        let num = |x: f64| {
            if x.is_finite() {
                format!("{x:.2}")
            } else {
                "n/a".into()
            }
        };
        writeln!(
            f,
            "compare: {} rows from {} to {} degrees at {} spp; band-averaged std of the luminance difference from the baseline",
            self.rows, self.rows_deg.0, self.rows_deg.1, self.spp
        )?;
        writeln!(
            f,
            "  (paper's statistic, noise included | noise-corrected with 95% interval | RMS noise)"
        )?;
        for e in &self.estimates.scenarios {
            writeln!(
                f,
                "  {:<14} {:>9.5} | {} | {:.5}{}",
                e.name,
                e.std,
                ci(&e.std_corrected),
                e.noise,
                if e.significant {
                    ""
                } else {
                    "  (not significantly different from the baseline)"
                }
            )?;
        }
        writeln!(
            f,
            "  noise model check (noise floor, measured / predicted variance): {}",
            ci(&self.noise_model_check)
        )?;
        let r = &self.improvement;
        writeln!(
            f,
            "  improvement ratio (low unmapped / low mapped): paper's statistic {}; corrected {} [{}, {}]; median over rows {}; trend {}, residual {}",
            num(r.plain),
            num(r.corrected.value),
            num(r.corrected.ci[0]),
            num(r.corrected.ci[1]),
            num(r.median_rows),
            num(r.trend.value),
            num(r.residual.value)
        )?;
        if r.significant {
            writeln!(f, "  normal mapping's effect is significant at 95%")?;
        } else {
            match r.spp_to_resolve {
                Some(n) => writeln!(
                    f,
                    "  NOT significant at 95%: about {n} spp would resolve it if the ratio stays near {:.2}",
                    r.corrected.value
                )?,
                None => writeln!(
                    f,
                    "  NOT significant at 95%, and more samples alone would not resolve it: {:.0}% of the interval's variance is spread over azimuth, not noise (render wider, or more cases)",
                    100.0 * (1.0 - r.noise_share_of_variance)
                )?,
            }
        }
        let glint = &self.estimates.scenarios[0].glint_rows_deg;
        if !glint.is_empty() {
            let w = &r.without_glint;
            writeln!(
                f,
                "  {} of {} rows cross the sun's glint ({:.2} to {:.2} degrees); without them the corrected ratio is {} [{}, {}]",
                glint.len(),
                self.rows,
                glint.first().copied().unwrap_or(0.0),
                glint.last().copied().unwrap_or(0.0),
                num(w.value),
                num(w.ci[0]),
                num(w.ci[1])
            )?;
        }
        let check = &self.noise_model_check;
        if check.ci[1] < NOISE_CHECK_RANGE.0 || check.ci[0] > NOISE_CHECK_RANGE.1 {
            writeln!(
                f,
                "  warning: the noise floor's measured / predicted variance is {} [{}, {}], well away from 1: the noise estimate is unreliable here (heavy-tailed samples, usually a bright sun's glint); trust the summary without glint rows, clip the sun or render more samples",
                num(check.value),
                num(check.ci[0]),
                num(check.ci[1])
            )?;
        }
        for sc in &self.scenarios {
            writeln!(
                f,
                "  {:<14} {:>9} triangles  tessellation {:.2} s  BVH {:.2} s  render {:.2} s",
                sc.name.name(),
                sc.triangles,
                sc.seconds_tessellation,
                sc.seconds_build,
                sc.seconds_render
            )?;
        }
        let dir = self.stats_csv.parent().unwrap_or(Path::new("."));
        write!(
            f,
            "  wrote {} {} {} and the renders in {}",
            self.stats_csv.display(),
            self.stats_png.display(),
            self.sheet_png.display(),
            dir.display()
        )
    }
}
