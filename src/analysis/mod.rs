//! The paper's statistics (section 5): per-pixel differences of relative luminance
//! ([`crate::color::luminance`]) of a scenario against the baseline, their azimuth-averaged
//! mean and standard deviation for every elevation row near the horizon (0 to -5 degrees by
//! default), and the band average of each; [`plot`] draws them (the paper's Figure 5) and the
//! renders side by side (Figure 4). `crate::app::compare` runs the scenarios.

pub mod plot;

use serde::Serialize;

use crate::color::luminance;
use crate::image_io::RgbImage;
use crate::render::Camera;

/// Azimuth-averaged statistics of a luminance difference on one elevation row.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct RowStat {
    pub elevation_deg: f64,
    pub mean: f64,
    pub std: f64,
}

/// For every row of `camera` whose centre lies in [bottom_deg, top_deg], the mean and standard
/// deviation over azimuth of Y(image) - Y(baseline). Sums in f64.
pub fn row_difference_stats(
    image: &RgbImage,
    baseline: &RgbImage,
    camera: &Camera,
    top_deg: f64,
    bottom_deg: f64,
) -> Vec<RowStat> {
    assert_eq!(
        (image.width, image.height),
        (baseline.width, baseline.height),
        "images of one camera"
    );
    (0..image.height)
        .filter_map(|y| {
            let elevation_deg = camera.row_elevation_deg(y);
            if elevation_deg > top_deg || elevation_deg < bottom_deg {
                return None;
            }
            let n = image.width as f64;
            let d =
                |x: usize| luminance(image.get(x, y)) as f64 - luminance(baseline.get(x, y)) as f64;
            let mean = (0..image.width).map(d).sum::<f64>() / n;
            let var = (0..image.width).map(|x| (d(x) - mean).powi(2)).sum::<f64>() / n;
            Some(RowStat {
                elevation_deg,
                mean,
                std: var.sqrt(),
            })
        })
        .collect()
}

/// Average of the rows' mean and standard deviation: (mean, std).
pub fn band_average(rows: &[RowStat]) -> (f64, f64) {
    let n = rows.len().max(1) as f64;
    (
        rows.iter().map(|r| r.mean).sum::<f64>() / n,
        rows.iter().map(|r| r.std).sum::<f64>() / n,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::Projection;
    use crate::rng::Rng;

    fn band_camera() -> Camera {
        // 3600 px: 0.1 degree rows; band +1 to -6 gives 70 rows.
        Camera::new(
            Projection::Equirect {
                band_deg: Some((1.0, -6.0)),
            },
            3600,
            2.0,
        )
    }

    #[test]
    fn identical_images_give_zero_mean_and_std() {
        let cam = band_camera();
        let mut img = RgbImage::new(cam.width, cam.height);
        let mut r = Rng::keyed(&[1]);
        img.pixels
            .iter_mut()
            .for_each(|p| *p = [r.f32(), r.f32(), r.f32()]);
        let rows = row_difference_stats(&img, &img, &cam, 0.0, -5.0);
        assert_eq!(rows.len(), 50);
        assert!(rows.iter().all(|r| r.mean == 0.0 && r.std == 0.0));
    }

    #[test]
    fn synthetic_differences_are_recovered() {
        let cam = band_camera();
        let base = RgbImage::new(cam.width, cam.height);
        let mut img = base.clone();
        let mut r = Rng::keyed(&[2]);
        let (c, sigma) = (0.25f32, 0.1f64);
        for y in 0..cam.height {
            let el = cam.row_elevation_deg(y);
            for x in 0..cam.width {
                let v = if el > -2.0 {
                    c // a constant offset in one band
                } else {
                    // Gaussian noise of known sigma (Box-Muller) in another
                    let (u1, u2) = (r.f64().max(1e-300), r.f64());
                    (sigma * (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()) as f32
                };
                img.pixels[y * cam.width + x] = [v; 3];
            }
        }
        let rows = row_difference_stats(&img, &base, &cam, 0.0, -5.0);
        for row in &rows {
            if row.elevation_deg > -2.0 {
                assert!(
                    (row.mean - c as f64).abs() < 1e-6 && row.std < 1e-6,
                    "{row:?}"
                );
            } else {
                assert!(
                    row.mean.abs() < 4.0 * sigma / (cam.width as f64).sqrt(),
                    "{row:?}"
                );
                assert!((row.std / sigma - 1.0).abs() < 0.06, "{row:?}");
            }
        }
        let noisy: Vec<RowStat> = rows
            .iter()
            .copied()
            .filter(|r| r.elevation_deg < -2.0)
            .collect();
        let (_, std) = band_average(&noisy);
        assert!(
            (std / sigma - 1.0).abs() < 0.02,
            "band-averaged std {std} vs {sigma}"
        );
    }

    #[test]
    fn rows_map_exactly_to_elevations_at_the_band_edges() {
        let cam = band_camera();
        let base = RgbImage::new(cam.width, cam.height);
        let rows = row_difference_stats(&base, &base, &cam, 0.0, -5.0);
        // row centres at -0.05 ... -4.95 degrees: exactly 50 rows, none outside [0, -5]
        assert!((rows[0].elevation_deg + 0.05).abs() < 1e-9);
        assert!((rows.last().unwrap().elevation_deg + 4.95).abs() < 1e-9);
    }
}
