//! BVH build time (rtcCommitScene) of regular grid meshes from 10^3 to 10^7 triangles at each
//! Embree build quality. Criterion's throughput is triangles per second. Meshes are built once
//! per size, outside the timing; each iteration builds a fresh scene from the same buffers.

use std::sync::Arc;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use vastocean::accel::embree::{BuildOptions, Device, Quality, Scene};
use vastocean::mesh::Mesh;

fn build(c: &mut Criterion) {
    let device = Device::new(0).expect("Embree device");
    let mut group = c.benchmark_group("embree_build");
    group.sample_size(10);
    for exp in 3..=7 {
        let target = 10f64.powi(exp);
        let side = (target / 2.0).sqrt().round() as u32;
        let mesh = Arc::new(Mesh::grid(side, side, 0.5));
        let tris = mesh.triangle_count() as u64;
        group.throughput(Throughput::Elements(tris));
        for &quality in Quality::ALL {
            group.bench_with_input(
                BenchmarkId::new(format!("{quality:?}").to_lowercase(), tris),
                &mesh,
                |b, mesh| {
                    b.iter_with_large_drop(|| {
                        Scene::new(
                            &device,
                            mesh.clone(),
                            BuildOptions {
                                quality,
                                compact: false,
                                robust: true,
                                grids: false,
                            },
                        )
                        .unwrap()
                    })
                },
            );
        }
    }
    group.finish();
}

criterion_group!(benches, build);
criterion_main!(benches);
