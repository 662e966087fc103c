//! Unit tests of the sky: lookups, the dome, the analytic skies and their irradiance.

use super::*;
use glam::DVec3;

use super::analytic::{SUN_COLOUR, acos, exp};

#[test]
fn inline_acos_and_exp_agree_with_libm() {
    let (mut worst_acos, mut worst_exp) = (0f64, 0f64);
    let n = 200_000;
    for i in 0..=n {
        for x in [-1.0 + 2.0 * i as f32 / n as f32, 1.0 - i as f32 * 1e-7] {
            worst_acos = worst_acos.max((acos(x) as f64 - (x as f64).acos()).abs());
        }
        let x = -87.0 * i as f32 / n as f32;
        let want = (x as f64).exp();
        worst_exp = worst_exp.max((exp(x) as f64 - want).abs() / want);
    }
    assert!(worst_acos < 3e-7, "{worst_acos}");
    // 2 ulp: f32's epsilon is 1.19e-7
    assert!(worst_exp < 2.4e-7, "{worst_exp}");
    assert_eq!((acos(1.0), exp(0.0)), (0.0, 1.0));
    assert_eq!(acos(-1.0), std::f32::consts::PI);
    assert!((acos(0.0) - std::f32::consts::FRAC_PI_2).abs() < 1e-7);
    assert!(exp(-1000.0) > 0.0 && exp(-1000.0) < 1e-37);
}

#[test]
fn sky_lookups_in_batches_equal_single_lookups() {
    let physical = AnalyticSky::Clear {
        sun_elevation_deg: 3.0,
        sun_azimuth_deg: 40.0,
        turbidity: 2.5,
    };
    let hand_made = AnalyticSky::HandMadeClear {
        sun_elevation_deg: 3.0,
        sun_azimuth_deg: 40.0,
        sun_radiance: 5e4,
        sky_scale: 1.0,
    };
    for model in [physical, hand_made] {
        batches_equal_single_lookups(model);
    }
}

fn batches_equal_single_lookups(model: AnalyticSky) {
    let mut sky = Sky::analytic(model);
    sky.dome_altitude_m = Some(200_000.0);
    let sun = sky_sun(&sky);
    let mut rng = crate::rng::Rng::keyed(&[11]);
    let camera = Vec3::new(0.0, sky.camera_height_m as f32, 0.0);
    // From the camera and from far hits; some through the sun's disc.
    let rays: Vec<(Vec3, Vec3)> = (0..37)
        .map(|i| {
            let org = if i % 3 == 0 {
                camera
            } else {
                Vec3::new(
                    rng.range(-5e3, 5e3),
                    rng.range(-1.0, 1.0),
                    rng.range(-5e3, 5e3),
                )
            };
            // (and some below the horizon, which the physical sky continues)
            let d = if i % 4 == 0 {
                sun + 1e-3 * Vec3::new(rng.range(-1.0, 1.0), 0.0, rng.range(-1.0, 1.0))
            } else {
                Vec3::new(
                    rng.range(-1.0, 1.0),
                    rng.range(-0.2, 1.0),
                    rng.range(-1.0, 1.0),
                )
            };
            (org, d.normalize())
        })
        .collect();
    let (orgs, dirs): (Vec<Vec3>, Vec<Vec3>) = rays.iter().copied().unzip();
    // The same sky as a map: its lanes compute where to read instead.
    let mut map = sky.clone();
    map.source = SkySource::Map(rasterize(&model, 256));
    for sky in [sky, map] {
        let mut many = vec![Vec3::ZERO; rays.len()];
        sky.radiance_many(&orgs, &dirs, &mut many);
        let mut bright = 0;
        for ((o, d), l) in rays.iter().zip(&many) {
            let alone = sky.radiance(*o, *d);
            assert_eq!(
                alone.to_array().map(f32::to_bits),
                l.to_array().map(f32::to_bits)
            );
            assert!(alone.is_finite() && alone.min_element() >= 0.0, "{alone}");
            bright += usize::from(alone.x > 1e2);
        }
        // (the analytic sun's disc is met; the map's texels are wider than it)
        let analytic = matches!(sky.source, SkySource::Analytic { .. });
        assert!(!analytic || (bright > 2 && bright < rays.len()), "{bright}");
        // The lanes see the dome: a far origin looks elsewhere than the camera does.
        let far = Vec3::new(0.0, 0.5, 150e3);
        let mut l = [Vec3::ZERO; 2];
        let up = Vec3::new(0.0, 0.05, 1.0).normalize();
        sky.radiance_many(&[camera, far], &[up, up], &mut l);
        assert_ne!(l[0], l[1]);
    }
}

fn sky_sun(sky: &Sky) -> Vec3 {
    match &sky.source {
        SkySource::Analytic { model, .. } => model.sun_direction(),
        SkySource::Map(_) => unreachable!(),
    }
}

#[test]
fn dome_direction_from_the_camera_is_the_ray_direction() {
    let mut sky = Sky::analytic(AnalyticSky::default());
    sky.dome_altitude_m = Some(200_000.0);
    let d = Vec3::new(0.6, 0.0, 0.8);
    let got = sky.dome_direction(Vec3::new(0.0, 2.0, 0.0), d, 200_000.0);
    assert!((got - d).length() < 1e-6);
    // From 5 km away, a horizontal ray meets the dome at a point the camera sees slightly
    // off the ray direction: parallax.
    let got = sky.dome_direction(Vec3::new(0.0, 0.0, 5000.0), Vec3::X, 200_000.0);
    assert!(got.z > 0.0 && (got - Vec3::X).length() < 0.01);
}

#[test]
fn dome_direction_in_f32_matches_the_f64_intersection() {
    let mut sky = Sky::analytic(AnalyticSky::default());
    // The sphere intersection in f64 about the earth's centre.
    let reference = |org: Vec3, dir: Vec3, alt: f64| {
        let r = sky.earth_radius_m;
        let o = org.as_dvec3() + DVec3::new(0.0, r, 0.0);
        let d = dir.as_dvec3();
        let (b, c) = (o.dot(d), o.length_squared() - (r + alt) * (r + alt));
        let q = o + (-b + (b * b - c).sqrt()) * d;
        (q - DVec3::new(0.0, sky.camera_height_m + r, 0.0)).normalize()
    };
    for (alt, bound) in [(200_000.0, 5e-7), (1_000.0, 5e-6)] {
        sky.dome_altitude_m = Some(alt);
        let mut rng = crate::rng::Rng::keyed(&[7]);
        let mut worst = 0f64;
        for _ in 0..20_000 {
            let mut u = || 2.0 * rng.f32() - 1.0;
            let org = Vec3::new(8000.0 * u(), 0.5 * u(), 8000.0 * u());
            // upwards, from grazing to the zenith, and a few downwards (they meet the dome
            // through the earth: still a well-defined far root)
            let dir = Vec3::new(u(), 0.3 * u() + 0.05, u()).normalize();
            let got = sky.dome_direction(org, dir, alt).as_dvec3();
            worst = worst.max(got.angle_between(reference(org, dir, alt)));
        }
        assert!(worst < bound, "{alt} m: {worst}");
    }
}

#[test]
fn map_lookup_follows_the_camera_convention() {
    let mut img = RgbImage::new(8, 4);
    img.pixels[4] = [1.0, 0.0, 0.0]; // row 0 (top), column 4 (azimuth 180 degrees, +x is column 0)
    img.pixels[8 * 2 + 2] = [0.0, 1.0, 0.0]; // row 2 (just below the horizon), azimuth 90 = +z
    let up_back = Vec3::new(-0.3, 0.95, 0.0).normalize();
    let c = lookup(&img, up_back);
    assert!(c.x > 0.2, "{c}");
    let below_z = Vec3::new(0.0, -0.3, 1.0).normalize();
    assert!(lookup(&img, below_z).y > 0.3);
}

#[test]
fn map_lookup_wraps_at_the_seam() {
    // Column 0 is bright, the last column dark: along +x (azimuth 0, the seam) the lookup
    // sits halfway between them; a little either side it leans to its own side.
    let mut img = RgbImage::new(8, 4);
    for y in 0..4 {
        img.pixels[y * 8] = [1.0; 3];
    }
    let at = |az: f32| lookup(&img, Vec3::new(az.cos(), 0.0, az.sin())).x;
    assert!((at(0.0) - 0.5).abs() < 1e-6, "{}", at(0.0));
    let quarter_texel = std::f32::consts::TAU / 32.0;
    assert!(
        (at(quarter_texel) - 0.75).abs() < 1e-5,
        "{}",
        at(quarter_texel)
    );
    assert!(
        (at(-quarter_texel) - 0.25).abs() < 1e-5,
        "{}",
        at(-quarter_texel)
    );
    // Halfway round, far from the seam, nothing bright.
    assert_eq!(at(std::f32::consts::PI), 0.0);
}

#[test]
fn clear_sky_sun_disc_has_the_right_size() {
    let hand_made = AnalyticSky::HandMadeClear {
        sun_elevation_deg: 4.0,
        sun_azimuth_deg: 180.0,
        sun_radiance: 2000.0,
        sky_scale: 1.0,
    };
    for s in [AnalyticSky::default(), hand_made] {
        let sun = s.sun_direction();
        let disc = s.radiance(sun).x;
        let (el, az) = (sun.y.asin(), sun.z.atan2(sun.x));
        // step away from the sun centre in elevation
        let at = |off: f32| {
            s.radiance(Vec3::new(
                (el + off).cos() * az.cos(),
                (el + off).sin(),
                (el + off).cos() * az.sin(),
            ))
            .x
        };
        assert!(disc > 1e3 * s.radiance(Vec3::Y).x, "{disc}");
        assert!(at(0.9 * SUN_RADIUS_RAD) >= 0.99 * disc);
        assert!(at(1.1 * SUN_RADIUS_RAD) < 0.01 * disc);
        // 0.53 degrees across: the disc ends at the same angle on the other side
        assert!(
            at(-0.9 * SUN_RADIUS_RAD) >= 0.99 * disc && at(-1.1 * SUN_RADIUS_RAD) < 0.01 * disc
        );
    }
    assert!((2.0 * SUN_RADIUS_RAD.to_degrees() - 0.53).abs() < 0.001);
}

/// The built-in clear sky, evaluated per ray in f32 lanes, is the model `sky generate` renders
/// in f64: the Preetham sky within 1e-4 of its value (each channel relative to the brightest,
/// or to 1 % of the zenith's where that is larger), the sun disc's radiance that model's atmosphere transmits, and below the
/// horizon the horizon's sky at that azimuth.
#[test]
fn the_built_in_clear_sky_is_the_preetham_model() {
    use crate::sky::procedural::{SkyKind, SkyModel, SkyParams};
    let mut rng = crate::rng::Rng::keyed(&[37]);
    for (el, t) in [
        (3.0, 2.5),
        (-5.0, 2.0),
        (0.5, 6.0),
        (20.0, 1.7),
        (60.0, 10.0),
    ] {
        let az = rng.range(0.0, 360.0);
        let built_in = AnalyticSky::Clear {
            sun_elevation_deg: el,
            sun_azimuth_deg: az,
            turbidity: t,
        };
        let eval = Evaluator::new(&built_in);
        let model = SkyModel::new(&SkyParams {
            kind: SkyKind::Clear,
            sun_elevation_deg: el as f64,
            sun_azimuth_deg: az as f64,
            turbidity: t as f64,
            ..SkyParams::default()
        })
        .unwrap();
        let zenith = model.radiance(DVec3::Y).y;
        let mut worst = 0f64;
        for i in 0..20_000 {
            let d = if i % 5 == 0 {
                // near the sun, where the aureole is steepest
                (model.sun().as_vec3()
                    + 0.05
                        * Vec3::new(
                            rng.range(-1.0, 1.0),
                            rng.range(-1.0, 1.0),
                            rng.range(-1.0, 1.0),
                        ))
                .normalize()
            } else {
                Vec3::new(
                    rng.range(-1.0, 1.0),
                    rng.range(-0.3, 1.0),
                    rng.range(-1.0, 1.0),
                )
                .normalize()
            };
            let (got, want) = (eval.radiance(d).as_dvec3(), model.radiance(d.as_dvec3()));
            // The disc's rim is where f32 and f64 may disagree about one ray.
            let gamma = d.as_dvec3().angle_between(model.sun());
            if (gamma - SUN_RADIUS_RAD as f64).abs() < 1e-5 {
                continue;
            }
            let err = (got - want).abs().max_element() / want.max_element().max(0.01 * zenith);
            assert!(err < 1e-4, "sun {el} T {t} d {d}: {got} vs {want}");
            worst = worst.max(err);
        }
        assert!(worst > 0.0, "the lanes are not the f64 model itself");
    }
}

#[test]
fn irradiance_of_a_uniform_sky_is_pi_times_its_radiance() {
    let sky = Sky::analytic(AnalyticSky::Uniform {
        radiance: [0.5, 1.0, 2.0],
    });
    let e = sky.irradiance();
    for (got, l) in e.to_array().into_iter().zip([0.5f32, 1.0, 2.0]) {
        assert!(
            (got / (std::f32::consts::PI * l) - 1.0).abs() < 1e-4,
            "{got}"
        );
    }
    // A sky bright only below the horizon gives no irradiance.
    let mut img = RgbImage::new(64, 32);
    for p in &mut img.pixels[16 * 64..] {
        *p = [1.0; 3];
    }
    assert_eq!(map_irradiance(&img), Vec3::ZERO);
}

#[test]
fn the_sun_disc_adds_its_exact_irradiance() {
    let sun = |el: f32| AnalyticSky::HandMadeClear {
        sun_elevation_deg: el,
        sun_azimuth_deg: 70.0,
        sun_radiance: 1000.0,
        sky_scale: 0.0,
    };
    // (1 - cos R) cancels badly in f32.
    let omega = (std::f64::consts::TAU * (1.0 - (SUN_RADIUS_RAD as f64).cos())) as f32;
    // Well up: L x solid angle x sin(elevation) (exact to second order in the radius).
    let e = sun(30.0).irradiance();
    let want = 1000.0 * SUN_COLOUR * omega * 0.5;
    assert!(
        ((e - want) / want).abs().max_element() < 1e-3,
        "{e} vs {want}"
    );
    // A sun 0.1 degrees up, its disc 0.265 degrees in radius: part of it is below the
    // horizon and adds nothing.
    let low = sun(0.1).irradiance().x;
    let full = 1000.0 * omega * 0.1f32.to_radians().sin();
    assert!(low > 0.0 && low < 1.5 * full, "{low} vs {full}");
    // The physical sky's disc adds its transmitted radiance the same way: its irradiance
    // with the sun high is the sky's plus the disc's.
    let clear = AnalyticSky::Clear {
        sun_elevation_deg: 30.0,
        sun_azimuth_deg: 70.0,
        turbidity: 2.5,
    };
    let e = clear.irradiance();
    let disc = clear.radiance(clear.sun_direction()) * omega * 0.5;
    // the sun carries most of a clear day's light at 30 degrees
    let share = disc.y / e.y;
    assert!(share > 0.5 && share < 0.95, "{share}");
    // and the whole is what a fine map of the sky holds (its disc some 6 texels across)
    let fine = map_irradiance(&rasterize(&clear, 4096));
    assert!(((e - fine) / e).abs().max_element() < 0.05, "{e} vs {fine}");
}

#[test]
fn bad_maps_are_rejected_with_the_reason() {
    let p = Path::new("sky.exr");
    assert!(
        validate_map(p, &RgbImage::new(10, 10))
            .unwrap_err()
            .to_string()
            .contains("equirectangular")
    );
    let mut img = RgbImage::new(8, 4);
    img.pixels[3] = [f32::NAN, 0.0, 0.0];
    assert!(
        validate_map(p, &img)
            .unwrap_err()
            .to_string()
            .contains("texel (3, 0)")
    );
    // every kind of bad value, in any channel, past the first chunk of the check; the first
    // bad texel is the one named; the largest finite value and zero are valid
    for bad in [f32::INFINITY, f32::NEG_INFINITY, -1e-30, -0.5, f32::NAN] {
        for channel in 0..3 {
            let mut img = RgbImage::new(128, 64);
            img.pixels[0] = [f32::MAX, 0.0, -0.0];
            img.pixels[5000][channel] = bad;
            img.pixels[7000] = [bad; 3];
            let e = validate_map(p, &img).unwrap_err().to_string();
            assert!(e.contains("texel (8, 39)"), "{bad} in {channel}: {e}");
        }
    }
    let mut img = RgbImage::new(128, 64);
    img.pixels[0] = [f32::MAX, 0.0, -0.0];
    assert!(validate_map(p, &img).is_ok());
}

/// `clip_relative` on the built-in sky clips as on a map: the disc (2e4 times the median sky
/// at 3 degrees) drops to the limit, hue kept; the sky below the limit keeps its bits; batches
/// give what single rays give; the irradiance loses the disc's excess. The limit is the same
/// as the map of the same sky gets.
#[test]
fn clipping_the_built_in_sky_caps_its_sun() {
    let model = AnalyticSky::default();
    let mut sky = Sky::analytic(model);
    let unclipped = sky.clone();
    let limit = sky.clip_relative(100.0);
    let mut map = Sky::analytic(model);
    map.source = SkySource::Map(rasterize(&model, 1024));
    assert_eq!(map.clip_relative(100.0), limit);
    let camera = Vec3::new(0.0, sky.camera_height_m as f32, 0.0);
    let sun = model.sun_direction();
    let (before, after) = (unclipped.radiance(camera, sun), sky.radiance(camera, sun));
    let lum = |c: Vec3| crate::color::luminance(c.to_array());
    assert!(lum(before) > 50.0 * limit, "{before} vs {limit}");
    assert!(
        (lum(after) / limit - 1.0).abs() < 1e-5,
        "{after} vs {limit}"
    );
    assert!(((after / before) - after.x / before.x).abs().max_element() < 1e-6);
    let up = Vec3::new(0.3, 0.5, -0.2).normalize();
    assert_eq!(sky.radiance(camera, up), unclipped.radiance(camera, up));
    let dirs = [sun, up, Vec3::Y, sun];
    let mut many = [Vec3::ZERO; 4];
    sky.radiance_many(&[camera; 4], &dirs, &mut many);
    for (d, l) in dirs.iter().zip(many) {
        assert_eq!(l, sky.radiance(camera, *d));
    }
    // the irradiance loses the disc's excess over the limit, times its cosine-weighted solid
    // angle (the disc is 0.27 degrees in radius, 3 degrees up)
    let omega = (std::f64::consts::TAU * (1.0 - (SUN_RADIUS_RAD as f64).cos())) as f32;
    let lost = lum(unclipped.irradiance()) - lum(sky.irradiance());
    let want = (lum(before) - limit) * omega * sun.y;
    assert!((lost / want - 1.0).abs() < 0.05, "{lost} vs {want}");
}
