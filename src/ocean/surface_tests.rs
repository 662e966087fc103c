//! Tests of the summed surface (`surface.rs`): flat sea, normals against sampled tangents, the
//! sampler against the direct Fourier sum, far origins, folding, and time. Its statistics
//! (RMS targets, variance, mean square slope) are tested in `surface_stats_tests.rs`.

use super::*;
use crate::ocean::LayerSpec;

pub(super) fn small(seed: u64) -> Surface {
    let p = OceanParams {
        layers: vec![
            LayerSpec {
                size_m: 200.0,
                n: 128,
            },
            LayerSpec {
                size_m: 23.7,
                n: 128,
            },
            LayerSpec {
                size_m: 2.93,
                n: 64,
            },
        ],
        // the sea's own samples in the texels, which these tests compare with the direct sum
        // and Parseval (the prefiltered default scales them)
        interp: Interp::Bilinear,
        ..OceanParams::default()
    };
    Surface::new(&p, seed).unwrap()
}

/// [`Sampler::normals`] and [`Sampler::samples`] read eight points at a time: each is what one
/// point's read gives, bit for bit.
#[test]
fn normals_and_samples_in_lanes_are_those_one_at_a_time() {
    let s = small(5);
    let mut points = Vec::new();
    // scattered points, either sign, near and far
    for i in 0..45u64 {
        let h = crate::rng::splitmix64(i);
        let (a, b) = ((h & 0xFFFF) as f32 / 65536.0, (h >> 48) as f32 / 65536.0);
        let scale = [3.0, 400.0, 60_000.0][i as usize % 3];
        points.push([(a - 0.5) * scale, (b - 0.5) * scale]);
    }
    // beyond the lanes' range in x alone, in z alone (1e15 m: past 2^51 texels, where the
    // lanes' rounding would go wrong), next to points within it; not a number (the floor's
    // edge cases are `split_lanes_is_split` in the layer's tests)
    let far_x = [[1.0e15, 2.0], [-3.0, 4.0], [7.5, 0.25]];
    let far_z = [[-3.0, 4.0], [5.0, -1.0e15]];
    let nan = [[0.5, 1.0], [f32::NAN, 1.0]];
    for interp in [
        Interp::Bilinear,
        Interp::Bicubic,
        Interp::VariancePreserving,
    ] {
        let sampler = s.sampler_with([1234.5, -987.25], interp);
        // 5 x 8 + 5 and 8 + 5: partial chunks of eight; 3: a chunk of four
        let cases = [&points[..], &points[..13], &points[..8], &points[..3], &[]];
        for points in cases.into_iter().chain([&far_x[..], &far_z[..], &nan[..]]) {
            let mut lanes = vec![[9.0f32; 3]; points.len()];
            sampler.normals(points, &mut lanes);
            let mut samples = vec![Sample::FLAT; points.len()];
            sampler.samples(points, &mut samples);
            for ((p, n), s) in points.iter().zip(&lanes).zip(&samples) {
                let one = sampler.normal(p[0], p[1]);
                assert_eq!(
                    n.map(f32::to_bits),
                    one.map(f32::to_bits),
                    "{interp:?} at {p:?}"
                );
                let one = sampler.sample(p[0], p[1]);
                let bits = |s: &Sample| {
                    let [a, b] = s.disp.map(f32::to_bits);
                    let [c, d, e] = s.normal.map(f32::to_bits);
                    [s.height.to_bits(), a, b, c, d, e, s.jacobian.to_bits()]
                };
                assert_eq!(bits(s), bits(&one), "{interp:?} sample at {p:?}");
            }
        }
    }
}

#[test]
fn flat_sea_normal_is_up() {
    let s = Surface::flat();
    let sampler = s.sampler([1.0e5, -3.0e4]);
    for &(u, v) in &[(0.0, 0.0), (12.5, -3.0), (-4000.0, 2500.0)] {
        let p = sampler.sample(u, v);
        assert_eq!(p, Sample::FLAT);
        assert_eq!(p.position(u, v), [u, 0.0, v]);
    }
    // a real sea with all amplitudes scaled to zero is flat too
    let mut calm = small(1);
    calm.layers.iter_mut().for_each(|l| l.scale(0.0));
    assert_eq!(calm.sampler([3.0, 4.0]).sample(1.5, 2.5), Sample::FLAT);
    assert_eq!(s.summary().realization_rms_m, 0.0);
}

#[test]
fn normal_matches_cross_product_of_sampled_tangents() {
    let s = small(2);
    let sampler = s.sampler_with([0.0, 0.0], Interp::Bicubic);
    let e = 2e-3f32;
    let mut worst = 0.0f32;
    let mut up = 0;
    for i in 0..200 {
        let (u, v) = (i as f32 * 0.731, i as f32 * 0.377 - 30.0);
        let n = sampler.sample(u, v).normal;
        let px = |du: f32, dv: f32| sampler.sample(u + du, v + dv).position(u + du, v + dv);
        let (a, b, c, d) = (px(e, 0.0), px(-e, 0.0), px(0.0, e), px(0.0, -e));
        let tx = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
        let tz = [c[0] - d[0], c[1] - d[1], c[2] - d[2]];
        let m = [
            tz[1] * tx[2] - tz[2] * tx[1],
            tz[2] * tx[0] - tz[0] * tx[2],
            tz[0] * tx[1] - tz[1] * tx[0],
        ];
        let len = (m[0] * m[0] + m[1] * m[1] + m[2] * m[2]).sqrt();
        let dot = (n[0] * m[0] + n[1] * m[1] + n[2] * m[2]) / len;
        worst = worst.max(1.0 - dot);
        up += usize::from(n[1] > 0.0);
        assert!(((n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) - 1.0).abs() < 1e-5);
    }
    assert!(worst < 0.02, "1 - cos(angle) up to {worst}");
    assert_eq!(up, 200);
}

#[test]
fn sampler_matches_direct_sum_of_layers() {
    // The exact surface is the sum of each layer's Fourier series at the world point. The
    // sampler must agree up to interpolation error (largest for gradients, whose top octave
    // in the finest layer has 2-4 texels per wavelength); a wrong wrap, origin, band or sign
    // would be an O(1) error.
    let s = small(3);
    let origin = [12_345.6, -7_890.1];
    let mut err = [[0.0f64; FIELD_COUNT]; 2];
    let mut norm = [0.0f64; FIELD_COUNT];
    for i in 0..150 {
        let (u, v) = (i as f32 * 0.613 - 40.0, i as f32 * 0.219 + 3.0);
        let mut exact = [0.0f64; FIELD_COUNT];
        for l in s.layers() {
            let d = l.eval_direct(origin[0] + u as f64, origin[1] + v as f64);
            for j in 0..FIELD_COUNT {
                exact[j] += d[j];
            }
        }
        for (m, interp) in [Interp::Bilinear, Interp::Bicubic].into_iter().enumerate() {
            let f = s.sampler_with(origin, interp).fields(u, v);
            for j in 0..FIELD_COUNT {
                err[m][j] += (f[j] as f64 - exact[j]).powi(2);
            }
        }
        for j in 0..FIELD_COUNT {
            norm[j] += exact[j] * exact[j];
        }
    }
    let rel = |m: usize, j: usize| (err[m][j] / norm[j]).sqrt();
    for j in 0..FIELD_COUNT {
        println!(
            "field {j}: rms error / rms: bilinear {:.3e} bicubic {:.3e}",
            rel(0, j),
            rel(1, j)
        );
        assert!(
            rel(1, j) < 0.7 * rel(0, j),
            "field {j}: bicubic must beat bilinear"
        );
        // measured (seed 3): h, Dx, Dz 1.7e-2..3.4e-2 bilinear, 3e-3..8e-3 bicubic;
        // gradients 0.14..0.19 bilinear, 0.07..0.11 bicubic
        let (bilinear, bicubic) = if j < field::DH_DX {
            (0.05, 0.012)
        } else {
            (0.25, 0.15)
        };
        assert!(rel(0, j) < bilinear && rel(1, j) < bicubic, "field {j}");
    }
}

#[test]
fn summed_layers_carry_the_spectrum_of_the_covered_band_in_both_schemes() {
    // The expected variance of the sum (the cell integrals of each layer's share of P) against
    // the spectrum's integral over the |k| interval the layers cover: the partition counts
    // every wavenumber once, whether the layers overlap or not.
    for base in [OceanParams::default(), OceanParams::tiling_layers()] {
        for (wind_speed, fetch_km, depth_m) in [(4.16, 204.5, 997.9), (1.78, 141.35, 263.4)] {
            let p = OceanParams {
                wind_speed,
                fetch_km,
                depth_m,
                rms_m: None,
                ..base.clone()
            };
            let s = Surface::new(&p, 3).unwrap();
            let sum: f64 = s.layers().iter().map(|l| l.expected_variance()).sum();
            let (lo, hi) = p.partition().covered();
            let integral = Spectrum::new(&p).band_variance(lo, hi);
            println!(
                "{:?} U={wind_speed}: sum / integral = {:.5}",
                p.layering,
                sum / integral
            );
            assert!(
                (sum / integral - 1.0).abs() < 0.01,
                "{:?}: {sum} vs {integral}",
                p.layering
            );
            // and the summary's per-layer spectrum shares add up to the same integral
            let shares: f64 = s
                .summary()
                .layers
                .iter()
                .map(|l| l.spectrum_rms_m.powi(2))
                .sum();
            assert!(
                (shares / integral - 1.0).abs() < 1e-3,
                "{shares} vs {integral}"
            );
        }
    }
}

#[test]
fn far_origin_keeps_precision() {
    let s = small(7);
    for interp in [
        Interp::Bilinear,
        Interp::Bicubic,
        Interp::VariancePreserving,
    ] {
        for &(u, v) in &[(0.37f32, -1.25f32), (13.3, 7.9), (-250.0, 410.5)] {
            let far = [100_000.0 + 0.125, -73_000.0 - 0.5];
            let a = s.sampler_with(far, interp).sample(u, v);
            // the same world point with the offset folded into the origin
            let b = s
                .sampler_with([far[0] + u as f64, far[1] + v as f64], interp)
                .sample(0.0, 0.0);
            assert!((a.height - b.height).abs() < 1e-4, "{a:?} vs {b:?}");
            for k in 0..3 {
                assert!((a.normal[k] - b.normal[k]).abs() < 2e-3);
            }
        }
    }
    // and one period of every layer away (lcm-free shift only for a single layer)
    let one = Surface::new(
        &OceanParams {
            layers: vec![LayerSpec {
                size_m: 47.3,
                n: 64,
            }],
            ..OceanParams::default()
        },
        1,
    )
    .unwrap();
    let a = one.sampler([0.0, 0.0]).sample(3.3, -2.1);
    let b = one
        .sampler([47.3 * 2114.0, -47.3 * 1000.0])
        .sample(3.3, -2.1);
    assert!((a.height - b.height).abs() < 1e-5 && (a.normal[0] - b.normal[0]).abs() < 1e-4);
}

#[test]
fn folding_is_detected_and_reported() {
    let calm = Surface::new(
        &OceanParams {
            choppiness: 0.0,
            ..OceanParams::default()
        },
        9,
    )
    .unwrap();
    assert_eq!(calm.summary().folded_fraction, 0.0);
    let rough = OceanParams {
        wind_speed: 15.0,
        fetch_km: 300.0,
        rms_m: None,
        choppiness: 2.5,
        ..OceanParams::default()
    };
    let s = Surface::new(&rough, 9).unwrap();
    let sum = s.summary();
    assert!(
        sum.folded_fraction > 1e-4 && sum.folded_fraction < 0.5,
        "{sum:?}"
    );
    // the normal points down exactly where J <= 0
    let sampler = s.sampler([0.0, 0.0]);
    let mut folded = 0;
    for i in 0..20_000 {
        let p = sampler.sample((i % 141) as f32 * 2.83, (i / 141) as f32 * 2.83);
        assert_eq!(p.normal[1] <= 0.0, p.jacobian <= 0.0);
        folded += usize::from(p.jacobian <= 0.0);
    }
    assert!(folded > 0);
}

/// What the fold bound rests on: no read of a layer returns a strain larger than the layer's
/// largest over its grid points times the read's reach (bilinear, Catmull-Rom), and the summed
/// surface's J is never below the bound. Seas: the small test sea, which the bound clears, and
/// the same scaled until it folds, which it must not clear.
#[test]
fn fold_bound_holds_for_every_read() {
    let mut worst_ratio = [0.0f64; 2];
    for (k, interp) in [Interp::Bilinear, Interp::Bicubic].into_iter().enumerate() {
        for chop in [1.0, 6.0] {
            let mut s = small(3);
            s.params.interp = interp;
            s.layers.iter_mut().for_each(|l| l.scale(chop));
            let reach = read_reach(interp).unwrap();
            let sampler = s.sampler([0.0, 0.0]);
            let bound = s.fold_bound();
            let mut min_j = f64::INFINITY;
            for i in 0..40_000u64 {
                let h = crate::rng::splitmix64(i);
                let u = (h & 0xFFFF) as f32 / 65536.0 * 200.0;
                let v = (h >> 48) as f32 / 65536.0 * 200.0;
                min_j = min_j.min(sampler.sample(u, v).jacobian as f64);
                for l in s.layers() {
                    let t = l.read(u as f64 * l.inv_dx(), v as f64 * l.inv_dx(), interp);
                    let m = l.grid_stats().max_strain;
                    for (j, f) in [field::DDX_DX, field::DDZ_DZ, field::DDX_DZ]
                        .into_iter()
                        .enumerate()
                    {
                        let ratio = t[f].abs() as f64 / m[j] as f64;
                        assert!(ratio <= reach * (1.0 + 1e-5), "{interp:?}: {ratio}");
                        worst_ratio[k] = worst_ratio[k].max(ratio);
                    }
                }
            }
            if let Some(b) = bound {
                assert!(
                    min_j >= b - 1e-5,
                    "{interp:?} x{chop}: J {min_j} < bound {b}"
                );
            }
            if chop == 1.0 {
                assert!(s.cannot_fold(), "{interp:?}: bound {bound:?}");
            } else {
                // a sea that does fold is not cleared by the bound
                assert!(min_j <= 0.0, "{interp:?} x{chop}: J >= {min_j}");
                assert!(!s.cannot_fold(), "{interp:?} x{chop}: bound {bound:?}");
            }
        }
    }
    // bicubic reads overshoot the grid's largest value, so a reach of 1 would not be a bound
    assert!(
        worst_ratio[0] <= 1.0 + 1e-5 && worst_ratio[1] > 1.0,
        "{worst_ratio:?}"
    );
}

#[test]
fn layers_sum_and_set_time_moves_waves() {
    let mut s = small(8);
    let sampler = s.sampler([5.0, 6.0]);
    let sum = sampler.fields(1.0, 2.0);
    let mut by_hand = [0.0f32; FIELD_COUNT];
    for l in s.layers() {
        let t = l.bilinear((5.0 + 1.0) * l.inv_dx(), (6.0 + 2.0) * l.inv_dx());
        for j in 0..FIELD_COUNT {
            by_hand[j] += t[j];
        }
    }
    for j in 0..FIELD_COUNT {
        assert!((sum[j] - by_hand[j]).abs() < 1e-5 * (1.0 + by_hand[j].abs()));
    }
    let before = s.sampler([0.0, 0.0]).sample(1.0, 1.0);
    let summary_before = s.summary().clone();
    s.set_time(2.0).unwrap();
    // the summary kept from time 0 is not served at time 2
    assert_ne!(s.summary().mss_lookup, summary_before.mss_lookup);
    assert!(
        s.set_time(f64::NAN)
            .unwrap_err()
            .to_string()
            .starts_with("ocean.time_s")
    );
    assert_ne!(before, s.sampler([0.0, 0.0]).sample(1.0, 1.0));
    assert_eq!(s.params().time_s, 2.0);
    fn send_sync<T: Send + Sync>() {}
    send_sync::<Surface>();
    send_sync::<Sampler<'_>>();
}
