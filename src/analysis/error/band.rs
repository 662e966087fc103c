//! From rows to a band: the summaries of a scenario's analysed rows, and which rows cross the
//! sun's glint.

use super::interval::{median, quantile, root};
use super::moments::RowSums;

/// One row of one scenario under one set of weights (the point estimate or a replicate).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct RowValue {
    pub mean: f64,
    /// Azimuthal variance of the measured difference, noise included.
    pub plain: f64,
    /// Mean noise variance of the pixel difference.
    pub noise: f64,
    /// Unbiased azimuthal variance of the expected difference (may be negative).
    pub signal: f64,
    /// The same of the smooth trend and of the residual detail.
    pub trend: f64,
    pub residual: f64,
}

impl RowValue {
    /// The trend is a circular moving average of each batch's difference, so its row mean is
    /// the difference's exactly and the residual's is exactly 0: the square of the row mean is
    /// estimated once, from the difference (whose pixels' noises are independent; the trend's
    /// are not), and the residual needs none.
    pub fn new(d: &RowSums, trend: &RowSums, residual: &RowSums) -> RowValue {
        let mean_square = d.signal() - d.p / d.n;
        RowValue {
            mean: d.mean(),
            plain: d.plain(),
            noise: d.noise().max(0.0),
            signal: d.signal(),
            trend: trend.p / trend.n + mean_square,
            residual: residual.p / residual.n,
        }
    }
}

/// Share of the rows cut from each end for the trimmed mean.
pub const TRIM: f64 = 0.2;

fn mean(v: impl Iterator<Item = f64>) -> f64 {
    let (s, n) = v.fold((0.0, 0usize), |(s, n), x| (s + x, n + 1));
    if n == 0 { f64::NAN } else { s / n as f64 }
}

/// Mean of the values left after cutting `TRIM` of them from each end (rounded down, so a
/// short band keeps every row).
fn trimmed_mean(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let cut = (TRIM * v.len() as f64).floor() as usize;
    mean(v[cut..v.len() - cut].iter().copied())
}

/// A band's summaries, each of variances (squared stds) so that ratios and square roots are
/// taken once, at the end.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct BandValue {
    /// Band mean of the rows' mean difference.
    pub mean: f64,
    /// The paper's statistic: the band mean of the rows' measured std (noise included).
    pub plain_std: f64,
    /// Band mean of the rows' unbiased signal variance: the corrected statistic is its root
    /// (the root mean square over rows of the rows' std).
    pub signal: f64,
    /// Band mean of the rows' noise-corrected std, each clipped at 0 (the paper's averaging of
    /// stds; biased where a row's noise rivals its signal).
    pub mean_of_stds: f64,
    pub median_signal: f64,
    pub trimmed_signal: f64,
    /// Over the rows that are not glint rows.
    pub without_glint: f64,
    pub trend: f64,
    pub residual: f64,
    /// Measured over predicted variance, summed over the band.
    pub variance_over_noise: f64,
}

impl BandValue {
    pub fn new(rows: &[RowValue], glint: &[bool]) -> BandValue {
        let kept = rows
            .iter()
            .zip(glint)
            .filter(|(_, g)| !**g)
            .map(|(r, _)| r.signal);
        BandValue {
            mean: mean(rows.iter().map(|r| r.mean)),
            plain_std: mean(rows.iter().map(|r| r.plain.sqrt())),
            signal: mean(rows.iter().map(|r| r.signal)),
            mean_of_stds: mean(rows.iter().map(|r| root(r.signal))),
            median_signal: median(rows.iter().map(|r| r.signal).collect()),
            trimmed_signal: trimmed_mean(rows.iter().map(|r| r.signal).collect()),
            without_glint: mean(kept),
            trend: mean(rows.iter().map(|r| r.trend)),
            residual: mean(rows.iter().map(|r| r.residual)),
            variance_over_noise: rows.iter().map(|r| r.plain).sum::<f64>()
                / rows.iter().map(|r| r.noise).sum::<f64>().max(1e-300),
        }
    }
}

/// How many times a row's RMS noise may exceed the quietest quarter's before the row counts
/// as holding sun-glint samples.
pub const GLINT_NOISE_FACTOR: f64 = 10.0;

/// One scenario's glint rows: a measured std above Tukey's far-out fence (Q3 + 3 IQR over the
/// rows), or a noise more than [`GLINT_NOISE_FACTOR`] times the rows' first quartile of noise
/// (a few samples of the sun's reflection, hundreds of times brighter than the rest, dominate
/// such rows; when they are most of the band, the fence alone misses them).
pub(super) fn glint_rows(rows: &[RowValue]) -> Vec<bool> {
    let sorted = |f: fn(&RowValue) -> f64| {
        let mut v: Vec<f64> = rows.iter().map(f).collect();
        v.sort_by(f64::total_cmp);
        v
    };
    let s = sorted(|r| r.plain.sqrt());
    let (q1, q3) = (quantile(&s, 0.25), quantile(&s, 0.75));
    let fence = q3 + 3.0 * (q3 - q1);
    let quiet = quantile(&sorted(|r| r.noise.sqrt()), 0.25);
    // With a noiseless quarter of the rows there is no quiet noise to compare with.
    rows.iter()
        .map(|r| {
            r.plain.sqrt() > fence || (quiet > 0.0 && r.noise.sqrt() > GLINT_NOISE_FACTOR * quiet)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(std: f64, noise: f64) -> RowValue {
        RowValue {
            plain: std * std,
            noise: noise * noise,
            ..RowValue::default()
        }
    }

    #[test]
    fn fences_find_outliers_and_noisy_majorities() {
        let g = glint_rows(&[1.0, 1.1, 0.9, 1.05, 0.95, 8.0].map(|s| row(s, 0.1)));
        assert_eq!(g, [false, false, false, false, false, true]);
        // Half the rows hold the glint: the fence misses them, their noise does not.
        let g =
            glint_rows(&[(0.1, 0.01), (2.0, 2.0), (0.1, 0.01), (2.5, 2.4)].map(|(s, n)| row(s, n)));
        assert_eq!(g, [false, true, false, true]);
    }

    #[test]
    fn band_summaries() {
        let rows: Vec<RowValue> = [4.0, 1.0, 1.0, 1.0, -0.5, 100.0, 1.0, 1.0, 1.0, 1.0]
            .iter()
            .map(|&s| RowValue {
                signal: s,
                ..RowValue::default()
            })
            .collect();
        let glint = [
            false, false, false, false, false, true, false, false, false, false,
        ];
        let b = BandValue::new(&rows, &glint);
        assert!((b.signal - 110.5 / 10.0).abs() < 1e-12);
        assert!((b.median_signal - 1.0).abs() < 1e-12);
        // Two cut from each end: -0.5 and 1.0 below, 100 and 4 above.
        assert!((b.trimmed_signal - 1.0).abs() < 1e-12);
        assert!((b.without_glint - 10.5 / 9.0).abs() < 1e-12);
        // The paper's averaging of stds clips the negative row at 0.
        assert!((b.mean_of_stds - (2.0 + 7.0 + 10.0) / 10.0).abs() < 1e-12);
    }
}
