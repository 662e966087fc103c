//! The renderer's fast paths against the plain ones: camera rays traced as batches give the
//! hits, radiance and counts of single rays, and a predicted camera hit is the closest hit.

use glam::Vec3;
use vastocean::accel::Ray;
use vastocean::config::WrongSide;
use vastocean::mesh::Mesh;
use vastocean::render::{
    AnalyticSky, Camera, NormalMode, SceneRef, Sky, TraceSettings, render_image,
};

use crate::render::{equirect, mean_abs_luminance_difference, ocean_grid, scene_ref, small_ocean};

/// Traces every `stride`-th pixel's `n` jittered camera rays as one batch (what the film does,
/// with the triangle its centre ray predicts) and one by one (a batch of one each, with the same
/// prediction): hit for hit, radiance bit for bit, count for count. A sample's result must not
/// depend on what else its batch holds, or a render split into passes would not merge into the
/// single render. (A batch whose rays all rise from above the highest vertex takes the sky
/// without the batch's stages; [`SceneRef::radiance`] never does.) Returns the counts and the
/// number of pixels.
fn assert_batches_match_single_rays(
    scene: &SceneRef,
    settings: &TraceSettings,
    camera: &Camera,
    stride: (usize, usize),
    n: usize,
) -> (vastocean::render::integrator::Counters, u64) {
    use vastocean::render::integrator::{CAMERA_BATCH, Counters};
    use vastocean::rng::Rng;
    let accel = scene.accel;
    let origin = [0.0, 2.0, 0.0];
    let (mut packed, mut single) = (Counters::default(), Counters::default());
    let mut pixels = 0;
    for y in (0..camera.height).step_by(stride.1) {
        for x in (0..camera.width).step_by(stride.0) {
            pixels += 1;
            let key = (y * camera.width + x) as u64;
            assert!(n <= CAMERA_BATCH);
            let pixel_rays = camera.pixel_rays(x, y);
            let rays: Vec<Ray> = (0..n)
                .map(|s| {
                    let j = (s as f32 + 0.5) / n as f32;
                    let d = pixel_rays.direction(j, (j * 7.0).fract());
                    Ray::new(origin, d.to_array())
                })
                .collect();
            let rng = |s: usize| Rng::keyed(&[3, key, s as u64]);
            // the film's draws for the first rough hits, one batch's points
            let strata = vastocean::render::strata::Strata::new(key);
            let draws: Vec<[f32; 2]> = (0..n as u32)
                .map(|j| {
                    let [u1, u2, ..] = strata.point(j);
                    [u1, u2]
                })
                .collect();
            let mut hits = vec![None; rays.len()];
            accel.intersect_many(&rays, &mut hits);
            let mut rngs: Vec<Rng> = (0..rays.len()).map(rng).collect();
            let mut out = vec![Vec3::ZERO; rays.len()];
            let centre = Ray::new(origin, pixel_rays.direction(0.5, 0.5).to_array());
            let predicted = scene.predict_camera_prim(&centre, &mut packed);
            assert_eq!(predicted, scene.predict_camera_prim(&centre, &mut single));
            scene.radiance_camera_batch(
                &rays,
                Some(&draws),
                predicted,
                settings,
                &mut rngs,
                &mut packed,
                &mut out,
            );
            for (s, ray) in rays.iter().enumerate() {
                assert_eq!(hits[s], accel.intersect(ray), "{} {ray:?}", accel.name());
                let mut l = [Vec3::ZERO];
                let one = std::slice::from_ref(ray);
                scene.radiance_camera_batch(
                    one,
                    Some(std::slice::from_ref(&draws[s])),
                    predicted,
                    settings,
                    &mut [rng(s)],
                    &mut single,
                    &mut l,
                );
                let l = l[0];
                assert_eq!(
                    l.to_array().map(f32::to_bits),
                    out[s].to_array().map(f32::to_bits),
                    "{} pixel ({x}, {y}) sample {s}",
                    accel.name()
                );
                // Without a prediction, a batch of one is what `radiance` gives.
                if predicted.is_none() {
                    let mut c = Counters::default();
                    let alone = scene.radiance(ray, false, 0, settings, &mut rng(s), &mut c);
                    assert_eq!(
                        alone.to_array().map(f32::to_bits),
                        l.to_array().map(f32::to_bits)
                    );
                }
            }
        }
    }
    // The timings differ run to run, and which calls are timed with the batching (normals are
    // computed a batch at a time); every other count must not.
    for c in [&mut packed, &mut single] {
        c.normal_batches = 0;
        (c.normal_timed, c.normal_timed_ns, c.normal_timed_points) = (0, 0, 0);
        (
            c.normal_timed_twice,
            c.normal_timed_twice_ns,
            c.normal_timed_twice_points,
        ) = (0, 0, 0);
    }
    assert_eq!(packed, single, "{}", accel.name());
    (single, pixels)
}

/// Two nested cubes about the camera (at 2 m), their vertex normals towards the centre but
/// leaning 45 degrees off their faces: most branches of a path meet a wall again, so past
/// `branch_depth` both branches of a hit draw random numbers.
fn nested_boxes() -> Mesh {
    let (mut positions, mut normals, mut indices) = (vec![], vec![], vec![]);
    for half in [5.0f32, 10.0] {
        for axis in 0..3 {
            for sign in [-1.0f32, 1.0] {
                let mut n = [0.0f32; 3];
                n[axis] = -sign * std::f32::consts::FRAC_1_SQRT_2;
                n[(axis + 1) % 3] = std::f32::consts::FRAC_1_SQRT_2;
                let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
                let base = positions.len() as u32;
                for (u, v) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                    let mut p = [0.0f32; 3];
                    (p[axis], p[a], p[b]) = (sign * half, u * half, v * half);
                    p[1] += 2.0;
                    positions.push(p);
                    normals.push(n);
                }
                indices.extend([[base, base + 1, base + 2], [base, base + 2, base + 3]]);
            }
        }
    }
    Mesh::new(positions, normals, vec![], indices).unwrap()
}

#[test]
fn camera_batches_give_the_same_hits_and_radiance_as_single_rays() {
    // The ocean, as the film renders it (mapped normals, the skip shortcuts), on every backend.
    let ocean = small_ocean(0.8);
    let sampler = ocean.sampler([0.0, 0.0]);
    let mesh = ocean_grid(&sampler, 40.0, 0.5);
    let slope = vastocean::render::integrator::max_slope(&mesh);
    let top = vastocean::render::integrator::highest_vertex_y(&mesh);
    let sky = Sky::analytic(AnalyticSky::default());
    let camera = equirect(256, Some((10.0, -60.0)));
    for accel in crate::common::backends(mesh) {
        let scene = SceneRef {
            skip_slope: slope,
            skip_above_y: top,
            predict_camera_hits: true,
            ..scene_ref(accel.as_ref(), sampler, 6_371_000.0, &sky)
        };
        // Full batches, a partial one, a lone ray.
        for n in [16, 5, 1] {
            let (c, pixels) = assert_batches_match_single_rays(
                &scene,
                &TraceSettings::default(),
                &camera,
                (13, 7),
                n,
            );
            assert!(
                c.hits > 10 * pixels * n as u64 / 16 && c.skipped_above > 0 && c.predicted > 0,
                "{c:?}"
            );
        }
    }
    // Paths that branch and bounce to the last segment: past `branch_depth` both branches of
    // most hits draw random choices, and their sub-batches thin out as rays escape, so each
    // sample's draws and results must be kept apart from its neighbours' at every depth. The
    // walls' vertex normals lean off their faces, so every wrong-side policy acts too.
    for accel in crate::common::backends(nested_boxes()) {
        let scene = SceneRef {
            ocean: None,
            ..scene_ref(accel.as_ref(), sampler, 6_371_000.0, &sky)
        };
        for (n, wrong_side) in [
            (16, WrongSide::Bend),
            (7, WrongSide::Bend),
            (16, WrongSide::Mirror),
            (16, WrongSide::Flip),
            (16, WrongSide::Terminate),
        ] {
            let settings = TraceSettings {
                normals: NormalMode::Vertex,
                branch_depth: 2,
                wrong_side,
                ..TraceSettings::default()
            };
            let (c, pixels) =
                assert_batches_match_single_rays(&scene, &settings, &equirect(32, None), (3, 3), n);
            assert!(
                c.hits > 2 * n as u64 * pixels && c.backfacing_shading > 0,
                "{c:?}"
            );
            assert!(
                wrong_side != WrongSide::Terminate || c.terminated > 0,
                "{c:?}"
            );
        }
    }
}

/// A camera ray descending more steeply than the mesh slopes crosses it once, so the hit it
/// finds on its pixel's predicted triangle is the BVH's closest hit, up to rounding; a shallower
/// ray must not take the predicted hit, which a crest in front may hide.
#[test]
fn predicted_camera_hits_are_the_closest_hits() {
    use vastocean::render::integrator::{Counters, hit_on_triangle, max_slope};
    let ocean = small_ocean(0.8);
    let sampler = ocean.sampler([0.0, 0.0]);
    let mesh = ocean_grid(&sampler, 40.0, 0.5);
    let slope = max_slope(&mesh);
    let sky = Sky::analytic(AnalyticSky::default());
    let camera = equirect(128, Some((0.0, -70.0)));
    for accel in crate::common::backends(mesh) {
        let scene = |predict| SceneRef {
            skip_slope: slope,
            predict_camera_hits: predict,
            ..scene_ref(accel.as_ref(), sampler, 6_371_000.0, &sky)
        };
        // The whole integrator: the same camera rays need a hit (every predicted one has it),
        // and pixels differ only where rounding moved a hit (which may also move a later
        // bounce: those counts agree closely, not exactly).
        let render = |predict| {
            render_image(
                &scene(predict),
                &camera,
                2.0,
                16,
                0,
                &TraceSettings::default(),
                0,
                false,
            )
        };
        let ((off, c_off), (on, c_on)) = (render(false), render(true));
        assert!(
            c_on.predicted > c_on.hits / 2 && c_on.prediction_rays > 0 && c_off.predicted == 0,
            "{c_on:?}"
        );
        assert_eq!(
            (c_on.rays, c_on.escaped_below_horizon),
            (c_off.rays, c_off.escaped_below_horizon)
        );
        assert!(
            c_on.hits.abs_diff(c_off.hits) <= c_off.hits / 1000,
            "{c_on:?} {c_off:?}"
        );
        let d = mean_abs_luminance_difference(&off.image, &on.image);
        let mean =
            on.image.pixels.iter().map(|p| p[1] as f64).sum::<f64>() / on.image.pixels.len() as f64;
        assert!(d < 1e-3 * mean, "{} {d} {mean}", accel.name());

        // Ray by ray: a steep ray's hit on the predicted triangle is the closest hit.
        let s = scene(true);
        let mut c = Counters::default();
        let mut checked = 0;
        for y in 0..camera.height {
            for x in (0..camera.width).step_by(3) {
                let pixel_rays = camera.pixel_rays(x, y);
                let ray = |jx, jy| Ray::new([0.0, 2.0, 0.0], pixel_rays.direction(jx, jy).into());
                let Some(prim) = s.predict_camera_prim(&ray(0.5, 0.5), &mut c) else {
                    continue;
                };
                let tri = accel.mesh().triangle(prim).map(Vec3::from);
                for j in 0..8 {
                    let r = ray((j as f32 + 0.5) / 8.0, (j as f32 * 0.37 + 0.1).fract());
                    if !s.descends_steeply(Vec3::from(r.dir)) {
                        continue;
                    }
                    let Some(p) = hit_on_triangle(&r, tri, prim) else {
                        continue;
                    };
                    let h = accel.intersect(&r).expect("a hit");
                    checked += 1;
                    assert!((h.t - p.t).abs() <= 1e-5 * p.t, "{r:?} {h:?} {p:?}");
                    if h.prim == prim {
                        assert!(
                            (h.u - p.u).abs() < 1e-4 && (h.v - p.v).abs() < 1e-4,
                            "{h:?} {p:?}"
                        );
                    }
                }
            }
        }
        assert!(checked > 1000, "{checked}");
    }

    // A ridge of slope 0.5 across the view, 14 to 18 m out, on a flat sea: a ray descending at
    // 0.1 meets its front, leaves through its back and meets the flat beyond; one at 0.8
    // meets the flat before the ridge. Each triangle has its own vertices, the vertex normals
    // its face normal, so where a ray hits shows in its radiance.
    let profile = [
        (-50.0f32, 0.0f32),
        (14.0, 0.0),
        (16.0, 1.0),
        (18.0, 0.0),
        (50.0, 0.0),
    ];
    let (mut positions, mut normals, mut indices) = (vec![], vec![], vec![]);
    for w in profile.windows(2) {
        let [(z0, y0), (z1, y1)] = [w[0], w[1]];
        let quad = [
            [-50.0, y0, z0],
            [-50.0, y1, z1],
            [50.0, y1, z1],
            [50.0, y0, z0],
        ];
        for tri in [[0, 1, 2], [0, 2, 3]] {
            let p = tri.map(|i| Vec3::from(quad[i]));
            let n = (p[1] - p[0]).cross(p[2] - p[0]).normalize();
            assert!(n.y > 0.0, "wound facing up");
            let base = positions.len() as u32;
            positions.extend(p.map(|p| p.to_array()));
            normals.extend([n.to_array(); 3]);
            indices.push([base, base + 1, base + 2]);
        }
    }
    let ridge = Mesh::new(positions, normals, vec![], indices).unwrap();
    assert_eq!(max_slope(&ridge), Some(0.5));
    let settings = TraceSettings {
        normals: NormalMode::Vertex,
        ..TraceSettings::default()
    };
    let camera_ray = |slope: f32| {
        Ray::new(
            [0.0, 2.0, 0.0],
            Vec3::new(0.0, -slope, 1.0).normalize().into(),
        )
    };
    let (shallow, steep) = (camera_ray(0.1), camera_ray(0.8));
    for accel in crate::common::backends(ridge) {
        let scene = SceneRef {
            skip_slope: Some(0.5),
            predict_camera_hits: true,
            ocean: None,
            ..scene_ref(accel.as_ref(), sampler, f64::INFINITY, &sky)
        };
        // The triangle a ray meets among the flat sea's past the ridge (6, 7) or before it.
        let meets = |ray: &Ray, prims: std::ops::Range<u32>| {
            prims
                .into_iter()
                .find(|&p| {
                    vastocean::accel::bvh::intersect_triangle(ray, accel.mesh().triangle(p))
                        .is_some()
                })
                .expect("a hit")
        };
        let (far_flat, near_flat) = (meets(&shallow, 6..8), meets(&steep, 0..2));
        let alone = |ray: &Ray, predicted| {
            let mut c = Counters::default();
            let mut l = [Vec3::ZERO];
            let mut rng = [vastocean::rng::Rng::keyed(&[1])];
            scene.radiance_camera_batch(
                &[*ray],
                None,
                predicted,
                &settings,
                &mut rng,
                &mut c,
                &mut l,
            );
            (l[0], c)
        };
        let (traced, _) = alone(&shallow, None);
        let (with_prediction, c) = alone(&shallow, Some(far_flat));
        assert_eq!(c.predicted, 0, "{}", accel.name());
        assert_eq!(with_prediction, traced, "{}", accel.name());
        // Had it taken the flat's hit, it would see what a parallel ray starting past the
        // ridge sees, which differs (the check above can fail).
        let past = Ray::new([0.0, 0.2, 18.0], shallow.dir);
        let (on_flat, _) = alone(&past, None);
        assert!(
            (traced - on_flat).length() > 1e-3 * on_flat.length(),
            "{traced} {on_flat}"
        );
        // Steeper than the ridge: the predicted flat triangle before it is taken.
        let (l, c) = alone(&steep, Some(near_flat));
        assert_eq!(c.predicted, 1, "{}", accel.name());
        assert!((l - alone(&steep, None).0).length() <= 1e-5 * l.length());
    }
}
