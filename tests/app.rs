//! The commands' jobs end to end, through the app layer: the files each writes and the keys of
//! its JSON.

use crate::common::vastocean;
use vastocean::app;
use vastocean::config::{LodChoice, LodConfig, NormalMode, Projection, SceneConfig};

fn tmp(name: &str) -> std::path::PathBuf {
    std::env::temp_dir().join(format!("vastocean-app-{name}-{}", std::process::id()))
}

#[test]
fn render_job_writes_exr_png_and_sidecar() {
    let mut cfg = SceneConfig::default();
    cfg.camera.width = 96;
    cfg.render.spp = 2;
    cfg.render.threads = 2;
    let dir = tmp("render");
    let job = app::render::RenderJob {
        scene: cfg,
        out: dir.join("scene"),
        progress: false,
        pass: None,
    };
    app::render::run(&job).unwrap();
    let sidecar: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("scene.json")).unwrap()).unwrap();
    for key in [
        "triangles",
        "seconds_total",
        "seconds_build",
        "seconds_trace",
        "seconds_normal_map",
        "rays",
        "mrays_per_s",
        "nan_count",
        "wrong_side_count",
        "rejected_rays",
        "noise_rms",
        "noise_rms_relative",
        "exr",
        "png",
    ] {
        assert!(sidecar.get(key).is_some(), "sidecar lacks {key}");
    }
    assert_eq!(sidecar["nan_count"], 0);
    assert!(sidecar["triangles"].as_u64().unwrap() > 1000);
    let img = vastocean::image_io::read_exr(&dir.join("scene.exr")).unwrap();
    assert_eq!((img.width, img.height), (96, 48));
    assert!(dir.join("scene.png").metadata().unwrap().len() > 100);
    // The per-pixel variance travels in the EXR, and the sidecar's noise is its RMS.
    let var = vastocean::image_io::read_exr_channel(&dir.join("scene.exr"), "Y.variance").unwrap();
    assert_eq!(var.len(), 96 * 48);
    assert!(var.iter().all(|v| v.is_finite() && *v >= 0.0));
    let rms = (var.iter().map(|&v| v as f64).sum::<f64>() / var.len() as f64).sqrt();
    let noise = sidecar["noise_rms"].as_f64().unwrap();
    assert!(
        noise > 0.0 && (rms / noise - 1.0).abs() < 1e-5,
        "{rms} vs {noise}"
    );
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn bad_input_is_classed_as_input() {
    let mut cfg = SceneConfig::default();
    cfg.camera.height_m = -1.0;
    let job = app::render::RenderJob {
        scene: cfg,
        out: tmp("bad").join("x"),
        progress: false,
        pass: None,
    };
    let e = app::render::run(&job).unwrap_err();
    assert_eq!(e.exit_code(), 2, "{e}");
    assert!(e.to_string().starts_with("camera.height_m"), "{e}");
    assert!(!tmp("bad").exists(), "nothing written for bad input");
}

#[test]
fn every_shipped_scene_loads_and_validates() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut n = 0;
    for e in std::fs::read_dir(&dir).unwrap() {
        let path = e.unwrap().path();
        if path.extension().is_some_and(|x| x == "toml") {
            let s = SceneConfig::load(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            s.validate().unwrap();
            // A scene without a sky map uses the built-in sky; a map it names must ship.
            if let Some(sky) = s.sky.file.as_ref() {
                assert!(
                    sky.is_file(),
                    "{}: {} is missing",
                    path.display(),
                    sky.display()
                );
            }
            n += 1;
        }
    }
    assert!(n >= 5, "the paper's five Table 1 cases at least");
}

#[test]
fn tiny_compare_runs_end_to_end_and_writes_every_file() {
    use app::compare::Scenario;
    let mut scene = SceneConfig::default();
    scene.camera.width = 512;
    scene.camera.projection = Projection::Equirect {
        band_deg: Some((1.0, -6.0)),
    };
    scene.render.spp = 8;
    scene.render.threads = 2;
    // `bend`: under `terminate` the coarse mesh can come within this tiny render's noise of
    // the baseline, and the corrected stds this test reads fall to 0
    scene.render.wrong_side = vastocean::config::WrongSide::Bend;
    let high = LodConfig {
        preset: LodChoice::Custom,
        near_size_m: Some(0.3),
        double_distance_m: Some(18.0),
        ..LodConfig::default()
    };
    let low = LodConfig {
        preset: LodChoice::PaperLow,
        ..LodConfig::default()
    };
    let dir = tmp("compare");
    let job = app::compare::CompareJob {
        scene,
        high,
        low,
        rows_deg: (0.0, -5.0),
        max_boost: 16,
        filtered: true,
        exact: false,
        against: vastocean::app::compare::Against::PaperHigh,
        truth_boost: vastocean::app::compare::DEFAULT_TRUTH_BOOST,
        truth_from: None,
        out: dir.clone(),
        progress: false,
    };
    let s = app::compare::run(&job).unwrap();
    // The pilot found the sun's glitter and boosted some analysed pixels, no other.
    assert_eq!(s.sampling.max_boost, 16);
    assert!(s.sampling.boosted_pixels > 0, "{:?}", s.sampling);
    assert!(s.sampling.boosted_pixels < s.sampling.analysed_pixels / 2);
    assert!(s.sampling.cost_factor > 1.0 && s.sampling.cost_factor <= 2.0);
    // With `filtered`, the low tessellation with filtered normals after the paper's five.
    assert_eq!(job.scenarios().last(), Some(&Scenario::LowFiltered));
    assert_eq!(s.scenarios.len(), 6);
    assert!(s.std_low_filtered_corrected.is_some_and(|v| v.is_finite()));
    for sc in job.scenarios() {
        for ext in ["exr", "png"] {
            let f = dir.join(format!("{}.{ext}", sc.name()));
            assert!(f.is_file(), "{} missing", f.display());
        }
    }
    for f in ["stats.csv", "stats.png", "sheet.png", "summary.json"] {
        assert!(dir.join(f).metadata().unwrap().len() > 50, "{f}");
    }
    // 512 px: 256 rows for 180 degrees, 0.70 degree rows; centres between 0 and -5 degrees: 7
    assert_eq!(s.rows, 7);
    let csv = std::fs::read_to_string(dir.join("stats.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + s.rows);
    assert!(csv.starts_with("elevation_deg,mean_high_unmapped,std_high_unmapped,"));
    assert!(s.std_low_unmapped > 0.0 && s.improvement_ratio.is_finite());
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    for key in [
        "std_high_unmapped_corrected",
        "std_low_mapped_corrected",
        "std_low_unmapped_corrected",
        "improvement_ratio_corrected",
        "improvement_ratio_ci",
        "improvement_significant",
        "improvement_ratio_median_rows",
        "improvement_ratio_trimmed",
        "noise_model_check",
        "estimates",
        "sampling",
        "baseline_noise",
        "baseline_noise_share",
        "commit",
    ] {
        assert!(summary.get(key).is_some(), "summary.json lacks {key}");
    }
    // An unbounded interval (the denominator's band variance can fall to 0 in a replicate)
    // has null, JSON's nothing, for its upper end.
    let ci = &summary["improvement_ratio_ci"];
    let hi = ci[1].as_f64().unwrap_or(f64::INFINITY);
    assert!(ci[0].as_f64().unwrap() <= hi, "{ci}");
    for sc in summary["estimates"]["scenarios"].as_array().unwrap() {
        for key in [
            "trend_std",
            "residual_std",
            "std_corrected",
            "variance_corrected",
            "noisy_rows",
            "std_corrected_trimmed",
            "rows",
        ] {
            assert!(sc.get(key).is_some(), "scenario estimate lacks {key}");
        }
    }
    assert!(
        csv.lines()
            .next()
            .unwrap()
            .contains("std_corrected_lo_low_mapped")
    );
    assert!(s.scenarios.iter().all(|sc| sc.nan_count == 0));
    assert_eq!(
        s.scenarios[0].triangles, s.scenarios[1].triangles,
        "both high scenarios trace one mesh"
    );
    // Over two seas, the filtered scenario is pooled beside the paper's.
    let pooled = app::compare::realizations::run(
        &app::compare::CompareJob {
            out: dir.join("pooled"),
            ..job.clone()
        },
        2,
    )
    .unwrap();
    let filtered = pooled.std_low_filtered_corrected.unwrap();
    assert!(
        filtered.value.is_finite() && filtered.value > 0.0,
        "{filtered:?}"
    );
    assert!(
        pooled
            .realizations
            .iter()
            .all(|r| r.variance_corrected.low_filtered.is_some())
    );
    assert!(pooled.to_string().contains("low filtered"));
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn bench_accuracy_writes_its_files_and_a_configuration_matches_itself() {
    use app::bench::accuracy::{AccuracyJob, Tessellation};
    use vastocean::config::LodChoice;
    let dir = tmp("bench-accuracy");
    let mut scene = AccuracyJob::default_scene();
    scene.render.threads = 2;
    // a policy other than the default, which the summary must name
    scene.render.wrong_side = vastocean::config::WrongSide::Mirror;
    let job = AccuracyJob {
        scene,
        width: 64,
        tessellations: vec![Tessellation::preset(LodChoice::PaperLow)],
        spp: vec![8, 32],
        normals: vec![NormalMode::Mapped, NormalMode::Vertex, NormalMode::Filtered],
        reference: Tessellation::preset(LodChoice::PaperLow),
        reference_spp: 32,
        reference_spp_max: 512,
        reference_max_boost: 4,
        out: dir.clone(),
        progress: false,
    };
    let r = app::bench::accuracy::run(&job).unwrap();
    assert_eq!(
        r.points.len(),
        6,
        "mapped, vertex and filtered, 8 and 32 spp"
    );
    assert!(
        r.points[4..]
            .iter()
            .all(|p| p.normals == NormalMode::Filtered)
    );
    // The mapped points are the reference's configuration with fewer samples: no bias to
    // resolve, and their error, noise included, is their noise (at 32 spp, four samples a
    // batch on a low-discrepancy pattern: a noise taken from the samples' variance, as if they
    // were independent, would overstate it).
    for same in &r.points[..2] {
        assert!(!same.bias_resolved && same.bias_ci[0] == 0.0, "{same:?}");
        assert!(
            same.error_ci[0] <= same.noise && same.noise <= same.error_ci[1],
            "{same:?}"
        );
    }
    // The reported share is the reference's noise over the smallest error in the table.
    let rf = &r.reference;
    let smallest = r
        .points
        .iter()
        .map(|p| p.error)
        .fold(f64::INFINITY, f64::min);
    assert!(
        (rf.noise_share - rf.noise_band / smallest).abs() < 1e-12,
        "{rf:?}"
    );
    assert_eq!(rf.spp_tried.last(), Some(&rf.spp));
    for f in ["frontier.csv", "frontier.png", "summary.json"] {
        assert!(dir.join(f).metadata().unwrap().len() > 50, "{f}");
    }
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    for key in [
        "points",
        "reference",
        "reference_noise_share",
        "monotone_within_intervals",
        "commit",
        "csv",
        "png",
        "front",
    ] {
        assert!(v.get(key).is_some(), "{key}");
    }
    assert_eq!(v["wrong_side"], "mirror");
    assert!(r.to_string().contains("wrong-side policy mirror"));
    for key in [
        "lod",
        "normals",
        "spp",
        "triangles",
        "seconds_total",
        "error",
        "error_ci",
        "bias",
        "bias_ci",
        "pareto",
    ] {
        assert!(v["points"][0].get(key).is_some(), "point lacks {key}");
    }
    assert!(
        v["points"]
            .as_array()
            .unwrap()
            .iter()
            .any(|p| p["pareto"] == true)
    );
    // A bad spp is bad input, and nothing is written.
    let bad = AccuracyJob {
        spp: vec![12],
        out: tmp("bench-accuracy-bad"),
        ..job
    };
    let e = app::bench::accuracy::run(&bad).unwrap_err();
    assert_eq!(e.exit_code(), 2, "{e}");
    assert!(!tmp("bench-accuracy-bad").exists());
    let _ = std::fs::remove_dir_all(dir);
}

#[cfg(feature = "embree")]
#[test]
fn bench_bvh_writes_a_row_per_backend_quality_and_size() {
    let dir = tmp("bench-bvh");
    let job = app::bench::bvh::BvhBenchJob {
        sizes: vec![1e3, 4e3],
        ..app::bench::bvh::BvhBenchJob::quick(dir.clone(), 2)
    };
    let r = app::bench::bvh::run(&job).unwrap();
    // Embree low, medium, high, refit and the Rust BVH, at each size.
    assert_eq!(r.rows.len(), 10);
    assert!(
        r.rows
            .iter()
            .all(|row| row.bytes > 0 && row.seconds > 0.0 && row.triangles > 500)
    );
    assert!(
        r.rows
            .iter()
            .all(|row| row.camera_mrays_per_s > 0.0 && row.random_mrays_per_s > 0.0)
    );
    let csv = std::fs::read_to_string(dir.join("bvh.csv")).unwrap();
    assert_eq!(csv.lines().count(), 11);
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    for key in [
        "backend",
        "quality",
        "triangles",
        "seconds",
        "tris_per_s",
        "bytes",
    ] {
        assert!(v["rows"][0].get(key).is_some(), "row lacks {key}");
    }
    assert!(dir.join("bvh.png").metadata().unwrap().len() > 1000);
    let _ = std::fs::remove_dir_all(dir);
}

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

#[test]
fn ocean_splits_its_slopes_for_a_footprint_as_filtered_normals_do() {
    use vastocean::app::ocean::{OceanJob, run};
    let split = |w: f64| {
        let job = OceanJob {
            params: vastocean::ocean::OceanParams::default(),
            seed: 1,
            png: None,
            profile: None,
            footprint_m: Some(w),
        };
        let report = run(&job).unwrap();
        let fp = report.footprint.clone().unwrap();
        (report.summary.mss_grid, fp)
    };
    // No footprint resolves everything; a kilometre-wide one leaves every layer to the lobe;
    // in between the resolved share falls with the width, and the two always sum to the
    // realization's slopes (the grid's, by Parseval).
    let (grid, none) = split(0.0);
    assert!(none.unresolved_mss.abs() < 1e-12 && none.layers.iter().all(|l| l.weight == 1.0));
    let mut last = none.resolved_mss;
    for w in [0.1, 1.0, 10.0, 1000.0] {
        let (_, fp) = split(w);
        let sum = fp.resolved_mss + fp.unresolved_mss;
        assert!((sum / grid - 1.0).abs() < 1e-3, "{w}: {sum} vs {grid}");
        assert!(
            fp.resolved_mss < last,
            "{w}: {} not below {last}",
            fp.resolved_mss
        );
        last = fp.resolved_mss;
    }
    let (_, far) = split(1000.0);
    assert!(far.resolved_mss < 1e-3 * grid, "{far:?}");
    assert!(
        run(&OceanJob {
            params: vastocean::ocean::OceanParams::default(),
            seed: 1,
            png: None,
            profile: None,
            footprint_m: Some(-1.0),
        })
        .is_err()
    );
}
