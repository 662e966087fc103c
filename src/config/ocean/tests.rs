use super::*;

fn err_of(f: impl FnOnce(&mut OceanParams)) -> String {
    let mut p = OceanParams::default();
    f(&mut p);
    p.validate().expect_err("must be rejected").to_string()
}

#[test]
fn the_partitions_sum_to_one_and_the_default_overlaps_at_the_peak() {
    for p in [OceanParams::default(), OceanParams::tiling_layers()] {
        p.validate().unwrap();
        let part = p.partition();
        let (lo, hi) = part.covered();
        for j in 0..=400 {
            let k = lo * (hi / lo).powf((j as f64 + 0.5) / 401.0);
            let w: Vec<f64> = (0..p.layers.len()).map(|i| part.weight(i, k)).collect();
            let sum: f64 = w.iter().sum();
            assert!((sum - 1.0).abs() < 1e-12, "{:?} k={k}: {w:?}", p.layering);
            assert!(w.iter().all(|&x| (0.0..=1.0).contains(&x)));
        }
    }
    // case 22's 54 m peak: half in each of the two long layers, none in the others
    let part = OceanParams::default().partition();
    let kp = std::f64::consts::TAU / 54.0;
    assert!((part.weight(0, kp) - 0.5).abs() < 1e-12 && (part.weight(1, kp) - 0.5).abs() < 1e-12);
    // and a gap between layers is refused, naming the layer
    let mut p = OceanParams::default();
    p.layers[2].size_m = 20.0;
    let e = p.validate().unwrap_err().to_string();
    assert!(
        e.starts_with("ocean.layers[2].size_m must be large enough that the layers leave no gap"),
        "{e}"
    );
    p.layers[2].size_m = 20_000.0;
    let e = p.validate().unwrap_err().to_string();
    assert!(e.contains("coarsest first"), "{e}");
}

#[test]
fn default_is_valid_and_bands_tile() {
    let p = OceanParams::tiling_layers();
    p.validate().unwrap();
    let b = p.bands();
    assert_eq!(b.len(), 3);
    for i in 1..b.len() {
        assert_eq!(b[i - 1].1, b[i].0);
    }
    assert!(b.iter().all(|(lo, hi)| lo < hi));
    // finest spacing 2-3 cm, as the paper suggests for 3 cm triangles
    let l = p.layers.last().unwrap();
    let dx = l.size_m / l.n as f64;
    assert!((0.02..=0.03).contains(&dx), "{dx}");
}

#[test]
fn a_height_target_is_given_once_as_rms_or_as_hs() {
    let hs = OceanParams {
        rms_m: None,
        hs_m: Some(1.2),
        ..OceanParams::default()
    };
    hs.validate().unwrap();
    assert_eq!(hs.rms_target(), Some(0.3));
    assert_eq!(OceanParams::default().rms_target(), Some(0.225));
    let e = err_of(|p| p.hs_m = Some(1.2));
    assert!(
        e.starts_with("ocean.hs_m must be given without ocean.rms_m"),
        "{e}"
    );
    let e = err_of(|p| {
        p.rms_m = None;
        p.hs_m = Some(-1.0)
    });
    assert!(e.starts_with("ocean.hs_m must be finite and > 0"), "{e}");
}

#[test]
fn bad_input_names_the_parameter() {
    assert_eq!(
        err_of(|p| p.wind_speed = -1.0),
        "ocean.wind_speed must be finite and > 0 (got -1)"
    );
    assert!(err_of(|p| p.wind_speed = 0.0).starts_with("ocean.wind_speed"));
    assert!(
        err_of(|p| p.wind_speed = f64::NAN)
            .contains("ocean.wind_speed must be finite and > 0 (got NaN)")
    );
    assert!(err_of(|p| p.fetch_km = 0.0).starts_with("ocean.fetch_km"));
    assert!(err_of(|p| p.fetch_km = f64::INFINITY).starts_with("ocean.fetch_km"));
    assert!(err_of(|p| p.depth_m = -3.0).starts_with("ocean.depth_m"));
    assert!(err_of(|p| p.depth_m = f64::NAN).starts_with("ocean.depth_m"));
    assert!(err_of(|p| p.rms_m = Some(0.0)).starts_with("ocean.rms_m"));
    assert!(err_of(|p| p.gamma = 0.5).starts_with("ocean.gamma"));
    assert!(err_of(|p| p.choppiness = f64::NAN).starts_with("ocean.choppiness"));
    assert!(err_of(|p| p.wind_dir_deg = f64::NAN).starts_with("ocean.wind_dir_deg"));
    assert!(err_of(|p| p.time_s = f64::INFINITY).starts_with("ocean.time_s"));
    assert!(err_of(|p| p.layers.clear()).starts_with("ocean.layers must be"));
    assert!(
        err_of(|p| p.layers[1].n = 500).starts_with("ocean.layers[1].n must be a power of two")
    );
    assert!(err_of(|p| p.layers[0].n = 8).starts_with("ocean.layers[0].n"));
    assert!(
        err_of(|p| p.layers[2].size_m = -5.83).starts_with("ocean.layers[2].size_m must be finite")
    );
    let disjoint = |f: fn(&mut OceanParams)| {
        let mut p = OceanParams::tiling_layers();
        f(&mut p);
        p.validate().expect_err("must be rejected").to_string()
    };
    // a finer layer too small to start its band at the coarser layer's edge
    assert!(
        disjoint(|p| p.layers[1].size_m = 3.0).starts_with("ocean.layers[1].size_m must be in [")
    );
    // or so large that its band would be nearly empty
    assert!(
        disjoint(|p| p.layers[2].size_m = 40.0).starts_with("ocean.layers[2].size_m must be in [")
    );
    assert!(
        err_of(|p| p.spreading_cap = Some(-1.0))
            .starts_with("ocean.spreading_cap must be finite and > 0")
    );
    assert!(
        err_of(|p| {
            p.spreading_cap = Some(75.0);
            p.spreading = SpreadingKind::Cos2;
        })
        .starts_with("ocean.spreading_cap must be set only with spreading = \"mitsuyasu\"")
    );
}

#[test]
fn serde_round_trip_and_unknown_keys() {
    let p = OceanParams::default();
    let json = serde_json::to_string(&p).unwrap();
    let q: OceanParams = serde_json::from_str(&json).unwrap();
    assert_eq!(p, q);
    let partial: OceanParams =
        toml::from_str("wind_speed = 2.38\nspectrum = \"pierson-moskowitz\"\n").unwrap();
    assert_eq!(partial.wind_speed, 2.38);
    assert_eq!(partial.spectrum, SpectrumKind::PiersonMoskowitz);
    assert_eq!(partial.rms_m, None);
    assert_eq!(partial.layers, p.layers);
    let bad = toml::from_str::<OceanParams>("wind_sped = 3.0\n")
        .unwrap_err()
        .to_string();
    assert!(bad.contains("wind_sped"), "{bad}");
    let bad = toml::from_str::<OceanParams>("[[layers]]\nsize_m = 10.0\nn = 64\nextra = 1\n")
        .unwrap_err()
        .to_string();
    assert!(bad.contains("extra"), "{bad}");
}

#[test]
fn every_preset_resolves_to_its_published_wind_and_height() {
    for n in 1..=12u8 {
        let mut p = OceanParams {
            beaufort: Some(n),
            ..OceanParams::default()
        };
        p.apply_preset();
        p.validate().unwrap();
        let row = Preset::Beaufort(n).row().unwrap();
        let (lo, hi) = row.wind_range_m_s.unwrap();
        assert!(
            (lo..=hi).contains(&p.wind_speed),
            "force {n}: {}",
            p.wind_speed
        );
        // the wind sea and the background swell hold the table's height together
        let total = p.rms_target().unwrap() * 4.0;
        assert!(
            (total - row.hs_m).abs() < 1e-12 * row.hs_m,
            "force {n}: {total}"
        );
        // a wind sea never steeper than full development allows
        let wind_hs = p.hs_m.unwrap();
        assert!(wind_hs <= sea_state::fully_developed_hs(p.wind_speed) * (1.0 + 1e-12));
        // the light winds need the swell, the strong ones are fetch-limited wind seas
        assert_eq!(!p.swell.is_empty(), n <= 5, "force {n}: {:?}", p.swell);
        assert!(
            p.fetch_km
                <= sea_state::FULLY_DEVELOPED_FETCH * p.wind_speed.powi(2) / 9810.0 * (1.0 + 1e-12)
        );
        // applying twice changes nothing
        let again = {
            let mut q = p.clone();
            q.apply_preset();
            q
        };
        assert_eq!(again, p);
    }
    for n in 1..=9u8 {
        let mut p = OceanParams {
            douglas: Some(n),
            ..OceanParams::default()
        };
        p.apply_preset();
        p.validate().unwrap();
        let row = Preset::Douglas(n).row().unwrap();
        let (lo, hi) = row.height_range_m;
        let hs = p.hs_m.unwrap();
        assert!(hs >= lo && hs <= hi.max(lo), "state {n}: {hs}");
        assert!(p.swell.is_empty(), "state {n}");
        // a fully developed sea of that height
        assert!((sea_state::fully_developed_hs(p.wind_speed) - hs).abs() < 1e-9 * hs);
    }
}

#[test]
fn a_preset_and_the_keys_it_sets_are_refused_together() {
    let preset = |f: &dyn Fn(&mut OceanParams)| {
        let mut p = OceanParams {
            beaufort: Some(3),
            ..OceanParams::default()
        };
        p.apply_preset();
        f(&mut p);
        p.validate().map_err(|e| e.to_string())
    };
    assert!(preset(&|_| {}).is_ok());
    let e = preset(&|p| p.wind_speed = 7.0).unwrap_err();
    assert!(
        e.starts_with("ocean.wind_speed must be left to ocean.beaufort = 3"),
        "{e}"
    );
    let e = preset(&|p| p.rms_m = Some(0.1)).unwrap_err();
    assert!(
        e.starts_with("ocean.hs_m") || e.starts_with("ocean.rms_m"),
        "{e}"
    );
    let e = preset(&|p| p.douglas = Some(2)).unwrap_err();
    assert!(
        e.starts_with("ocean.douglas must be given without ocean.beaufort"),
        "{e}"
    );
    let e = preset(&|p| {
        p.swell.remove(0);
    })
    .unwrap_err();
    assert!(e.starts_with("ocean.swell[0]"), "{e}");
    // the scene's own swells go after the background swell, and clearing keeps them
    let mut p = OceanParams {
        beaufort: Some(2),
        swell: vec![SwellParams::new(1.0, 12.0, 90.0)],
        ..OceanParams::default()
    };
    p.apply_preset();
    p.validate().unwrap();
    assert_eq!(p.swell.len(), 2);
    p.clear_preset();
    assert_eq!(p.swell, vec![SwellParams::new(1.0, 12.0, 90.0)]);
    assert!(
        err_of(|p| p.beaufort = Some(13))
            .starts_with("ocean.beaufort must be a Beaufort force in 1..=12")
    );
    assert!(
        err_of(|p| p.douglas = Some(0)).starts_with("ocean.douglas must be a Douglas sea state")
    );
}

#[test]
fn a_peak_period_needs_a_height_and_a_swell_its_ranges() {
    assert!(err_of(|p| (p.tp_s, p.rms_m) = (Some(8.0), None)).contains("with a height target"));
    assert!(err_of(|p| p.tp_s = Some(0.1)).starts_with("ocean.tp_s must be in (0.5, 30]"));
    assert!(
        err_of(|p| (p.tp_s, p.spectrum) = (Some(8.0), SpectrumKind::PiersonMoskowitz))
            .contains("tma")
    );
    let swell = |f: &dyn Fn(&mut SwellParams)| {
        err_of(|p| {
            let mut s = SwellParams::new(1.0, 10.0, 0.0);
            f(&mut s);
            p.swell = vec![s];
        })
    };
    assert!(swell(&|s| s.hs_m = 0.0).starts_with("ocean.swell[0].hs_m must be in (0, 25]"));
    assert!(swell(&|s| s.tp_s = f64::NAN).starts_with("ocean.swell[0].tp_s"));
    assert!(swell(&|s| s.dir_deg = f64::INFINITY).starts_with("ocean.swell[0].dir_deg"));
    assert!(swell(&|s| s.spreading_s = -1.0).starts_with("ocean.swell[0].spreading_s"));
    assert!(swell(&|s| s.gamma = 0.5).starts_with("ocean.swell[0].gamma"));
    assert!(
        err_of(|p| p.swell = vec![SwellParams::new(1.0, 10.0, 0.0); 5])
            .starts_with("ocean.swell must be at most 4")
    );
    // the target of a sea with swells is the partitions' variances summed
    let p = OceanParams {
        rms_m: None,
        hs_m: Some(3.0),
        swell: vec![SwellParams::new(4.0, 12.0, 0.0)],
        ..OceanParams::default()
    };
    assert!((p.rms_target().unwrap() - 5.0 / 4.0).abs() < 1e-15);
    assert_eq!(p.wind_rms_target(), Some(0.75));
}

#[test]
fn auto_layers_follow_the_peak_and_are_valid_for_every_peak() {
    // the default sea (a 54 m peak) gets exactly the default layers
    let mut p = OceanParams {
        layers: Vec::new(),
        ..OceanParams::default()
    };
    p.resolve_layers();
    assert!(p.layers_auto);
    assert_eq!(p.layers, OceanParams::default().layers);
    // every peak from 0.3 m to 300 m gets layers that validate, in three tiers
    let mut tiers = std::collections::BTreeSet::new();
    for i in 0..=60 {
        let tp = 0.55 * 1.1f64.powi(i);
        let mut p = OceanParams {
            tp_s: Some(tp.min(30.0)),
            layers_auto: true,
            ..OceanParams::default()
        };
        p.resolve_layers();
        p.validate()
            .unwrap_or_else(|e| panic!("peak {} m: {e}", p.shortest_peak_wavelength()));
        let peak = p.shortest_peak_wavelength();
        let top = p.layers[2].size_m;
        tiers.insert(p.layers.len());
        if (auto::MIN_MID_PEAK_M..auto::SHORT_PEAK_M).contains(&peak) {
            // five mid layers of 24-34 peaks, texels of 1/30 of it
            assert_eq!(p.layers.len(), 8, "{peak}");
            assert!(top / peak > 33.0 && p.layers[6].size_m / peak > 24.0);
        } else if (auto::SHORT_PEAK_M..auto::LONG_PEAK_M).contains(&peak) {
            assert_eq!((p.layers[0].n, top), (4096, 20.9), "{peak}");
        } else {
            assert_eq!(p.layers, OceanParams::default().layers, "{peak}");
        }
    }
    assert_eq!(tiers.len(), 2, "{tiers:?}"); // 8 layers, or 4 (two kinds)
    // explicit layers are kept
    let mut p = OceanParams::tiling_layers();
    p.resolve_layers();
    assert_eq!(p.layers, OceanParams::tiling_layers().layers);
    let mut p = OceanParams {
        beaufort: Some(3),
        layers_auto: true,
        ..OceanParams::default()
    };
    p.apply_preset();
    p.resolve_layers();
    assert_eq!(p.layers[0].n, 4096, "Beaufort 3's 17 m peak");
}
