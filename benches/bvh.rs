//! The Rust BVH (binned SAH build; Woop, Benthin & Wald 2013 watertight traversal) against
//! Embree's robust medium-quality build: build time on flat grids of 10^3 to 10^6 triangles
//! (throughput = triangles per second), and closest-hit throughput of 100k random rays
//! (throughput = rays per second) on the same grids and on the paper-low ocean. Both backends
//! trace on the same rayon pool in chunks; the Embree half needs the `embree` feature.

use std::sync::Arc;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use rayon::prelude::*;
use vastocean::accel::bvh::Bvh;
use vastocean::accel::{Accel, Hit, Ray};
use vastocean::lod::{Preset, tessellate};
use vastocean::mesh::Mesh;
use vastocean::ocean::{OceanParams, Surface};
use vastocean::rng::Rng;

const RAYS: usize = 100_000;

fn grids() -> Vec<Arc<Mesh>> {
    (3..=6)
        .map(|exp| {
            let side = (10f64.powi(exp) / 2.0).sqrt().round() as u32;
            Arc::new(Mesh::grid(side, side, 0.5))
        })
        .collect()
}

/// Rays from above the mesh's bounds aimed at random points inside them.
fn rays_over(mesh: &Mesh, n: usize) -> Vec<Ray> {
    let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    for p in mesh.positions() {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let h = hi[1] - lo[1] + 1.0;
    let mut r = Rng::keyed(&[7]);
    (0..n)
        .map(|_| {
            let org = [
                r.range(lo[0], hi[0]),
                hi[1] + h * (1.0 + r.f32()),
                r.range(lo[2], hi[2]),
            ];
            let to = [
                r.range(lo[0], hi[0]),
                r.range(lo[1], hi[1]),
                r.range(lo[2], hi[2]),
            ];
            let d: [f32; 3] = std::array::from_fn(|k| to[k] - org[k]);
            let len = d.iter().map(|c| c * c).sum::<f32>().sqrt();
            Ray::new(org, d.map(|c| c / len))
        })
        .collect()
}

fn trace(accel: &dyn Accel, rays: &[Ray], hits: &mut [Option<Hit>]) {
    rays.par_chunks(1024)
        .zip(hits.par_chunks_mut(1024))
        .for_each(|(r, h)| accel.intersect_many(r, h));
}

fn build(c: &mut Criterion) {
    #[cfg(feature = "embree")]
    let device = vastocean::accel::embree::Device::new(0).expect("Embree device");
    let mut group = c.benchmark_group("bvh_build");
    group.sample_size(10);
    for mesh in grids() {
        let tris = mesh.triangle_count() as u64;
        group.throughput(Throughput::Elements(tris));
        group.bench_with_input(BenchmarkId::new("rust", tris), &mesh, |b, mesh| {
            b.iter_with_large_drop(|| Bvh::build(mesh.clone()))
        });
        #[cfg(feature = "embree")]
        group.bench_with_input(BenchmarkId::new("embree", tris), &mesh, |b, mesh| {
            use vastocean::accel::embree::{BuildOptions, Scene};
            b.iter_with_large_drop(|| {
                Scene::new(&device, mesh.clone(), BuildOptions::default()).unwrap()
            })
        });
    }
    group.finish();
}

fn throughput(c: &mut Criterion) {
    #[cfg(feature = "embree")]
    let device = vastocean::accel::embree::Device::new(0).expect("Embree device");
    let surface = Surface::new(&OceanParams::default(), 1).expect("default ocean");
    let (ocean, _) = tessellate(&Preset::PaperLow.params(2.0), &surface.sampler([0.0, 0.0]))
        .expect("paper-low tessellation");
    let mut scenes: Vec<(String, Arc<Mesh>)> = grids()
        .into_iter()
        .map(|m| (format!("grid_{}", m.triangle_count()), m))
        .collect();
    scenes.push(("paper_low".into(), Arc::new(ocean)));
    let mut group = c.benchmark_group("bvh_trace");
    group.sample_size(10);
    group.throughput(Throughput::Elements(RAYS as u64));
    for (name, mesh) in scenes {
        let rays = rays_over(&mesh, RAYS);
        let mut hits = vec![None; RAYS];
        let bvh = Bvh::build(mesh.clone());
        group.bench_function(BenchmarkId::new("rust", &name), |b| {
            b.iter(|| trace(&bvh, &rays, &mut hits))
        });
        #[cfg(feature = "embree")]
        {
            use vastocean::accel::embree::{BuildOptions, Scene};
            let scene = Scene::new(&device, mesh.clone(), BuildOptions::default()).unwrap();
            group.bench_function(BenchmarkId::new("embree", &name), |b| {
                b.iter(|| trace(&scene, &rays, &mut hits))
            });
        }
    }
    group.finish();
}

criterion_group!(benches, build, throughput);
criterion_main!(benches);
