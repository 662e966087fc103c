//! The scenario comparison of the paper's section 5: the four scenarios (high/low tessellation
//! x with/without normal mapping) and a noise floor rendered from one ocean, one sky and one
//! camera, each tessellation built once and traced for every scenario that uses it; then the
//! per-row statistics against the baseline, `stats.csv`, the plots and `summary.json`.

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use super::{RowStat, band_average, plot, row_difference_stats};
use crate::config::{LodConfig, SceneConfig};
use crate::image_io::{
    ImageError, auto_exposure, write_atomically, write_exr, write_json, write_png,
};
use crate::render::pipeline::{RenderError, Rendered, prepare};
use crate::render::{NormalMode, Projection};

/// What to compare: one scene (ocean, sky, camera, samples) and the two tessellations.
#[derive(Clone, Debug, Serialize)]
pub struct CompareOptions {
    pub scene: SceneConfig,
    pub high: LodConfig,
    pub low: LodConfig,
    /// Elevation rows analysed: from `rows_deg.0` down to `rows_deg.1` (the paper: 0 to -5).
    pub rows_deg: (f64, f64),
}

/// One rendered scenario.
#[derive(Clone, Debug, Serialize)]
pub struct ScenarioInfo {
    pub name: String,
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

/// Errors of a comparison.
#[derive(Debug, thiserror::Error)]
pub enum CompareError {
    #[error(transparent)]
    Render(#[from] RenderError),
    #[error(transparent)]
    Image(#[from] ImageError),
    #[error("cannot draw {}: {message}", path.display())]
    Plot { path: PathBuf, message: String },
    #[error("{0}")]
    Invalid(String),
}

/// The scenario names, in the paper's order (1 is the baseline), and the noise floor.
pub const SCENARIOS: [&str; 5] = [
    "high_mapped",
    "high_unmapped",
    "low_mapped",
    "low_unmapped",
    "noise_floor",
];

/// Renders the four scenarios and the noise floor into `out_dir` and writes the statistics.
pub fn compare(
    opts: &CompareOptions,
    out_dir: &Path,
    progress: bool,
) -> Result<CompareSummary, CompareError> {
    let (top, bottom) = opts.rows_deg;
    if !(top.is_finite() && bottom.is_finite() && top > bottom) {
        return Err(CompareError::Invalid(format!(
            "rows must run from a higher to a lower elevation (got {top}:{bottom})"
        )));
    }
    if let Projection::Equirect { band_deg } = opts.scene.camera.projection {
        if let Some((bt, bb)) = band_deg
            && (top > bt || bottom < bb)
        {
            return Err(CompareError::Invalid(format!(
                "the analysed rows {top}:{bottom} must lie inside the rendered band {bt}:{bb}"
            )));
        }
    } else {
        return Err(CompareError::Invalid(
            "compare needs the equirectangular camera (elevation rows)".into(),
        ));
    }
    let t_total = Instant::now();
    let mut scenarios = Vec::new();
    let mut images: Vec<Rendered> = Vec::new();
    for (tess, lod) in [("high", &opts.high), ("low", &opts.low)] {
        let mut cfg = opts.scene.clone();
        cfg.lod = lod.clone();
        if progress {
            eprintln!("compare: {tess} tessellation ({:?})", lod.preset);
        }
        let prepared = prepare(&cfg)?;
        let runs: &[(NormalMode, u64)] = if tess == "high" {
            // The noise floor: the baseline scenario again with independent sample seeds.
            &[
                (NormalMode::Mapped, 0),
                (NormalMode::Vertex, 0),
                (NormalMode::Mapped, 0x9e37_79b9),
            ]
        } else {
            &[(NormalMode::Mapped, 0), (NormalMode::Vertex, 0)]
        };
        for &(normals, seed_offset) in runs {
            let mut c = cfg.clone();
            c.render.normals = normals;
            c.render.seed = cfg.render.seed.wrapping_add(seed_offset);
            let r = prepared.render(&c, progress)?;
            let name = match (tess, normals, seed_offset) {
                (_, _, s) if s != 0 => "noise_floor".to_string(),
                (t, NormalMode::Mapped, _) => format!("{t}_mapped"),
                (t, NormalMode::Vertex, _) => format!("{t}_unmapped"),
            };
            let rep = &r.report;
            scenarios.push(ScenarioInfo {
                name,
                tessellation: format!("{:?} ({} triangles)", lod.preset, rep.triangles),
                normals,
                seed: c.render.seed,
                triangles: rep.triangles,
                seconds_tessellation: rep.seconds_tessellation,
                seconds_build: rep.seconds_build,
                seconds_render: rep.seconds_trace,
                wrong_side_count: rep.wrong_side_count,
                nan_count: rep.nan_count,
                exr: PathBuf::new(),
                png: PathBuf::new(),
            });
            images.push(r);
        }
    }
    // Order as SCENARIOS: high_mapped, high_unmapped, low_mapped, low_unmapped, noise_floor.
    let order: Vec<usize> = SCENARIOS
        .iter()
        .map(|n| {
            scenarios
                .iter()
                .position(|s| s.name == *n)
                .expect("every scenario rendered")
        })
        .collect();
    let scenarios: Vec<ScenarioInfo> = order.iter().map(|&i| scenarios[i].clone()).collect();
    let images: Vec<&Rendered> = order.iter().map(|&i| &images[i]).collect();

    // One exposure for all, so the sheet compares like with like.
    let exposure = auto_exposure(&images[0].image);
    let mut scenarios = scenarios;
    for (s, r) in scenarios.iter_mut().zip(&images) {
        s.exr = out_dir.join(format!("{}.exr", s.name));
        s.png = out_dir.join(format!("{}.png", s.name));
        write_exr(&s.exr, &r.image)?;
        write_png(&s.png, &r.image, exposure)?;
    }

    let camera = &images[0].camera;
    let base = &images[0].image;
    let stats: Vec<Vec<RowStat>> = images[1..]
        .iter()
        .map(|r| row_difference_stats(&r.image, base, camera, top, bottom))
        .collect();
    if stats[0].is_empty() {
        return Err(CompareError::Invalid(format!(
            "no image row lies between {top} and {bottom} degrees; widen the band or the image"
        )));
    }
    let stats_csv = out_dir.join("stats.csv");
    write_atomically(&stats_csv, |w| {
        use std::io::Write;
        writeln!(
            w,
            "elevation_deg,mean_high_unmapped,std_high_unmapped,mean_low_mapped,std_low_mapped,mean_low_unmapped,std_low_unmapped,mean_noise_floor,std_noise_floor"
        )?;
        for i in 0..stats[0].len() {
            write!(w, "{:.6}", stats[0][i].elevation_deg)?;
            for s in &stats {
                write!(w, ",{:.9},{:.9}", s[i].mean, s[i].std)?;
            }
            writeln!(w)?;
        }
        Ok(())
    })?;
    let stats_png = out_dir.join("stats.png");
    plot::stats_plot(&stats_png, &stats, (top, bottom)).map_err(|message| CompareError::Plot {
        path: stats_png.clone(),
        message,
    })?;
    let sheet_png = out_dir.join("sheet.png");
    let labels: Vec<String> = scenarios[..4]
        .iter()
        .map(|s| {
            format!(
                "{}: {}, {} normals",
                s.name,
                s.tessellation,
                if s.normals == NormalMode::Mapped {
                    "mapped"
                } else {
                    "vertex"
                }
            )
        })
        .collect();
    plot::contact_sheet(
        &sheet_png,
        &images[..4].iter().map(|r| &r.image).collect::<Vec<_>>(),
        &labels,
        exposure,
    )
    .map_err(|message| CompareError::Plot {
        path: sheet_png.clone(),
        message,
    })?;

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
        scenarios,
        seconds_total: t_total.elapsed().as_secs_f64(),
        stats_csv,
        stats_png,
        sheet_png,
    };
    write_json(&out_dir.join("summary.json"), &summary)?;
    Ok(summary)
}
