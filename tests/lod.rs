//! The doubling tessellation (paper section 2, Figure 1): watertight meshes without T-junctions
//! for both patterns and every reading, no cracks under a real displaced ocean (rays straight
//! down through Embree), texture coordinate = nominal position, triangle sizes following the
//! doubling rule, the curved-earth mapping against Rodrigues' rotation, horizon distances,
//! auto LOD against the pixel footprint, exact counts, PLY round trip, and input errors.

use std::collections::HashMap;

use vastocean::lod::{
    self, LodParams, Pattern, Preset, Reading, count_triangles, horizon_distance, tessellate,
    try_count,
};
use vastocean::mesh::{Mesh, write_ply};
use vastocean::ocean::{LayerSpec, OceanParams, Surface};

const R_EARTH: f64 = 6_371_000.0;

/// s = 0.5 m, d = 4 m, 3 generations: rings end at 4, 8, 16, 32 m (`nested`) or 4, 12, 28, 60 m
/// (`widths`); d / s is even, so no ring edge is snapped.
fn small(reading: Reading, pattern: Pattern, max: f64) -> LodParams {
    LodParams {
        near_size_m: 0.5,
        double_distance_m: 4.0,
        generations: Some(3),
        max_distance_m: Some(max),
        pattern,
        reading,
        earth_radius_m: R_EARTH,
        camera_height_m: 2.0,
    }
}

/// One small FFT layer so the suite stays fast; choppy, so vertices move sideways too.
fn small_ocean() -> Surface {
    let params = OceanParams {
        layers: vec![LayerSpec {
            size_m: 37.3,
            n: 64,
        }],
        ..OceanParams::default()
    };
    Surface::new(&params, 7).expect("small ocean")
}

fn configs() -> Vec<(String, LodParams)> {
    let frustum = Pattern::Frustum {
        yaw_deg: 30.0,
        hfov_deg: 90.0,
    };
    let mut out = Vec::new();
    for &reading in Reading::ALL {
        for (pattern, max) in [
            (Pattern::Square, 40.0),
            (Pattern::Square, 21.0),
            (frustum, 40.0),
        ] {
            out.push((
                format!("{reading:?} {pattern} max {max}"),
                small(reading, pattern, max),
            ));
        }
    }
    // Narrow wedges in many directions: their edges cut through the split cells everywhere.
    for yaw_deg in (0..24).map(|i| i as f64 * 15.0 + 7.0) {
        let pattern = Pattern::Frustum {
            yaw_deg,
            hfov_deg: 8.0,
        };
        out.push((
            format!("nested {pattern}"),
            small(Reading::Nested, pattern, 40.0),
        ));
    }
    // Uncapped, cut by distance inside a ring with a coarser one outside, and snapped ring
    // edges (d / s odd).
    let mut p = small(Reading::Nested, Pattern::Square, 30.0);
    p.generations = None;
    p.double_distance_m = 3.5;
    out.push(("nested uncapped, snapped".into(), p));
    out
}

fn uv_radius(uv: [f32; 2]) -> f64 {
    (uv[0] as f64).hypot(uv[1] as f64)
}

/// Checks that every edge is used by one or two triangles, twice only with opposite
/// directions, that one-triangle edges lie on the rim, and that no vertex sits inside an edge.
fn check_watertight(name: &str, params: &LodParams, mesh: &Mesh) {
    let s0 = params.near_size_m;
    let uvs = mesh.uvs();
    let lattice: Vec<(i64, i64)> = uvs
        .iter()
        .map(|uv| {
            let q = uv.map(|c| c as f64 / s0);
            let l = q.map(|c| c.round());
            assert!(
                (q[0] - l[0]).abs() < 1e-4 && (q[1] - l[1]).abs() < 1e-4,
                "{name}: uv {uv:?} off the {s0} m lattice"
            );
            (l[0] as i64, l[1] as i64)
        })
        .collect();
    let at: HashMap<(i64, i64), u32> = lattice
        .iter()
        .enumerate()
        .map(|(i, &p)| (p, i as u32))
        .collect();
    assert_eq!(at.len(), uvs.len(), "{name}: two vertices at one position");
    let mut edges: HashMap<(u32, u32), (u32, i32)> = HashMap::new();
    for t in mesh.indices() {
        for e in 0..3 {
            let (a, b) = (t[e], t[(e + 1) % 3]);
            let entry = edges.entry((a.min(b), a.max(b))).or_default();
            entry.0 += 1;
            entry.1 += if a < b { 1 } else { -1 };
        }
    }
    let rings = lod::rings(params).unwrap();
    let outer = rings.last().unwrap().2;
    let max = params.max_distance();
    let mut boundary = 0;
    for (&(a, b), &(n, dir)) in &edges {
        assert!(n <= 2, "{name}: edge ({a}, {b}) in {n} triangles");
        if n == 2 {
            assert_eq!(dir, 0, "{name}: edge ({a}, {b}) wound the same way twice");
        } else {
            boundary += 1;
            let (pa, pb) = (uvs[a as usize], uvs[b as usize]);
            let mid = [0.5 * (pa[0] + pb[0]), 0.5 * (pa[1] + pb[1])];
            let cheb = mid[0].abs().max(mid[1].abs()) as f64;
            let on_rim = uv_radius(mid) >= max - 1e-3 || cheb >= outer - 1e-3;
            let outside_fov = match params.pattern {
                Pattern::Square => false,
                Pattern::Frustum { yaw_deg, hfov_deg } => {
                    let ang = (mid[1] as f64).atan2(mid[0] as f64).to_degrees() - yaw_deg;
                    let ang = (ang + 540.0).rem_euclid(360.0) - 180.0;
                    ang.abs() > 0.5 * hfov_deg
                }
            };
            assert!(
                on_rim || outside_fov,
                "{name}: open edge at {mid:?} inside the tessellated region"
            );
        }
    }
    assert!(boundary > 0, "{name}: a finite mesh has a rim");
    // T-junctions: walk each edge over the finest lattice and look for a vertex on it.
    for &(a, b) in edges.keys() {
        let (p, q) = (lattice[a as usize], lattice[b as usize]);
        let (dx, dz) = (q.0 - p.0, q.1 - p.1);
        let g = gcd(dx.unsigned_abs(), dz.unsigned_abs()) as i64;
        for t in 1..g {
            let r = (p.0 + dx / g * t, p.1 + dz / g * t);
            assert!(
                !at.contains_key(&r),
                "{name}: vertex at {r:?} inside edge {p:?}-{q:?} (T-junction)"
            );
        }
    }
    // Every vertex is used.
    let mut used = vec![false; mesh.vertex_count()];
    for t in mesh.indices() {
        for &i in t {
            used[i as usize] = true;
        }
    }
    assert!(used.iter().all(|&u| u), "{name}: unreferenced vertex");
}

fn gcd(a: u64, b: u64) -> u64 {
    if b == 0 { a } else { gcd(b, a % b) }
}

#[test]
fn meshes_are_watertight_without_t_junctions() {
    let flat = Surface::flat();
    let sampler = flat.sampler([0.0, 0.0]);
    for (name, params) in configs() {
        let (mesh, stats) = tessellate(&params, &sampler).unwrap();
        assert_eq!(stats.triangles, mesh.triangle_count());
        check_watertight(&name, &params, &mesh);
    }
}

#[test]
fn counts_match_the_built_mesh() {
    let flat = Surface::flat();
    let sampler = flat.sampler([0.0, 0.0]);
    for (name, params) in configs() {
        let (mesh, stats) = tessellate(&params, &sampler).unwrap();
        let c = try_count(&params).unwrap();
        // `mesh` and `mesh --count-only` report the same extent.
        assert_eq!(c.max_distance_m, stats.max_distance_m, "{name}");
        assert_eq!(
            (c.triangles, c.vertices),
            (mesh.triangle_count(), mesh.vertex_count()),
            "{name}"
        );
        assert_eq!(count_triangles(&params), c.triangles);
        assert_eq!(
            stats.per_ring.iter().map(|r| r.triangles).sum::<usize>(),
            c.triangles
        );
    }
}

#[test]
fn no_triangle_is_degenerate() {
    let ocean = small_ocean();
    let sampler = ocean.sampler([1234.5, -987.0]);
    for (name, params) in configs() {
        let (mesh, _) = tessellate(&params, &sampler).unwrap();
        for (k, t) in mesh.indices().iter().enumerate() {
            let [a, b, c] = t.map(|i| mesh.uvs()[i as usize]);
            let nominal = 0.5
                * ((b[0] - a[0]) as f64 * (c[1] - a[1]) as f64
                    - (b[1] - a[1]) as f64 * (c[0] - a[0]) as f64);
            let side = cell_side(&[a, b, c].map(|p| p.map(|v| v as f64)));
            // Wound like Mesh::grid (negative in (x, z)); at least a quarter of its cell.
            assert!(
                -nominal >= 0.249 * side * side,
                "{name}: triangle {k} nominal area {nominal}"
            );
            let [p, q, r] = mesh.triangle(k as u32);
            let u: [f64; 3] = std::array::from_fn(|i| (q[i] - p[i]) as f64);
            let v: [f64; 3] = std::array::from_fn(|i| (r[i] - p[i]) as f64);
            let n = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            let area = 0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            assert!(area > 1e-3 * -nominal, "{name}: triangle {k} area {area}");
        }
    }
}

/// The side of the grid cell a triangle was cut from: its longest edge in the Chebyshev norm
/// (a side or diagonal of the cell; a fan to a midpoint has half sides too).
fn cell_side(p: &[[f64; 2]; 3]) -> f64 {
    (0..3)
        .map(|e| {
            let (a, b) = (p[e], p[(e + 1) % 3]);
            (b[0] - a[0]).abs().max((b[1] - a[1]).abs())
        })
        .fold(0.0, f64::max)
}

/// The rule itself: ring k of `nested` reaches d 2^k, of `widths` d (2^(k+1) - 1); triangles
/// there have cells of s 2^min(k, cap).
fn expected_size(params: &LodParams, cheb: f64) -> f64 {
    let d = params.double_distance_m;
    let cap = params.generations.unwrap_or(u32::MAX);
    let mut k = 0u32;
    loop {
        let edge = match params.reading {
            Reading::NestedWhole | Reading::Nested | Reading::NestedToHorizon => {
                d * 2f64.powi(k as i32)
            }
            Reading::Widths | Reading::WidthsToHorizon => d * (2f64.powi(k as i32 + 1) - 1.0),
        };
        if cheb < edge || k >= cap {
            return params.near_size_m * 2f64.powi(k.min(cap) as i32);
        }
        k += 1;
    }
}

#[test]
fn triangle_size_follows_the_doubling_rule() {
    let flat = Surface::flat();
    let sampler = flat.sampler([0.0, 0.0]);
    for &reading in Reading::ALL {
        let params = small(reading, Pattern::Square, 90.0);
        let (mesh, stats) = tessellate(&params, &sampler).unwrap();
        let mut seen = std::collections::BTreeSet::new();
        for t in mesh.indices() {
            let p = t.map(|i| mesh.uvs()[i as usize].map(|c| c as f64));
            let c = [0, 1].map(|i| (p[0][i] + p[1][i] + p[2][i]) / 3.0);
            let shortest = cell_side(&p);
            let want = expected_size(&params, c[0].abs().max(c[1].abs()));
            assert!(
                (shortest - want).abs() < 1e-6,
                "{reading:?}: triangle at {c:?} has side {shortest}, rule says {want}"
            );
            seen.insert((shortest * 1000.0) as i64);
        }
        assert_eq!(seen.len(), 4, "{reading:?}: sizes {seen:?}");
        assert_eq!(stats.rings, 4);
        let far = mesh
            .uvs()
            .iter()
            .map(|&uv| uv_radius(uv))
            .fold(0.0, f64::max);
        // The cap ends the square at its corner, or the last generation runs to the cut.
        let (lo, hi) = match reading {
            Reading::Nested | Reading::NestedWhole => (32.0 * 2f64.sqrt(), 32.0 * 2f64.sqrt()),
            Reading::Widths => (60.0 * 2f64.sqrt(), 60.0 * 2f64.sqrt()),
            _ => (90.0, 90.0 + 4.0 * 2f64.sqrt()),
        };
        assert!(far >= lo - 1e-3 && far <= hi + 1e-3, "{reading:?}: {far}");
    }
}

/// Rodrigues' rotation of v by `theta` about the unit axis k.
fn rodrigues(v: [f64; 3], k: [f64; 3], theta: f64) -> [f64; 3] {
    let (s, c) = theta.sin_cos();
    let kxv = [
        k[1] * v[2] - k[2] * v[1],
        k[2] * v[0] - k[0] * v[2],
        k[0] * v[1] - k[1] * v[0],
    ];
    let kv = k[0] * v[0] + k[1] * v[1] + k[2] * v[2];
    std::array::from_fn(|i| v[i] * c + kxv[i] * s + k[i] * kv * (1.0 - c))
}

#[test]
fn vertices_hold_nominal_position_displaced_point_and_normal_on_the_sphere() {
    let ocean = small_ocean();
    let sampler = ocean.sampler([50.0, 20.0]);
    // Small planets, so the tilt is large enough to see; on the smaller two the outer vertices
    // lie past the small-angle series' reach (0.1 rad), the inner ones within it, and on 20 m
    // so far past it (2.8 rad) that the series would be wrong in f32.
    for radius in [2000.0, 200.0, 20.0] {
        vertices_on_a_planet(&sampler, radius);
    }
    // The far rim of a sea at rest drops by about r^2 / 2R.
    let mut params = small(Reading::Nested, Pattern::Square, 40.0);
    params.earth_radius_m = 2000.0;
    let flat = Surface::flat();
    let (mesh, _) = tessellate(&params, &flat.sampler([0.0, 0.0])).unwrap();
    for (p, uv) in mesh.positions().iter().zip(mesh.uvs()) {
        let r = uv_radius(*uv);
        assert!((p[1] as f64 + r * r / 4000.0).abs() < 1e-3 * (1.0 + r * r / 4000.0));
    }
}

fn vertices_on_a_planet(sampler: &vastocean::ocean::Sampler, radius: f64) {
    let mut params = small(Reading::Nested, Pattern::Square, 40.0);
    params.earth_radius_m = radius;
    let (mesh, _) = tessellate(&params, sampler).unwrap();
    let rings = lod::rings(&params).unwrap();
    // vertices past the series' reach and within it
    let mut reach = [0usize; 2];
    for v in 0..mesh.vertex_count() {
        let uv = mesh.uvs()[v];
        let (x, z) = (uv[0] as f64, uv[1] as f64);
        // The texture coordinate is the nominal lattice point of the vertex's ring.
        let cheb = x.abs().max(z.abs());
        let ring = rings.iter().find(|r| cheb <= r.2 + 1e-9).unwrap();
        let size = ring.0;
        for c in [x, z] {
            assert!(((c / size).round() - c / size).abs() < 1e-5, "uv {uv:?}");
        }
        // Independent oracle: the flat-frame point and normal rotated about the sphere's
        // centre by r / R, the axis perpendicular to the nadir-to-vertex direction.
        let s = sampler.sample(uv[0], uv[1]);
        let r = x.hypot(z);
        let (ux, uz) = if r > 0.0 { (x / r, z / r) } else { (1.0, 0.0) };
        let axis = [uz, 0.0, -ux];
        let theta = r / params.earth_radius_m;
        let above_centre = [
            s.disp[0] as f64,
            params.earth_radius_m + s.height as f64,
            s.disp[1] as f64,
        ];
        let p = rodrigues(above_centre, axis, theta);
        let want = [p[0], p[1] - params.earth_radius_m, p[2]];
        let got = mesh.positions()[v];
        // bit for bit the one-at-a-time frame, within the series' reach or past it
        let (one, _) = lod::curved_frame_point(x, z, &s, radius);
        assert_eq!(got, one.map(|c| c as f32), "vertex {v} at {uv:?}");
        reach[usize::from(theta < 0.1)] += 1;
        for i in 0..3 {
            assert!(
                (got[i] as f64 - want[i]).abs() < 2e-4,
                "vertex {v} at {uv:?}: {got:?} vs {want:?}"
            );
        }
        let n = rodrigues(s.normal.map(|c| c as f64), axis, theta);
        let gn = mesh.normals()[v];
        for i in 0..3 {
            assert!((gn[i] as f64 - n[i]).abs() < 1e-5, "normal {gn:?} vs {n:?}");
        }
    }
    if radius < 400.0 {
        assert!(reach[0] > 0 && reach[1] > 0, "{reach:?}");
    }
}

#[test]
fn horizon_distance_matches_sqrt_2rh() {
    for h in [2.0, 100.0] {
        let want = (2.0 * R_EARTH * h).sqrt();
        let got = horizon_distance(h, R_EARTH);
        assert!((got / want - 1.0).abs() < 0.01, "{h} m: {got} vs {want}");
        // Tessellation by default stops just past it.
        let params = LodParams {
            near_size_m: h * 10.0,
            double_distance_m: h * 50.0,
            generations: None,
            max_distance_m: None,
            reading: Reading::Nested,
            ..Preset::PaperLow.params(h)
        };
        let flat = Surface::flat();
        let (mesh, stats) = tessellate(&params, &flat.sampler([0.0, 0.0])).unwrap();
        let far = mesh
            .uvs()
            .iter()
            .map(|&uv| uv_radius(uv))
            .fold(0.0, f64::max);
        let last = stats.per_ring.last().unwrap().size_m;
        assert!(stats.max_distance_m > got && stats.max_distance_m < 1.06 * got);
        assert!(
            far >= stats.max_distance_m && far <= stats.max_distance_m + 1.5 * last,
            "{h} m: farthest vertex {far}, max {}",
            stats.max_distance_m
        );
    }
    assert!((horizon_distance(2.0, R_EARTH) - 5048.0).abs() < 1.0);
}

#[test]
fn whole_reading_completes_the_ring_that_reaches_the_cut() {
    let mut params = small(Reading::NestedWhole, Pattern::Square, 21.0);
    params.generations = None;
    let flat = Surface::flat();
    let (mesh, stats) = tessellate(&params, &flat.sampler([0.0, 0.0])).unwrap();
    // Rings end at 4, 8, 16 and 32 m; the last reaches past 21 m and is kept whole.
    assert_eq!(stats.rings, 4);
    assert_eq!(stats.max_distance_m, 32.0);
    let cheb = |uv: &[f32; 2]| uv[0].abs().max(uv[1].abs());
    assert_eq!(mesh.uvs().iter().map(cheb).fold(0.0, f32::max), 32.0);
    // N = d / s = 8: (2N)^2 cells in the centre, 3 N^2 in each doubled ring, two triangles
    // per cell and one more for each of the 4 N cells along a hole.
    let n = 8;
    assert_eq!(mesh.triangle_count(), 8 * n * n + 3 * (6 * n * n + 4 * n));
}

#[test]
fn frustum_pattern_skips_what_the_camera_cannot_see() {
    let flat = Surface::flat();
    let sampler = flat.sampler([0.0, 0.0]);
    let (yaw, hfov) = (-120.0, 60.0);
    let square = small(Reading::Nested, Pattern::Square, 40.0);
    let frustum = small(
        Reading::Nested,
        Pattern::Frustum {
            yaw_deg: yaw,
            hfov_deg: hfov,
        },
        40.0,
    );
    let (all, _) = tessellate(&square, &sampler).unwrap();
    let (seen, _) = tessellate(&frustum, &sampler).unwrap();
    let fraction = seen.triangle_count() as f64 / all.triangle_count() as f64;
    assert!(fraction < 0.3, "{fraction}");
    let (mut in_view, mut far) = (0, 0);
    for t in seen.indices() {
        let p = t.map(|i| seen.uvs()[i as usize].map(|c| c as f64));
        let c = [0, 1].map(|i| (p[0][i] + p[1][i] + p[2][i]) / 3.0);
        let r = c[0].hypot(c[1]);
        let ang = (c[1].atan2(c[0]).to_degrees() - yaw + 540.0).rem_euclid(360.0) - 180.0;
        if r >= 3.0 {
            far += 1;
            if ang.abs() <= 0.5 * hfov {
                in_view += 1;
            }
        }
        // Cells straddle the wedge's edge.
        assert!(
            r < 3.0 || ang.abs() < 0.5 * hfov + 25.0,
            "triangle at {c:?} ({ang} deg) is behind the camera"
        );
    }
    assert!(
        in_view as f64 > 0.7 * far as f64,
        "{in_view} of {far} in view"
    );
    // Everything the camera sees is there: the wedge of the square mesh is in the frustum mesh.
    let keys = |m: &Mesh| -> std::collections::HashSet<[i64; 6]> {
        m.indices()
            .iter()
            .map(|t| {
                let mut k = t.map(|i| m.uvs()[i as usize].map(|c| (c * 1000.0).round() as i64));
                k.sort();
                [k[0][0], k[0][1], k[1][0], k[1][1], k[2][0], k[2][1]]
            })
            .collect()
    };
    let seen_keys = keys(&seen);
    for (t, k) in all.indices().iter().zip(keys(&all)) {
        let _ = t;
        let c = [0, 1].map(|i| (k[i] + k[2 + i] + k[4 + i]) as f64 / 3000.0);
        let ang = (c[1].atan2(c[0]).to_degrees() - yaw + 540.0).rem_euclid(360.0) - 180.0;
        if ang.abs() < 0.5 * hfov {
            assert!(seen_keys.contains(&k), "in-view triangle at {c:?} missing");
        }
    }
}

#[test]
fn auto_lod_keeps_triangles_near_the_pixel_footprint() {
    let (h, width) = (2.0, 1024);
    let mut params = LodParams::auto(h, width);
    let a = std::f64::consts::TAU / width as f64;
    assert!((params.near_size_m - a * h).abs() < 1e-12);
    params.max_distance_m = Some(150.0);
    let flat = Surface::flat();
    let (mesh, _) = tessellate(&params, &flat.sampler([0.0, 0.0])).unwrap();
    let (mut lo, mut hi) = (f64::INFINITY, 0.0f64);
    for t in mesh.indices() {
        let p = t.map(|i| mesh.uvs()[i as usize].map(|c| c as f64));
        let c = [0, 1].map(|i| (p[0][i] + p[1][i] + p[2][i]) / 3.0);
        let side = cell_side(&p);
        let footprint = a * (c[0] * c[0] + c[1] * c[1] + h * h).sqrt();
        lo = lo.min(side / footprint);
        hi = hi.max(side / footprint);
    }
    assert!(
        lo > 0.5 && hi < 2.5,
        "triangle / pixel footprint in [{lo}, {hi}]"
    );
}

#[cfg(feature = "embree")]
#[test]
fn rays_straight_down_never_fall_through_the_displaced_mesh() {
    use std::sync::Arc;
    use vastocean::accel::embree::{BuildOptions, Device, Scene};
    use vastocean::accel::{Accel, Ray};
    use vastocean::rng::Rng;

    let ocean = small_ocean();
    let sampler = ocean.sampler([-3210.0, 777.0]);
    let mut params = small(Reading::Nested, Pattern::Square, 60.0);
    params.generations = None;
    params.near_size_m = 0.25;
    params.double_distance_m = 3.0;
    let (mesh, _) = tessellate(&params, &sampler).unwrap();
    let device = Device::new(2).expect("Embree device");
    let scene = Scene::new(&device, Arc::new(mesh), BuildOptions::default()).unwrap();
    let mut rng = Rng::keyed(&[42, 0x6c6f64]);
    let radius = 0.9 * params.max_distance();
    let rays: Vec<Ray> = (0..100_000)
        .map(|_| {
            let r = radius * (rng.f32() as f64).sqrt();
            let phi = std::f64::consts::TAU * rng.f32() as f64;
            Ray::new(
                [(r * phi.cos()) as f32, 50.0, (r * phi.sin()) as f32],
                [0.0, -1.0, 0.0],
            )
        })
        .collect();
    let mut hits = vec![None; rays.len()];
    scene.intersect_many(&rays, &mut hits);
    let misses: Vec<_> = rays
        .iter()
        .zip(&hits)
        .filter(|(_, h)| h.is_none())
        .map(|(r, _)| r.org)
        .take(5)
        .collect();
    assert!(misses.is_empty(), "rays fell through at {misses:?}");
}

/// Every tessellation's whole cells come in blocks ([`vastocean::mesh::Block`], checked
/// against the triangles when the mesh is made): no triangle is in two blocks, and the blocks
/// hold every triangle but those of the cells touching a coarser ring's hole.
#[test]
fn blocks_hold_every_whole_cell_once() {
    let flat = Surface::flat();
    let sampler = flat.sampler([0.0, 0.0]);
    for (name, params) in configs() {
        let (mesh, _) = tessellate(&params, &sampler).unwrap();
        let mut seen = vec![false; mesh.triangle_count()];
        for b in mesh.blocks() {
            for &first in &mesh.block_rows()[b.first_row as usize..][..usize::from(b.rows)] {
                for (t, seen) in seen
                    .iter_mut()
                    .enumerate()
                    .skip(first as usize)
                    .take(2 * usize::from(b.cells))
                {
                    assert!(!*seen, "{name}: triangle {t} in two blocks");
                    *seen = true;
                }
            }
        }
        let outside = seen.iter().filter(|&&b| !b).count();
        // the cells along each hole: three triangles each, and two whole cells at each corner
        let sides: usize = lod::rings(&params)
            .unwrap()
            .iter()
            .skip(1)
            .map(|&(size, inner, _)| 4 * (3 * (2.0 * inner / size).round() as usize + 2 * 2))
            .sum();
        assert!(
            outside <= sides,
            "{name}: {outside} triangles outside the blocks, at most {sides} expected"
        );
        // rows stack into blocks: fewer blocks than cell rows with blocks in them
        assert!(!mesh.blocks().is_empty(), "{name}: no blocks");
        assert!(
            mesh.blocks().iter().any(|b| b.rows > 1),
            "{name}: no block of more than one row"
        );
    }
}

/// Embree traces a tessellation's blocks as grids: the same hits as its triangles give (the
/// same triangle, t and barycentrics within f32 rounding), bar rays through an edge.
#[cfg(feature = "embree")]
#[test]
fn a_tessellation_traced_as_grids_hits_what_its_triangles_do() {
    use std::sync::Arc;
    use vastocean::accel::embree::{BuildOptions, Device, Scene};
    use vastocean::accel::{Accel, Ray};
    use vastocean::rng::Rng;

    let ocean = small_ocean();
    let sampler = ocean.sampler([-3210.0, 777.0]);
    let params = small(Reading::Nested, Pattern::Square, 60.0);
    let (mesh, _) = tessellate(&params, &sampler).unwrap();
    let mesh = Arc::new(mesh);
    let device = Device::new(2).expect("Embree device");
    let scene = |grids| {
        let options = BuildOptions {
            grids,
            ..BuildOptions::default()
        };
        Scene::new(&device, mesh.clone(), options).unwrap()
    };
    let (grids, triangles) = (scene(true), scene(false));
    let mut rng = Rng::keyed(&[43, 0x6c6f64]);
    // from 2 m up in every direction below the horizon, grazing ones included
    let rays: Vec<Ray> = (0..100_000)
        .map(|_| {
            let el = -(1e-3 + 0.5 * rng.f32()).powi(2) * 3.0;
            let az = std::f32::consts::TAU * rng.f32();
            let d = [el.cos() * az.cos(), el.sin(), el.cos() * az.sin()];
            Ray::new([rng.f32() - 0.5, 2.0, rng.f32() - 0.5], d)
        })
        .collect();
    let (mut a, mut b) = (vec![None; rays.len()], vec![None; rays.len()]);
    grids.intersect_many(&rays, &mut a);
    triangles.intersect_many(&rays, &mut b);
    let (mut hits, mut edges) = (0, 0);
    for (ray, (g, t)) in rays.iter().zip(a.iter().zip(&b)) {
        match (g, t) {
            (Some(g), Some(t)) if g.prim == t.prim => {
                hits += 1;
                assert!(
                    (g.t - t.t).abs() <= 1e-5 * t.t,
                    "{ray:?}: t {} vs {}",
                    g.t,
                    t.t
                );
                assert!(
                    (g.u - t.u).abs() < 1e-4 && (g.v - t.v).abs() < 1e-4,
                    "{ray:?}: barycentrics ({}, {}) vs ({}, {})",
                    g.u,
                    g.v,
                    t.u,
                    t.v
                );
                let (pu, pt) = (grids.interpolate_uv(g), triangles.interpolate_uv(t));
                assert!((pu[0] - pt[0]).abs() < 1e-3 && (pu[1] - pt[1]).abs() < 1e-3);
            }
            (None, None) => {}
            // a ray through an edge or a vertex may meet either side
            (Some(h), _) | (None, Some(h)) => {
                let near_edge = h.u.min(h.v).min(1.0 - h.u - h.v) < 1e-4;
                assert!(near_edge, "{ray:?}: grids {g:?}, triangles {t:?}");
                edges += 1;
            }
        }
    }
    assert!(hits > 60_000, "{hits} rays hit the sea");
    assert!(edges < 50, "{edges} rays through edges");
}

#[test]
fn ply_round_trip() {
    let flat = Surface::flat();
    let params = small(Reading::Nested, Pattern::Square, 10.0);
    let (mesh, _) = tessellate(&params, &flat.sampler([0.0, 0.0])).unwrap();
    let dir = std::env::temp_dir().join(format!("vastocean-lod-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("mesh.ply");
    write_ply(&mesh, &path).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let end = b"end_header\n";
    let split = bytes
        .windows(end.len())
        .position(|w| w == end)
        .expect("header")
        + end.len();
    let header = std::str::from_utf8(&bytes[..split]).unwrap();
    let lines: Vec<&str> = header
        .lines()
        .filter(|l| !l.starts_with("comment"))
        .collect();
    let (nv, nf) = (mesh.vertex_count(), mesh.triangle_count());
    let vertex = format!("element vertex {nv}");
    let face = format!("element face {nf}");
    assert_eq!(
        lines,
        [
            "ply",
            "format binary_little_endian 1.0",
            &vertex,
            "property float x",
            "property float y",
            "property float z",
            "property float nx",
            "property float ny",
            "property float nz",
            "property float s",
            "property float t",
            &face,
            "property list uchar uint vertex_indices",
            "end_header",
        ]
    );
    let body = &bytes[split..];
    assert_eq!(body.len(), nv * 32 + nf * 13);
    let f = |at: usize| f32::from_le_bytes(body[at..at + 4].try_into().unwrap());
    let last = nv - 1;
    assert_eq!(
        [f(last * 32), f(last * 32 + 4), f(last * 32 + 8)],
        mesh.positions()[last]
    );
    assert_eq!([f(last * 32 + 24), f(last * 32 + 28)], mesh.uvs()[last]);
    let faces = &body[nv * 32..];
    for (k, t) in mesh.indices().iter().enumerate() {
        let rec = &faces[k * 13..k * 13 + 13];
        assert_eq!(rec[0], 3);
        let idx: [u32; 3] = std::array::from_fn(|i| {
            u32::from_le_bytes(rec[1 + 4 * i..5 + 4 * i].try_into().unwrap())
        });
        assert_eq!(&idx, t);
    }
    // Only the final file remains; a bad path fails without leaving anything.
    let names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, ["mesh.ply"]);
    // A folder that cannot exist (its parent is a regular file): the error names the file.
    let e = write_ply(&mesh, &dir.join("mesh.ply").join("m.ply")).unwrap_err();
    assert!(e.to_string().contains("m.ply"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_parameters_name_the_field() {
    let base = Preset::PaperHigh.params(2.0);
    let msg = |f: &dyn Fn(&mut LodParams)| {
        let mut p = base.clone();
        f(&mut p);
        p.validate().unwrap_err().to_string()
    };
    assert_eq!(
        msg(&|p| p.near_size_m = 0.0),
        "lod.near_size_m must be finite and > 0 (got 0)"
    );
    assert!(msg(&|p| p.double_distance_m = f64::NAN).starts_with("lod.double_distance_m"));
    assert!(msg(&|p| p.camera_height_m = -1.0).starts_with("lod.camera_height_m"));
    assert!(msg(&|p| p.max_distance_m = Some(f64::INFINITY)).starts_with("lod.max_distance_m"));
    assert!(
        msg(&|p| p.pattern = Pattern::Frustum {
            yaw_deg: 0.0,
            hfov_deg: 200.0
        })
        .starts_with("lod.pattern.hfov_deg")
    );
    let mut huge = base.clone();
    huge.near_size_m = 1e-4;
    huge.generations = None;
    assert!(matches!(
        try_count(&huge),
        Err(lod::LodError::TooLarge { .. })
    ));
    // Config files: unknown keys are refused; the pattern parses from TOML and the CLI form.
    let toml_text = r#"
        near_size_m = 0.9
        double_distance_m = 18.0
        generations = 6
        pattern = { kind = "frustum", yaw_deg = 10.0, hfov_deg = 70.0 }
        reading = "widths"
        earth_radius_m = 6371000.0
        camera_height_m = 2.0
    "#;
    let p: LodParams = toml::from_str(toml_text).unwrap();
    assert_eq!(p.reading, Reading::Widths);
    assert_eq!(p.pattern, "frustum:10:70".parse().unwrap());
    assert_eq!(p.pattern.to_string().parse::<Pattern>().unwrap(), p.pattern);
    assert!(toml::from_str::<LodParams>(&format!("{toml_text}\nbogus = 1")).is_err());
    assert!("frustum:10".parse::<Pattern>().is_err());
    assert!("square".parse::<Pattern>() == Ok(Pattern::Square));
}

/// The counts of the module doc's readings table and the default reading's pinned values.
#[test]
fn paper_preset_counts_for_the_default_reading() {
    let high = count_triangles(&Preset::PaperHigh.params(2.0));
    let low = count_triangles(&Preset::PaperLow.params(2.0));
    println!("default reading: high {high}, low {low} (paper 22341600, 25520)");
    assert_eq!((high, low), (22_341_600, 25_520));
    // The closed form behind them: 62 N^2 + 36 N for N = d / s.
    for n in [600usize, 20] {
        let want = 62 * n * n + 36 * n;
        assert!(want == high || want == low);
    }
}

/// The module doc's readings table: (high, low) with the text's cap of 6, then without a cap.
#[test]
#[ignore = "counts every reading of both paper tessellations (about 10 s)"]
fn readings_table() {
    let table = [
        (
            Reading::NestedWhole,
            (15_854_400, 18_080),
            (22_341_600, 25_520),
        ),
        (Reading::Nested, (15_854_400, 18_080), (20_047_904, 23_064)),
        (Reading::Widths, (49_098_392, 56_112), (57_203_344, 65_608)),
        (
            Reading::NestedToHorizon,
            (60_884_136, 68_816),
            (20_047_904, 23_064),
        ),
        (
            Reading::WidthsToHorizon,
            (85_660_280, 97_248),
            (57_203_344, 65_608),
        ),
    ];
    for (reading, capped, uncapped) in table {
        for (generations, want) in [(Some(6), capped), (None, uncapped)] {
            let [high, low] = [Preset::PaperHigh, Preset::PaperLow].map(|p| {
                let mut params = p.params(2.0);
                params.reading = reading;
                params.generations = generations;
                count_triangles(&params)
            });
            println!("{reading:?} cap {generations:?}: high {high}, low {low}");
            assert_eq!((high, low), want, "{reading:?} cap {generations:?}");
        }
    }
}

fn build_and_report(params: &LodParams) {
    let ocean = Surface::new(&OceanParams::default(), 1).unwrap();
    let start = std::time::Instant::now();
    let (mesh, stats) = tessellate(params, &ocean.sampler([0.0, 0.0])).unwrap();
    println!(
        "{} triangles, {} vertices, {} rings, {:.2} s, {} MB",
        stats.triangles,
        stats.vertices,
        stats.rings,
        start.elapsed().as_secs_f64(),
        stats.bytes >> 20
    );
    assert_eq!(mesh.triangle_count(), count_triangles(params));
}

#[test]
#[ignore = "builds the paper-high tessellation (22 M triangles) on the default ocean"]
fn paper_high_tessellation() {
    build_and_report(&Preset::PaperHigh.params(2.0));
}
