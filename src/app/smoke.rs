//! `vastocean smoke`: Embree on its own. Builds a BVH over a wavy grid and traces random rays
//! down onto it: the quickest check that Debian's Embree works on this machine, and how fast.

use std::fmt;
use std::sync::Arc;
use std::time::Instant;

use rayon::prelude::*;
use serde::Serialize;

use super::AppError;
use crate::accel::embree::{BuildOptions, Device, Quality, Scene};
use crate::accel::{Accel, Ray, tracing_pool};
use crate::mesh::Mesh;
use crate::rng::Rng;

#[derive(Clone, Copy, Debug)]
pub struct SmokeJob {
    /// Grid cells per side (two triangles per cell).
    pub cells: u32,
    pub rays: usize,
    pub quality: Quality,
    /// Threads for Embree and the tracer (0 = all cores).
    pub threads: usize,
}

#[derive(Clone, Debug, Serialize)]
pub struct SmokeReport {
    pub embree_version: String,
    pub triangles: usize,
    pub vertices: usize,
    pub bytes: usize,
    pub quality: Quality,
    pub seconds_mesh: f64,
    pub seconds_build: f64,
    pub build_mtris_per_s: f64,
    pub rays: usize,
    pub hits: usize,
    pub mean_hit_distance_m: f64,
    pub seconds_trace: f64,
    pub mrays_per_s: f64,
}

/// A `cells` x `cells` grid of 1 m cells under a gentle swell, so rays meet sloped triangles.
fn wavy_grid(cells: u32) -> Result<Mesh, AppError> {
    let flat = Mesh::grid(cells, cells, 1.0);
    let positions: Vec<[f32; 3]> = flat
        .positions()
        .iter()
        .map(|p| [p[0], 0.3 * (0.37 * p[0]).sin() * (0.23 * p[2]).cos(), p[2]])
        .collect();
    Mesh::new(
        positions,
        vec![],
        flat.uvs().to_vec(),
        flat.indices().to_vec(),
    )
    .map_err(|e| AppError::Run(e.into()))
}

/// Rays from 5 m up over the grid (and a little beyond it), pointing down within +-27 degrees.
fn rays_down(n: usize, extent: f32) -> Vec<Ray> {
    (0..n)
        .map(|i| {
            let mut r = Rng::keyed(&[42, i as u64]);
            let org = [
                r.range(-0.1, 1.1) * extent,
                5.0,
                r.range(-0.1, 1.1) * extent,
            ];
            let d = [r.range(-0.5, 0.5), -1.0, r.range(-0.5, 0.5)];
            let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            Ray::new(org, [d[0] / n, d[1] / n, d[2] / n])
        })
        .collect()
}

pub fn run(job: &SmokeJob) -> Result<SmokeReport, AppError> {
    if job.cells == 0 || job.cells > 20_000 {
        return Err(AppError::input(format!(
            "--cells must be in 1..=20000 (got {})",
            job.cells
        )));
    }
    let pool = tracing_pool(job.threads)?;
    let t0 = Instant::now();
    let mesh = Arc::new(wavy_grid(job.cells)?);
    let seconds_mesh = t0.elapsed().as_secs_f64();
    let device = Device::new(job.threads)?;
    let options = BuildOptions {
        quality: job.quality,
        ..Default::default()
    };
    let scene = Scene::new(&device, mesh.clone(), options)?;
    let rays = rays_down(job.rays, job.cells as f32);
    let mut hits = vec![None; rays.len()];
    let t1 = Instant::now();
    pool.install(|| {
        rays.par_chunks(4096)
            .zip(hits.par_chunks_mut(4096))
            .for_each(|(r, h)| scene.intersect_many(r, h));
    });
    let seconds_trace = t1.elapsed().as_secs_f64();
    let hit_count = hits.iter().flatten().count();
    let mean_t = hits.iter().flatten().map(|h| h.t as f64).sum::<f64>() / hit_count.max(1) as f64;
    Ok(SmokeReport {
        embree_version: device.version(),
        triangles: mesh.triangle_count(),
        vertices: mesh.vertex_count(),
        bytes: mesh.bytes(),
        quality: job.quality,
        seconds_mesh,
        seconds_build: scene.build_seconds(),
        build_mtris_per_s: mesh.triangle_count() as f64 / scene.build_seconds() / 1e6,
        rays: job.rays,
        hits: hit_count,
        mean_hit_distance_m: mean_t,
        seconds_trace,
        mrays_per_s: job.rays as f64 / seconds_trace / 1e6,
    })
}

impl fmt::Display for SmokeReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "Embree {}: {} triangles built in {:.3} s ({:.1} M triangles/s, {} quality)",
            self.embree_version,
            self.triangles,
            self.seconds_build,
            self.build_mtris_per_s,
            self.quality
        )?;
        write!(
            f,
            "{} rays: {} hits ({:.1}%), mean distance {:.2} m, {:.2} Mrays/s",
            self.rays,
            self.hits,
            100.0 * self.hits as f64 / self.rays.max(1) as f64,
            self.mean_hit_distance_m,
            self.mrays_per_s
        )
    }
}
