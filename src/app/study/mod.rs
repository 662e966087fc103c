//! `vastocean study plan | run | summarize`: the paper's study of many random cases (its 93,
//! Figure 10), runnable on one machine or a cluster. `plan` draws the cases from a seed and
//! writes one scene file per case plus `plan.toml` (the settings every case shares) into a
//! study folder with a copy of the skies it uses, so the folder is the study's single source of
//! truth and travels to a cluster whole. `run` runs one case's comparison into
//! `cases/K/`, its `summary.json` written last and atomically, so a case with a summary is
//! finished and is skipped (resumable), and an interrupted one is redone. Cases are independent:
//! any scheduler (GNU parallel, a Slurm job array) can run them. `summarize` gathers the
//! finished cases into `cases.csv`, `per_sky.csv`, `scatter.png` and `summary.json`.

use std::fmt;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::AppError;
use crate::config::{LodConfig, Projection, SceneConfig};
use crate::image_io::write_atomically;
use crate::rng::Rng;

/// Where the cases' sea states are drawn from. Wind, fetch and depth cover the paper's Table 1
/// (wind 1.3-4.91 m/s, fetch 99.95-204.5 km, depth 150.9-997.9 m) with a margin on each side;
/// wind is uniform, fetch and depth, scale parameters spanning factors of 3 to 12, log-uniform.
/// The RMS height is the spectrum's own times a factor drawn log-uniform from `rescale`, the
/// range the paper's five Table 1 cases need ([`sea_shape`]), so that a case is a sea a wind
/// makes, as near to it as the paper's are; a sea steeper than `max_steepness` (Hs over the
/// peak wavelength; waves break at about 1/7) is drawn again.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq)]
pub struct Ranges {
    pub wind_m_s: (f64, f64),
    pub fetch_km: (f64, f64),
    pub depth_m: (f64, f64),
    /// How plans drawn before physical seas chose the RMS height: log-uniform over this range,
    /// whatever the wind (rescale factors of 0.26 to 5.62 on the 93-case study).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rms_m: Option<(f64, f64)>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rescale: Option<(f64, f64)>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_steepness: Option<f64>,
}

pub const RANGES: Ranges = Ranges {
    wind_m_s: (1.0, 6.0),
    fetch_km: (80.0, 250.0),
    depth_m: (100.0, 1200.0),
    rms_m: None,
    rescale: Some((0.6, 1.95)),
    max_steepness: Some(1.0 / 7.0),
};

/// How far a case's sea is from the sea its wind makes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SeaShape {
    /// RMS height over the spectrum's own (the square root of its integral): 1 without an RMS
    /// target.
    pub rescale: f64,
    /// Significant wave height (4 x RMS) over the spectrum's peak wavelength.
    pub steepness: f64,
}

/// The rescale factor and steepness of a sea state (from its spectrum; no layers are built).
pub fn sea_shape(ocean: &crate::config::OceanParams) -> SeaShape {
    let spectrum = crate::ocean::Spectrum::new(ocean);
    let own = spectrum.total_variance().sqrt();
    let rms = ocean.rms_target().unwrap_or(own);
    SeaShape {
        rescale: rms / own,
        steepness: 4.0 * rms * spectrum.peak_wavenumber() / std::f64::consts::TAU,
    }
}

/// What a plan written before a setting existed ran with: a uniform render, one sea.
fn one() -> u16 {
    1
}

/// `plan.toml`: what every case shares, and how the cases were drawn.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Plan {
    pub cases: usize,
    pub seed: u64,
    /// The tessellations compared (the baseline and the low one; a case's own `[lod]` section
    /// is not used) and the analysed rows (the paper: 0 to -5 degrees).
    pub high: LodConfig,
    pub low: LodConfig,
    pub rows_deg: (f64, f64),
    /// Most samples a noisy pixel may take (`compare --max-boost`); plans written before it
    /// existed read 1, a uniform render, as they ran.
    #[serde(default = "one")]
    pub max_boost: u16,
    /// Ocean realizations per case (`compare --realizations`): with more than one, a case is
    /// its sea state, pooled over that many ocean seeds from the case's own; plans written
    /// before it existed read 1.
    #[serde(default = "one")]
    pub realizations: u16,
    /// Sky maps the cases draw from, in `skies/` beside this file.
    pub skies: Vec<String>,
    pub ranges: Ranges,
}

/// What `study plan` is asked for.
#[derive(Clone, Debug)]
pub struct PlanJob {
    pub out: PathBuf,
    pub cases: usize,
    pub seed: u64,
    /// The scene every case starts from (camera, render settings, water); each case draws its
    /// sea state, sky and seeds. Its camera becomes the paper's panorama band, +1 to -6 degrees.
    pub base: SceneConfig,
    pub high: LodConfig,
    pub low: LodConfig,
    pub max_boost: u16,
    pub realizations: u16,
    /// The sky collection to draw from.
    pub skies_dir: PathBuf,
}

#[derive(Clone, Debug, Serialize)]
pub struct PlanReport {
    pub dir: PathBuf,
    pub cases: usize,
    pub skies: usize,
    pub plan: PathBuf,
}

fn case_dir(dir: &Path, k: usize) -> PathBuf {
    dir.join("cases").join(k.to_string())
}

/// A case's summary, if the case is finished: its summary.json reads as a comparison's (a
/// truncated or emptied file, `{}`, is not one, and the case is run again).
fn finished_summary(cdir: &Path) -> Option<serde_json::Value> {
    let text = std::fs::read_to_string(cdir.join("summary.json")).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    (v["improvement_ratio_ci"].is_array() && v["commit"].is_string()).then_some(v)
}

/// Case `k`'s scene (1-based), drawn from the seed, and its sky's file name.
fn draw_case(job: &PlanJob, skies: &[String], k: usize) -> (SceneConfig, String) {
    let mut r = Rng::keyed(&[job.seed, 0x7374_7564, k as u64]);
    let uniform = |r: &mut Rng, (lo, hi): (f64, f64)| lo + (hi - lo) * r.f64();
    let log_uniform = |r: &mut Rng, (lo, hi): (f64, f64)| {
        (f64::ln(lo) + (f64::ln(hi) - f64::ln(lo)) * r.f64()).exp()
    };
    let mut s = job.base.clone();
    let (rescale, max_steepness) = (
        RANGES.rescale.expect("physical seas"),
        RANGES.max_steepness.expect("physical seas"),
    );
    // Seas past breaking are drawn again (none in these ranges so far: the guard is for ranges
    // to come); the draws stay a function of the seed alone.
    for _ in 0..1000 {
        s.ocean.wind_speed = uniform(&mut r, RANGES.wind_m_s);
        s.ocean.fetch_km = log_uniform(&mut r, RANGES.fetch_km);
        s.ocean.depth_m = log_uniform(&mut r, RANGES.depth_m);
        let factor = log_uniform(&mut r, rescale);
        let own = crate::ocean::Spectrum::new(&s.ocean)
            .total_variance()
            .sqrt();
        s.ocean.rms_m = Some(factor * own);
        s.ocean.hs_m = None;
        if sea_shape(&s.ocean).steepness <= max_steepness {
            break;
        }
    }
    let sky = skies[((r.f64() * skies.len() as f64) as usize).min(skies.len() - 1)].clone();
    // Relative to the case's scene file, cases/K/scene.toml.
    s.sky.file = Some(Path::new("../../skies").join(&sky));
    s.camera.projection = Projection::Equirect {
        band_deg: Some((1.0, -6.0)),
    };
    s.render.seed = k as u64;
    s.render.ocean_seed = k as u64;
    // What `vastocean render --config cases/K/scene.toml` shows: the low tessellation. (`study
    // run` takes both tessellations from the plan.)
    s.lod = job.low.clone();
    (s, sky)
}

/// Draws the cases and writes the study folder. Refuses a folder that already holds a plan.
pub fn plan(job: &PlanJob) -> Result<PlanReport, AppError> {
    if job.cases == 0 || job.cases > 100_000 {
        return Err(AppError::input(format!(
            "--cases must be in 1..=100000 (got {})",
            job.cases
        )));
    }
    let (spp, k) = (
        job.base.render.spp,
        crate::analysis::error::MIN_BATCHES as u32,
    );
    if spp < k || !spp.is_multiple_of(k) {
        return Err(AppError::input(format!(
            "--spp must be a multiple of {k} (each case's comparison deals its samples into {k} batches; got {spp})"
        )));
    }
    if job.max_boost == 0 {
        return Err(AppError::input("--max-boost is at least 1"));
    }
    if job.realizations == 0 {
        return Err(AppError::input("--realizations is at least 1"));
    }
    let plan_path = job.out.join("plan.toml");
    if plan_path.exists() {
        return Err(AppError::input(format!(
            "{} exists: a study folder holds one plan (edit its case files, or plan into a new folder)",
            plan_path.display()
        )));
    }
    let mut skies: Vec<String> = std::fs::read_dir(&job.skies_dir)
        .map_err(|e| {
            AppError::Input(format!("cannot read {}: {e}", job.skies_dir.display()).into())
        })?
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".exr"))
        .collect();
    skies.sort();
    if skies.is_empty() {
        return Err(AppError::input(format!(
            "{} holds no .exr sky maps",
            job.skies_dir.display()
        )));
    }
    // Every map is read whole before anything is written: a corrupt one fails the plan, not
    // the cases that draw it.
    for name in &skies {
        crate::sky::Sky::load(&job.skies_dir.join(name))
            .map_err(|e| AppError::Input(format!("sky map {name}: {e}").into()))?;
    }
    let mut scenes = Vec::new();
    for k in 1..=job.cases {
        let (s, sky) = draw_case(job, &skies, k);
        // Checked before anything is written.
        let mut check = s.clone();
        check.sky.file = Some(job.skies_dir.join(sky));
        check.validate()?;
        for lod in [&job.high, &job.low] {
            lod.validate()?;
            crate::lod::params_for(lod, &check.camera)?;
        }
        scenes.push(s);
    }
    for name in &skies {
        let dst = job.out.join("skies").join(name);
        let bytes = std::fs::read(job.skies_dir.join(name))
            .map_err(|e| AppError::Input(format!("cannot read sky {name}: {e}").into()))?;
        write_atomically(&dst, |w| std::io::Write::write_all(w, &bytes))?;
    }
    for (i, s) in scenes.iter().enumerate() {
        let text = toml::to_string(s).map_err(|e| AppError::Run(e.into()))?;
        let path = case_dir(&job.out, i + 1).join("scene.toml");
        write_atomically(&path, |w| std::io::Write::write_all(w, text.as_bytes()))?;
    }
    let plan = Plan {
        cases: job.cases,
        seed: job.seed,
        high: job.high.clone(),
        low: job.low.clone(),
        rows_deg: (0.0, -5.0),
        max_boost: job.max_boost,
        realizations: job.realizations,
        skies: skies.clone(),
        ranges: RANGES,
    };
    let text = toml::to_string(&plan).map_err(|e| AppError::Run(e.into()))?;
    // The plan last: a folder with a plan.toml has all its cases.
    write_atomically(&plan_path, |w| {
        std::io::Write::write_all(w, text.as_bytes())
    })?;
    Ok(PlanReport {
        dir: job.out.clone(),
        cases: job.cases,
        skies: skies.len(),
        plan: plan_path,
    })
}

/// Reads a study folder's plan.
pub fn read_plan(dir: &Path) -> Result<Plan, AppError> {
    let path = dir.join("plan.toml");
    let text = std::fs::read_to_string(&path).map_err(|e| {
        AppError::Input(format!("cannot read {} (not a study folder?): {e}", path.display()).into())
    })?;
    toml::from_str(&text).map_err(|e| AppError::Input(format!("{}: {e}", path.display()).into()))
}

impl fmt::Display for PlanReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "planned {} cases over {} skies in {} (edit cases/K/scene.toml to change a case); run them with\n  parallel -j 2 vastocean study run {} --threads 1 --case {{}} ::: $(seq 1 {})",
            self.cases,
            self.skies,
            self.dir.display(),
            self.dir.display(),
            self.cases
        )
    }
}

mod run;
mod summary;
pub use run::{CaseOutcome, run_case};
pub use summary::{CaseRow, StudySummary, summarize};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_paper_cases_lie_in_the_rescale_range_and_drawn_seas_stay_physical() {
        let scenes = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
        let (lo, hi) = RANGES.rescale.unwrap();
        let mut factors = Vec::new();
        for case in [12, 22, 34, 50, 87] {
            let s = SceneConfig::load(&scenes.join(format!("paper-case-{case}.toml"))).unwrap();
            let shape = sea_shape(&s.ocean);
            assert!((lo..=hi).contains(&shape.rescale), "case {case}: {shape:?}");
            assert!(shape.steepness < 0.1, "case {case}: {shape:?}");
            factors.push(shape.rescale);
        }
        // The range is the paper's, not wider than it needs by more than a margin.
        let (min, max) = factors
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(a, b), &f| (a.min(f), b.max(f)));
        assert!(min - lo < 0.05 && hi - max < 0.05, "{factors:?}");
        let job = PlanJob {
            out: PathBuf::new(),
            cases: 200,
            seed: 1,
            base: SceneConfig::default(),
            high: LodConfig::default(),
            low: LodConfig::default(),
            max_boost: 1,
            realizations: 1,
            skies_dir: PathBuf::new(),
        };
        let skies = vec!["a.exr".to_string()];
        let mut drawn = Vec::new();
        for k in 1..=200 {
            let (s, _) = draw_case(&job, &skies, k);
            let shape = sea_shape(&s.ocean);
            assert!(
                (lo * 0.999..=hi * 1.001).contains(&shape.rescale),
                "case {k}: {shape:?}"
            );
            assert!(shape.steepness <= 1.0 / 7.0, "case {k}: {shape:?}");
            assert!(
                (RANGES.wind_m_s.0..=RANGES.wind_m_s.1).contains(&s.ocean.wind_speed),
                "case {k}"
            );
            drawn.push(shape.rescale);
        }
        // Both ends of the range are drawn.
        assert!(drawn.iter().any(|&f| f < lo * 1.1) && drawn.iter().any(|&f| f > hi * 0.9));
        // The same seed draws the same case.
        assert_eq!(draw_case(&job, &skies, 7).0, draw_case(&job, &skies, 7).0);
    }
}
