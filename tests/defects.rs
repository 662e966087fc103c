//! The defects probes of bad inputs and extreme scenes found, each reproduced as a new user
//! would meet it, through the binary: the exit code, the message, the files left.

use crate::common::vastocean;

fn tmp(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("vastocean-defects-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The files in `dir`, sorted (hidden ones included: temporary files are hidden).
fn files(dir: &std::path::Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

const R: [&str; 6] = ["--width", "128", "--spp", "1", "--threads", "1"];

fn render(out: &std::path::Path, extra: &[&str]) -> (i32, String, String) {
    let o = out.to_str().unwrap();
    let mut args = vec!["render"];
    for pair in R.chunks(2) {
        if !extra.contains(&pair[0]) {
            args.extend_from_slice(pair);
        }
    }
    args.extend_from_slice(&["--out", o]);
    args.extend_from_slice(extra);
    vastocean(&args)
}

#[test]
fn a_failed_run_leaves_the_previous_set_untouched_and_no_temporary_files() {
    let dir = tmp("set");
    let o = dir.join("o");
    assert_eq!(render(&o, &[]).0, 0);
    assert_eq!(files(&dir), ["o.exr", "o.json", "o.png"]);
    let before: Vec<_> = ["o.exr", "o.json", "o.png"]
        .iter()
        .map(|f| std::fs::read(dir.join(f)).unwrap())
        .collect();
    // A directory where one output goes: refused before any work, as bad input.
    let x = dir.join("x");
    std::fs::create_dir(dir.join("x.png")).unwrap();
    let (code, _, err) = render(&x, &[]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("x.png is a directory"), "{err}");
    assert_eq!(files(&dir), ["o.exr", "o.json", "o.png", "x.png"]);
    // A set whose commit fails half way (the PNG's name turns into a directory after the
    // check): the previous set stays whole.
    let staged = vastocean::image_io::stage_json(&dir.join("o.json"), &1).unwrap();
    let bad = vastocean::image_io::stage_json(&dir.join("x.png"), &2).unwrap();
    assert!(vastocean::image_io::commit_all(vec![staged, bad]).is_err());
    let after: Vec<_> = ["o.exr", "o.json", "o.png"]
        .iter()
        .map(|f| std::fs::read(dir.join(f)).unwrap())
        .collect();
    assert_eq!(before, after);
    assert_eq!(files(&dir), ["o.exr", "o.json", "o.png", "x.png"]);
    // Temporary files of a killed run (a process that no longer exists) are swept.
    let stale = dir.join(format!(
        ".o.exr{}4000000000.0",
        vastocean::image_io::TEMP_MARKER
    ));
    std::fs::write(&stale, b"half").unwrap();
    assert_eq!(render(&o, &[]).0, 0);
    assert_eq!(files(&dir), ["o.exr", "o.json", "o.png", "x.png"]);
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn an_interrupt_while_writing_removes_the_temporary_files() {
    let dir = tmp("sigint");
    let o = dir.join("o");
    let args = [
        "render",
        "--width",
        "2048",
        "--spp",
        "1",
        "--threads",
        "1",
        "--out",
    ];
    let mut child = crate::common::spawn_quiet(&args, &o);
    // Wait until the EXR is being written (its temporary file exists), then interrupt.
    let t = std::time::Instant::now();
    let mut seen = false;
    while t.elapsed().as_secs() < 120 {
        if files(&dir)
            .iter()
            .any(|f| f.contains(vastocean::image_io::TEMP_MARKER))
        {
            seen = true;
            break;
        }
        if child.try_wait().unwrap().is_some() {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    let killed = crate::common::interrupt(&child);
    let status = child.wait().unwrap();
    let left = files(&dir);
    if seen && killed && status.code() == Some(130) {
        assert!(left.is_empty(), "{left:?}");
    } else {
        // The run finished before the signal: then the whole set is there.
        assert_eq!(left, ["o.exr", "o.json", "o.png"], "{status:?}");
    }
    assert!(seen, "the EXR's temporary file was never seen");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn compare_refuses_an_output_that_is_a_file_before_any_work() {
    let dir = tmp("compare-out");
    let f = dir.join("afile");
    std::fs::write(&f, b"").unwrap();
    let (code, _, err) = vastocean(&["compare", "--out", f.to_str().unwrap(), "--width", "64"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("not a directory"), "{err}");
    // No rendering happened: nothing was printed about the tessellations.
    assert!(!err.contains("tessellation"), "{err}");
    let _ = std::fs::remove_dir_all(dir);
}

/// Writes a scene file and renders it with the quick flags; (exit code, stdout, stderr).
fn render_toml(dir: &std::path::Path, toml: &str, extra: &[&str]) -> (i32, String, String) {
    let cfg = dir.join("scene.toml");
    std::fs::write(&cfg, toml).unwrap();
    let mut args = vec!["--config", cfg.to_str().unwrap()];
    args.extend_from_slice(extra);
    render(&dir.join("o"), &args)
}

fn sidecar(dir: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("o.json")).unwrap()).unwrap()
}

#[test]
fn a_pinhole_looking_down_sees_no_holes_and_holes_are_counted() {
    let dir = tmp("pinhole");
    for (h, yaw, pitch, hfov) in [
        (100.0, 45.0, -35.0, 90.0),
        (2.0, 45.0, -35.0, 90.0),
        (2.0, 10.0, -60.0, 60.0),
    ] {
        let toml = format!(
            "[camera]\nheight_m = {h}\nprojection = {{ kind = \"pinhole\", hfov_deg = {hfov}, yaw_deg = {yaw}, pitch_deg = {pitch} }}\n"
        );
        let (code, _, err) = render_toml(&dir, &toml, &["--width", "256", "--spp", "2"]);
        assert_eq!(code, 0, "{err}");
        let j = sidecar(&dir);
        assert_eq!(j["escaped_below_horizon"], 0, "{toml}");
        let warnings = j["warnings"].as_array().unwrap();
        assert!(
            !warnings
                .iter()
                .any(|w| w.as_str().unwrap().contains("holes")),
            "{toml}: {warnings:?}"
        );
    }
    // The count has teeth: a tessellation cut 200 m out leaves the sea beyond it a hole.
    let toml = "[lod]\npreset = \"custom\"\nnear_size_m = 0.5\ndouble_distance_m = 10.0\nmax_distance_m = 200.0\nreading = \"nested\"\n";
    let (code, _, err) = render_toml(&dir, toml, &[]);
    assert_eq!(code, 0, "{err}");
    let j = sidecar(&dir);
    assert!(j["escaped_below_horizon"].as_u64().unwrap() > 0, "{j}");
    assert!(
        err.contains("warning: ") && err.contains("holes in the tessellation"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn a_camera_below_a_wave_crest_is_refused_naming_both_heights() {
    let dir = tmp("under");
    let (code, _, err) = render(
        &dir.join("r"),
        &["--wind", "25", "--rms", "3", "--fetch", "1000"],
    );
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("camera.height_m = 2 m") && err.contains("stands at"),
        "{err}"
    );
    // Raised well above the crests, the same sea renders.
    let (code, _, err) = render(
        &dir.join("r"),
        &[
            "--wind",
            "25",
            "--rms",
            "3",
            "--fetch",
            "1000",
            "--camera-height",
            "30",
        ],
    );
    assert_eq!(code, 0, "{err}");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn radiance_inputs_are_finite_non_negative_and_bounded() {
    let dir = tmp("radiance");
    for (toml, field) in [
        (
            "[sky.analytic]\nkind = \"hand-made-clear\"\nsun_radiance = 1e40\n",
            "sun_radiance",
        ),
        (
            "[sky.analytic]\nkind = \"hand-made-clear\"\nsun_radiance = -1.0\n",
            "sun_radiance",
        ),
        (
            "[sky.analytic]\nkind = \"hand-made-clear\"\nsun_radiance = 1e19\n",
            "sun_radiance",
        ),
        ("[sky]\nscale = 1e30\n", "sky.scale"),
        (
            "[sky.analytic]\nkind = \"uniform\"\nradiance = [1.0, nan, 1.0]\n",
            "radiance",
        ),
    ] {
        let (code, _, err) = render_toml(&dir, toml, &[]);
        assert_eq!(code, 2, "{toml}: {err}");
        assert!(err.contains(field) && err.contains("1e18"), "{err}");
    }
    // The bound itself renders, without a NaN.
    let (code, _, err) = render_toml(
        &dir,
        "[sky.analytic]\nkind = \"hand-made-clear\"\nsun_radiance = 1e18\nsun_elevation_deg = 30.0\n",
        &[],
    );
    assert_eq!(code, 0, "{err}");
    assert_eq!(sidecar(&dir)["nan_count"], 0);
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn folding_warns_and_beyond_a_tenth_is_refused() {
    let dir = tmp("fold");
    let (code, out, err) = render_toml(&dir, "[ocean]\nchoppiness = 4.0\n", &[]);
    assert_eq!(code, 0, "{err}");
    let folded = sidecar(&dir)["folded_fraction"].as_f64().unwrap();
    assert!(folded > 0.0 && folded < 0.1, "{folded}");
    // Warnings go to stderr, so that stdout holds the report alone.
    assert!(
        err.contains("warning: ") && err.contains("folds over itself"),
        "{err}"
    );
    assert!(!out.contains("warning"), "{out}");
    let (code, _, err) = render_toml(&dir, "[ocean]\nchoppiness = 1e6\n", &[]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("folds over itself") && err.contains("above 10%"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn threads_and_memory_are_bounded_before_any_work() {
    let dir = tmp("bounds");
    let (code, _, err) = render(&dir.join("o"), &["--threads", "10000"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("at most"), "{err}");
    let (code, _, err) = vastocean(&["info", "--threads", "100000"]);
    assert!(err.contains("at most"), "{err}");
    assert_eq!(code, 2, "{err}");
    // A width the validator accepts but no machine here can hold: refused with the figure.
    let o = dir.join("w");
    let (code, _, err) = vastocean(&[
        "render",
        "--width",
        "65536",
        "--spp",
        "1",
        "--out",
        o.to_str().unwrap(),
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("needs about") && err.contains("GB"), "{err}");
    assert!(files(&dir).is_empty(), "{:?}", files(&dir));
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn bad_input_exits_2_and_one_sun_rule_holds_for_every_sky() {
    let dir = tmp("input");
    let (code, _, err) = vastocean(&["ocean", "--layers=1e30:256", "--rms", "0.2"]);
    assert_eq!(code, 2, "{err}");
    // An output that cannot be written is named, and refused before work.
    let (code, _, err) = vastocean(&["mesh", "--ply", "/proc/vastocean/m.ply"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("/proc/vastocean"), "{err}");
    // The OS error is said once.
    assert_eq!(err.matches("os error").count(), 1, "{err}");
    for el in ["91", "-11"] {
        let (code, _, toml_err) = render_toml(
            &dir,
            &format!("[sky.analytic]\nkind = \"clear\"\nsun_elevation_deg = {el}\n"),
            &[],
        );
        assert_eq!(code, 2, "{toml_err}");
        let x = dir.join("x.exr");
        let (code, _, gen_err) = vastocean(&[
            "sky",
            "generate",
            "--kind",
            "clear",
            &format!("--sun-elevation={el}"),
            "--out",
            x.to_str().unwrap(),
        ]);
        assert_eq!(code, 2, "{gen_err}");
        let rule = "in [-10, 90] degrees";
        assert!(
            toml_err.contains(rule) && gen_err.contains(rule),
            "{toml_err}\n{gen_err}"
        );
    }
    // Twilight is in the rule, for both.
    let (code, _, err) = render_toml(
        &dir,
        "[sky.analytic]\nkind = \"clear\"\nsun_elevation_deg = -10\n",
        &[],
    );
    assert_eq!(code, 0, "{err}");
    for kind in ["clear", "overcast", "partly-cloudy"] {
        let x = dir.join("t.exr");
        let (code, _, err) = vastocean(&[
            "sky",
            "generate",
            "--kind",
            kind,
            "--sun-elevation=-10",
            "--width",
            "64",
            "--out",
            x.to_str().unwrap(),
        ]);
        assert_eq!(code, 0, "{kind}: {err}");
        let (code, _, err) = vastocean(&["sky", "info", x.to_str().unwrap()]);
        assert_eq!(code, 0, "{kind}: {err}");
    }
    // Every key is optional but a variant's `kind`.
    let (code, _, err) = render_toml(
        &dir,
        "[camera.projection]\nkind = \"pinhole\"\n[sky.analytic]\nkind = \"clear\"\n",
        &[],
    );
    assert_eq!(code, 0, "{err}");
    let _ = std::fs::remove_dir_all(dir);
}

/// A sea state past the physical bounds is bad input, named before any work: an RMS height of
/// 1e300 m panicked in the repeat metric, a wind of 1e308 m/s never finished.
#[test]
fn a_sea_state_past_its_physical_bounds_exits_2() {
    for (flag, value, field) in [
        ("--rms", "1e300", "ocean.rms_m"),
        ("--wind", "1e308", "ocean.wind_speed"),
        ("--fetch", "1e9", "ocean.fetch_km"),
        ("--depth", "20000", "ocean.depth_m"),
    ] {
        let (code, _, err) = vastocean(&["ocean", flag, value]);
        assert_eq!(code, 2, "{flag} {value}: {err}");
        assert!(err.contains(field) && err.contains("at most"), "{err}");
        // Numbers stay readable.
        assert!(err.len() < 400, "{err}");
    }
}

/// `--out DIR/` names a folder, not a file prefix: refused before work, no hidden `.exr`; a pass
/// that would hold no samples is refused rather than written empty.
#[test]
fn outputs_that_cannot_mean_what_was_asked_are_refused() {
    let dir = tmp("prefix");
    let slash = format!("{}/", dir.display());
    for args in [
        vec!["render", "--width", "64", "--spp", "1", "--out", &slash],
        vec![
            "render",
            "--width",
            "64",
            "--spp",
            "1",
            "--out",
            dir.to_str().unwrap(),
        ],
        vec![
            "render", "--width", "64", "--spp", "2", "--pass", "1/2", "--out", &slash,
        ],
    ] {
        let (code, _, err) = vastocean(&args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(err.contains("names a folder"), "{err}");
    }
    let pass = dir.join("p");
    let (code, _, err) = vastocean(&[
        "render",
        "--width",
        "64",
        "--spp",
        "2",
        "--pass",
        "3/3",
        "--out",
        pass.to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("holds no samples at 2 spp"), "{err}");
    assert!(files(&dir).is_empty(), "{:?}", files(&dir));
    let _ = std::fs::remove_dir_all(dir);
}

/// Sizes that aborted on allocation (exit 134) or ran for minutes into many GB are bad input,
/// named by their flag, before any work.
#[test]
fn sizes_past_what_the_machine_can_hold_exit_2() {
    let embree: &[&[&str]] = if cfg!(feature = "embree") {
        &[
            &["smoke", "--rays", "99999999999999"],
            &["smoke", "--cells", "100000"],
            &["crosscheck", "--rays", "200000000"],
        ]
    } else {
        &[]
    };
    let general: &[&[&str]] = &[
        &[
            "sky",
            "generate",
            "--kind",
            "clear",
            "--sun-elevation",
            "5",
            "--width",
            "1000000",
            "--out",
            "/tmp/x.exr",
        ],
        &[
            "sky",
            "sheet",
            "skies/clear-sun03.exr",
            "--thumb-width",
            "100000",
            "--out",
            "/tmp/x.png",
        ],
    ];
    for &args in general.iter().chain(embree) {
        let (code, _, err) = vastocean(args);
        assert_eq!(code, 2, "{args:?}: {err}");
        let flag = args
            .iter()
            .rev()
            .find(|a| a.starts_with("--") && **a != "--out")
            .unwrap();
        assert!(
            err.contains(flag) && err.contains("is not in"),
            "{args:?}: {err}"
        );
    }
}
