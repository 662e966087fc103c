//! What a newcomer meets first, through the binary: the shipped scenes, `--dump-config` and
//! `--config -`, `--version`, completions and man pages, and bad input that names the flag
//! typed (the README's and docs' promises are in `docs.rs`).

use std::path::{Path, PathBuf};

use crate::common::vastocean;

pub(crate) fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("vastocean-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Renders a shipped scene at a tiny size; (stdout, stderr, sidecar).
fn render_scene(scene: &Path, out: &Path) -> (String, String, serde_json::Value) {
    let (code, stdout, stderr) = vastocean(&[
        "render",
        "--config",
        scene.to_str().unwrap(),
        "--width",
        "64",
        "--spp",
        "1",
        "--threads",
        "2",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{}: {stderr}", scene.display());
    let json = std::fs::read_to_string(out.with_extension("json")).unwrap();
    (stdout, stderr, serde_json::from_str(&json).unwrap())
}

#[test]
fn every_shipped_scene_renders_cleanly() {
    let dir = tmp("scenes");
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(repo().join("scenes"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    scenes.sort();
    assert!(scenes.len() >= 8, "{scenes:?}");
    for scene in &scenes {
        let name = scene.file_stem().unwrap().to_str().unwrap();
        let (_, stderr, j) = render_scene(scene, &dir.join(name));
        assert_eq!(j["nan_count"], 0, "{name}");
        assert_eq!(j["escaped_below_horizon"], 0, "{name}");
        assert!(
            !stderr.contains("warning:"),
            "{name} warns as shipped: {stderr}"
        );
        let png = dir.join(format!("{name}.png"));
        assert!(std::fs::metadata(&png).unwrap().len() > 0, "{name}");
    }
    let _ = std::fs::remove_dir_all(dir);
}

/// `--hs` and `--rms` replace the scene's height target whichever key gave it, and cannot be
/// given together.
#[test]
fn a_height_flag_replaces_the_scenes_target() {
    let (code, out, err) = vastocean(&["render", "--hs", "1.2", "--dump-config"]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("hs_m = 1.2") && !out.contains("rms_m"),
        "{out}"
    );
    let dir = tmp("hs");
    let file = dir.join("hs.toml");
    std::fs::write(&file, &out).unwrap();
    let (code, out, err) = vastocean(&[
        "render",
        "--config",
        file.to_str().unwrap(),
        "--rms",
        "0.3",
        "--dump-config",
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.contains("rms_m = 0.3") && !out.contains("hs_m"),
        "{out}"
    );
    let (code, _, err) = vastocean(&["render", "--hs", "1.2", "--rms", "0.3"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--hs") && err.contains("--rms"), "{err}");
    let (code, _, err) = vastocean(&["render", "--hs", "-1", "--dump-config"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--hs (ocean.hs_m) must be"), "{err}");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn dump_config_is_read_back_to_the_same_scene_from_a_file_or_stdin() {
    let dir = tmp("dump");
    let scene = repo().join("scenes/paper-case-87.toml");
    let (code, first, err) = vastocean(&[
        "render",
        "--config",
        scene.to_str().unwrap(),
        "--width",
        "300",
        "--spp",
        "3",
        "--dump-config",
    ]);
    assert_eq!(code, 0, "{err}");
    // Every key is written, the flags applied, the sky map's path absolute.
    assert!(
        first.contains("width = 300") && first.contains("spp = 3"),
        "{first}"
    );
    let sky = repo().join("skies/photo-sunset.exr");
    let absolute_sky =
        std::path::absolute(scene.parent().unwrap().join("../skies/photo-sunset.exr")).unwrap();
    assert!(
        first.contains(&format!("file = {:?}", absolute_sky.to_str().unwrap())),
        "{first}"
    );
    assert!(absolute_sky.is_absolute() && sky.exists());
    let file = dir.join("dumped.toml");
    std::fs::write(&file, &first).unwrap();
    let (code, second, err) = vastocean(&[
        "render",
        "--config",
        file.to_str().unwrap(),
        "--dump-config",
    ]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(first, second);
    // `--config -`: stdin, its relative paths taken from the working directory.
    let run = |stdin: &str| {
        use std::io::Write;
        let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_vastocean"))
            .args(["render", "--config", "-", "--dump-config"])
            .current_dir(repo())
            .stdin(std::process::Stdio::piped())
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        child
            .stdin
            .take()
            .unwrap()
            .write_all(stdin.as_bytes())
            .unwrap();
        let o = child.wait_with_output().unwrap();
        (
            o.status.code(),
            String::from_utf8_lossy(&o.stdout).into_owned(),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )
    };
    let (code, third, err) = run(&first);
    assert_eq!((code, third.as_str()), (Some(0), first.as_str()), "{err}");
    let (code, text, err) = run("[sky]\nfile = \"skies/photo-sunset.exr\"\n");
    assert_eq!(code, Some(0), "{err}");
    assert!(
        text.contains(&format!(
            "file = {:?}",
            repo().join("skies/photo-sunset.exr").to_str().unwrap()
        )),
        "{text}"
    );
    let (code, _, err) = run("wind = \n");
    assert_eq!(code, Some(2));
    assert!(err.contains("<stdin>"), "{err}");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn version_completions_and_man_pages() {
    let (code, version, _) = vastocean(&["--version"]);
    assert_eq!(code, 0);
    assert!(version.starts_with(&format!("vastocean {}", env!("CARGO_PKG_VERSION"))));
    if cfg!(feature = "embree") {
        assert!(
            version.contains("(Embree 3.") || version.contains("(Embree 4."),
            "{version}"
        );
    } else {
        assert!(version.contains("without Embree"), "{version}");
    }
    for shell in ["bash", "zsh", "fish"] {
        let (code, script, err) = vastocean(&["completions", shell]);
        assert_eq!(code, 0, "{err}");
        assert!(
            script.contains("render") && script.contains("dump-config"),
            "{shell}"
        );
    }
    // A reader that stops early (`| head`) is not a failure: the script is larger than a pipe.
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_vastocean"))
        .args(["completions", "bash"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut head = [0u8; 16];
    std::io::Read::read_exact(child.stdout.as_mut().unwrap(), &mut head).unwrap();
    drop(child.stdout.take());
    let o = child.wait_with_output().unwrap();
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let (code, _, err) = vastocean(&["completions", "cmd.exe"]);
    assert_eq!(code, 2, "{err}");
    let dir = tmp("man");
    let (code, out, err) = vastocean(&["man", "--out", dir.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("man pages"), "{out}");
    let page = std::fs::read_to_string(dir.join("vastocean-render.1")).unwrap();
    assert!(
        page.contains(".TH") && page.contains("dump\\-config"),
        "{page}"
    );
    assert!(dir.join("vastocean-sky-generate.1").exists());
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn bad_input_names_the_flag_typed_and_negative_values_parse() {
    let dir = tmp("flags");
    let out = dir.join("o");
    let o = out.to_str().unwrap();
    for (args, flag) in [
        (vec!["--width", "1"], "--width (camera.width)"),
        (
            vec!["--camera-height", "-2"],
            "--camera-height (camera.height_m)",
        ),
        (vec!["--rms", "1e300"], "--rms (ocean.rms_m)"),
        (vec!["--band", "5:9"], "--band (camera.projection.band_deg)"),
        (
            vec!["--wind", "1e-9", "--width", "64"],
            "--wind (ocean.wind_speed)",
        ),
    ] {
        let mut a = vec!["render", "--out", o];
        a.extend(&args);
        let (code, _, err) = vastocean(&a);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(
            err.starts_with(&format!("error: {flag} must")),
            "{args:?}: {err}"
        );
        // Numbers as typed, not 300 digits or nine zeros.
        assert!(err.len() < 400 && !err.contains("000000000"), "{err}");
    }
    let (code, _, err) = vastocean(&["ocean", "--wind", "1e308"]);
    assert_eq!(code, 2);
    assert!(
        err.starts_with("error: --wind (ocean.wind_speed) must be at most 100"),
        "{err}"
    );
    // From a scene file, the error names the key.
    let scene = dir.join("s.toml");
    std::fs::write(&scene, "[camera]\nwidth = 1\n").unwrap();
    let (code, _, err) = vastocean(&["render", "--config", scene.to_str().unwrap(), "--out", o]);
    assert_eq!(code, 2);
    assert!(err.starts_with("error: camera.width must"), "{err}");
    // Negative numbers are values, as --band's are.
    let (code, _, err) = vastocean(&["ocean", "--layers", "-400:512"]);
    assert_eq!(code, 2);
    assert!(
        !err.contains("unexpected argument") && err.contains("-400"),
        "{err}"
    );
    let (code, _, err) = vastocean(&[
        "ocean",
        "--profile",
        "-5,0,5,0,2",
        "--csv",
        dir.join("p.csv").to_str().unwrap(),
        "--layers",
        "40:64",
    ]);
    assert_eq!(code, 0, "{err}");
    let (code, _, err) = vastocean(&["render", "--frames", "-1:0:2:x", "--out", o]);
    assert_eq!(code, 2);
    assert!(err.contains("START:END:STEP"), "{err}");
    let (_, info, _) = vastocean(&["info", "--json"]);
    let info: serde_json::Value = serde_json::from_str(&info).unwrap();
    let backends = info["backends"].as_array().unwrap();
    assert!(backends.iter().all(|b| b != "brute"), "{backends:?}");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn a_study_is_not_planned_over_a_corrupt_sky_map() {
    let dir = tmp("study-skies");
    let skies = dir.join("skies");
    std::fs::create_dir_all(&skies).unwrap();
    std::fs::copy(repo().join("skies/clear-sun10.exr"), skies.join("good.exr")).unwrap();
    std::fs::write(skies.join("broken.exr"), b"not an EXR").unwrap();
    let (code, _, err) = vastocean(&[
        "study",
        "plan",
        "--out",
        dir.join("study").to_str().unwrap(),
        "--cases",
        "2",
        "--skies",
        skies.to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("broken.exr"), "{err}");
    assert!(!dir.join("study/plan.toml").exists());
    let _ = std::fs::remove_dir_all(dir);
}

/// `--exposure` sets the PNG's exposure in stops and leaves the EXR alone; the sidecar says what
/// the PNG used (also what `auto` chose); a value that is neither is refused naming the flag.
#[test]
fn exposure_scales_the_png_only() {
    let dir = tmp("exposure");
    let mean_png = |p: &Path| {
        let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(p).unwrap()));
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        let b = &buf[..info.buffer_size()];
        b.iter().map(|&v| v as f64).sum::<f64>() / b.len() as f64
    };
    let mut means = Vec::new();
    for e in ["-2", "3", "auto"] {
        let out = dir.join(format!("e{e}"));
        let o = out.to_str().unwrap();
        let args = ["render", "--width", "64", "--spp", "1", "--backend", "rust"];
        let (code, json, err) =
            vastocean(&[&args[..], &["--exposure", e, "--out", o, "--json"]].concat());
        assert_eq!(code, 0, "{err}");
        let json: serde_json::Value = serde_json::from_str(&json).unwrap();
        let stops = json["png_exposure_stops"].as_f64().unwrap();
        let exr = vastocean::image_io::read_exr(&out.with_extension("exr")).unwrap();
        if e == "auto" {
            let auto = vastocean::image_io::auto_exposure(&exr).log2() as f64;
            assert!((stops - auto).abs() < 1e-6, "{stops} vs {auto}");
        } else {
            assert_eq!(stops, e.parse::<f64>().unwrap());
        }
        means.push((mean_png(&out.with_extension("png")), exr.pixels.clone()));
    }
    assert!(means[0].0 < means[1].0, "{} vs {}", means[0].0, means[1].0);
    assert_eq!(
        means[0].1, means[1].1,
        "the EXR does not depend on the exposure"
    );
    let (code, _, err) = vastocean(&[
        "render",
        "--exposure",
        "bright",
        "--out",
        dir.join("x").to_str().unwrap(),
    ]);
    assert_eq!(code, 2);
    assert!(err.contains("--exposure") && err.contains("stops"), "{err}");
    let _ = std::fs::remove_dir_all(dir);
}

/// `--exr-compression` (and `render.exr_compression` in a scene file) chooses how the EXR is
/// stored, uncompressed by default; the pixels are the same bits whichever is chosen; a name
/// that is none of them is refused naming the choices.
#[test]
fn exr_compression_stores_the_same_pixels() {
    let dir = tmp("exr-compression");
    let scene = dir.join("zip.toml");
    std::fs::write(&scene, "[render]\nexr_compression = \"zip\"\n").unwrap();
    let mut pixels = Vec::new();
    for (name, args, stored) in [
        (
            "default",
            vec![],
            exr::compression::Compression::Uncompressed,
        ),
        (
            "piz",
            vec!["--exr-compression", "piz"],
            exr::compression::Compression::PIZ,
        ),
        (
            "file",
            vec!["--config", scene.to_str().unwrap()],
            exr::compression::Compression::ZIP16,
        ),
    ] {
        let out = dir.join(name);
        let render = ["render", "--width", "32", "--spp", "2", "--backend", "rust"];
        let o = ["--out", out.to_str().unwrap()];
        let (code, _, err) = vastocean(&[&render[..], &args[..], &o[..]].concat());
        assert_eq!(code, 0, "{err}");
        let exr = out.with_extension("exr");
        let meta = exr::meta::MetaData::read_from_file(&exr, false).unwrap();
        assert_eq!(meta.headers[0].compression, stored, "{name}");
        let mut bits: Vec<u32> = (vastocean::image_io::read_exr(&exr).unwrap().pixels)
            .iter()
            .flatten()
            .map(|v| v.to_bits())
            .collect();
        let variance = vastocean::image_io::read_exr_channel(&exr, "Y.variance").unwrap();
        bits.extend(variance.iter().map(|v| v.to_bits()));
        pixels.push(bits);
    }
    assert!(pixels.windows(2).all(|p| p[0] == p[1]));
    let (code, _, err) = vastocean(&["render", "--exr-compression", "lzw"]);
    assert_eq!(code, 2);
    assert!(
        err.contains("--exr-compression") && err.contains("piz"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn truth_flags_that_would_do_nothing_are_refused() {
    let out = std::env::temp_dir().join("vastocean-truth-flags-refused");
    let o = out.to_str().unwrap();
    for (args, want) in [
        (
            vec!["compare", "--truth-boost", "8", "--out", o],
            "--against truth",
        ),
        (
            vec![
                "compare",
                "--truth-boost",
                "8",
                "--truth-from",
                o,
                "--out",
                o,
            ],
            "keeps its own",
        ),
    ] {
        let (code, _, err) = vastocean(&args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(err.contains(want), "{args:?}: {err}");
    }
    assert!(!out.join("summary.json").exists());
}

#[test]
fn bench_accuracy_takes_a_wrong_side_policy_and_refuses_a_bad_one() {
    let (_, help, _) = vastocean(&["bench", "accuracy", "--help"]);
    assert!(help.contains("--wrong-side"), "{help}");
    let out = tmp("bench-bad-policy");
    let (code, _, err) = vastocean(&[
        "bench",
        "accuracy",
        "--quick",
        "--wrong-side",
        "sideways",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("sideways") && err.contains("terminate"),
        "{err}"
    );
    assert!(!out.join("summary.json").exists());
}
