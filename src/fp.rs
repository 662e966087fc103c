//! Floating-point helpers for robust ray tracing, after pbrt-v4 (Pharr, Jakob & Humphreys,
//! section 6.8 "Managing Rounding Error", `OffsetRayOrigin` in `ray.h`) and psychopath's
//! `fp_utils.rs`: the rounding-error bound `gamma(n)`, the error bound of a point interpolated
//! on a triangle, and the spawn point of a secondary ray that is guaranteed to lie on the
//! intended side of the surface it leaves. `f32::next_up` / `next_down` (std, stable since Rust
//! 1.86) are the one-ulp steps.

use glam::Vec3;

/// Bound on the relative error of `n` successive f32 roundings: `n·u / (1 - n·u)` with `u` the
/// unit roundoff (pbrt's gamma(n)).
pub const fn gamma(n: f32) -> f32 {
    let u = f32::EPSILON * 0.5;
    n * u / (1.0 - n * u)
}

/// Absolute error bound, per component, of the point `b0·p0 + b1·p1 + b2·p2` computed in f32
/// from barycentrics `b` (pbrt-v4's triangle intersection: gamma(7) covers the products, the
/// sums and the barycentrics' own rounding).
#[inline]
pub fn barycentric_error(b: [f32; 3], p: [Vec3; 3]) -> Vec3 {
    gamma(7.0) * (b[0].abs() * p[0].abs() + b[1].abs() * p[1].abs() + b[2].abs() * p[2].abs())
}

/// Origin for a ray leaving a surface point `p` (error bound `p_err`, surface normal `n`, not
/// necessarily unit) in direction `w`: `p` moved along `n` by `|n|·p_err` to the side `w` points
/// to, each moved component then rounded one more ulp away from the surface, so the computed
/// origin is on the intended side whatever the rounding (pbrt-v4 `OffsetRayOrigin`).
#[inline]
pub fn offset_ray_origin(p: Vec3, p_err: Vec3, n: Vec3, w: Vec3) -> Vec3 {
    let d = n.abs().dot(p_err);
    let mut offset = d * n;
    if w.dot(n) < 0.0 {
        offset = -offset;
    }
    let po = p + offset;
    Vec3::from_array(std::array::from_fn(|i| {
        if offset[i] > 0.0 {
            po[i].next_up()
        } else if offset[i] < 0.0 {
            po[i].next_down()
        } else {
            po[i]
        }
    }))
}

/// floor(p) as an integer, for |p| < 2^53 (a NaN gives 0): truncation plus a correction,
/// since `f64::floor` is a libm call on baseline x86-64 (no SSE4.1 `roundsd`).
#[inline]
pub fn floor_i64(p: f64) -> i64 {
    let i = p as i64;
    if (i as f64) > p { i - 1 } else { i }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gamma_bounds_n_roundings() {
        let u = f32::EPSILON as f64 * 0.5;
        assert!((gamma(1.0) as f64 - u / (1.0 - u)).abs() < 1e-12);
        assert!(gamma(7.0) > 7.0 * f32::EPSILON / 2.0 && gamma(7.0) < 8.0 * f32::EPSILON / 2.0);
    }

    #[test]
    fn offset_origin_lies_strictly_on_the_side_of_w() {
        // A tilted plane through a point 7 km away: the offset origin must be on w's side of
        // the plane when the plane is evaluated exactly (f64), for rays leaving either side.
        let n = Vec3::new(0.3, 0.9, -0.2).normalize();
        for (i, p) in [
            Vec3::new(7000.0, -3.8, 1234.5),
            Vec3::new(-5123.25, 0.1, -8999.0),
            Vec3::new(0.5, 0.0, 0.25),
        ]
        .into_iter()
        .enumerate()
        {
            let err = Vec3::splat(gamma(7.0)) * p.abs();
            for w in [n, -n, Vec3::new(1.0, 0.01, 0.0), Vec3::new(1.0, -0.01, 0.0)] {
                let o = offset_ray_origin(p, err, n, w);
                let side = (o.as_dvec3() - p.as_dvec3()).dot(n.as_dvec3());
                let want = w.dot(n).signum() as f64;
                assert!(side * want > 0.0, "case {i}: w {w} side {side}");
            }
        }
    }

    #[test]
    fn floor_i64_is_floor() {
        for p in [
            -2.5,
            -2.0,
            -1e-300,
            -0.0,
            0.0,
            1e-300,
            0.999_999,
            1.0,
            7.5,
            -1e15 - 0.5,
            4e15,
        ] {
            assert_eq!(floor_i64(p), p.floor() as i64, "{p}");
        }
    }

    #[test]
    fn zero_error_moves_the_point_by_at_most_one_ulp() {
        let p = Vec3::new(1.0, 2.0, 3.0);
        let o = offset_ray_origin(p, Vec3::ZERO, Vec3::Y, Vec3::Y);
        // d = 0: no offset at all, so no ulp step either
        assert_eq!(o, p);
    }
}
