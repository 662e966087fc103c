//! The error estimator behind every accuracy figure the project reports: the paper's per-row
//! standard deviation of a luminance difference against a baseline, with the Monte Carlo noise
//! taken out without bias, band summaries, ratios of two scenarios, and 95 % intervals that say
//! where the converged value of this image lies. docs/error-estimator.md gives the evidence
//! behind each choice.
//!
//! **What is estimated.** For a scenario S and the baseline 0, the expected pixel difference
//! mu(x) = E[Y_S(x) - Y_0(x)] (the difference of the two converged images). Per elevation row,
//! sigma^2 = the variance of mu over azimuth; per band of rows, the corrected statistic is
//! sqrt(mean over rows of sigma^2), the root mean square over rows of the rows' std. A ratio of
//! two scenarios is sqrt(sum sigma_a^2 / sum sigma_b^2) over the band.
//!
//! **Without bias, without clipping.** The films keep k batch means per pixel (samples dealt
//! round-robin, each batch its own sample pattern and random streams; `crate::render::film`),
//! so the batch differences D_1..D_k of a pixel are independent estimates of mu(x), whatever
//! correlation shared sample seeds put between S and 0. A product of two of them, D_b D_c with
//! b != c, estimates mu(x)^2 with nothing to subtract; averaged over the pairs and the row's
//! pixels (and the row mean's square estimated the same way) it gives sigma^2 without bias
//! ([`moments::RowSums::signal`]). It is negative when the noise happened to exceed the signal,
//! and it is kept negative: rows are summed first, and a square root is taken once, of the
//! band's sum. (Per-row stds, clipped at 0 and then averaged, as the paper averages them, are
//! reported too, and are biased upwards where a row's noise rivals its signal.)
//!
//! **Intervals.** A bootstrap of the samples: each replicate redraws, in every azimuth block
//! independently, which batches it takes ([`bootstrap`]); every statistic is recomputed from
//! per-block moments; the interval is the bias-corrected percentile interval of [`REPLICATES`]
//! replicates (deterministic seed), their spread scaled by sqrt(k / (k - 1)). The image is held
//! fixed: an interval covers the converged value of this image (this sea, this sky, this
//! camera), not of the sea state; blocks redrawn over azimuth as well were measured to give
//! intervals 2 to 6 times wider that still covered, and were not kept. An interval cannot show
//! samples that were never drawn (a pixel whose sun reflection no sample has hit yet); glint
//! rows are therefore named, and the robust summaries beside the mean say how much they weigh.
//!
//! **Robust summaries.** The median and the 20 % trimmed mean over rows; the glint rows (a
//! far-outlier std or a noise far above the quiet rows', see [`band::glint_rows`]) by
//! elevation, and the statistic without them; how many rows have more noise than signal; and
//! the split of each row into a smooth azimuthal trend (a circular moving average over
//! [`TREND_DEG`] degrees of each batch) and the residual detail.

mod band;
mod bootstrap;
mod interval;
mod moments;
pub mod realizations;
#[cfg(test)]
mod tests;

use rayon::prelude::*;
use serde::Serialize;

use crate::render::Camera;
use crate::render::film::Film;
use band::{BandValue, RowValue, glint_rows};
pub use band::{GLINT_NOISE_FACTOR, TRIM};
pub use bootstrap::REPLICATES;
use interval::root;
pub use interval::{CONFIDENCE, Interval};
pub(crate) use interval::{median, quantile};
use moments::{Field, K, RowSums, Weights};

/// Azimuthal length of a bootstrap block, degrees.
pub const BLOCK_DEG: f64 = 5.625;
/// Width of the moving average that defines the smooth azimuthal trend, degrees.
pub const TREND_DEG: f64 = 10.0;
/// Fewest batches (and so samples per pixel) the estimate takes: with fewer, a bootstrap of
/// the batches has too few ways to draw them.
pub const MIN_BATCHES: usize = 8;

/// One analysed row of one scenario.
#[derive(Clone, Debug, Serialize)]
pub struct RowEstimate {
    pub elevation_deg: f64,
    /// Azimuthal mean of the difference.
    pub mean: f64,
    /// The paper's statistic: azimuthal std of the difference, noise included.
    pub std: f64,
    /// RMS Monte Carlo noise of the pixel difference.
    pub noise: f64,
    /// Unbiased azimuthal variance of the expected difference (negative when the noise
    /// happened to exceed the signal), its root (0 then) and the root's interval.
    pub variance_corrected: f64,
    pub std_corrected: f64,
    pub std_corrected_ci: [f64; 2],
    /// A glint row (see the module doc).
    pub glint: bool,
    /// Its noise variance exceeds its corrected variance.
    pub noisy: bool,
    pub trend_std: f64,
    pub residual_std: f64,
}

/// One scenario against the baseline, over the band of analysed rows.
#[derive(Clone, Debug, Serialize)]
pub struct ScenarioEstimate {
    pub name: String,
    /// Band average of the rows' mean difference (a brightening when positive).
    pub mean: Interval,
    /// The paper's band average of the rows' std, noise included.
    pub std: f64,
    /// The corrected statistic: root mean square over rows of the std of the expected
    /// difference, and the band's mean variance it is the root of (may be negative).
    pub std_corrected: Interval,
    pub variance_corrected: Interval,
    /// The paper's averaging (band mean of per-row stds, each noise-corrected and clipped at 0).
    pub std_corrected_mean_rows: f64,
    /// Root of the median, and of the trimmed mean, over rows of the corrected variance.
    pub std_corrected_median_rows: Interval,
    pub std_corrected_trimmed: Interval,
    /// Elevations of the glint rows (the same for every scenario), and the statistic without.
    pub glint_rows_deg: Vec<f64>,
    pub std_corrected_without_glint: Interval,
    /// Rows whose noise variance exceeds their corrected variance.
    pub noisy_rows: usize,
    /// The corrected statistic of the smooth azimuthal trend and of the residual detail.
    pub trend_std: Interval,
    pub residual_std: Interval,
    /// RMS noise of the pixel difference over the band.
    pub noise: f64,
    /// Measured over predicted variance summed over the band: about 1 where the scenario
    /// differs from the baseline by noise alone (the noise floor checks the noise model).
    pub variance_over_noise: Interval,
    /// The corrected variance's interval lies above 0: the scenario differs from the baseline.
    pub significant: bool,
    pub rows: Vec<RowEstimate>,
}

/// A ratio of two scenarios' corrected band statistics, with its verdict.
#[derive(Clone, Debug, Serialize)]
pub struct RatioEstimate {
    /// Of the paper's plain statistic (noise included), for comparison.
    pub plain: f64,
    /// sqrt(band variance of one / of the other); +inf when the second's is at or below 0.
    pub corrected: Interval,
    /// Whether the interval excludes 1.
    pub significant: bool,
    /// The same ratio of the median over rows, of the trimmed mean, and without glint rows.
    pub median_rows: Interval,
    pub trimmed: Interval,
    pub without_glint: Interval,
    pub trend: Interval,
    pub residual: Interval,
    /// When not significant: samples per pixel at which the interval would exclude 1 if the
    /// ratio stayed put (the interval's width is all Monte Carlo noise, which shrinks as
    /// 1/sqrt(spp)).
    pub spp_to_resolve: Option<u64>,
}

/// The estimator's input: the baseline and the scenarios, each as a film of one camera.
pub struct Inputs<'a> {
    pub camera: &'a Camera,
    pub baseline: &'a Film,
    pub scenarios: Vec<(String, &'a Film)>,
    /// Analysed elevations, from `rows_deg.0` down to `rows_deg.1`.
    pub rows_deg: (f64, f64),
    /// Seed of the bootstrap.
    pub seed: u64,
}

/// What the estimator found.
#[derive(Clone, Debug, Serialize)]
pub struct Estimates {
    pub rows: usize,
    pub block_deg: f64,
    pub blocks: usize,
    pub batches: usize,
    pub replicates: usize,
    pub scenarios: Vec<ScenarioEstimate>,
}

/// Errors in what was asked.
#[derive(Debug, thiserror::Error)]
pub enum EstimateError {
    #[error(
        "the error estimate needs at least {MIN_BATCHES} samples per pixel, in {MIN_BATCHES} independent batches (got {0})"
    )]
    TooFewSamples(u32),
    #[error("the films were rendered without batch means (render them with batches)")]
    NoBatches,
    #[error("no image row lies between {0} and {1} degrees; widen the band or the image")]
    NoRows(f64, f64),
    #[error(
        "the images differ in size, or their samples are split into batches differently (films of different spp need spp a multiple of the batch count)"
    )]
    Mismatch,
}

/// The estimator over one set of films: per-block moments are made once, each replicate's
/// row values from them, and every statistic is read from those.
pub struct Estimator {
    names: Vec<String>,
    spp: f64,
    k: usize,
    blocks: usize,
    elevations: Vec<f64>,
    /// Row values of every scenario: the point estimate, and each replicate's.
    point: Vec<Vec<RowValue>>,
    replicates: Vec<Vec<Vec<RowValue>>>,
    /// The glint rows, the same for every scenario (a union), fixed by the point estimate.
    glint: Vec<bool>,
}

/// Every scenario's row values under one draw of batch weights.
fn rows_under(table: &moments::Table, draw: &[[f64; K]]) -> Vec<Vec<RowValue>> {
    table
        .moments
        .iter()
        .zip(&table.weights)
        .map(|(rows, w)| {
            rows.iter()
                .map(|blocks| {
                    let mut sums = [RowSums::default(); 3];
                    for (m, c) in blocks.iter().zip(draw) {
                        let weights = Weights::new(c, w, table.k);
                        for (s, f) in
                            sums.iter_mut()
                                .zip([Field::Difference, Field::Trend, Field::Residual])
                        {
                            s.add_weighted(m.field(f), m.n, &weights, 1.0);
                        }
                    }
                    RowValue::new(&sums[0], &sums[1], &sums[2])
                })
                .collect()
        })
        .collect()
}

impl Estimator {
    pub fn new(inp: &Inputs) -> Result<Estimator, EstimateError> {
        let table = moments::table(inp)?;
        if table.k < MIN_BATCHES {
            return Err(EstimateError::TooFewSamples(inp.baseline.spp));
        }
        let point = rows_under(&table, &bootstrap::identity(table.blocks, table.k));
        let glint = (0..table.elevations.len())
            .map(|i| point.iter().any(|rows| glint_rows(rows)[i]))
            .collect();
        let replicates = (0..REPLICATES)
            .into_par_iter()
            .map(|r| rows_under(&table, &bootstrap::draw(inp.seed, r, table.blocks, table.k)))
            .collect();
        Ok(Estimator {
            names: inp.scenarios.iter().map(|(n, _)| n.clone()).collect(),
            spp: inp.baseline.spp as f64,
            k: table.k,
            blocks: table.blocks,
            elevations: table.elevations,
            point,
            replicates,
            glint,
        })
    }

    /// The interval of a statistic of scenario `s`'s rows.
    fn interval(&self, s: usize, f: impl Fn(&[RowValue]) -> f64 + Sync) -> Interval {
        Interval::new(
            f(&self.point[s]),
            self.replicates.iter().map(|r| f(&r[s])),
            bootstrap::inflation(self.k),
        )
    }

    /// The interval of a statistic of two scenarios' rows.
    fn interval2(
        &self,
        a: usize,
        b: usize,
        f: impl Fn(&[RowValue], &[RowValue]) -> f64 + Sync,
    ) -> Interval {
        Interval::new(
            f(&self.point[a], &self.point[b]),
            self.replicates.iter().map(|r| f(&r[a], &r[b])),
            bootstrap::inflation(self.k),
        )
    }

    fn band(&self, rows: &[RowValue]) -> BandValue {
        BandValue::new(rows, &self.glint)
    }

    /// Every scenario against the baseline.
    pub fn scenarios(&self) -> Estimates {
        let scenarios = (0..self.names.len())
            .map(|s| self.scenario(s))
            .collect::<Vec<_>>();
        Estimates {
            rows: self.elevations.len(),
            block_deg: BLOCK_DEG,
            blocks: self.blocks,
            batches: self.k,
            replicates: REPLICATES,
            scenarios,
        }
    }

    fn scenario(&self, s: usize) -> ScenarioEstimate {
        let point = &self.point[s];
        let b = self.band(point);
        let variance_corrected = self.interval(s, |r| self.band(r).signal);
        let rows = point
            .iter()
            .enumerate()
            .map(|(i, r)| RowEstimate {
                elevation_deg: self.elevations[i],
                mean: r.mean,
                std: r.plain.sqrt(),
                noise: r.noise.sqrt(),
                variance_corrected: r.signal,
                std_corrected: root(r.signal),
                std_corrected_ci: self.interval(s, |rows| rows[i].signal).map(root).ci,
                glint: self.glint[i],
                noisy: r.noise > r.signal,
                trend_std: root(r.trend),
                residual_std: root(r.residual),
            })
            .collect();
        ScenarioEstimate {
            name: self.names[s].clone(),
            mean: self.interval(s, |r| self.band(r).mean),
            std: b.plain_std,
            std_corrected: variance_corrected.map(root),
            variance_corrected,
            std_corrected_mean_rows: b.mean_of_stds,
            std_corrected_median_rows: self.interval(s, |r| self.band(r).median_signal).map(root),
            std_corrected_trimmed: self.interval(s, |r| self.band(r).trimmed_signal).map(root),
            glint_rows_deg: self
                .elevations
                .iter()
                .zip(&self.glint)
                .filter(|(_, g)| **g)
                .map(|(e, _)| *e)
                .collect(),
            std_corrected_without_glint: self.interval(s, |r| self.band(r).without_glint).map(root),
            noisy_rows: point.iter().filter(|r| r.noise > r.signal).count(),
            trend_std: self.interval(s, |r| self.band(r).trend).map(root),
            residual_std: self.interval(s, |r| self.band(r).residual).map(root),
            noise: (point.iter().map(|r| r.noise).sum::<f64>() / point.len().max(1) as f64).sqrt(),
            variance_over_noise: self.interval(s, |r| self.band(r).variance_over_noise),
            significant: variance_corrected.above(0.0),
            rows,
        }
    }

    /// The ratio of scenario `num`'s corrected band statistic to scenario `den`'s (indices into
    /// the inputs' scenarios), with its interval and, when that does not exclude 1, the samples
    /// per pixel that would resolve it.
    pub fn ratio(&self, num: usize, den: usize) -> RatioEstimate {
        let ratio = |f: fn(&BandValue) -> f64| {
            move |a: &[RowValue], b: &[RowValue]| {
                let (x, y) = (f(&self.band(a)), f(&self.band(b)));
                if y > 0.0 { root(x / y) } else { f64::INFINITY }
            }
        };
        // A ratio of stds is at least 0 (its replicates are; widening them about the estimate
        // can reach below).
        let interval = |f| self.interval2(num, den, ratio(f)).at_least(0.0);
        let corrected = interval(|v| v.signal);
        let significant = corrected.excludes(1.0);
        let v = corrected.value;
        let spp_to_resolve = (!significant && v.is_finite() && v != 1.0).then(|| {
            let half = if v > 1.0 {
                v - corrected.ci[0]
            } else {
                corrected.ci[1] - v
            };
            (self.spp * (half / (v - 1.0).abs()).powi(2))
                .ceil()
                .min(1e15) as u64
        });
        let (pa, pb) = (self.band(&self.point[num]), self.band(&self.point[den]));
        RatioEstimate {
            plain: pa.plain_std / pb.plain_std,
            corrected,
            significant,
            median_rows: interval(|v| v.median_signal),
            trimmed: interval(|v| v.trimmed_signal),
            without_glint: interval(|v| v.without_glint),
            trend: interval(|v| v.trend),
            residual: interval(|v| v.residual),
            spp_to_resolve,
        }
    }

    /// The error of scenario `s` as rendered, noise included: the root mean square over rows of
    /// the azimuthal std of its difference from the baseline, less the baseline's own noise
    /// (`baseline_noise[row]`, the mean over the row's pixels of the variance of the baseline's
    /// pixel mean; rendered with other sample seeds, its noise adds to the difference's). With a
    /// converged baseline this is what a user of that render sees: its systematic error and its
    /// noise together.
    ///
    /// With `with_mean`, the rows' mean difference counts too: the root mean square over the
    /// band's pixels of the difference from the converged image.
    pub fn total_error(&self, s: usize, baseline_noise: &[f64], with_mean: bool) -> Interval {
        assert_eq!(baseline_noise.len(), self.elevations.len());
        self.interval(s, |rows| {
            let sum: f64 = rows
                .iter()
                .zip(baseline_noise)
                .map(|(r, n)| r.plain - n + if with_mean { r.mean * r.mean } else { 0.0 })
                .sum();
            sum / rows.len() as f64
        })
        .map(root)
    }

    /// Elevations of the analysed rows, degrees.
    pub fn elevations(&self) -> &[f64] {
        &self.elevations
    }
}
