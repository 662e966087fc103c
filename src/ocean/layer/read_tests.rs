//! Tests of the layer's reads between grid points ([`super::read`] and the prefiltered slope
//! fields): oracles are the scalar read, the direct Fourier sum and the grid's own statistics.

use super::tests::{mid_layer, rms_of, spectrum};
use super::*;
use crate::ocean::{Interp, OceanParams};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

#[test]
fn split_lanes_is_split() {
    let below = |x: f64| f64::from_bits(x.to_bits() - 1);
    let mut values = vec![0.0, -0.0, 1e-300, -1e-300, 0.5, -0.5, 2.5, -2.5, 3.0, -3.0];
    values.extend([
        below(1.0),
        -below(1.0),
        below(-3.0),
        1e9 + 0.25,
        -1e9 - 0.75,
    ]);
    values.extend([
        LANE_RANGE - 0.5,
        -(LANE_RANGE - 0.5),
        below(LANE_RANGE),
        -1234.0,
    ]);
    for chunk in values.chunks(8) {
        let mut p = [0.0; 8];
        p[..chunk.len()].copy_from_slice(chunk);
        let (i, f) = split_lanes(&p);
        for l in 0..8 {
            let (si, sf) = split(p[l]);
            assert_eq!(
                (i[l] as i64, f[l].to_bits()),
                (si, sf.to_bits()),
                "at {}",
                p[l]
            );
        }
    }
}

#[test]
fn interpolation_error_against_direct_sum() {
    let layer = mid_layer(128, 4);
    let mut rng = ChaCha8Rng::seed_from_u64(99);
    let mut err = [[0.0f64; 2]; 3];
    let mut norm = [0.0f64; 2];
    for _ in 0..400 {
        let x = (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64 * layer.size_m();
        let z = (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64 * layer.size_m();
        let d = layer.eval_direct(x, z);
        let (px, pz) = (x * layer.inv_dx(), z * layer.inv_dx());
        let all = [
            Interp::Bilinear,
            Interp::Bicubic,
            Interp::VariancePreserving,
        ];
        for (m, interp) in all.into_iter().enumerate() {
            let r = layer.read(px, pz, interp);
            for (q, j) in [field::H, field::DH_DX].into_iter().enumerate() {
                err[m][q] += (r[j] as f64 - d[j]).powi(2);
                if m == 0 {
                    norm[q] += d[j] * d[j];
                }
            }
        }
    }
    let rel = |m: usize, q: usize| (err[m][q] / norm[q]).sqrt();
    println!(
        "interp rms error / rms: h bilinear {:.2e} bicubic {:.2e} variance-preserving {:.2e}; dh/dx bilinear {:.2e} bicubic {:.2e} variance-preserving {:.2e}",
        rel(0, 0),
        rel(1, 0),
        rel(2, 0),
        rel(0, 1),
        rel(1, 1),
        rel(2, 1)
    );
    for q in 0..2 {
        assert!(rel(1, q) < 0.5 * rel(0, q), "bicubic must beat bilinear");
        // keeping the variance does not cost accuracy point by point
        assert!(
            rel(2, q) < rel(0, q),
            "variance-preserving must not be worse than bilinear"
        );
    }
    assert!(rel(0, 0) < 0.05 && rel(1, 0) < 0.012);
    assert!(rel(0, 1) < 0.12 && rel(1, 1) < 0.03);
}

/// Variance-preserving reads: a texel at its grid point, bit for bit; between grid points every
/// field keeps its grid variance (within 3 % over 20 000 points) on a layer whose band runs to
/// full Nyquist, where a bilinear read of the slopes loses over 10 % of it.
#[test]
fn variance_preserving_reads_keep_every_fields_variance() {
    let p = OceanParams::default();
    let n = 64;
    let band = (4.0 * TAU / 47.3, std::f64::consts::PI * n as f64 / 47.3);
    let layer = Layer::new(&spectrum(&p), 47.3, n, band, 1.0, 5, 0.0).unwrap();
    for (ix, iz) in [(0, 0), (5, 63), (31, 17)] {
        let got = layer.variance_preserving(ix as f64, iz as f64);
        assert_eq!(got, layer.fields()[iz * n + ix]);
    }
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let (mut preserving, mut bilinear) = ([0f64; FIELD_COUNT], [0f64; FIELD_COUNT]);
    let points = 20_000;
    for _ in 0..points {
        let px = (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64 * n as f64;
        let pz = (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64 * n as f64;
        let (a, b) = (layer.variance_preserving(px, pz), layer.bilinear(px, pz));
        for j in 0..FIELD_COUNT {
            preserving[j] += (a[j] as f64).powi(2) / points as f64;
            bilinear[j] += (b[j] as f64).powi(2) / points as f64;
        }
    }
    for (j, got) in preserving.iter().enumerate() {
        let grid = rms_of(&layer, j).powi(2);
        assert!(
            (got / grid - 1.0).abs() < 0.03,
            "field {j}: {got} vs {grid}"
        );
    }
    let slope = rms_of(&layer, field::DH_DX).powi(2);
    assert!(
        bilinear[field::DH_DX] < 0.9 * slope,
        "{} vs {slope}",
        bilinear[field::DH_DX]
    );
}

/// The same layer with its derivative fields prefiltered ([`Layer::set_slope_prefilter`]).
fn prefiltered(layer: &Layer) -> Layer {
    let mut p = Layer {
        fields: Vec::new(),
        lag_correlations: std::sync::OnceLock::new(),
        h0: layer.h0.clone(),
        fft: layer.fft.clone(),
        ..*layer
    };
    p.set_slope_prefilter(true);
    p.compute_fields(layer.time_s());
    p
}

/// Prefiltered slope fields, on a layer whose band runs to full Nyquist (where a bilinear read
/// of the slopes loses over 10 % of their mean square) and on the half-Nyquist middle layer:
/// the heights and displacements are the plain layer's (to f32 rounding); the grid's mean square slope
/// is the sea's (Parseval, within f32 rounding); read at 20 000 random points between grid
/// points, every derivative field keeps the sea's mean square within 2 %; and point by point
/// the slopes are closer to the direct Fourier sum than a bilinear read's.
#[test]
fn prefiltered_slopes_keep_each_waves_power() {
    let p = OceanParams::default();
    let n = 64;
    let full = (4.0 * TAU / 47.3, std::f64::consts::PI * n as f64 / 47.3);
    let layers = [
        Layer::new(&spectrum(&p), 47.3, n, full, 1.0, 5, 0.0).unwrap(),
        mid_layer(128, 4),
    ];
    for plain in &layers {
        let pre = prefiltered(plain);
        // (Dz shares its transform with dh/dx, so it is the same to the transform's rounding)
        for j in [field::H, field::DX, field::DZ] {
            let tol = 1e-5 * rms_of(plain, j) as f32;
            for (a, b) in plain.fields().iter().zip(pre.fields()) {
                assert!(
                    (a[j] - b[j]).abs() <= tol,
                    "field {j}: {} vs {}",
                    a[j],
                    b[j]
                );
            }
        }
        let (sea, grid) = (plain.grid_stats().mss, pre.grid_stats().mss);
        assert!((grid / sea - 1.0).abs() < 1e-4, "grid mss {grid} vs {sea}");
        let m = plain.n() as f64;
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let (mut read, mut bilinear) = ([0f64; FIELD_COUNT], [0f64; FIELD_COUNT]);
        let (mut err_pre, mut err_bil, mut norm) = (0.0, 0.0, 0.0);
        let points = 20_000;
        for i in 0..points {
            let px = (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64 * m;
            let pz = (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64 * m;
            let (a, b) = (
                pre.read(px, pz, Interp::Prefiltered),
                plain.read(px, pz, Interp::Bilinear),
            );
            for j in 0..FIELD_COUNT {
                read[j] += (a[j] as f64).powi(2) / points as f64;
                bilinear[j] += (b[j] as f64).powi(2) / points as f64;
            }
            if i < 400 {
                let d = plain.eval_direct(px * plain.dx(), pz * plain.dx());
                for j in [field::DH_DX, field::DH_DZ] {
                    err_pre += (a[j] as f64 - d[j]).powi(2);
                    err_bil += (b[j] as f64 - d[j]).powi(2);
                    norm += d[j] * d[j];
                }
            }
        }
        for j in SLOPES {
            let sea = rms_of(plain, j).powi(2);
            assert!(
                (read[j] / sea - 1.0).abs() < 0.02,
                "field {j}: prefiltered {} vs sea {sea}",
                read[j]
            );
        }
        let (pre_err, bil_err) = ((err_pre / norm).sqrt(), (err_bil / norm).sqrt());
        println!(
            "n {}: slopes' mean square as read / the sea's: bilinear {:.3} prefiltered {:.3}; rms error / rms against the direct sum: bilinear {bil_err:.3e} prefiltered {pre_err:.3e}",
            plain.n(),
            bilinear[field::DH_DX] / rms_of(plain, field::DH_DX).powi(2),
            read[field::DH_DX] / rms_of(plain, field::DH_DX).powi(2),
        );
        assert!(pre_err < bil_err, "{pre_err} vs {bil_err}");
    }
    let slope = rms_of(&layers[0], field::DH_DX).powi(2);
    let full_bilinear: f64 = {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        (0..20_000)
            .map(|_| {
                let px = (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64 * n as f64;
                let pz = (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64 * n as f64;
                (layers[0].bilinear(px, pz)[field::DH_DX] as f64).powi(2) / 20_000.0
            })
            .sum()
    };
    assert!(full_bilinear < 0.9 * slope, "{full_bilinear} vs {slope}");
}
