//! The error estimator on real renders: `compare` at a few samples per pixel against the same
//! comparison converged, on the default scene under the hand-made clear sky with a sun 2000
//! times the sky (whose glint is what makes the estimate hard; the scene the committed checks
//! measured), and the null tests: a scenario against itself under another
//! sample seed, and the noise floor. Heavy: `make test-full`.

use std::path::{Path, PathBuf};

use vastocean::analysis::error::{Estimator, Inputs};
use vastocean::app;
use vastocean::app::compare::{CompareJob, CompareSummary};
use vastocean::config::{LodChoice, LodConfig, NormalMode, Projection, SceneConfig};
use vastocean::render::film::{MAX_BATCHES, Samples};
use vastocean::render::pipeline::{Prepared, prepare};

fn tmp(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!("vastocean-estimator-{}-{name}", std::process::id()))
}

/// The baseline's tessellation here: 30 cm triangles near the camera, doubling every 18 m.
fn high_lod() -> LodConfig {
    LodConfig {
        preset: LodChoice::Custom,
        near_size_m: Some(0.3),
        double_distance_m: Some(18.0),
        ..LodConfig::default()
    }
}

fn low_lod() -> LodConfig {
    LodConfig {
        preset: LodChoice::PaperLow,
        ..LodConfig::default()
    }
}

/// The default scene at 512 px (seven analysed rows), a 30 cm tessellation against paper-low.
fn compare(spp: u32, seed: u64, max_boost: u16) -> CompareSummary {
    let mut scene = SceneConfig::default();
    scene.sky.analytic = vastocean::config::AnalyticSky::HandMadeClear {
        sun_elevation_deg: 4.0,
        sun_azimuth_deg: 180.0,
        sun_radiance: 2000.0,
        sky_scale: 1.0,
    };
    scene.camera.width = 512;
    scene.camera.projection = Projection::Equirect {
        band_deg: Some((1.0, -6.0)),
    };
    scene.render.spp = spp;
    scene.render.seed = seed;
    scene.render.threads = 2;
    // the policy its converged ratios and the docs' figures were measured under
    scene.render.wrong_side = vastocean::config::WrongSide::Bend;
    let out = tmp(&format!("{spp}-{seed}-{max_boost}"));
    let job = CompareJob {
        scene,
        high: high_lod(),
        low: low_lod(),
        rows_deg: (0.0, -5.0),
        max_boost,
        filtered: false,
        exact: false,
        against: vastocean::app::compare::Against::PaperHigh,
        truth_boost: vastocean::app::compare::DEFAULT_TRUTH_BOOST,
        truth_from: None,
        out: out.clone(),
        progress: false,
    };
    let s = app::compare::run(&job).unwrap();
    let _ = std::fs::remove_dir_all(out);
    s
}

/// At 16 and 64 spp, over eight sample seeds, the improvement ratio's 95 % intervals hold the
/// converged ratio (7 of 8 expected; at least 6 required; 8 of 8 each when written), and at 64
/// spp with the glint pixels boosted the estimates lie within 10 % of it (7 of 8 when written),
/// more of them than at 128 spp rendering every pixel alike, which costs about as much (3 of 8). The estimator this replaced (per-row stds
/// clipped at 0 and averaged, intervals from a bootstrap over azimuth blocks) covered 6 of 12
/// seeds at 64 and 256 spp on the full-size default scene and drifted with spp
/// (docs/error-estimator.md).
#[test]
#[ignore]
fn compare_intervals_hold_the_converged_ratio() {
    let converged = compare(4096, 1000, 64);
    let truth = converged.improvement.corrected;
    // The converged ratio is known to a few per cent.
    assert!(
        truth.ci[1] - truth.ci[0] < 0.06 * truth.value,
        "converged {truth:?}"
    );
    let mut report = Vec::new();
    let mut close_at_cost = Vec::new();
    // Uniform at 128 spp costs about what 64 spp boosted does (its samples 1.4 to 2 times a
    // uniform 64's, and the pilots a quarter of the baseline's and of the low scenarios').
    for (spp, max_boost) in [(16, 64), (64, 64), (128, 1)] {
        let (mut covered, mut close) = (0, 0);
        for seed in 1..=8 {
            let r = compare(spp, seed, max_boost).improvement.corrected;
            covered += usize::from(r.contains(truth.value));
            close += usize::from((r.value / truth.value - 1.0).abs() < 0.1);
            report.push(format!("{spp} spp boost {max_boost} seed {seed}: {r:?}"));
        }
        eprintln!(
            "{spp} spp, boost {max_boost}: {covered} of 8 cover {truth:?}, {close} within 10 %"
        );
        let report = report.join("\n");
        assert!(covered >= 6, "{covered} of 8 cover {truth:?}:\n{report}");
        if (spp, max_boost) == (64, 64) {
            assert!(
                close >= 7,
                "{close} of 8 within 10 % of {truth:?}:\n{report}"
            );
        }
        if spp >= 64 {
            close_at_cost.push(close);
        }
    }
    // At about equal cost, boosting the glint pixels brings the estimates closer than
    // spreading the samples evenly.
    assert!(close_at_cost[0] > close_at_cost[1], "{close_at_cost:?}");
}

/// A scenario's film rendered with `normals` on a prepared tessellation at sample seed `seed`.
fn film(
    prepared: &Prepared,
    scene: &SceneConfig,
    normals: NormalMode,
    seed: u64,
) -> vastocean::render::pipeline::Rendered {
    let mut c = scene.clone();
    c.render.normals = normals;
    c.render.seed = seed;
    prepared
        .render_samples(&c, MAX_BATCHES, Samples::ALL, false, false)
        .unwrap()
        .0
}

/// The null test: a scenario compared with itself under another sample seed. Against the
/// baseline, paper-low without mapping at sample seed 1 and again at seed 2 differ by the same
/// expected image, so their ratio's interval must hold 1 and not be significant; and the noise
/// floor (the baseline at another seed) must not differ from the baseline, its measured noise
/// matching the predicted. The calm overcast sea of the estimator's checks, 512 px at 64 spp,
/// where the ratio is resolved to a few per cent, so that holding 1 says something.
#[test]
#[ignore]
fn a_scenario_against_itself_under_another_seed_is_a_null_result() {
    let mut scene = SceneConfig::load(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/results/estimator/calm-overcast.toml"),
    )
    .unwrap();
    scene.camera.width = 512;
    scene.camera.projection = Projection::Equirect {
        band_deg: Some((1.0, -6.0)),
    };
    scene.render.spp = 64;
    scene.render.threads = 2;
    let high = prepare(&SceneConfig {
        lod: high_lod(),
        ..scene.clone()
    })
    .unwrap();
    let base = film(&high, &scene, NormalMode::Mapped, 1);
    let floor = film(&high, &scene, NormalMode::Mapped, 2);
    drop(high);
    let low = prepare(&SceneConfig {
        lod: low_lod(),
        ..scene.clone()
    })
    .unwrap();
    let once = film(&low, &scene, NormalMode::Vertex, 1);
    let again = film(&low, &scene, NormalMode::Vertex, 2);
    let inputs = Inputs {
        camera: &base.camera,
        baseline: &base.film,
        scenarios: vec![
            ("low unmapped".into(), &once.film),
            ("low unmapped, seed 2".into(), &again.film),
            ("noise floor".into(), &floor.film),
        ],
        rows_deg: (0.0, -5.0),
        seed: 1,
    };
    let estimator = Estimator::new(&inputs).unwrap();
    let e = estimator.scenarios();
    let r = estimator.ratio(1, 0);
    eprintln!(
        "null ratio {:?}; noise floor {:?}",
        r.corrected, e.scenarios[2].variance_corrected
    );
    // The difference itself is resolved, and the ratio narrowly: holding 1 is a test.
    assert!(e.scenarios[0].significant && e.scenarios[1].significant);
    assert!(r.corrected.ci[1] - r.corrected.ci[0] < 0.05, "{r:?}");
    assert!(r.corrected.contains(1.0) && !r.significant, "{r:?}");
    let nf = &e.scenarios[2];
    assert!(!nf.significant, "{:?}", nf.variance_corrected);
    assert!(
        nf.variance_over_noise.contains(1.0),
        "{:?}",
        nf.variance_over_noise
    );
}

/// `compare`'s own noise floor on the default scene (a physical sun, glint pixels boosted): not
/// significantly different from the baseline, its noise as predicted.
#[test]
#[ignore]
fn compares_noise_floor_is_not_significant() {
    // Seed 11: the coverage test renders seeds 1 to 8 into folders of the same names.
    let s = compare(64, 11, 64);
    let nf = &s.estimates.scenarios[3];
    assert_eq!(nf.name, "noise_floor");
    assert!(!nf.significant, "{:?}", nf.variance_corrected);
    assert!(
        s.noise_model_check.contains(1.0),
        "{:?}",
        s.noise_model_check
    );
    assert!(s.improvement.significant, "{:?}", s.improvement.corrected);
}
