//! Where `compare` spends its samples. The statistic's noise sits in a few pixels: those where
//! the sun's glitter is found by a few bright samples (on the default scene at 256 spp, five
//! pixels of a row's 1024 hold all but a trace of its noise), and those a coarse facet's
//! reflection of the sun covers in part. Pilot renders of the baseline and of the two low
//! scenarios, with their own sample seeds, find them; the scenarios are then rendered with
//! those pixels taking up to `max_boost` times the samples. The pilot's samples are not used in the
//! estimate: a pixel chosen because its own samples looked noisy would be biased, a pixel
//! chosen by independent samples is not (every pixel's estimate stays unbiased, whatever its
//! sample count).

use serde::Serialize;

use crate::render::Camera;
use crate::render::film::Film;

/// Added to the sample seed for the pilot (independent of the scenarios' and the noise
/// floor's samples).
pub const PILOT_SEED: u64 = 0x0070_696c_6f74;

/// How many extra samples the boost may add, as a share of the uniform render's: at most that
/// many more in all (the boost map is made sparser until it fits).
pub const BUDGET: f64 = 1.0;

/// Columns and rows a noisy pilot pixel lends its noise to: the glitter moves a little
/// between tessellations, and a glint pixel may show no hit in a short pilot.
const DILATE: (isize, isize) = (2, 1);

/// How the samples were spent (in `summary.json`).
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct SamplingReport {
    /// Most samples a pixel may take, in multiples of `spp` (1: a uniform render).
    pub max_boost: u16,
    pub pilot_spp: u32,
    pub pilot_seed: u64,
    /// Analysed pixels that took more than `spp` samples, and all analysed pixels.
    pub boosted_pixels: usize,
    pub analysed_pixels: usize,
    /// Samples of one scenario over those of a uniform render at `spp`.
    pub cost_factor: f64,
    /// Mean samples per analysed pixel.
    pub mean_spp_analysed: f64,
    /// The pilots' run time: their traces and the boost map (not the ocean or the meshes).
    pub seconds_pilot: f64,
}

/// Most samples one pixel may take (the film's fixed-point sums are exact up to a million).
pub const MAX_PIXEL_SAMPLES: u64 = 1_000_000;

/// The largest boost a render at `spp` may use: `max_boost`, or less where it would take a pixel
/// past [`MAX_PIXEL_SAMPLES`].
pub fn boost_limit(spp: u32, max_boost: u16) -> u16 {
    (MAX_PIXEL_SAMPLES / u64::from(spp.max(1))).clamp(1, u64::from(max_boost)) as u16
}

/// The pilot's samples per pixel for a comparison at `spp`: a quarter, at least 8 (the
/// estimate's batches).
pub fn pilot_spp(spp: u32) -> u32 {
    (spp / 4).max(8)
}

/// A boost map that samples the rows `rows_deg` of `camera`'s image (factor 1) and leaves every
/// other row out (0): all of a pilot that [`boost_map`] reads, whose dilation stays inside them.
pub fn analysed_rows(camera: &Camera, rows_deg: (f64, f64)) -> Vec<u16> {
    let w = camera.width;
    let mut map = vec![0u16; w * camera.height];
    for y in camera.rows_between(rows_deg) {
        map[y * w..(y + 1) * w].fill(1);
    }
    map
}

/// The boost map from the pilots: each analysed pixel's noise (the per-sample variance of its
/// luminance, the largest over the pilots and its neighbourhood) against the median analysed
/// pixel's, v / v0,
/// gives it (v / v0)^(2/3) times the samples, rounded down to a power of two and at most
/// `max_boost`: the split that minimises the variance of a sum of squared noisy values for a
/// given number of samples (each pixel's variance falls as 1/n, its square as 1/n^2). If the
/// extra samples would pass [`BUDGET`], v0 is doubled until they do not.
pub fn boost_map(
    pilots: &[Film],
    camera: &Camera,
    rows_deg: (f64, f64),
    max_boost: u16,
) -> Vec<u16> {
    let (w, h) = (camera.width, camera.height);
    let mut boost = vec![1u16; w * h];
    let rows = camera.rows_between(rows_deg);
    if max_boost <= 1 || rows.is_empty() || pilots.is_empty() {
        return boost;
    }
    let v = |x: usize, y: usize| {
        pilots
            .iter()
            .map(|p| p.var_y[y * w + x] as f64 * p.spp as f64)
            .fold(0.0, f64::max)
    };
    let (first, last) = (rows[0] as isize, *rows.last().unwrap() as isize);
    let dilated = |x: usize, y: usize| {
        let mut m: f64 = 0.0;
        for dy in -DILATE.1..=DILATE.1 {
            let yy = y as isize + dy;
            if yy < first || yy > last {
                continue;
            }
            for dx in -DILATE.0..=DILATE.0 {
                let xx = (x as isize + dx).rem_euclid(w as isize) as usize;
                m = m.max(v(xx, yy as usize));
            }
        }
        m
    };
    let noise: Vec<(usize, f64)> = rows
        .iter()
        .flat_map(|&y| (0..w).map(move |x| (y, x)))
        .map(|(y, x)| (y * w + x, dilated(x, y)))
        .collect();
    let mut v0 = crate::analysis::error::median(
        rows.iter()
            .flat_map(|&y| (0..w).map(move |x| v(x, y)))
            .collect(),
    );
    if v0.is_nan() || v0 <= 0.0 {
        // A noiseless majority: the mean of the noisy minority is the scale.
        v0 = noise.iter().map(|p| p.1).sum::<f64>() / noise.len() as f64;
        if v0.is_nan() || v0 <= 0.0 {
            return boost;
        }
    }
    let budget = BUDGET * (w * h) as f64;
    for _ in 0..64 {
        let factor = |vx: f64| -> u16 {
            let f = (vx / v0).powf(2.0 / 3.0);
            if f < 2.0 {
                1
            } else {
                let p = f.log2().floor().min(15.0) as u32;
                (1u32 << p).min(max_boost as u32) as u16
            }
        };
        let extra: f64 = noise.iter().map(|&(_, vx)| factor(vx) as f64 - 1.0).sum();
        if extra <= budget {
            for &(i, vx) in &noise {
                boost[i] = factor(vx);
            }
            return boost;
        }
        v0 *= 2.0;
    }
    boost
}

/// The report of a boost map.
pub fn report(
    boost: &[u16],
    camera: &Camera,
    rows_deg: (f64, f64),
    spp: u32,
    max_boost: u16,
    seed: u64,
    seconds_pilot: f64,
) -> SamplingReport {
    let w = camera.width;
    let analysed: Vec<u16> = camera
        .rows_between(rows_deg)
        .into_iter()
        .flat_map(|y| boost[y * w..(y + 1) * w].iter().copied())
        .collect();
    let total: f64 = boost.iter().map(|&b| b as f64).sum();
    SamplingReport {
        max_boost,
        pilot_spp: if max_boost > 1 { pilot_spp(spp) } else { 0 },
        pilot_seed: seed,
        boosted_pixels: analysed.iter().filter(|&&b| b > 1).count(),
        analysed_pixels: analysed.len(),
        cost_factor: total / boost.len().max(1) as f64,
        mean_spp_analysed: spp as f64 * analysed.iter().map(|&b| b as f64).sum::<f64>()
            / analysed.len().max(1) as f64,
        seconds_pilot,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Projection;
    use crate::image_io::RgbImage;

    fn film(w: usize, h: usize, var: impl Fn(usize, usize) -> f32) -> Film {
        Film {
            image: RgbImage::new(w, h),
            var_y: (0..w * h).map(|i| var(i % w, i / w)).collect(),
            spp: 16,
            batches: None,
        }
    }

    #[test]
    fn glints_get_samples_their_neighbours_some_and_the_rest_none() {
        let cam = Camera::new(
            Projection::Equirect {
                band_deg: Some((1.0, -6.0)),
            },
            512,
            2.0,
        );
        let (w, h) = (cam.width, cam.height);
        // One very noisy pixel per analysed row at column 100, a quiet sky elsewhere.
        let f = film(w, h, |x, _| if x == 100 { 1000.0 } else { 1.0 });
        let b = boost_map(std::slice::from_ref(&f), &cam, (0.0, -5.0), 64);
        let analysed: Vec<usize> = (0..h)
            .filter(|&y| (-5.0..=0.0).contains(&cam.row_elevation_deg(y)))
            .collect();
        for y in 0..h {
            let row = &b[y * w..(y + 1) * w];
            if analysed.contains(&y) {
                // (1000)^(2/3) = 100 -> 64, and the dilation lends it two columns each side.
                assert_eq!(&row[98..=102], &[64; 5], "row {y}");
                assert_eq!(row[97], 1);
                assert_eq!(row[103], 1);
                assert_eq!(row.iter().filter(|&&m| m > 1).count(), 5);
            } else {
                assert!(row.iter().all(|&m| m == 1), "row {y} is not analysed");
            }
        }
        // Off, and a noiseless film: no boost.
        let one = |f: &Film, m| boost_map(std::slice::from_ref(f), &cam, (0.0, -5.0), m);
        assert!(one(&f, 1).iter().all(|&m| m == 1));
        assert!(one(&film(w, h, |_, _| 0.0), 64).iter().all(|&m| m == 1));
        // A second pilot noisy elsewhere (a facet's sun reflection at column 300) adds its
        // pixels.
        let g = film(w, h, |x, _| if x == 300 { 1000.0 } else { 1.0 });
        let both = boost_map(&[f.clone(), g], &cam, (0.0, -5.0), 64);
        let y = analysed[0];
        assert_eq!(both[y * w + 100], 64);
        assert_eq!(both[y * w + 300], 64);
    }

    #[test]
    fn no_pixel_passes_a_million_samples() {
        assert_eq!(boost_limit(1024, 64), 64);
        assert_eq!(boost_limit(65536, 64), 15);
        assert_eq!(boost_limit(1_000_000, 64), 1);
        assert_eq!(boost_limit(16, 1), 1);
    }

    #[test]
    fn the_budget_holds_when_noise_is_everywhere() {
        let cam = Camera::new(Projection::Equirect { band_deg: None }, 256, 2.0);
        let (w, h) = (cam.width, cam.height);
        // Every eighth column 1000 times noisier than the rest: with its neighbours, 5 of 8
        // pixels want 64 times the samples, far past the budget.
        let f = film(w, h, |x, _| if x % 8 == 0 { 1000.0 } else { 1.0 });
        let b = boost_map(&[f], &cam, (90.0, -90.0), 64);
        let extra: f64 = b.iter().map(|&m| m as f64 - 1.0).sum();
        assert!(extra <= BUDGET * (w * h) as f64, "{extra}");
        assert!(
            extra > 0.5 * BUDGET * (w * h) as f64,
            "{extra}: the budget is used"
        );
        assert!(b.contains(&1), "the quiet columns take no more");
        let r = report(&b, &cam, (90.0, -90.0), 16, 64, 1, 0.0);
        assert!(r.cost_factor <= 1.0 + BUDGET + 1e-9);
        assert_eq!(r.analysed_pixels, w * h);
    }
}
