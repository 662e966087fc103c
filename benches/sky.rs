//! Sky radiance per escaped ray, in batches as the integrator asks for it: the built-in
//! (Preetham) clear sky, the hand-made clear sky and the shipped Preetham map of the default
//! scene, for rays from the camera (no dome intersection) in the directions a panorama sends.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;
use vastocean::config::AnalyticSky;
use vastocean::sky::Sky;

fn skies(c: &mut Criterion) {
    let n = 1 << 16;
    let dirs: Vec<Vec3> = (0..n)
        .map(|i| {
            // a spiral over the upper hemisphere and a little below the horizon
            let t = i as f32 / n as f32;
            let (el, az) = (-0.1 + 1.6 * t, i as f32 * 2.399_963);
            Vec3::new(el.cos() * az.cos(), el.sin(), el.cos() * az.sin())
        })
        .collect();
    let map = Sky::load(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/skies/clear-sun03.exr"
    )))
    .expect("the shipped sky map");
    let hand_made = AnalyticSky::HandMadeClear {
        sun_elevation_deg: 3.0,
        sun_azimuth_deg: 180.0,
        sun_radiance: 2000.0,
        sky_scale: 1.0,
    };
    let camera = Vec3::new(0.0, map.camera_height_m as f32, 0.0);
    let orgs = vec![camera; n];
    let mut out = vec![Vec3::ZERO; n];
    let mut group = c.benchmark_group("sky");
    group.throughput(Throughput::Elements(n as u64));
    for (name, sky) in [
        ("clear_preetham", Sky::analytic(AnalyticSky::default())),
        ("hand_made_clear", Sky::analytic(hand_made)),
        ("map_clear_sun03", map),
    ] {
        group.bench_function(name, |b| {
            b.iter(|| sky.radiance_many(&orgs, &dirs, &mut out));
        });
    }
    group.finish();
}

criterion_group!(benches, skies);
criterion_main!(benches);
