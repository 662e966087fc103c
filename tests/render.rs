//! The path tracer against analytic answers: a white furnace, a flat sea under a gradient sky,
//! the mapped normal against the ocean itself, coarse vs fine meshes, determinism and grazing
//! rays at the horizon. The oracles run on every backend this build has.

use glam::Vec3;
use vastocean::accel::{Accel, Ray};
use vastocean::config::WrongSide;
use vastocean::image_io::RgbImage;
use vastocean::mesh::Mesh;
use vastocean::ocean::{LayerSpec, OceanParams, Sampler, Surface};
use vastocean::render::water::fresnel;
use vastocean::render::{
    AnalyticSky, Camera, NormalMode, Projection, SceneRef, Sky, TraceSettings, Water, render_image,
};

/// A square grid of `cell`-metre cells over [-half, half]^2 around the camera, displaced by the
/// ocean (paper eq. 4) with its normals (eq. 7) and nominal positions as texture coordinates.
pub(crate) fn ocean_grid(sampler: &Sampler, half: f32, cell: f32) -> Mesh {
    let n = (2.0 * half / cell).round() as u32;
    let flat = Mesh::grid(n, n, cell);
    let mut positions = Vec::with_capacity(flat.vertex_count());
    let mut normals = Vec::with_capacity(flat.vertex_count());
    let mut uvs = Vec::with_capacity(flat.vertex_count());
    for p in flat.positions() {
        let (u, v) = (p[0] - half, p[2] - half);
        let s = sampler.sample(u, v);
        positions.push(s.position(u, v));
        normals.push(s.normal);
        uvs.push([u, v]);
    }
    Mesh::new(positions, normals, uvs, flat.indices().to_vec()).unwrap()
}

pub(crate) fn small_ocean(choppiness: f64) -> Surface {
    let params = OceanParams {
        layers: vec![
            LayerSpec {
                size_m: 61.7,
                n: 128,
            },
            LayerSpec { size_m: 7.9, n: 64 },
        ],
        rms_m: Some(0.15),
        choppiness,
        ..OceanParams::default()
    };
    Surface::new(&params, 7).unwrap()
}

/// The integrator's view of a test scene, tracing every ray (no skip shortcut).
pub(crate) fn scene_ref<'a>(
    accel: &'a dyn Accel,
    sampler: Sampler<'a>,
    earth_radius_m: f64,
    sky: &'a Sky,
) -> SceneRef<'a> {
    SceneRef {
        accel,
        skip_slope: None,
        skip_above_y: None,
        predict_camera_hits: false,
        ocean: Some(sampler),
        slopes: None,
        sun: None,
        earth_radius_m,
        sky,
        objects: None,
    }
}

/// The production backend: Embree when this build has it, else the Rust BVH.
pub(crate) fn accel(mesh: Mesh) -> Box<dyn Accel> {
    crate::common::backends(mesh).remove(0)
}

pub(crate) fn equirect(width: usize, band: Option<(f64, f64)>) -> Camera {
    Camera::new(Projection::Equirect { band_deg: band }, width, 2.0)
}

#[test]
fn mapped_normal_tilt_agrees_with_the_tessellators_curved_earth_frame() {
    // The integrator tilts mapped normals in f32 at every hit; the tessellator places vertices
    // and their normals in f64. At a vertex both must give the same normal.
    let ocean = small_ocean(1.0);
    let sampler = ocean.sampler([0.0, 0.0]);
    let mut rng = vastocean::rng::Rng::keyed(&[17]);
    for _ in 0..1000 {
        let (u, v) = (rng.range(-6000.0, 6000.0), rng.range(-6000.0, 6000.0));
        let s = sampler.sample(u, v);
        let (_, n) = vastocean::lod::curved_frame_point(u as f64, v as f64, &s, 6_371_000.0);
        let tilted =
            vastocean::render::integrator::tilt_to_earth(u, v, 6_371_000.0, Vec3::from(s.normal));
        let want = Vec3::new(n[0] as f32, n[1] as f32, n[2] as f32);
        assert!(
            (tilted - want).length() < 1e-6,
            "at ({u}, {v}): {tilted} vs {want}"
        );
    }
}

#[test]
fn white_furnace_every_pixel_equals_the_sky() {
    let ocean = small_ocean(1.0);
    let sampler = ocean.sampler([0.0, 0.0]);
    let l = [0.5f32, 0.7, 1.0];
    let sky = Sky::analytic(AnalyticSky::Uniform { radiance: l });
    // Under a uniform sky of irradiance pi L, R_rs = (1 - F(0)) / pi makes the upwelling
    // radiance below the surface L itself (see Water::upwelling).
    let f0 = fresnel(1.0, 1.0, Water::default().ior);
    let water = Water {
        absorption: [0.0; 3],
        upwelling_rrs: [(1.0 - f0) * std::f32::consts::FRAC_1_PI; 3],
        ..Water::default()
    };
    let upwelling = water.upwelling(sky.irradiance()).to_array();
    for accel in crate::common::backends(ocean_grid(&sampler, 60.0, 0.5)) {
        let scene = scene_ref(accel.as_ref(), sampler, 6_371_000.0, &sky);
        // Every policy that keeps the weight of a wrong-side direction conserves energy.
        for (normals, wrong_side) in [
            (NormalMode::Vertex, WrongSide::Mirror),
            (NormalMode::Mapped, WrongSide::Mirror),
            (NormalMode::Mapped, WrongSide::Flip),
            (NormalMode::Mapped, WrongSide::Bend),
        ] {
            let settings = TraceSettings {
                normals,
                water,
                wrong_side,
                upwelling,
                ..TraceSettings::default()
            };
            let (film, c) =
                render_image(&scene, &equirect(64, None), 2.0, 4, 1, &settings, 0, false);
            let img = film.image;
            assert!(c.hits > 1000, "the sea must be hit: {c:?}");
            let worst = img
                .pixels
                .iter()
                .map(|p| {
                    (0..3)
                        .map(|k| ((p[k] - l[k]) / l[k]).abs())
                        .fold(0f32, f32::max)
                })
                .fold(0f32, f32::max);
            // Only paths cut at 10 segments lose energy; they are rare.
            assert!(
                worst < 0.01,
                "{} {normals:?} {wrong_side:?}: worst relative error {worst}, truncated {}",
                accel.name(),
                c.truncated
            );
            assert_eq!(c.nan, 0);
        }
    }
}

#[test]
fn flat_sea_matches_the_fresnel_weighted_mirror_lookup() {
    let flat = Surface::flat();
    let sampler = flat.sampler([0.0, 0.0]);
    let (zenith, horizon) = ([0.1f32, 0.2, 0.6], [0.9f32, 0.8, 0.7]);
    let sky = Sky::analytic(AnalyticSky::Gradient { zenith, horizon });
    for accel in crate::common::backends(ocean_grid(&sampler, 4000.0, 50.0)) {
        // A flat mesh: no earth curvature, so the mapped normal is +y like the geometry.
        let scene = scene_ref(accel.as_ref(), sampler, f64::INFINITY, &sky);
        let water = Water::default();
        let settings = TraceSettings {
            water,
            upwelling: water.upwelling(sky.irradiance()).to_array(),
            ..TraceSettings::default()
        };
        let cam = equirect(128, Some((-2.0, -60.0)));
        let img = render_image(&scene, &cam, 2.0, 256, 3, &settings, 0, false)
            .0
            .image;
        let sky_at = |d: Vec3| Vec3::from(horizon).lerp(Vec3::from(zenith), d.y.clamp(0.0, 1.0));
        let mut worst = 0f32;
        for y in 0..cam.height {
            for x in (0..cam.width).step_by(7) {
                // the pixel's exact average over a 16 x 16 sub-pixel grid
                let mut sum = Vec3::ZERO;
                for sy in 0..16 {
                    for sx in 0..16 {
                        let d = cam.direction(
                            x as f32 + (sx as f32 + 0.5) / 16.0,
                            y as f32 + (sy as f32 + 0.5) / 16.0,
                        );
                        let f = fresnel(-d.y, 1.0, water.ior);
                        sum += f * sky_at(Vec3::new(d.x, -d.y, d.z))
                            + (1.0 - f) * Vec3::from(settings.upwelling);
                    }
                }
                let want = sum / 256.0;
                let got = Vec3::from(img.get(x, y));
                worst = worst.max(((got - want) / want).abs().max_element());
            }
        }
        assert!(
            worst < 0.01,
            "{}: worst relative error {worst}",
            accel.name()
        );
    }
}

#[test]
fn mapped_normal_is_the_ocean_normal_at_the_hit() {
    // Without choppiness the nominal position of a surface point is its (x, z), so the ocean can
    // be sampled there directly, independently of the texture-coordinate interpolation.
    let ocean = small_ocean(0.0);
    let sampler = ocean.sampler([0.0, 0.0]);
    let accel = accel(ocean_grid(&sampler, 20.0, 0.8));
    let sky = Sky::analytic(AnalyticSky::default());
    let scene = scene_ref(accel.as_ref(), sampler, f64::INFINITY, &sky);
    let mut rng = vastocean::rng::Rng::keyed(&[5]);
    let mut max_vertex_err = 0f32;
    for _ in 0..2000 {
        let (x, z) = (rng.range(-15.0, 15.0), rng.range(-15.0, 15.0));
        let h = accel
            .intersect(&Ray::new([x, 10.0, z], [0.0, -1.0, 0.0]))
            .expect("hit");
        let want = Vec3::from(sampler.sample(x, z).normal);
        let mapped = scene.normal_at(&h, NormalMode::Mapped);
        assert!(
            (mapped - want).length() < 2e-3,
            "mapped {mapped} vs ocean {want} at ({x}, {z})"
        );
        max_vertex_err =
            max_vertex_err.max((scene.normal_at(&h, NormalMode::Vertex) - want).length());
    }
    // ...while interpolated vertex normals of 0.8 m triangles miss the finer waves.
    assert!(
        max_vertex_err > 0.02,
        "vertex normals should differ on a coarse mesh: {max_vertex_err}"
    );
}

pub(crate) fn mean_abs_luminance_difference(a: &RgbImage, b: &RgbImage) -> f64 {
    let lum = vastocean::color::luminance;
    let (num, den): (f64, f64) = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .map(|(p, q)| (((lum(*p) - lum(*q)) as f64).abs(), lum(*q) as f64))
        .fold((0.0, 0.0), |s, v| (s.0 + v.0, s.1 + v.1));
    num / den
}

#[test]
fn vertex_and_mapped_differ_on_a_coarse_mesh_and_agree_on_a_fine_one() {
    // One long-wave layer only, so a 5 cm mesh resolves every wave.
    let params = OceanParams {
        layers: vec![LayerSpec {
            size_m: 40.0,
            n: 64,
        }],
        rms_m: Some(0.1),
        ..OceanParams::default()
    };
    let ocean = Surface::new(&params, 3).unwrap();
    let sampler = ocean.sampler([0.0, 0.0]);
    let sky = Sky::analytic(AnalyticSky::Gradient {
        zenith: [0.1, 0.2, 0.6],
        horizon: [1.0, 0.9, 0.8],
    });
    let cam = Camera::new(
        Projection::Pinhole {
            hfov_deg: 50.0,
            yaw_deg: 0.0,
            pitch_deg: -60.0,
            roll_deg: 0.0,
        },
        48,
        1.0,
    );
    let diff = |cell: f32| {
        let accel = accel(ocean_grid(&sampler, 12.0, cell));
        let scene = scene_ref(accel.as_ref(), sampler, f64::INFINITY, &sky);
        let render = |normals| {
            render_image(
                &scene,
                &cam,
                3.0,
                16,
                9,
                &TraceSettings {
                    normals,
                    ..TraceSettings::default()
                },
                0,
                false,
            )
            .0
            .image
        };
        mean_abs_luminance_difference(&render(NormalMode::Vertex), &render(NormalMode::Mapped))
    };
    let (coarse, fine) = (diff(2.0), diff(0.05));
    // Measured: 1.3e-2 (2 m cells) against 3e-5 (5 cm cells).
    assert!(
        coarse > 0.005,
        "coarse mesh: vertex vs mapped differ by {coarse}"
    );
    assert!(fine < 0.001, "fine mesh: vertex vs mapped differ by {fine}");
    assert!(fine < coarse / 20.0, "coarse {coarse}, fine {fine}");
}

#[test]
fn render_is_bit_identical_for_one_and_two_threads() {
    let ocean = small_ocean(1.0);
    let sampler = ocean.sampler([0.0, 0.0]);
    let sky = Sky::analytic(AnalyticSky::default());
    for accel in crate::common::backends(ocean_grid(&sampler, 40.0, 0.5)) {
        let scene = scene_ref(accel.as_ref(), sampler, 6_371_000.0, &sky);
        let render = |threads| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                render_image(
                    &scene,
                    &equirect(96, Some((10.0, -40.0))),
                    2.0,
                    3,
                    11,
                    &TraceSettings::default(),
                    8,
                    false,
                )
            })
        };
        let (a, ca) = render(1);
        let (b, cb) = render(2);
        assert_eq!(ca.rays, cb.rays);
        // Every output of the film, not only the image, is thread-count free.
        assert_eq!(a.var_y, b.var_y);
        assert_eq!(a.batches, b.batches);
        // Three samples, so three batches of one sample each.
        assert_eq!(
            a.batches.as_ref().map(|b| b.spp.clone()),
            Some(vec![1, 1, 1])
        );
        let (a, b) = (a.image, b.image);
        assert!(
            a.pixels
                .iter()
                .zip(&b.pixels)
                .all(|(p, q)| p.map(f32::to_bits) == q.map(f32::to_bits)),
            "{}",
            accel.name()
        );
    }
}

#[test]
fn skipping_rays_that_cannot_return_changes_no_pixel() {
    let ocean = small_ocean(0.5);
    let sampler = ocean.sampler([0.0, 0.0]);
    let mesh = ocean_grid(&sampler, 40.0, 0.5);
    let slope = vastocean::render::integrator::max_slope(&mesh).expect("a height field");
    assert!(slope > 0.0 && slope < 5.0, "{slope}");
    let top = vastocean::render::integrator::highest_vertex_y(&mesh);
    let accel = accel(mesh);
    let sky = Sky::analytic(AnalyticSky::default());
    let render = |skip_slope, skip_above_y| {
        let scene = SceneRef {
            skip_slope,
            skip_above_y,
            predict_camera_hits: false,
            accel: accel.as_ref(),
            ocean: Some(sampler),
            slopes: None,
            sun: None,
            earth_radius_m: 6_371_000.0,
            sky: &sky,
            objects: None,
        };
        render_image(
            &scene,
            &equirect(96, Some((5.0, -60.0))),
            2.0,
            4,
            2,
            &TraceSettings::default(),
            0,
            false,
        )
    };
    let (a, ca) = render(None, None);
    let (b, cb) = render(Some(slope), None);
    // The band reaches 5 degrees above the horizon: the camera's rays there leave upwards
    // from 2 m, above every vertex, and are skipped too.
    let (c, cc) = render(Some(slope), top);
    // Rays into the water that dive, and rays leaving a hit into the air that climb, more
    // steeply than any triangle are not traced.
    assert!(
        cb.skipped > 1000
            && cb.skipped_rising > 1000
            && cb.rays + cb.skipped + cb.skipped_rising == ca.rays,
        "{ca:?} {cb:?}"
    );
    // (A rising ray spawned above the highest vertex counts as skipped above, not rising.)
    assert!(
        cc.skipped_above > 500
            && cc.rays + cc.skipped_above + cc.skipped_rising == cb.rays + cb.skipped_rising,
        "{cb:?} {cc:?}"
    );
    let same = |a: &vastocean::image_io::RgbImage, b: &vastocean::image_io::RgbImage| {
        a.pixels
            .iter()
            .zip(&b.pixels)
            .all(|(p, q)| p.map(f32::to_bits) == q.map(f32::to_bits))
    };
    assert!(same(&a.image, &b.image));
    assert!(same(&a.image, &c.image));
    // A fold: the middle triangle is wound facing down (an overhang), so a ray under the upper
    // sheet could meet the inverted one. The shortcut must switch itself off.
    let folded = Mesh::new(
        vec![
            [0.0, 0.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 0.3, 0.0],
            [1.0, 0.3, 1.0],
            [0.6, 0.5, 0.0],
            [0.6, 0.5, 1.0],
            [1.6, 0.6, 0.0],
            [1.6, 0.6, 1.0],
        ],
        vec![],
        vec![],
        vec![
            [0, 1, 3],
            [0, 3, 2],
            [2, 3, 5],
            [2, 5, 4],
            [4, 5, 7],
            [4, 7, 6],
        ],
    )
    .unwrap();
    assert_eq!(vastocean::render::integrator::max_slope(&folded), None);
    // Slopes of 1 or more disable it too (see max_slope).
    let steep = Mesh::new(
        vec![[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [1.0, -1.2, 0.0]],
        vec![],
        vec![],
        vec![[0, 1, 2]],
    )
    .unwrap();
    assert_eq!(vastocean::render::integrator::max_slope(&steep), None);
}

#[test]
fn grazing_rays_at_the_horizon_give_no_nan() {
    let ocean = small_ocean(1.5);
    let sampler = ocean.sampler([0.0, 0.0]);
    let accel = accel(ocean_grid(&sampler, 300.0, 1.0));
    let mut sky = Sky::analytic(AnalyticSky::default());
    sky.dome_altitude_m = Some(200_000.0);
    let scene = scene_ref(accel.as_ref(), sampler, 6_371_000.0, &sky);
    // every policy: bending a normal at a grazing angle is the likeliest to divide by nothing
    for wrong_side in [
        WrongSide::Mirror,
        WrongSide::Flip,
        WrongSide::Bend,
        WrongSide::Terminate,
    ] {
        let (img, c) = render_image(
            &scene,
            &equirect(720, Some((1.0, -2.0))),
            2.0,
            2,
            5,
            &TraceSettings {
                wrong_side,
                ..TraceSettings::default()
            },
            0,
            false,
        );
        let img = img.image;
        assert_eq!(c.nan, 0, "{wrong_side:?}: {c:?}");
        assert!(
            img.pixels
                .iter()
                .all(|p| p.iter().all(|v| v.is_finite() && *v >= 0.0))
        );
        assert!(c.hits > 0);
    }
}

#[test]
fn rays_spawned_from_far_hits_never_rehit_their_own_triangle() {
    // The default ocean on the paper's low tessellation (out to 9.2 km); hits 5-9 km from the
    // camera, where f32 coordinates keep only about half a millimetre. Secondary rays leave
    // every hit in directions from steep to within 0.01 degrees of the triangle's plane.
    use vastocean::config::SceneConfig;
    use vastocean::render::integrator::spawn_ray;
    let cfg = SceneConfig::default();
    let lod = vastocean::lod::params_for(&cfg.lod, &cfg.camera).unwrap();
    let ocean = Surface::new(&cfg.ocean, cfg.render.ocean_seed).unwrap();
    let (mesh, _) = vastocean::lod::tessellate(&lod, &ocean.sampler([0.0, 0.0])).unwrap();
    for accel in crate::common::backends(mesh) {
        let mesh = accel.mesh();
        let mut rng = vastocean::rng::Rng::keyed(&[99]);
        let (mut spawned, mut rehit) = (0, Vec::new());
        while spawned < 40_000 {
            let (r, az) = (
                rng.range(5000.0, 9000.0),
                rng.range(0.0, std::f32::consts::TAU),
            );
            let target = Vec3::new(r * az.cos(), 0.0, r * az.sin());
            let d = Vec3::new(rng.range(-1.0, 1.0), -1.0, rng.range(-1.0, 1.0)).normalize();
            let Some(hit) =
                accel.intersect(&Ray::new((target - 30.0 * d).to_array(), d.to_array()))
            else {
                continue;
            };
            let [p0, p1, p2] = mesh.triangle(hit.prim).map(Vec3::from);
            let n = (p1 - p0).cross(p2 - p0).normalize();
            let t = (p1 - p0).normalize();
            for w in [
                d - 2.0 * d.dot(n) * n,
                d,
                (t + 2e-4 * n).normalize(),
                (t - 2e-4 * n).normalize(),
                (-t + 2e-4 * n).normalize(),
                (-t - 2e-4 * n).normalize(),
            ] {
                let ray = spawn_ray(mesh, &hit, w);
                spawned += 1;
                if let Some(h) = accel.intersect(&ray)
                    && h.prim == hit.prim
                {
                    rehit.push((hit, w, h.t));
                }
            }
        }
        assert!(
            rehit.is_empty(),
            "{}: {} of {spawned} spawned rays re-hit their own triangle, first {:?}",
            accel.name(),
            rehit.len(),
            rehit[0]
        );
    }
}
