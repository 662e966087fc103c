//! Filtered normals against mapped ones: the same normal where the footprint resolves every
//! wave, the same image under a sky without a sun, and less noise under the sun.

use vastocean::accel::Ray;
use vastocean::config::{AnalyticSky, FilterLobe, NormalMode, Projection, SceneConfig, WrongSide};
use vastocean::ocean::Interp;
use vastocean::render::pipeline::{Prepared, prepare};
use vastocean::render::{Camera, SceneRef};

/// The default sea, a 256-pixel-wide band from 1 degree above the horizon to 6 below.
fn scene(sky: Option<AnalyticSky>) -> SceneConfig {
    let mut cfg = SceneConfig::default();
    cfg.camera.width = 256;
    cfg.camera.projection = Projection::Equirect {
        band_deg: Some((1.0, -6.0)),
    };
    if let Some(sky) = sky {
        cfg.sky.analytic = sky;
    }
    cfg
}

/// Mean luminance of the rows 0 to 5 degrees below the horizon, and its standard error.
fn band_mean(p: &Prepared, cfg: &SceneConfig) -> (f64, f64, Option<f64>) {
    let r = p.render(cfg, false).unwrap();
    let camera = Camera::new(cfg.camera.projection, cfg.camera.width, cfg.camera.aspect);
    let rows = camera.rows_between((0.0, -5.0));
    let w = camera.width;
    let (mut sum, mut var) = (0.0, 0.0);
    for &y in &rows {
        for x in 0..w {
            let px = r.film.image.pixels[y * w + x];
            sum += vastocean::color::luminance(px) as f64;
            var += r.film.var_y[y * w + x] as f64;
        }
    }
    let n = (rows.len() * w) as f64;
    (sum / n, var.sqrt() / n, r.report.noise_rms_sea)
}

fn with(cfg: &SceneConfig, normals: NormalMode, lobe: FilterLobe, spp: u32) -> SceneConfig {
    let mut c = cfg.clone();
    c.render.normals = normals;
    c.render.filter_lobe = lobe;
    c.render.spp = spp;
    c
}

#[test]
fn filtered_normals_converge_to_the_mapped_image_under_a_sky_without_a_sun() {
    // A gradient sky: no glints, so a few samples converge. The `mapped` lobe's Gaussian slopes
    // are the ones the lookup reads (bilinear reads keep some 11 % less slope variance than the
    // sea's), which matters most under `terminate`, where the slopes decide how many paths end:
    // with the sea's slopes the lobe is 3.6 % darker there (0.377 against 0.391), which the
    // tolerance of half a per cent plus four standard errors (0.011) refuses. The smith lobe
    // models the sea's slopes (docs/filtered.md).
    let sky = AnalyticSky::Gradient {
        zenith: [0.3, 0.5, 1.0],
        horizon: [1.0, 1.0, 1.0],
    };
    for (policy, interp) in [
        (WrongSide::Bend, Interp::Bilinear),
        (WrongSide::Terminate, Interp::Bilinear),
        (WrongSide::Terminate, Interp::VariancePreserving),
        // the read tables of prefiltered slopes are the sea's own
        (WrongSide::Terminate, Interp::Prefiltered),
    ] {
        let mut cfg = scene(Some(sky));
        cfg.render.wrong_side = policy;
        cfg.ocean.interp = interp;
        let p = prepare(&cfg).unwrap();
        let (mapped, se_m, _) =
            band_mean(&p, &with(&cfg, NormalMode::Mapped, FilterLobe::Mapped, 32));
        let (filtered, se_f, _) = band_mean(
            &p,
            &with(&cfg, NormalMode::Filtered, FilterLobe::Mapped, 32),
        );
        let (smith, _, _) = band_mean(&p, &with(&cfg, NormalMode::Filtered, FilterLobe::Smith, 32));
        let tolerance = 0.005 * mapped + 4.0 * (se_m * se_m + se_f * se_f).sqrt();
        assert!(
            (filtered - mapped).abs() < tolerance,
            "{policy}, {interp:?} reads: filtered {filtered} vs mapped {mapped} (+- {tolerance})"
        );
        // Smith's masking loses light that `bend` keeps; `terminate` loses more (measured here:
        // mapped 0.61, Smith 0.47 under `bend`; mapped 0.38, Smith 0.43 under `terminate`)
        if policy == WrongSide::Bend {
            assert!(
                smith < 0.95 * mapped,
                "smith {smith} vs mapped {mapped}: masking loses light"
            );
        } else {
            assert!(
                smith > mapped,
                "smith {smith} vs mapped {mapped}: terminate ends more light than masking"
            );
        }
    }
}

#[test]
fn a_footprint_that_resolves_every_wave_gives_the_mapped_normal() {
    let cfg = scene(None);
    let p = prepare(&cfg).unwrap();
    let slopes = p.ocean.read_slopes();
    let scene = SceneRef {
        accel: p.accel.as_ref(),
        skip_slope: None,
        skip_above_y: None,
        predict_camera_hits: false,
        ocean: Some(p.ocean.sampler([0.0, 0.0]).with_levels(p.ocean.levels())),
        slopes: Some(slopes),
        sun: p.sky.sun_light(),
        earth_radius_m: 6_371_000.0,
        sky: &p.sky,
        objects: None,
    };
    let mut checked = 0;
    for i in 0..64 {
        let a = i as f32 * 0.1;
        let dir = glam::Vec3::new(a.cos(), -0.2 - 0.01 * i as f32, a.sin()).normalize();
        let ray = Ray::new([0.0, cfg.camera.height_m as f32, 0.0], dir.to_array());
        let Some(hit) = p.accel.intersect(&ray) else {
            continue;
        };
        let mapped = scene.normal_at(&hit, NormalMode::Mapped);
        let (n, cov) = scene.filtered_normal_at(&hit, 0.0, NormalMode::Filtered);
        assert_eq!(n, mapped);
        assert_eq!(cov, [0.0; 3]);
        // A footprint of a metre, bounded by paper-low's 0.9 m triangles near the camera to a
        // std of 3 cm, leaves much of the finest layer's slopes unresolved, and the normal
        // keeps the rest.
        let (wide, cov) = scene.filtered_normal_at(&hit, 1.0, NormalMode::Filtered);
        assert!(cov[0] + cov[2] > 1e-3, "{cov:?}");
        assert!(wide != mapped && wide.is_normalized());
        checked += 1;
    }
    assert!(checked > 50);
}

#[test]
fn on_a_mesh_finer_than_the_footprint_the_lobe_leaves_the_waves_the_mesh_holds() {
    // Triangles 10 cm across out to 18 m, doubling beyond, and the band 1 to 6 degrees below
    // the horizon (hits 19 to 115 m away) 256 pixels wide: each pixel's footprint spans 0.5 to
    // 3 m, so the mesh holds waves far below it. Where a grazing ray lands then depends on
    // the facets it sees, and the mapped normal there follows them; a lobe drawn by area that
    // took those waves would lose that (measured on this scene without the mesh's bound:
    // filtered normals 10 % darker than mapped ones, 0.363 against 0.404).
    let sky = AnalyticSky::Gradient {
        zenith: [0.3, 0.5, 1.0],
        horizon: [1.0, 1.0, 1.0],
    };
    let mut cfg = scene(Some(sky));
    cfg.camera.projection = Projection::Equirect {
        band_deg: Some((-1.0, -6.0)),
    };
    cfg.lod.preset = vastocean::config::LodChoice::Custom;
    cfg.lod.near_size_m = Some(0.1);
    cfg.lod.double_distance_m = Some(18.0);
    cfg.lod.max_distance_m = Some(150.0);
    let p = prepare(&cfg).unwrap();
    let rows = Camera::new(cfg.camera.projection, cfg.camera.width, cfg.camera.aspect)
        .rows_between((-1.0, -6.0));
    let mean = |normals: NormalMode| {
        let c = with(&cfg, normals, FilterLobe::Mapped, 32);
        let r = p.render(&c, false).unwrap();
        let w = c.camera.width;
        let (mut sum, mut var) = (0.0, 0.0);
        for &y in &rows {
            for x in 0..w {
                sum += vastocean::color::luminance(r.film.image.pixels[y * w + x]) as f64;
                var += r.film.var_y[y * w + x] as f64;
            }
        }
        let n = (rows.len() * w) as f64;
        (sum / n, var.sqrt() / n)
    };
    let ((mapped, se_m), (filtered, se_f)) = (mean(NormalMode::Mapped), mean(NormalMode::Filtered));
    let tolerance = 0.005 * mapped + 4.0 * (se_m * se_m + se_f * se_f).sqrt();
    assert!(
        (filtered - mapped).abs() < tolerance,
        "filtered {filtered} vs mapped {mapped} (+- {tolerance})"
    );
}

#[test]
fn one_or_eight_sun_samples_give_the_same_glitter() {
    // The default sky's sun 3 degrees up over the band 0 to 5 degrees below the horizon, where
    // the glitter is: eight samples where the lobe may reflect the sun (one elsewhere) against
    // one everywhere, independent seeds, the same band to within four standard errors (about
    // 2 % here). How the two sides of the weights share the sun is checked where it matters,
    // on a lobe as narrow as the disc (`render::bsdf` tests).
    let cfg = scene(None);
    let p = prepare(&cfg).unwrap();
    let mut one = with(&cfg, NormalMode::Filtered, FilterLobe::Mapped, 64);
    one.render.sun_samples = 1;
    let mut eight = one.clone();
    eight.render.sun_samples = 8;
    eight.render.seed = one.render.seed + 1;
    let (a, se_a, _) = band_mean(&p, &one);
    let (b, se_b, _) = band_mean(&p, &eight);
    let se = (se_a * se_a + se_b * se_b).sqrt();
    assert!(
        (a - b).abs() < 4.0 * se,
        "one sample {a} +- {se_a}, eight {b} +- {se_b}"
    );
    eprintln!("one sample {a} +- {se_a}, eight {b} +- {se_b}");
}
