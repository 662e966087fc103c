//! The estimator on synthetic films whose converged difference is known: Gaussian noise,
//! noise that swamps the signal, and sun-glint-like noise (rare samples hundreds of times
//! brighter than the rest).

use super::*;
use crate::config::Projection;
use crate::image_io::RgbImage;
use crate::render::film::Batches;
use crate::rng::Rng;

const NB: usize = 8;

/// A film from per-pixel batch means (`batches[pixel][b]`), `per_batch` samples each.
fn film_of(batches: &[[f64; NB]], w: usize, h: usize, per_batch: u32) -> Film {
    let full: Vec<f32> = batches
        .iter()
        .map(|b| (b.iter().sum::<f64>() / NB as f64) as f32)
        .collect();
    Film {
        image: RgbImage {
            width: w,
            height: h,
            pixels: full.iter().map(|&x| [x; 3]).collect(),
        },
        var_y: vec![0.0; w * h],
        spp: NB as u32 * per_batch,
        batches: Some(Batches {
            k: NB,
            spp: vec![per_batch; NB],
            luminance: batches.iter().flatten().map(|&x| x as f32).collect(),
        }),
    }
}

fn camera(width: usize) -> Camera {
    Camera::new(
        Projection::Equirect {
            band_deg: Some((1.0, -6.0)),
        },
        width,
        2.0,
    )
}

/// The analysed rows' indices in the camera's image (0 to -5 degrees).
fn analysed(cam: &Camera) -> Vec<usize> {
    (0..cam.height)
        .filter(|&y| {
            let e = cam.row_elevation_deg(y);
            (-5.0..=0.0).contains(&e)
        })
        .collect()
}

/// The band statistic of a known per-pixel expected difference: root mean over rows of its
/// population variance over the row.
fn truth_of(mu: &[f64], cam: &Camera) -> f64 {
    let w = cam.width;
    let rows = analysed(cam);
    let mean_var = rows
        .iter()
        .map(|&y| {
            let r = &mu[y * w..(y + 1) * w];
            let m = r.iter().sum::<f64>() / w as f64;
            r.iter().map(|x| (x - m).powi(2)).sum::<f64>() / w as f64
        })
        .sum::<f64>()
        / rows.len() as f64;
    mean_var.sqrt()
}

/// A baseline and a scenario whose expected difference is a random field of std `sigma_true`
/// (returned, as realized) plus Monte Carlo noise: each batch of the baseline carries noise of
/// std `noise`, and the scenario, rendered "with the same seeds", the same noise plus an
/// independent part of std `own` (so per-image variances would overstate the difference's
/// noise). The pixel difference's noise is `own / sqrt(8)`.
fn synthetic(
    width: usize,
    seed: u64,
    sigma_true: f64,
    noise: f64,
    own: f64,
) -> (Camera, Film, Film, f64) {
    let cam = camera(width);
    let (w, h) = (cam.width, cam.height);
    let mut r = Rng::keyed(&[seed]);
    let mut base = vec![[0.0; NB]; w * h];
    let mut scen = vec![[0.0; NB]; w * h];
    let mut mu = vec![0.0; w * h];
    for i in 0..w * h {
        mu[i] = sigma_true * r.gauss();
        for k in 0..NB {
            let shared = 1.0 + noise * r.gauss();
            base[i][k] = shared;
            scen[i][k] = shared + mu[i] + own * r.gauss();
        }
    }
    let truth = truth_of(&mu, &cam);
    (cam, film_of(&base, w, h, 1), film_of(&scen, w, h, 1), truth)
}

fn estimate(cam: &Camera, base: &Film, scens: &[&Film], seed: u64) -> Estimator {
    Estimator::new(&Inputs {
        camera: cam,
        baseline: base,
        scenarios: scens
            .iter()
            .enumerate()
            .map(|(i, f)| (format!("s{i}"), *f))
            .collect(),
        rows_deg: (0.0, -5.0),
        seed,
    })
    .unwrap()
}

#[test]
fn known_difference_is_recovered_under_known_noise() {
    // Difference noise per pixel: own / sqrt(8) = 0.212 against a true std of 0.1; the shared
    // noise (0.5) must not count.
    let (cam, base, scen, truth) = synthetic(1024, 1, 0.1, 0.5, 0.6);
    let e = estimate(&cam, &base, &[&scen], 1)
        .scenarios()
        .scenarios
        .remove(0);
    // 1024 px: 0.35 degree rows, 14 of them between 0 and -5 degrees.
    assert_eq!(e.rows.len(), 14);
    let noise = 0.6 / 8f64.sqrt();
    assert!((e.noise / noise - 1.0).abs() < 0.03, "noise {}", e.noise);
    assert!(
        (e.std - (0.01f64 + noise * noise).sqrt()).abs() < 0.01,
        "plain {}",
        e.std
    );
    let c = e.std_corrected;
    assert!(c.contains(truth), "{c:?} against {truth}");
    assert!((c.value - truth).abs() < 0.01, "{c:?}");
    assert!(e.significant);
    assert_eq!(
        e.noisy_rows, 14,
        "noise variance 0.045 against a signal of 0.01"
    );
    // Measured over predicted variance: (0.1^2 + noise^2) / noise^2.
    let want = (0.01 + noise * noise) / (noise * noise);
    assert!((e.variance_over_noise.value / want - 1.0).abs() < 0.05);
    // With no true difference: the variance's interval holds 0, the variance ratio 1.
    let (cam, base, scen, _) = synthetic(1024, 2, 0.0, 0.5, 0.6);
    let e = estimate(&cam, &base, &[&scen], 2)
        .scenarios()
        .scenarios
        .remove(0);
    assert!(
        e.variance_corrected.contains(0.0),
        "{:?}",
        e.variance_corrected
    );
    assert!(!e.significant);
    assert!(
        e.variance_over_noise.contains(1.0),
        "{:?}",
        e.variance_over_noise
    );
}

/// The intervals hold the converged value about 95 % of the time, and are about as wide as the
/// estimates' own spread over independent films says they should be (neither too narrow nor
/// uselessly wide).
#[test]
fn intervals_cover_the_converged_value_about_95_percent_of_the_time() {
    let trials = 100;
    let (mut covered, mut errors, mut widths) = (0, Vec::new(), Vec::new());
    for k in 0..trials {
        let (cam, base, scen, truth) = synthetic(256, 100 + k, 0.05, 0.2, 0.3);
        let e = estimate(&cam, &base, &[&scen], k)
            .scenarios()
            .scenarios
            .remove(0);
        let c = e.std_corrected;
        covered += usize::from(c.contains(truth));
        errors.push(c.value - truth);
        widths.push(c.ci[1] - c.ci[0]);
    }
    // Binomial: 95 +- 2.2 expected; outside 88..=100 the intervals are wrong. (99 when
    // written: the bootstrap is a little conservative here.)
    assert!(
        (88..=100).contains(&covered),
        "{covered} of {trials} covered"
    );
    let n = trials as f64;
    let m = errors.iter().sum::<f64>() / n;
    let sd = (errors.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    let ratio = median(widths) / (2.0 * 1.96 * sd);
    eprintln!("GAUSS width over spread {ratio}");
    assert!(
        (0.8..1.5).contains(&ratio),
        "interval width / (2 x 1.96 x spread) = {ratio}"
    );
}

/// Where the noise swamps the signal (noise variance 25 times the signal's) the corrected
/// variance is unbiased on average over many films; where there is no signal at all, per-row
/// stds clipped at 0 and averaged (the paper's averaging, and what the estimator did before)
/// read a difference that is not there, while the band's variance averages to 0.
#[test]
fn the_corrected_variance_is_unbiased_where_noise_swamps_the_signal() {
    let trials = 40;
    let n = trials as f64;
    let (mut ests, mut truth) = (Vec::new(), 0.0);
    let (mut clipped, mut nulls) = (0.0, Vec::new());
    for k in 0..trials {
        let (cam, base, scen, t) = synthetic(256, 300 + k, 0.04, 0.2, 0.2 * 8f64.sqrt());
        let e = estimate(&cam, &base, &[&scen], k)
            .scenarios()
            .scenarios
            .remove(0);
        ests.push(e.variance_corrected.value);
        truth += t * t / n;
        let (cam, base, scen, _) = synthetic(256, 400 + k, 0.0, 0.2, 0.2 * 8f64.sqrt());
        let e = estimate(&cam, &base, &[&scen], k)
            .scenarios()
            .scenarios
            .remove(0);
        clipped += e.std_corrected_mean_rows / n;
        nulls.push(e.variance_corrected.value);
    }
    let mean_se = |v: &[f64]| {
        let m = v.iter().sum::<f64>() / n;
        (
            m,
            (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt(),
        )
    };
    let (est, sd) = mean_se(&ests);
    assert!(
        (est - truth).abs() < 3.0 * sd,
        "mean estimate {est} against {truth} (se {sd})"
    );
    let (null, sd) = mean_se(&nulls);
    assert!(
        null.abs() < 3.0 * sd,
        "mean estimate {null} against 0 (se {sd})"
    );
    // Noise std 0.2 a pixel; a row's variance estimate has a standard error of about
    // 0.04 * sqrt(2 / 256) = 0.0035, whose positive half's root averages about 0.03.
    assert!(clipped > 0.02, "clipped {clipped}");
}

/// Sun-glint noise: each sample of a pixel in the glint columns hits the sun (radiance
/// `sun`) with a probability that differs between the films, so the expected difference there
/// is large and its estimate from a few hits very noisy.
/// The glint pixels take `boost` times the samples, as `compare`'s pilot would have them.
fn glints(seed: u64, per_batch: u32, sun: f64, boost: u32) -> (Camera, Film, Vec<Film>, [f64; 2]) {
    let cam = camera(256);
    let (w, h) = (cam.width, cam.height);
    let mut r = Rng::keyed(&[seed, 0x676c]);
    // Hit probabilities per pixel: the baseline's, and two scenarios', near azimuth 180.
    let p = |x: usize, y: usize, which: u64| -> f64 {
        let d = x as f64 - w as f64 / 2.0;
        if d.abs() > 4.0 {
            return 0.0;
        }
        let h = crate::rng::splitmix64(which ^ (x as u64 * 977 + y as u64 * 131)) >> 11;
        0.005 + 0.05 * (h as f64 / (1u64 << 53) as f64)
    };
    let mut films = Vec::new();
    let mut mus = [vec![0.0; w * h], vec![0.0; w * h]];
    for which in 0..3u64 {
        let mut px = vec![[0.0; NB]; w * h];
        for y in 0..h {
            for x in 0..w {
                let pr = p(x, y, which);
                // A gentle sky: a smooth azimuthal pattern that differs by film.
                let sky = 1.0 + 0.05 * which as f64 * ((x as f64) * 0.05).sin();
                if which > 0 {
                    mus[which as usize - 1][y * w + x] = sky - 1.0 + sun * (pr - p(x, y, 0));
                }
                let n = if pr > 0.0 {
                    per_batch * boost
                } else {
                    per_batch
                };
                for v in px[y * w + x].iter_mut() {
                    let mut s = 0.0;
                    for _ in 0..n {
                        s += sky + if r.f64() < pr { sun } else { 0.0 };
                    }
                    *v = s / n as f64;
                }
            }
        }
        films.push(film_of(&px, w, h, per_batch));
    }
    let truth = [truth_of(&mus[0], &cam), truth_of(&mus[1], &cam)];
    let base = films.remove(0);
    (cam, base, films, truth)
}

/// Sun glints at 16 spp (two samples a batch) with the glint pixels boosted 64 times, as
/// `compare` renders them: the ratio's intervals cover the converged ratio (36 of 40 when
/// written) and say something (median width 0.29 of the ratio). Unboosted, where most batches of
/// a glint pixel hold no hit, the same films covered 29 of 40 with intervals reaching to
/// infinity: an interval cannot show samples that were never drawn.
#[test]
fn ratio_intervals_cover_under_boosted_sun_glints() {
    let trials = 40;
    let (mut covered, mut widths) = (0, Vec::new());
    for k in 0..trials {
        let (cam, base, films, t) = glints(500 + k, 2, 1000.0, 64);
        let r = estimate(&cam, &base, &[&films[0], &films[1]], k).ratio(0, 1);
        let truth = t[0] / t[1];
        covered += usize::from(r.corrected.contains(truth));
        widths.push((r.corrected.ci[1] - r.corrected.ci[0]) / truth);
    }
    // 38 expected; 34 is the binomial's 3 % lower tail.
    assert!(covered >= 34, "{covered} of {trials} covered");
    let width = median(widths);
    assert!(width < 0.5, "median interval width {width} of the ratio");
}

#[test]
fn ratio_of_two_known_differences() {
    // b was made against another baseline; against this one it differs by the same field
    // (both baselines expect 1) plus more noise.
    let (cam, base, a, ta) = synthetic(1024, 7, 0.2, 0.3, 0.2);
    let (_, _, b, tb) = synthetic(1024, 8, 0.1, 0.3, 0.2);
    let r = estimate(&cam, &base, &[&a, &b], 3).ratio(0, 1);
    assert!(r.corrected.contains(ta / tb), "{r:?} against {}", ta / tb);
    assert!(r.significant && r.spp_to_resolve.is_none());
}

#[test]
fn a_scenario_against_itself_is_not_significant() {
    // The noise floor: the baseline again with other seeds.
    let (cam, base, _, _) = synthetic(512, 11, 0.0, 0.3, 0.0);
    let (_, again, _, _) = synthetic(512, 12, 0.0, 0.3, 0.0);
    let e = estimate(&cam, &base, &[&again], 5)
        .scenarios()
        .scenarios
        .remove(0);
    assert!(!e.significant, "{:?}", e.variance_corrected);
    assert!(
        e.variance_over_noise.contains(1.0),
        "{:?}",
        e.variance_over_noise
    );
}

#[test]
fn too_few_batches_is_an_error() {
    let (cam, base, scen, _) = synthetic(256, 1, 0.1, 0.1, 0.1);
    let mut few = scen.clone();
    let b = few.batches.as_mut().unwrap();
    b.k = 4;
    b.spp.truncate(4);
    b.luminance = b
        .luminance
        .chunks(NB)
        .flat_map(|c| c[..4].to_vec())
        .collect();
    let mut base4 = base.clone();
    *base4.batches.as_mut().unwrap() = few.batches.clone().unwrap();
    let err = Estimator::new(&Inputs {
        camera: &cam,
        baseline: &base4,
        scenarios: vec![("s".into(), &few)],
        rows_deg: (0.0, -5.0),
        seed: 1,
    });
    assert!(matches!(err, Err(EstimateError::TooFewSamples(_))));
}

/// Where the noise swamps both differences, a ratio's interval is wide but never reaches below
/// 0 (the bootstrap widens its replicates about the estimate, which could).
#[test]
fn a_ratio_interval_never_reaches_below_zero() {
    for k in 0..12 {
        let (cam, base, a, _) = synthetic(256, 600 + k, 0.04, 0.2, 0.2 * 8f64.sqrt());
        let (_, _, b, _) = synthetic(256, 700 + k, 0.04, 0.2, 0.2 * 8f64.sqrt());
        let r = estimate(&cam, &base, &[&a, &b], k).ratio(0, 1);
        for iv in [r.corrected, r.median_rows, r.trimmed, r.trend, r.residual] {
            assert!(iv.ci[0] >= 0.0, "{iv:?}");
        }
    }
}
