//! The displaced ocean as an implicit function of a point in the camera frame.
//!
//! Every point P has an altitude a(P) above the earth's sphere and an arc position s(P): the
//! nominal position (arc length from the camera's nadir, as the tessellation's texture
//! coordinates measure it) of the sphere point straight below it. The surface point of nominal
//! position x is X(x) = base(x) + tilt(Dx, h, Dz) ([`crate::lod::curved_frame_position`]); where
//! the sea does not fold, x -> s(X(x)) is one to one, so over every arc position there is one
//! surface point, of altitude A(s). F(P) = a(P) - A(s(P)) is positive above the surface and
//! negative below it, and a ray meets the surface where F changes sign along it. A(s) needs
//! the x with s(X(x)) = s: Newton's method on x -> s(X(x)), whose Jacobian is I + dD/dx (the
//! layers' exact FFT derivatives of the displacement), started from a Newton step off the last
//! point along the ray, whose Jacobian is already read (a ray's next point is close to its last).

use crate::lod::{atan_over_arg, curved_frame_position};
use crate::ocean::slopes::LevelSet;
use crate::ocean::{Sampler, field};

/// Newton steps before an inversion gives up (it then answers with the last point reached and
/// says it did not converge: near a fold the fixed-point fallback converges slowly).
const MAX_NEWTON: usize = 24;
/// Residual in arc position at which an inversion stops, m.
pub(super) const TOL_S: f64 = 1e-7;

/// Arc position s and altitude a of the point `p` over a sphere of radius `r` centred at
/// (0, -r, 0) (`p` not at the centre). The altitude is computed as (|P - C|^2 - r^2) / (|P - C| + r), free of the
/// cancellation of |P - C| - r.
#[inline]
pub(super) fn sphere_coords(p: [f64; 3], r: f64) -> ([f64; 2], f64) {
    let (x, z) = (p[0], p[2]);
    let yc = p[1] + r;
    let h2 = x * x + z * z;
    let rho = (h2 + yc * yc).sqrt();
    let alt = (h2 + p[1] * (p[1] + 2.0 * r)) / (rho + r);
    // s = r atan(rh / yc) along (x, z) / rh, rh the distance from the axis: with u = rh / yc,
    // r atan(u) / (u yc), a series in u^2 where the angle is small (no sqrt, no atan2)
    let k = if yc > 0.0 {
        r / yc * atan_over_arg(h2 / (yc * yc))
    } else {
        let rh = h2.sqrt();
        if rh > 0.0 { r * rh.atan2(yc) / rh } else { 0.0 }
    };
    ([x * k, z * k], alt)
}

/// Where the last evaluation along a ray found the surface: its arc position, nominal x, and
/// the Jacobian of the map x -> s there, I + dD/dx (symmetric: `[a11, a12, a22]`).
#[derive(Clone, Copy, Debug)]
pub(super) struct Warm {
    pub s: [f64; 2],
    pub x: [f64; 2],
    pub jacobian: [f64; 3],
}

/// The Jacobian I + dD/dx of the map from nominal to arc position, `[a11, a12, a22]`, from the
/// fields at one point.
#[inline]
fn jacobian(f: &crate::ocean::Texel) -> [f64; 3] {
    [
        1.0 + f[field::DDX_DX] as f64,
        f[field::DDX_DZ] as f64,
        1.0 + f[field::DDZ_DZ] as f64,
    ]
}

/// `x + J^-1 r` for the symmetric Jacobian `j`, or `x + r` (the fixed-point step) where J is
/// near singular (a fold's neighbourhood).
#[inline]
fn newton_step(x: [f64; 2], r: [f64; 2], j: [f64; 3]) -> [f64; 2] {
    let det = j[0] * j[2] - j[1] * j[1];
    if det > 0.05 {
        [
            x[0] + (j[2] * r[0] - j[1] * r[1]) / det,
            x[1] + (j[0] * r[1] - j[1] * r[0]) / det,
        ]
    } else {
        [x[0] + r[0], x[1] + r[1]]
    }
}

/// F at one point, and the nominal position of the surface point over it.
#[derive(Clone, Copy, Debug)]
pub(super) struct Eval {
    pub f: f64,
    pub x: [f64; 2],
    /// The inversion reached its tolerance (else F is the last step's, of unknown error).
    pub converged: bool,
}

/// The implicit surface around one camera origin.
#[derive(Clone, Copy)]
pub(super) struct Implicit<'a> {
    pub sampler: Sampler<'a>,
    /// The levels the surface reads ([`Sampler::fields_f64_at`]).
    pub lod: LevelSet,
    pub earth_radius_m: f64,
    /// How much F can change per metre of error in the nominal position found: one plus the
    /// surface's slope bound (infinite without one, so inversions run to [`TOL_S`]).
    pub lip: f64,
}

impl Implicit<'_> {
    /// The surface point of nominal position `x` and its sphere coordinates.
    #[inline]
    fn surface(&self, x: [f64; 2]) -> (crate::ocean::Texel, [f64; 2], f64) {
        let f = self.sampler.fields_f64_at(x[0], x[1], &self.lod);
        let v = [f[field::DX] as f64, f[field::H] as f64, f[field::DZ] as f64];
        let q = curved_frame_position(x[0], x[1], v, self.earth_radius_m);
        let (s, a) = sphere_coords(q, self.earth_radius_m);
        (f, s, a)
    }

    /// F(`p`) and the nominal position over it; `warm`, if any, seeds the inversion and is
    /// updated to this point. The inversion stops at a residual of [`TOL_S`], or sooner once
    /// the residual can change F by at most a tenth of |F| (it moves the surface point by at
    /// most `lip` times the residual: [`Implicit::lip`]), which a march needs, not a root.
    pub fn eval(&self, p: [f64; 3], warm: &mut Option<Warm>) -> Eval {
        let (s, a) = sphere_coords(p, self.earth_radius_m);
        // the last point's x moved by its Jacobian's inverse times the change in s: a Newton
        // step taken with the Jacobian already known, so that most evaluations along a march
        // meet their tolerance at the first read
        let mut x = match warm {
            Some(w) => newton_step(w.x, [s[0] - w.s[0], s[1] - w.s[1]], w.jacobian),
            None => s,
        };
        let mut alt = 0.0;
        let mut converged = false;
        let mut jac = [1.0, 0.0, 1.0];
        for k in 0..=MAX_NEWTON {
            let (f, sq, aq) = self.surface(x);
            alt = aq;
            let r = [s[0] - sq[0], s[1] - sq[1]];
            let res = r[0].abs() + r[1].abs();
            converged = res <= TOL_S || res * self.lip <= 0.1 * (a - aq).abs();
            jac = jacobian(&f);
            if converged || k == MAX_NEWTON {
                break;
            }
            x = newton_step(x, r, jac);
        }
        *warm = Some(Warm {
            s,
            x,
            jacobian: jac,
        });
        Eval {
            f: a - alt,
            x,
            converged,
        }
    }
}
