//! Tests of the summed surface (`surface.rs`): flat sea, normals against sampled tangents, the
//! sampler against the direct Fourier sum, RMS targets, variance of the union of bands, far
//! origins, folding, and time.

use super::summary::slope2;
use super::*;
use crate::ocean::{LayerSpec, SpreadingKind};

fn small(seed: u64) -> Surface {
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

#[test]
fn normals_in_lanes_are_the_normals_one_at_a_time() {
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
            for (p, n) in points.iter().zip(&lanes) {
                let one = sampler.normal(p[0], p[1]);
                assert_eq!(
                    n.map(f32::to_bits),
                    one.map(f32::to_bits),
                    "{interp:?} at {p:?}"
                );
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
fn target_rms_is_hit() {
    // The earlier default layers (fine grids): the interpolated surface has the target RMS.
    // With the default overlapping layers the realization does too, but bilinear reads of the
    // 10.3 and 12.7 km layers (8-10 texels per peak wavelength) lose ~5 % of it between texels
    // (docs/ocean.md).
    for (base, sampled_tolerance) in [
        (OceanParams::tiling_layers(), 0.01),
        (OceanParams::default(), 0.06),
    ] {
        for (seed, target) in [(4, 0.225), (5, 0.548), (6, 0.098)] {
            target_rms_case(&base, seed, target, sampled_tolerance);
        }
    }
}

fn target_rms_case(base: &OceanParams, seed: u64, target: f64, sampled_tolerance: f64) {
    {
        let p = OceanParams {
            rms_m: Some(target),
            ..base.clone()
        };
        let s = Surface::new(&p, seed).unwrap();
        let sum = s.summary();
        assert!(
            (sum.realization_rms_m / target - 1.0).abs() < 1e-4,
            "{sum:?}"
        );
        // the summed, interpolated surface measured independently of Parseval
        assert!(
            (sum.sampled_rms_m / target - 1.0).abs() < sampled_tolerance,
            "sampled {} vs {target}",
            sum.sampled_rms_m
        );
        assert!((sum.hs_m - 4.0 * target).abs() < 1e-3);
        assert_eq!(sum.hs_target_m, Some(4.0 * target));
    }
    // the same target as a significant wave height: the same scale, the same surface
    let by_hs = OceanParams {
        rms_m: None,
        hs_m: Some(4.0 * target),
        ..base.clone()
    };
    let by_rms = OceanParams {
        rms_m: Some(target),
        ..base.clone()
    };
    let (a, b) = (
        Surface::new(&by_hs, seed).unwrap().summary().clone(),
        Surface::new(&by_rms, seed).unwrap().summary().clone(),
    );
    assert!((a.hs_m / (4.0 * target) - 1.0).abs() < 1e-4, "{a:?}");
    assert_eq!(a.amplitude_scale, b.amplitude_scale);
    assert_eq!(a.hs_target_m, Some(4.0 * target));
}

#[test]
fn surface_variance_matches_union_of_bands() {
    // three layers, 16 seeds: the realization variance against the spectrum integral over
    // the union of bands (no double counting across layers)
    let p = OceanParams {
        wind_speed: 1.3,
        fetch_km: 194.8,
        depth_m: 381.4,
        rms_m: None,
        spreading: SpreadingKind::DonelanBanner,
        layers: vec![
            LayerSpec {
                size_m: 800.0,
                n: 256,
            },
            LayerSpec {
                size_m: 93.1,
                n: 128,
            },
            LayerSpec {
                size_m: 11.3,
                n: 64,
            },
        ],
        ..OceanParams::default()
    };
    let spectrum = Spectrum::new(&p);
    let b = p.bands();
    let union = spectrum.band_variance(b[0].0, b[2].1);
    let mut mean = 0.0;
    for seed in 100..116 {
        let s = Surface::new(&p, seed).unwrap();
        let sum = s.summary();
        assert!(
            (sum.spectrum_rms_m.powi(2) / union - 1.0).abs() < 1e-6,
            "{} vs {union}",
            sum.spectrum_rms_m.powi(2)
        );
        mean += sum.realization_rms_m.powi(2) / 16.0;
    }
    println!(
        "3 layers, 16-seed mean variance / union-of-bands integral = {:.4}",
        mean / union
    );
    assert!((mean / union - 1.0).abs() < 0.05, "{mean} vs {union}");
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

/// What `compute_fields` measures as it writes the texels is what a pass over them finds, and
/// the amplitudes' Parseval variance (which scales a surface to its RMS target before the
/// transforms) is the grid's.
#[test]
fn grid_stats_are_the_texels_and_parseval_the_grid() {
    let s = small(4);
    for l in s.layers() {
        let f = l.fields();
        let mean = |g: &dyn Fn(&Texel) -> f64| f.iter().map(g).sum::<f64>() / f.len() as f64;
        let g = l.grid_stats();
        let rel = |a: f64, b: f64| (a / b - 1.0).abs();
        assert!(rel(g.variance, mean(&|t| (t[field::H] as f64).powi(2))) < 1e-12);
        assert!(rel(g.mss, mean(&slope2)) < 1e-12);
        for (j, fi) in [field::DDX_DX, field::DDZ_DZ, field::DDX_DZ]
            .into_iter()
            .enumerate()
        {
            let m = f.iter().map(|t| t[fi].abs()).fold(0.0f32, f32::max);
            assert_eq!(g.max_strain[j], m);
        }
        let parseval = l.spectral_height_variance(l.time_s());
        assert!(
            rel(parseval, g.variance) < 1e-5,
            "{parseval} vs {}",
            g.variance
        );
    }
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

/// The mean square slope three ways on the default layers: the realization's grid gradients
/// hold the spectrum's integral of k^2 P (a few per cent of realization scatter: the slope
/// variance sits in many modes); reads between grid points lose some of it, bilinear more than
/// bicubic, each layer no more than its grid holds; the sum's slopes are the layers' added.
/// Prefiltered reads and variance-preserving ones keep each layer's grid slopes
/// (within 1 %), and so the spectrum's within 2 % on the default sea, the bound the slopes must
/// meet.
#[test]
fn mean_square_slope_of_the_spectrum_the_grid_and_the_lookup() {
    let read = |interp| {
        let p = OceanParams {
            interp,
            ..OceanParams::default()
        };
        Surface::new(&p, 3).unwrap().summary().clone()
    };
    let (bilinear, bicubic, preserving, prefiltered) = (
        read(Interp::Bilinear),
        read(Interp::Bicubic),
        read(Interp::VariancePreserving),
        read(Interp::Prefiltered),
    );
    for s in [&bilinear, &bicubic, &preserving, &prefiltered] {
        assert!((s.mss_grid / s.mss_spectrum - 1.0).abs() < 0.03, "{s:?}");
        let layers: f64 = s.layers.iter().map(|l| l.mss_lookup).sum();
        // independent layers: cross terms average out over the 512^2 points
        assert!((s.mss_lookup / layers - 1.0).abs() < 0.01, "{s:?}");
        for l in &s.layers {
            assert!(l.mss_lookup < 1.01 * l.mss_grid, "{l:?}");
            assert!((l.mss_grid / l.mss_spectrum - 1.0).abs() < 0.05, "{l:?}");
        }
    }
    assert!(
        bilinear.mss_lookup < 0.95 * bilinear.mss_spectrum,
        "{bilinear:?}"
    );
    assert!(
        bicubic.mss_lookup > bilinear.mss_lookup * 1.05,
        "{bicubic:?}"
    );
    // The default read is one of the two that keep the spectrum's slope within 2 % (what
    // `ocean --json` reports as mss_lookup on the default scene).
    assert!(matches!(
        OceanParams::default().interp,
        Interp::Prefiltered | Interp::VariancePreserving
    ));
    for s in [&preserving, &prefiltered] {
        assert!((s.mss_lookup / s.mss_spectrum - 1.0).abs() < 0.02, "{s:?}");
        for l in &s.layers {
            assert!((l.mss_lookup / l.mss_grid - 1.0).abs() < 0.01, "{l:?}");
        }
    }
    // The grid does not depend on how it is read (the prefiltered layers' from the
    // coefficients, by Parseval, to rounding).
    assert_eq!(bilinear.mss_grid, bicubic.mss_grid);
    assert_eq!(bilinear.mss_grid, preserving.mss_grid);
    assert!((prefiltered.mss_grid / bilinear.mss_grid - 1.0).abs() < 1e-5);
}

#[test]
fn a_preset_with_a_crossing_swell_reaches_its_height_in_its_proportions() {
    let mut p = OceanParams {
        beaufort: Some(3),
        swell: vec![crate::ocean::SwellParams::new(0.5, 9.0, 90.0)],
        ..small(1).params().clone()
    };
    p.apply_preset();
    let target = p.rms_target().unwrap();
    // WMO's 0.6 m for force 3 and the crossing swell's 0.5 m, summed in variance
    assert!((4.0 * target - (0.36f64 + 0.25).sqrt()).abs() < 1e-12);
    let mut shares = [0.0; 3];
    for seed in 0..4 {
        let s = Surface::new(&p, seed).unwrap();
        let sum = s.summary();
        assert!((sum.hs_m / (4.0 * target) - 1.0).abs() < 1e-4, "{sum:?}");
        assert_eq!(sum.hs_target_m, Some(4.0 * target));
        let names: Vec<&str> = sum.partitions.iter().map(|q| q.name.as_str()).collect();
        assert_eq!(names, ["wind sea", "swell 1", "swell 2"]);
        for (share, q) in shares.iter_mut().zip(&sum.partitions) {
            *share += q.variance_share / 4.0;
        }
        let crossing = &sum.partitions[2];
        assert!(
            (crossing.direction_deg - 90.0).abs() < 1e-9
                && (crossing.peak_period_s - 9.0).abs() < 1e-9
        );
    }
    // the shares (of the scaled spectrum over the layers) are the asked variances' (wind sea
    // 0.412 m, background swell 0.436 m, crossing swell 0.5 m) up to the layers' coverage
    let asked = [0.412f64, 0.436, 0.5].map(|h| h * h / 0.61);
    for (got, want) in shares.iter().zip(asked) {
        assert!((got - want).abs() < 0.02, "{shares:?} vs {asked:?}");
    }
}
