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
    let az = f32c::TAU * x / w;
    let el = f32c::FRAC_PI_2 - f32c::PI * y / h;
    direction(el, az)
}

/// The continuous pixel position of direction `d` (unit length) in a `w` x `h` full-sphere
/// image: the inverse of [`pixel_direction`], azimuth in [0, w).
#[inline]
pub fn direction_pixel(d: Vec3, w: f32, h: f32) -> (f32, f32) {
    let az = d.z.atan2(d.x).rem_euclid(f32c::TAU);
    let el = d.y.clamp(-1.0, 1.0).asin();
    (az / f32c::TAU * w, (f32c::FRAC_PI_2 - el) / f32c::PI * h)
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
    TAU / w as f64 * PI / h as f64 * row_elevation(j, h).cos()
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
