//! The exact displaced surface on both backends: Embree's user geometry and the Rust tree of
//! prisms find the same hits; a render on it is NaN-free with no holes; scenes that cannot
//! use it are refused.

use vastocean::config::{Backend, NormalMode, SceneConfig, SurfaceKind};

#[cfg(feature = "embree")]
mod cross {
    use std::sync::Arc;

    use vastocean::accel::embree::{BuildOptions, Device, ExactScene};
    use vastocean::accel::exact::{Exact, ExactSurface};
    use vastocean::accel::{Accel, Ray};
    use vastocean::lod::{EARTH_RADIUS_M, LodParams, Pattern, Reading, tessellate};
    use vastocean::mesh::Mesh;
    use vastocean::ocean::{LayerSpec, OceanParams, Surface};
    use vastocean::rng::Rng;

    const CAMERA_M: f64 = 5.0;

    fn sea() -> Arc<Surface> {
        let p = OceanParams {
            layers: vec![
                LayerSpec {
                    size_m: 200.0,
                    n: 128,
                },
                LayerSpec {
                    size_m: 23.7,
                    n: 128,
                },
                LayerSpec {
                    size_m: 2.93,
                    n: 64,
                },
            ],
            ..OceanParams::default()
        };
        Arc::new(Surface::new(&p, 3).unwrap())
    }

    fn coarse(ocean: &Surface) -> Arc<Mesh> {
        let params = LodParams {
            near_size_m: 0.9,
            double_distance_m: 18.0,
            generations: None,
            max_distance_m: Some(400.0),
            pattern: Pattern::Square,
            reading: Reading::default(),
            earth_radius_m: EARTH_RADIUS_M,
            camera_height_m: CAMERA_M,
        };
        Arc::new(tessellate(&params, &ocean.sampler([0.0, 0.0])).unwrap().0)
    }

    /// Camera rays from steep to grazing, and rays rising at grazing angles from near the sea.
    fn rays(n: usize, seed: u64) -> Vec<Ray> {
        let mut rng = Rng::keyed(&[seed]);
        (0..n)
            .map(|k| {
                let az = std::f64::consts::TAU * rng.f64();
                if k % 2 == 0 {
                    let el = -(1.0 + 60.0 * rng.f64().powi(3)).to_radians();
                    let d = [el.cos() * az.cos(), el.sin(), el.cos() * az.sin()];
                    Ray::new([0.0, CAMERA_M as f32, 0.0], d.map(|c| c as f32))
                } else {
                    let el = (0.3 + 6.0 * rng.f64()).to_radians();
                    let o = [60.0 * rng.f64() - 30.0, 0.4, 60.0 * rng.f64() - 30.0];
                    let d = [el.cos() * az.cos(), el.sin(), el.cos() * az.sin()];
                    Ray::new(o.map(|c| c as f32), d.map(|c| c as f32))
                }
            })
            .collect()
    }

    /// The test sea, and its exact surface inside the coarse mesh's prisms on both backends
    /// (with the levels' surfaces too where `levels`).
    fn backends(levels: bool) -> (Arc<Surface>, Exact, ExactScene) {
        let ocean = sea();
        let mesh = coarse(&ocean);
        let surface =
            || ExactSurface::new(ocean.clone(), [0.0, 0.0], EARTH_RADIUS_M, levels).unwrap();
        let rust = Exact::build(mesh.clone(), surface());
        let device = Device::new(2).unwrap();
        let embree = ExactScene::new(&device, mesh, surface(), BuildOptions::default()).unwrap();
        (ocean, rust, embree)
    }

    #[test]
    fn embree_user_geometry_and_the_rust_prisms_find_the_same_hits() {
        let (_, rust, embree) = backends(false);
        let (mut hits, mut worst) = (0, 0.0f64);
        for ray in rays(400, 1) {
            match (rust.intersect(&ray), embree.intersect(&ray)) {
                (None, None) => {}
                (Some(a), Some(b)) => {
                    hits += 1;
                    // the same crossing, found from other prisms' warm starts
                    let rel = (a.t as f64 - b.t as f64).abs() / (a.t as f64).max(1.0);
                    worst = worst.max(rel);
                    let (xa, xb) = (rust.interpolate_uv(&a), embree.interpolate_uv(&b));
                    assert!(
                        (xa[0] - xb[0]).abs() < 1e-2 && (xa[1] - xb[1]).abs() < 1e-2,
                        "nominal {xa:?} against {xb:?} on {ray:?}"
                    );
                }
                (a, b) => panic!("rust {a:?}, embree {b:?} on {ray:?}"),
            }
        }
        assert!(worst < 1e-4, "t differs by {worst} of itself");
        // every camera ray, and some of the rising ones (the next wave)
        assert!(hits > 205, "{hits} of 400 rays hit");
        assert!(embree.take_error().is_none());
    }

    /// With the levels held (filtered normals), both backends find the same hits on random
    /// surfaces of them: each layer read from one of its levels, or left out.
    #[test]
    fn both_backends_find_the_same_hits_on_the_levels_surfaces() {
        use vastocean::ocean::slopes::{ALL_WAVES, NOT_READ};
        let (ocean, rust, embree) = backends(true);
        let levels = ocean.levels();
        let mut rng = Rng::keyed(&[21]);
        let rays = rays(300, 2);
        let lods: Vec<_> = rays
            .iter()
            .map(|_| {
                let mut lod = ALL_WAVES;
                for (i, l) in lod.iter_mut().enumerate().take(ocean.layers().len()) {
                    let pick = (rng.f64() * (levels.count(i) + 2) as f64) as usize;
                    *l = if pick > levels.count(i) {
                        NOT_READ
                    } else {
                        pick as u8
                    };
                }
                lod
            })
            .collect();
        let (mut a, mut b) = (vec![None; rays.len()], vec![None; rays.len()]);
        rust.intersect_many_at(&rays, &lods, &mut a);
        embree.intersect_many_at(&rays, &lods, &mut b);
        let mut hits = 0;
        for ((ray, lod), (a, b)) in rays.iter().zip(&lods).zip(a.iter().zip(&b)) {
            match (a, b) {
                (None, None) => {}
                (Some(a), Some(b)) => {
                    hits += 1;
                    let rel = (a.t as f64 - b.t as f64).abs() / (a.t as f64).max(1.0);
                    assert!(rel < 1e-4, "t {} against {} on {ray:?} ({lod:?})", a.t, b.t);
                }
                (a, b) => panic!("rust {a:?}, embree {b:?} on {ray:?} ({lod:?})"),
            }
        }
        assert!(hits > 120, "{hits} of 300 rays hit");
        assert!(embree.take_error().is_none());
    }
}

#[cfg(feature = "embree")]
#[test]
fn crosscheck_of_the_exact_surface_finds_no_disagreement() {
    use vastocean::app::crosscheck::{CrosscheckJob, run};
    let r = run(&CrosscheckJob {
        lod: vastocean::config::LodChoice::PaperLow,
        rays: 2000,
        width: 16,
        spp: 1,
        seed: 5,
        threads: 2,
        surface: SurfaceKind::Exact,
    })
    .unwrap();
    assert_eq!(r.rays.unexplained_disagreements, 0, "{r}");
    assert!(r.rays.same_prim > 1000, "{r}");
    assert!(r.rays.max_rel_dt <= 1e-4, "{r}");
}

fn small_scene(surface: SurfaceKind) -> SceneConfig {
    let mut cfg = SceneConfig::default();
    cfg.camera.width = 64;
    cfg.render.spp = 2;
    cfg.render.backend = Backend::Rust;
    cfg.render.surface = surface;
    cfg
}

#[test]
fn an_exact_render_has_no_nans_holes_or_self_hits() {
    let cfg = small_scene(SurfaceKind::Exact);
    let r = vastocean::render::pipeline::render_scene(&cfg, false)
        .unwrap()
        .report;
    assert_eq!(r.backend, "rust-exact");
    assert_eq!(r.nan_count, 0);
    assert_eq!(r.escaped_below_horizon, 0);
    // no ray meets the surface again where it left it (the geometric normal is the bilinear
    // surface's own, so a leaving ray is on its side)
    assert_eq!(r.self_hits, 0);
    let hits = r.counters.hits as f64;
    assert!(hits > 1000.0);
    // the mapped normal and the surface's tangent plane disagree rarely, whatever the policy
    // does about it (bends, mirrors or ends the branch)
    let events = vastocean::app::compare::truth::wrong_side_events(&r.counters);
    assert!(
        events > 0 && (events as f64) < 0.01 * hits,
        "{events} of {hits}"
    );
}

/// Filtered normals on the exact surface: each path meets the surface of the waves its
/// footprint resolves, with no NaN, hole or self-hit, and its rough hits take the lobe.
#[test]
fn a_filtered_exact_render_meets_the_resolved_waves() {
    let mut cfg = small_scene(SurfaceKind::Exact);
    cfg.render.normals = NormalMode::Filtered;
    let r = render_without_nans_holes_or_self_hits(&cfg);
    assert!(
        r.counters.rough_hits > 100,
        "{} rough hits",
        r.counters.rough_hits
    );
}

#[test]
fn exact_surface_refuses_vertex_normals_and_bicubic_reads() {
    let mut cfg = small_scene(SurfaceKind::Exact);
    cfg.render.normals = NormalMode::Vertex;
    let e = cfg.validate().unwrap_err().to_string();
    assert!(e.contains("render.normals") && e.contains("exact"), "{e}");
    let mut cfg = small_scene(SurfaceKind::Exact);
    cfg.ocean.interp = vastocean::ocean::Interp::Bicubic;
    let e = cfg.validate().unwrap_err().to_string();
    assert!(e.contains("ocean.interp"), "{e}");
}

/// The exact surface reads the paper's bilinear fields as well as the default prefiltered ones
/// (its bounds taken from the texels either way), with no NaN, hole or self-hit.
#[test]
fn an_exact_render_reads_bilinear_fields() {
    let mut cfg = small_scene(SurfaceKind::Exact);
    assert_ne!(cfg.ocean.interp, vastocean::ocean::Interp::Bilinear);
    cfg.ocean.interp = vastocean::ocean::Interp::Bilinear;
    render_without_nans_holes_or_self_hits(&cfg);
}

/// Renders `cfg` on the Rust prisms and checks it has no NaN, no hole below the horizon, no
/// ray meeting the surface where it left it, and over a thousand hits.
fn render_without_nans_holes_or_self_hits(
    cfg: &SceneConfig,
) -> vastocean::render::report::RenderReport {
    cfg.validate().unwrap();
    let r = vastocean::render::pipeline::render_scene(cfg, false)
        .unwrap()
        .report;
    assert_eq!(r.backend, "rust-exact");
    assert_eq!(r.nan_count, 0);
    assert_eq!(r.escaped_below_horizon, 0);
    assert_eq!(r.self_hits, 0);
    assert!(r.counters.hits > 1000);
    r
}

#[test]
fn compare_refuses_an_exact_scene_and_checks_its_exact_scenario_before_any_work() {
    use vastocean::app::compare::{CompareJob, run};
    let out = std::env::temp_dir().join("vastocean-exact-compare-refused");
    let job = |scene: SceneConfig, exact: bool| CompareJob {
        scene,
        high: Default::default(),
        low: Default::default(),
        rows_deg: (0.0, -5.0),
        max_boost: 1,
        filtered: false,
        exact,
        against: vastocean::app::compare::Against::PaperHigh,
        truth_boost: vastocean::app::compare::DEFAULT_TRUTH_BOOST,
        truth_from: None,
        out: out.clone(),
        progress: false,
    };
    // the paper's scenarios are meshes: an exact scene is refused, pointing to --exact
    let e = run(&job(small_scene(SurfaceKind::Exact), false)).unwrap_err();
    assert_eq!(e.exit_code(), 2, "{e}");
    assert!(e.to_string().contains("--exact"), "{e}");
    // --exact with reads the exact surface cannot bound: refused before anything renders
    let mut scene = small_scene(SurfaceKind::Mesh);
    scene.ocean.interp = vastocean::ocean::Interp::Bicubic;
    let e = run(&job(scene, true)).unwrap_err();
    assert_eq!(e.exit_code(), 2, "{e}");
    assert!(e.to_string().contains("ocean.interp"), "{e}");
    assert!(!out.join("summary.json").exists());
}

/// The comparisons' scene: the default sea, the band +1 to -6 degrees at 128 px, 8 spp.
fn band_scene() -> SceneConfig {
    let mut scene = SceneConfig::default();
    scene.camera.width = 128;
    scene.camera.projection = vastocean::config::Projection::Equirect {
        band_deg: Some((1.0, -6.0)),
    };
    scene.render.spp = 8;
    scene.render.threads = 2;
    scene
}

/// `compare --exact --filtered` renders the exact surface with mapped and with filtered
/// normals, last, with their statistics; and a scene prepared on the exact surface without
/// the levels' surfaces refuses a filtered render, whose paths would meet the whole sea.
#[test]
fn compare_renders_the_exact_surface_with_filtered_normals_and_a_bare_surface_refuses_them() {
    use vastocean::app::compare::{CompareJob, Scenario, run};
    use vastocean::config::{LodChoice, LodConfig, NormalMode};
    let mut scene = band_scene();
    scene.render.backend = Backend::Rust;
    let out = std::env::temp_dir().join("vastocean-compare-exact-filtered");
    let _ = std::fs::remove_dir_all(&out);
    let job = CompareJob {
        scene: scene.clone(),
        high: LodConfig {
            preset: LodChoice::Custom,
            near_size_m: Some(0.6),
            double_distance_m: Some(18.0),
            ..LodConfig::default()
        },
        low: LodConfig::default(),
        rows_deg: (0.0, -5.0),
        max_boost: 1,
        filtered: true,
        exact: true,
        against: vastocean::app::compare::Against::PaperHigh,
        truth_boost: vastocean::app::compare::DEFAULT_TRUTH_BOOST,
        truth_from: None,
        out: out.clone(),
        progress: false,
    };
    let names = job.scenarios();
    assert_eq!(
        names[names.len() - 2..],
        [Scenario::LowExact, Scenario::LowExactFiltered]
    );
    let s = run(&job).unwrap();
    assert_eq!(s.scenarios.len(), 8);
    for v in [
        s.std_low_exact_corrected,
        s.std_low_exact_filtered_corrected,
    ] {
        assert!(v.is_some_and(|v| v.is_finite() && v >= 0.0), "{v:?}");
    }
    assert!(out.join("low_exact_filtered.exr").is_file());
    let _ = std::fs::remove_dir_all(&out);

    // prepared with mapped normals: no levels' surfaces, so a filtered render is refused
    let mut cfg = small_scene(SurfaceKind::Exact);
    let bare = vastocean::render::pipeline::prepare(&cfg).unwrap();
    cfg.render.normals = NormalMode::Filtered;
    let Err(e) = bare.render(&cfg, false) else {
        panic!("a filtered render on a bare exact surface was not refused");
    };
    let e = e.to_string();
    assert!(e.contains("levels"), "{e}");
}

#[test]
fn compare_against_truth_measures_every_scenario_against_a_truth_free_of_wrong_side_events() {
    use vastocean::app::compare::{Against, CompareJob, Scenario, run};
    use vastocean::config::{LodChoice, LodConfig};
    let scene = band_scene();
    let out = std::env::temp_dir().join("vastocean-compare-truth");
    let again = std::env::temp_dir().join("vastocean-compare-truth-reused");
    for d in [&out, &again] {
        let _ = std::fs::remove_dir_all(d);
    }
    let job = CompareJob {
        scene,
        high: LodConfig {
            preset: LodChoice::Custom,
            near_size_m: Some(0.3),
            double_distance_m: Some(18.0),
            ..LodConfig::default()
        },
        low: LodConfig::default(),
        rows_deg: (0.0, -5.0),
        max_boost: 1,
        filtered: false,
        exact: false,
        against: Against::Truth,
        truth_boost: 2,
        truth_from: None,
        out: out.clone(),
        progress: false,
    };
    let s = run(&job).unwrap();
    let t = s.truth.as_ref().expect("the truth");
    // the shading normal is the surface's own: no policy is ever consulted
    assert!(t.counters.hits > 1000, "{:?}", t.counters);
    assert!(t.wrong_side_share < 1e-3, "{}", t.wrong_side_share);
    assert_eq!(t.counters.nan, 0);
    assert_eq!(t.counters.self_hits, 0);
    // twice the scenarios' samples, on the analysed rows only
    let width = job.scene.camera.width as u64;
    assert_eq!(t.samples, 2 * 8 * width * s.rows as u64);
    let rows = s.truth_rows.as_ref().unwrap();
    assert_eq!(rows.len(), s.rows);
    for r in rows {
        assert!(
            r.luminance > 0.0 && r.noise > 0.0 && r.noise < r.luminance,
            "{r:?}"
        );
    }
    for sc in &s.scenarios {
        let (std, mean) = (sc.std_vs_truth, sc.mean_vs_truth);
        if sc.name == Scenario::NoiseFloor {
            assert!(std.is_none() && mean.is_none());
            continue;
        }
        let (std, mean) = (std.unwrap(), mean.unwrap());
        assert!(std.ci[0] <= std.value && std.value <= std.ci[1], "{std:?}");
        assert!(
            mean.ci[0] <= mean.value && mean.value <= mean.ci[1],
            "{mean:?}"
        );
    }
    // the truth is the same sea as the finer mesh, whose cells (0.3 m near the camera, metres
    // in the band) smooth the short waves away: within some tens of per cent of it whatever
    // the wrong-side policy (brighter under `bend`, darker under `terminate`); a truth of
    // another sea, sky or scale would be off by far more
    let band = rows.iter().map(|r| r.luminance).sum::<f64>() / rows.len() as f64;
    let high = s.scenarios[0].mean_vs_truth.unwrap();
    assert!(high.value.abs() < 0.3 * band, "{high:?} of {band}");
    assert!(out.join("truth.exr").is_file() && out.join("truth.png").is_file());
    let csv = std::fs::read_to_string(out.join("stats_vs_truth.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + s.rows);
    assert!(csv.starts_with("elevation_deg,mean_high_mapped,std_high_mapped,"));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(json["against"], "truth");
    assert!(
        json["truth_rows"]
            .as_array()
            .is_some_and(|r| r.len() == s.rows)
    );
    assert!(json["truth"]["wrong_side_share"].as_f64().is_some());
    assert!(json["scenarios"][2]["std_vs_truth"]["ci"].is_array());

    // Another policy reuses that truth: nothing of it is rendered again.
    let mut reuse = job.clone();
    reuse.scene.render.wrong_side = vastocean::config::WrongSide::Mirror;
    reuse.truth_from = Some(out.clone());
    reuse.out = again.clone();
    let r = run(&reuse).unwrap();
    let rt = r.truth.as_ref().unwrap();
    assert_eq!(rt.reused_from.as_deref(), Some(out.as_path()));
    assert!(!again.join("truth.exr").exists());
    assert_eq!(r.truth_rows.as_ref().unwrap().len(), s.rows);
    for (a, b) in rows.iter().zip(r.truth_rows.as_ref().unwrap()) {
        assert_eq!(a.luminance, b.luminance);
    }
    assert!(r.scenarios[3].std_vs_truth.is_some());
    // a truth of another sea is refused before anything renders, naming what differs
    let mut other = reuse.clone();
    other.scene.ocean.wind_speed += 1.0;
    other.out = std::env::temp_dir().join("vastocean-compare-truth-refused");
    let e = run(&other).unwrap_err();
    assert_eq!(e.exit_code(), 2, "{e}");
    assert!(e.to_string().contains("[ocean]"), "{e}");
    assert!(!other.out.join("summary.json").exists());
    // and --truth-from without --against truth is refused
    let mut paper = reuse.clone();
    paper.against = Against::PaperHigh;
    assert_eq!(run(&paper).unwrap_err().exit_code(), 2);
}
