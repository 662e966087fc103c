//! Normals drawn by area among those that face a ray: under the wrong-side policy `terminate`,
//! a normal drawn from the `mapped` lobe that faces away from the ray ends the path's branches,
//! so each path's branches are all or nothing. Drawn instead among the facing normals and
//! weighted by their share of the lobe, the branches have the same expected value without that
//! coin toss. Which normals face a ray is a half-plane of slopes, so the share is a normal
//! distribution's tail and the draw a truncated normal (by its inverse distribution function).

use glam::Vec3;

use super::Lobe;

// glibc's (and every C library's) complementary error function, to full f64 precision: the
// share of a lobe facing a grazing ray may be a far tail.
unsafe extern "C" {
    safe fn erfc(x: f64) -> f64;
}

/// P(Z <= x) for a standard normal Z.
pub fn normal_cdf(x: f64) -> f64 {
    0.5 * erfc(-x * std::f64::consts::FRAC_1_SQRT_2)
}

/// The x with P(Z <= x) = p, 0 < p < 1: Acklam's rational approximation (relative error
/// 1.15e-9, far below the f32 slopes drawn with it).
pub fn normal_quantile(p: f64) -> f64 {
    const A: [f64; 6] = [
        -3.969683028665376e1,
        2.209460984245205e2,
        -2.759285104469687e2,
        1.38357751867269e2,
        -3.066479806614716e1,
        2.506628277459239,
    ];
    const B: [f64; 5] = [
        -5.447609879822406e1,
        1.615858368580409e2,
        -1.556989798598866e2,
        6.680131188771972e1,
        -1.328068155288572e1,
    ];
    const C: [f64; 6] = [
        -7.784894002430293e-3,
        -3.223964580411365e-1,
        -2.400758277161838,
        -2.549732539343734,
        4.374664141464968,
        2.938163982698783,
    ];
    const D: [f64; 4] = [
        7.784695709041462e-3,
        3.224671290700398e-1,
        2.445134137142996,
        3.754408661907416,
    ];
    let poly = |c: &[f64], x: f64| c.iter().fold(0.0, |acc, &k| acc * x + k);
    let tail = |p: f64| {
        let q = (-2.0 * p.ln()).sqrt();
        poly(&C, q) / (poly(&D, q) * q + 1.0)
    };
    const LOW: f64 = 0.02425;
    if p < LOW {
        tail(p)
    } else if p > 1.0 - LOW {
        -tail(1.0 - p)
    } else {
        let q = p - 0.5;
        let r = q * q;
        poly(&A, r) * q / (poly(&B, r) * r + 1.0)
    }
}

impl Lobe {
    /// [`Lobe::sample_area`] among the normals that face `d` (world, pointing at the surface:
    /// d . m < 0 for the world normal m), from two uniform numbers, with the share of the lobe
    /// they hold; `None` where no normal of the lobe faces it. A normal faces d when its slopes
    /// (sx, sy) satisfy a sx + b sy > c, (a, b, c) being d in the lobe's frame: a half-plane,
    /// so along the unit direction e of (a alpha_x, b alpha_y) the standard normal variable z of
    /// the slopes must exceed a threshold t, and across it, w, is free. z is drawn from the
    /// tail beyond t by inverting its distribution, w as in a plain draw. Where nearly all of
    /// the lobe faces d (t < -4) it is the plain draw with a share of 1, which may face away.
    pub fn sample_area_facing(&self, d: Vec3, u1: f32, u2: f32) -> Option<(Vec3, f32)> {
        let (a, b, c) = (
            f64::from(d.dot(self.x)),
            f64::from(d.dot(self.y)),
            f64::from(d.dot(self.z)),
        );
        let k = std::f64::consts::FRAC_1_SQRT_2;
        let [ax, ay] = self.alpha.map(|x| k * f64::from(x));
        let [mx, my] = self.mean.map(f64::from);
        let (ea, eb) = (a * ax, b * ay);
        // (no overflow or underflow to guard against: |ea|, |eb| <= alpha, and a sigma below
        // 1e-12 is treated apart; `hypot` is a library call that cost 2 % of a render)
        let sigma = (ea * ea + eb * eb).sqrt();
        let mu = a * mx + b * my;
        if sigma < 1e-12 {
            // the slopes' spread does not move the normal towards or away from d
            return (mu > c).then(|| (self.sample_area(u1, u2), 1.0));
        }
        let t = (c - mu) / sigma;
        if t < -4.0 {
            // At most 3.2e-5 of the lobe faces away: the plain draw, whose rare normal facing
            // away the caller ends as before (the same expected value, without the tail's
            // arithmetic on most hits).
            return Some((self.sample_area(u1, u2), 1.0));
        }
        let share = normal_cdf(-t);
        if share < 1e-30 {
            return None;
        }
        let tiny = f64::MIN_POSITIVE;
        let z = -normal_quantile(((1.0 - f64::from(u1)) * share).max(tiny));
        let w = normal_quantile(f64::from(u2).clamp(1e-12, 1.0 - 1e-12));
        let (ex, ey) = (ea / sigma, eb / sigma);
        let (g1, g2) = (z * ex - w * ey, z * ey + w * ex);
        let (sx, sy) = (mx + ax * g1, my + ay * g2);
        let m = Vec3::new(-sx as f32, -sy as f32, 1.0).normalize();
        Some((m, share as f32))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// The quantile against the exact root of F(x) = p (one Halley step from it, on glibc's
    /// erfc, which lands within rounding of the root), from far tails to the middle.
    #[test]
    fn the_quantile_inverts_the_distribution_function() {
        let halley = |x: f64, p: f64| {
            let u = (normal_cdf(x) - p) * (2.0 * std::f64::consts::PI).sqrt() * (0.5 * x * x).exp();
            x - u / (1.0 + 0.5 * x * u)
        };
        for p in [
            1e-300,
            1e-30,
            1e-8,
            0.001,
            0.02425,
            0.1,
            0.5,
            0.77,
            0.99,
            1.0 - 1e-9,
        ] {
            let x = normal_quantile(p);
            let root = halley(x, p);
            let back = normal_cdf(root);
            assert!(
                (back - p).abs() <= 1e-12 * p.max(1e-3),
                "{p}: {root} -> {back}"
            );
            assert!(
                (x - root).abs() <= 1e-8 * root.abs().max(1.0),
                "{p}: {x} against {root}"
            );
        }
        assert!((normal_quantile(0.975) - 1.959_963_984_540_054).abs() < 1e-8);
        assert!((normal_cdf(-1.0) - 0.158_655_253_931_457_05).abs() < 1e-15);
    }

    /// For lobes and rays from steep to grazing (and a lobe whose centre faces away): every
    /// drawn normal faces the ray; the share is the fraction of plain draws that face it; and
    /// the drawn normals' mean slopes are the facing plain draws' mean slopes.
    #[test]
    fn facing_draws_are_the_plain_draws_that_face_the_ray() {
        let lobes = [
            Lobe::around(Vec3::Y, Vec3::Y, [0.02, 0.0, 0.02]).unwrap(),
            Lobe::around(
                Vec3::Y,
                Vec3::new(0.15, 1.0, -0.05).normalize(),
                [0.05, 0.012, 0.01],
            )
            .unwrap(),
            Lobe::around(
                Vec3::Y,
                Vec3::new(-0.4, 1.0, 0.0).normalize(),
                [0.01, 0.0, 0.03],
            )
            .unwrap(),
        ];
        let rays = [
            Vec3::new(0.3, -1.0, 0.1),
            Vec3::new(1.0, -0.1, 0.2),
            Vec3::new(1.0, -0.02, -0.3),
            Vec3::new(-0.2, -0.05, 1.0),
        ];
        let n = 200_000;
        let mut rng = Rng::keyed(&[7]);
        for (li, lobe) in lobes.iter().enumerate() {
            for &d in &rays {
                let d = d.normalize();
                let slopes = |m: Vec3| Vec3::new(-m.x / m.z, -m.y / m.z, 0.0);
                let (mut facing, mut plain_mean) = (0usize, Vec3::ZERO);
                for _ in 0..n {
                    let m = lobe.sample_area(rng.f32(), rng.f32());
                    if d.dot(lobe.world(m, false)) < 0.0 {
                        facing += 1;
                        plain_mean += slopes(m);
                    }
                }
                let share = facing as f64 / n as f64;
                let drawn = lobe.sample_area_facing(d, 0.5, 0.5);
                if facing == 0 {
                    assert!(drawn.is_none_or(|(_, s)| s < 1e-4), "lobe {li}, {d}");
                    continue;
                }
                let (_, s) = drawn.expect("a lobe that faces the ray");
                // (a share within one draw of 0 or 1 has a sample error of about 1 / n)
                let se = (share * (1.0 - share) / n as f64).sqrt() + 1.0 / n as f64;
                assert!(
                    (f64::from(s) - share).abs() < 4.0 * se,
                    "lobe {li}, {d}: share {s} against {share} +- {se}"
                );
                let (mut mean, mut away) = (Vec3::ZERO, 0);
                for _ in 0..n {
                    let (m, s) = lobe.sample_area_facing(d, rng.f32(), rng.f32()).unwrap();
                    if d.dot(lobe.world(m, false)) >= 0.0 {
                        // only a plain draw (share 1) may face away
                        assert_eq!(s, 1.0, "lobe {li}, {d}: faces away");
                        away += 1;
                    } else {
                        mean += slopes(m);
                    }
                }
                assert!(
                    away <= n / 10_000,
                    "lobe {li}, {d}: {away} of {n} face away"
                );
                let facing_draws = n - away;
                let (mean, plain) = (mean / facing_draws as f32, plain_mean / facing as f32);
                let tol = 4.0 * (lobe.alpha[0].max(lobe.alpha[1]) / (facing as f32).sqrt()) + 1e-4;
                assert!(
                    (mean - plain).length() < tol,
                    "lobe {li}, {d}: mean slopes {mean} against {plain} (tol {tol})"
                );
            }
        }
    }
}
