//! Tests of the slope tables, the levels' split and the blended reads ([`super`]).

use super::*;
use crate::ocean::OceanParams;

/// The default sea with the texels holding its own samples, which Parseval's sums are
/// (the prefiltered default scales them).
fn surface() -> Surface {
    let p = OceanParams {
        interp: crate::ocean::Interp::Bilinear,
        ..OceanParams::default()
    };
    Surface::new(&p, 1).unwrap()
}

#[test]
fn each_layers_slopes_are_its_grids() {
    // Parseval: the mean of (dh/dx)^2 over a layer's grid is the sum of kx^2 |h~|^2.
    let s = surface();
    let slopes = SurfaceSlopes::new(&s, SlopeSource::Spectrum);
    for (layer, bands) in s.layers().iter().zip(slopes.layers()) {
        let f = layer.fields();
        let mean = |i: usize, j: usize| {
            f.iter().map(|t| t[i] as f64 * t[j] as f64).sum::<f64>() / f.len() as f64
        };
        use crate::ocean::field::{DH_DX, DH_DZ};
        let grid = [mean(DH_DX, DH_DX), mean(DH_DX, DH_DZ), mean(DH_DZ, DH_DZ)];
        let total = bands.total();
        let scale = grid[0] + grid[2];
        for c in 0..3 {
            assert!(
                (total[c] - grid[c]).abs() < 1e-4 * scale,
                "layer of {} m: {total:?} vs grid {grid:?}",
                layer.size_m()
            );
        }
    }
}

#[test]
fn the_read_tables_hold_the_slopes_the_lookup_reads() {
    // Each layer's table as read against its mean square slope as the surface reads it (a
    // jittered 512^2 grid of reads), bilinear and Catmull-Rom: within 1 % (measured: 0.14 %
    // at most for both), where the sea's own is 2 % to 22 % more than bilinear reads
    // (the finest layer's waves run to Nyquist, where a bilinear read keeps a third of the
    // power).
    for interp in [Interp::Bilinear, Interp::Bicubic] {
        let params = OceanParams {
            interp,
            ..OceanParams::default()
        };
        let s = Surface::new(&params, 1).unwrap();
        let read = SurfaceSlopes::new(&s, SlopeSource::Read(interp));
        let sea = SurfaceSlopes::new(&s, SlopeSource::Spectrum);
        let summary = s.summary();
        for (r, l) in read.layers().iter().zip(&summary.layers) {
            let r = r.total()[0] + r.total()[2];
            assert!(
                (r / l.mss_lookup - 1.0).abs() < 0.01,
                "{interp:?}, layer of {} m: table {r:.4e}, lookup {:.4e}",
                l.size_m,
                l.mss_lookup
            );
        }
        if interp == Interp::Bilinear {
            let (r, g) = (read.layers().last().unwrap(), sea.layers().last().unwrap());
            assert!(r.total()[0] + r.total()[2] < 0.95 * (g.total()[0] + g.total()[2]));
        }
    }
}

#[test]
fn the_read_power_transfer_of_each_interpolation() {
    for i in 0..=16 {
        let theta = std::f64::consts::PI * i as f64 / 16.0;
        let bilinear = read_power_transfer(Interp::Bilinear, theta);
        assert!(
            (bilinear - (2.0 + theta.cos()) / 3.0).abs() < 1e-12,
            "{theta}"
        );
        let bicubic = read_power_transfer(Interp::Bicubic, theta);
        assert!(
            bicubic >= bilinear - 1e-6 && bicubic <= 1.0 + 1e-6,
            "{theta}"
        );
        assert_eq!(read_power_transfer(Interp::VariancePreserving, theta), 1.0);
    }
    assert!((read_power_transfer(Interp::Bicubic, 0.0) - 1.0).abs() < 1e-6);
}

#[test]
fn the_split_resolves_all_at_zero_width_and_nothing_at_a_huge_one() {
    for source in [SlopeSource::Spectrum, SlopeSource::Read(Interp::Bilinear)] {
        let slopes = SurfaceSlopes::new(&surface(), source);
        assert_eq!(slopes.split(0.0), Split::RESOLVED);
        let far = slopes.split(1e6);
        assert!(
            far.levels
                .iter()
                .take(slopes.layers().len())
                .all(|&l| l == NOT_READ)
        );
        let total = slopes.total();
        for c in 0..3 {
            assert!((far.cov[c] as f64 - total[c]).abs() <= 1e-6 * (total[0] + total[2]));
        }
    }
}

#[test]
fn the_split_moves_smoothly_and_keeps_each_layers_variance() {
    // What a blend of two levels keeps plus what it leaves is the layer's whole, at any
    // width; the unresolved part only grows with the width, without a jump; the layers are
    // read from ever coarser levels, the finest first.
    for source in [SlopeSource::Spectrum, SlopeSource::Read(Interp::Bilinear)] {
        let slopes = SurfaceSlopes::new(&surface(), source);
        let total = slopes.total();
        let tr = total[0] + total[2];
        let mut last = 0.0;
        let mut coordinates = vec![0.0f32; slopes.layers().len()];
        for i in 0..500 {
            let w = 1e-4 * 1.03f32.powi(i);
            let s = slopes.split(w);
            let mut unresolved = 0.0;
            for (j, l) in slopes.layers().iter().enumerate() {
                let x = l.level_coordinate(w);
                assert!(x >= coordinates[j], "width {w}: layer {j} went finer");
                coordinates[j] = x;
                let (level, t) = if s.levels[j] == NOT_READ {
                    (l.levels() + 1, 0.0)
                } else {
                    (s.levels[j] as usize, s.blend[j] as f64)
                };
                let (r, u) = (l.resolved(level, t), l.unresolved(level, t));
                let whole = l.total()[0] + l.total()[2];
                assert!(
                    (r[0] + r[2] + u[0] + u[2] - whole).abs() < 1e-9 * tr,
                    "width {w}, layer {j}"
                );
                unresolved += u[0] + u[2];
            }
            assert!(
                (unresolved - (s.cov[0] + s.cov[2]) as f64).abs() < 1e-6 * tr,
                "width {w}"
            );
            if i > 0 {
                assert!(unresolved >= last - 1e-7 * tr, "width {w}");
                assert!(
                    unresolved - last < 0.05 * tr,
                    "a jump of the split at width {w}"
                );
            }
            last = unresolved;
        }
    }
}

#[test]
fn the_blend_tables_hold_the_slopes_the_blended_reads_have() {
    // Each layer read alone as a split asks, from each of its levels blended half and half
    // with the next (and the last with nothing), on 65,536 random points of its period:
    // the mean square slope of the reads against the tables, within 2.5 % (four standard
    // errors of the sampled mean), for each read. Linear waves: the normal's slope is then
    // the summed fields' (with choppiness it is not quite, by half a per cent).
    for interp in [Interp::Bilinear, Interp::Prefiltered, Interp::Bicubic] {
        let params = OceanParams {
            interp,
            choppiness: 0.0,
            ..OceanParams::default()
        };
        let s = Surface::new(&params, 1).unwrap();
        let slopes = SurfaceSlopes::new(&s, SlopeSource::Read(interp));
        let sampler = s.sampler([0.0, 0.0]).with_levels(s.levels());
        let mut rng = crate::rng::Rng::keyed(&[17]);
        let mut checked = 0;
        for (i, l) in slopes.layers().iter().enumerate() {
            let size = s.layers()[i].size_m() as f32;
            for level in 0..=l.levels() {
                let mut split = Split::RESOLVED;
                split.levels = [NOT_READ; MAX_LAYERS];
                split.levels[i] = level as u8;
                split.blend[i] = 0.5;
                let (n, mut sum) = (65_536, 0.0f64);
                let splits = [split; 8];
                for _ in 0..n / 8 {
                    let uv: [[f32; 2]; 8] =
                        std::array::from_fn(|_| [rng.f32() * size, rng.f32() * size]);
                    let mut out = [[0.0f32; 3]; 8];
                    sampler.normals_split(&uv, &splits, &mut out);
                    for m in out {
                        let (a, b) = (m[0] / m[1], m[2] / m[1]);
                        sum += (a * a + b * b) as f64;
                    }
                }
                let r = l.resolved(level, 0.5);
                let (got, want) = (sum / n as f64, r[0] + r[2]);
                assert!(
                    (got / want - 1.0).abs() < 0.025,
                    "{interp:?}, layer {i}, level {level} blended: reads {got:.4e}, table {want:.4e}"
                );
                checked += 1;
            }
        }
        assert!(checked > 12, "{checked}");
    }
}

#[test]
fn a_resolved_split_reads_the_mapped_normals_bit_for_bit() {
    let s = surface();
    let sampler = s.sampler([123.0, -45.0]).with_levels(s.levels());
    let mut rng = crate::rng::Rng::keyed(&[19]);
    let uv: Vec<[f32; 2]> = (0..37)
        .map(|_| [rng.f32() * 400.0 - 200.0, rng.f32() * 400.0 - 200.0])
        .collect();
    let (mut a, mut b) = (vec![[0.0f32; 3]; uv.len()], vec![[0.0f32; 3]; uv.len()]);
    sampler.normals(&uv, &mut a);
    sampler.normals_split(&uv, &vec![Split::RESOLVED; uv.len()], &mut b);
    assert_eq!(a, b);
}

#[test]
fn a_level_holds_its_layers_waves_times_its_gaussian() {
    // Level l's slopes, from its own amplitudes, against the layer's amplitudes times
    // exp(-|k|^2 s^2 / 2), s = 2^l texels, summed here wave by wave.
    let s = surface();
    for (i, layer) in s.layers().iter().enumerate() {
        let levels = s.levels();
        assert!(levels.count(i) >= 1, "layer {i}");
        for l in 1..=levels.count(i) {
            let sigma = layer.dx() * (1u64 << l) as f64;
            let (n, dk) = (layer.n(), std::f64::consts::TAU / layer.size_m());
            let half = (n >> l) as f64 / 2.0;
            let mut want = 0.0;
            for ix in layer.band_indices() {
                for iz in layer.band_indices() {
                    let (sx, sz) = (signed_index(ix, n), signed_index(iz, n));
                    if sx.abs() >= half || sz.abs() >= half {
                        continue;
                    }
                    let k2 = (sx * sx + sz * sz) * dk * dk;
                    let h = layer.h_tilde(ix, iz, layer.time_s()).norm_sqr();
                    want += k2 * h * (-k2 * sigma * sigma).exp();
                }
            }
            let got = levels.level(i, l).slope_cov(SlopeSource::Spectrum);
            assert!(
                ((got[0] + got[2]) / want - 1.0).abs() < 1e-4,
                "layer {i} level {l}: {got:?} vs {want}"
            );
        }
    }
}

#[test]
fn one_pass_over_the_cells_gives_each_grids_own_tables() {
    // LayerSlopes::of against the separate passes over the layer and its levels, of the sea
    // and as read, at rest and at a time where every cell's phase turns: the terms are the
    // same, only the order of the rows' sums differs.
    let mut s = surface();
    for t in [0.0, 5.0] {
        s.set_time(t).unwrap();
        let interp = s.params().interp;
        let read = SlopeSource::Read(interp);
        for source in [SlopeSource::Spectrum, read] {
            let tables = SurfaceSlopes::new(&s, source);
            let levels = s.levels();
            for (i, (layer, got)) in s.layers().iter().zip(tables.layers()).enumerate() {
                let level = |l: usize| if l == 0 { layer } else { levels.level(i, l) };
                let count = levels.count(i);
                let close = |a: Cov, b: Cov, what: &str| {
                    let scale = b[0].abs() + b[2].abs();
                    for c in 0..3 {
                        assert!(
                            (a[c] - b[c]).abs() <= 1e-12 * scale,
                            "t {t}, {source:?}, layer {i}, {what}: {a:?} against {b:?}"
                        );
                    }
                };
                close(got.total(), layer.slope_cov(source), "total");
                assert_eq!(got.levels(), count);
                for l in 0..=count {
                    close(got.own[l], level(l).slope_cov(read), &format!("own {l}"));
                }
                for l in 0..count {
                    let want = level(l).slope_cross(level(l + 1), interp);
                    close(got.cross[l], want, &format!("cross {l}"));
                }
            }
        }
    }
}
