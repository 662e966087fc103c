//! `compare --against truth`: a baseline on which the wrong-side question never arises. The
//! paper measures every scenario against its high tessellation with mapped normals, and that
//! baseline is itself touched by the wrong-side policy (about one hit in seven in the analysed
//! band has a shading normal that disagrees with its triangle). The truth is the exact
//! displaced surface (`crate::accel::exact`, found inside the low tessellation's triangles)
//! shaded with its own tangent plane ([`NormalMode::Geometric`]): the normal that shades is the
//! geometry's, so a mirror reflection leaves at the elevation it arrived at and no policy is
//! ever consulted. It is rendered on the analysed rows only, with `truth_boost` times each
//! pixel's samples, and every scenario (the paper's baseline included) is measured against it
//! with the same estimator. The truth is by far a comparison's dearest part and no wrong-side policy touches
//! it, so `--truth-from DIR` reuses one an earlier comparison of the same scene rendered
//! (`truth.exr` and `truth.json` say what it is), for a sweep over policies.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::{CompareJob, Scenario, ScenarioInfo};
use crate::analysis::error::{EstimateError, Estimates, Estimator, Inputs};
use crate::app::AppError;
use crate::color::luminance;
use crate::config::{NormalMode, SceneConfig, SurfaceKind};
use crate::image_io::{read_exr, read_exr_channel};
use crate::render::film::{Batches, Film, MAX_BATCHES, Samples};
use crate::render::pipeline::{Prepared, Rendered};
use crate::render::{Camera, Counters};

/// What the scenarios are measured against.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Against {
    /// The paper's baseline only: the high tessellation with mapped normals.
    #[default]
    PaperHigh,
    /// The paper's baseline and, beside it, the truth (every scenario against both).
    Truth,
}

crate::config::choice!(Against { PaperHigh => "paper-high", Truth => "truth" });

/// The truth's samples per analysed pixel, in multiples of that pixel's samples in the
/// scenarios, unless `--truth-boost` says otherwise.
pub const DEFAULT_TRUTH_BOOST: u16 = 4;

/// The largest share of the truth's hits with a wrong-side event (a shading normal facing
/// away, bent, or sending a ray to the wrong side) for it to count as free of them.
pub const MAX_WRONG_SIDE_SHARE: f64 = 1e-3;

/// Added to the scene's sample seed for the truth's samples.
const TRUTH_SEED: u64 = 0x0074_7275_7468;

/// One analysed row of the truth.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct TruthRow {
    pub elevation_deg: f64,
    /// Azimuthal mean of the pixels' luminance.
    pub luminance: f64,
    /// Standard error of that mean (the pixels' Monte Carlo noise).
    pub noise: f64,
}

/// The truth as rendered.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Truth {
    pub surface: SurfaceKind,
    pub normals: NormalMode,
    pub seed: u64,
    /// Samples per pixel before the boosts.
    pub spp: u32,
    /// Samples of each analysed pixel, in multiples of its samples in the scenarios.
    pub boost: u16,
    /// Samples traced (analysed rows only; every other pixel takes none).
    pub samples: u64,
    pub seconds_build: f64,
    pub seconds_render: f64,
    /// Hits with a wrong-side event: shading normals facing away, bent, or sending a ray to
    /// the wrong side (each hit counted once per event), and their share of the hits.
    pub wrong_side_events: u64,
    pub wrong_side_share: f64,
    pub counters: Counters,
    pub exr: PathBuf,
    /// With `--truth-from`: the folder whose truth this comparison reused.
    #[serde(default)]
    pub reused_from: Option<PathBuf>,
}

/// `truth.json`, beside `truth.exr`: the truth's scene and how it was rendered, which
/// `--truth-from` checks before it reuses the image.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct TruthFile {
    pub scene: SceneConfig,
    pub rows_deg: (f64, f64),
    pub truth: Truth,
}

/// The scene the truth renders: the low tessellation's exact surface, geometric normals.
/// (The policy is never consulted; it is pinned so that every truth of a scene is recorded
/// alike.)
pub(super) fn scene(job: &CompareJob) -> SceneConfig {
    let mut c = super::render::exact_scene(job);
    c.render.normals = NormalMode::Geometric;
    c.render.wrong_side = Default::default();
    c
}

/// What of two truth scenes differs in a way that may change the converged image, by
/// section; empty when nothing does. The sample seed, the wrong-side policy (never
/// consulted), the threads, the backend, the preview's exposure and the EXR's compression do
/// not. (The tessellation must match: where its triangles end is where the sea ends.) A sky
/// map is compared by its path as given.
fn differences(a: &SceneConfig, b: &SceneConfig) -> Vec<&'static str> {
    let normal = |c: &SceneConfig| {
        let mut c = c.clone();
        c.render.seed = 0;
        c.render.wrong_side = Default::default();
        c.render.threads = 0;
        c.render.backend = Default::default();
        c.render.exposure = None;
        c.render.exr_compression = Default::default();
        c
    };
    let (a, b) = (normal(a), normal(b));
    let mut d = Vec::new();
    if a.ocean != b.ocean || a.render.ocean_seed != b.render.ocean_seed {
        d.push("[ocean] (or render.ocean_seed)");
    }
    if a.lod != b.lod {
        d.push("[lod]");
    }
    if a.sky != b.sky {
        d.push("[sky]");
    }
    if a.camera != b.camera {
        d.push("[camera]");
    }
    if a.water != b.water {
        d.push("[water]");
    }
    let (mut ra, mut rb) = (a.render.clone(), b.render.clone());
    ra.ocean_seed = 0;
    rb.ocean_seed = 0;
    if ra != rb {
        d.push("[render]");
    }
    d
}

/// A scene as a truth's record gives it back: through the JSON text (fields the record does
/// not keep, such as whether the layers were chosen automatically, and floats read back from
/// their text, compare alike).
fn as_recorded(c: &SceneConfig) -> Result<SceneConfig, AppError> {
    let text = serde_json::to_string(c).map_err(|e| AppError::Run(e.into()))?;
    serde_json::from_str(&text).map_err(|e| AppError::Run(e.into()))
}

/// The truth an earlier comparison wrote into `dir`, checked against this job's scene and rows.
pub(super) fn load(job: &CompareJob, dir: &Path) -> Result<(Truth, Film), AppError> {
    let json = dir.join("truth.json");
    let text = std::fs::read_to_string(&json).map_err(|e| {
        AppError::input(format!(
            "--truth-from {}: cannot read {} ({e}); it is written by compare --against truth",
            dir.display(),
            json.display()
        ))
    })?;
    let file: TruthFile = serde_json::from_str(&text).map_err(|e| {
        AppError::input(format!(
            "--truth-from: {} is not a truth's record: {e}",
            json.display()
        ))
    })?;
    let d = differences(&file.scene, &as_recorded(&scene(job))?);
    if !d.is_empty() {
        return Err(AppError::input(format!(
            "--truth-from {}: that truth was rendered for another scene (its {} differ)",
            dir.display(),
            d.join(", ")
        )));
    }
    if file.rows_deg != job.rows_deg {
        return Err(AppError::input(format!(
            "--truth-from {}: that truth covers the rows {}:{}, this comparison analyses {}:{}",
            dir.display(),
            file.rows_deg.0,
            file.rows_deg.1,
            job.rows_deg.0,
            job.rows_deg.1
        )));
    }
    let exr = dir.join("truth.exr");
    let image = read_exr(&exr)?;
    let var_y = read_exr_channel(&exr, "Y.variance")?;
    let k = MAX_BATCHES;
    let mut luminance = vec![0.0f32; image.pixels.len() * k];
    for b in 0..k {
        let channel = read_exr_channel(&exr, &format!("Y.batch{b}"))?;
        for (p, v) in channel.into_iter().enumerate() {
            luminance[p * k + b] = v;
        }
    }
    let spp = file.truth.spp;
    let film = Film {
        image,
        var_y,
        spp,
        batches: Some(Batches {
            k,
            spp: vec![spp / k as u32; k],
            luminance,
        }),
    };
    let truth = Truth {
        reused_from: Some(dir.to_path_buf()),
        ..file.truth
    };
    Ok((truth, film))
}

/// The truth's samples per pixel, in multiples of the scene's spp: `job.truth_boost` times the
/// scenarios' own (`boost`) on the analysed rows (at most [`super::sampling::MAX_PIXEL_SAMPLES`]
/// a pixel), none elsewhere.
pub(super) fn boost_map(job: &CompareJob, boost: &[u16], camera: &Camera) -> Vec<u16> {
    // no pixel past the sample cap the scenarios keep to
    let cap = u32::from(super::sampling::boost_limit(job.scene.render.spp, u16::MAX));
    let mut out = vec![0u16; boost.len()];
    let w = camera.width;
    for y in camera.rows_between(job.rows_deg) {
        for x in y * w..(y + 1) * w {
            out[x] = (u32::from(boost[x]) * u32::from(job.truth_boost)).min(cap) as u16;
        }
    }
    out
}

/// The rows `rows_deg` of a film: elevation, mean luminance, its standard error.
pub(super) fn rows(camera: &Camera, film: &Film, rows_deg: (f64, f64)) -> Vec<TruthRow> {
    let rows = camera.rows_between(rows_deg);
    let w = film.image.width;
    let noise = film.row_noise(&rows);
    rows.iter()
        .zip(noise)
        .map(|(&y, var)| TruthRow {
            elevation_deg: camera.row_elevation_deg(y),
            luminance: film.image.pixels[y * w..(y + 1) * w]
                .iter()
                .map(|&p| f64::from(luminance(p)))
                .sum::<f64>()
                / w as f64,
            noise: (var / w as f64).sqrt(),
        })
        .collect()
}

/// Wrong-side events of a render's counters.
pub fn wrong_side_events(c: &Counters) -> u64 {
    c.wrong_side + c.backfacing_shading + c.bent
}

/// Renders the truth with `prepared` (the exact surface; its scene `cfg`, from [`scene`]),
/// the scenarios' per-pixel samples `boost`.
pub(super) fn render(
    job: &CompareJob,
    prepared: &Prepared,
    cfg: &SceneConfig,
    boost: &[u16],
    camera: &Camera,
) -> Result<(Truth, Rendered), AppError> {
    let map = boost_map(job, boost, camera);
    let mut c = cfg.clone();
    c.render.seed = cfg.render.seed.wrapping_add(TRUTH_SEED);
    let samples = Samples {
        boost: Some(&map),
        ..Samples::ALL
    };
    let (r, _) = prepared.render_samples(&c, MAX_BATCHES, samples, false, job.progress)?;
    let counters = r.report.counters;
    let events = wrong_side_events(&counters);
    let truth = Truth {
        surface: c.render.surface,
        normals: c.render.normals,
        seed: c.render.seed,
        spp: c.render.spp,
        boost: job.truth_boost,
        samples: map
            .iter()
            .map(|&b| u64::from(b) * u64::from(c.render.spp))
            .sum(),
        seconds_build: r.report.seconds_build,
        seconds_render: r.report.seconds_trace,
        wrong_side_events: events,
        wrong_side_share: events as f64 / counters.hits.max(1) as f64,
        counters,
        exr: job.out.join("truth.exr"),
        reused_from: None,
    };
    Ok((truth, r))
}

/// Every scenario but the noise floor (a second draw of the paper's baseline) against the
/// truth, with the estimator every other figure uses.
pub(super) fn estimates(
    job: &CompareJob,
    runs: &[(ScenarioInfo, Rendered)],
    truth: &Film,
) -> Result<Estimates, AppError> {
    let scenarios = runs
        .iter()
        .filter(|(info, _)| info.name != Scenario::NoiseFloor)
        .map(|(info, r)| (info.name.name().to_string(), &r.film))
        .collect();
    let inputs = Inputs {
        camera: &runs[0].1.camera,
        baseline: truth,
        scenarios,
        rows_deg: job.rows_deg,
        seed: job.scene.render.seed,
    };
    let estimator = Estimator::new(&inputs).map_err(|e| match e {
        EstimateError::Mismatch => AppError::Run(e.into()),
        _ => AppError::Input(e.into()),
    })?;
    Ok(estimator.scenarios())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Projection;

    #[test]
    fn a_scene_matches_its_record_and_what_differs_is_named() {
        let mut c = SceneConfig::default();
        // not kept in the record, and a float whose shortest text is long
        c.ocean.layers_auto = true;
        c.ocean.wind_speed = 4.123_456_789_012_345;
        let text = serde_json::to_string(&c).unwrap();
        let recorded: SceneConfig = serde_json::from_str(&text).unwrap();
        let against = |o: &SceneConfig| differences(&recorded, &as_recorded(o).unwrap());
        assert!(against(&c).is_empty(), "{:?}", against(&c));
        // what never changes the truth's converged image
        let mut same = c.clone();
        same.render.seed += 1;
        same.render.wrong_side = crate::config::WrongSide::Mirror;
        same.render.exposure = Some(1.0);
        same.render.exr_compression = crate::config::ExrCompression::Piz;
        same.render.threads = 1;
        assert!(against(&same).is_empty(), "{:?}", against(&same));
        // what does, by section
        let mut other = c.clone();
        other.render.ocean_seed += 1;
        assert_eq!(against(&other), ["[ocean] (or render.ocean_seed)"]);
        let mut other = c.clone();
        other.water.ior = 1.4;
        assert_eq!(against(&other), ["[water]"]);
        let mut other = c.clone();
        other.lod.preset = crate::config::LodChoice::PaperHigh;
        assert_eq!(against(&other), ["[lod]"]);
        let mut other = c.clone();
        other.render.max_segments -= 1;
        assert_eq!(against(&other), ["[render]"]);
    }

    #[test]
    fn the_truth_samples_the_analysed_rows_only_with_the_scenarios_boost_times_its_own() {
        let camera = Camera::new(
            Projection::Equirect {
                band_deg: Some((1.0, -6.0)),
            },
            360,
            2.0,
        );
        let job = CompareJob {
            scene: Default::default(),
            high: Default::default(),
            low: Default::default(),
            rows_deg: (0.0, -5.0),
            max_boost: 64,
            filtered: false,
            exact: false,
            against: Against::Truth,
            truth_boost: 3,
            truth_from: None,
            out: std::env::temp_dir(),
            progress: false,
        };
        let boost: Vec<u16> = (0..camera.width * camera.height)
            .map(|i| [1, 2, 64][i % 3])
            .collect();
        let map = boost_map(&job, &boost, &camera);
        let analysed = camera.rows_between(job.rows_deg);
        assert!(!analysed.is_empty() && analysed.len() < camera.height);
        for y in 0..camera.height {
            for x in 0..camera.width {
                let i = y * camera.width + x;
                let want = if analysed.contains(&y) {
                    3 * boost[i]
                } else {
                    0
                };
                assert_eq!(map[i], want, "pixel ({x}, {y})");
            }
        }
    }
}
