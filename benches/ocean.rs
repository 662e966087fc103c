//! Ocean generation and sampling speed. `layer_fields`: one layer's eight fields at one time
//! (eq. 2 evolution, four packed 2-D inverse FFTs, interleaving) for N = 256, 512, 1024; the
//! issue's target is < 250 ms at N = 1024 on 2 cores. `surface_sample`: position + normal of the
//! default 3-layer surface (512/512/256) through rayon, over a camera-near grid read in row
//! order (the tessellator's pattern) and over points scattered across 2 km (hits seen by the
//! integrator); throughput is points per second, target > 20 M/s.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use rayon::prelude::*;
use std::hint::black_box;
use vastocean::ocean::{Interp, Layer, OceanParams, Spectrum, Surface};

fn layer_fields(c: &mut Criterion) {
    let params = OceanParams::default();
    let spectrum = Spectrum::new(&params);
    let mut group = c.benchmark_group("layer_fields");
    group.sample_size(10);
    for n in [256usize, 512, 1024] {
        let size = 400.0;
        let band = (
            std::f64::consts::PI / size,
            std::f64::consts::PI * n as f64 / size,
        );
        let mut layer = Layer::new(&spectrum, size, n, band, 1.0, 1, 0.0).expect("layer");
        let mut t = 0.0;
        group.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| {
                t += 0.1;
                layer.compute_fields(black_box(t));
            })
        });
    }
    group.finish();
}

fn surface_sample(c: &mut Criterion) {
    let surface = Surface::new(&OceanParams::default(), 1).expect("surface");
    const SIDE: usize = 1024;
    let points = (SIDE * SIDE) as u64;
    let mut group = c.benchmark_group("surface_sample");
    group.throughput(Throughput::Elements(points));
    group.sample_size(10);
    // 3 cm spacing: the tessellator's vertex grid around the camera
    let grid = |i: usize| {
        (
            (i % SIDE) as f32 * 0.03 - 15.0,
            (i / SIDE) as f32 * 0.03 - 15.0,
        )
    };
    // a fixed scramble of 2 km: integrator hits arriving in no useful order
    let scattered = |i: usize| {
        let h = (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        (
            (h >> 40) as f32 / 16_777_216.0 * 2000.0 - 1000.0,
            ((h >> 16) & 0xFF_FFFF) as f32 / 16_777_216.0 * 2000.0 - 1000.0,
        )
    };
    for interp in [Interp::Bilinear, Interp::Bicubic] {
        let sampler = surface.sampler_with([12_345.0, -6_789.0], interp);
        for (name, pattern) in [
            ("grid", &grid as &(dyn Fn(usize) -> (f32, f32) + Sync)),
            ("scattered", &scattered),
        ] {
            group.bench_function(format!("{interp:?}/{name}").to_lowercase(), |b| {
                b.iter(|| {
                    (0..SIDE)
                        .into_par_iter()
                        .map(|row| {
                            let mut acc = 0.0f32;
                            for col in 0..SIDE {
                                let (u, v) = pattern(row * SIDE + col);
                                let s = sampler.sample(u, v);
                                let p = s.position(u, v);
                                acc += p[1] + s.normal[0] + p[0] * 1e-9;
                            }
                            acc
                        })
                        .sum::<f32>()
                })
            });
        }
    }
    group.finish();
}

fn surface_build(c: &mut Criterion) {
    let mut group = c.benchmark_group("surface_build");
    group.sample_size(10);
    let params = OceanParams::default();
    group.bench_function("default_3_layers", |b| {
        b.iter(|| Surface::new(black_box(&params), 1).expect("surface"))
    });
    group.finish();
}

criterion_group!(benches, layer_fields, surface_sample, surface_build);
criterion_main!(benches);
