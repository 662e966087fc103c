//! Animation (`render --frames`): a refitted frame is the frame a from-scratch render of the
//! same ocean time gives, on both backends; the sequence's files and JSON; an interrupted
//! sequence keeps its finished frames.

use crate::common::vastocean;
use vastocean::app::frames::{FrameRange, FramesJob, parse_frames, run};
use vastocean::config::{Backend, SceneConfig};
use vastocean::render::pipeline::{prepare, prepare_for_frames};

fn tmp(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("vastocean-frames-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn scene(backend: Backend) -> SceneConfig {
    let mut cfg = SceneConfig::default();
    cfg.camera.width = 96;
    cfg.render.spp = 8;
    cfg.render.threads = 2;
    cfg.render.backend = backend;
    // No RMS target: a from-scratch surface at time t would be scaled by its own variance at
    // t, the animation keeps the first frame's amplitudes (as a sea does).
    cfg.ocean.rms_m = None;
    cfg
}

fn backends() -> Vec<Backend> {
    if cfg!(feature = "embree") {
        vec![Backend::Embree, Backend::Rust]
    } else {
        vec![Backend::Rust]
    }
}

#[test]
fn a_refitted_frame_equals_a_frame_built_from_scratch() {
    for backend in backends() {
        let cfg = scene(backend);
        let mut animated = prepare_for_frames(&cfg).unwrap();
        let first = animated.render(&cfg, false).unwrap();
        let t = 1.7;
        let update = animated.advance_to(t, cfg.camera.height_m).unwrap();
        assert!(update.seconds_refit > 0.0 && update.seconds_geometry > 0.0);
        let mut at_t = cfg.clone();
        at_t.ocean.time_s = t;
        let fresh = prepare(&at_t).unwrap();
        // The moved mesh is the tessellation of the surface at t, bit for bit.
        assert_eq!(
            animated.accel.mesh().positions(),
            fresh.accel.mesh().positions(),
            "{backend:?}"
        );
        assert_eq!(
            animated.accel.mesh().normals(),
            fresh.accel.mesh().normals()
        );
        assert_eq!(animated.skip_slope, fresh.skip_slope);
        let a = animated.render(&at_t, false).unwrap();
        let b = fresh.render(&at_t, false).unwrap();
        // Same mesh and samples: only the BVHs differ (refitted vs built), so the images agree
        // up to ties between triangles. Within noise: the mean luminance...
        let (ya, yb) = (mean_y(&a.film), mean_y(&b.film));
        let se = a.report.noise_rms.unwrap() / (a.film.image.pixels.len() as f64).sqrt();
        assert!(
            (ya - yb).abs() <= 4.0 * se,
            "{backend:?}: {ya} vs {yb} (se {se})"
        );
        // ...and nearly every pixel is the same to the bit.
        let same = a
            .film
            .image
            .pixels
            .iter()
            .zip(&b.film.image.pixels)
            .filter(|(p, q)| p == q)
            .count();
        assert!(
            same as f64 >= 0.99 * a.film.image.pixels.len() as f64,
            "{backend:?}: {same} of {} pixels identical",
            a.film.image.pixels.len()
        );
        // The test has teeth: the sea did move between the frames.
        assert_ne!(first.film.image.pixels, a.film.image.pixels, "{backend:?}");
        assert!(a.report.escaped_below_horizon == 0 && a.report.nan_count == 0);
    }
}

fn mean_y(film: &vastocean::render::film::Film) -> f64 {
    vastocean::render::pipeline::mean_luminance(&film.image)
}

#[test]
fn a_sequence_writes_numbered_frames_and_one_json() {
    let dir = tmp("sequence");
    let mut cfg = scene(Backend::Rust);
    cfg.camera.width = 48;
    cfg.render.spp = 2;
    let r = run(&FramesJob {
        scene: cfg,
        out: dir.join("seq"),
        progress: false,
        frames: parse_frames("0.5:1.5:0.5").unwrap(),
    })
    .unwrap();
    assert_eq!(r.frames.len(), 3);
    assert_eq!(
        r.frames.iter().map(|f| f.time_s).collect::<Vec<_>>(),
        [0.5, 1.0, 1.5]
    );
    for f in &r.frames {
        assert!(f.exr.exists() && f.png.exists());
        assert!(f.nan_count == 0 && f.escaped_below_horizon == 0);
    }
    assert!(r.frames[2].exr.ends_with("seq.0003.exr"));
    // the first frame was built, the others moved
    assert_eq!(r.frames[0].update.seconds_refit, 0.0);
    assert!(r.frames[1..].iter().all(|f| f.update.seconds_refit > 0.0));
    assert!(r.rebuild_over_update.unwrap() > 0.0);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("seq.json")).unwrap()).unwrap();
    assert_eq!(json["frames"].as_array().unwrap().len(), 3);
    assert_eq!(json["frames_planned"], 3);
    // one exposure for the sequence: what `auto` chose for the first frame
    let first = vastocean::image_io::read_exr(&r.frames[0].exr).unwrap();
    let auto = vastocean::image_io::auto_exposure(&first).log2();
    assert_eq!(r.png_exposure_stops, Some(auto));
    let last = vastocean::image_io::read_exr(&r.frames[2].exr).unwrap();
    assert_ne!(vastocean::image_io::auto_exposure(&last).log2(), auto);
    assert!(r.stale_frames.is_empty());
    // A shorter sequence over the same prefix names the longer one's leftover frame.
    let r = run(&FramesJob {
        scene: cfg_small(),
        out: dir.join("seq"),
        progress: false,
        frames: parse_frames("0:0.2:0.1").unwrap(),
    })
    .unwrap();
    assert!(r.stale_frames.is_empty(), "three frames overwrite three");
    // Times are rounded: 0.2, not 0.30000000000000004-style sums.
    assert_eq!(
        r.frames.iter().map(|f| f.time_s).collect::<Vec<_>>(),
        [0.0, 0.1, 0.2]
    );
    let r = run(&FramesJob {
        scene: cfg_small(),
        out: dir.join("seq"),
        progress: false,
        frames: parse_frames("0:0:1").unwrap(),
    })
    .unwrap();
    let stale: Vec<_> = ["0002.exr", "0002.png", "0003.exr", "0003.png"]
        .iter()
        .map(|f| dir.join(format!("seq.{f}")))
        .collect();
    assert_eq!(r.stale_frames, stale);
    let warnings = vastocean::app::Remarks::warnings(&r);
    assert!(
        warnings
            .iter()
            .any(|w| w.contains("seq.0002.exr") && w.contains("earlier")),
        "{warnings:?}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

fn cfg_small() -> SceneConfig {
    let mut cfg = scene(Backend::Rust);
    cfg.camera.width = 48;
    cfg.render.spp = 2;
    cfg
}

#[test]
fn frame_times_print_as_typed() {
    let t = parse_frames("0:1:0.1").unwrap().times();
    assert_eq!(t.len(), 11);
    assert_eq!(t[3].to_string(), "0.3");
    assert_eq!(t[7].to_string(), "0.7");
    assert_eq!(
        FrameRange {
            start_s: -1.0,
            end_s: 0.0,
            step_s: 0.5
        }
        .times(),
        [-1.0, -0.5, 0.0]
    );
}

#[test]
fn bad_frame_ranges_are_refused_by_name() {
    for bad in [
        "1:0:0.1",
        "0:1:0",
        "0:1:-1",
        "0:1",
        "a:b:c",
        "0:1:nan",
        "0:1e6:0.01",
    ] {
        assert!(parse_frames(bad).is_err(), "{bad}");
    }
    assert_eq!(
        parse_frames("0:1:0.25").unwrap(),
        FrameRange {
            start_s: 0.0,
            end_s: 1.0,
            step_s: 0.25
        }
    );
    assert_eq!(parse_frames("0:1:0.1").unwrap().times().len(), 11);
    let (code, _, err) = vastocean(&["render", "--frames", "0:1:0", "--width", "32"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("START:END:STEP"), "{err}");
    let (code, _, err) = vastocean(&["render", "--frames", "0:1:1", "--pass", "1/2"]);
    assert_eq!(code, 2, "{err}");
}

#[test]
fn an_interrupted_sequence_keeps_its_finished_frames() {
    let dir = tmp("interrupt");
    std::fs::create_dir_all(&dir).unwrap();
    let o = dir.join("s");
    let args = [
        "render",
        "--width",
        "256",
        "--spp",
        "4",
        "--threads",
        "1",
        "--backend",
        "rust",
        "--frames",
        "0:100:1",
        "--out",
    ];
    let mut child = crate::common::spawn_quiet(&args, &o);
    let json = dir.join("s.json");
    let t = std::time::Instant::now();
    while !json.exists() && t.elapsed().as_secs() < 300 {
        assert!(
            child.try_wait().unwrap().is_none(),
            "the sequence ended early"
        );
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    assert!(json.exists(), "no frame finished in 300 s");
    assert!(crate::common::interrupt(&child));
    assert_eq!(child.wait().unwrap().code(), Some(130));
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let frames = report["frames"].as_array().unwrap();
    assert!(!frames.is_empty() && frames.len() < 101);
    for f in frames {
        for key in ["exr", "png"] {
            let p = std::path::PathBuf::from(f[key].as_str().unwrap());
            assert!(p.exists(), "{p:?} listed but missing");
        }
    }
    let temps: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|f| f.contains(vastocean::image_io::TEMP_MARKER))
        .collect();
    assert!(temps.is_empty(), "{temps:?}");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn refitted_backends_agree_with_the_oracle_over_moved_vertices() {
    use crate::common::{Verdict, backends, judge, random_mesh, random_rays};
    use vastocean::accel::brute::BruteForce;
    let mesh = random_mesh(3000, 0.05, 11);
    // every vertex moves by up to 0.1 (twice a triangle's size)
    let moved: Vec<[f32; 3]> = mesh
        .positions()
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let s = (i as f32 * 0.618).fract() - 0.5;
            [p[0] + 0.2 * s, p[1] - 0.1 * s, p[2] + 0.15 * s]
        })
        .collect();
    let normals = vec![[0.0, 1.0, 0.0]; mesh.normals().len()];
    let mut oracle_mesh = mesh.clone();
    oracle_mesh.set_vertices(&moved, &normals).unwrap();
    let oracle = BruteForce::new(oracle_mesh);
    let rays = random_rays(4000, 5);
    // (Embree's medium-quality scene rebuilds on update; its refit-quality path is the one
    // `prepare_for_frames` builds, tested above.)
    for i in 0..backends(mesh.clone()).len() {
        // one backend alone owns its mesh (the others are dropped), so it may move it
        let mut accel = backends(mesh.clone()).swap_remove(i);
        accel.update_vertices(&moved, &normals).unwrap();
        let wrong: Vec<String> = rays
            .iter()
            .filter_map(|r| match judge(&oracle, r, accel.intersect(r), 1e-4) {
                Verdict::Wrong(w) => Some(w),
                _ => None,
            })
            .collect();
        assert!(
            wrong.is_empty(),
            "{}: {:?}",
            accel.name(),
            &wrong[..wrong.len().min(3)]
        );
    }
}
