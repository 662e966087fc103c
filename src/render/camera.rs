//! Cameras: the paper's equirectangular 360 x 180 degree camera (optionally restricted to an
//! elevation band, so near-horizon studies do not pay for the whole sphere) and a pinhole
//! perspective camera. Directions follow [`crate::equirect`]: y up, azimuth 0 along +x.

use glam::Vec3;

pub use crate::config::Projection;
use crate::equirect;

/// A camera with its image size. For the equirectangular camera `width` is the full 360 degree
/// width; the full-sphere height is `width / 2` and `height` is the band's row count.
#[derive(Clone, Copy, Debug)]
pub struct Camera {
    pub projection: Projection,
    pub width: usize,
    pub height: usize,
    /// First full-sphere row of the band (0 without a band).
    row0: usize,
}

impl Camera {
    /// Builds the camera for an image `width` pixels wide. For the pinhole, `aspect` = width /
    /// height; the equirectangular camera derives its height from the band.
    pub fn new(projection: Projection, width: usize, aspect: f64) -> Camera {
        match projection {
            Projection::Equirect { band_deg } => {
                let full_h = width / 2;
                let (row0, rows) = match band_deg {
                    None => (0, full_h),
                    Some((top, bottom)) => {
                        let r0 =
                            equirect::elevation_deg_to_row(top, full_h).floor().max(0.0) as usize;
                        let r1 = (equirect::elevation_deg_to_row(bottom, full_h).ceil() as usize)
                            .min(full_h);
                        (r0, r1.saturating_sub(r0).max(1))
                    }
                };
                Camera {
                    projection,
                    width,
                    height: rows,
                    row0,
                }
            }
            Projection::Pinhole { .. } => Camera {
                projection,
                width,
                height: ((width as f64 / aspect).round() as usize).max(1),
                row0: 0,
            },
        }
    }

    /// The image rows whose centres lie between the elevations `rows_deg.0` (top) and
    /// `rows_deg.1` (bottom), both included: the rows an analysis reads.
    pub fn rows_between(&self, rows_deg: (f64, f64)) -> Vec<usize> {
        (0..self.height)
            .filter(|&y| {
                let e = self.row_elevation_deg(y);
                e <= rows_deg.0 && e >= rows_deg.1
            })
            .collect()
    }

    /// The full-sphere row of image row 0 (0 without a band).
    pub fn first_row(&self) -> usize {
        self.row0
    }

    /// Elevation in degrees at the centre of image row `y` (equirectangular camera).
    pub fn row_elevation_deg(&self, y: usize) -> f64 {
        equirect::row_elevation_deg(self.row0 + y, self.width / 2)
    }

    /// The directions through pixel (x, y), for its many samples ([`PixelRays::direction`]).
    pub fn pixel_rays(&self, x: usize, y: usize) -> PixelRays<'_> {
        let corner = match self.projection {
            // Pixels narrower than 0.01 rad: the series below are exact in f32
            Projection::Equirect { .. } if self.width >= MIN_SERIES_WIDTH => {
                let (az, el) = equirect::pixel_angles(
                    x as f32,
                    (self.row0 + y) as f32,
                    self.width as f32,
                    (self.width / 2) as f32,
                );
                Some((az.sin_cos(), el.sin_cos()))
            }
            _ => None,
        };
        PixelRays {
            camera: self,
            x,
            y,
            corner,
        }
    }

    /// Direction through image position (x, y) in pixels (fractional: x + 0.5 is a pixel centre).
    pub fn direction(&self, x: f32, y: f32) -> Vec3 {
        match self.projection {
            Projection::Equirect { .. } => equirect::pixel_direction(
                x,
                self.row0 as f32 + y,
                self.width as f32,
                (self.width / 2) as f32,
            ),
            Projection::Pinhole {
                hfov_deg,
                yaw_deg,
                pitch_deg,
                roll_deg,
            } => {
                let tan_half = (hfov_deg.to_radians() as f32 * 0.5).tan();
                let sx = (2.0 * x / self.width as f32 - 1.0) * tan_half;
                let sy = (1.0 - 2.0 * y / self.height as f32) * tan_half * self.height as f32
                    / self.width as f32;
                let (yaw, pitch) = (yaw_deg.to_radians() as f32, pitch_deg.to_radians() as f32);
                let fwd = equirect::direction(pitch, yaw);
                let mut right = Vec3::new(-yaw.sin(), 0.0, yaw.cos());
                let mut up = right.cross(fwd);
                if roll_deg != 0.0 {
                    // right side down for a positive roll (config::camera::pinhole_basis64)
                    let (s, c) = (roll_deg.to_radians() as f32).sin_cos();
                    (right, up) = (c * right - s * up, s * right + c * up);
                }
                (fwd + sx * right + sy * up).normalize()
            }
        }
    }
}

impl Camera {
    /// For a pinhole camera `camera_height_m` above a smooth sea on an earth of radius
    /// `earth_radius_m`: the row (fractional, 0 at the image's top edge) where the horizon
    /// crosses each column's centre, `None` where it lies outside the image (or the column
    /// never meets it). The horizon dips below the level by acos(R / (R + h)). `None` for the
    /// equirectangular camera, whose rows are elevations.
    pub fn horizon_rows(
        &self,
        camera_height_m: f64,
        earth_radius_m: f64,
    ) -> Option<Vec<Option<f32>>> {
        if !matches!(self.projection, Projection::Pinhole { .. }) {
            return None;
        }
        let dip = (earth_radius_m / (earth_radius_m + camera_height_m)).acos();
        let target = -(dip.sin() as f32);
        let h = self.height as f32;
        let rows = (0..self.width)
            .map(|x| {
                // above the horizon where positive. The horizon is a cone of half-angle near
                // 90 degrees, a near-straight line across the image that a column crosses once
                // at most: bisect the crossing (from the top down, or the bottom up when
                // the camera is rolled over)
                let above = |y: f32| self.direction(x as f32 + 0.5, y).y - target;
                let top_above = above(0.0) >= 0.0;
                if top_above == (above(h) >= 0.0) {
                    return None;
                }
                let (mut lo, mut hi) = (0.0f32, h);
                for _ in 0..40 {
                    let mid = 0.5 * (lo + hi);
                    if (above(mid) >= 0.0) == top_above {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                Some(0.5 * (lo + hi))
            })
            .collect();
        Some(rows)
    }
}

/// Narrowest equirectangular image whose pixels span under 0.01 rad (2 pi / 629), where
/// [`PixelRays`] adds a sample's offset by series; narrower ones call [`Camera::direction`].
const MIN_SERIES_WIDTH: usize = 629;

/// The directions through one pixel. For the equirectangular camera (at least
/// [`MIN_SERIES_WIDTH`] wide) the sines and cosines of its corner's azimuth and elevation are
/// computed once, and a sample's offset within the pixel (under 0.01 rad) is added by the
/// angle-sum formulas with Taylor series (two libm `sincosf` calls a sample were 6 % of the
/// default render's trace). As close to the exact direction as [`Camera::direction`] with its
/// own f32 angles, within 10 % (both about 5e-7; tested).
#[derive(Clone, Copy, Debug)]
pub struct PixelRays<'a> {
    camera: &'a Camera,
    x: usize,
    y: usize,
    /// ((sin, cos) of the azimuth, (sin, cos) of the elevation) at the pixel's corner.
    corner: Option<((f32, f32), (f32, f32))>,
}

impl PixelRays<'_> {
    /// Direction through (x + jx, y + jy) for jx, jy in [0, 1].
    #[inline]
    pub fn direction(&self, jx: f32, jy: f32) -> Vec3 {
        let Some(((sa, ca), (se, ce))) = self.corner else {
            return self
                .camera
                .direction(self.x as f32 + jx, self.y as f32 + jy);
        };
        let w = self.camera.width as f32;
        let (da, de) = equirect::pixel_angle_steps(jx, jy, w, (self.camera.width / 2) as f32);
        // sin and cos of angles under 0.01 rad: the next terms are below 1e-12
        let sc = |d: f32| {
            let d2 = d * d;
            (
                d * (1.0 - d2 * (1.0 / 6.0)),
                1.0 - 0.5 * d2 * (1.0 - d2 * (1.0 / 12.0)),
            )
        };
        let ((sda, cda), (sde, cde)) = (sc(da), sc(de));
        let (s_az, c_az) = (sa * cda + ca * sda, ca * cda - sa * sda);
        let (s_el, c_el) = (se * cde + ce * sde, ce * cde - se * sde);
        Vec3::new(c_el * c_az, s_el, c_el * s_az)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A level pinhole's horizon lies tan(dip) below the image's middle, in image-plane units
    /// of tan(hfov / 2) per half width; a camera pitched up by more than half its vertical field
    /// of view has none in its image; the equirectangular camera gives none.
    #[test]
    fn the_horizon_row_of_a_pinhole_is_the_dip_below_its_middle() {
        let (w, h_m, r) = (400, 50.0, 6.371e6);
        let cam = |pitch_deg| {
            Camera::new(
                Projection::Pinhole {
                    hfov_deg: 40.0,
                    yaw_deg: 10.0,
                    pitch_deg,
                    roll_deg: 0.0,
                },
                w,
                2.0,
            )
        };
        let c = cam(0.0);
        let rows = c.horizon_rows(h_m, r).unwrap();
        let dip = (r / (r + h_m)).acos();
        let tan_half = 20f64.to_radians().tan();
        // at the middle column: sy = -tan(dip) (the direction (1, sy) has y / |.| = -sin(dip))
        let expect = 0.5 * c.height as f64 * (1.0 + dip.tan() / (tan_half * 0.5));
        let mid = rows[w / 2].unwrap() as f64;
        assert!(
            (mid - expect).abs() < 0.05 * (w as f64 / 400.0) + 0.02,
            "{mid} vs {expect}"
        );
        assert!(rows.iter().all(|r| r.is_some()));
        // rolled upside down, the image turns half round about its centre
        let over = Camera::new(
            Projection::Pinhole {
                hfov_deg: 40.0,
                yaw_deg: 10.0,
                pitch_deg: 0.0,
                roll_deg: 180.0,
            },
            w,
            2.0,
        );
        let turned = over.horizon_rows(h_m, r).unwrap();
        for x in 0..w {
            let (a, b) = (turned[x].unwrap(), rows[w - 1 - x].unwrap());
            assert!((a - (c.height as f32 - b)).abs() < 0.01, "{x}: {a} {b}");
        }
        assert!(
            cam(30.0)
                .horizon_rows(h_m, r)
                .unwrap()
                .iter()
                .all(|r| r.is_none())
        );
        let pano = Camera::new(Projection::Equirect { band_deg: None }, 64, 2.0);
        assert!(pano.horizon_rows(h_m, r).is_none());
    }

    /// A pinhole rolled 90 degrees (right side down) sees at the top of its square image what
    /// the upright one sees at its right edge, and at its right edge what the upright one
    /// sees at its bottom.
    #[test]
    fn a_rolled_pinhole_turns_its_image_about_the_view() {
        let cam = |roll_deg| {
            Camera::new(
                Projection::Pinhole {
                    hfov_deg: 50.0,
                    yaw_deg: 25.0,
                    pitch_deg: -10.0,
                    roll_deg,
                },
                64,
                1.0,
            )
        };
        let (upright, rolled) = (cam(0.0), cam(90.0));
        let close = |a: Vec3, b: Vec3| (a - b).length() < 1e-5;
        assert!(close(
            rolled.direction(32.0, 0.0),
            upright.direction(64.0, 32.0)
        ));
        assert!(close(
            rolled.direction(64.0, 32.0),
            upright.direction(32.0, 64.0)
        ));
        assert!(close(
            rolled.direction(32.0, 32.0),
            upright.direction(32.0, 32.0)
        ));
    }

    #[test]
    fn equirect_band_rows_map_exactly_to_elevations() {
        // 3600 px wide: 1800 rows for 180 degrees, 0.1 degree per row.
        let c = Camera::new(
            Projection::Equirect {
                band_deg: Some((1.0, -6.0)),
            },
            3600,
            2.0,
        );
        assert_eq!(c.height, 70);
        assert!((c.row_elevation_deg(0) - 0.95).abs() < 1e-9);
        assert!((c.row_elevation_deg(69) + 5.95).abs() < 1e-9);
        // the top edge of row 0 is exactly +1 degree, the bottom edge of the last row -6
        assert!((c.direction(0.0, 0.0).y - 1f32.to_radians().sin()).abs() < 1e-6);
        assert!((c.direction(0.0, 70.0).y + 6f32.to_radians().sin()).abs() < 1e-6);
    }

    #[test]
    fn pixel_rays_follow_the_camera() {
        for (projection, width) in [
            (Projection::Equirect { band_deg: None }, 2048),
            (Projection::Equirect { band_deg: None }, 640),
            (Projection::Equirect { band_deg: None }, 64),
            (
                Projection::Equirect {
                    band_deg: Some((2.0, -30.0)),
                },
                4096,
            ),
            (
                Projection::Pinhole {
                    hfov_deg: 60.0,
                    yaw_deg: 30.0,
                    pitch_deg: -5.0,
                    roll_deg: 0.0,
                },
                300,
            ),
        ] {
            let c = Camera::new(projection, width, 1.5);
            // Against the exact direction (f64), next to what `direction` itself achieves in f32.
            let (mut worst, mut worst_direction) = (0f64, 0f64);
            for y in (0..c.height).step_by(7) {
                for x in (0..c.width).step_by(13) {
                    let rays = c.pixel_rays(x, y);
                    for (jx, jy) in [(0.0, 0.0), (0.5, 0.5), (0.99, 0.01), (0.3, 1.0)] {
                        let (xf, yf) = (x as f32 + jx, y as f32 + jy);
                        let got = rays.direction(jx, jy);
                        if matches!(projection, Projection::Pinhole { .. }) {
                            assert_eq!(got, c.direction(xf, yf));
                            continue;
                        }
                        let (w, h) = (c.width as f64, (c.width / 2) as f64);
                        let az = std::f64::consts::TAU * (x as f64 + jx as f64) / w;
                        let row = (c.row0 + y) as f64 + jy as f64;
                        let el = std::f64::consts::FRAC_PI_2 - std::f64::consts::PI * row / h;
                        let want = equirect::direction64(el, az);
                        let err = |d: Vec3| (d.as_dvec3() - want).abs().max_element();
                        worst = worst.max(err(got));
                        worst_direction = worst_direction.max(err(c.direction(xf, yf)));
                    }
                }
            }
            assert!(
                worst < 6e-7 && worst <= 1.1 * worst_direction,
                "{projection:?} {width}: {worst} ({worst_direction})"
            );
        }
    }

    #[test]
    fn equirect_axes() {
        let c = Camera::new(Projection::Equirect { band_deg: None }, 360, 2.0);
        assert_eq!(c.height, 180);
        assert!((c.direction(0.0, 90.0) - Vec3::X).length() < 1e-6);
        assert!((c.direction(90.0, 90.0) - Vec3::Z).length() < 1e-6);
        assert!((c.direction(0.0, 0.0) - Vec3::Y).length() < 1e-6);
    }

    #[test]
    fn pinhole_centre_looks_along_yaw_and_pitch() {
        let c = Camera::new(
            Projection::Pinhole {
                hfov_deg: 60.0,
                yaw_deg: 90.0,
                pitch_deg: -10.0,
                roll_deg: 0.0,
            },
            200,
            2.0,
        );
        let d = c.direction(100.0, 50.0);
        let p = (-10f32).to_radians();
        assert!(
            (d - Vec3::new(0.0, p.sin(), p.cos())).length() < 1e-5,
            "{d}"
        );
        // the left edge is 30 degrees off axis
        assert!((c.direction(0.0, 50.0).dot(d) - 30f32.to_radians().cos()).abs() < 1e-5);
    }
}
