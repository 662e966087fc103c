//! What a newcomer meets first, through the binary: the README's command table against
//! `--help`, the shipped scenes, `--dump-config` and `--config -`, `--version`, completions and
//! man pages, and bad input that names the flag typed.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use crate::common::vastocean;

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("vastocean-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The names under "Commands:" in a `--help` text (clap's own `help` left out).
fn help_commands(help: &str) -> Vec<String> {
    help.lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next())
        .filter(|c| *c != "help")
        .map(str::to_string)
        .collect()
}

/// Every command path the binary has: `render`, `sky generate`, ...
fn binary_commands() -> BTreeSet<String> {
    let (_, top, _) = vastocean(&["--help"]);
    let mut all = BTreeSet::new();
    for c in help_commands(&top) {
        let (_, sub, _) = vastocean(&[c.as_str(), "--help"]);
        let subs = help_commands(&sub);
        if subs.is_empty() {
            all.insert(c);
        } else {
            all.extend(subs.into_iter().map(|s| format!("{c} {s}")));
        }
    }
    all
}

/// The README's command table: for each `vastocean ...` span of its first column, the command
/// paths it names (`sky generate\|import` names two) and the flags it shows.
fn readme_commands() -> Vec<(Vec<String>, Vec<String>)> {
    let text = std::fs::read_to_string(repo().join("README.md")).unwrap();
    let table = text
        .split("\n## Commands\n")
        .nth(1)
        .expect("README has a Commands section");
    let mut out = Vec::new();
    for row in table.lines().filter(|l| l.starts_with("| `vastocean ")) {
        let first = row.split(" | ").next().unwrap();
        for span in first.split('`').skip(1).step_by(2) {
            let span = span.replace("\\|", "|");
            let mut words = span.split_whitespace().skip(1);
            let Some(cmd) = words.next() else { continue };
            let mut paths = vec![cmd.to_string()];
            let rest: Vec<&str> = words.collect();
            if let Some(sub) = rest
                .first()
                .filter(|w| w.chars().all(|c| c.is_ascii_lowercase() || c == '|'))
            {
                paths = sub.split('|').map(|s| format!("{cmd} {s}")).collect();
            }
            let flags = rest
                .iter()
                .flat_map(|w| w.split(['[', ']', '|']))
                .filter(|w| w.starts_with("--"))
                .map(str::to_string)
                .collect();
            out.push((paths, flags));
        }
    }
    out
}

#[test]
fn the_readme_command_table_matches_the_binary() {
    let binary = binary_commands();
    let table = readme_commands();
    let named: BTreeSet<String> = table.iter().flat_map(|(p, _)| p.clone()).collect();
    let least = if cfg!(feature = "embree") { 20 } else { 17 };
    assert!(binary.len() >= least, "{binary:?}");
    assert_eq!(
        binary.difference(&named).collect::<Vec<_>>(),
        Vec::<&String>::new(),
        "commands missing from the README's table"
    );
    // Commands that need Embree are absent from a build without it.
    let embree_only = ["crosscheck", "smoke", "bench bvh"];
    assert_eq!(
        named
            .difference(&binary)
            .filter(|c| cfg!(feature = "embree") || !embree_only.contains(&c.as_str()))
            .collect::<Vec<_>>(),
        Vec::<&String>::new(),
        "the README's table names commands the binary lacks"
    );
    for (paths, flags) in &table {
        for path in paths.iter().filter(|p| binary.contains(*p)) {
            let mut args: Vec<&str> = path.split(' ').collect();
            args.push("--help");
            let (_, help, _) = vastocean(&args);
            for flag in flags {
                assert!(
                    help.contains(&format!("{flag} ")) || help.contains(&format!("{flag}\n")),
                    "README shows `vastocean {path} {flag}`, which its --help lacks"
                );
            }
        }
    }
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

/// The README and docs/ pages: (path, text).
fn pages() -> Vec<(PathBuf, String)> {
    let mut files = vec![repo().join("README.md")];
    for e in std::fs::read_dir(repo().join("docs")).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "md") {
            files.push(p);
        }
    }
    files
        .into_iter()
        .map(|p| {
            let t = std::fs::read_to_string(&p).unwrap();
            (p, t)
        })
        .collect()
}

#[test]
fn every_relative_link_in_the_readme_and_docs_resolves() {
    let mut checked = 0;
    for (page, text) in pages() {
        for link in text.split("](").skip(1) {
            let target = link.split(')').next().unwrap();
            let file = target.split('#').next().unwrap();
            if file.is_empty() || file.contains("://") {
                continue;
            }
            let path = page.parent().unwrap().join(file);
            assert!(
                path.exists(),
                "{}: link to {target} is broken",
                page.display()
            );
            checked += 1;
        }
    }
    assert!(checked > 50, "{checked}");
}

#[test]
fn the_docs_hold_no_issue_numbers_or_commit_ids() {
    for (page, text) in pages() {
        for (n, line) in text.lines().enumerate() {
            let lower = line.to_lowercase();
            for word in lower.split(|c: char| !c.is_ascii_alphanumeric()) {
                let hex = word.len() >= 7
                    && word.chars().all(|c| c.is_ascii_hexdigit())
                    && word.chars().any(|c| c.is_ascii_digit())
                    && word.chars().any(|c| c.is_ascii_alphabetic());
                assert!(
                    !hex,
                    "{}:{}: `{word}` reads as a commit id",
                    page.display(),
                    n + 1
                );
            }
            let issue = lower
                .match_indices("issue ")
                .any(|(i, _)| lower[i + 6..].starts_with(|c: char| c.is_ascii_digit()));
            assert!(
                !issue,
                "{}:{}: an issue number: {line}",
                page.display(),
                n + 1
            );
            assert!(
                !lower.contains("this session"),
                "{}:{}: {line}",
                page.display(),
                n + 1
            );
        }
    }
}

#[test]
fn every_flag_of_every_command_has_help_text() {
    for path in binary_commands() {
        let mut args: Vec<&str> = path.split(' ').collect();
        args.push("--help");
        let (code, help, _) = vastocean(&args);
        assert_eq!(code, 0, "{path}");
        let lines: Vec<&str> = help.lines().collect();
        for (i, line) in lines.iter().enumerate() {
            let flag = line.trim_start();
            if !(line.starts_with("  ") && flag.starts_with('-')) {
                continue;
            }
            // The text follows on the same line after a gap, or (when some flag of the command
            // has a long text) on the lines below, indented further.
            let same_line = flag
                .split_once("  ")
                .is_some_and(|(_, t)| !t.trim().is_empty());
            let next = lines.get(i + 1).copied().unwrap_or("");
            let below = next.starts_with("          ") && !next.trim().is_empty();
            assert!(
                same_line || below,
                "vastocean {path}: `{flag}` has no help text"
            );
        }
    }
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
