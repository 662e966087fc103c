//! `study summarize`: the finished cases gathered into `cases.csv`, `per_sky.csv`,
//! `scatter.png` and `summary.json`.

use std::fmt;
use std::path::{Path, PathBuf};

use serde::Serialize;

use super::{case_dir, finished_summary, read_plan};
use crate::analysis::charts::{ScatterPoint, scatter};
use crate::app::AppError;
use crate::config::SceneConfig;
use crate::image_io::{stage, write_json};

/// One finished case, as `cases.csv` has it.
#[derive(Clone, Debug, Serialize)]
pub struct CaseRow {
    pub case: usize,
    pub wind_m_s: f64,
    pub fetch_km: f64,
    pub depth_m: f64,
    pub rms_m: f64,
    /// The RMS height over the spectrum's own, and Hs over the peak wavelength
    /// ([`super::sea_shape`]).
    pub rescale: f64,
    pub steepness: f64,
    pub sky: String,
    pub sun_elevation_deg: f64,
    /// Ocean realizations pooled into the row (1: one sea). With more, the stds are roots of
    /// mean band variances and the ratio the geometric mean over the seas (`compare
    /// --realizations`); the columns from the plain statistic to the cost are medians over
    /// the seas.
    pub realizations: usize,
    pub std_high_unmapped_corrected: f64,
    pub std_low_mapped_corrected: f64,
    pub std_low_mapped_ci: [f64; 2],
    pub std_low_unmapped_corrected: f64,
    pub std_low_unmapped_ci: [f64; 2],
    pub improvement_ratio: f64,
    pub improvement_ratio_corrected: f64,
    pub improvement_ratio_ci: [f64; 2],
    pub improvement_significant: bool,
    pub improvement_ratio_without_glint: f64,
    /// The ratio of the median and of the trimmed mean over rows (the robust summaries).
    pub improvement_ratio_median_rows: f64,
    pub improvement_ratio_trimmed: f64,
    pub glint_rows: usize,
    pub noise_model_check: f64,
    /// Samples of one scenario over a uniform render's (the boost of the noisy pixels).
    pub cost_factor: f64,
    pub seconds_total: f64,
    /// The commit of the vastocean that ran the case.
    pub commit: String,
}

/// `study summarize`'s `summary.json`.
#[derive(Clone, Debug, Serialize)]
pub struct StudySummary {
    /// The commit of the vastocean that summarized the study (each case's summary.json names
    /// the one that ran it).
    pub commit: &'static str,
    pub cases: usize,
    pub finished: usize,
    pub missing: Vec<usize>,
    /// Cases whose noise-corrected ratio (low unmapped / low mapped) exceeds 1.
    pub improved: usize,
    /// ... whose ratio's 95 % interval lies above 1, or below it.
    pub improved_significant: usize,
    pub worse_significant: usize,
    pub median_ratio: f64,
    pub ratio_quartiles: [f64; 2],
    pub seconds_total: f64,
    /// The commits the finished cases were run with (one, unless the study was resumed with
    /// another build).
    pub case_commits: Vec<String>,
    pub rows: Vec<CaseRow>,
    pub cases_csv: PathBuf,
    pub per_sky_csv: PathBuf,
    pub scatter_png: PathBuf,
}

/// Median and quartiles; an infinite ratio counts (as the largest), a NaN does not.
fn quartiles(v: &[f64]) -> (f64, [f64; 2]) {
    let mut s: Vec<f64> = v.iter().copied().filter(|x| !x.is_nan()).collect();
    s.sort_by(f64::total_cmp);
    if s.is_empty() {
        return (f64::NAN, [f64::NAN; 2]);
    }
    let q = |p: f64| crate::analysis::error::quantile(&s, p);
    (q(0.5), [q(0.25), q(0.75)])
}

/// The sun's elevation in a case's sky map (its brightest region), degrees.
fn sun_elevation(scene: &SceneConfig) -> f64 {
    scene
        .sky
        .file
        .as_ref()
        .and_then(|f| crate::image_io::read_exr(f).ok())
        .and_then(|img| crate::sky::tools::find_sun(&img))
        .map_or(f64::NAN, |(el, _)| el)
}

/// An unbounded upper end is null in JSON.
fn pair(val: &serde_json::Value) -> [f64; 2] {
    [
        val[0].as_f64().unwrap_or(f64::NAN),
        val[1].as_f64().unwrap_or(f64::INFINITY),
    ]
}

fn read_json(path: &Path) -> Result<serde_json::Value, AppError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| AppError::Input(format!("cannot read {}: {e}", path.display()).into()))?;
    serde_json::from_str(&text)
        .map_err(|e| AppError::Input(format!("{}: {e}", path.display()).into()))
}

/// The columns of a row that one comparison gives and a pool of seas does not: read from each
/// sea's comparison, and their medians for a pooled case.
#[derive(Clone, Copy)]
struct Minor {
    plain_ratio: f64,
    without_glint: f64,
    median_rows: f64,
    trimmed: f64,
    cost_factor: f64,
    glint_rows: usize,
    noise_model_check: f64,
}

impl Minor {
    fn of(v: &serde_json::Value) -> Minor {
        let value = |key: &str| v[key]["value"].as_f64().unwrap_or(f64::NAN);
        Minor {
            plain_ratio: v["improvement_ratio"].as_f64().unwrap_or(f64::NAN),
            without_glint: value("improvement_ratio_without_glint"),
            median_rows: value("improvement_ratio_median_rows"),
            trimmed: value("improvement_ratio_trimmed"),
            cost_factor: v["sampling"]["cost_factor"].as_f64().unwrap_or(1.0),
            glint_rows: v["estimates"]["scenarios"][0]["glint_rows_deg"]
                .as_array()
                .map_or(0, |a| a.len()),
            noise_model_check: value("noise_model_check"),
        }
    }

    fn median(seas: &[Minor]) -> Minor {
        let m = |f: fn(&Minor) -> f64| quartiles(&seas.iter().map(f).collect::<Vec<_>>()).0;
        Minor {
            plain_ratio: m(|s| s.plain_ratio),
            without_glint: m(|s| s.without_glint),
            median_rows: m(|s| s.median_rows),
            trimmed: m(|s| s.trimmed),
            cost_factor: m(|s| s.cost_factor),
            glint_rows: m(|s| s.glint_rows as f64).round() as usize,
            noise_model_check: m(|s| s.noise_model_check),
        }
    }
}

/// Gathers the finished cases of the study in `dir`.
pub fn summarize(dir: &Path) -> Result<StudySummary, AppError> {
    let plan = read_plan(dir)?;
    let mut rows = Vec::new();
    let mut missing = Vec::new();
    let mut suns = std::collections::HashMap::new();
    for k in 1..=plan.cases {
        let cdir = case_dir(dir, k);
        // Unfinished, or a summary that is not a comparison's: missing, to be run again.
        let Some(v) = finished_summary(&cdir) else {
            missing.push(k);
            continue;
        };
        let scene = SceneConfig::load(&cdir.join("scene.toml"))?;
        let sky = scene
            .sky
            .file
            .as_ref()
            .and_then(|f| f.file_stem())
            .map_or("analytic".into(), |n| n.to_string_lossy().into_owned());
        let sun = *suns
            .entry(sky.clone())
            .or_insert_with(|| sun_elevation(&scene));
        let f = |key: &str| v[key].as_f64().unwrap_or(f64::NAN);
        // A pooled case lists its seas; each has its own comparison in ocean-seed-S/.
        let seas: Vec<serde_json::Value> = match v["realizations"].as_array() {
            Some(list) => list
                .iter()
                .map(|r| {
                    read_json(
                        &cdir
                            .join(format!("ocean-seed-{}", r["ocean_seed"]))
                            .join("summary.json"),
                    )
                })
                .collect::<Result<_, _>>()?,
            None => vec![v.clone()],
        };
        let (std, minor) = if seas.len() > 1 {
            let pooled = |key: &str| {
                let iv = &v[format!("{key}_corrected")];
                (iv["value"].as_f64().unwrap_or(f64::NAN), pair(&iv["ci"]))
            };
            (
                [
                    (pooled("std_high_unmapped").0, [f64::NAN; 2]),
                    pooled("std_low_mapped"),
                    pooled("std_low_unmapped"),
                ],
                Minor::median(&seas.iter().map(Minor::of).collect::<Vec<_>>()),
            )
        } else {
            let scenario = |name: &str| {
                v["estimates"]["scenarios"]
                    .as_array()
                    .and_then(|a| a.iter().find(|s| s["name"] == name))
                    .map_or([f64::NAN; 2], |s| pair(&s["std_corrected"]["ci"]))
            };
            (
                [
                    (f("std_high_unmapped_corrected"), [f64::NAN; 2]),
                    (f("std_low_mapped_corrected"), scenario("low_mapped")),
                    (f("std_low_unmapped_corrected"), scenario("low_unmapped")),
                ],
                Minor::of(&v),
            )
        };
        let shape = super::sea_shape(&scene.ocean);
        rows.push(CaseRow {
            case: k,
            wind_m_s: scene.ocean.wind_speed,
            fetch_km: scene.ocean.fetch_km,
            depth_m: scene.ocean.depth_m,
            rms_m: scene.ocean.rms_target().unwrap_or(f64::NAN),
            rescale: shape.rescale,
            steepness: shape.steepness,
            sky,
            sun_elevation_deg: sun,
            realizations: seas.len(),
            std_high_unmapped_corrected: std[0].0,
            std_low_mapped_corrected: std[1].0,
            std_low_mapped_ci: std[1].1,
            std_low_unmapped_corrected: std[2].0,
            std_low_unmapped_ci: std[2].1,
            improvement_ratio: minor.plain_ratio,
            // null: the ratio is infinite (low-mapped's difference is below its noise).
            improvement_ratio_corrected: v["improvement_ratio_corrected"]
                .as_f64()
                .unwrap_or(f64::INFINITY),
            improvement_ratio_ci: pair(&v["improvement_ratio_ci"]),
            improvement_significant: v["improvement_significant"].as_bool().unwrap_or(false),
            improvement_ratio_without_glint: minor.without_glint,
            improvement_ratio_median_rows: minor.median_rows,
            improvement_ratio_trimmed: minor.trimmed,
            cost_factor: minor.cost_factor,
            commit: v["commit"].as_str().unwrap_or("unknown").to_string(),
            glint_rows: minor.glint_rows,
            noise_model_check: minor.noise_model_check,
            seconds_total: f("seconds_total"),
        });
    }
    let ratios: Vec<f64> = rows.iter().map(|r| r.improvement_ratio_corrected).collect();
    let (median_ratio, ratio_quartiles) = quartiles(&ratios);
    let (cases_csv, per_sky_csv, scatter_png) = (
        dir.join("cases.csv"),
        dir.join("per_sky.csv"),
        dir.join("scatter.png"),
    );
    write_outputs(&rows, &cases_csv, &per_sky_csv, &scatter_png)?;
    let summary = StudySummary {
        commit: crate::app::commit(),
        cases: plan.cases,
        finished: rows.len(),
        missing,
        improved: ratios.iter().filter(|&&r| r > 1.0).count(),
        improved_significant: rows
            .iter()
            .filter(|r| r.improvement_ratio_ci[0] > 1.0)
            .count(),
        worse_significant: rows
            .iter()
            .filter(|r| r.improvement_ratio_ci[1] < 1.0)
            .count(),
        median_ratio,
        ratio_quartiles,
        seconds_total: rows.iter().map(|r| r.seconds_total).sum(),
        case_commits: {
            let mut c: Vec<String> = rows.iter().map(|r| r.commit.clone()).collect();
            c.sort();
            c.dedup();
            c
        },
        rows,
        cases_csv,
        per_sky_csv,
        scatter_png,
    };
    write_json(&dir.join("summary.json"), &summary)?;
    Ok(summary)
}

fn write_outputs(
    rows: &[CaseRow],
    cases_csv: &Path,
    per_sky_csv: &Path,
    scatter_png: &Path,
) -> Result<(), AppError> {
    use std::io::Write;
    let cases = stage(cases_csv, |w| {
        writeln!(
            w,
            "case,wind_m_s,fetch_km,depth_m,rms_m,rescale,steepness,sky,sun_elevation_deg,realizations,std_high_unmapped_corrected,std_low_mapped_corrected,std_low_mapped_lo,std_low_mapped_hi,std_low_unmapped_corrected,std_low_unmapped_lo,std_low_unmapped_hi,improvement_ratio,improvement_ratio_corrected,improvement_ratio_lo,improvement_ratio_hi,improvement_significant,improvement_ratio_without_glint,improvement_ratio_median_rows,improvement_ratio_trimmed,glint_rows,noise_model_check,cost_factor,seconds_total,commit"
        )?;
        for r in rows {
            writeln!(
                w,
                "{},{:.3},{:.2},{:.1},{:.4},{:.3},{:.4},{},{:.2},{},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{:.4},{:.4},{:.4},{:.4},{},{:.4},{:.4},{:.4},{},{:.3},{:.3},{:.1},{}",
                r.case,
                r.wind_m_s,
                r.fetch_km,
                r.depth_m,
                r.rms_m,
                r.rescale,
                r.steepness,
                r.sky,
                r.sun_elevation_deg,
                r.realizations,
                r.std_high_unmapped_corrected,
                r.std_low_mapped_corrected,
                r.std_low_mapped_ci[0],
                r.std_low_mapped_ci[1],
                r.std_low_unmapped_corrected,
                r.std_low_unmapped_ci[0],
                r.std_low_unmapped_ci[1],
                r.improvement_ratio,
                r.improvement_ratio_corrected,
                r.improvement_ratio_ci[0],
                r.improvement_ratio_ci[1],
                r.improvement_significant,
                r.improvement_ratio_without_glint,
                r.improvement_ratio_median_rows,
                r.improvement_ratio_trimmed,
                r.glint_rows,
                r.noise_model_check,
                r.cost_factor,
                r.seconds_total,
                r.commit
            )?;
        }
        Ok(())
    })?;
    let mut skies: Vec<&str> = rows.iter().map(|r| r.sky.as_str()).collect();
    skies.sort();
    skies.dedup();
    let per_sky = stage(per_sky_csv, |w| {
        writeln!(
            w,
            "sky,sun_elevation_deg,cases,improved,improved_significant,median_ratio,min_ratio,max_ratio"
        )?;
        for sky in &skies {
            let mine: Vec<&CaseRow> = rows.iter().filter(|r| r.sky == *sky).collect();
            let ratios: Vec<f64> = mine.iter().map(|r| r.improvement_ratio_corrected).collect();
            let (med, _) = quartiles(&ratios);
            let fold = |f: fn(f64, f64) -> f64, init: f64| ratios.iter().copied().fold(init, f);
            writeln!(
                w,
                "{sky},{:.2},{},{},{},{:.3},{:.3},{:.3}",
                mine[0].sun_elevation_deg,
                mine.len(),
                ratios.iter().filter(|&&r| r > 1.0).count(),
                mine.iter()
                    .filter(|r| r.improvement_ratio_ci[0] > 1.0)
                    .count(),
                med,
                fold(f64::min, f64::INFINITY),
                fold(f64::max, f64::NEG_INFINITY)
            )?;
        }
        Ok(())
    })?;
    let points: Vec<ScatterPoint> = rows
        .iter()
        .map(|r| ScatterPoint {
            x: r.std_low_unmapped_corrected,
            x_ci: r.std_low_unmapped_ci,
            y: r.std_low_mapped_corrected,
            y_ci: r.std_low_mapped_ci,
            group: skies.iter().position(|s| *s == r.sky).unwrap_or(0),
        })
        .collect();
    scatter(
        scatter_png,
        &format!(
            "{} cases: band-averaged std of the luminance difference from the baseline, rows 0 to -5 degrees, noise-corrected (95% intervals)",
            rows.len()
        ),
        "low tessellation, vertex normals (unmapped)",
        "low tessellation, normal mapped",
        &skies,
        &points,
    )
    .map_err(|m| AppError::Run(format!("cannot draw {}: {m}", scatter_png.display()).into()))?;
    cases.commit()?;
    per_sky.commit()?;
    Ok(())
}

impl fmt::Display for StudySummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "study: {} of {} cases finished{}",
            self.finished,
            self.cases,
            if self.missing.is_empty() {
                String::new()
            } else {
                format!(" (missing: {:?})", self.missing)
            }
        )?;
        writeln!(
            f,
            "  normal mapping brought the low tessellation closer to the baseline in {} of {} cases ({} significantly); worse, significantly, in {}",
            self.improved, self.finished, self.improved_significant, self.worse_significant
        )?;
        writeln!(
            f,
            "  improvement ratio (noise-corrected): median {:.2}, quartiles {:.2} to {:.2}",
            self.median_ratio, self.ratio_quartiles[0], self.ratio_quartiles[1]
        )?;
        write!(
            f,
            "  wrote {} {} {}",
            self.cases_csv.display(),
            self.per_sky_csv.display(),
            self.scatter_png.display()
        )
    }
}
