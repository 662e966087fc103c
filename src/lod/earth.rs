//! The curved earth under the tessellation (DESIGN.md, "Curved earth"): the horizon distance of
//! a camera, and the map from a nominal horizontal position x (camera-relative, arc length from
//! the camera's nadir) and the flat-frame surface sample of eqs. 4 and 7 to a point and normal in
//! the camera's frame (y up at the nadir, origin at mean sea level below the camera).

use crate::ocean::Sample;

/// Distance along the sea (arc length) from the camera's nadir to the geometric horizon of a
/// camera `camera_height_m` above a sphere of radius `earth_radius_m`: R acos(R / (R + h)),
/// about sqrt(2 R h) (within h / 3R relative).
pub fn horizon_distance(camera_height_m: f64, earth_radius_m: f64) -> f64 {
    let (r, h) = (earth_radius_m, camera_height_m.max(0.0));
    // atan of tangent length over R avoids acos's cancellation near 1.
    r * ((2.0 * r * h + h * h).sqrt()).atan2(r)
}

/// Angles below which [`sin_versine`] sums its series: their truncation is under 3e-18 of the
/// value there, so they agree with libm's functions to rounding.
const SERIES_MAX_RAD: f64 = 0.1;

/// sin(theta) and the versine 1 - cos(theta) = 2 sin^2(theta / 2), the latter free of
/// cancellation. A sea's angles about the nadir are small (5 km is 8e-4 rad): there Taylor
/// series to theta^9 and theta^10 replace libm's calls, which were a tenth of the exact
/// surface's root finding.
#[inline]
pub(crate) fn sin_versine(theta: f64) -> (f64, f64) {
    if theta.abs() < SERIES_MAX_RAD {
        sin_versine_series(theta)
    } else {
        sin_versine_libm(theta)
    }
}

/// [`sin_versine`]'s series, whatever the angle.
#[inline]
fn sin_versine_series(theta: f64) -> (f64, f64) {
    let t = theta * theta;
    let sin = theta * (1.0 - t / 6.0 * (1.0 - t / 20.0 * (1.0 - t / 42.0 * (1.0 - t / 72.0))));
    let vers = 0.5 * t * (1.0 - t / 12.0 * (1.0 - t / 30.0 * (1.0 - t / 56.0 * (1.0 - t / 90.0))));
    (sin, vers)
}

/// [`sin_versine`] past the series' reach, out of line: where a loop inlined both branches,
/// the compiler evaluated both for every element and selected (see [`curved_frame_point_near`]).
#[cold]
#[inline(never)]
fn sin_versine_libm(theta: f64) -> (f64, f64) {
    let half = (0.5 * theta).sin();
    (theta.sin(), 2.0 * half * half)
}

/// atan(u) / u as a function of w = u^2 >= 0: the series 1 - w/3 + w^2/5 - ... to w^5 below
/// w = 1e-3 (u < 0.032 rad, 200 km on the earth; truncation under 1e-19), libm above (out of
/// line, as in [`sin_versine`]).
#[inline]
pub(crate) fn atan_over_arg(w: f64) -> f64 {
    if w < 1e-3 {
        1.0 - w * (1.0 / 3.0 - w * (1.0 / 5.0 - w * (1.0 / 7.0 - w * (1.0 / 9.0 - w / 11.0))))
    } else {
        atan_over_arg_libm(w)
    }
}

#[cold]
#[inline(never)]
fn atan_over_arg_libm(w: f64) -> f64 {
    let u = w.sqrt();
    u.atan() / u
}

/// The curved frame at nominal position (x, z): the sphere point at angle r / R about the
/// nadir, and the local axes there (radial tangent, azimuthal tangent, up).
struct Frame {
    ux: f64,
    uz: f64,
    base: [f64; 3],
    tr: [f64; 3],
    ta: [f64; 3],
    up: [f64; 3],
}

impl Frame {
    #[inline]
    fn at(x: f64, z: f64, earth_radius_m: f64) -> Frame {
        Frame::with(x, z, earth_radius_m, sin_versine).0
    }

    /// The frame from `sine_versine` of the angle about the nadir, and whether that angle is
    /// within the series' reach (false for NaN).
    #[inline(always)]
    fn with(
        x: f64,
        z: f64,
        earth_radius_m: f64,
        sine_versine: impl Fn(f64) -> (f64, f64),
    ) -> (Frame, bool) {
        // (no overflow to guard against at sea-scale distances: sqrt, not hypot)
        let r = (x * x + z * z).sqrt();
        let (ux, uz) = if r > 0.0 { (x / r, z / r) } else { (1.0, 0.0) };
        let theta = r / earth_radius_m;
        let (st, vers) = sine_versine(theta);
        let ct = 1.0 - vers;
        let drop = earth_radius_m * vers;
        let frame = Frame {
            ux,
            uz,
            base: [earth_radius_m * st * ux, -drop, earth_radius_m * st * uz],
            tr: [ct * ux, -st, ct * uz],
            ta: [-uz, 0.0, ux],
            up: [st * ux, ct, st * uz],
        };
        (frame, theta.abs() < SERIES_MAX_RAD)
    }

    /// A flat-frame vector (x, y, z) in the local axes.
    #[inline]
    fn tilt(&self, v: [f64; 3]) -> [f64; 3] {
        let radial = v[0] * self.ux + v[2] * self.uz;
        let azim = -v[0] * self.uz + v[2] * self.ux;
        std::array::from_fn(|i| radial * self.tr[i] + azim * self.ta[i] + v[1] * self.up[i])
    }
}

/// Surface point X and unit normal of `sample` (taken at nominal camera-relative position
/// (x, z)) in the camera frame: the nominal point moves onto the sphere at angle r / R about the
/// nadir, and the flat-frame displacement (Dx, h, Dz) and normal are rotated by that tilt, so
/// a sea at rest drops by 2 R sin^2(r / 2R) ~ r^2 / 2R.
#[inline]
pub fn curved_frame_point(
    x: f64,
    z: f64,
    sample: &Sample,
    earth_radius_m: f64,
) -> ([f64; 3], [f64; 3]) {
    point_in(&Frame::at(x, z, earth_radius_m), sample)
}

/// [`curved_frame_point`] with the series whatever the angle, and whether the angle is within
/// the series' reach: where it is, the point and normal are [`curved_frame_point`]'s bit for
/// bit; where not (past 637 km on the earth, or NaN), the caller takes [`curved_frame_point`].
/// Without a library call, a loop over many points compiles to vector code: the
/// tessellation's, whose inlined [`sin_versine`] the compiler had vectorised by evaluating
/// both of its branches for every vertex, two libm `sin` calls each.
#[inline]
pub(crate) fn curved_frame_point_near(
    x: f64,
    z: f64,
    sample: &Sample,
    earth_radius_m: f64,
) -> ([f64; 3], [f64; 3], bool) {
    let (f, near) = Frame::with(x, z, earth_radius_m, sin_versine_series);
    let (p, n) = point_in(&f, sample);
    (p, n, near)
}

#[inline]
fn point_in(f: &Frame, sample: &Sample) -> ([f64; 3], [f64; 3]) {
    let d = f.tilt([
        sample.disp[0] as f64,
        sample.height as f64,
        sample.disp[1] as f64,
    ]);
    let n = f.tilt(sample.normal.map(|c| c as f64));
    (std::array::from_fn(|i| f.base[i] + d[i]), n)
}

/// The point of [`curved_frame_point`] alone, for a displacement `v` = (Dx, h, Dz) held in f64
/// (the exact surface's root finder); the same arithmetic, so the same point.
#[inline]
pub fn curved_frame_position(x: f64, z: f64, v: [f64; 3], earth_radius_m: f64) -> [f64; 3] {
    let f = Frame::at(x, z, earth_radius_m);
    let d = f.tilt(v);
    std::array::from_fn(|i| f.base[i] + d[i])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn horizon_is_close_to_sqrt_2rh() {
        for h in [2.0, 100.0] {
            let d = horizon_distance(h, 6.371e6);
            assert!(
                (d / (2.0 * 6.371e6 * h).sqrt() - 1.0).abs() < 1e-4,
                "{h}: {d}"
            );
        }
    }

    #[test]
    fn small_angle_series_match_libm_to_rounding() {
        // every angle from 1e-9 rad to past the series' end, on both sides of the switch
        let mut worst = [0.0f64; 3];
        for i in 0..=4000 {
            let theta = 1e-9 * 10f64.powf(i as f64 * 8.5 / 4000.0);
            let (s, v) = sin_versine(theta);
            let half = (0.5 * theta).sin();
            let rel = |a: f64, b: f64| ((a - b) / b).abs();
            worst[0] = worst[0].max(rel(s, theta.sin()));
            worst[1] = worst[1].max(rel(v, 2.0 * half * half));
            let u = theta.tan();
            worst[2] = worst[2].max(rel(atan_over_arg(u * u), u.atan() / u));
        }
        // a few ulps: each side rounds on its own
        for (w, name) in worst.iter().zip(["sin", "versine", "atan(u)/u"]) {
            assert!(*w < 4.0 * f64::EPSILON, "{name}: {w:e}");
        }
    }

    #[test]
    fn the_series_frame_is_the_frame_within_its_reach() {
        let sample = Sample {
            height: 0.3,
            disp: [0.1, -0.2],
            normal: [0.1, 0.99, -0.05],
            ..Sample::FLAT
        };
        let r_e = 1000.0;
        // within the reach (100 m here), on both sides of its end, past it, and NaN
        for (x, z) in [
            (0.0, 0.0),
            (3.0, -4.0),
            (70.0, 70.0),
            (70.0, 72.0),
            (300.0, 1.0),
        ]
        .into_iter()
        .chain([(f64::NAN, 1.0)])
        {
            let (p, n, near) = curved_frame_point_near(x, z, &sample, r_e);
            let theta = x.hypot(z) / r_e;
            assert_eq!(near, theta < SERIES_MAX_RAD, "({x}, {z})");
            if near {
                let bits = |v: [f64; 3]| v.map(f64::to_bits);
                let (pw, nw) = curved_frame_point(x, z, &sample, r_e);
                assert_eq!((bits(p), bits(n)), (bits(pw), bits(nw)), "({x}, {z})");
            }
        }
    }

    #[test]
    fn flat_sea_lies_on_the_sphere() {
        let r_e = 1000.0;
        let (p, n) = curved_frame_point(300.0, -400.0, &Sample::FLAT, r_e);
        let c = [0.0, -r_e, 0.0];
        let dist = ((p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2) + (p[2] - c[2]).powi(2)).sqrt();
        assert!((dist - r_e).abs() < 1e-9);
        // Normal points away from the centre; arc length from the nadir is 500 m.
        for i in 0..3 {
            assert!((n[i] - (p[i] - c[i]) / r_e).abs() < 1e-12);
        }
        assert!((r_e * (1.0 + p[1] / r_e).acos() - 500.0).abs() < 1e-6);
    }
}
