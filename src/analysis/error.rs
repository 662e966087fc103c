//! The error estimator behind every accuracy figure the project reports: the paper's per-row
//! standard deviation of a luminance difference, corrected for Monte Carlo noise, with 95 %
//! confidence intervals, robust band summaries and a significance verdict.
//!
//! **Noise model.** For a scenario S and the baseline 0 rendered with `n` samples per pixel,
//! the pixel difference is D = Y_S - Y_0. The films keep k batch means per pixel (samples dealt
//! round-robin, each batch with its own sample pattern and random streams; `crate::render::film`),
//! so the batch differences D_1..D_k are independent estimates of the same expected difference,
//! including the correlation two renders with the same sample seeds have. Their spread
//! estimates the per-sample variance without bias, s^2 = sum_b n_b (D_b - D)^2 / (k - 1) (the
//! between-batch sum of squares), and the noise variance of D is s^2 / n. With k = 8 this has 7
//! degrees of freedom per pixel; two halves would have 1, which sun glints (a few samples
//! hundreds of times brighter than the rest) make too erratic to subtract. The measured variance
//! of D along a row is the true variance plus the row's mean noise variance, so
//! `std_corrected = sqrt(max(0, std^2 - noise^2))` with `noise^2` the row mean of the pixel
//! noise variances.
//!
//! **Intervals.** A block bootstrap over azimuth: each row is cut into blocks of
//! [`BLOCK_DEG`] degrees, and a replicate draws as many blocks with replacement, the same blocks
//! for every row and every scenario (so statistics that combine rows or scenarios, like the
//! improvement ratio, keep their correlations). Every statistic is recomputed per replicate
//! from per-block sums; the 95 % interval is the 2.5 and 97.5 percentiles of
//! [`REPLICATES`] replicates (deterministic seed). Blocks longer than the azimuthal
//! correlation of the difference (wave groups, glints) keep the interval honest; the interval
//! covers both the Monte Carlo noise and how much the statistic varies over azimuth.
//!
//! **Robust summaries.** Beside the paper's mean over rows: the median over rows; the glint
//! rows (those that cross the sun's reflection: a far-outlier std, or a noise far above the
//! quiet rows', see [`glint_rows`]), reported by elevation, and the mean and the ratio without
//! them; and the split of each row into a smooth azimuthal trend (a circular moving average
//! over [`TREND_DEG`] degrees) and the residual detail, each noise-corrected. With a physical
//! sun (radiance thousands of times the sky's) the glint rows' noise is so heavy-tailed that no
//! estimate from a few hundred samples per pixel is stable; the summary without them is.
//!
//! **How many samples.** When an interval does not separate a ratio from 1, the same bootstrap
//! run on each half of the batches alone (half the samples) tells how much of the interval's
//! width is
//! Monte Carlo noise (it scales as 1/spp in variance) and how much the spread over azimuth
//! (it does not); from the two, the spp at which the interval would exclude 1 if the ratio
//! stayed where it is, or that more samples alone cannot do it.

use rayon::prelude::*;
use serde::Serialize;

use crate::render::Camera;
use crate::render::film::{Batches, Film};
use crate::rng::Rng;

/// Azimuthal length of a bootstrap block, degrees.
pub const BLOCK_DEG: f64 = 5.625;
/// Width of the moving average that defines the smooth azimuthal trend, degrees.
pub const TREND_DEG: f64 = 10.0;
/// Bootstrap replicates.
pub const REPLICATES: usize = 1000;
/// Two-sided confidence level of every interval.
pub const CONFIDENCE: f64 = 0.95;

/// Per-block sums of one scenario's difference on one row.
#[derive(Clone, Copy, Debug, Default)]
struct Sums {
    n: f64,
    /// Sum and sum of squares of D, and the sum of its per-pixel noise variances.
    d: [f64; 3],
    /// The same for each half (with that half's noise variance).
    half: [[f64; 3]; 2],
    /// Sum and sum of squares of the trend and of the residual.
    trend: [f64; 2],
    residual: [f64; 2],
}

impl std::ops::AddAssign for Sums {
    fn add_assign(&mut self, o: Sums) {
        self.n += o.n;
        for k in 0..3 {
            self.d[k] += o.d[k];
            self.half[0][k] += o.half[0][k];
            self.half[1][k] += o.half[1][k];
        }
        for k in 0..2 {
            self.trend[k] += o.trend[k];
            self.residual[k] += o.residual[k];
        }
    }
}

/// Variance of a sample from its sums (population form: the row is the whole population of
/// its pixels).
fn variance(n: f64, s1: f64, s2: f64) -> f64 {
    let m = s1 / n;
    (s2 / n - m * m).max(0.0)
}

/// Which of a row's statistics to take: of the full difference or of one half.
#[derive(Clone, Copy, PartialEq)]
enum Which {
    Full,
    Half(usize),
}

/// A row's statistics from its sums.
#[derive(Clone, Copy, Debug, Default)]
struct RowValue {
    mean: f64,
    std: f64,
    noise: f64,
    std_corrected: f64,
    trend: f64,
    residual: f64,
    variance: f64,
    noise_variance: f64,
}

fn row_value(s: &Sums, which: Which, trend_px: f64) -> RowValue {
    let [s1, s2, q] = match which {
        Which::Full => s.d,
        Which::Half(h) => s.half[h],
    };
    let var = variance(s.n, s1, s2);
    let noise = q / s.n;
    let trend_var = variance(s.n, s.trend[0], s.trend[1]);
    let residual_var = variance(s.n, s.residual[0], s.residual[1]);
    RowValue {
        mean: s1 / s.n,
        std: var.sqrt(),
        noise: noise.sqrt(),
        std_corrected: (var - noise).max(0.0).sqrt(),
        // A moving average of k pixels keeps 1/k of the noise variance; the residual the rest.
        trend: (trend_var - noise / trend_px).max(0.0).sqrt(),
        residual: (residual_var - noise * (1.0 - 1.0 / trend_px))
            .max(0.0)
            .sqrt(),
        variance: var,
        noise_variance: noise,
    }
}

/// Band summaries of one scenario from its rows.
#[derive(Clone, Copy, Debug, Default)]
struct BandValue {
    mean: f64,
    std: f64,
    std_corrected: f64,
    median_corrected: f64,
    without_glint: f64,
    trend: f64,
    residual: f64,
    variance_over_noise: f64,
}

fn mean(v: impl Iterator<Item = f64>) -> f64 {
    let (s, n) = v.fold((0.0, 0usize), |(s, n), x| (s + x, n + 1));
    s / n.max(1) as f64
}

/// Median of a list (NaN when empty).
pub(crate) fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let m = v.len() / 2;
    if v.len() % 2 == 1 {
        v[m]
    } else {
        0.5 * (v[m - 1] + v[m])
    }
}

/// The p-quantile (0..=1) of sorted values, linear between order statistics.
fn quantile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let x = p * (sorted.len() - 1) as f64;
    let (i, f) = (x.floor() as usize, x - x.floor());
    let j = (i + 1).min(sorted.len() - 1);
    sorted[i] * (1.0 - f) + sorted[j] * f
}

/// How many times a row's RMS noise may exceed the quietest quarter's before the row counts
/// as holding sun-glint samples.
pub const GLINT_NOISE_FACTOR: f64 = 10.0;

/// One scenario's glint rows: a measured std above Tukey's far-out fence (Q3 + 3 IQR over the
/// rows), or a noise more than [`GLINT_NOISE_FACTOR`] times the rows' first quartile of noise
/// (a few samples of the sun's reflection, hundreds of times brighter than the rest, dominate
/// such rows; when they are most of the band, the fence alone misses them).
fn glint_rows(rows: &[RowValue]) -> Vec<bool> {
    let sorted = |f: fn(&RowValue) -> f64| {
        let mut v: Vec<f64> = rows.iter().map(f).collect();
        v.sort_by(f64::total_cmp);
        v
    };
    let s = sorted(|r| r.std);
    let (q1, q3) = (quantile(&s, 0.25), quantile(&s, 0.75));
    let fence = q3 + 3.0 * (q3 - q1);
    let quiet = quantile(&sorted(|r| r.noise), 0.25);
    rows.iter()
        .map(|r| r.std > fence || r.noise > GLINT_NOISE_FACTOR * quiet)
        .collect()
}

fn band(rows: &[RowValue], glint: &[bool]) -> BandValue {
    let kept = || rows.iter().zip(glint).filter(|(_, g)| !**g).map(|(r, _)| r);
    BandValue {
        mean: mean(rows.iter().map(|r| r.mean)),
        std: mean(rows.iter().map(|r| r.std)),
        std_corrected: mean(rows.iter().map(|r| r.std_corrected)),
        median_corrected: median(rows.iter().map(|r| r.std_corrected).collect()),
        without_glint: mean(kept().map(|r| r.std_corrected)),
        trend: mean(rows.iter().map(|r| r.trend)),
        residual: mean(rows.iter().map(|r| r.residual)),
        variance_over_noise: rows.iter().map(|r| r.variance).sum::<f64>()
            / rows
                .iter()
                .map(|r| r.noise_variance)
                .sum::<f64>()
                .max(1e-300),
    }
}

/// A value and its 95 % interval.
#[derive(Clone, Copy, Debug, Serialize, PartialEq)]
pub struct Interval {
    pub value: f64,
    pub ci: [f64; 2],
}

/// Standard normal CDF (Abramowitz & Stegun 7.1.26 for erf, |error| < 1.5e-7).
fn normal_cdf(z: f64) -> f64 {
    let x = z.abs() / std::f64::consts::SQRT_2;
    let t = 1.0 / (1.0 + 0.327_591_1 * x);
    let poly = t
        * (0.254_829_592
            + t * (-0.284_496_736
                + t * (1.421_413_741 + t * (-1.453_152_027 + t * 1.061_405_429))));
    let erf = 1.0 - poly * (-x * x).exp();
    0.5 * (1.0 + erf.copysign(z))
}

/// Standard normal quantile, by bisection on [`normal_cdf`] (60 steps: exact to its accuracy).
fn normal_quantile(p: f64) -> f64 {
    let (mut lo, mut hi) = (-10.0, 10.0);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if normal_cdf(mid) < p {
            lo = mid
        } else {
            hi = mid
        }
    }
    0.5 * (lo + hi)
}

impl Interval {
    /// The bias-corrected percentile interval (Efron 1987): the percentiles are moved by how
    /// far the replicates' median sits from the estimate, which matters here because a
    /// noise-corrected std (a square root of a difference of variances) is biased.
    fn new(value: f64, mut replicates: Vec<f64>) -> Interval {
        replicates.retain(|x| x.is_finite());
        replicates.sort_by(f64::total_cmp);
        let n = replicates.len().max(1) as f64;
        let below = replicates.iter().filter(|&&x| x < value).count() as f64;
        let equal = replicates.iter().filter(|&&x| x == value).count() as f64;
        let p0 = ((below + 0.5 * equal) / n).clamp(0.5 / n, 1.0 - 0.5 / n);
        let z0 = normal_quantile(p0);
        let z = normal_quantile(0.5 + 0.5 * CONFIDENCE);
        Interval {
            value,
            ci: [
                quantile(&replicates, normal_cdf(2.0 * z0 - z)),
                quantile(&replicates, normal_cdf(2.0 * z0 + z)),
            ],
        }
    }
    /// Whether the interval lies entirely above `x`.
    pub fn above(&self, x: f64) -> bool {
        self.ci[0] > x
    }
    /// Whether the interval excludes `x`.
    pub fn excludes(&self, x: f64) -> bool {
        self.ci[0] > x || self.ci[1] < x
    }
}

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
    pub std_corrected: f64,
    pub std_corrected_ci: [f64; 2],
    /// A far outlier among the scenario's rows (in practice: crosses the sun's glint).
    pub glint: bool,
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
    /// Band average of the noise-corrected std.
    pub std_corrected: Interval,
    /// Median over rows of the noise-corrected std.
    pub std_corrected_median_rows: f64,
    /// Elevations of the far-outlier rows, and the corrected band average without them.
    pub glint_rows_deg: Vec<f64>,
    pub std_corrected_without_glint: f64,
    /// Band averages of the noise-corrected std of the smooth azimuthal trend and of the
    /// residual detail.
    pub trend_std: Interval,
    pub residual_std: Interval,
    /// RMS noise of the pixel difference, band average.
    pub noise: f64,
    /// Measured over predicted variance summed over the band: about 1 where the scenario
    /// differs from the baseline by noise alone (the noise floor checks the noise model).
    pub variance_over_noise: Interval,
    /// The corrected std's interval lies above 0: the scenario differs from the baseline.
    pub significant: bool,
    pub rows: Vec<RowEstimate>,
}

/// A ratio of two scenarios' corrected band statistics, with its verdict.
#[derive(Clone, Debug, Serialize)]
pub struct RatioEstimate {
    /// Of the paper's plain statistic (noise included), for comparison.
    pub plain: f64,
    pub corrected: Interval,
    /// Whether the interval excludes 1.
    pub significant: bool,
    pub median_rows: f64,
    /// Over the rows that are not glint rows (the same rows for both scenarios).
    pub without_glint: Interval,
    pub trend: Interval,
    pub residual: Interval,
    /// When not significant: samples per pixel at which the interval would exclude 1 if the
    /// ratio stayed put; `None` when more samples alone cannot (the spread over azimuth
    /// dominates) or when it is significant already.
    pub spp_to_resolve: Option<u64>,
    /// Share of the ratio's bootstrap variance that is Monte Carlo noise at this spp.
    pub noise_share_of_variance: f64,
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
    pub replicates: usize,
    pub scenarios: Vec<ScenarioEstimate>,
}

/// Errors in what was asked.
#[derive(Debug, thiserror::Error)]
pub enum EstimateError {
    #[error("the error estimate needs at least 2 samples per pixel (got {0})")]
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

/// Per-row, per-block sums of every scenario: `[scenario][row][block]`.
struct Table {
    sums: Vec<Vec<Vec<Sums>>>,
    elevations: Vec<f64>,
    blocks: usize,
    trend_px: f64,
}

/// Circular moving average over `k` (odd) samples.
fn moving_average(v: &[f64], k: usize) -> Vec<f64> {
    let n = v.len();
    let h = (k / 2) as isize;
    let at = |i: isize| v[i.rem_euclid(n as isize) as usize];
    let mut s: f64 = (-h..=h).map(at).sum();
    let mut out = Vec::with_capacity(n);
    for i in 0..n as isize {
        out.push(s / k as f64);
        s += at(i + h + 1) - at(i - h);
    }
    out
}

/// One row of one scenario from the batch means: per pixel, the difference D (the weighted
/// mean of the batch differences), the per-sample variance s^2 of the difference (the
/// between-batch sum of squares over k - 1), and the difference of each half of the batches
/// (even, odd).
struct RowDiff {
    d: Vec<f64>,
    var_sample: Vec<f64>,
    half: [Vec<f64>; 2],
}

/// How much each batch difference weighs in a pixel's difference: its sample count when both
/// films split their samples alike (the difference is then the difference of the images);
/// equal weights when each film's batches hold equal counts (films of different spp, each a
/// multiple of the batch count); `None` otherwise.
fn batch_weights(scen: &Batches, base: &Batches) -> Option<Vec<f64>> {
    let uniform = |b: &Batches| b.spp.iter().all(|&c| c == b.spp[0] && c > 0);
    if scen.k != base.k {
        None
    } else if scen.spp == base.spp {
        Some(scen.spp.iter().map(|&c| c as f64).collect())
    } else if uniform(scen) && uniform(base) {
        Some(vec![1.0; scen.k])
    } else {
        None
    }
}

fn row_diff(scen: &Batches, base: &Batches, n_b: &[f64], y: usize, w: usize) -> RowDiff {
    let k = scen.k;
    let n: f64 = n_b.iter().sum();
    let half_n = |h: usize| (h..k).step_by(2).map(|b| n_b[b]).sum::<f64>();
    let hn = [half_n(0), half_n(1)];
    let mut out = RowDiff {
        d: Vec::with_capacity(w),
        var_sample: Vec::with_capacity(w),
        half: [Vec::with_capacity(w), Vec::with_capacity(w)],
    };
    let mut db = vec![0.0; k];
    for x in 0..w {
        let i = (y * w + x) * k;
        for (b, v) in db.iter_mut().enumerate() {
            *v = scen.luminance[i + b] as f64 - base.luminance[i + b] as f64;
        }
        let mean = (0..k).map(|b| n_b[b] * db[b]).sum::<f64>() / n;
        let ssb: f64 = (0..k).map(|b| n_b[b] * (db[b] - mean).powi(2)).sum();
        out.d.push(mean);
        out.var_sample.push(ssb / (k - 1) as f64);
        for (h, (half, &nh)) in out.half.iter_mut().zip(&hn).enumerate() {
            let sum: f64 = (h..k).step_by(2).map(|b| n_b[b] * db[b]).sum();
            half.push(sum / nh.max(1e-300));
        }
    }
    out
}

fn table(inp: &Inputs) -> Result<Table, EstimateError> {
    let base = inp.baseline;
    let bb = base.batches.as_ref().ok_or(EstimateError::NoBatches)?;
    if bb.k < 2 {
        return Err(EstimateError::TooFewSamples(base.spp));
    }
    let mut weights = Vec::new();
    for (_, f) in &inp.scenarios {
        let b = f.batches.as_ref().ok_or(EstimateError::NoBatches)?;
        if (f.image.width, f.image.height) != (base.image.width, base.image.height) {
            return Err(EstimateError::Mismatch);
        }
        weights.push(batch_weights(b, bb).ok_or(EstimateError::Mismatch)?);
    }
    let (top, bottom) = inp.rows_deg;
    let w = base.image.width;
    let rows: Vec<usize> = (0..base.image.height)
        .filter(|&y| {
            let e = inp.camera.row_elevation_deg(y);
            e <= top && e >= bottom
        })
        .collect();
    if rows.is_empty() {
        return Err(EstimateError::NoRows(top, bottom));
    }
    let block_px = ((BLOCK_DEG / 360.0 * w as f64).round() as usize).clamp(1, w);
    let blocks = w.div_ceil(block_px);
    let trend_px = ((TREND_DEG / 360.0 * w as f64).round() as usize).clamp(1, w) | 1;
    let sums = inp
        .scenarios
        .par_iter()
        .zip(&weights)
        .map(|((_, film), n_b)| {
            let fb = film.batches.as_ref().expect("checked above");
            let n: f64 = n_b.iter().sum();
            let half_n = |h: usize| (h..bb.k).step_by(2).map(|b| n_b[b]).sum::<f64>();
            let hn = [half_n(0), half_n(1)];
            rows.iter()
                .map(|&y| {
                    let r = row_diff(fb, bb, n_b, y, w);
                    let trend = moving_average(&r.d, trend_px);
                    let mut out = vec![Sums::default(); blocks];
                    for x in 0..w {
                        let (d, v, t) = (r.d[x], r.var_sample[x], trend[x]);
                        let s = &mut out[x / block_px];
                        s.n += 1.0;
                        s.d[0] += d;
                        s.d[1] += d * d;
                        s.d[2] += v / n;
                        for ((sh, rh), &nh) in s.half.iter_mut().zip(&r.half).zip(&hn) {
                            let dh = rh[x];
                            sh[0] += dh;
                            sh[1] += dh * dh;
                            sh[2] += v / nh.max(1e-300);
                        }
                        s.trend[0] += t;
                        s.trend[1] += t * t;
                        s.residual[0] += d - t;
                        s.residual[1] += (d - t) * (d - t);
                    }
                    out
                })
                .collect()
        })
        .collect();
    Ok(Table {
        sums,
        elevations: rows
            .iter()
            .map(|&y| inp.camera.row_elevation_deg(y))
            .collect(),
        blocks,
        trend_px: trend_px as f64,
    })
}

impl Table {
    /// Each scenario's rows, summed over the given block multiset.
    fn rows(&self, blocks: &[usize]) -> Vec<Vec<Sums>> {
        self.sums
            .iter()
            .map(|rows| {
                rows.iter()
                    .map(|row| {
                        let mut s = Sums::default();
                        for &b in blocks {
                            s += row[b];
                        }
                        s
                    })
                    .collect()
            })
            .collect()
    }

    /// The blocks of bootstrap replicate `r`, drawn with replacement; deterministic in `seed`.
    fn draw(&self, seed: u64, r: usize) -> Vec<usize> {
        let mut rng = Rng::keyed(&[seed, 0x626f_6f74, r as u64]);
        (0..self.blocks)
            .map(|_| ((rng.f64() * self.blocks as f64) as usize).min(self.blocks - 1))
            .collect()
    }
}

/// Row values from per-row sums.
fn values(sums: &[Vec<Sums>], which: Which, trend_px: f64) -> Vec<Vec<RowValue>> {
    sums.iter()
        .map(|rows| rows.iter().map(|s| row_value(s, which, trend_px)).collect())
        .collect()
}

/// The estimator over one set of films: the per-block moments are made once, and so are the
/// bootstrap replicates' per-row sums; every statistic is read from them.
pub struct Estimator {
    names: Vec<String>,
    spp: f64,
    elevations: Vec<f64>,
    blocks: usize,
    trend_px: f64,
    /// Per-row sums of every scenario: the point estimate, and each replicate's.
    point: Vec<Vec<Sums>>,
    replicates: Vec<Vec<Vec<Sums>>>,
    /// Which rows are glint rows (fixed by the point estimate, so "without glint" always
    /// leaves out the same rows).
    glint: Vec<Vec<bool>>,
}

impl Estimator {
    pub fn new(inp: &Inputs) -> Result<Estimator, EstimateError> {
        let table = table(inp)?;
        let all: Vec<usize> = (0..table.blocks).collect();
        let point = table.rows(&all);
        // The same rows for every scenario (a union), so their summaries compare like with like.
        let per_scenario: Vec<Vec<bool>> = values(&point, Which::Full, table.trend_px)
            .iter()
            .map(|rows| glint_rows(rows))
            .collect();
        let union: Vec<bool> = (0..table.elevations.len())
            .map(|i| per_scenario.iter().any(|g| g[i]))
            .collect();
        let glint = vec![union; per_scenario.len()];
        let replicates = (0..REPLICATES)
            .into_par_iter()
            .map(|r| table.rows(&table.draw(inp.seed, r)))
            .collect();
        Ok(Estimator {
            names: inp.scenarios.iter().map(|(n, _)| n.clone()).collect(),
            spp: inp.baseline.spp as f64,
            elevations: table.elevations.clone(),
            blocks: table.blocks,
            trend_px: table.trend_px,
            point,
            replicates,
            glint,
        })
    }

    /// Band values of every scenario.
    fn bands(&self, rows: &[Vec<RowValue>]) -> Vec<BandValue> {
        rows.iter()
            .zip(&self.glint)
            .map(|(r, g)| band(r, g))
            .collect()
    }

    /// Every scenario against the baseline.
    pub fn scenarios(&self) -> Estimates {
        let point = values(&self.point, Which::Full, self.trend_px);
        let reps: Vec<(Vec<Vec<RowValue>>, Vec<BandValue>)> = self
            .replicates
            .par_iter()
            .map(|sums| {
                let rows = values(sums, Which::Full, self.trend_px);
                let bands = self.bands(&rows);
                (rows, bands)
            })
            .collect();
        let point_bands = self.bands(&point);
        let scenarios = self
            .names
            .iter()
            .enumerate()
            .map(|(k, name)| {
                let b = point_bands[k];
                let rep = |f: fn(&BandValue) -> f64| reps.iter().map(|r| f(&r.1[k])).collect();
                let std_corrected = Interval::new(b.std_corrected, rep(|v| v.std_corrected));
                let rows = point[k]
                    .iter()
                    .enumerate()
                    .map(|(i, r)| RowEstimate {
                        elevation_deg: self.elevations[i],
                        mean: r.mean,
                        std: r.std,
                        noise: r.noise,
                        std_corrected: r.std_corrected,
                        std_corrected_ci: Interval::new(
                            r.std_corrected,
                            reps.iter().map(|x| x.0[k][i].std_corrected).collect(),
                        )
                        .ci,
                        glint: self.glint[k][i],
                        trend_std: r.trend,
                        residual_std: r.residual,
                    })
                    .collect();
                ScenarioEstimate {
                    name: name.clone(),
                    mean: Interval::new(b.mean, rep(|v| v.mean)),
                    std: b.std,
                    std_corrected,
                    std_corrected_median_rows: b.median_corrected,
                    glint_rows_deg: self
                        .elevations
                        .iter()
                        .zip(&self.glint[k])
                        .filter(|(_, g)| **g)
                        .map(|(e, _)| *e)
                        .collect(),
                    std_corrected_without_glint: b.without_glint,
                    trend_std: Interval::new(b.trend, rep(|v| v.trend)),
                    residual_std: Interval::new(b.residual, rep(|v| v.residual)),
                    noise: mean(point[k].iter().map(|r| r.noise)),
                    variance_over_noise: Interval::new(
                        b.variance_over_noise,
                        rep(|v| v.variance_over_noise),
                    ),
                    significant: std_corrected.above(0.0),
                    rows,
                }
            })
            .collect();
        Estimates {
            rows: self.elevations.len(),
            block_deg: BLOCK_DEG,
            blocks: self.blocks,
            replicates: REPLICATES,
            scenarios,
        }
    }

    /// The ratio of scenario `num`'s corrected band std to scenario `den`'s (indices into the
    /// inputs' scenarios), with its interval and, when that does not exclude 1, the samples
    /// per pixel that would resolve it.
    pub fn ratio(&self, num: usize, den: usize) -> RatioEstimate {
        let p = self.bands(&values(&self.point, Which::Full, self.trend_px));
        let div = |b: &[BandValue], f: fn(&BandValue) -> f64| f(&b[num]) / f(&b[den]);
        let reps: Vec<[f64; 6]> = self
            .replicates
            .par_iter()
            .map(|sums| {
                let b = self.bands(&values(sums, Which::Full, self.trend_px));
                let h0 = self.bands(&values(sums, Which::Half(0), self.trend_px));
                let h1 = self.bands(&values(sums, Which::Half(1), self.trend_px));
                [
                    div(&b, |v| v.std_corrected),
                    div(&b, |v| v.trend),
                    div(&b, |v| v.residual),
                    div(&h0, |v| v.std_corrected),
                    div(&h1, |v| v.std_corrected),
                    div(&b, |v| v.without_glint),
                ]
            })
            .collect();
        let col = |i: usize| reps.iter().map(|r| r[i]).collect::<Vec<f64>>();
        let value = div(&p, |v| v.std_corrected);
        let corrected = Interval::new(value, col(0));
        let significant = corrected.excludes(1.0);
        // Bootstrap variance = S (spread over azimuth) + N / spp (noise); each half, at
        // spp / 2, sees S + 2 N / spp.
        let v_full = spread(&col(0)).powi(2);
        let v_half = 0.5 * (spread(&col(3)).powi(2) + spread(&col(4)).powi(2));
        let noise_term = (v_half - v_full).max(0.0);
        let s_term = (v_full - noise_term).max(0.0);
        let z = normal_quantile(0.5 + 0.5 * CONFIDENCE);
        let spp_to_resolve = if significant || noise_term <= 0.0 {
            None
        } else {
            let room = ((value - 1.0).abs() / z).powi(2) - s_term;
            (room > 0.0).then(|| (self.spp * noise_term / room).ceil() as u64)
        };
        RatioEstimate {
            plain: div(&p, |v| v.std),
            corrected,
            significant,
            median_rows: div(&p, |v| v.median_corrected),
            without_glint: Interval::new(div(&p, |v| v.without_glint), col(5)),
            trend: Interval::new(div(&p, |v| v.trend), col(1)),
            residual: Interval::new(div(&p, |v| v.residual), col(2)),
            spp_to_resolve,
            noise_share_of_variance: if v_full > 0.0 {
                (noise_term / v_full).min(1.0)
            } else {
                0.0
            },
        }
    }
}

impl Estimator {
    /// Root-mean-square difference of scenario `k` from the baseline over every analysed
    /// pixel (mean difference included), noise-corrected, over `scale` (e.g. the baseline's
    /// mean luminance, for a relative error), with its interval.
    pub fn rms_difference(&self, k: usize, scale: f64) -> Interval {
        let rms = |rows: &[Sums]| {
            let (mut sq, mut px) = (0.0, 0.0);
            for s in rows {
                // Sum of D^2 less the noise variances: an unbiased sum of squared true differences.
                sq += s.d[1] - s.d[2];
                px += s.n;
            }
            (sq / px.max(1.0)).max(0.0).sqrt() / scale
        };
        Interval::new(
            rms(&self.point[k]),
            self.replicates.iter().map(|r| rms(&r[k])).collect(),
        )
    }
}

/// Standard deviation of bootstrap replicates.
fn spread(v: &[f64]) -> f64 {
    let v: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    let m = mean(v.iter().copied());
    mean(v.iter().map(|x| (x - m).powi(2))).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moving_average_is_circular_and_keeps_the_mean() {
        let v: Vec<f64> = (0..10).map(|i| i as f64).collect();
        let m = moving_average(&v, 3);
        assert!((m[0] - (9.0 + 0.0 + 1.0) / 3.0).abs() < 1e-12);
        assert!((m[5] - 5.0).abs() < 1e-12);
        assert!((m.iter().sum::<f64>() - v.iter().sum::<f64>()).abs() < 1e-9);
    }

    #[test]
    fn normal_cdf_and_quantile() {
        assert!((normal_cdf(1.959_964) - 0.975).abs() < 1e-6);
        assert!((normal_cdf(0.0) - 0.5).abs() < 1e-9);
        assert!((normal_quantile(0.975) - 1.959_964).abs() < 1e-4);
        assert!((normal_quantile(0.1) + 1.281_552).abs() < 1e-4);
    }

    #[test]
    fn quantiles_and_fences() {
        let s = [1.0, 2.0, 3.0, 4.0];
        assert_eq!(quantile(&s, 0.0), 1.0);
        assert_eq!(quantile(&s, 1.0), 4.0);
        assert!((quantile(&s, 0.5) - 2.5).abs() < 1e-12);
        let row = |std: f64, noise: f64| RowValue {
            std,
            noise,
            ..RowValue::default()
        };
        let g = glint_rows(&[1.0, 1.1, 0.9, 1.05, 0.95, 8.0].map(|s| row(s, 0.1)));
        assert_eq!(g, [false, false, false, false, false, true]);
        // Half the rows hold the glint: the fence misses them, their noise does not.
        let g =
            glint_rows(&[(0.1, 0.01), (2.0, 2.0), (0.1, 0.01), (2.5, 2.4)].map(|(s, n)| row(s, n)));
        assert_eq!(g, [false, true, false, true]);
        assert_eq!(median(vec![3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(vec![4.0, 1.0, 2.0, 3.0]), 2.5);
        assert!(median(Vec::new()).is_nan());
    }

    use crate::config::Projection;
    use crate::image_io::RgbImage;

    fn gauss(r: &mut Rng) -> f64 {
        let (u1, u2) = (r.f64().max(1e-300), r.f64());
        (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
    }

    /// A film from per-pixel batch luminances (`batches[pixel][b]`, one sample each).
    const K: usize = 8;

    fn film_of(batches: Vec<[f64; K]>, w: usize, h: usize) -> Film {
        let full: Vec<f32> = batches
            .iter()
            .map(|b| (b.iter().sum::<f64>() / K as f64) as f32)
            .collect();
        Film {
            image: RgbImage {
                width: w,
                height: h,
                pixels: full.iter().map(|&x| [x; 3]).collect(),
            },
            var_y: vec![0.0; w * h],
            spp: K as u32,
            batches: Some(Batches {
                k: K,
                spp: vec![1; K],
                luminance: batches.iter().flatten().map(|&x| x as f32).collect(),
            }),
        }
    }

    /// A baseline and a scenario whose difference is a random field of std `sigma_true` plus
    /// Monte Carlo noise: each batch (one sample) of the baseline carries noise of std `noise`,
    /// and the scenario, rendered "with the same seeds", carries the same noise plus an
    /// independent part of std `own` (so per-image variances would overstate the difference's
    /// noise). The pixel difference's noise is `own / sqrt(8)`.
    fn synthetic(seed: u64, sigma_true: f64, noise: f64, own: f64) -> (Camera, Film, Film) {
        let cam = Camera::new(
            Projection::Equirect {
                band_deg: Some((1.0, -6.0)),
            },
            1024,
            2.0,
        );
        let (w, h) = (cam.width, cam.height);
        let mut r = Rng::keyed(&[seed]);
        let mut base = vec![[0.0; K]; w * h];
        let mut scen = vec![[0.0; K]; w * h];
        for i in 0..w * h {
            let truth = sigma_true * gauss(&mut r);
            for k in 0..K {
                let shared = 1.0 + noise * gauss(&mut r);
                base[i][k] = shared;
                scen[i][k] = shared + truth + own * gauss(&mut r);
            }
        }
        (cam, film_of(base, w, h), film_of(scen, w, h))
    }

    fn estimate_one(cam: &Camera, base: &Film, scen: &Film, seed: u64) -> ScenarioEstimate {
        let inp = Inputs {
            camera: cam,
            baseline: base,
            scenarios: vec![("s".into(), scen)],
            rows_deg: (0.0, -5.0),
            seed,
        };
        Estimator::new(&inp)
            .unwrap()
            .scenarios()
            .scenarios
            .remove(0)
    }

    #[test]
    fn known_difference_is_recovered_under_known_noise() {
        // Difference noise per pixel: own / sqrt(8) = 0.212 against a true std of 0.1; the
        // shared noise (0.5) must not count.
        let (cam, base, scen) = synthetic(1, 0.1, 0.5, 0.6);
        let e = estimate_one(&cam, &base, &scen, 1);
        // 1024 px: 0.35 degree rows, 14 of them between 0 and -5 degrees.
        assert_eq!(e.rows.len(), 14);
        let noise = 0.6 / 8f64.sqrt();
        assert!((e.noise / noise - 1.0).abs() < 0.03, "noise {}", e.noise);
        assert!(
            (e.std - (0.01f64 + noise * noise).sqrt()).abs() < 0.01,
            "plain {}",
            e.std
        );
        let c = e.std_corrected;
        assert!(c.ci[0] <= 0.1 && 0.1 <= c.ci[1], "{c:?}");
        assert!((c.value - 0.1).abs() < 0.01, "{c:?}");
        assert!(e.significant);
        // Measured over predicted variance: (0.1^2 + noise^2) / noise^2.
        let want = (0.01 + noise * noise) / (noise * noise);
        assert!((e.variance_over_noise.value / want - 1.0).abs() < 0.05);
        // With no true difference the corrected std's interval reaches down to about 0 and the
        // variance ratio to 1.
        let (cam, base, scen) = synthetic(2, 0.0, 0.5, 0.6);
        let e = estimate_one(&cam, &base, &scen, 2);
        assert!(e.std_corrected.value < 0.03, "{:?}", e.std_corrected);
        assert!(e.variance_over_noise.ci[0] < 1.0 && e.variance_over_noise.ci[1] > 1.0);
    }

    #[test]
    fn intervals_cover_the_truth_about_95_percent_of_the_time() {
        let trials = 100;
        let covered = (0..trials)
            .filter(|&k| {
                let (cam, base, scen) = synthetic(100 + k, 0.05, 0.2, 0.3);
                let c = estimate_one(&cam, &base, &scen, k).std_corrected;
                c.ci[0] <= 0.05 && 0.05 <= c.ci[1]
            })
            .count();
        // Binomial: 95 +- 2.2 expected; outside 88..=100 the intervals are wrong. (Measured
        // over 200 trials: 194, 97 %; with two halves instead of 8 batches and plain
        // percentile intervals, 85 of these 100.)
        assert!(
            (88..=100).contains(&covered),
            "{covered} of {trials} covered"
        );
    }

    #[test]
    fn ratio_of_two_known_differences() {
        let (cam, base, a) = synthetic(7, 0.2, 0.3, 0.2);
        let (_, _, b) = synthetic(8, 0.1, 0.3, 0.2);
        let inp = Inputs {
            camera: &cam,
            baseline: &base,
            scenarios: vec![("a".into(), &a), ("b".into(), &b)],
            rows_deg: (0.0, -5.0),
            seed: 3,
        };
        let r = Estimator::new(&inp).unwrap().ratio(0, 1);
        assert!(
            r.corrected.ci[0] <= 2.0 && 2.0 <= r.corrected.ci[1],
            "{r:?}"
        );
        assert!(r.significant && r.spp_to_resolve.is_none());
    }
}
