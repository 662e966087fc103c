//! The paper's two tessellations (section 5; [`Preset`]) for a 2 m camera with the default
//! ocean sampled at every vertex: `paper_high` (22 341 600 triangles) and `paper_low` (25 520).
//! Throughput is triangles per second; the target for `paper_high` is < 3 s and
//! < 1.5 GB on 2 cores.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use vastocean::lod::{Preset, count_triangles, tessellate};
use vastocean::ocean::{OceanParams, Surface};

fn paper(c: &mut Criterion) {
    let ocean = Surface::new(&OceanParams::default(), 1).expect("default ocean");
    let sampler = ocean.sampler([0.0, 0.0]);
    let mut group = c.benchmark_group("lod");
    group.sample_size(10);
    for (name, params) in [
        ("paper_low", Preset::PaperLow.params(2.0)),
        ("paper_high", Preset::PaperHigh.params(2.0)),
    ] {
        let tris = count_triangles(&params) as u64;
        group.throughput(Throughput::Elements(tris));
        group.bench_with_input(BenchmarkId::new(name, tris), &params, |b, params| {
            b.iter_with_large_drop(|| tessellate(params, &sampler).expect("tessellation"))
        });
    }
    group.finish();
}

criterion_group!(benches, paper);
criterion_main!(benches);
