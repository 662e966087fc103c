//! The sweep's renders and measurements: every configuration rendered and kept over the
//! analysed band, the reference rendered over that band, and each point's errors against it.

use std::sync::Arc;
use std::time::Instant;

use super::{AccuracyJob, Point, ROWS, exact_scene, scene_with};
use crate::analysis::error::{Estimator, Inputs};
use crate::app::AppError;
use crate::app::bench::Progress;
use crate::app::compare::sampling;
use crate::color::luminance;
use crate::config::{NormalMode, SceneConfig, SurfaceKind};
use crate::ocean::Surface;
use crate::render::Camera;
use crate::render::film::{Film, MAX_BATCHES, Samples};
use crate::render::pipeline::{Prepared, Setup, prepare_with};
use crate::sky::Sky;

/// A point as rendered: its cost, and its film over the analysed band.
pub(super) struct Rendered {
    pub point: Point,
    pub band: Film,
}

/// Renders every configuration, each tessellation prepared once, all of them on one ocean and
/// one sky (built by the first), then the exact surface's points (their own preparation: the
/// prisms and the layers' pyramids); keeps each film's band. A point's time counts the ocean's
/// build as a render of its own would.
pub(super) fn render_points(
    job: &AccuracyJob,
    band: &Camera,
    progress: &Progress,
) -> Result<(Vec<Rendered>, Shared), AppError> {
    let mut out = Vec::new();
    let mut shared: Option<Shared> = None;
    // mapped normals on the exact surface, and filtered ones where the sweep has them (each
    // prepared on its own: filtered normals' prisms hold the levels' surfaces too)
    let filtered = job.normals.contains(&NormalMode::Filtered);
    let exact = job.exact.iter().flat_map(|x| {
        [NormalMode::Mapped, NormalMode::Filtered]
            .into_iter()
            .filter(move |&n| n == NormalMode::Mapped || filtered)
            .map(move |n| {
                (
                    &x.tessellation,
                    exact_scene(job, &x.tessellation, n),
                    vec![(n, SurfaceKind::Exact)],
                    &x.spp,
                )
            })
    });
    let meshes = job.tessellations.iter().map(|t| {
        let modes = job
            .normals
            .iter()
            .map(|&n| (n, SurfaceKind::Mesh))
            .collect();
        (t, scene_with(job, t), modes, &job.spp)
    });
    for (t, cfg, modes, spps) in meshes.chain(exact) {
        let p = prepare_with(&cfg, Shared::setup(shared.as_ref()))?;
        let first = shared.get_or_insert_with(|| Shared::of(&p));
        first.count(&p);
        let set_up = first.seconds_ocean + p.seconds_tessellation + p.seconds_build;
        let structures = (p.ocean.bytes() + p.accel.mesh().bytes()) as u64 + p.accel.bytes();
        for (normals, surface) in modes {
            for &spp in spps {
                let mut c = cfg.clone();
                c.render.normals = normals;
                c.render.spp = spp;
                let r = p.render_batches(&c, MAX_BATCHES, false)?;
                let (film, rep) = (r.film, r.report);
                // The levels are kept on the shared ocean: the first filtered render builds
                // them, and every filtered point counts what that took.
                let seconds_levels = if normals == NormalMode::Filtered {
                    *first.seconds_levels.get_or_insert(rep.seconds_levels)
                } else {
                    0.0
                };
                let film_bytes = (film.image.pixels.len() * 12
                    + film.batches.as_ref().map_or(0, |b| b.luminance.len() * 4))
                    as u64;
                let band_film = film.rows(band.first_row(), band.height);
                out.push(Rendered {
                    point: Point {
                        lod: t.name.clone(),
                        normals,
                        surface,
                        spp,
                        triangles: rep.triangles,
                        seconds_ocean: first.seconds_ocean,
                        seconds_tessellation: rep.seconds_tessellation,
                        seconds_build: rep.seconds_build,
                        seconds_levels,
                        seconds_trace: rep.seconds_trace,
                        seconds_normal_map: rep.seconds_normal_map,
                        seconds_total: set_up + seconds_levels + rep.seconds_trace,
                        memory_bytes: structures + film_bytes,
                        rays: rep.rays,
                        error: f64::NAN,
                        error_ci: [f64::NAN; 2],
                        bias: f64::NAN,
                        bias_ci: [f64::NAN; 2],
                        bias_resolved: false,
                        error_plain: f64::NAN,
                        noise: band_noise(&band_film, band).1.sqrt(),
                        rmse_relative: f64::NAN,
                        rmse_relative_ci: [f64::NAN; 2],
                        pareto: false,
                    },
                    band: band_film,
                });
                let exact = if surface == SurfaceKind::Exact {
                    " on the exact surface"
                } else {
                    ""
                };
                progress.step(format!("{} {normals}{exact} {spp} spp", t.name));
            }
        }
    }
    // (`check` refuses a job without tessellations)
    let shared = shared.expect("at least one tessellation");
    Ok((out, shared))
}

/// The ocean and sky every scene of the benchmark renders, and the seconds the ocean took.
pub(super) struct Shared {
    ocean: Arc<Surface>,
    sky: Arc<Sky>,
    pub seconds_ocean: f64,
    /// What building filtered normals' levels and slope tables took, once one render has.
    pub seconds_levels: Option<f64>,
    /// How many of the scenes prepared on these built an ocean of their own (1: the first).
    pub oceans_built: usize,
}

impl Shared {
    fn of(p: &Prepared) -> Shared {
        Shared {
            ocean: Arc::clone(&p.ocean),
            sky: Arc::clone(&p.sky),
            seconds_ocean: p.seconds_ocean,
            seconds_levels: None,
            oceans_built: 0,
        }
    }

    /// Counts `p`'s ocean if it built one (a scene handed an ocean takes no time for it).
    pub(super) fn count(&mut self, p: &Prepared) {
        if !Arc::ptr_eq(&p.ocean, &self.ocean) || p.seconds_ocean > 0.0 {
            self.oceans_built += 1;
        }
    }

    /// A scene's set-up on these, or building its own when there are none yet.
    pub(super) fn setup(shared: Option<&Shared>) -> Setup {
        Setup {
            ocean: shared.map(|s| Arc::clone(&s.ocean)),
            sky: shared.map(|s| Arc::clone(&s.sky)),
            ..Setup::default()
        }
    }
}

/// Per analysed row, the mean over its pixels of the variance of the pixel mean (from the
/// batches: the samples of a pixel are not independent, see `Film::batch_variance_of_mean`);
/// and that averaged over the rows.
pub(super) fn band_noise(film: &Film, band: &Camera) -> (Vec<f64>, f64) {
    let rows = film.row_noise(&band.rows_between(ROWS));
    let mean = rows.iter().sum::<f64>() / rows.len().max(1) as f64;
    (rows, mean)
}

/// Mean luminance over the analysed rows.
pub(super) fn band_luminance(film: &Film, band: &Camera) -> f64 {
    let w = film.image.width;
    let rows = band.rows_between(ROWS);
    let sum: f64 = rows
        .iter()
        .flat_map(|&y| &film.image.pixels[y * w..(y + 1) * w])
        .map(|&c| luminance(c) as f64)
        .sum();
    sum / (rows.len() * w).max(1) as f64
}

/// The reference at `spp`: a pilot, then the analysed rows with the noisiest pixels boosted.
pub(super) fn render_reference(
    p: &Prepared,
    cfg: &SceneConfig,
    spp: u32,
    max_boost: u16,
) -> Result<(Film, sampling::SamplingReport, f64), AppError> {
    let t = Instant::now();
    let mut c = cfg.clone();
    c.render.spp = spp;
    let camera = Camera::new(c.camera.aimed(), c.camera.width, c.camera.aspect);
    let boost = if max_boost > 1 {
        let mut pc = c.clone();
        pc.render.spp = sampling::pilot_spp(spp);
        pc.render.seed = c.render.seed.wrapping_add(sampling::PILOT_SEED);
        let pilot = p.render(&pc, false)?;
        let limit = sampling::boost_limit(spp, max_boost);
        sampling::boost_map(&[pilot.film], &camera, ROWS, limit)
    } else {
        vec![1; camera.width * camera.height]
    };
    let seconds_pilot = t.elapsed().as_secs_f64();
    let samples = Samples {
        boost: Some(&boost),
        ..Samples::ALL
    };
    let (r, _) = p.render_samples(&c, MAX_BATCHES, samples, false, false)?;
    let report = sampling::report(
        &boost,
        &camera,
        ROWS,
        spp,
        max_boost,
        c.render.seed.wrapping_add(sampling::PILOT_SEED),
        seconds_pilot,
    );
    Ok((r.film, report, t.elapsed().as_secs_f64()))
}

/// Every point's errors against one reference.
pub(super) fn measure(
    points: &mut [Rendered],
    reference: &Film,
    band: &Camera,
    seed: u64,
) -> Result<(), AppError> {
    let (ref_noise, _) = band_noise(reference, band);
    let scale = band_luminance(reference, band);
    for r in points.iter_mut() {
        let e = Estimator::new(&Inputs {
            camera: band,
            baseline: reference,
            scenarios: vec![(r.point.lod.clone(), &r.band)],
            rows_deg: ROWS,
            seed,
        })
        .map_err(|e| AppError::Run(e.into()))?;
        let s = e.scenarios().scenarios.remove(0);
        let total = e.total_error(0, &ref_noise, false);
        let rms = e.total_error(0, &ref_noise, true);
        let p = &mut r.point;
        p.error = total.value;
        p.error_ci = total.ci;
        p.bias = s.std_corrected.value;
        p.bias_ci = s.std_corrected.ci;
        p.bias_resolved = s.significant;
        p.error_plain = s.std;
        p.rmse_relative = rms.value / scale;
        p.rmse_relative_ci = rms.ci.map(|x| x / scale);
    }
    Ok(())
}
