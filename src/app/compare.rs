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
use crate::analysis::{RowStat, band_average, plot, row_difference_stats};
use crate::config::{LodConfig, NormalMode, Projection, SceneConfig};
use crate::image_io::{auto_exposure, write_atomically, write_exr, write_json, write_png};
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
    pub exr: PathBuf,
    pub png: PathBuf,
}

/// `summary.json`: band averages, the improvement ratio and what each scenario cost.
#[derive(Clone, Debug, Serialize)]
pub struct CompareSummary {
    pub std_high_unmapped: f64,
    pub std_low_mapped: f64,
    pub std_low_unmapped: f64,
    pub std_noise_floor: f64,
    pub mean_high_unmapped: f64,
    pub mean_low_mapped: f64,
    pub mean_low_unmapped: f64,
    pub mean_noise_floor: f64,
    /// std(low unmapped) / std(low mapped): how much normal mapping brings the low tessellation
    /// closer to the baseline (the paper: 5 to 10 for its case 87).
    pub improvement_ratio: f64,
    pub rows: usize,
    pub rows_deg: (f64, f64),
    pub scenarios: Vec<ScenarioInfo>,
    pub seconds_total: f64,
    pub stats_csv: PathBuf,
    pub stats_png: PathBuf,
    pub sheet_png: PathBuf,
}

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
    Ok(())
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
            let r = prepared.render(&c, job.progress)?;
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
                exr: job.out.join(format!("{}.exr", sc.name())),
                png: job.out.join(format!("{}.png", sc.name())),
            };
            out.push((info, r));
        }
    }
    out.sort_by_key(|(info, _)| Scenario::ALL.iter().position(|s| *s == info.name));
    Ok(out)
}

/// `stats.csv`: one line per analysed row, mean and std of each scenario's difference.
fn write_stats_csv(path: &Path, stats: &[Vec<RowStat>]) -> Result<(), AppError> {
    Ok(write_atomically(path, |w| {
        use std::io::Write;
        write!(w, "elevation_deg")?;
        for sc in &Scenario::ALL[1..] {
            write!(w, ",mean_{0},std_{0}", sc.name())?;
        }
        writeln!(w)?;
        for i in 0..stats[0].len() {
            write!(w, "{:.6}", stats[0][i].elevation_deg)?;
            for s in stats {
                write!(w, ",{:.9},{:.9}", s[i].mean, s[i].std)?;
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
    let exposure = auto_exposure(&runs[0].1.image);
    for (info, r) in &runs {
        write_exr(&info.exr, &r.image)?;
        write_png(&info.png, &r.image, exposure)?;
    }

    let camera = &runs[0].1.camera;
    let base = &runs[0].1.image;
    let stats: Vec<Vec<RowStat>> = runs[1..]
        .iter()
        .map(|(_, r)| row_difference_stats(&r.image, base, camera, top, bottom))
        .collect();
    if stats[0].is_empty() {
        return Err(AppError::input(format!(
            "no image row lies between {top} and {bottom} degrees; widen the band or the image"
        )));
    }
    let stats_csv = job.out.join("stats.csv");
    write_stats_csv(&stats_csv, &stats)?;
    let plot_error = |path: &Path| {
        let path = path.to_path_buf();
        move |message: String| {
            AppError::Run(format!("cannot draw {}: {message}", path.display()).into())
        }
    };
    let stats_png = job.out.join("stats.png");
    plot::stats_plot(&stats_png, &stats, (top, bottom)).map_err(plot_error(&stats_png))?;
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
    let images: Vec<_> = runs[..4].iter().map(|(_, r)| &r.image).collect();
    plot::contact_sheet(&sheet_png, &images, &labels, exposure).map_err(plot_error(&sheet_png))?;

    let avg: Vec<(f64, f64)> = stats.iter().map(|s| band_average(s)).collect();
    let summary = CompareSummary {
        std_high_unmapped: avg[0].1,
        std_low_mapped: avg[1].1,
        std_low_unmapped: avg[2].1,
        std_noise_floor: avg[3].1,
        mean_high_unmapped: avg[0].0,
        mean_low_mapped: avg[1].0,
        mean_low_unmapped: avg[2].0,
        mean_noise_floor: avg[3].0,
        improvement_ratio: avg[2].1 / avg[1].1,
        rows: stats[0].len(),
        rows_deg: (top, bottom),
        scenarios: runs.into_iter().map(|(info, _)| info).collect(),
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
        writeln!(
            f,
            "compare: {} rows from {} to {} degrees; band-averaged std of the luminance difference from the baseline:",
            self.rows, self.rows_deg.0, self.rows_deg.1
        )?;
        writeln!(
            f,
            "  high tessellation, unmapped  {:.5}",
            self.std_high_unmapped
        )?;
        writeln!(
            f,
            "  low tessellation, mapped     {:.5}",
            self.std_low_mapped
        )?;
        writeln!(
            f,
            "  low tessellation, unmapped   {:.5}",
            self.std_low_unmapped
        )?;
        writeln!(
            f,
            "  noise floor                  {:.5}",
            self.std_noise_floor
        )?;
        writeln!(
            f,
            "  improvement ratio (low unmapped / low mapped): {:.2}",
            self.improvement_ratio
        )?;
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
