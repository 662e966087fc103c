//! `vastocean bench bvh`: BVH build time against triangle count for Embree (low, medium and
//! high quality, a refit of moved vertices, and medium with the blocks of whole cells as grids,
//! `medium-grids`) and the Rust BVH, on ocean meshes from the
//! project's own tessellation (the paper's doubling rule, log-spaced sizes up to paper-high's
//! 22.3 M triangles); the median of repeated builds, triangles per second, the memory of the
//! built structure, and trace speed (camera rays of a panorama and the secondary rays its hits
//! spawn, and `crosscheck`'s incoherent random rays from above) on every mesh. Writes `bvh.csv`,
//! `bvh.png` and `summary.json` into `out`.

use std::fmt;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use glam::Vec3;
use rayon::prelude::*;
use serde::Serialize;

use super::{Progress, near_size_for, near_size_lod};
use crate::accel::bvh::Bvh;
use crate::accel::crosscheck::random_rays_over;
use crate::accel::embree::{BuildOptions, Device, Quality, Scene};
use crate::accel::{Accel, Ray, tracing_pool};
use crate::analysis::charts::{Series, log_log};
use crate::analysis::error::median;
use crate::app::AppError;
use crate::config::{CameraConfig, OceanParams};
use crate::image_io::{stage, write_json};
use crate::mesh::Mesh;
use crate::ocean::Surface;
use crate::render::water::{reflect, refract};
use crate::render::{Camera, Projection};

#[derive(Clone, Debug)]
pub struct BvhBenchJob {
    pub out: PathBuf,
    /// About how many triangles each mesh has (the tessellation's near size is chosen for it).
    pub sizes: Vec<f64>,
    /// Worker threads (0 = all cores).
    pub threads: usize,
    pub progress: bool,
}

impl BvhBenchJob {
    /// 10^3 .. 10^7 triangles and paper-high's 22.3 M, log-spaced.
    pub fn full(out: PathBuf, threads: usize) -> BvhBenchJob {
        BvhBenchJob {
            out,
            sizes: vec![1e3, 1e4, 1e5, 1e6, 1e7, 22_341_600.0],
            threads,
            progress: true,
        }
    }

    /// 10^3 .. 10^6 triangles.
    pub fn quick(out: PathBuf, threads: usize) -> BvhBenchJob {
        BvhBenchJob {
            sizes: vec![1e3, 1e4, 1e5, 1e6],
            ..BvhBenchJob::full(out, threads)
        }
    }
}

/// One backend and quality on one mesh.
#[derive(Clone, Debug, Serialize)]
pub struct BvhRow {
    /// "embree" or "rust".
    pub backend: &'static str,
    /// Embree's build quality ("low", "medium", "high", "refit", or "medium-grids" for the
    /// mesh's blocks as grids); "sah" for the Rust BVH.
    pub quality: String,
    pub triangles: usize,
    /// Median wall-clock seconds of `builds` builds (for refit: of refits of moved vertices).
    pub seconds: f64,
    pub builds: usize,
    pub tris_per_s: f64,
    /// Memory of the built structure, bytes (Embree: what its memory monitor saw the build
    /// allocate; Rust: nodes, leaf-ordered triangles and ids). The mesh is not counted.
    pub bytes: u64,
    pub mesh_bytes: usize,
    /// Trace speed: the camera rays of a 1024 x 512 panorama 2 m up, and the reflected and
    /// refracted rays spawned at their hits.
    pub camera_mrays_per_s: f64,
    pub secondary_mrays_per_s: f64,
    /// Trace speed of 200 000 incoherent rays from above the mesh aimed at random points in
    /// its bounds (`vastocean crosscheck`'s random rays, seed 1).
    pub random_mrays_per_s: f64,
}

/// The three ray sets every backend traces.
struct RaySets {
    camera: Vec<Ray>,
    secondary: Vec<Ray>,
    random: Vec<Ray>,
}

impl RaySets {
    /// Mrays/s of `accel` on (camera, secondary, random).
    fn speeds(&self, accel: &dyn Accel) -> (f64, f64, f64) {
        (
            mrays_per_s(accel, &self.camera),
            mrays_per_s(accel, &self.secondary),
            mrays_per_s(accel, &self.random),
        )
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct BvhBenchReport {
    pub rows: Vec<BvhRow>,
    pub threads: usize,
    pub seconds_total: f64,
    pub csv: PathBuf,
    pub png: PathBuf,
    pub json: PathBuf,
}

fn repeats(triangles: usize) -> usize {
    if triangles < 1_000_000 { 5 } else { 3 }
}

/// The default ocean tessellated for about `target` triangles (camera 2 m up).
fn ocean_mesh(ocean: &Surface, target: f64) -> Result<Mesh, AppError> {
    let camera = CameraConfig::default();
    let params = crate::lod::params_for(&near_size_lod(near_size_for(target)), &camera)?;
    Ok(crate::lod::tessellate(&params, &ocean.sampler([0.0, 0.0]))?.0)
}

/// Camera rays of a 1024 x 512 panorama 2 m up, the secondary rays their hits spawn, and
/// random rays from above.
fn test_rays(accel: &dyn Accel) -> RaySets {
    let camera = Camera::new(Projection::Equirect { band_deg: None }, 1024, 2.0);
    let camera_rays: Vec<Ray> = (0..camera.height)
        .flat_map(|y| (0..camera.width).map(move |x| (x, y)))
        .map(|(x, y)| {
            let d = camera.direction(x as f32 + 0.5, y as f32 + 0.5);
            Ray::new([0.0, 2.0, 0.0], d.to_array())
        })
        .collect();
    let mesh = accel.mesh();
    let secondary = camera_rays
        .par_iter()
        .flat_map_iter(|r| {
            let hit = accel.intersect(r);
            hit.into_iter().flat_map(move |h| {
                let [p0, p1, p2] = mesh.triangle(h.prim).map(Vec3::from);
                let n = (p1 - p0).cross(p2 - p0).normalize_or(Vec3::Y);
                let n = if n.dot(Vec3::from(r.dir)) > 0.0 {
                    -n
                } else {
                    n
                };
                let d = Vec3::from(r.dir);
                let mut out = vec![crate::render::integrator::spawn_ray(
                    mesh,
                    &h,
                    reflect(d, n),
                )];
                if let Some(t) = refract(d, n, 1.0 / 1.333) {
                    out.push(crate::render::integrator::spawn_ray(mesh, &h, t));
                }
                out
            })
        })
        .collect();
    RaySets {
        camera: camera_rays,
        secondary,
        random: random_rays_over(mesh, RANDOM_RAYS, 1),
    }
}

/// How many random rays each backend traces.
const RANDOM_RAYS: usize = 200_000;

/// Mrays/s of tracing `rays` in parallel chunks (best of three, against noise from the
/// machine).
fn mrays_per_s(accel: &dyn Accel, rays: &[Ray]) -> f64 {
    let mut hits = vec![None; rays.len()];
    let best = (0..3)
        .map(|_| {
            let t = Instant::now();
            rays.par_chunks(1024)
                .zip(hits.par_chunks_mut(1024))
                .for_each(|(r, h)| accel.intersect_many(r, h));
            t.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min);
    rays.len() as f64 / best.max(1e-12) / 1e6
}

/// Embree at one quality on one mesh, its cells as triangles or (`grids`) its blocks of whole
/// cells as grids.
fn embree_row(
    device: &Arc<Device>,
    mesh: &Arc<Mesh>,
    quality: Quality,
    grids: bool,
    speed: Option<&RaySets>,
) -> Result<(BvhRow, Scene), AppError> {
    let options = BuildOptions {
        quality,
        grids,
        ..BuildOptions::default()
    };
    let n = mesh.triangle_count();
    let mut times = Vec::new();
    for _ in 0..repeats(n) {
        times.push(Scene::new(device, mesh.clone(), options)?.build_seconds());
    }
    // A refit moves the vertices, so that scene gets a mesh of its own.
    let own = if quality == Quality::Refit {
        Arc::new((**mesh).clone())
    } else {
        mesh.clone()
    };
    let mut scene = Scene::new(device, own, options)?;
    let bytes = scene.bytes();
    if quality == Quality::Refit {
        // What a refit costs: move every vertex and refit, alternating two positions.
        let original = mesh.positions().to_vec();
        let moved: Vec<[f32; 3]> = original
            .iter()
            .map(|p| [p[0], p[1] + 0.05 * (0.37 * p[0]).sin(), p[2]])
            .collect();
        drop(times);
        times = (0..repeats(n))
            .map(|i| scene.refit(if i % 2 == 0 { &moved } else { &original }))
            .collect::<Result<_, _>>()?;
    }
    let seconds = median(times);
    let (camera, secondary, random) = speed.map_or((0.0, 0.0, 0.0), |r| r.speeds(&scene));
    let row = BvhRow {
        backend: "embree",
        quality: if grids {
            format!("{quality}-grids")
        } else {
            quality.to_string()
        },
        triangles: n,
        seconds,
        builds: repeats(n),
        tris_per_s: n as f64 / seconds,
        bytes,
        mesh_bytes: mesh.bytes(),
        camera_mrays_per_s: camera,
        secondary_mrays_per_s: secondary,
        random_mrays_per_s: random,
    };
    Ok((row, scene))
}

/// The Rust BVH on one mesh.
fn rust_row(mesh: &Arc<Mesh>, rays: &RaySets) -> BvhRow {
    let n = mesh.triangle_count();
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..repeats(n) {
        let bvh = Bvh::build(mesh.clone());
        times.push(bvh.build_seconds());
        last = Some(bvh);
    }
    let bvh = last.expect("at least one build");
    let seconds = median(times);
    let (camera, secondary, random) = rays.speeds(&bvh);
    BvhRow {
        backend: "rust",
        quality: "sah".into(),
        triangles: n,
        seconds,
        builds: repeats(n),
        tris_per_s: n as f64 / seconds,
        bytes: Accel::bytes(&bvh),
        mesh_bytes: mesh.bytes(),
        camera_mrays_per_s: camera,
        secondary_mrays_per_s: secondary,
        random_mrays_per_s: random,
    }
}

pub fn run(job: &BvhBenchJob) -> Result<BvhBenchReport, AppError> {
    crate::app::check_output_dir(&job.out)?;
    let t0 = Instant::now();
    let pool = tracing_pool(job.threads)?;
    let threads = pool.current_num_threads();
    let sizes = &job.sizes;
    if sizes.is_empty() || sizes.iter().any(|n| !(1.0..=1e9).contains(n)) {
        return Err(AppError::input(format!(
            "mesh sizes must be between 1 and 1e9 triangles (got {sizes:?})"
        )));
    }
    let progress = Progress::new(job.progress, sizes.len() as u64 * 6, "bench bvh");
    let rows = pool.install(|| -> Result<Vec<BvhRow>, AppError> {
        let ocean = Surface::new(&OceanParams::default(), 1)?;
        let device = Device::new(threads)?;
        let mut rows = Vec::new();
        for &target in sizes {
            let mesh = Arc::new(ocean_mesh(&ocean, target)?);
            let n = mesh.triangle_count();
            // Rays from the medium-quality scene, traced through every backend.
            let (medium, scene) = embree_row(&device, &mesh, Quality::Medium, false, None)?;
            let rays = test_rays(&scene);
            let (camera, secondary, random) = rays.speeds(&scene);
            let medium = BvhRow {
                camera_mrays_per_s: camera,
                secondary_mrays_per_s: secondary,
                random_mrays_per_s: random,
                ..medium
            };
            drop(scene);
            progress.step(format!("{n} triangles: embree medium"));
            for quality in [Quality::Low, Quality::High, Quality::Refit] {
                let (row, _) = embree_row(&device, &mesh, quality, false, Some(&rays))?;
                rows.push(row);
                progress.step(format!("{n} triangles: embree {quality}"));
            }
            let (row, _) = embree_row(&device, &mesh, Quality::Medium, true, Some(&rays))?;
            rows.push(row);
            progress.step(format!("{n} triangles: embree medium, grids"));
            rows.push(medium);
            rows.push(rust_row(&mesh, &rays));
            progress.step(format!("{n} triangles: rust"));
        }
        Ok(rows)
    })?;
    progress.finish();
    rows_sorted_write(job, rows, threads, t0)
}

/// Sorts the rows (backend, quality, size) and writes the three files together.
fn rows_sorted_write(
    job: &BvhBenchJob,
    mut rows: Vec<BvhRow>,
    threads: usize,
    t0: Instant,
) -> Result<BvhBenchReport, AppError> {
    rows.sort_by(|a, b| {
        (a.backend, &a.quality, a.triangles).cmp(&(b.backend, &b.quality, b.triangles))
    });
    let (csv, png, json) = (
        job.out.join("bvh.csv"),
        job.out.join("bvh.png"),
        job.out.join("summary.json"),
    );
    let staged_csv = stage(&csv, |w| {
        use std::io::Write;
        writeln!(
            w,
            "backend,quality,triangles,seconds,builds,tris_per_s,bytes,mesh_bytes,camera_mrays_per_s,secondary_mrays_per_s,random_mrays_per_s"
        )?;
        for r in &rows {
            writeln!(
                w,
                "{},{},{},{:.6},{},{:.0},{},{},{:.3},{:.3},{:.3}",
                r.backend,
                r.quality,
                r.triangles,
                r.seconds,
                r.builds,
                r.tris_per_s,
                r.bytes,
                r.mesh_bytes,
                r.camera_mrays_per_s,
                r.secondary_mrays_per_s,
                r.random_mrays_per_s
            )?;
        }
        Ok(())
    })?;
    let series: Vec<Series> = {
        let mut keys: Vec<(&str, &str)> = rows
            .iter()
            .map(|r| (r.backend, r.quality.as_str()))
            .collect();
        keys.dedup();
        keys.iter()
            .map(|&(b, q)| Series {
                label: format!("{b} {q}"),
                points: rows
                    .iter()
                    .filter(|r| r.backend == b && r.quality == q)
                    .map(|r| (r.triangles as f64, r.seconds))
                    .collect(),
            })
            .collect()
    };
    log_log(
        &png,
        &format!("BVH build time (median; refit: of moved vertices), {threads} threads"),
        "triangles",
        "seconds",
        &series,
    )
    .map_err(|m| AppError::Run(format!("cannot draw {}: {m}", png.display()).into()))?;
    let report = BvhBenchReport {
        rows,
        threads,
        seconds_total: t0.elapsed().as_secs_f64(),
        csv,
        png,
        json: json.clone(),
    };
    staged_csv.commit()?;
    write_json(&json, &report)?;
    Ok(report)
}

impl fmt::Display for BvhBenchReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "BVH build time against triangle count ({} threads; median of repeated builds)",
            self.threads
        )?;
        writeln!(
            f,
            "  backend quality  triangles    seconds   M tris/s      MB   camera Mrays/s   secondary Mrays/s   random Mrays/s"
        )?;
        for r in &self.rows {
            writeln!(
                f,
                "  {:<7} {:<7} {:>10} {:>10.4} {:>10.2} {:>7.1} {:>16.2} {:>19.2} {:>16.2}",
                r.backend,
                r.quality,
                r.triangles,
                r.seconds,
                r.tris_per_s / 1e6,
                r.bytes as f64 / 1e6,
                r.camera_mrays_per_s,
                r.secondary_mrays_per_s,
                r.random_mrays_per_s
            )?;
        }
        write!(
            f,
            "  wrote {} {} {} in {:.0} s",
            self.csv.display(),
            self.png.display(),
            self.json.display(),
            self.seconds_total
        )
    }
}
