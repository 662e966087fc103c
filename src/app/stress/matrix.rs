//! The stress matrix: the base scene varied one axis at a time, and the crossings of extremes
//! (see the parent module).

use super::{Cell, Extra};
use crate::config::{
    AnalyticSky, Backend, FilterLobe, LodChoice, NormalMode, Projection, SceneConfig, WrongSide,
};

/// Whole multiples of every period of [`period_layers`] are multiples of 400 m.
const PERIOD_MULTIPLE_M: f64 = 400.0 * 250.0;

/// Layers whose sizes are exact in binary (400, 50, 6.25 m), so a world offset of a whole
/// multiple of 400 m is a whole number of periods of each in floating point too.
fn period_layers(scene: &mut SceneConfig) {
    use crate::config::ocean::LayerSpec;
    scene.ocean.layers = vec![
        LayerSpec {
            size_m: 400.0,
            n: 512,
        },
        LayerSpec {
            size_m: 50.0,
            n: 512,
        },
        LayerSpec {
            size_m: 6.25,
            n: 256,
        },
    ];
}

fn pinhole(pitch_deg: f64) -> Projection {
    Projection::Pinhole {
        hfov_deg: 90.0,
        yaw_deg: 30.0,
        pitch_deg,
        roll_deg: 0.0,
    }
}

fn clear_sun(elevation_deg: f32) -> AnalyticSky {
    let AnalyticSky::Clear {
        sun_azimuth_deg,
        turbidity,
        ..
    } = AnalyticSky::default()
    else {
        unreachable!("the default sky is the clear one")
    };
    AnalyticSky::Clear {
        sun_elevation_deg: elevation_deg,
        sun_azimuth_deg,
        turbidity,
    }
}

/// A sea state by wind speed, with the spectrum's own height (no RMS target).
fn sea(scene: &mut SceneConfig, wind_m_s: f64) {
    scene.ocean.wind_speed = wind_m_s;
    scene.ocean.rms_m = None;
}

/// A storm: 25 m/s over 1000 km, scaled to 3 m RMS (12 m significant wave height). Under the
/// camera's nadir at the origin a crest stands at 2.8 m.
fn storm(scene: &mut SceneConfig) {
    scene.ocean.wind_speed = 25.0;
    scene.ocean.fetch_km = 1000.0;
    scene.ocean.rms_m = Some(3.0);
}

/// Moves the camera along +x, in 1 m steps, to the first place where the sea under it stands
/// below mean level: a camera centimetres above mean level is above the water there, whatever
/// the realization (over a crest it would rightly be refused; `sea-storm-camera-under` tests
/// that).
fn over_a_trough(scene: &mut SceneConfig) {
    let Ok(surface) = crate::ocean::Surface::new(&scene.ocean, scene.render.ocean_seed) else {
        return; // the cell reports the bad sea itself
    };
    let [x0, z0] = scene.camera.position_m;
    if let Some(x) = (0..10_000).map(|i| x0 + i as f64).find(|&x| {
        crate::render::pipeline::surface_height_at_nadir(&surface.sampler([x, z0])) < 0.0
    }) {
        scene.camera.position_m = [x, z0];
    }
}

/// The cells, base first (see the module doc).
pub fn matrix(base: &SceneConfig, full: bool) -> Vec<Cell> {
    let mut cells = Vec::new();
    let mut add = |name, axis, value: String, f: &dyn Fn(&mut SceneConfig), extra| {
        let mut scene = base.clone();
        f(&mut scene);
        cells.push(Cell {
            name,
            axis,
            value,
            scene,
            extra,
        });
    };
    add(
        "base",
        "base",
        "2 m, origin, default sea, sun 4 deg, equirect, Embree, paper-low".into(),
        &|_| {},
        Extra::None,
    );
    let heights: &[(&str, f64)] = if full {
        &[
            ("height-0.05", 0.05),
            ("height-0.5", 0.5),
            ("height-100", 100.0),
            ("height-1000", 1000.0),
            ("height-10000", 10_000.0),
        ]
    } else {
        &[
            ("height-0.05", 0.05),
            ("height-100", 100.0),
            ("height-10000", 10_000.0),
        ]
    };
    for &(name, h) in heights {
        add(
            name,
            "camera height",
            format!("{h} m"),
            &|s| {
                s.camera.height_m = h;
                if h < 1.0 {
                    over_a_trough(s);
                }
            },
            Extra::None,
        );
    }
    let positions: &[(&str, f64)] = if full {
        &[
            ("position-1e5", 1e5),
            ("position-1e7", 1e7),
            ("position-1e9", 1e9),
        ]
    } else {
        &[("position-1e5", 1e5), ("position-1e7", 1e7)]
    };
    for &(name, x) in positions {
        add(
            name,
            "world position",
            format!("({x}, {x}) m"),
            &|s| s.camera.position_m = [x, x],
            Extra::None,
        );
    }
    add(
        "period-origin",
        "world position",
        "origin, layers 400/50/6.25 m".into(),
        &period_layers,
        Extra::None,
    );
    add(
        "period-multiple",
        "world position",
        format!("({PERIOD_MULTIPLE_M}, {PERIOD_MULTIPLE_M}) m: whole periods of every layer"),
        &|s| {
            period_layers(s);
            s.camera.position_m = [PERIOD_MULTIPLE_M, PERIOD_MULTIPLE_M];
        },
        Extra::Identical("period-origin"),
    );
    add(
        "sea-calm",
        "sea state",
        "wind 0.5 m/s".into(),
        &|s| sea(s, 0.5),
        Extra::None,
    );
    add(
        "sea-storm",
        "sea state",
        "wind 25 m/s, fetch 1000 km, 3 m RMS; camera 30 m".into(),
        &|s| {
            storm(s);
            s.camera.height_m = 30.0;
        },
        Extra::None,
    );
    add(
        "sea-storm-camera-under",
        "sea state",
        "storm, camera 2 m (below a 2.8 m crest)".into(),
        &|s| {
            storm(s);
        },
        Extra::Refused,
    );
    let suns: &[(&str, f32)] = if full {
        &[
            ("sun--10", -10.0),
            ("sun-0", 0.0),
            ("sun-30", 30.0),
            ("sun-60", 60.0),
            ("sun-90", 90.0),
        ]
    } else {
        &[("sun--10", -10.0), ("sun-30", 30.0), ("sun-90", 90.0)]
    };
    for &(name, el) in suns {
        add(
            name,
            "sun elevation",
            format!("{el} deg"),
            &|s| s.sky.analytic = clear_sun(el),
            Extra::None,
        );
    }
    for (name, pitch) in [
        ("pinhole-down", -60.0),
        ("pinhole-level", 0.0),
        ("pinhole-up", 30.0),
    ] {
        add(
            name,
            "camera",
            format!("pinhole 90 deg wide, pitch {pitch} deg"),
            &|s| s.camera.projection = pinhole(pitch),
            Extra::None,
        );
    }
    add(
        "rust",
        "backend",
        "Rust BVH".into(),
        &|s| s.render.backend = Backend::Rust,
        Extra::Agrees("base"),
    );
    add(
        "lod-auto",
        "tessellation",
        "auto".into(),
        &|s| s.lod.preset = LodChoice::Auto,
        Extra::None,
    );
    for (name, lobe) in [
        ("filtered", FilterLobe::Mapped),
        ("filtered-smith", FilterLobe::Smith),
    ] {
        add(
            name,
            "normals",
            format!("filtered, {lobe} lobe (the sun sampled)"),
            &|s| {
                s.render.normals = NormalMode::Filtered;
                s.render.filter_lobe = lobe;
            },
            Extra::None,
        );
    }
    if full {
        add(
            "filtered-height-10000",
            "normals",
            "filtered from 10 km up (every wave below the footprint)".into(),
            &|s| {
                s.render.normals = NormalMode::Filtered;
                s.camera.height_m = 10_000.0;
            },
            Extra::None,
        );
        add(
            "lod-paper-high",
            "tessellation",
            "paper-high".into(),
            &|s| s.lod.preset = LodChoice::PaperHigh,
            Extra::None,
        );
        add(
            "lod-paper-high-rust",
            "tessellation",
            "paper-high, Rust BVH".into(),
            &|s| {
                s.lod.preset = LodChoice::PaperHigh;
                s.render.backend = Backend::Rust;
            },
            Extra::Agrees("lod-paper-high"),
        );
    }
    // A uniform sky of 1, and a policy that keeps every branch's energy (`bend`): under the
    // default `terminate` an ended branch carries no light, and a cell could only ever lose it.
    let furnace = |s: &mut SceneConfig| {
        s.sky.analytic = AnalyticSky::Uniform { radiance: [1.0; 3] };
        s.render.wrong_side = WrongSide::Bend;
    };
    add(
        "furnace",
        "white furnace",
        "uniform sky 1".into(),
        &furnace,
        Extra::Furnace,
    );
    add(
        "furnace-storm",
        "white furnace",
        "uniform sky 1, storm, camera 30 m".into(),
        &|s| {
            furnace(s);
            storm(s);
            s.camera.height_m = 30.0;
        },
        Extra::Furnace,
    );
    for (name, lobe) in [
        ("furnace-filtered", FilterLobe::Mapped),
        ("furnace-filtered-smith", FilterLobe::Smith),
    ] {
        add(
            name,
            "white furnace",
            format!("uniform sky 1, storm, filtered normals ({lobe} lobe)"),
            &|s| {
                furnace(s);
                storm(s);
                s.camera.height_m = 30.0;
                s.render.normals = NormalMode::Filtered;
                s.render.filter_lobe = lobe;
            },
            Extra::Furnace,
        );
    }
    add(
        "furnace-pinhole-down",
        "white furnace",
        "uniform sky 1, pinhole down".into(),
        &|s| {
            furnace(s);
            s.camera.projection = pinhole(-60.0);
        },
        Extra::Furnace,
    );
    // A white Lambertian ship floating in view, a white metal one held just above the sea
    // beside the camera, and a clear glass hull (no deckhouse) floating half under the
    // water: light between the sea and the objects may bounce many times,
    // and still no pixel may exceed the sky's 1.
    add(
        "furnace-objects",
        "white furnace",
        "uniform sky 1, white diffuse, metal and glass ships".into(),
        &|s| {
            furnace(s);
            let white = [1.0; 3];
            s.objects = vec![
                crate::config::ObjectConfig {
                    position_m: [30.0, 10.0],
                    albedo: white,
                    ship: crate::config::ShipConfig {
                        deckhouse_albedo: white,
                        ..Default::default()
                    },
                    ..Default::default()
                },
                crate::config::ObjectConfig {
                    position_m: [0.0, -12.0],
                    height_m: 3.0,
                    float: false,
                    material: crate::config::Material::Metal,
                    albedo: white,
                    ..Default::default()
                },
                crate::config::ObjectConfig {
                    position_m: [-25.0, 15.0],
                    material: crate::config::Material::Glass,
                    albedo: white,
                    roughness: 0.05,
                    ship: crate::config::ShipConfig {
                        deckhouse_m: 0.0,
                        ..Default::default()
                    },
                    ..Default::default()
                },
            ];
        },
        Extra::Furnace,
    );
    // Crossings of extremes.
    add(
        "height-10000-pinhole-down",
        "crossing",
        "camera 10 km, pinhole down".into(),
        &|s| {
            s.camera.height_m = 10_000.0;
            s.camera.projection = pinhole(-60.0);
        },
        Extra::None,
    );
    add(
        "position-1e7-storm",
        "crossing",
        "(1e7, 1e7) m, storm, camera 30 m".into(),
        &|s| {
            s.camera.position_m = [1e7, 1e7];
            storm(s);
            s.camera.height_m = 30.0;
        },
        Extra::None,
    );
    add(
        "height-0.05-calm",
        "crossing",
        "camera 0.05 m, wind 0.5 m/s".into(),
        &|s| {
            s.camera.height_m = 0.05;
            sea(s, 0.5);
        },
        Extra::None,
    );
    add(
        "sun-90-pinhole-down",
        "crossing",
        "sun at the zenith, pinhole down".into(),
        &|s| {
            s.sky.analytic = clear_sun(90.0);
            s.camera.projection = pinhole(-60.0);
        },
        Extra::None,
    );
    add(
        "rust-storm-pinhole-down",
        "crossing",
        "Rust BVH, storm, camera 30 m, pinhole down".into(),
        &|s| {
            s.render.backend = Backend::Rust;
            storm(s);
            s.camera.height_m = 30.0;
            s.camera.projection = pinhole(-60.0);
        },
        Extra::Agrees("storm-pinhole-down"),
    );
    add(
        "storm-pinhole-down",
        "crossing",
        "storm, camera 30 m, pinhole down".into(),
        &|s| {
            storm(s);
            s.camera.height_m = 30.0;
            s.camera.projection = pinhole(-60.0);
        },
        Extra::None,
    );
    cells
}
