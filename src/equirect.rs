//! The equirectangular convention, in one place: y is up, elevation is measured from the
//! horizon, azimuth 0 looks along +x and 90 degrees along +z; a map or image `w` x `h` pixels
//! covers 360 x 180 degrees with the zenith at its top edge and azimuth 0 at its left edge.
//! Pixel coordinates are continuous: pixel (i, j) spans [i, i+1) x [j, j+1), so its centre is
//! (i + 0.5, j + 0.5). The camera, the sky lookup, sky generation and import all go through
//! these functions (the f32 ones render, the f64 ones make and analyse sky maps).

use std::f32::consts as f32c;
use std::f64::consts::{FRAC_PI_2, PI, TAU};

use glam::{DVec3, Vec3};

/// Unit direction at elevation `el` and azimuth `az`, radians.
#[inline]
pub fn direction(el: f32, az: f32) -> Vec3 {
    Vec3::new(el.cos() * az.cos(), el.sin(), el.cos() * az.sin())
}

/// [`direction`] in f64.
#[inline]
pub fn direction64(el: f64, az: f64) -> DVec3 {
    DVec3::new(el.cos() * az.cos(), el.sin(), el.cos() * az.sin())
}

/// Direction through continuous pixel position (x, y) of a `w` x `h` full-sphere image.
#[inline]
pub fn pixel_direction(x: f32, y: f32, w: f32, h: f32) -> Vec3 {
    let (az, el) = pixel_angles(x, y, w, h);
    direction(el, az)
}

/// Azimuth and elevation (radians) at continuous pixel position (x, y) of a `w` x `h`
/// full-sphere image.
#[inline]
pub fn pixel_angles(x: f32, y: f32, w: f32, h: f32) -> (f32, f32) {
    (f32c::TAU * x / w, f32c::FRAC_PI_2 - f32c::PI * y / h)
}

/// How much azimuth and elevation change over (dx, dy) pixels of a `w` x `h` full-sphere image.
#[inline]
pub fn pixel_angle_steps(dx: f32, dy: f32, w: f32, h: f32) -> (f32, f32) {
    (f32c::TAU * dx / w, -(f32c::PI * dy / h))
}

/// The continuous pixel position of direction `d` (any non-zero length) in a `w` x `h`
/// full-sphere image: the inverse of [`pixel_direction`], azimuth in [0, w] (w only by
/// rounding; [`crate::sky::lookup`] wraps it).
#[inline]
pub fn direction_pixel(d: Vec3, w: f32, h: f32) -> (f32, f32) {
    // rem_euclid(TAU) of an angle in (-pi, pi], without fmodf
    let az = atan2(d.z, d.x);
    let az = if az < 0.0 { az + f32c::TAU } else { az };
    // asin(d.y) for a unit direction, and right for any length.
    let el = atan2(d.y, (d.x * d.x + d.z * d.z).sqrt());
    (az / f32c::TAU * w, (f32c::FRAC_PI_2 - el) / f32c::PI * h)
}

/// atan2(y, x) in (-pi, pi], within 3e-7 rad of the true angle, inlined: every sky-map lookup
/// takes two, and libm's `atan2f` and `asinf` calls were 6 % of the default render's trace.
/// The kernel is Cephes' `atanf` (S. L. Moshier): reduction to |t| <= tan(pi/8) by
/// atan(t) = pi/4 + atan((t - 1) / (t + 1)), then an odd polynomial of degree 9. Zeros and
/// infinities give what libm gives (atan2(+-0, -0) = +-pi), NaN gives NaN. The division and
/// square roots on a lookup's path are what it costs (the sky's time is latency, not
/// instruction count).
#[inline]
pub fn atan2(y: f32, x: f32) -> f32 {
    let (ax, ay) = (x.abs(), y.abs());
    // atan of the smaller over the larger, in [0, pi/4], then reflected into its octant.
    let (lo, hi) = if ay > ax { (ax, ay) } else { (ay, ax) };
    // t = lo / hi, and past tan(pi/8) (t - 1) / (t + 1) = (lo - hi) / (lo + hi): one division.
    let (base, num, den) = if lo > 0.414_213_57 * hi {
        (f32c::FRAC_PI_4, lo - hi, lo + hi)
    } else {
        (0.0, lo, hi)
    };
    let u = if den == 0.0 { num } else { num / den };
    let z = u * u;
    let p = (((8.053_744_5e-2 * z - 1.387_768_6e-1) * z + 1.997_771_1e-1) * z - 3.333_295e-1) * z;
    let mut a = base + (p * u + u);
    if ay > ax {
        a = f32c::FRAC_PI_2 - a;
    }
    if x.is_sign_negative() {
        a = f32c::PI - a;
    }
    a.copysign(y)
}

/// Elevation (radians) of the centre of row `j` of an image `h` rows high.
#[inline]
pub fn row_elevation(j: usize, h: usize) -> f64 {
    FRAC_PI_2 - (j as f64 + 0.5) / h as f64 * PI
}

/// Azimuth (radians) of the centre of column `i` of an image `w` columns wide.
#[inline]
pub fn column_azimuth(i: usize, w: usize) -> f64 {
    (i as f64 + 0.5) / w as f64 * TAU
}

/// Continuous row coordinate (0 at the top edge, `h` at the bottom) of an elevation in degrees.
#[inline]
pub fn elevation_deg_to_row(elevation_deg: f64, h: usize) -> f64 {
    (90.0 - elevation_deg) / 180.0 * h as f64
}

/// Elevation in degrees of the centre of row `j` of an image `h` rows high.
#[inline]
pub fn row_elevation_deg(j: usize, h: usize) -> f64 {
    90.0 - j as f64 * 180.0 / h as f64 - 90.0 / h as f64
}

/// Solid angle of one texel of row `j` of a `w` x `h` map, steradians.
#[inline]
pub fn texel_solid_angle(j: usize, w: usize, h: usize) -> f64 {
    texel_solid_angle_at(row_elevation(j, h).cos(), w, h)
}

/// Solid angle of a `w` x `h` map's texel at an elevation of cosine `cos_el`, steradians.
#[inline]
pub fn texel_solid_angle_at(cos_el: f64, w: usize, h: usize) -> f64 {
    TAU / w as f64 * PI / h as f64 * cos_el
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axes_follow_the_convention() {
        assert!((direction(0.0, 0.0) - Vec3::X).length() < 1e-6);
        assert!((direction(0.0, f32c::FRAC_PI_2) - Vec3::Z).length() < 1e-6);
        assert!((direction(f32c::FRAC_PI_2, 1.0) - Vec3::Y).length() < 1e-6);
        // the middle row of a 360 x 180 image is the horizon; its left edge azimuth 0
        assert!((pixel_direction(0.0, 90.0, 360.0, 180.0) - Vec3::X).length() < 1e-6);
        assert!((pixel_direction(90.0, 90.0, 360.0, 180.0) - Vec3::Z).length() < 1e-6);
    }

    #[test]
    fn pixel_and_direction_are_inverse() {
        let (w, h) = (1024.0, 512.0);
        for &(x, y) in &[
            (0.5, 0.5),
            (100.25, 255.5),
            (1023.5, 300.0),
            (512.0, 480.75),
        ] {
            let d = pixel_direction(x, y, w, h);
            let (x2, y2) = direction_pixel(d, w, h);
            assert!((x2 - x).abs() < 2e-3 && (y2 - y).abs() < 2e-3, "{x},{y}");
        }
    }

    #[test]
    fn fast_atan2_agrees_with_libm() {
        let mut worst = 0f64;
        let n = 20_000;
        for i in 0..n {
            // every angle, at radii from tiny to huge
            let ang = (i as f64 + 0.37) / n as f64 * TAU - PI;
            for r in [1e-30, 1e-3, 1.0, 7.5e4, 1e30] {
                let (y, x) = ((r * ang.sin()) as f32, (r * ang.cos()) as f32);
                let want = (y as f64).atan2(x as f64);
                worst = worst.max((atan2(y, x) as f64 - want).abs());
            }
        }
        assert!(worst < 3e-7, "{worst}");
        // the axes and the special values, as libm gives them
        for (y, x) in [
            (0.0f32, 1.0f32),
            (1.0, 0.0),
            (0.0, -1.0),
            (-1.0, 0.0),
            (-0.0, -1.0),
            (0.0, 0.0),
            (1.0, 1.0),
            (3.0, -3.0),
        ] {
            assert!((atan2(y, x) - y.atan2(x)).abs() <= 2.5e-7, "{y} {x}");
        }
        assert!(atan2(f32::NAN, 1.0).is_nan() && atan2(1.0, f32::NAN).is_nan());
        assert!(atan2(f32::NAN, 0.0).is_nan() && atan2(0.0, f32::NAN).is_nan());
        assert_eq!(atan2(0.0, -0.0), std::f32::consts::PI);
        assert_eq!(atan2(-0.0, 0.0).to_bits(), (-0.0f32).to_bits());
        assert_eq!(atan2(5.0, f32::INFINITY), 0.0);
    }

    #[test]
    fn rows_and_elevations_agree() {
        let h = 1800;
        for j in [0, 899, 900, 1799] {
            let deg = row_elevation_deg(j, h);
            assert!((deg - row_elevation(j, h).to_degrees()).abs() < 1e-9);
            // the centre's continuous row coordinate is j + 0.5
            assert!((elevation_deg_to_row(deg, h) - (j as f64 + 0.5)).abs() < 1e-9);
        }
        let total: f64 = (0..64).map(|j| texel_solid_angle(j, 128, 64) * 128.0).sum();
        assert!((total / (4.0 * PI) - 1.0).abs() < 1e-3, "{total}");
        assert!((column_azimuth(0, 4) - TAU / 8.0).abs() < 1e-12);
        assert!((direction64(0.3, 1.1).as_vec3() - direction(0.3, 1.1)).length() < 1e-6);
    }
}
