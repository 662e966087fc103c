//! Objects on the sea: the ship's hits on every backend against the brute-force oracle, where
//! floating puts it, and the light a diffuse object reflects.

use glam::Vec3;
use vastocean::accel::brute::BruteForce;
use vastocean::accel::{Accel, Ray};
use vastocean::config::{AnalyticSky, Backend, ObjectConfig, Projection, SceneConfig, ShipConfig};
use vastocean::objects::SceneObjects;
use vastocean::render::pipeline::prepare;
use vastocean::rng::Rng;

/// A scene with one ship at world (x, z), heading 30 degrees.
fn ship_scene(x: f64, z: f64, float: bool) -> SceneConfig {
    SceneConfig {
        objects: vec![ObjectConfig {
            position_m: [x, z],
            heading_deg: 30.0,
            float,
            ..ObjectConfig::default()
        }],
        ..SceneConfig::default()
    }
}

fn placed(cfg: &SceneConfig, backend: Backend) -> SceneObjects {
    let p = prepare(cfg).expect("the scene prepares");
    let sampler = p.ocean.sampler(cfg.camera.position_m);
    let r = p.lod.earth_radius_m;
    SceneObjects::build(&cfg.objects, &sampler, cfg.camera.position_m, r, backend, 2)
        .expect("the objects build")
        .expect("one object")
}

/// Rays from around the ships at their points: every backend's instances (Embree's instance
/// geometries, the Rust BVH's loop over instance boxes) find the brute-force oracle's hit on
/// the placed triangles at its distance, on the same object. Two of the three ships share one
/// mesh (one prototype, two instances).
#[test]
fn the_ships_are_hit_alike_by_every_backend_and_the_oracle() {
    let mut cfg = ship_scene(60.0, -20.0, true);
    cfg.objects.push(ObjectConfig {
        position_m: [75.0, 10.0],
        heading_deg: -50.0,
        ..ObjectConfig::default()
    });
    cfg.objects.push(ObjectConfig {
        position_m: [40.0, 30.0],
        scale: 0.5,
        float: false,
        height_m: 1.0,
        ..ObjectConfig::default()
    });
    let mut backends = vec![placed(&cfg, Backend::Rust)];
    if cfg!(feature = "embree") {
        backends.push(placed(&cfg, Backend::Embree));
    }
    assert_eq!(
        backends[0].prototypes.len(),
        2,
        "the same mesh at the same scale is shared"
    );
    assert_eq!(backends[0].instances.len(), 3);
    let mesh = backends[0].scene_mesh();
    assert_eq!(mesh.triangle_count(), 3 * 1836);
    // the instances' f32 placement is the objects' poses evaluated vertex by vertex in f64
    let p = prepare(&cfg).unwrap();
    let sampler = p.ocean.sampler(cfg.camera.position_m);
    let mut first = 0;
    for o in &cfg.objects {
        let local = vastocean::objects::LocalMesh::of(o).unwrap();
        let pose = vastocean::objects::Pose::of(o, &local, &sampler, o.position_m);
        for (v, q) in local.positions.iter().enumerate() {
            let d = pose.place(glam::DVec3::from(*q) * o.scale).to_array();
            let w = vastocean::lod::curved_frame_position(
                o.position_m[0],
                o.position_m[1],
                d,
                p.lod.earth_radius_m,
            );
            let got = mesh.positions()[first + v];
            for i in 0..3 {
                assert!((got[i] as f64 - w[i]).abs() < 1e-4, "{got:?} against {w:?}");
            }
        }
        first += local.positions.len();
    }
    let oracle = BruteForce::new(mesh.clone());
    let mut rng = Rng::keyed(&[35, 1]);
    let rays: Vec<Ray> = (0..6000)
        .map(|i| {
            let target = Vec3::from(mesh.positions()[i * 7 % mesh.vertex_count()])
                + 0.3 * Vec3::from(rng.unit_vector());
            let org = target + 30.0 * Vec3::from(rng.unit_vector()) + Vec3::new(0.0, 5.0, 0.0);
            Ray::new(org.to_array(), (target - org).normalize().to_array())
        })
        .collect();
    for objects in &backends {
        let name = objects.backend_name();
        let mut hits = 0;
        for ray in &rays {
            match (objects.intersect(ray), oracle.intersect(ray)) {
                (Some(a), Some(b)) => {
                    hits += 1;
                    assert!(
                        (a.t - b.t).abs() <= 1e-4 * b.t.max(1.0),
                        "{name}: t {} against the oracle's {} (prims {} and {})",
                        a.t,
                        b.t,
                        a.prim,
                        b.prim
                    );
                    assert_eq!(
                        objects.locate(a.prim).0,
                        objects.locate(b.prim).0,
                        "{name}: the same object"
                    );
                }
                (None, None) => {}
                (a, b) => panic!("{name}: {a:?} against the oracle's {b:?}"),
            }
        }
        assert!(hits > 3000, "{name}: most rays aim at a ship: {hits} hits");
    }
}

/// On a calm sea (1 mm RMS) the floating ship sits at its design waterline: its keel at the
/// draft below mean sea level (within the millimetre and the earth's curvature at its 60 m).
/// On the default sea it lies on the least-squares plane through the surface under it: its
/// heave between the lowest and highest of those heights, pitch and roll under 10 degrees.
#[test]
fn a_floating_ship_sits_at_its_draft_on_a_calm_sea_and_on_the_waves_on_a_rough_one() {
    let mut calm = ship_scene(60.0, 0.0, true);
    calm.ocean.rms_m = Some(0.001);
    let objects = placed(&calm, Backend::Rust);
    let keel = objects
        .scene_mesh()
        .positions()
        .iter()
        .map(|p| p[1])
        .fold(f32::INFINITY, f32::min) as f64;
    let draft = ShipConfig::default().draft_m;
    assert!(
        (keel + draft).abs() < 0.005,
        "keel at {keel} m, draft {draft} m"
    );
    let plane = objects.placed[0].plane.expect("it floats");
    assert!(plane.heave.abs() < 0.005, "{plane:?}");

    let rough = ship_scene(60.0, 0.0, true);
    let p = prepare(&rough).unwrap();
    let sampler = p.ocean.sampler(rough.camera.position_m);
    let objects = placed(&rough, Backend::Rust);
    let plane = objects.placed[0].plane.expect("it floats");
    let local = vastocean::objects::LocalMesh::of(&rough.objects[0]).unwrap();
    let (s, c) = 30f64.to_radians().sin_cos();
    let heights: Vec<f64> = vastocean::objects::float::waterplane_points(&local, 1.0)
        .iter()
        .map(|q| {
            let (x, z) = (60.0 + q[0] * c - q[1] * s, q[0] * s + q[1] * c);
            vastocean::objects::surface_height_at(&sampler, x as f32, z as f32)
        })
        .collect();
    let (lo, hi) = heights
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &h| {
            (a.min(h), b.max(h))
        });
    assert!(
        hi - lo > 0.05,
        "the default sea has waves under the hull: {lo}..{hi}"
    );
    assert!(
        lo <= plane.heave && plane.heave <= hi,
        "{plane:?} outside {lo}..{hi}"
    );
    let (pitch, roll) = plane.pitch_roll_deg();
    assert!(pitch.abs() < 10.0 && roll.abs() < 10.0, "{pitch} {roll}");
    // the fixed ship stays where it is put
    let fixed = placed(&ship_scene(60.0, 0.0, false), Backend::Rust);
    assert!(fixed.placed[0].plane.is_none());
}

/// A camera looking straight down at the deck of a ship held 50 m above the sea: the deck
/// sees the whole sky and nothing else, so a Lambertian deck of albedo a has radiance
/// a E / pi, E the sky's downwelling irradiance. Under a uniform sky of 1 every sample is
/// exactly a; under the clear sky with its sun (sampled by next-event estimation and weighed
/// against the bounce by multiple importance) the mean agrees with a E / pi within its noise
/// and the irradiance's own quadrature. A GGX metal deck under the uniform sky reflects its
/// directional albedo (masking loses a little of F0).
#[test]
fn a_deck_under_the_open_sky_reflects_its_irradiance() {
    let albedo = 0.6;
    let mut cfg = crate::common::looking_down(80.0, 6.0, 48, 64);
    cfg.objects = vec![ObjectConfig {
        float: false,
        height_m: 50.0,
        albedo: [albedo; 3],
        ship: ShipConfig {
            deckhouse_m: 0.0,
            ..ShipConfig::default()
        },
        ..ObjectConfig::default()
    }];
    cfg.sky.analytic = AnalyticSky::Uniform { radiance: [1.0; 3] };
    let p = prepare(&cfg).unwrap();
    let r = p.render(&cfg, false).unwrap();
    for px in &r.film.image.pixels {
        for c in px {
            assert!((c - albedo as f32).abs() < 1e-5, "{px:?}");
        }
    }

    // a metal deck under the uniform sky reflects its directional albedo, E[F G2 / G1] over
    // GGX's visible normals seen from straight above (the camera's rays are within 3 degrees)
    let mut metal = cfg.clone();
    metal.objects[0].material = vastocean::config::Material::Metal;
    metal.objects[0].roughness = 0.5;
    let p = prepare(&metal).unwrap();
    let r = p.render(&metal, false).unwrap();
    let g = vastocean::render::ggx::Ggx {
        alpha: 0.5,
        f0: Vec3::splat(albedo as f32),
    };
    let mut rng = Rng::keyed(&[35, 2]);
    let n = 400_000;
    let expected: f64 = (0..n)
        .filter_map(|_| g.sample(Vec3::Z, rng.f32(), rng.f32()))
        .map(|(_, w)| w.x as f64)
        .sum::<f64>()
        / n as f64;
    let (mean, se) = crate::common::mean_luminance_se(&r);
    assert!(
        (mean - expected).abs() < 4.0 * se + 0.002,
        "metal deck {mean:.5} +- {se:.5}, directional albedo {expected:.5}"
    );
    // GGX loses a fifth of its visible normals past 45 degrees at alpha 0.5 (tan^2 CDF)
    assert!(
        expected < 0.8 * albedo && expected > 0.6 * albedo,
        "{expected}"
    );

    let mut sunny = cfg.clone();
    sunny.sky = vastocean::config::SkyConfig::default();
    let p = prepare(&sunny).unwrap();
    let irradiance = p.sky.irradiance();
    assert!(p.sky.sun_light().is_some(), "the default sky has a sun");
    let r = p.render(&sunny, false).unwrap();
    let (mean, se) = crate::common::mean_luminance_se(&r);
    let lum = |c: [f32; 3]| vastocean::color::luminance(c) as f64;
    let expected = albedo * lum(irradiance.to_array()) / std::f64::consts::PI;
    assert!(
        (mean - expected).abs() < 4.0 * se + 0.005 * expected,
        "deck {mean:.5} +- {se:.5}, a E / pi = {expected:.5}"
    );
}

/// An animation moves a floating ship with the sea: at another time its pose is that time's
/// (the same as a scene prepared at that time directly), and a fixed one stays put.
#[test]
fn a_floating_ship_moves_with_the_sea_from_frame_to_frame() {
    let mut cfg = ship_scene(60.0, 0.0, true);
    cfg.objects.push(ObjectConfig {
        float: false,
        position_m: [-80.0, 10.0],
        ..ObjectConfig::default()
    });
    let mut p = vastocean::render::pipeline::prepare_for_frames(&cfg).unwrap();
    let before = p.objects.as_ref().unwrap().report();
    p.advance_to(3.0, cfg.camera.height_m).unwrap();
    let after = p.objects.as_ref().unwrap().report();
    assert_ne!(
        before[0], after[0],
        "the sea moved in 3 s, and the ship with it"
    );
    assert_eq!(before[1], after[1], "a fixed object stays where it was put");
    let mut at_3 = cfg.clone();
    at_3.ocean.time_s = 3.0;
    let direct = prepare(&at_3).unwrap().objects.unwrap().report();
    for (a, b) in after.iter().zip(&direct) {
        let heave = a.heave_m.zip(b.heave_m).map(|(x, y)| (x - y).abs());
        assert!(heave.is_none_or(|d| d < 1e-4), "{a:?} against {b:?}");
    }
}

/// A 2 m cube held 5 m up and 20 m ahead of a pinhole camera at its height: each pixel whose
/// centre ray meets the cube's front face (x = 19 m) has id 1, depth the distance to that face
/// and normal -x; the sky above the horizon is -1 at infinite depth, the water below 0; the
/// bounding box in the sidecar is the box of those pixels; the sidecar's horizon row parts
/// sky from water in every column.
#[test]
fn the_layers_for_training_data_see_a_known_box() {
    let dir = std::env::temp_dir().join(format!("vastocean-aov-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let cube = dir.join("cube.obj");
    let mut obj = String::new();
    for k in 0..8 {
        let c = |bit: usize| if k & bit == 0 { -1.0 } else { 1.0 };
        obj += &format!("v {} {} {}\n", c(1), c(2), c(4));
    }
    for f in [
        [1, 5, 7, 3],
        [2, 4, 8, 6],
        [1, 2, 6, 5],
        [3, 7, 8, 4],
        [1, 3, 4, 2],
        [5, 6, 8, 7],
    ] {
        obj += &format!("f {} {} {} {}\n", f[0], f[1], f[2], f[3]);
    }
    std::fs::write(&cube, obj).unwrap();
    let mut cfg = SceneConfig::default();
    cfg.camera.height_m = 5.0;
    cfg.camera.width = 96;
    cfg.camera.aspect = 2.0;
    cfg.camera.projection = Projection::Pinhole {
        hfov_deg: 30.0,
        yaw_deg: 0.0,
        pitch_deg: 0.0,
        roll_deg: 0.0,
    };
    cfg.render.spp = 1;
    cfg.render.aovs = vec![
        vastocean::config::Aov::Depth,
        vastocean::config::Aov::Normal,
        vastocean::config::Aov::Id,
    ];
    cfg.objects = vec![ObjectConfig {
        mesh: cube.clone(),
        position_m: [20.0, 0.0],
        height_m: 5.0,
        float: false,
        ..ObjectConfig::default()
    }];
    let p = prepare(&cfg).unwrap();
    let r = p.render(&cfg, false).unwrap();
    let (w, h) = (r.camera.width, r.camera.height);
    let id = r.aovs.id.as_ref().unwrap();
    let depth = r.aovs.depth.as_ref().unwrap();
    let [nx, ny, nz] = r.aovs.normal.as_ref().unwrap();
    let (mut lo, mut hi) = ([usize::MAX; 2], [0usize; 2]);
    let mut checked = [0; 3];
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            let d = r.camera.direction(x as f32 + 0.5, y as f32 + 0.5);
            let t = 19.0 / d.x;
            let (py, pz) = (5.0 + t * d.y, t * d.z);
            // inside the face, clear of its edges by a hair (curvature and rounding)
            let inside = (py - 5.0).abs() < 0.99 && pz.abs() < 0.99;
            let outside = (py - 5.0).abs() > 1.01 || pz.abs() > 1.01;
            if inside {
                assert_eq!(id[i], 1.0, "pixel {x},{y}");
                assert!((depth[i] - t).abs() < 1e-3, "{x},{y}: {} vs {t}", depth[i]);
                assert!((nx[i] + 1.0).abs() < 1e-4 && ny[i].abs() < 1e-4 && nz[i].abs() < 1e-4);
                lo = [lo[0].min(x), lo[1].min(y)];
                hi = [hi[0].max(x), hi[1].max(y)];
                checked[0] += 1;
            } else if outside && d.y > 0.0 {
                assert_eq!(id[i], -1.0, "sky at {x},{y}");
                assert!(depth[i].is_infinite());
                checked[1] += 1;
            } else if outside && d.y < -0.05 {
                assert_eq!(id[i], 0.0, "water at {x},{y}");
                assert!(depth[i].is_finite() && ny[i] > 0.0);
                checked[2] += 1;
            }
        }
    }
    assert!(checked.iter().all(|&n| n > 100), "{checked:?}");
    // the sidecar's horizon parts the sky from the water, a pixel either side of it
    let rows = r
        .report
        .horizon_row_px
        .as_ref()
        .expect("a pinhole has a horizon");
    assert_eq!(rows.len(), w);
    for (x, row) in rows.iter().enumerate() {
        let row = row.expect("a level camera sees the horizon in every column");
        if (lo[0].saturating_sub(2)..=hi[0] + 2).contains(&x) {
            continue; // the box stands in front of the horizon
        }
        let (above, below) = (row.floor() as usize - 1, row.ceil() as usize + 1);
        assert_eq!(id[above * w + x], -1.0, "column {x}: horizon at row {row}");
        assert_eq!(id[below * w + x], 0.0, "column {x}: horizon at row {row}");
    }
    let b = r.report.objects[0].bbox_px.expect("the box is seen");
    for (got, want) in [(b[0], lo[0]), (b[1], lo[1])] {
        assert!(
            got <= want && want - got <= 1,
            "{b:?} against {lo:?}..{hi:?}"
        );
    }
    for (got, want) in [(b[2], hi[0]), (b[3], hi[1])] {
        assert!(
            got >= want && got - want <= 1,
            "{b:?} against {lo:?}..{hi:?}"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Bad objects are refused as bad input (exit 2) with the key or the file named, and the
/// layers are refused beside `--pass` (a pass holds samples, not layers).
#[test]
fn bad_objects_and_layers_in_passes_are_refused_with_their_reasons() {
    let dir = std::env::temp_dir().join(format!("vastocean-badobj-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("s.toml");
    let out = dir.join("out").to_string_lossy().to_string();
    for (object, says) in [
        ("mesh = \"hull.stl\"", "object[0].mesh"),
        ("mesh = \"missing.obj\"", "missing.obj"),
        ("albedo = [1.5, 0.5, 0.5]", "object[0].albedo"),
        ("ship = { beam_m = 50.0 }", "object[0].ship.beam_m"),
        ("material = \"glass\"", "object[0].material"),
        ("name = \"a\"\n[[object]]\nname = \"a\"", "object[1].name"),
        (
            "material = \"glass\"\nior = 0.5\nship = { deckhouse_m = 0.0 }",
            "object[0].ior",
        ),
    ] {
        std::fs::write(&scene, format!("[[object]]\n{object}\n")).unwrap();
        let s = scene.to_string_lossy().to_string();
        let args = [
            "render", "--config", &s, "--width", "64", "--spp", "1", "--out", &out,
        ];
        let (code, _, err) = crate::common::vastocean(&args);
        assert_eq!(code, 2, "{object}: {err}");
        assert!(err.contains(says), "{object}: {err}");
    }
    let args = [
        "render", "--aov", "id", "--pass", "1/2", "--width", "64", "--out", &out,
    ];
    let (code, _, err) = crate::common::vastocean(&args);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("--pass"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}
