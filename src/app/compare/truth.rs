//! `compare --against truth`: a baseline on which the wrong-side question never arises. The
//! paper measures every scenario against its high tessellation with mapped normals, and that
//! baseline is itself touched by the wrong-side policy (about one hit in seven in the analysed
//! band has its shading normal bent). The truth is the exact displaced surface
//! (`crate::accel::exact`, found inside the low tessellation's triangles) shaded with its own
//! tangent plane ([`NormalMode::Geometric`]): the normal that shades is the geometry's, so a
//! mirror reflection leaves at the elevation it arrived at and no policy is ever consulted. It
//! is rendered on the analysed rows only, with `truth_boost` times each pixel's samples, and
//! every scenario (the paper's baseline included) is measured against it with the same
//! estimator.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use super::{CompareJob, Scenario, ScenarioInfo};
use crate::analysis::error::{EstimateError, Estimates, Estimator, Inputs};
use crate::app::AppError;
use crate::color::luminance;
use crate::config::{NormalMode, SceneConfig};
use crate::render::film::{Film, MAX_BATCHES, Samples};
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
const TRUTH_SEED: u64 = 0x7472_7574_68;

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
#[derive(Clone, Debug, Serialize)]
pub struct Truth {
    pub surface: &'static str,
    pub normals: NormalMode,
    pub seed: u64,
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
}

/// The truth's samples per pixel, in multiples of the scene's spp: `job.truth_boost` times the
/// scenarios' own (`boost`) on the analysed rows, none elsewhere.
pub(super) fn boost_map(job: &CompareJob, boost: &[u16], camera: &Camera) -> Vec<u16> {
    let mut out = vec![0u16; boost.len()];
    let w = camera.width;
    for y in camera.rows_between(job.rows_deg) {
        for x in y * w..(y + 1) * w {
            out[x] =
                (u32::from(boost[x]) * u32::from(job.truth_boost)).min(u32::from(u16::MAX)) as u16;
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

/// Renders the truth with `prepared` (the exact surface; its scene `cfg`), the scenarios'
/// per-pixel samples `boost`.
pub(super) fn render(
    job: &CompareJob,
    prepared: &Prepared,
    cfg: &SceneConfig,
    boost: &[u16],
    camera: &Camera,
) -> Result<(Truth, Rendered), AppError> {
    let map = boost_map(job, boost, camera);
    let mut c = cfg.clone();
    c.render.normals = NormalMode::Geometric;
    c.render.seed = cfg.render.seed.wrapping_add(TRUTH_SEED);
    let samples = Samples {
        boost: Some(&map),
        ..Samples::ALL
    };
    let (r, _) = prepared.render_samples(&c, MAX_BATCHES, samples, false, job.progress)?;
    let counters = r.report.counters;
    let events = wrong_side_events(&counters);
    let truth = Truth {
        surface: "exact",
        normals: NormalMode::Geometric,
        seed: c.render.seed,
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
    };
    Ok((truth, r))
}

/// Every scenario but the noise floor (a second draw of the paper's baseline) against the
/// truth, with the estimator every other figure uses.
pub(super) fn estimates(
    job: &CompareJob,
    runs: &[(ScenarioInfo, Rendered)],
    truth: &Rendered,
) -> Result<Estimates, AppError> {
    let scenarios = runs
        .iter()
        .filter(|(info, _)| info.name != Scenario::NoiseFloor)
        .map(|(info, r)| (info.name.name().to_string(), &r.film))
        .collect();
    let inputs = Inputs {
        camera: &truth.camera,
        baseline: &truth.film,
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
