//! How `compare` renders: each tessellation prepared once and traced for every scenario that
//! uses it, after the pilot that places the samples; and, with `--against truth`, the truth on
//! the analysed rows only.

use std::sync::Arc;
use std::time::Instant;

use super::sampling::{self, SamplingReport};
use super::truth::{self, Truth};
use super::{CompareJob, Scenario, ScenarioInfo};
use crate::app::AppError;
use crate::config::{LodConfig, NormalMode, SceneConfig, SurfaceKind};
use crate::render::film::{MAX_BATCHES, Samples};
use crate::render::pipeline::{Prepared, Rendered, Setup, prepare_with};

/// What [`render_scenarios`] returns: the scenarios in [`CompareJob::scenarios`] order, the
/// truth if asked for (and not reused), and how the samples were spent.
pub(super) struct Renders {
    pub runs: Vec<(ScenarioInfo, Rendered)>,
    pub truth: Option<(Truth, Rendered)>,
    pub sampling: SamplingReport,
}

/// The scene as one tessellation renders it.
pub(super) fn with_lod(scene: &SceneConfig, lod: &LodConfig) -> SceneConfig {
    SceneConfig {
        lod: lod.clone(),
        ..scene.clone()
    }
}

/// The scene of scenarios `low_exact` and `low_exact_filtered`: the low tessellation's exact
/// surface, prepared with filtered normals (its levels' surfaces built) when the second is
/// rendered.
pub(super) fn exact_scene(job: &CompareJob) -> SceneConfig {
    let mut c = with_lod(&job.scene, &job.low);
    c.render.surface = SurfaceKind::Exact;
    // the levels' surfaces are built only for a filtered scenario
    c.render.normals = if job.exact && job.filtered {
        NormalMode::Filtered
    } else {
        NormalMode::Mapped
    };
    c
}

/// A scene prepared when its scenarios' turn comes (after the previous one is freed).
type Later<'a> = Box<dyn FnOnce() -> Result<Prepared, crate::render::pipeline::RenderError> + 'a>;

/// Renders every scenario, each tessellation prepared once, after the pilot that places the
/// samples; returned in [`CompareJob::scenarios`] order, with how the samples were spent.
pub(super) fn render_scenarios(job: &CompareJob) -> Result<Renders, AppError> {
    let say = |what: String| {
        if job.progress {
            eprintln!("compare: {what}");
        }
    };
    // The low tessellation first (its pilots need it), kept while the high one is traced.
    let (high_cfg, low_cfg) = (
        with_lod(&job.scene, &job.high),
        with_lod(&job.scene, &job.low),
    );
    say(format!("low tessellation ({})", job.low.preset));
    let low = prepare_with(
        &low_cfg,
        Setup {
            progress: job.progress,
            ..Setup::default()
        },
    )?;
    let camera = crate::render::Camera::new(
        job.scene.camera.projection,
        job.scene.camera.width,
        job.scene.camera.aspect,
    );
    let mut pilots = Vec::new();
    // The boost map reads the pilots' analysed rows only: no other row is traced.
    let analysed = sampling::analysed_rows(&camera, job.rows_deg);
    let pilot = |prepared: &Prepared, cfg: &SceneConfig, sc: Scenario| {
        let mut c = cfg.clone();
        c.render.normals = sc.normals();
        c.render.spp = sampling::pilot_spp(cfg.render.spp);
        c.render.seed = cfg.render.seed.wrapping_add(sampling::PILOT_SEED);
        say(format!("pilot of {} at {} spp", sc.name(), c.render.spp));
        let samples = Samples {
            boost: Some(&analysed),
            ..Samples::ALL
        };
        prepared
            .render_samples(&c, 0, samples, false, job.progress)
            .map(|(r, _)| r.film)
    };
    let boosting = job.max_boost > 1;
    // the pilots' own time: their traces and the boost map, not the sea or the meshes
    let t = Instant::now();
    if boosting {
        for sc in [Scenario::LowMapped, Scenario::LowUnmapped] {
            pilots.push(pilot(&low, &low_cfg, sc)?);
        }
    }
    let mut seconds_pilot = t.elapsed().as_secs_f64();
    say(format!("high tessellation ({})", job.high.preset));
    // the same sea and sky: the low tessellation's, not a second build of them
    let high = prepare_with(
        &high_cfg,
        Setup {
            ocean: Some(Arc::clone(&low.ocean)),
            sky: Some(Arc::clone(&low.sky)),
            progress: job.progress,
            ..Setup::default()
        },
    )?;
    let boost = if boosting {
        let t = Instant::now();
        pilots.push(pilot(&high, &high_cfg, Scenario::HighMapped)?);
        seconds_pilot += t.elapsed().as_secs_f64();
        let limit = sampling::boost_limit(job.scene.render.spp, job.max_boost);
        sampling::boost_map(&pilots, &camera, job.rows_deg, limit)
    } else {
        vec![1; camera.width * camera.height]
    };
    drop(pilots);
    let samples = Samples {
        boost: Some(&boost),
        ..Samples::ALL
    };
    let mut out = Vec::new();
    let mut truth_run = None;
    let (ocean, sky) = (Arc::clone(&low.ocean), Arc::clone(&low.sky));
    let exact_cfg = exact_scene(job);
    let exact = || {
        prepare_with(
            &exact_cfg,
            Setup {
                ocean: Some(ocean),
                sky: Some(sky),
                progress: job.progress,
                ..Setup::default()
            },
        )
    };
    let groups: [(bool, Later, &SceneConfig, &LodConfig); 3] = [
        (true, Box::new(|| Ok(high)), &high_cfg, &job.high),
        (false, Box::new(|| Ok(low)), &low_cfg, &job.low),
        (false, Box::new(exact), &exact_cfg, &job.low),
    ];
    for (k, (is_high, prepared, cfg, lod)) in groups.into_iter().enumerate() {
        let exact = k == 2;
        let wanted: Vec<Scenario> = job
            .scenarios()
            .into_iter()
            .filter(|s| s.high() == is_high && s.exact() == exact)
            .collect();
        let with_truth = exact && job.against == truth::Against::Truth && job.truth_from.is_none();
        if wanted.is_empty() && !with_truth {
            continue;
        }
        if exact {
            say(format!(
                "exact surface in the low tessellation ({})",
                lod.preset
            ));
        }
        let prepared: Prepared = prepared()?;
        for sc in wanted {
            let mut c = cfg.clone();
            c.render.normals = sc.normals();
            c.render.seed = cfg.render.seed.wrapping_add(sc.seed_offset());
            let (r, _) = prepared.render_samples(&c, MAX_BATCHES, samples, false, job.progress)?;
            let rep = &r.report;
            let info = ScenarioInfo {
                name: sc,
                tessellation: format!("{} ({} triangles)", lod.preset, rep.triangles),
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
                std_vs_truth: None,
                mean_vs_truth: None,
            };
            out.push((info, r));
        }
        if with_truth {
            say(format!(
                "truth: the exact surface, geometric normals, {}x the samples on the analysed rows",
                job.truth_boost
            ));
            let cfg = truth::scene(job);
            truth_run = Some(truth::render(job, &prepared, &cfg, &boost, &camera)?);
        }
        // The high tessellation's BVH is freed here, before the low one is traced.
        drop(prepared);
    }
    let order = job.scenarios();
    out.sort_by_key(|(info, _)| order.iter().position(|s| *s == info.name));
    let report = sampling::report(
        &boost,
        &camera,
        job.rows_deg,
        job.scene.render.spp,
        job.max_boost,
        job.scene.render.seed.wrapping_add(sampling::PILOT_SEED),
        seconds_pilot,
    );
    Ok(Renders {
        runs: out,
        truth: truth_run,
        sampling: report,
    })
}
