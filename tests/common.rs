//! Scenes, backends and comparisons shared by the integration tests.

use std::sync::Arc;

use vastocean::accel::bvh::Bvh;
use vastocean::accel::{Accel, Ray, brute::BruteForce};
use vastocean::mesh::Mesh;
use vastocean::rng::Rng;

/// Every production backend this build has, over one mesh, the default one (Embree when
/// built in) first: the oracles run on each.
pub fn backends(mesh: Mesh) -> Vec<Box<dyn Accel>> {
    let mesh = Arc::new(mesh);
    #[allow(unused_mut)]
    let mut all: Vec<Box<dyn Accel>> = Vec::new();
    #[cfg(feature = "embree")]
    {
        use vastocean::accel::embree::{BuildOptions, Device, Scene};
        let device = Device::new(2).expect("an Embree device");
        all.push(Box::new(
            Scene::new(&device, mesh.clone(), BuildOptions::default()).expect("a scene"),
        ));
    }
    let pool = vastocean::accel::tracing_pool(2).expect("a pool");
    all.push(Box::new(pool.install(|| Bvh::build(mesh))));
    all
}

/// `n` random triangles with corners in the unit cube, edges up to about `size` long.
pub fn random_mesh(n: usize, size: f32, seed: u64) -> Mesh {
    let mut r = Rng::keyed(&[seed, 0x6d65_7368]);
    let mut positions = Vec::with_capacity(3 * n);
    for _ in 0..n {
        let c = [r.f32(), r.f32(), r.f32()];
        for _ in 0..3 {
            positions.push(std::array::from_fn(|k| c[k] + size * (r.f32() - 0.5)));
        }
    }
    let indices = (0..n as u32)
        .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
        .collect();
    Mesh::new(positions, vec![], vec![], indices).unwrap()
}

/// Rays from random points in a slightly larger cube in uniformly random directions.
pub fn random_rays(n: usize, seed: u64) -> Vec<Ray> {
    let mut r = Rng::keyed(&[seed, 0x7261_7973]);
    (0..n)
        .map(|_| {
            Ray::new(
                [r.range(-0.2, 1.2), r.range(-0.2, 1.2), r.range(-0.2, 1.2)],
                r.unit_vector(),
            )
        })
        .collect()
}

/// How a backend's answer for one ray compares with the brute-force oracle.
#[derive(Debug, PartialEq)]
pub enum Verdict {
    Same,
    /// Different answers, but the ray passes within `tol` (barycentric) of an edge of the
    /// triangle in question, or the two triangles lie at the same distance: a tie that f32
    /// and f64 arithmetic may legitimately break differently.
    Ambiguous,
    Wrong(String),
}

/// Compares `hit` for `ray` with the oracle, allowing `rel_t` relative error in t.
pub fn judge(
    oracle: &BruteForce,
    ray: &Ray,
    hit: Option<vastocean::accel::Hit>,
    rel_t: f64,
) -> Verdict {
    // The nearest hit is one pass over the triangles; only a disagreement needs them all.
    let nearest = oracle.nearest(ray);
    match (hit, nearest) {
        (None, None) => return Verdict::Same,
        (Some(h), Some((t, p, _, _)))
            if h.prim == p && ((h.t as f64 - t).abs() <= rel_t * t.abs().max(1e-3)) =>
        {
            return Verdict::Same;
        }
        _ => {}
    }
    let all = oracle.all_hits(ray);
    // Within 1e-4 (barycentric) of the triangle's boundary, inside or outside: a hit or miss
    // there may legitimately go either way in f32. A line that misses the triangle by more is
    // no excuse for a hit on it.
    let near_edge = |prim: u32| {
        vastocean::accel::brute::line_hit(ray, oracle.mesh().triangle(prim))
            .is_some_and(|(_, u, v)| u.min(v).min(1.0 - u - v).abs() < 1e-4)
    };
    match (hit, all.first()) {
        (None, None) => Verdict::Same,
        (Some(h), Some(&(t, p)))
            if h.prim == p && ((h.t as f64 - t).abs() <= rel_t * t.abs().max(1e-3)) =>
        {
            Verdict::Same
        }
        (Some(h), Some(&(t, p))) => {
            let tie = all
                .iter()
                .any(|&(t2, p2)| p2 == h.prim && (t2 - t).abs() <= rel_t * t.abs().max(1e-3));
            if tie || near_edge(h.prim) || near_edge(p) {
                Verdict::Ambiguous
            } else {
                Verdict::Wrong(format!(
                    "backend prim {} t {} vs oracle prim {p} t {t}",
                    h.prim, h.t
                ))
            }
        }
        (None, Some(&(t, p))) if near_edge(p) => {
            let _ = t;
            Verdict::Ambiguous
        }
        (Some(h), None) if near_edge(h.prim) => Verdict::Ambiguous,
        (a, b) => Verdict::Wrong(format!("backend {a:?} vs oracle {b:?}")),
    }
}

/// Runs the binary; (exit code, stdout, stderr).
pub fn vastocean(args: &[&str]) -> (i32, String, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_vastocean"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Starts the binary with `args` and then `out`, its output discarded (for interrupting it).
pub fn spawn_quiet(args: &[&str], out: &std::path::Path) -> std::process::Child {
    std::process::Command::new(env!("CARGO_BIN_EXE_vastocean"))
        .args(args)
        .arg(out)
        .stderr(std::process::Stdio::null())
        .stdout(std::process::Stdio::null())
        .spawn()
        .unwrap()
}

/// Sends SIGINT (what Ctrl-C sends) to `child`; whether `kill` succeeded.
pub fn interrupt(child: &std::process::Child) -> bool {
    std::process::Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap()
        .success()
}

/// A square pinhole image `width` pixels wide looking straight down from `height_m` through a
/// field of view of `hfov_deg`, at `spp` samples per pixel, over the default sea.
pub fn looking_down(
    height_m: f64,
    hfov_deg: f64,
    width: usize,
    spp: u32,
) -> vastocean::config::SceneConfig {
    let mut cfg = vastocean::config::SceneConfig::default();
    cfg.camera.height_m = height_m;
    cfg.camera.width = width;
    cfg.camera.aspect = 1.0;
    cfg.camera.projection = vastocean::config::Projection::Pinhole {
        hfov_deg,
        yaw_deg: 0.0,
        pitch_deg: -90.0,
        roll_deg: 0.0,
    };
    cfg.render.spp = spp;
    cfg
}

/// A render's mean pixel luminance and its standard error (from the film's per-pixel
/// variances of the mean).
pub fn mean_luminance_se(r: &vastocean::render::pipeline::Rendered) -> (f64, f64) {
    let lum = |c: [f32; 3]| vastocean::color::luminance(c) as f64;
    let n = r.film.image.pixels.len() as f64;
    let mean = r.film.image.pixels.iter().map(|&c| lum(c)).sum::<f64>() / n;
    let se = (r.film.var_y.iter().map(|&v| v as f64).sum::<f64>()).sqrt() / n;
    (mean, se)
}
