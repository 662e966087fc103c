//! Floating: an object's heave, pitch and roll from the sea under it, as a least-squares plane
//! through the surface's height at points spread over the hull's waterplane. No
//! hydrodynamics: no buoyancy balance (the hull sits with its design waterline on the plane,
//! whatever its weight), no inertia (it follows the sea at each instant), no added mass or
//! damping; a hull longer than the waves averages them out, as a real one does.

use glam::{DMat3, DVec3};

use super::LocalMesh;

/// The plane h = heave + slope_x x + slope_z z in the object's frame (x forward, z to
/// starboard, m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    pub heave: f64,
    pub slope_x: f64,
    pub slope_z: f64,
}

impl Plane {
    /// The calm sea's plane.
    pub const LEVEL: Plane = Plane {
        heave: 0.0,
        slope_x: 0.0,
        slope_z: 0.0,
    };

    /// Pitch (bow up positive) and roll (starboard up positive), degrees.
    pub fn pitch_roll_deg(&self) -> (f64, f64) {
        (
            self.slope_x.atan().to_degrees(),
            self.slope_z.atan().to_degrees(),
        )
    }

    /// The object's axes once it lies on the plane: forward (in the plane, over +x), up (the
    /// plane's normal) and starboard, as the columns of a rotation.
    pub fn rotation(&self) -> DMat3 {
        let up = DVec3::new(-self.slope_x, 1.0, -self.slope_z).normalize();
        let forward = DVec3::new(1.0, self.slope_x, 0.0).normalize();
        DMat3::from_cols(forward, up, forward.cross(up))
    }
}

/// The least-squares plane through `heights[i]` at `points[i]` (at least three points, not on
/// one line; fewer give the level plane at their mean height).
pub fn fit_plane(points: &[[f64; 2]], heights: &[f64]) -> Plane {
    assert_eq!(points.len(), heights.len());
    let n = points.len() as f64;
    let mean = |f: &dyn Fn(usize) -> f64| (0..points.len()).map(f).sum::<f64>() / n;
    let (mx, mz, mh) = (
        mean(&|i| points[i][0]),
        mean(&|i| points[i][1]),
        mean(&|i| heights[i]),
    );
    // centred normal equations for the slopes
    let (mut sxx, mut sxz, mut szz, mut sxh, mut szh) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for (p, h) in points.iter().zip(heights) {
        let (x, z, h) = (p[0] - mx, p[1] - mz, h - mh);
        sxx += x * x;
        sxz += x * z;
        szz += z * z;
        sxh += x * h;
        szh += z * h;
    }
    let det = sxx * szz - sxz * sxz;
    if points.len() < 3 || det <= 1e-12 * (sxx * szz).max(f64::MIN_POSITIVE) {
        return Plane {
            heave: if points.is_empty() { 0.0 } else { mh },
            ..Plane::LEVEL
        };
    }
    let slope_x = (szz * sxh - sxz * szh) / det;
    let slope_z = (sxx * szh - sxz * sxh) / det;
    Plane {
        heave: mh - slope_x * mx - slope_z * mz,
        slope_x,
        slope_z,
    }
}

/// Stations along the waterplane, and points across it at each.
const STATIONS: usize = 9;
const ACROSS: usize = 5;

/// Points spread over the hull's waterplane, in the object's frame (x, z): at 9 stations along
/// the part of the mesh at or below its waterline (y <= 0), 5 points across the breadth the
/// mesh has there (its extremes in z within the station's slice). A mesh with nothing below
/// the waterline takes its whole extent.
pub fn waterplane_points(mesh: &LocalMesh, scale: f64) -> Vec<[f64; 2]> {
    let below: Vec<[f64; 3]> = mesh
        .positions
        .iter()
        .copied()
        .filter(|p| p[1] <= 0.0)
        .collect();
    let pts = if below.is_empty() {
        &mesh.positions
    } else {
        &below
    };
    let (x0, x1) = pts
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p[0]), b.max(p[0]))
        });
    let width = (x1 - x0).max(f64::MIN_POSITIVE);
    let mut spans = [(f64::INFINITY, f64::NEG_INFINITY); STATIONS];
    for p in pts {
        let k = (((p[0] - x0) / width * STATIONS as f64) as usize).min(STATIONS - 1);
        spans[k] = (spans[k].0.min(p[2]), spans[k].1.max(p[2]));
    }
    let mut out = Vec::with_capacity(STATIONS * ACROSS);
    for (k, &(z0, z1)) in spans.iter().enumerate() {
        if z0 > z1 {
            continue;
        }
        let x = x0 + (k as f64 + 0.5) / STATIONS as f64 * width;
        for j in 0..ACROSS {
            let z = z0 + (j as f64 + 0.5) / ACROSS as f64 * (z1 - z0);
            out.push([x * scale, z * scale]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::ShipConfig;

    #[test]
    fn a_plane_through_points_on_a_plane_is_that_plane() {
        let pts: Vec<[f64; 2]> = (0..20)
            .map(|i| {
                [
                    (i as f64 * 1.7).sin() * 9.0 + 1.0,
                    (i as f64 * 0.9).cos() * 3.0 - 0.5,
                ]
            })
            .collect();
        let h: Vec<f64> = pts
            .iter()
            .map(|p| 0.4 - 0.05 * p[0] + 0.12 * p[1])
            .collect();
        let plane = fit_plane(&pts, &h);
        assert!((plane.heave - 0.4).abs() < 1e-12, "{plane:?}");
        assert!((plane.slope_x + 0.05).abs() < 1e-12, "{plane:?}");
        assert!((plane.slope_z - 0.12).abs() < 1e-12, "{plane:?}");
        // the rotation takes the frame's up to the plane's normal and keeps forward in it
        let r = plane.rotation();
        let n = DVec3::new(0.05, 1.0, -0.12).normalize();
        assert!((r.y_axis - n).length() < 1e-12);
        assert!(r.x_axis.dot(n).abs() < 1e-12 && r.z_axis.dot(n).abs() < 1e-12);
        assert!((r.determinant() - 1.0).abs() < 1e-12);
        // too few points: the level plane at their mean
        assert_eq!(fit_plane(&pts[..2], &[1.0, 3.0]).heave, 2.0);
    }

    /// The Wigley hull's waterplane points lie inside its waterline outline (as wide as it is at
    /// each station's slice) and cover its length.
    #[test]
    fn the_waterplane_points_cover_the_hull() {
        let s = ShipConfig::default();
        let pts = waterplane_points(&super::super::ship::wigley_ship(&s), 2.0);
        assert_eq!(pts.len(), STATIONS * ACROSS);
        for p in &pts {
            let (x, z) = (p[0] / 2.0, p[1] / 2.0);
            let xi = 2.0 * x / s.length_m;
            assert!(xi.abs() < 1.0);
            // within the outline at the station's slice's inner edge (a ninth of the length)
            let inner = (xi.abs() - 1.0 / STATIONS as f64).max(0.0);
            assert!(
                z.abs() <= 0.5 * s.beam_m * (1.0 - inner * inner) + 1e-9,
                "{p:?}"
            );
        }
        let x_max = pts.iter().map(|p| p[0]).fold(0.0, f64::max);
        assert!(x_max > 0.8 * s.length_m, "{x_max}");
    }
}
