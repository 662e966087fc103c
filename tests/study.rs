//! `vastocean study` end to end through the binary and GNU parallel: plan, run, resume,
//! summarize, and a case over two ocean realizations.

use crate::app::tmp;
use crate::common::vastocean;

#[test]
fn study_plans_runs_through_gnu_parallel_resumes_and_summarizes() {
    let dir = tmp("study");
    let skies = dir.join("skies-in");
    std::fs::create_dir_all(&skies).unwrap();
    let shipped = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("skies");
    for name in ["clear-sun10.exr", "overcast-sun15.exr"] {
        std::fs::copy(shipped.join(name), skies.join(name)).unwrap();
    }
    let study = dir.join("study");
    let s = |p: &std::path::Path| p.to_str().unwrap().to_owned();
    #[rustfmt::skip]
    let plan = ["study", "plan", "--out", &s(&study), "--cases", "3", "--seed", "5",
        "--width", "256", "--spp", "8", "--high-near-size", "0.45", "--low-near-size", "0.9",
        "--clip-sun", "100", "--skies", &s(&skies), "--wrong-side", "bend"];
    let (code, out, err) = vastocean(&plan);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("planned 3 cases over 2 skies"), "{out}");
    let text = std::fs::read_to_string(study.join("plan.toml")).unwrap();
    assert!(
        text.contains("cases = 3") && text.contains("near_size_m = 0.45"),
        "{text}"
    );
    // The same seed draws the same cases; a folder holds one plan.
    let case1 = std::fs::read_to_string(study.join("cases/1/scene.toml")).unwrap();
    assert!(
        case1.contains("clip_relative = 100") && case1.contains("wrong_side = \"bend\""),
        "{case1}"
    );
    assert_eq!(
        vastocean(&plan).0,
        2,
        "a second plan into one folder is refused"
    );
    let again = dir.join("again");
    let mut plan2 = plan;
    let again_s = s(&again);
    plan2[3] = &again_s;
    assert_eq!(vastocean(&plan2).0, 0);
    assert_eq!(
        std::fs::read_to_string(again.join("cases/1/scene.toml")).unwrap(),
        case1
    );

    // All three cases through GNU parallel, as `make study` and docs/comparison.md run them.
    let status = std::process::Command::new("parallel")
        .args(["-j", "2", "--halt", "now,fail=1"])
        .arg(env!("CARGO_BIN_EXE_vastocean"))
        .args(["study", "run", &s(&study), "--threads", "1", "--case", "{}"])
        .args([":::", "1", "2", "3"])
        .output()
        .expect("GNU parallel is missing: `make setup` installs it (Debian package parallel)");
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    for k in 1..=3 {
        assert!(study.join(format!("cases/{k}/summary.json")).is_file());
    }

    // The Slurm job-array script, run as one array task would run it (sbatch reads the
    // #SBATCH lines; to bash they are comments).
    std::fs::remove_file(study.join("cases/3/summary.json")).unwrap();
    let script =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/cluster/study.sbatch");
    let task = std::process::Command::new("bash")
        .arg(&script)
        .arg(&study)
        .env("SLURM_ARRAY_TASK_ID", "3")
        .env("SLURM_CPUS_PER_TASK", "1")
        .env("VASTOCEAN", env!("CARGO_BIN_EXE_vastocean"))
        .output()
        .unwrap();
    assert!(
        task.status.success(),
        "{}",
        String::from_utf8_lossy(&task.stderr)
    );
    assert!(String::from_utf8_lossy(&task.stdout).starts_with("case 3: improvement ratio"));
    assert!(study.join("cases/3/summary.json").is_file());

    // A finished case is skipped: nothing is rewritten.
    let summary1 = study.join("cases/1/summary.json");
    let before = std::fs::metadata(&summary1).unwrap().modified().unwrap();
    let (code, out, _) = vastocean(&["study", "run", &s(&study), "--case", "1"]);
    assert_eq!(code, 0);
    assert!(out.contains("finished already"), "{out}");
    assert_eq!(
        std::fs::metadata(&summary1).unwrap().modified().unwrap(),
        before
    );

    // Interrupted mid-case: no summary, so the next run redoes it.
    let summary2 = study.join("cases/2/summary.json");
    std::fs::remove_file(&summary2).unwrap();
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_vastocean"))
        .args(["study", "run", &s(&study), "--threads", "1", "--case", "2"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut line = String::new();
    std::io::BufRead::read_line(
        &mut std::io::BufReader::new(child.stderr.as_mut().unwrap()),
        &mut line,
    )
    .unwrap();
    assert!(line.starts_with("case 2: running"), "{line}");
    child.kill().unwrap();
    assert!(!child.wait().unwrap().success());
    assert!(!summary2.exists(), "an interrupted case has no summary");
    let (code, out, err) =
        vastocean(&["study", "run", &s(&study), "--threads", "1", "--case", "2"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.starts_with("case 2: improvement ratio"), "{out}");
    assert!(summary2.is_file());

    // A case that is not in the plan is the user's error.
    assert_eq!(vastocean(&["study", "run", &s(&study), "--case", "4"]).0, 2);

    // Summarize, with one case missing: listed, not fatal.
    std::fs::remove_file(study.join("cases/3/summary.json")).unwrap();
    let (code, out, err) = vastocean(&["study", "summarize", &s(&study), "--json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    for key in [
        "cases",
        "finished",
        "missing",
        "improved",
        "improved_significant",
        "worse_significant",
        "median_ratio",
        "ratio_quartiles",
    ] {
        assert!(v.get(key).is_some(), "summary.json lacks {key}");
    }
    assert_eq!(
        (v["cases"].as_u64(), v["finished"].as_u64()),
        (Some(3), Some(2))
    );
    assert_eq!(v["missing"], serde_json::json!([3]));
    // Every case was run by this build, whose commit the cases and the summary name.
    assert_eq!(v["case_commits"], serde_json::json!([v["commit"]]));
    assert_eq!(
        v["rows"][0]["cost_factor"].as_f64().map(|c| c >= 1.0),
        Some(true)
    );
    let improved = v["improved"].as_u64().unwrap();
    assert!(v["improved_significant"].as_u64().unwrap() <= improved && improved <= 2);
    let on_disk: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(study.join("summary.json")).unwrap())
            .unwrap();
    assert_eq!(on_disk["finished"], 2);
    let csv = std::fs::read_to_string(study.join("cases.csv")).unwrap();
    assert_eq!(csv.lines().count(), 3, "{csv}");
    assert!(csv.starts_with("case,wind_m_s,fetch_km,depth_m,rms_m,rescale,steepness,sky,"));
    // Every drawn sea is within the paper's rescale range and far from breaking.
    for row in csv.lines().skip(1) {
        let col: Vec<&str> = row.split(',').collect();
        let (rescale, steepness): (f64, f64) = (col[5].parse().unwrap(), col[6].parse().unwrap());
        assert!(
            (0.59..=1.96).contains(&rescale) && steepness < 1.0 / 7.0,
            "{row}"
        );
    }
    let per_sky = std::fs::read_to_string(study.join("per_sky.csv")).unwrap();
    assert!(per_sky.lines().count() >= 2, "{per_sky}");
    assert!(study.join("scatter.png").metadata().unwrap().len() > 1000);

    // A case over two ocean realizations: each sea's comparison in its folder, the row pooled,
    // and the one-sea case of the same plan seed read alike otherwise.
    let pooled = dir.join("pooled");
    let mut plan3 = plan.to_vec();
    let pooled_s = s(&pooled);
    plan3[3] = &pooled_s;
    plan3.extend(["--realizations", "2"]);
    plan3[5] = "1";
    assert_eq!(vastocean(&plan3).0, 0);
    let (code, out, err) = vastocean(&["study", "run", &pooled_s, "--threads", "2", "--case", "1"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("over 2 ocean seeds"), "{out}");
    let case = pooled.join("cases/1");
    for seed in [1, 2] {
        assert!(
            case.join(format!("ocean-seed-{seed}/summary.json"))
                .is_file()
        );
    }
    let (code, out, err) = vastocean(&["study", "summarize", &pooled_s, "--json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let row = &v["rows"][0];
    assert_eq!(row["realizations"], 2);
    for key in [
        "std_low_mapped_corrected",
        "improvement_ratio_corrected",
        "improvement_ratio",
        "cost_factor",
    ] {
        assert!(
            row[key].as_f64().is_some_and(f64::is_finite),
            "{key}: {row}"
        );
    }
    let one: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(case.join("ocean-seed-1/summary.json")).unwrap(),
    )
    .unwrap();
    let ratios: Vec<f64> = ["ocean-seed-1", "ocean-seed-2"]
        .iter()
        .map(|d| {
            let v: serde_json::Value = serde_json::from_str(
                &std::fs::read_to_string(case.join(d).join("summary.json")).unwrap(),
            )
            .unwrap();
            v["improvement_ratio_corrected"].as_f64().unwrap()
        })
        .collect();
    // The pool is the geometric mean of the seas' ratios.
    let pooled_ratio = row["improvement_ratio_corrected"].as_f64().unwrap();
    assert!(
        (pooled_ratio - (ratios[0] * ratios[1]).sqrt()).abs() < 1e-9,
        "{ratios:?} {row}"
    );
    assert_eq!(one["commit"], row["commit"]);

    // An emptied summary is not a finished case: missing, not a row of NaN.
    std::fs::write(study.join("cases/1/summary.json"), "{}").unwrap();
    let (code, out, err) = vastocean(&["study", "summarize", &s(&study), "--json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["missing"], serde_json::json!([1, 3]), "{out}");
    let _ = std::fs::remove_dir_all(dir);
}
