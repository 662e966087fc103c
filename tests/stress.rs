//! The numerical-stability matrix (`vastocean stress`): a subset in the default suite, the
//! quick matrix through the binary and the full one under `make test-full`.

use vastocean::app::stress::{StressJob, run};

fn out(name: &str) -> std::path::PathBuf {
    std::env::temp_dir().join(format!("vastocean-stress-{name}-{}", std::process::id()))
}

/// One cell per kind of check: furnace, periodicity, backend agreement, refusal, an extreme
/// camera; small images so a debug build runs them in seconds.
#[test]
fn a_subset_of_the_matrix_passes_every_invariant() {
    let mut job = StressJob::quick(out("subset"));
    job.select(&[
        "furnace".into(),
        "period-multiple".into(),
        "rust".into(),
        "sea-storm-camera-under".into(),
        "height-10000-pinhole-down".into(),
        "sun--10".into(),
    ])
    .unwrap();
    for c in &mut job.cells {
        c.scene.camera.width = 48;
        c.scene.render.spp = 2;
    }
    let r = run(&job).unwrap();
    // The cells compared with were added: period-origin and base.
    assert_eq!(r.cells, 8, "{r}");
    assert_eq!(r.failed, 0, "{r}");
    let get = |n: &str| r.results.iter().find(|c| c.name == n).unwrap();
    assert_eq!(get("period-multiple").identical, Some(true));
    assert!(get("rust").agreement_z.unwrap() < 4.0);
    assert!(get("sea-storm-camera-under").refused.is_some());
    assert!(get("furnace").max_luminance <= 1.0001 && get("furnace").max_luminance > 0.01);
    let csv = std::fs::read_to_string(&r.csv).unwrap();
    assert_eq!(csv.lines().count(), 9, "{csv}");
    assert!(job.select(&["no-such-cell".into()]).is_err());
    let _ = std::fs::remove_dir_all(out("subset"));
}

/// The checks have teeth: a furnace whose sky is brighter than 1 fails, and so does a
/// "periodic" offset that is not a whole number of periods.
#[test]
fn the_checks_fail_when_they_should() {
    use vastocean::config::AnalyticSky;
    let mut job = StressJob::quick(out("teeth"));
    job.select(&["furnace".into(), "period-multiple".into()])
        .unwrap();
    for c in &mut job.cells {
        c.scene.camera.width = 32;
        c.scene.render.spp = 1;
        match c.name {
            "furnace" => c.scene.sky.analytic = AnalyticSky::Uniform { radiance: [2.0; 3] },
            "period-multiple" => c.scene.camera.position_m = [123.0, 0.0],
            _ => {}
        }
    }
    let r = run(&job).unwrap();
    assert_eq!(r.failed, 2, "{r}");
}

#[test]
#[ignore = "the quick matrix through the binary: seconds in release"]
fn the_quick_matrix_passes_through_the_binary() {
    let o = out("quick");
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_vastocean"))
        .args(["stress", "--quick", "--json", "--out", o.to_str().unwrap()])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "{text}\n{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let j: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(j["failed"], 0);
    assert!(j["cells"].as_u64().unwrap() >= 25);
    let _ = std::fs::remove_dir_all(o);
}

#[test]
#[ignore = "the quick matrix on the exact surface: about five minutes in release (the storm's cells)"]
fn the_quick_matrix_passes_on_the_exact_surface() {
    let mut job = StressJob::quick(out("exact-quick"));
    job.on_exact_surface();
    let r = run(&job).unwrap();
    assert_eq!(r.failed, 0, "{r}");
    let _ = std::fs::remove_dir_all(out("exact-quick"));
}

#[test]
#[ignore = "the full matrix: several minutes in release, paper-high included"]
fn the_full_matrix_passes() {
    let r = run(&StressJob::full(out("full"))).unwrap();
    assert_eq!(r.failed, 0, "{r}");
    let _ = std::fs::remove_dir_all(out("full"));
}

/// `--surface exact`: every cell on the exact surface, the cells it cannot render (vertex
/// normals, paper-high) left out with those that compare with them, the filtered cells kept; a
/// small subset passes here, the whole quick matrix in `make test-full`.
#[test]
fn the_matrix_runs_on_the_exact_surface() {
    use vastocean::config::{LodChoice, NormalMode, SurfaceKind};
    let mut full = StressJob::full(out("exact-full"));
    let before = full.cells.len();
    full.on_exact_surface();
    assert!(full.cells.len() < before);
    for c in &full.cells {
        assert_eq!(c.scene.render.surface, SurfaceKind::Exact, "{}", c.name);
        assert_ne!(c.scene.render.normals, NormalMode::Vertex, "{}", c.name);
        assert_ne!(c.scene.lod.preset, LodChoice::PaperHigh, "{}", c.name);
        assert!(!c.name.contains("paper-high"), "{}", c.name);
    }
    assert!(
        (full.cells.iter()).any(|c| c.scene.render.normals == NormalMode::Filtered),
        "the filtered cells are kept"
    );
    let mut job = StressJob::quick(out("exact"));
    job.on_exact_surface();
    small_subset_passes(job, "exact");
}

/// Four cells (furnace, periodicity, backend agreement, a sun below the horizon) and the two
/// they compare with, at 48 px and 2 spp, pass.
fn small_subset_passes(mut job: StressJob, name: &str) {
    job.select(&[
        "furnace".into(),
        "period-multiple".into(),
        "rust".into(),
        "sun--10".into(),
    ])
    .unwrap();
    for c in &mut job.cells {
        c.scene.camera.width = 48;
        c.scene.render.spp = 2;
    }
    let r = run(&job).unwrap();
    assert_eq!(r.cells, 6, "{r}");
    assert_eq!(r.failed, 0, "{r}");
    let get = |n: &str| r.results.iter().find(|c| c.name == n).unwrap();
    assert_eq!(get("period-multiple").identical, Some(true));
    assert!(get("rust").agreement_z.unwrap() < 4.0);
    assert!(get("furnace").max_luminance <= 1.0001 && get("furnace").max_luminance > 0.01);
    let _ = std::fs::remove_dir_all(out(name));
}

/// `--interp bilinear` (the paper's read; the default is prefiltered): every cell reads the
/// sea's own samples, and a subset passes on the mesh and on the exact surface.
#[test]
fn the_matrix_runs_with_bilinear_reads() {
    use vastocean::ocean::Interp;
    assert_ne!(
        Interp::default(),
        Interp::Bilinear,
        "the default cells cover it already"
    );
    for exact in [false, true] {
        let name = if exact {
            "bilinear-exact"
        } else {
            "bilinear-mesh"
        };
        let mut job = StressJob::quick(out(name));
        job.reading(Interp::Bilinear);
        if exact {
            job.on_exact_surface();
        }
        for c in &job.cells {
            assert_eq!(c.scene.ocean.interp, Interp::Bilinear, "{}", c.name);
        }
        small_subset_passes(job, name);
    }
}

/// Rays leaving exact hits tens of kilometres from a camera 10 km up clear the surface: the
/// cell at its own size (smaller images miss the two paths that met it again when the offset
/// trusted the normal from the f32 nominal position).
#[test]
fn rays_leaving_far_exact_hits_do_not_meet_the_surface_again() {
    let mut job = StressJob::quick(out("exact-far"));
    job.on_exact_surface();
    job.select(&["height-10000".into()]).unwrap();
    let r = run(&job).unwrap();
    assert_eq!(r.failed, 0, "{r}");
    let cell = r.results.iter().find(|c| c.name == "height-10000").unwrap();
    assert_eq!(cell.self_hits, 0, "{r}");
    assert_eq!(cell.nan_samples, 0, "{r}");
    let _ = std::fs::remove_dir_all(out("exact-far"));
}
