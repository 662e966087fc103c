//! A camera an object carries (`[camera.mount]`): where the mount puts and points it, that a
//! render from the mount is the render from a free camera at the place it resolves to, that
//! an animation moves it with the ship, and that a bad mount is refused with its reason.

use vastocean::config::{Mount, ObjectConfig, Projection, SceneConfig};
use vastocean::objects::mount::mounted_camera;
use vastocean::ocean::Surface;
use vastocean::render::pipeline::{prepare, prepare_for_frames};

fn pinhole(yaw_deg: f64, pitch_deg: f64, roll_deg: f64) -> Projection {
    Projection::Pinhole {
        hfov_deg: 40.0,
        yaw_deg,
        pitch_deg,
        roll_deg,
    }
}

/// A ship at world (500, -200) heading `heading_deg`, carrying a pinhole camera `offset_m`
/// from its origin.
fn bridge_scene(heading_deg: f64, float: bool, offset_m: [f64; 3]) -> SceneConfig {
    let mut cfg = SceneConfig::default();
    cfg.camera.width = 64;
    cfg.camera.projection = pinhole(0.0, -5.0, 0.0);
    cfg.camera.mount = Some(Mount {
        object: "own".into(),
        offset_m,
    });
    cfg.render.spp = 2;
    cfg.objects = vec![ObjectConfig {
        name: Some("own".into()),
        position_m: [500.0, -200.0],
        heading_deg,
        float,
        height_m: 1.5,
        ..ObjectConfig::default()
    }];
    cfg
}

fn angles(p: Projection) -> (f64, f64, f64) {
    match p {
        Projection::Pinhole {
            yaw_deg,
            pitch_deg,
            roll_deg,
            ..
        } => (yaw_deg, pitch_deg, roll_deg),
        Projection::Equirect { .. } => panic!("a pinhole stays one"),
    }
}

/// On a fixed object heading 90 degrees (its bow along +z), an offset 10 m forward, 6 m up
/// and 2 m to starboard is world (-2, +10) from its origin, 7.5 m above the sea (the object
/// stands 1.5 m up), and a camera looking along the bow looks along azimuth 90 with its own
/// pitch. On a floating ship on the default sea, the camera's height is the ship's pose's and
/// a camera looking along the bow pitches with the hull.
#[test]
fn the_mount_places_and_aims_the_camera_by_the_objects_pose() {
    let cfg = bridge_scene(90.0, false, [10.0, 6.0, 2.0]);
    cfg.validate().unwrap();
    let ocean = Surface::new(&cfg.ocean, cfg.render.ocean_seed).unwrap();
    let cam = mounted_camera(&cfg.camera, &cfg.objects, &ocean).unwrap();
    assert!(cam.mount.is_none());
    let [x, z] = cam.position_m;
    assert!(
        (x - 498.0).abs() < 1e-9 && (z + 190.0).abs() < 1e-9,
        "{x} {z}"
    );
    assert!((cam.height_m - 7.5).abs() < 1e-9, "{}", cam.height_m);
    let (yaw, pitch, roll) = angles(cam.projection);
    assert!((yaw - 90.0).abs() < 1e-9, "{yaw}");
    assert!(
        (pitch + 5.0).abs() < 1e-9 && roll.abs() < 1e-9,
        "{pitch} {roll}"
    );

    let cfg = bridge_scene(30.0, true, [0.0, 8.0, 0.0]);
    let ocean = Surface::new(&cfg.ocean, cfg.render.ocean_seed).unwrap();
    let mut level = cfg.camera.clone();
    level.projection = pinhole(0.0, 0.0, 0.0);
    let cam = mounted_camera(&level, &cfg.objects, &ocean).unwrap();
    let p = prepare(&cfg).unwrap();
    let ship = &p.objects.as_ref().unwrap().report()[0];
    let (heave, ship_pitch, ship_roll) = (
        ship.heave_m.unwrap(),
        ship.pitch_deg.unwrap(),
        ship.roll_deg.unwrap(),
    );
    assert!(
        ship_pitch.abs() > 0.05 && ship_roll.abs() > 0.05,
        "the default sea tilts the ship: {ship:?}"
    );
    // 8 m up the mast of a tilted hull: a little lower than heave + 8
    let up = 8.0
        / (1.0 + ship_pitch.to_radians().tan().powi(2) + ship_roll.to_radians().tan().powi(2))
            .sqrt();
    assert!(
        (cam.height_m - (heave + up)).abs() < 2e-3,
        "{} against {heave} + {up}",
        cam.height_m
    );
    let (yaw, pitch, roll) = angles(cam.projection);
    assert!(
        (pitch - ship_pitch).abs() < 1e-3,
        "{pitch} against {ship_pitch}"
    );
    // starboard up is the camera's right side up: a negative roll, of about the ship's
    assert!(
        (roll + ship_roll).abs() < 0.05,
        "{roll} against {ship_roll}"
    );
    assert!((yaw - 30.0).abs() < 0.5, "{yaw}");
}

/// The render from the mount is the render from a free camera put where the mount resolved
/// it (the report's camera), pixel for pixel.
#[test]
fn a_mounted_render_is_the_free_render_from_where_the_mount_put_the_camera() {
    let mut cfg = bridge_scene(20.0, true, [-7.0, 7.8, 0.0]);
    cfg.objects.push(ObjectConfig {
        position_m: [700.0, -180.0],
        heading_deg: 100.0,
        ..ObjectConfig::default()
    });
    let mounted = prepare(&cfg).unwrap().render(&cfg, false).unwrap();
    let free = mounted.report.config.clone();
    assert!(
        free.camera.mount.is_none(),
        "the report holds the placed camera"
    );
    assert!(
        (free.camera.position_m[0] - 500.0).abs() < 8.0 && free.camera.height_m > 6.0,
        "{:?}",
        free.camera
    );
    let again = prepare(&free).unwrap().render(&free, false).unwrap();
    assert_eq!(mounted.film.image.pixels, again.film.image.pixels);
    assert_eq!(mounted.report.objects, again.report.objects);
    let ids: Vec<u32> = mounted.report.objects.iter().map(|o| o.id).collect();
    assert_eq!(ids, [1, 2]);
}

/// From frame to frame the camera moves with the ship: at 3 s it stands where a scene prepared
/// at 3 s puts it, which is not where it stood at 0 s.
#[test]
fn an_animation_carries_the_mounted_camera_with_the_ship() {
    let cfg = bridge_scene(20.0, true, [-7.0, 7.8, 0.0]);
    let p = prepare_for_frames(&cfg).unwrap();
    let before = p.mounted.clone().unwrap();
    let (p, update) = p.remount_to(&cfg, 3.0).unwrap();
    let after = p.mounted.clone().unwrap();
    assert!(update.seconds_ocean > 0.0 && update.seconds_refit > 0.0);
    assert!(
        (after.height_m - before.height_m).abs() > 1e-3,
        "{} then {}",
        before.height_m,
        after.height_m
    );
    let mut at_3 = cfg.clone();
    at_3.ocean.time_s = 3.0;
    let direct = prepare(&at_3).unwrap().mounted.unwrap();
    // (the layers moved to 3 s and built at 3 s agree to f32 rounding)
    assert!(
        (direct.height_m - after.height_m).abs() < 1e-4,
        "{} {}",
        direct.height_m,
        after.height_m
    );
    let (a, b) = (angles(direct.projection), angles(after.projection));
    assert!(
        (a.0 - b.0).abs() + (a.1 - b.1).abs() + (a.2 - b.2).abs() < 1e-3,
        "{a:?} {b:?}"
    );
    let r = p.render(&at_3, false).unwrap();
    assert_eq!(r.report.config.camera.height_m, after.height_m);
}

/// A mount naming no object, and a mount beside a camera position, are refused naming the key.
#[test]
fn a_bad_mount_is_refused_with_its_reason() {
    let mut cfg = bridge_scene(0.0, true, [0.0, 5.0, 0.0]);
    cfg.camera.mount.as_mut().unwrap().object = "ghost".into();
    let e = cfg.validate().unwrap_err().to_string();
    assert!(
        e.starts_with("camera.mount.object") && e.contains("own"),
        "{e}"
    );
    let mut cfg = bridge_scene(0.0, true, [0.0, 5.0, 0.0]);
    cfg.camera.height_m = 12.0;
    let e = cfg.validate().unwrap_err().to_string();
    assert!(e.starts_with("camera.mount"), "{e}");
    let mut cfg = bridge_scene(0.0, true, [0.0, f64::NAN, 0.0]);
    let e = cfg.validate().unwrap_err().to_string();
    assert!(e.starts_with("camera.mount.offset_m"), "{e}");
    // a camera mounted below the waterline is under the sea
    cfg.camera.mount.as_mut().unwrap().offset_m = [0.0, -2.0, 0.0];
    let e = prepare(&cfg).err().expect("refused").to_string();
    assert!(e.contains("not above the sea"), "{e}");
}
