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

/// The same layer with its fields prefiltered ([`Layer::set_prefilter`]).
fn prefiltered(layer: &Layer) -> Layer {
    let mut p = Layer {
        fields: Vec::new(),
        lag_correlations: std::sync::OnceLock::new(),
        h0: layer.h0.clone(),
        fft: layer.fft.clone(),
        ..*layer
    };
    p.set_prefilter(true);
    p.compute_fields(layer.time_s());
    p
}

/// Prefiltered fields, on a layer whose band runs to full Nyquist (where a bilinear read of the
/// slopes loses over 10 % of their mean square) and on the half-Nyquist middle layer, against
/// the plain layer, at 20 000 random points between grid points: the grid's variance and mean
/// square slope are the sea's (Parseval, within f32 rounding); every derivative field as read
/// keeps the sea's mean square within 2 %, and so does the gradient of the bilinear height
/// surface itself (the exact surface's slope), where the plain layer's lose more than 5 % on
/// the full-Nyquist layer; and point by point, the heights and the slopes are closer to the
/// direct Fourier sum than the plain layer's.
#[test]
fn prefiltered_fields_keep_each_waves_slope_power() {
    let p = OceanParams::default();
    let n = 64;
    let full = (4.0 * TAU / 47.3, std::f64::consts::PI * n as f64 / 47.3);
    let layers = [
        Layer::new(&spectrum(&p), 47.3, n, full, 1.0, 5, 0.0).unwrap(),
        mid_layer(128, 4),
    ];
    for (k, plain) in layers.iter().enumerate() {
        let pre = prefiltered(plain);
        let (a, b) = (plain.grid_stats(), pre.grid_stats());
        assert!((b.mss / a.mss - 1.0).abs() < 1e-4, "{a:?} vs {b:?}");
        assert!(
            (b.variance / a.variance - 1.0).abs() < 1e-4,
            "{a:?} vs {b:?}"
        );
        let m = plain.n() as f64;
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let (mut read, mut bilinear) = ([0f64; FIELD_COUNT], [0f64; FIELD_COUNT]);
        let (mut surface_pre, mut surface_bil) = (0.0, 0.0);
        // squared errors against the direct sum: [height, slopes] x [prefiltered, plain]
        let (mut err, mut norm) = ([[0.0f64; 2]; 2], [0.0f64; 2]);
        let points = 20_000;
        for i in 0..points {
            let px = (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64 * m;
            let pz = (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64 * m;
            let reads = [
                pre.read(px, pz, Interp::Prefiltered),
                plain.read(px, pz, Interp::Bilinear),
            ];
            for j in 0..FIELD_COUNT {
                read[j] += (reads[0][j] as f64).powi(2) / points as f64;
                bilinear[j] += (reads[1][j] as f64).powi(2) / points as f64;
            }
            let (gp, gb) = (pre.surface_gradient(px, pz), plain.surface_gradient(px, pz));
            surface_pre += (gp[0] * gp[0] + gp[1] * gp[1]) / points as f64;
            surface_bil += (gb[0] * gb[0] + gb[1] * gb[1]) / points as f64;
            if i < 400 {
                let d = plain.eval_direct(px * plain.dx(), pz * plain.dx());
                for (q, fields) in [&[field::H][..], &[field::DH_DX, field::DH_DZ]]
                    .into_iter()
                    .enumerate()
                {
                    for &j in fields {
                        for (e, r) in err[q].iter_mut().zip(&reads) {
                            *e += (r[j] as f64 - d[j]).powi(2);
                        }
                        norm[q] += d[j] * d[j];
                    }
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
        let sea = a.mss;
        assert!(
            (surface_pre / sea - 1.0).abs() < 0.02,
            "surface's own slopes {surface_pre} vs sea {sea}"
        );
        if k == 0 {
            assert!(surface_bil < 0.95 * sea, "{surface_bil} vs {sea}");
            let slope = rms_of(plain, field::DH_DX).powi(2);
            assert!(bilinear[field::DH_DX] < 0.9 * slope, "{bilinear:?}");
        }
        let rel = |q: usize, r: usize| (err[q][r] / norm[q]).sqrt();
        println!(
            "n {}: mean square slope / the sea's: reads bilinear {:.3} prefiltered {:.3}, height surface bilinear {:.3} prefiltered {:.3}; rms error / rms against the direct sum: h bilinear {:.3e} prefiltered {:.3e}, slopes bilinear {:.3e} prefiltered {:.3e}",
            plain.n(),
            (bilinear[field::DH_DX] + bilinear[field::DH_DZ]) / sea,
            (read[field::DH_DX] + read[field::DH_DZ]) / sea,
            surface_bil / sea,
            surface_pre / sea,
            rel(0, 1),
            rel(0, 0),
            rel(1, 1),
            rel(1, 0),
        );
        for q in 0..2 {
            assert!(rel(q, 0) < rel(q, 1), "{q}: {} vs {}", rel(q, 0), rel(q, 1));
        }
    }
}

#[test]
fn the_cross_transfer_of_two_grids_is_the_mean_product_of_their_reads() {
    // A cosine of random phase sampled on a grid and on one twice as coarse (every other
    // point), each read between its points, linearly or by Catmull-Rom: the mean product of
    // the two reads over the positions and phases is half the real part of the cross transfer.
    for interp in [Interp::Bilinear, Interp::Bicubic] {
        for theta in [0.0, 0.3, 0.9, 1.6, 2.5, 3.1] {
            let read = |spacing: f64, x: f64, phase: f64| -> f64 {
                let (i, f) = ((x / spacing).floor(), (x / spacing).fract());
                let v = |j: f64| (theta * j * spacing + phase).cos();
                match interp {
                    Interp::Bicubic => {
                        let w = catmull_rom(f as f32);
                        (0..4).map(|k| w[k] as f64 * v(i + k as f64 - 1.0)).sum()
                    }
                    _ => (1.0 - f) * v(i) + f * v(i + 1.0),
                }
            };
            let (points, phases) = (4096, 16);
            let mut sum = 0.0;
            for p in 0..phases {
                let phase = std::f64::consts::TAU * (p as f64 + 0.5) / phases as f64;
                for k in 0..points {
                    let x = 2.0 * (k as f64 + 0.5) / points as f64;
                    sum += read(1.0, x, phase) * read(2.0, x, phase);
                }
            }
            let got = sum / (points * phases) as f64;
            let want = 0.5 * read_cross_transfer(interp, theta).re;
            assert!(
                (got - want).abs() < 1e-5,
                "{interp:?} at {theta}: mean product {got}, transfer {want}"
            );
        }
    }
    // Prefiltered reads divide by each grid's power: no wave is kept more than wholly.
    for i in 0..=16 {
        let theta = std::f64::consts::PI * i as f64 / 16.0;
        let c = read_cross_transfer(Interp::Prefiltered, theta);
        assert!(c.norm() <= 1.0 + 1e-9, "{theta}: {c}");
    }
    assert!((read_cross_transfer(Interp::Bilinear, 0.0) - 1.0).norm() < 1e-12);
}
