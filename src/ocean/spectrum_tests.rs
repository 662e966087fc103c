use super::*;
use crate::ocean::SwellParams;

fn case22(kind: SpectrumKind) -> OceanParams {
    OceanParams {
        spectrum: kind,
        ..OceanParams::default()
    }
}

/// Integral of P(k) over the plane on a polar grid: checks the Jacobian and D's normalisation
/// independently of `band_variance`.
fn polar_integral(s: &Spectrum, k_lo: f64, k_hi: f64) -> f64 {
    let n_theta = 1440;
    let dth = TAU / n_theta as f64;
    integrate_log(
        |k| {
            let mut ring = 0.0;
            for j in 0..n_theta {
                let th = -PI + (j as f64 + 0.5) * dth;
                ring += s.p_k(k * th.cos(), k * th.sin());
            }
            ring * dth * k
        },
        k_lo,
        k_hi,
        0.01,
    )
}

#[test]
fn dispersion_limits_and_inverse() {
    // deep: omega^2 = g k; shallow: omega = k sqrt(g h)
    let k = 0.5;
    assert!((dispersion(k, 1e4) - (G * k).sqrt()).abs() < 1e-12);
    let k = 1e-4;
    assert!((dispersion(k, 2.0) / (k * (G * 2.0).sqrt()) - 1.0).abs() < 1e-7);
    for &(k, h) in &[(0.01, 5.0), (0.3, 20.0), (2.0, 1000.0), (0.05, 150.9)] {
        let e = 1e-6 * k;
        let fd = (dispersion(k + e, h) - dispersion(k - e, h)) / (2.0 * e);
        assert!((group_velocity(k, h) / fd - 1.0).abs() < 1e-7, "{k} {h}");
        assert!((wavenumber(dispersion(k, h), h) / k - 1.0).abs() < 1e-12);
    }
}

#[test]
fn kitaigorodskii_is_continuous_piecewise() {
    assert_eq!(kitaigorodskii(0.0), 0.0);
    assert_eq!(kitaigorodskii(1.0), 0.5);
    assert_eq!(kitaigorodskii(2.0), 1.0);
    assert_eq!(kitaigorodskii(7.0), 1.0);
    for &x in &[1.0, 2.0] {
        assert!((kitaigorodskii(x - 1e-9) - kitaigorodskii(x + 1e-9)).abs() < 1e-8);
    }
    assert!((kitaigorodskii(1.5) - 0.875).abs() < 1e-15);
}

#[test]
fn jonswap_peaks_at_omega_p_with_gamma_enhancement() {
    let (a, wp) = jonswap_parameters(4.16, 204_500.0);
    // case 22 by hand: (U^2/(F g))^0.22 and (g^2/(U F))^(1/3)
    assert!((a - 0.076 * (4.16f64.powi(2) / (204_500.0 * 9.81)).powf(0.22)).abs() < 1e-15);
    assert!((wp - 1.0637).abs() < 1e-3, "{wp}");
    let mut best = (0.0, 0.0);
    for i in 1..20_000 {
        let w = wp * (0.5 + i as f64 * 1e-4);
        let s = jonswap(w, a, wp, 3.3);
        if s > best.1 {
            best = (w, s);
        }
    }
    assert!((best.0 / wp - 1.0).abs() < 2e-3, "{}", best.0 / wp);
    let ratio = jonswap(wp, a, wp, 3.3) / pierson_moskowitz_shape(wp, a, wp);
    assert!((ratio - 3.3).abs() < 1e-12);
}

#[test]
fn spreading_functions_are_normalised() {
    for spreading in [
        SpreadingKind::Mitsuyasu,
        SpreadingKind::DonelanBanner,
        SpreadingKind::Cos2,
        SpreadingKind::Uniform,
    ] {
        let s = Spectrum::new(&OceanParams {
            spreading,
            ..OceanParams::default()
        });
        for r in [0.3, 0.8, 1.0, 1.3, 3.0, 20.0] {
            let w = r * s.omega_p;
            let n = 200_000;
            let d = TAU / n as f64;
            let sum: f64 = (0..n)
                .map(|j| s.spreading_at(w, -PI + (j as f64 + 0.5) * d))
                .sum::<f64>()
                * d;
            assert!((sum - 1.0).abs() < 1e-6, "{spreading:?} r={r}: {sum}");
            assert!(s.spreading_at(w, 0.0) >= s.spreading_at(w, 2.0));
        }
    }
    assert!((ln_gamma(5.0) - 24f64.ln()).abs() < 1e-13);
    assert!((ln_gamma(0.5) - PI.sqrt().ln()).abs() < 1e-13);
}

#[test]
fn tma_full_band_variance_gamma1_matches_closed_form() {
    // With gamma = 1 JONSWAP integrates to alpha g^2 / (5 omega_p^4); at 998 m depth the
    // Kitaigorodskii factor is 1 wherever S is not negligible. The P(k) plane integral goes
    // through the finite-depth Jacobian and D(theta).
    for spreading in [SpreadingKind::Mitsuyasu, SpreadingKind::DonelanBanner] {
        let p = OceanParams {
            gamma: 1.0,
            spreading,
            ..case22(SpectrumKind::Tma)
        };
        let s = Spectrum::new(&p);
        let closed = s.alpha * G * G / (5.0 * s.omega_p.powi(4));
        let plane = polar_integral(&s, 1e-3, 1e3);
        assert!(
            (plane / closed - 1.0).abs() < 0.01,
            "{spreading:?}: {plane} vs {closed}"
        );
        assert!((s.total_variance() / closed - 1.0).abs() < 1e-6);
    }
}

#[test]
fn plane_integral_equals_band_variance_in_shallow_water() {
    // Case 34-like shallow sea: the Jacobian differs from deep water here.
    let p = OceanParams {
        depth_m: 8.0,
        ..case22(SpectrumKind::Tma)
    };
    let s = Spectrum::new(&p);
    let (lo, hi) = (0.05, 3.0);
    let a = polar_integral(&s, lo, hi);
    let b = s.band_variance(lo, hi);
    assert!((a / b - 1.0).abs() < 1e-3, "{a} vs {b}");
}

#[test]
fn deep_water_tma_equals_jonswap() {
    let deep = |kind| {
        Spectrum::new(&OceanParams {
            depth_m: 10_000.0,
            ..case22(kind)
        })
    };
    let (t, j) = (deep(SpectrumKind::Tma), deep(SpectrumKind::Jonswap));
    for i in 0..400 {
        let w = 0.2 * 1.02f64.powi(i);
        assert_eq!(t.s_omega(w), j.s_omega(w), "omega {w}");
    }
    for i in 0..100 {
        let k = 0.01 * 1.1f64.powi(i);
        assert_eq!(t.p_k(k * 0.6, k * 0.8), j.p_k(k * 0.6, k * 0.8));
    }
    assert!((t.total_variance() / j.total_variance() - 1.0).abs() < 1e-12);
}

#[test]
fn shallow_water_attenuates_tma() {
    let shallow = Spectrum::new(&OceanParams {
        depth_m: 5.0,
        ..case22(SpectrumKind::Tma)
    });
    let j = Spectrum::new(&OceanParams {
        depth_m: 5.0,
        ..case22(SpectrumKind::Jonswap)
    });
    let ratio = shallow.total_variance() / j.total_variance();
    assert!(ratio < 0.9 && ratio > 0.1, "{ratio}");
}

#[test]
fn pm_and_phillips_peak_where_stated() {
    for kind in [SpectrumKind::PiersonMoskowitz, SpectrumKind::Phillips] {
        let s = Spectrum::new(&case22(kind));
        let f = |r: f64| s.s_omega(s.omega_p * r);
        assert!(f(1.0) > f(0.99) && f(1.0) > f(1.01), "{kind:?}");
        assert!(s.total_variance() > 0.0);
    }
}

#[test]
fn energy_is_downwind() {
    let s = Spectrum::new(&OceanParams {
        wind_dir_deg: 90.0,
        ..case22(SpectrumKind::Tma)
    });
    let k = s.peak_wavenumber();
    // wind towards +z
    assert!(s.p_k(0.0, k) > 100.0 * s.p_k(k, 0.0));
    assert!(s.p_k(0.0, k) > 100.0 * s.p_k(0.0, -k));
}

#[test]
fn a_swell_holds_its_height_over_the_layers_and_spreads_around_its_direction() {
    // no wind-sea target: the swell holds its Hs outright over the layers' wavenumbers
    let p = OceanParams {
        rms_m: None,
        swell: vec![SwellParams {
            hs_m: 2.0,
            tp_s: 12.0,
            dir_deg: 120.0,
            spreading_s: 40.0,
            gamma: 5.0,
        }],
        ..OceanParams::default()
    };
    let s = Spectrum::new(&p);
    let (lo, hi) = (PI / p.layers[0].size_m, crate::ocean::nyquist(&p.layers[3]));
    let swell = s.part_variance(Part::Swell(0), lo, hi, |_| 1.0);
    assert!((swell - 0.25).abs() < 1e-9, "{swell}");
    // the whole sea is the wind sea plus the swell, over the plane as over omega
    let wind = s.part_variance(Part::Wind, lo, hi, |_| 1.0);
    let total = s.band_variance(lo, hi);
    assert!((total - wind - swell).abs() < 1e-12 * total);
    let polar = polar_integral(&s, lo, hi);
    assert!((polar / total - 1.0).abs() < 2e-3, "{polar} vs {total}");
    // its energy travels towards 120 degrees, not back
    let kp = s.swells[0].omega_p.powi(2) / G;
    let at = |deg: f64| {
        let a = deg.to_radians();
        s.p_k(kp * a.cos(), kp * a.sin())
    };
    assert!(at(120.0) > 1e3 * at(300.0) && at(120.0) > at(100.0));
    assert!((at(100.0) / at(140.0) - 1.0).abs() < 1e-9);
    // with a wind-sea target the swell's level stands to the wind sea's as the targets do
    let q = OceanParams {
        hs_m: Some(1.0),
        rms_m: None,
        ..p.clone()
    };
    let s = Spectrum::new(&q);
    let ratio = s.part_variance(Part::Swell(0), lo, hi, |_| 1.0)
        / s.part_variance(Part::Wind, lo, hi, |_| 1.0);
    assert!((ratio - 4.0).abs() < 1e-9, "{ratio}");
}

#[test]
fn a_peak_period_moves_the_wind_seas_peak_and_drops_the_fetch_note() {
    let p = OceanParams {
        tp_s: Some(8.0),
        ..OceanParams::default()
    };
    let s = Spectrum::new(&p);
    assert!((s.omega_p - TAU / 8.0).abs() < 1e-15);
    assert!(s.dimensionless_fetch().is_none());
    assert!(
        Spectrum::new(&OceanParams::default())
            .dimensionless_fetch()
            .is_some()
    );
}
