use super::*;
use crate::config::AnalyticSky;
use crate::sky::Sky;

/// Mean and standard error of `n` draws of `f`.
fn mean_se(n: usize, mut f: impl FnMut() -> f64) -> (f64, f64) {
    let (mut s, mut s2) = (0.0, 0.0);
    for _ in 0..n {
        let x = f();
        s += x;
        s2 += x * x;
    }
    let m = s / n as f64;
    (m, ((s2 / n as f64 - m * m).max(0.0) / n as f64).sqrt())
}

/// The sun's light a rough hit gathers, split as multiple importance sampling splits it: the
/// sun's `k` samples ([`sample_sun`]) plus the sun the reflected ray finds, weighed with the
/// density [`sample_sun`] hands back for that ray. Their sum must be the sun's light through the
/// lobe (the disc sampled alone, many times) for any k: a side that did not count the samples
/// would miss or double its share. With no sample (k = 0, where a hit's lobe reflects none of
/// the sun) the reflected ray carries 0 and takes the whole sun, as `weigh_sun` weighs it. The lobe is narrow (slopes of std 1e-3), so the reflected
/// ray's density rivals the sun samples' and both shares are large.
#[test]
fn the_sun_samples_and_the_reflected_ray_share_the_sun_for_any_count() {
    let sky = Sky::analytic(AnalyticSky::Clear {
        sun_elevation_deg: 20.0,
        sun_azimuth_deg: 30.0,
        turbidity: 2.5,
    });
    let sun = sky.sun_light().unwrap();
    let s = sun.direction();
    // the view whose mirror direction about the vertical is the sun's centre, a little off it
    let wo = Vec3::new(-s.x, s.y, -s.z + 2e-3).normalize();
    let lobe = Lobe::new(Vec3::Y, [1e-6, 0.0, 1e-6]).unwrap();
    let (wo_l, _) = lobe.local(wo);
    let bsdf = |w: Vec3| {
        let (wl, below) = lobe.local(w);
        if below {
            return (0.0, 0.0);
        }
        (
            lobe.reflection_pdf(wo_l, wl),
            lobe.reflection_cos(wo_l, wl, 1.0),
        )
    };
    let sp = SurfacePoint {
        p: Vec3::new(0.0, 2.0, 0.0),
        ng: Vec3::Y,
        err: Vec3::ZERO,
        prim: 0,
    };
    let lum = |l: Vec3| luminance(l.to_array()) as f64;
    let mut rng = Rng::keyed(&[23]);
    let mut c = Counters::default();
    let n = 200_000;
    // the disc alone
    let (truth, truth_se) = mean_se(n, || {
        let sample = sun.sample(sp.p, rng.f32(), rng.f32());
        if sample.pdf == 0.0 {
            return 0.0;
        }
        bsdf(sample.d).1 as f64 * lum(sun.radiance(&sample)) / sample.pdf as f64
    });
    assert!(truth > 0.0);
    let mut shares = Vec::new();
    for k in [1, 3, 8, 0] {
        let (nee, nee_se) = mean_se(n, || {
            let (light, _) = sample_sun(&sun, sp, k, None, &mut rng, &mut c, bsdf);
            light.map_or(0.0, |(_, l)| lum(l))
        });
        let (by_ray, by_ray_se) = mean_se(n, || {
            let m = lobe.world(lobe.sample_visible(wo_l, rng.f32(), rng.f32()), false);
            let w = reflect(-wo, m);
            let (p, f) = bsdf(w);
            let (p_sun, radiance) = sun.seen(sp.p, w);
            if p == 0.0 || p_sun == 0.0 {
                return 0.0;
            }
            let (_, carried) = sample_sun(&sun, sp, k, Some(p), &mut rng, &mut c, |_| (0.0, 0.0));
            // (`weigh_sun`: a ray that carries no density weighs the sun fully)
            let weight = if carried > 0.0 {
                power_heuristic(carried, p_sun)
            } else {
                1.0
            };
            f as f64 / p as f64 * lum(radiance) * weight as f64
        });
        let se = (nee_se.powi(2) + by_ray_se.powi(2) + truth_se.powi(2)).sqrt();
        assert!(
            (nee + by_ray - truth).abs() < 4.0 * se,
            "k = {k}: sun's samples {nee} + reflected ray {by_ray} = {} against {truth} +- {se}",
            nee + by_ray
        );
        shares.push(by_ray / truth);
    }
    // both shares large at one sample, the reflected ray's shrinking as the samples grow, and
    // the whole of it without them
    assert!(
        shares[0] > 0.1 && shares[0] < 0.9 && shares[2] < shares[0] && shares[3] > 0.9,
        "{shares:?}"
    );
}
