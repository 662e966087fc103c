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
