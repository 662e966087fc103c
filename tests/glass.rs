//! Glass objects (`material = "glass"`): a clear slab seen straight down passes the sea
//! below it by the Fresnel equations' transmission, with its internal reflections summed; a
//! mesh wound inward is noticed.

use vastocean::config::{AnalyticSky, Material, ObjectConfig};
use vastocean::render::pipeline::prepare;

/// A closed box 2a wide and 2t thick about the origin, faces wound outward (or, `inward`,
/// the other way), as OBJ text.
fn slab_obj(a: f64, t: f64, inward: bool) -> String {
    let mut s = String::new();
    for (x, y, z) in [
        (-a, -t, -a),
        (a, -t, -a),
        (a, -t, a),
        (-a, -t, a),
        (-a, t, -a),
        (a, t, -a),
        (a, t, a),
        (-a, t, a),
    ] {
        s += &format!("v {x} {y} {z}\n");
    }
    for f in [
        "5 8 7", "5 7 6", "1 2 3", "1 3 4", "1 5 6", "1 6 2", "4 3 7", "4 7 8", "1 4 8", "1 8 5",
        "2 6 7", "2 7 3",
    ] {
        let f: Vec<&str> = f.split(' ').collect();
        let f = if inward {
            [f[0], f[2], f[1]]
        } else {
            [f[0], f[1], f[2]]
        };
        s += &format!("f {}\n", f.join(" "));
    }
    s
}

/// A pinhole 260 m up looking straight down through a 20 m wide, 1 m thick slab held 200 m
/// up (or not), under a uniform sky of 1: (mean luminance, its standard error, the render's
/// warnings).
fn through_slab(slab: Option<&std::path::Path>, ior: f64) -> (f64, f64, Vec<String>) {
    let mut cfg = crate::common::looking_down(260.0, 2.0, 48, 256);
    cfg.sky.analytic = AnalyticSky::Uniform { radiance: [1.0; 3] };
    if let Some(mesh) = slab {
        cfg.objects = vec![ObjectConfig {
            mesh: mesh.to_path_buf(),
            float: false,
            height_m: 200.0,
            material: Material::Glass,
            albedo: [1.0; 3],
            roughness: 0.001,
            ior,
            ..ObjectConfig::default()
        }];
    }
    let r = prepare(&cfg).unwrap().render(&cfg, false).unwrap();
    assert_eq!(r.report.nan_count, 0);
    let (mean, se) = crate::common::mean_luminance_se(&r);
    (mean, se, r.report.warnings)
}

/// Through a clear slab at normal incidence the sea is seen with the slab's transmission
/// T = (1 - R) / (1 + R) (both faces and every internal reflection; R = ((n - 1) / (n + 1))^2),
/// and the sky of 1 it reflects fills the rest: L = T L_sea + (1 - T). At n = 1 the slab is
/// not there at all.
#[test]
fn a_glass_slab_passes_the_sea_by_the_fresnel_equations() {
    let dir = std::env::temp_dir().join(format!("vastocean-glass-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mesh = dir.join("slab.obj");
    std::fs::write(&mesh, slab_obj(10.0, 0.5, false)).unwrap();
    let (sea, sea_se, _) = through_slab(None, 1.5);
    for ior in [1.5, 2.4] {
        let (glass, glass_se, warnings) = through_slab(Some(&mesh), ior);
        assert!(warnings.is_empty(), "{warnings:?}");
        let r = ((ior - 1.0) / (ior + 1.0)).powi(2);
        let t = (1.0 - r) / (1.0 + r);
        let expected = t * sea + (1.0 - t);
        let se = (glass_se.powi(2) + (t * sea_se).powi(2)).sqrt();
        assert!(
            (glass - expected).abs() < 4.0 * se + 0.002,
            "n = {ior}: through the slab {glass:.5} +- {glass_se:.5}, T L_sea + 1 - T = \
             {expected:.5} (sea {sea:.5} +- {sea_se:.5}, T {t:.4})"
        );
        assert!(
            (glass - sea).abs() > 4.0 * se,
            "the slab is seen: {glass} {sea}"
        );
    }
    let (air, air_se, _) = through_slab(Some(&mesh), 1.0);
    assert!(
        (air - sea).abs() < 4.0 * (air_se.powi(2) + sea_se.powi(2)).sqrt() + 1e-4,
        "a slab of n = 1 is not there: {air} against {sea}"
    );
    // wound inward, rays that think they left it travel on inside it and out of its far side
    // flagged as inside: they meet nothing, are counted, and the render says why
    let inward = dir.join("inward.obj");
    std::fs::write(&inward, slab_obj(10.0, 0.5, true)).unwrap();
    let (_, _, warnings) = through_slab(Some(&inward), 1.5);
    assert!(
        warnings.iter().any(|w| w.contains("wound outward")),
        "{warnings:?}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
