//! The Rust BVH (Woop, Benthin & Wald 2013 watertight intersection, binned SAH build): agreement
//! with the brute-force oracle and with Embree, watertight shared edges, and degenerate input.

use std::sync::Arc;

use rayon::prelude::*;
use vastocean::accel::bvh::{Bvh, intersect_triangle};
use vastocean::accel::{Accel, Hit, Ray, brute::BruteForce};
use vastocean::mesh::Mesh;

use crate::common::{Verdict, judge, random_mesh, random_rays};

/// How far (barycentric) the ray's line passes from the nearest edge of `prim`, in f64.
/// Unlike `judge`'s tolerance, a triangle the line misses by a wide margin counts as far.
fn edge_margin(mesh: &Mesh, ray: &Ray, prim: u32) -> f64 {
    let wide = Ray {
        tnear: f32::MIN,
        tfar: f32::MAX,
        ..*ray
    };
    // Grows the triangle about its centroid until the line meets it, to learn the margin
    // without re-deriving barycentrics here.
    let tri = mesh.triangle(prim);
    let c: [f32; 3] = std::array::from_fn(|k| (tri[0][k] + tri[1][k] + tri[2][k]) / 3.0);
    for grow in [1.0f32, 1.0003, 1.003, 1.03, 1.3, 3.0, 30.0] {
        let g = tri.map(|v| std::array::from_fn(|k| c[k] + grow * (v[k] - c[k])));
        if vastocean::accel::brute::intersect_triangle(&wide, g).is_some() {
            return (grow - 1.0) as f64;
        }
    }
    f64::INFINITY
}

/// Checks `accel` against brute force on `rays`: no wrong answer, few ambiguous ones, every
/// hit a real intersection (within f32 rounding) of the triangle it names. Returns the hits.
fn check_against_oracle(accel: &dyn Accel, oracle: &BruteForce, rays: &[Ray]) -> Vec<Option<Hit>> {
    let mut hits = vec![None; rays.len()];
    accel.intersect_many(rays, &mut hits);
    let verdicts: Vec<Verdict> = rays
        .par_iter()
        .zip(&hits)
        .map(|(r, h)| judge(oracle, r, *h, 1e-4))
        .collect();
    let wrong: Vec<_> = verdicts
        .iter()
        .filter(|v| matches!(v, Verdict::Wrong(_)))
        .collect();
    assert!(
        wrong.is_empty(),
        "{}: {} wrong of {}, first {:?}",
        accel.name(),
        wrong.len(),
        rays.len(),
        wrong[0]
    );
    let ambiguous = verdicts
        .iter()
        .filter(|v| **v == Verdict::Ambiguous)
        .count();
    assert!(
        ambiguous * 5_000 <= rays.len().max(5_000),
        "{}: {ambiguous} ambiguous of {}",
        accel.name(),
        rays.len()
    );
    let bogus = rays
        .par_iter()
        .zip(&hits)
        .filter(|(r, h)| h.is_some_and(|h| edge_margin(oracle.mesh(), r, h.prim) > 1e-3))
        .count();
    assert_eq!(
        bogus,
        0,
        "{}: hits on triangles the ray misses",
        accel.name()
    );
    hits
}

#[test]
fn bvh_agrees_with_brute_force_on_random_meshes() {
    for (tris, size, seed, nrays, min_hits) in [
        (1, 0.8, 11, 2_000, 5),
        (7, 0.5, 12, 5_000, 50),
        (300, 0.2, 13, 20_000, 1_500),
        (10_000, 0.08, 1, 20_000, 6_000),
    ] {
        let mesh = Arc::new(random_mesh(tris, size, seed));
        let oracle = BruteForce::new((*mesh).clone());
        let rays = random_rays(nrays, seed + 100);
        let bvh = Bvh::build(mesh.clone());
        bvh.validate().unwrap();
        let hits = check_against_oracle(&bvh, &oracle, &rays);
        let hit_count = hits.iter().filter(|h| h.is_some()).count();
        eprintln!("{tris} triangles: {hit_count} hits of {nrays}");
        assert!(
            hit_count >= min_hits,
            "{tris} triangles stopped only {hit_count} of {nrays} rays"
        );
        // The any-hit query agrees with the closest hit, also when tfar stops short of it.
        for (r, h) in rays.iter().zip(&hits) {
            assert_eq!(bvh.occluded(r), h.is_some(), "{r:?}");
            assert_eq!(bvh.intersect(r), *h);
            if let Some(h) = h {
                let short = Ray {
                    tfar: 0.5 * h.t,
                    ..*r
                };
                assert_eq!(bvh.occluded(&short), bvh.intersect(&short).is_some());
                assert!(bvh.intersect(&short).is_none_or(|s| s.t <= short.tfar));
            }
        }
        #[cfg(feature = "embree")]
        {
            use vastocean::accel::embree::{BuildOptions, Device, Scene};
            let scene =
                Scene::new(&Device::new(2).unwrap(), mesh, BuildOptions::default()).unwrap();
            check_against_oracle(&scene, &oracle, &rays);
        }
    }
}

#[test]
fn degenerate_centroids_and_triangles_build_and_trace() {
    // 50 copies of one triangle: no SAH split separates them, so the build must split by
    // count. Every copy is at the same t; any of them is a right answer.
    let n = 50u32;
    let mut positions = Vec::new();
    for _ in 0..n {
        positions.extend([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]);
    }
    let indices = (0..n).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]).collect();
    let bvh = Bvh::build(Arc::new(
        Mesh::new(positions, vec![], vec![], indices).unwrap(),
    ));
    bvh.validate().unwrap();
    assert!(bvh.node_count() > 1);
    let h = bvh
        .intersect(&Ray::new([0.2, 1.0, 0.3], [0.0, -1.0, 0.0]))
        .unwrap();
    assert!(h.prim < n && h.t == 1.0 && (h.u - 0.2).abs() < 1e-6 && (h.v - 0.3).abs() < 1e-6);

    // Only degenerate triangles (a point, a segment): nothing to hit, nothing to crash.
    let m = Mesh::new(
        vec![[0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]],
        vec![],
        vec![],
        vec![[0, 0, 0], [0, 1, 2], [1, 2, 1]],
    )
    .unwrap();
    let bvh = Bvh::build(Arc::new(m));
    bvh.validate().unwrap();
    for r in [
        Ray::new([0.0, 1.0, 0.0], [0.0, -1.0, 0.0]),
        Ray::new([1.0, 1.0, 0.0], [0.0, -1.0, 0.0]),
        Ray::new([-1.0, 0.0, 0.0], [1.0, 0.0, 0.0]),
    ] {
        assert_eq!(bvh.intersect(&r), None, "{r:?}");
        assert!(!bvh.occluded(&r));
    }
}

#[test]
fn rays_parallel_on_the_surface_or_malformed_give_no_nan() {
    let mesh = Mesh::new(
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 1.0],
            [0.0, 0.0, 1.0],
        ],
        vec![],
        vec![],
        vec![[0, 1, 2], [3, 3, 3], [3, 4, 1], [3, 5, 4]],
    )
    .unwrap();
    let bvh = Bvh::build(Arc::new(mesh));
    let hits_or_not = [
        Ray::new([0.5, 0.0, 0.2], [0.0, 1.0, 0.0]), // starts on the surface, leaves upward
        Ray::new([0.5, 0.0, 0.2], [0.0, -1.0, 0.0]), // starts on the surface, leaves downward
        Ray::new([0.5, 0.0, 0.2], [1.0, 0.0, 0.0]), // starts on the surface, runs along it
        Ray::new([0.0, 1.0, 0.0], [0.0, -1.0, 0.0]), // through the degenerate triangle's point
        Ray::new([-1.0, 0.0, 0.5], [1.0, 0.0, 0.0]), // in the plane, parallel
        Ray::new([-1.0, 0.0, 0.5], [1.0, -0.0, -0.0]), // the same with negative zeros
    ];
    for r in &hits_or_not {
        if let Some(h) = bvh.intersect(r) {
            assert!(
                h.t.is_finite() && h.u.is_finite() && h.v.is_finite(),
                "{r:?} -> {h:?}"
            );
            assert!(h.t >= r.tnear);
        }
        // Any-hit and closest-hit traversal agree on whether there is a hit.
        assert_eq!(bvh.occluded(r), bvh.intersect(r).is_some(), "{r:?}");
    }
    // A ray starting on the surface and leaving it does not hit it again: t = 0 is within
    // rounding error of zero (pbrt's conservative t check).
    let on = bvh.intersect(&Ray::new([0.5, 0.0, 0.2], [0.0, -1.0, 0.0]));
    assert!(on.is_none(), "{on:?}");
    let never = [
        Ray::new([0.5, 1.0, 0.5], [0.0, 0.0, 0.0]), // no direction
        Ray::new([0.5, 1.0, 0.5], [f32::NAN, -1.0, 0.0]), // NaN direction
        Ray::new([0.5, 1.0, 0.5], [0.0, -f32::INFINITY, 0.0]),
        Ray::new([0.5, 1.0, 0.5], [1.0, 0.0, 0.0]), // parallel, above the plane
        Ray {
            tnear: 2.0,
            tfar: 1.0,
            ..Ray::new([0.5, 1.5, 0.5], [0.0, -1.0, 0.0])
        }, // empty interval
        Ray {
            tfar: 0.999,
            ..Ray::new([0.5, 1.0, 0.5], [0.0, -1.0, 0.0])
        }, // stops short
    ];
    for r in &never {
        assert_eq!(bvh.intersect(r), None, "{r:?}");
        assert!(!bvh.occluded(r), "{r:?}");
    }
    assert!(
        bvh.intersect(&Ray::new([0.5, 1.0, 0.5], [0.0, -1.0, 0.0]))
            .is_some()
    );
    // The triangle test itself honours tnear (the BVH's boxes would hide a lapse).
    let tri = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]];
    let late = Ray {
        tnear: 1.5,
        ..Ray::new([0.2, 1.0, 0.2], [0.0, -1.0, 0.0])
    };
    assert_eq!(intersect_triangle(&late, tri), None);
    assert!(intersect_triangle(&Ray { tnear: 0.5, ..late }, tri).is_some());
}

#[test]
fn rays_through_shared_edges_and_vertices_never_fall_through() {
    // Every integer coordinate of a 1 m grid is a shared edge or vertex, exactly representable;
    // half-integers on the diagonals are shared diagonal edges.
    let mesh = Mesh::grid(32, 32, 1.0);
    let bvh = Bvh::build(Arc::new(mesh.clone()));
    let mut rays = Vec::new();
    for i in 1..32 {
        for j in 1..32 {
            let (x, z) = (i as f32, j as f32);
            for (dx, dz) in [(0.0, 0.0), (0.5, 0.0), (0.0, 0.5), (0.5, 0.5), (0.25, 0.25)] {
                for dir in [
                    [0.0f32, -1.0, 0.0],
                    [-0.0, -1.0, -0.0],
                    [0.3, -1.0, 0.2],
                    [-0.7, -0.1, 0.7],
                    [0.0, -0.3, -1.0],
                ] {
                    let n = (dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]).sqrt();
                    let d = dir.map(|c| c / n);
                    let target = [x + dx, 0.0, z + dz];
                    let org = [target[0] - 2.0 * d[0], -2.0 * d[1], target[2] - 2.0 * d[2]];
                    rays.push((Ray::new(org, d), target));
                }
            }
        }
    }
    let mut fell = 0;
    for (r, target) in &rays {
        let Some(h) = bvh.intersect(r) else {
            fell += 1;
            continue;
        };
        assert!((h.t - 2.0).abs() < 1e-4, "t {} for {r:?}", h.t);
        let p = Mesh::interpolate(mesh.positions(), mesh.indices()[h.prim as usize], h.u, h.v);
        assert!(
            (0..3).all(|k| (p[k] - target[k]).abs() < 1e-4),
            "hit point {p:?} for target {target:?}"
        );
        assert!(bvh.occluded(r));
        // Every triangle the watertight test accepts is met at the aimed point.
        let accepted: Vec<u32> = (0..mesh.triangle_count() as u32)
            .filter(|&p| {
                intersect_triangle(r, mesh.triangle(p)).is_some_and(|(t, u, v)| {
                    assert!((t - 2.0).abs() < 1e-4 && u >= 0.0 && v >= 0.0 && u + v <= 1.0);
                    true
                })
            })
            .collect();
        assert!(accepted.contains(&h.prim), "{accepted:?} vs {h:?}");
    }
    assert_eq!(fell, 0, "{fell} of {} edge rays fell through", rays.len());
}

#[cfg(feature = "embree")]
mod against_embree {
    use super::*;
    use vastocean::accel::crosscheck::{CrossReport, crosscheck, random_rays_over};
    use vastocean::lod::{Preset, tessellate};
    use vastocean::ocean::{OceanParams, Surface};

    fn paper_low() -> Arc<Mesh> {
        let surface = Surface::new(&OceanParams::default(), 1).unwrap();
        let (mesh, _) = tessellate(&Preset::PaperLow.params(2.0), &surface.sampler([0.0, 0.0]))
            .expect("paper-low tessellation");
        Arc::new(mesh)
    }

    fn assert_agrees(r: &CrossReport, min_hits: usize) {
        eprintln!("{}", serde_json::to_string_pretty(r).unwrap());
        assert_eq!(r.unexplained_disagreements, 0, "{r:?}");
        assert_eq!(
            r.disagreements,
            r.explained_disagreements + r.unexplained_disagreements
        );
        assert_eq!(r.same_prim + r.both_miss + r.disagreements, r.rays);
        assert!(r.same_prim >= min_hits, "{r:?}");
        assert!(r.agree_fraction > 0.9999, "{r:?}");
        assert!(r.max_rel_dt < 1e-4, "{r:?}");
        assert!(r.rust_mrays_per_s > 0.0 && r.embree_mrays_per_s > 0.0);
        assert!(r.rust_build_s > 0.0 && r.embree_build_s > 0.0);
    }

    /// About 2 s in the test profile on 2 cores, so the full million runs by default.
    #[test]
    fn bvh_matches_embree_on_1m_rays_over_the_paper_low_ocean() {
        let mesh = paper_low();
        let n = 1_000_000;
        let rays = random_rays_over(&mesh, n, 5);
        let r = crosscheck(mesh, &rays, 2).unwrap();
        assert_eq!(r.rays, n);
        assert_agrees(&r, n / 2);
    }

    #[test]
    #[ignore = "1M-triangle mesh: about 10 s of builds in the test profile"]
    fn bvh_matches_embree_on_a_1m_triangle_mesh() {
        let mesh = Arc::new(random_mesh(1_000_000, 0.01, 9));
        let rays = random_rays(200_000, 10);
        let r = crosscheck(mesh, &rays, 2).unwrap();
        assert_agrees(&r, 50_000);
    }

    #[test]
    fn rays_over_a_mesh_start_above_it_and_aim_into_its_bounds() {
        let mesh = Mesh::grid(10, 20, 1.0);
        let rays = random_rays_over(&mesh, 1_000, 3);
        assert_eq!(rays, random_rays_over(&mesh, 1_000, 3));
        for r in &rays {
            assert!(r.org[1] > 1.0 && r.dir[1] < 0.0, "{r:?}");
            let len = r.dir.iter().map(|c| c * c).sum::<f32>().sqrt();
            assert!((len - 1.0).abs() < 1e-5);
            // The target lies in the flat box y = 0, so the ray reaches it at y = 0.
            let t = -r.org[1] / r.dir[1];
            let p = r.at(t);
            assert!(
                p[0] > -1e-3 && p[0] < 10.001 && p[2] > -1e-3 && p[2] < 20.001,
                "{p:?}"
            );
        }
    }
}
