//! Sample passes rendered apart and merged (`render --pass K/N`, `merge`): bit-identical to a
//! single render; mixed passes refused; the Slurm array script.

use crate::common::vastocean;
use vastocean::app::passes::{MergeJob, merge};
use vastocean::app::render::{RenderJob, run};
use vastocean::config::SceneConfig;

fn tmp(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("vastocean-passes-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn scene() -> SceneConfig {
    let mut cfg = SceneConfig::default();
    cfg.camera.width = 64;
    cfg.render.spp = 7;
    cfg.render.threads = 2;
    cfg
}

fn job(cfg: &SceneConfig, out: std::path::PathBuf, pass: Option<(usize, usize)>) -> RenderJob {
    RenderJob {
        scene: cfg.clone(),
        out,
        progress: false,
        pass,
    }
}

#[test]
fn merged_passes_are_bit_identical_to_a_single_render() {
    let dir = tmp("identical");
    let cfg = scene();
    let single = run(&job(&cfg, dir.join("single"), None)).unwrap();
    let bytes = |p: &std::path::Path| std::fs::read(p).unwrap();
    for n in [1, 2, 3] {
        // Passes rendered with another thread count, merged in reverse order.
        let mut c = cfg.clone();
        c.render.threads = 1;
        let mut files = Vec::new();
        for k in (1..=n).rev() {
            let r = run(&job(&c, dir.join(format!("n{n}-p{k}")), Some((k, n)))).unwrap();
            files.push(r.pass_file.unwrap());
        }
        let m = merge(&MergeJob {
            passes: files,
            out: dir.join(format!("merged{n}")),
        })
        .unwrap();
        assert_eq!(bytes(&m.exr), bytes(&single.exr), "N = {n}: EXR");
        assert_eq!(bytes(&m.png), bytes(&single.png), "N = {n}: PNG");
        assert_eq!(m.spp, 7);
        assert_eq!(m.rays, single.rays);
        assert_eq!(m.noise_rms, single.noise_rms);
        assert!(m.passes.as_ref().unwrap().missing.is_empty());
    }
    // The merge has teeth: one pass alone is not the whole image, and says what it lacks.
    let m = merge(&MergeJob {
        passes: vec![dir.join("n3-p2.pass")],
        out: dir.join("partial"),
    })
    .unwrap();
    assert_ne!(bytes(&m.exr), bytes(&single.exr));
    assert_eq!(m.spp, 2);
    assert_eq!(m.passes.unwrap().missing, vec![1, 3]);
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn merge_refuses_passes_of_different_renders() {
    let dir = tmp("mixed");
    let cfg = scene();
    let pass = |name: &str, c: &SceneConfig, k, n| {
        run(&job(c, dir.join(name), Some((k, n))))
            .unwrap()
            .pass_file
            .unwrap()
    };
    let a1 = pass("a1", &cfg, 1, 2);
    let mut other_seed = cfg.clone();
    other_seed.render.seed = 99;
    let b2 = pass("b2", &other_seed, 2, 2);
    let c2 = pass("c2", &cfg, 2, 3);
    let s = |p: &std::path::PathBuf| p.to_str().unwrap().to_string();
    let out = dir.join("m");
    for (files, says) in [
        (vec![s(&a1), s(&b2)], "different scenes"),
        (vec![s(&a1), s(&c2)], "not the same render"),
        (vec![s(&a1), s(&a1)], "given twice"),
        (
            vec![s(&a1), "Cargo.toml".into()],
            "not a vastocean pass file",
        ),
    ] {
        let mut args = vec!["merge"];
        args.extend(files.iter().map(String::as_str));
        args.extend(["--out", out.to_str().unwrap()]);
        let (code, _, err) = vastocean(&args);
        assert_eq!(code, 2, "{err}");
        assert!(err.contains(says), "{err}");
    }
    assert!(!dir.join("m.exr").exists());
    // Bad --pass values are bad input.
    for bad in ["0/3", "4/3", "3", "a/b"] {
        let (code, _, err) = vastocean(&["render", "--pass", bad, "--width", "16"]);
        assert_eq!(code, 2, "{bad}: {err}");
    }
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn the_slurm_array_script_renders_one_pass_and_skips_a_finished_one() {
    let dir = tmp("slurm");
    std::fs::create_dir_all(&dir).unwrap();
    let toml = dir.join("scene.toml");
    std::fs::write(&toml, "[camera]\nwidth = 32\n[render]\nspp = 4\n").unwrap();
    let script = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("benches/cluster/render-passes.sbatch");
    let task = |k: &str| {
        std::process::Command::new("bash")
            .arg(&script)
            .arg(&toml)
            .arg(dir.join("parts"))
            .env("SLURM_ARRAY_TASK_ID", k)
            .env("SLURM_ARRAY_TASK_COUNT", "2")
            .env("SLURM_CPUS_PER_TASK", "1")
            .env("VASTOCEAN", env!("CARGO_BIN_EXE_vastocean"))
            .output()
            .unwrap()
    };
    for k in ["1", "2"] {
        let t = task(k);
        assert!(t.status.success(), "{}", String::from_utf8_lossy(&t.stderr));
    }
    let t = task("2");
    assert!(String::from_utf8_lossy(&t.stdout).contains("exists, skipped"));
    let parts = dir.join("parts");
    let (code, out, err) = vastocean(&[
        "merge",
        parts.join("p1.pass").to_str().unwrap(),
        parts.join("p2.pass").to_str().unwrap(),
        "--out",
        dir.join("render").to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(
        out.starts_with("merged 2 of 2 passes: 4 of 4 samples"),
        "{out}"
    );
    let _ = std::fs::remove_dir_all(dir);
}
