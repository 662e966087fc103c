//! Tests of the exact surface: the pyramids' bounds against every read, the implicit function
//! on and off the surface, the prisms around their patches, and hits against a dense march.

use std::sync::Arc;

use super::implicit::sphere_coords;
use super::*;
use crate::lod::{LodParams, Pattern, Reading, tessellate};
use crate::ocean::slopes::{ALL_WAVES, LevelSet};
use crate::ocean::{LayerSpec, OceanParams, field};
use crate::rng::Rng;

const EARTH_R: f64 = crate::lod::EARTH_RADIUS_M;
const CAMERA_M: f64 = 5.0;

pub(super) fn sea(choppiness: f64) -> Arc<Surface> {
    let p = OceanParams {
        layers: vec![
            LayerSpec {
                size_m: 200.0,
                n: 128,
            },
            LayerSpec {
                size_m: 23.7,
                n: 128,
            },
            LayerSpec {
                size_m: 2.93,
                n: 64,
            },
        ],
        choppiness,
        ..OceanParams::default()
    };
    Arc::new(Surface::new(&p, 7).unwrap())
}

fn coarse_mesh(ocean: &Surface, origin: [f64; 2]) -> Mesh {
    let params = LodParams {
        near_size_m: 0.9,
        double_distance_m: 18.0,
        generations: None,
        max_distance_m: Some(300.0),
        pattern: Pattern::Square,
        reading: Reading::default(),
        earth_radius_m: EARTH_R,
        camera_height_m: CAMERA_M,
    };
    tessellate(&params, &ocean.sampler(origin)).unwrap().0
}

/// Every read's h and displacement lie within its box's ranges, which narrow with the box.
#[test]
fn pyramid_bounds_hold_every_read_and_narrow_with_the_box() {
    let ocean = sea(1.0);
    let origin = [1234.5, -987.25];
    let sampler = ocean.sampler(origin);
    let b = SurfaceBounds::new(&sampler, None);
    let global = b.height(&ALL_WAVES, -1e6, 1e6, -1e6, 1e6);
    let mut rng = Rng::keyed(&[3]);
    let (mut narrower, mut narrower_d) = (0, 0);
    for _ in 0..400 {
        let (x0, z0) = (rng.f64() * 600.0 - 300.0, rng.f64() * 600.0 - 300.0);
        let size = 0.01 * 1e4f64.powf(rng.f64()); // 1 cm to 100 m
        let (x1, z1) = (x0 + size, z0 + size * rng.f64());
        let [lo, hi] = b.height(&ALL_WAVES, x0, x1, z0, z1);
        assert!(lo >= global[0] && hi <= global[1]);
        narrower += usize::from(hi - lo < 0.5 * (global[1] - global[0]));
        let d = b.displacement(&ALL_WAVES, x0, x1, z0, z1);
        let [dx, dz] = b.disp(&ALL_WAVES);
        assert!(d[0] >= -dx - 1e-6 && d[1] <= dx + 1e-6, "{d:?} {dx}");
        assert!(d[2] >= -dz - 1e-6 && d[3] <= dz + 1e-6, "{d:?} {dz}");
        narrower_d += usize::from(d[1] - d[0] < dx);
        for _ in 0..50 {
            let (x, z) = (x0 + (x1 - x0) * rng.f64(), z0 + (z1 - z0) * rng.f64());
            let f = sampler.fields_f64(x, z);
            let h = f[field::H] as f64;
            assert!(lo <= h && h <= hi, "{h} outside [{lo}, {hi}] at ({x}, {z})");
            let (fx, fz) = (f[field::DX] as f64, f[field::DZ] as f64);
            assert!(
                d[0] <= fx && fx <= d[1],
                "Dx {fx} outside {d:?} at ({x}, {z})"
            );
            assert!(
                d[2] <= fz && fz <= d[3],
                "Dz {fz} outside {d:?} at ({x}, {z})"
            );
        }
    }
    // boxes of centimetres to metres are far narrower than the whole sea's range
    assert!(
        narrower > 200,
        "{narrower} of 400 boxes narrower than half the range"
    );
    // and their displacement ranges narrower than half the largest |Dx| on either side
    assert!(
        narrower_d > 200,
        "{narrower_d} of 400 boxes with a Dx range under the largest |Dx|"
    );
}

/// A box's own slope and strain bounds hold every secant of the bilinear surface inside it
/// (a secant is a mean of the derivative between its ends), and on boxes of centimetres to a
/// few metres they are well below the whole sea's.
#[test]
fn local_slope_and_strain_bounds_hold_every_secant_in_the_box() {
    let ocean = sea(1.0);
    let origin = [1234.5, -987.25];
    let sampler = ocean.sampler(origin);
    let b = SurfaceBounds::new(&sampler, None);
    let global = b.steepness(&ALL_WAVES, -1e6, 1e6, -1e6, 1e6);
    let sea = b.sea_steepness(&ALL_WAVES);
    let global_limit = sea
        .slope_limit()
        .expect("the test sea has a slope bound")
        .norm;
    // summed per layer, the strain's Gershgorin bound is never tighter than the sea's own
    assert!(global.slope_limit().expect("bounded").norm >= global_limit);
    // (the pyramids' f32 blocks are rounded up by 1e-6)
    for (g, s) in global.slope.iter().zip(sea.slope) {
        assert!(*g >= s && *g <= s * (1.0 + 2e-6), "{g} {s}");
    }
    let mut rng = Rng::keyed(&[4]);
    let mut lower = 0;
    const EPS: f64 = 1e-3;
    for _ in 0..300 {
        let (x0, z0) = (rng.f64() * 600.0 - 300.0, rng.f64() * 600.0 - 300.0);
        let size = 0.01 * 300f64.powf(rng.f64()); // 1 cm to 3 m
        let (x1, z1) = (x0 + size, z0 + size);
        let local = b.steepness(&ALL_WAVES, x0, x1, z0, z1);
        assert!(local.slope[0] <= global.slope[0] && local.slope[1] <= global.slope[1]);
        assert!(local.strain <= global.strain);
        // the box's bound, and one over a centimetre more on each side for the arc-position
        // secants below (their paths in nominal position stray a little from their ends)
        let limit = local
            .slope_limit()
            .expect("the test sea's strain is below 0.95");
        lower += usize::from(limit.norm < 0.5 * global_limit);
        let wide = b
            .steepness(&ALL_WAVES, x0 - 0.01, x1 + 0.01, z0 - 0.01, z1 + 0.01)
            .slope_limit()
            .expect("bounded");
        for _ in 0..40 {
            let x = x0 + (x1 - x0 - EPS) * rng.f64();
            let z = z0 + (z1 - z0 - EPS) * rng.f64();
            let f = |x: f64, z: f64| sampler.fields_f64(x, z).map(|v| v as f64);
            let (c, right, below) = (f(x, z), f(x + EPS, z), f(x, z + EPS));
            let d = |a: &[f64; crate::ocean::FIELD_COUNT], k: usize| (a[k] - c[k]) / EPS;
            let (hx, hz) = (d(&right, field::H), d(&below, field::H));
            // f32 texels: differences over 1 mm carry their rounding, ~1e-7 m / 1e-3 m
            let tol = 1e-2;
            assert!(
                hx.abs() <= local.slope[0] + tol && hz.abs() <= local.slope[1] + tol,
                "{hx} {hz} {local:?}"
            );
            // H(s) = h(x(s)), s = x + D(x): between two surface points 1 mm apart in a random
            // direction, the change of h is within the directional bound of the change of s
            let (ux, uz) = (rng.f64() * std::f64::consts::TAU).sin_cos();
            let far = f(x + EPS * ux, z + EPS * uz);
            let ds = [
                EPS * ux + far[field::DX] - c[field::DX],
                EPS * uz + far[field::DZ] - c[field::DZ],
            ];
            let dh = (far[field::H] - c[field::H]).abs();
            let bound = wide.rate(ds[0].abs(), ds[1].abs(), ds[0].hypot(ds[1]));
            assert!(dh <= bound + tol * EPS, "{dh} > {bound} {wide:?}");
            assert!(bound <= wide.norm * ds[0].hypot(ds[1]) * (1.0 + 1e-12));
            let s = [
                [d(&right, field::DX), d(&below, field::DX)],
                [d(&right, field::DZ), d(&below, field::DZ)],
            ];
            let rows = (s[0][0].abs() + s[0][1].abs()).max(s[1][0].abs() + s[1][1].abs());
            assert!(rows <= local.strain + tol, "{s:?} {local:?}");
        }
    }
    assert!(
        lower > 150,
        "{lower} of 300 boxes' slope bounds below half the sea's ({global_limit})"
    );
}

/// A stretch's box of nominal positions, narrowed by the displacement's range, holds the
/// nominal position of the surface point under every point of the stretch: rays from 2 m to
/// 10 km up, steep to grazing, stretches of 1 cm to 300 m out to 60 km.
#[test]
fn a_stretch_box_holds_the_nominal_positions_under_it() {
    let ocean = sea(1.0);
    let surface = ExactSurface::new(ocean, [50.0, 20.0], EARTH_R, false).unwrap();
    let mut rng = Rng::keyed(&[8]);
    let mut narrower = 0;
    let [dx, _] = surface.all.disp;
    for _ in 0..300 {
        let height = 2.0 * 5000f64.powf(rng.f64());
        let (az, dip) = (
            std::f64::consts::TAU * rng.f64(),
            0.001 + 1.5 * rng.f64().powi(3),
        );
        let d = [dip.cos() * az.cos(), -dip.sin(), dip.cos() * az.sin()];
        let reach = (height / dip.sin()).min(60e3);
        let t0 = reach * rng.f64();
        let t1 = t0 + 0.01 * 3e4f64.powf(rng.f64());
        let (area, points) = surface.nominal_box_and_points([0.0, height, 0.0], d, [t0, t1], 40);
        narrower += usize::from(area[1] - area[0] < (t1 - t0) + 2.0 * dx - 0.1);
        for e in points.iter().filter(|e| e.converged) {
            let [x, z] = e.x;
            assert!(
                area[0] <= x && x <= area[1] && area[2] <= z && z <= area[3],
                "({x}, {z}) outside {area:?} ({height} m up, dip {dip}, t {t0}..{t1})"
            );
        }
    }
    // the narrowing narrows: most boxes are well inside the sea's largest displacement
    assert!(narrower > 150, "{narrower} of 300 boxes narrowed");
}

#[test]
fn implicit_function_is_the_signed_altitude_above_the_surface() {
    for chop in [0.0, 1.0] {
        let ocean = sea(chop);
        let origin = [50.0, 20.0];
        let surface = ExactSurface::new(ocean.clone(), origin, EARTH_R, false).unwrap();
        // inversions to full accuracy, and as a march runs them (to a tenth of F)
        let imp = Implicit {
            lip: f64::INFINITY,
            ..surface.implicit(&surface.all)
        };
        let marching = surface.implicit(&surface.all);
        let mut rng = Rng::keyed(&[5]);
        for _ in 0..300 {
            let r = 5000.0 * rng.f64();
            let phi = std::f64::consts::TAU * rng.f64();
            let x = [r * phi.cos(), r * phi.sin()];
            let f = imp.sampler.fields_f64(x[0], x[1]);
            let v = [f[field::DX] as f64, f[field::H] as f64, f[field::DZ] as f64];
            let p = crate::lod::curved_frame_position(x[0], x[1], v, EARTH_R);
            let e = imp.eval(p, &mut None);
            assert!(e.f.abs() < 1e-6, "F = {} on the surface (chop {chop})", e.f);
            assert!(
                (e.x[0] - x[0]).abs() < 1e-4 && (e.x[1] - x[1]).abs() < 1e-4,
                "nominal {x:?} found as {:?}",
                e.x
            );
            // straight up and down from the surface point: F is the altitude difference
            let (s, _) = sphere_coords(p, EARTH_R);
            let up = {
                let c = [p[0], p[1] + EARTH_R, p[2]];
                let l = (c[0] * c[0] + c[1] * c[1] + c[2] * c[2]).sqrt();
                c.map(|k| k / l)
            };
            for delta in [-0.01, 0.01, 0.3] {
                let q = std::array::from_fn(|k| p[k] + delta * up[k]);
                let (sq, _) = sphere_coords(q, EARTH_R);
                assert!((sq[0] - s[0]).abs() < 1e-6 && (sq[1] - s[1]).abs() < 1e-6);
                let fq = imp.eval(q, &mut None).f;
                assert!(
                    (fq - delta).abs() < 1e-5,
                    "F {fq} at {delta} m (chop {chop})"
                );
                let fm = marching.eval(q, &mut None).f;
                assert!(
                    (fm - delta).abs() <= 0.1 * delta.abs() + 1e-6,
                    "{fm} at {delta} m"
                );
            }
        }
    }
}

/// Every surface point `point` gives at 20 random nominal positions in every 37th triangle of
/// `mesh` lies in that triangle's prism; how many of those prisms are under 2 m tall.
fn check_prisms_hold(
    mesh: &Mesh,
    prisms: &[([f32; 3], [f32; 3])],
    rng: &mut Rng,
    mut point: impl FnMut(&mut Rng, [f64; 2]) -> [f64; 3],
) -> usize {
    let mut tight = 0;
    for (tri, prism) in mesh.indices().iter().zip(prisms).step_by(37) {
        let uv = tri.map(|v| mesh.uvs()[v as usize].map(f64::from));
        for _ in 0..20 {
            let (mut a, mut b) = (rng.f64(), rng.f64());
            if a + b > 1.0 {
                (a, b) = (1.0 - a, 1.0 - b);
            }
            let x: [f64; 2] = std::array::from_fn(|k| {
                uv[0][k] + a * (uv[1][k] - uv[0][k]) + b * (uv[2][k] - uv[0][k])
            });
            let p = point(rng, x);
            for k in 0..3 {
                assert!(
                    prism.0[k] as f64 <= p[k] && p[k] <= prism.1[k] as f64,
                    "{p:?} outside {prism:?}"
                );
            }
        }
        tight += usize::from(prism.1[1] - prism.0[1] < 2.0);
    }
    tight
}

/// The surface point of nominal position `x` on the surface `lod` that `sampler` reads.
fn surface_point(sampler: &crate::ocean::Sampler, x: [f64; 2], lod: &LevelSet) -> [f64; 3] {
    let f = sampler.fields_f64_at(x[0], x[1], lod);
    let v = [f[field::DX] as f64, f[field::H] as f64, f[field::DZ] as f64];
    crate::lod::curved_frame_position(x[0], x[1], v, EARTH_R)
}

#[test]
fn prisms_hold_the_surface_over_their_triangles() {
    let ocean = sea(1.0);
    let origin = [0.0, 0.0];
    let mesh = coarse_mesh(&ocean, origin);
    let surface = ExactSurface::new(ocean.clone(), origin, EARTH_R, false).unwrap();
    let prisms = prisms_of(&mesh, &surface);
    let sampler = ocean.sampler(origin);
    let mut rng = Rng::keyed(&[9]);
    let tight = check_prisms_hold(&mesh, &prisms, &mut rng, |_, x| {
        surface_point(&sampler, x, &ALL_WAVES)
    });
    assert!(tight > 0, "every prism is taller than 2 m");
}

/// The first sign change of F along the ray by steps of `step` metres, narrowed by bisection in
/// f64, up to `t_max`: the oracle.
fn dense_march(
    surface: &ExactSurface,
    lod: &LevelSet,
    ray: &Ray,
    step: f64,
    t_max: f64,
) -> Option<f64> {
    let imp = surface.implicit(&surface.query(lod).view);
    let o = ray.org.map(f64::from);
    let d = ray.dir.map(f64::from);
    let at = |t: f64| -> [f64; 3] { std::array::from_fn(|k| o[k] + t * d[k]) };
    let f = |t: f64| imp.eval(at(t), &mut None).f;
    let mut t = ray.tnear as f64;
    let mut ft = f(t);
    while t < t_max {
        let tn = t + step;
        let fnext = f(tn);
        if (fnext > 0.0) != (ft > 0.0) {
            let (mut a, mut b) = (t, tn);
            for _ in 0..60 {
                let m = 0.5 * (a + b);
                if (f(m) > 0.0) == (ft > 0.0) {
                    a = m;
                } else {
                    b = m;
                }
            }
            return Some(0.5 * (a + b));
        }
        (t, ft) = (tn, fnext);
    }
    None
}

/// 48 rays, each on the surface `lod_of` draws for it: camera rays from steep to grazing, and
/// rays rising at grazing angles from just above and just below that surface; each hits where
/// the dense march finds the first sign change, to 1e-4 of t, and names the nominal position
/// of the point hit. Returns how many hit.
fn agree_with_a_dense_march(exact: &Exact, lod_of: &mut dyn FnMut(&mut Rng) -> LevelSet) -> usize {
    let mut rng = Rng::keyed(&[11]);
    let mut rays = Vec::new();
    // camera rays, steep to grazing
    for _ in 0..24 {
        let el = -(3.5f64 + 60.0 * rng.f64().powi(3)).to_radians();
        let az = std::f64::consts::TAU * rng.f64();
        let d = [el.cos() * az.cos(), el.sin(), el.cos() * az.sin()];
        let lod = lod_of(&mut rng);
        rays.push((
            Ray::new([0.0, CAMERA_M as f32, 0.0], d.map(|c| c as f32)),
            lod,
        ));
    }
    // rays rising at grazing angles from just above the surface (reflections that may meet
    // the next wave) and from just below it (refractions, which meet it from the water side)
    for k in 0..24 {
        let lod = lod_of(&mut rng);
        let imp = exact.surface().implicit(&exact.surface().query(&lod).view);
        let x = [40.0 * rng.f64() - 20.0, 40.0 * rng.f64() - 20.0];
        let p = surface_point(&imp.sampler, x, &lod);
        let above = k % 2 == 0;
        let el = (0.5 + 8.0 * rng.f64()).to_radians();
        let az = std::f64::consts::TAU * rng.f64();
        let o = [p[0], p[1] + if above { 0.02 } else { -0.02 }, p[2]];
        let d = [el.cos() * az.cos(), el.sin(), el.cos() * az.sin()];
        rays.push((Ray::new(o.map(|c| c as f32), d.map(|c| c as f32)), lod));
    }
    let mut hits = 0;
    for (ray, lod) in &rays {
        let want = dense_march(exact.surface(), lod, ray, 0.002, 150.0);
        let got = exact.intersect_at(ray, lod).filter(|h| h.t < 150.0);
        match (want, got) {
            (None, None) => {}
            (Some(w), Some(g)) => {
                hits += 1;
                assert!(
                    (g.t as f64 - w).abs() <= 1e-4 * w.max(1.0),
                    "t {} against the oracle's {w} on {ray:?} ({lod:?})",
                    g.t
                );
                // the hit names the nominal position of the surface point hit
                let imp = exact.surface().implicit(&exact.surface().query(lod).view);
                let x = exact.interpolate_uv(&g).map(f64::from);
                let p = ray.at(g.t).map(f64::from);
                let e = imp.eval(p, &mut None);
                assert!((e.x[0] - x[0]).abs() < 1e-2 && (e.x[1] - x[1]).abs() < 1e-2);
            }
            (w, g) => panic!("oracle {w:?}, exact {g:?} on {ray:?} ({lod:?})"),
        }
    }
    hits
}

/// The test sea and its exact surface in the coarse mesh's prisms around the origin (with the
/// levels' surfaces too where `levels`).
fn exact_on_the_sea(levels: bool) -> (Arc<Surface>, Arc<Mesh>, Exact) {
    let ocean = sea(1.0);
    let mesh = Arc::new(coarse_mesh(&ocean, [0.0, 0.0]));
    let surface = ExactSurface::new(ocean.clone(), [0.0, 0.0], EARTH_R, levels).unwrap();
    let exact = Exact::build(mesh.clone(), surface);
    (ocean, mesh, exact)
}

#[test]
fn hits_agree_with_a_dense_march() {
    let (_, _, exact) = exact_on_the_sea(false);
    let hits = agree_with_a_dense_march(&exact, &mut |_| ALL_WAVES);
    assert!(hits >= 36, "{hits} of 48 rays hit");
}

/// A random surface of the layers' levels: each layer at one of its levels, or left out.
fn random_lod(ocean: &Surface, rng: &mut Rng) -> LevelSet {
    let levels = ocean.levels();
    let mut lod = ALL_WAVES;
    for (i, l) in lod.iter_mut().enumerate().take(ocean.layers().len()) {
        let n = levels.count(i) + 2;
        let pick = ((rng.f64() * n as f64) as usize).min(n - 1);
        *l = if pick > levels.count(i) {
            crate::ocean::slopes::NOT_READ
        } else {
            pick as u8
        };
    }
    lod
}

/// With the levels held, rays on random surfaces of them (each layer at one of its levels, or
/// left out) hit where the dense march on that surface finds its first crossing, and the
/// prisms hold every such surface over their triangles.
#[test]
fn hits_on_the_levels_surfaces_agree_with_a_dense_march() {
    let (ocean, mesh, exact) = exact_on_the_sea(true);
    let hits = agree_with_a_dense_march(&exact, &mut |rng| random_lod(&ocean, rng));
    assert!(hits >= 30, "{hits} of 48 rays hit");
    let sampler = ocean.sampler([0.0, 0.0]).with_levels(ocean.levels());
    let mut rng = Rng::keyed(&[12]);
    check_prisms_hold(&mesh, &exact.prisms, &mut rng, |rng, x| {
        surface_point(&sampler, x, &random_lod(&ocean, rng))
    });
}
