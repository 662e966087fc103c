//! Tests of [`super`] (the layer): oracles are the direct Fourier sum, finite differences and
//! the spectrum's band integral.

use super::*;
use crate::ocean::{OceanParams, SpectrumKind, SpreadingKind};

pub(super) fn spectrum(p: &OceanParams) -> Spectrum {
    Spectrum::new(p)
}

pub(super) fn rms_of(layer: &Layer, j: usize) -> f64 {
    let s: f64 = layer.fields().iter().map(|t| (t[j] as f64).powi(2)).sum();
    (s / layer.fields().len() as f64).sqrt()
}

/// A 47.3 m layer of case 22 holding the band the default surface gives it, at n = 128.
pub(super) fn mid_layer(n: usize, seed: u64) -> Layer {
    let p = OceanParams::default();
    // the band spans a factor 8 up to half Nyquist, as the default 47.3 m / 512 layer's does
    let band = (
        4.0 * TAU / 47.3,
        std::f64::consts::PI * n as f64 / 47.3 * 0.5,
    );
    Layer::new(&spectrum(&p), 47.3, n, band, 1.3, seed, 3.7).unwrap()
}

#[test]
fn fft_matches_naive_dft() {
    let p = OceanParams {
        wind_speed: 12.0,
        ..OceanParams::default()
    };
    let s = spectrum(&p);
    let layer = Layer::new(&s, 60.0, 16, (0.0, 10.0), 1.3, 5, 3.7).unwrap();
    let rms: Vec<f64> = (0..FIELD_COUNT).map(|j| rms_of(&layer, j)).collect();
    assert!(rms.iter().all(|&r| r > 0.0), "{rms:?}");
    for iz in 0..16 {
        for ix in 0..16 {
            let d = layer.eval_direct(ix as f64 * layer.dx(), iz as f64 * layer.dx());
            let t = layer.fields()[iz * 16 + ix];
            for j in 0..FIELD_COUNT {
                assert!(
                    (t[j] as f64 - d[j]).abs() < 1e-5 * rms[j],
                    "field {j} at ({ix},{iz}): {} vs {}",
                    t[j],
                    d[j]
                );
            }
        }
    }
}

#[test]
fn height_is_real() {
    let layer = mid_layer(128, 11);
    let c = layer.height_complex();
    let rms = (c.iter().map(|v| (v.re as f64).powi(2)).sum::<f64>() / c.len() as f64).sqrt();
    let imag = c.iter().map(|v| v.im.abs() as f64).fold(0.0, f64::max);
    assert!(rms > 0.0);
    println!("max |Im h| / rms = {:.2e}", imag / rms);
    assert!(imag < 2e-6 * rms, "max |Im h| / rms = {}", imag / rms);
    // and the packed transform put the same real part into field H
    for (v, t) in c.iter().zip(layer.fields()) {
        assert!((v.re - t[field::H]).abs() as f64 <= 1e-5 * rms);
    }
}

#[test]
fn fields_are_periodic() {
    let layer = mid_layer(32, 2);
    let l = layer.size_m();
    for &(x, z) in &[(0.3, 7.1), (12.25, 40.0), (46.9, 0.01)] {
        let a = layer.eval_direct(x, z);
        let b = layer.eval_direct(x + l, z - 3.0 * l);
        let (px, pz) = (x * layer.inv_dx(), z * layer.inv_dx());
        let n = layer.n() as f64;
        let (c, d) = (layer.bilinear(px, pz), layer.bilinear(px - n, pz + 2.0 * n));
        let (e, f) = (layer.bicubic(px, pz), layer.bicubic(px + 5.0 * n, pz));
        for j in 0..FIELD_COUNT {
            let r = rms_of(&layer, j);
            assert!((a[j] - b[j]).abs() < 1e-9 * r, "direct field {j}");
            assert!((c[j] - d[j]).abs() as f64 <= 1e-6 * r, "bilinear field {j}");
            assert!((e[j] - f[j]).abs() as f64 <= 1e-6 * r, "bicubic field {j}");
        }
    }
    // across the seam (between the last and first texel) the reads are as good as inside
    let line_error = |x: f64| {
        let mut e = 0.0;
        for k in 0..64 {
            let z = k as f64 * 0.731;
            let d = layer.eval_direct(x, z)[field::H];
            let b = layer.bicubic(x * layer.inv_dx(), z * layer.inv_dx())[field::H] as f64;
            e += (b - d).powi(2);
        }
        e.sqrt()
    };
    let (seam, inside) = (
        line_error(l - 0.5 * layer.dx()),
        line_error(0.5 * l - 0.5 * layer.dx()),
    );
    assert!(seam < 2.0 * inside + 1e-9, "seam {seam} vs inside {inside}");
    assert!(seam < 0.05 * rms_of(&layer, field::H) * 8.0);
}

#[test]
fn fft_gradients_match_finite_differences() {
    let layer = mid_layer(64, 3);
    let e = 1e-4 * layer.dx();
    let pairs = [
        (field::H, field::DH_DX, true),
        (field::H, field::DH_DZ, false),
        (field::DX, field::DDX_DX, true),
        (field::DZ, field::DDZ_DZ, false),
        (field::DX, field::DDX_DZ, false),
        (field::DZ, field::DDX_DZ, true),
    ];
    let rms: Vec<f64> = (0..FIELD_COUNT).map(|j| rms_of(&layer, j)).collect();
    for &(ix, iz) in &[(0, 0), (5, 17), (63, 31), (40, 2)] {
        let (x, z) = (ix as f64 * layer.dx(), iz as f64 * layer.dx());
        let t = layer.fields()[iz * 64 + ix];
        for &(f, g, along_x) in &pairs {
            let (dx, dz) = if along_x { (e, 0.0) } else { (0.0, e) };
            let fd = (layer.eval_direct(x + dx, z + dz)[f] - layer.eval_direct(x - dx, z - dz)[f])
                / (2.0 * e);
            assert!(
                (fd - t[g] as f64).abs() < 1e-4 * rms[g],
                "d{f}/d{} at ({ix},{iz}): fd {fd} vs fft {}",
                if along_x { "x" } else { "z" },
                t[g]
            );
        }
    }
    // and on the grid itself: central differences of the sampled field over one texel
    let n = layer.n();
    let (mut err, mut norm) = (0.0, 0.0);
    for iz in 0..n {
        for ix in 0..n {
            let f = |i: usize, k: usize| layer.fields()[(k % n) * n + (i % n)];
            let cd =
                (f(ix + 1, iz)[field::H] - f(ix + n - 1, iz)[field::H]) as f64 / (2.0 * layer.dx());
            let g = f(ix, iz)[field::DH_DX] as f64;
            err += (cd - g).powi(2);
            norm += g * g;
        }
    }
    let rel = (err / norm).sqrt();
    // half-Nyquist band: sin(k dx)/(k dx) >= 0.64 at its edge, much better where energy is
    assert!(rel < 0.15, "grid central difference vs FFT gradient: {rel}");
}

#[test]
fn variance_matches_band_integral_over_16_seeds() {
    // Case 12 (lambda_p = 24 m) on 800 m: the peak spans many cells, so 16 seeds average
    // out the chi-square scatter of the few hundred modes that hold the energy.
    let p = OceanParams {
        wind_speed: 1.3,
        fetch_km: 194.8,
        depth_m: 381.4,
        spreading: SpreadingKind::DonelanBanner,
        ..OceanParams::default()
    };
    let s = spectrum(&p);
    let (size, n) = (800.0, 256);
    let band = (
        std::f64::consts::PI / size,
        0.5 * std::f64::consts::PI * n as f64 / size,
    );
    let integral = s.band_variance(band.0, band.1);
    let mut mean = 0.0;
    for seed in 0..16 {
        let layer = Layer::new(&s, size, n, band, 0.0, seed, 0.0).unwrap();
        assert!((layer.expected_variance() / integral - 1.0).abs() < 0.01);
        mean += layer.height_variance() / 16.0;
    }
    println!(
        "16-seed mean variance / band integral = {:.4}",
        mean / integral
    );
    assert!(
        (mean / integral - 1.0).abs() < 0.05,
        "realization {mean} vs spectrum {integral}"
    );
}

#[test]
fn grid_sum_matches_band_integral() {
    // The sum of P dk^2 over the grid (the expected variance, no random draw) against the
    // band integral, on the default 400 m layer where the case-22 peak is only ~1 cell wide
    // radially, and for case 12 whose Mitsuyasu spreading is ~1 cell wide in angle.
    for p in [
        OceanParams::tiling_layers(),
        OceanParams {
            wind_speed: 1.3,
            fetch_km: 194.8,
            depth_m: 381.4,
            ..OceanParams::tiling_layers()
        },
    ] {
        let s = spectrum(&p);
        let band = p.bands()[0];
        let layer = Layer::new(&s, 400.0, 512, band, 1.0, 1, 0.0).unwrap();
        let ratio = layer.expected_variance() / s.band_variance(band.0, band.1);
        println!("grid sum / band integral = {ratio:.5}");
        assert!((ratio - 1.0).abs() < 0.005, "{ratio}");
    }
}

#[test]
fn waves_travel_downwind() {
    for wind_dir_deg in [0.0, 90.0, 200.0] {
        let p = OceanParams {
            wind_dir_deg,
            spectrum: SpectrumKind::Jonswap,
            ..OceanParams::default()
        };
        let s = spectrum(&p);
        let mut a = Layer::new(&s, 400.0, 128, (0.0, 2.0), 0.0, 8, 10.0).unwrap();
        let h0: Vec<f32> = a.fields().iter().map(|t| t[field::H]).collect();
        let grad: Vec<(f32, f32)> = a
            .fields()
            .iter()
            .map(|t| (t[field::DH_DX], t[field::DH_DZ]))
            .collect();
        a.compute_fields(10.05);
        // dh/dt = -c . grad h for a pattern moving with velocity c
        let (wx, wz) = (
            wind_dir_deg.to_radians().cos() as f32,
            wind_dir_deg.to_radians().sin() as f32,
        );
        let mut corr = 0.0f64;
        let mut norm = (0.0f64, 0.0f64);
        for ((t, h), g) in a.fields().iter().zip(&h0).zip(&grad) {
            let dhdt = t[field::H] - h;
            let along = g.0 * wx + g.1 * wz;
            corr += (dhdt * along) as f64;
            norm.0 += (dhdt * dhdt) as f64;
            norm.1 += (along * along) as f64;
        }
        let c = corr / (norm.0 * norm.1).sqrt();
        assert!(
            c < -0.8,
            "wind {wind_dir_deg}: corr(dh/dt, downwind slope) = {c}"
        );
    }
}

#[test]
fn choppiness_sharpens_crests() {
    let layer = mid_layer(64, 6);
    // horizontal divergence is negative (points converge) where h is high
    let (mut c, mut nh, mut nd) = (0.0f64, 0.0f64, 0.0f64);
    for t in layer.fields() {
        let div = (t[field::DDX_DX] + t[field::DDZ_DZ]) as f64;
        c += t[field::H] as f64 * div;
        nh += (t[field::H] as f64).powi(2);
        nd += div * div;
    }
    assert!(c / (nh * nd).sqrt() < -0.5);
    // J is 1 without choppiness
    let p = OceanParams::default();
    let flat_j = Layer::new(&spectrum(&p), 47.3, 32, (2.0, 8.0), 0.0, 6, 0.0).unwrap();
    assert!(flat_j.fields().iter().all(|t| jacobian(t) == 1.0));
    assert_eq!(flat_j.folded_fraction(), 0.0);
}

#[test]
fn seed_determines_the_realization() {
    let a = mid_layer(32, 21);
    let b = mid_layer(32, 21);
    let c = mid_layer(32, 22);
    assert_eq!(a.fields(), b.fields());
    assert_ne!(a.fields(), c.fields());
}

/// A cell's amplitude is its own: the cells two bands share get the same h0 whichever band is
/// drawn (each cell seeks to its own words of its row's stream, so skipping the cells outside a
/// band shifts nothing).
#[test]
fn a_cells_amplitude_does_not_depend_on_the_band() {
    let p = OceanParams::default();
    let (size, n) = (47.3, 64);
    let dk = TAU / size;
    let layer = |band| Layer::new(&spectrum(&p), size, n, band, 1.3, 5, 0.0).unwrap();
    let narrow = layer((6.0 * dk, 12.0 * dk));
    let wide = layer((2.0 * dk, 30.0 * dk));
    let mut shared = 0;
    for i in 0..n * n {
        let (ix, iz) = (i / n, i % n);
        let (a, b) = (&narrow.h0_at(ix, iz), &wide.h0_at(ix, iz));
        let k = signed_index(ix, n).hypot(signed_index(iz, n)) * dk;
        if (6.0 * dk..12.0 * dk).contains(&k) {
            assert_eq!(a, b, "cell ({ix}, {iz})");
            shared += usize::from(a.norm_sqr() > 0.0);
        } else {
            assert_eq!(
                *a,
                C32::default(),
                "cell ({ix}, {iz}) is outside the narrow band"
            );
        }
    }
    assert!(shared > 300, "{shared} shared cells with energy");
}

/// Planes shared between layers leave nothing behind: a narrow-band layer computed in the planes
/// a wider, finer one used gets the fields it gets in planes of its own, bit for bit.
#[test]
fn shared_planes_give_the_fields_of_fresh_ones() {
    let p = OceanParams::default();
    let (size, n) = (47.3, 64);
    let dk = TAU / size;
    let wide = || Layer::new(&spectrum(&p), size, 2 * n, (dk, 60.0 * dk), 1.0, 3, 0.0).unwrap();
    let mut narrow = Layer::new(&spectrum(&p), size, n, (2.0 * dk, 9.0 * dk), 1.0, 4, 0.0).unwrap();
    let fresh = narrow.fields().to_vec();
    let mut planes = super::FieldPlanes::default();
    wide().compute_fields_in(0.5, &mut planes);
    narrow.compute_fields_in(0.0, &mut planes);
    assert_eq!(narrow.fields(), &fresh[..]);
}

/// The compact layout of the amplitudes: every grid index within the reach maps to a distinct
/// slot and back, the reach is closed under the mirror i -> -i, and it holds every cell of the
/// band (a band to the Nyquist keeps all but the Nyquist index).
#[test]
fn band_cells_cover_the_band_once() {
    use super::amplitudes::BandCells;
    for (n, reach_k) in [
        (64usize, 9.5),
        (64, 10.0),
        (64, 32.0),
        (256, 1.0),
        (16, 0.5),
    ] {
        let cells = BandCells::new(n, 1.0, reach_k);
        let inside: Vec<usize> = (0..n).filter(|&i| cells.inside(i)).collect();
        assert_eq!(inside, cells.grid_indices().collect::<Vec<_>>());
        assert_eq!(inside.len(), cells.width, "n {n}, k_max {reach_k}");
        let mut seen = vec![false; cells.width];
        for &i in &inside {
            let c = cells.compact_index(i);
            assert!(!seen[c], "slot {c} twice");
            seen[c] = true;
            assert_eq!(cells.grid_index(c), i);
            assert!(cells.inside((n - i) % n), "mirror of {i}");
        }
        for i in 0..n {
            let s = signed_index(i, n);
            if i != n / 2 && s.abs() < reach_k {
                assert!(cells.inside(i), "index {i} (signed {s}) of k_max {reach_k}");
            }
        }
        // outside the reach: every other index, once (what the transforms clear)
        let outside: Vec<usize> = cells.outside().collect();
        assert_eq!(
            outside,
            (0..n).filter(|&i| !cells.inside(i)).collect::<Vec<_>>()
        );
    }
}

/// The column pass on one thread reuses its gathered columns from block to block, so every
/// block but the first starts from the transforms of the one before: a layer whose band leaves
/// rows out (they are cleared, not written) and that spans several blocks of columns, at a time
/// that is not 0, against the direct Fourier sum at every texel.
#[test]
fn reused_columns_give_the_direct_sum_in_every_block() {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let n = 64;
    let layer = pool.install(|| mid_layer(n, 8));
    let rms: Vec<f64> = (0..FIELD_COUNT).map(|j| rms_of(&layer, j)).collect();
    let rows = (0..n)
        .filter(|&i| (signed_index(i, n) * TAU / 47.3).abs() < layer.k_max)
        .count();
    assert!(rows < n - 1, "the band leaves rows out ({rows} of {n})");
    for iz in 0..n {
        for ix in 0..n {
            let d = layer.eval_direct(ix as f64 * layer.dx(), iz as f64 * layer.dx());
            let t = layer.fields()[iz * n + ix];
            for j in 0..FIELD_COUNT {
                assert!(
                    (t[j] as f64 - d[j]).abs() < 1e-5 * rms[j],
                    "field {j} at ({ix},{iz}): {} vs {}",
                    t[j],
                    d[j]
                );
            }
        }
    }
}

/// The spectral multipliers take sqrt(kx^2 + kz^2) where they took hypot: on every cell of the
/// default layers' bands the two round to the same f32 multipliers.
#[test]
fn multipliers_round_alike_with_hypot_on_the_default_layers() {
    let hypot = |lam: f64, kx: f64, kz: f64| {
        let k = kx.hypot(kz);
        let (ux, uz) = if k > 0.0 {
            (kx / k, kz / k)
        } else {
            (0.0, 0.0)
        };
        [
            Complex::new(1.0 - lam * ux, 0.0),
            Complex::new(-kx, lam * uz),
            Complex::new(0.0, kz - lam * kx * ux),
            Complex::new(-lam * kz * uz, -lam * kx * uz),
        ]
        .map(|m: Complex<f64>| C32::new(m.re as f32, m.im as f32))
    };
    let p = OceanParams::default();
    for (i, l) in p.layers.iter().enumerate() {
        let (n, dk) = (l.n, TAU / l.size_m);
        let k_max = p.partition().support(i).1;
        let reach = ((k_max / dk) as usize + 1).min(n / 2);
        for ix in (0..reach).chain(n - reach + 1..n) {
            for iz in (0..reach).chain(n - reach + 1..n) {
                let (kx, kz) = (signed_index(ix, n) * dk, signed_index(iz, n) * dk);
                assert_eq!(
                    super::fields::multipliers(p.choppiness, kx, kz),
                    hypot(p.choppiness, kx, kz),
                    "layer {i} cell ({ix}, {iz})"
                );
            }
        }
    }
}

/// The radial table that draws the amplitudes against the spectrum's own formulas: the same
/// cells and random numbers, so h0 within 5e-5 of its RMS and every field within 1e-4 of its
/// RMS (the build's accuracy bound; measured 1e-6 to 2e-5). Seas: the default (case 22, spreading exponent 84 at the
/// peak), Beaufort 5 with a crossing swell (three partitions), a storm, and a 30 m deep sea with
/// the spreading capped; layers put each sea's peak inside a 256-texel grid.
#[test]
fn table_matches_exact_spectrum() {
    use super::amplitudes::PointSpectrum;
    let mut seas = vec![OceanParams::default()];
    let mut b5 = OceanParams {
        beaufort: Some(5),
        ..OceanParams::default()
    };
    b5.apply_preset();
    b5.swell.push(crate::ocean::SwellParams {
        hs_m: 1.2,
        tp_s: 9.0,
        dir_deg: 70.0,
        spreading_s: 25.0,
        gamma: 3.3,
    });
    seas.push(b5);
    seas.push(OceanParams {
        wind_speed: 20.0,
        fetch_km: 400.0,
        ..OceanParams::default()
    });
    seas.push(OceanParams {
        depth_m: 30.0,
        spreading_cap: Some(25.0),
        wind_dir_deg: -40.0,
        ..OceanParams::default()
    });
    for (i, p) in seas.iter().enumerate() {
        let spectrum = spectrum(p);
        let peak_m = TAU / spectrum.peak_wavenumber();
        let size_m = 12.0 * peak_m;
        let n = 256;
        let dk = TAU / size_m;
        let band = (0.5 * dk, 0.5 * n as f64 * dk);
        let weight = |k: f64| (1.0 + (k / (10.0 * dk)).powi(2)).recip();
        let table = PointSpectrum::new(&spectrum, &weight, band.1 + dk);
        assert!(matches!(table, PointSpectrum::Table(_)), "sea {i}");
        let exact = PointSpectrum::Exact {
            spectrum: &spectrum,
            weight: &weight,
        };
        let build = |point| {
            let mut layer = Layer::build(point, p.depth_m, size_m, n, band, 1.0, 7, 2.5);
            layer.compute_fields(2.5);
            layer
        };
        let (fast, slow) = (build(&table), build(&exact));
        let rel = |a: &mut dyn Iterator<Item = (f64, f64)>| {
            let (d, r) = a.fold((0.0, 0.0), |(d, r), (x, y)| {
                (d + (x - y).powi(2), r + y * y)
            });
            (d / r).sqrt()
        };
        let h0 = rel(&mut fast
            .h0
            .iter()
            .zip(slow.h0.iter())
            .flat_map(|(a, b)| [(a.re as f64, b.re as f64), (a.im as f64, b.im as f64)]));
        assert!(h0 < 5e-5, "sea {i}: h0 differs by {h0:.2e} of its RMS");
        assert!(
            (fast.expected_variance / slow.expected_variance - 1.0).abs() < 1e-4,
            "sea {i}: variance {} vs {}",
            fast.expected_variance,
            slow.expected_variance
        );
        for j in 0..FIELD_COUNT {
            let e = rel(&mut fast
                .fields()
                .iter()
                .zip(slow.fields())
                .map(|(a, b)| (a[j] as f64, b[j] as f64)));
            assert!(e < 1e-4, "sea {i}: field {j} differs by {e:.2e} of its RMS");
        }
    }
}
