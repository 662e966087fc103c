//! Confidence intervals from bootstrap replicates: the bias-corrected percentile interval
//! (Efron 1987), and the order statistics and normal quantiles it needs.

use serde::Serialize;

/// Two-sided confidence level of every interval.
pub const CONFIDENCE: f64 = 0.95;

/// A value and its 95 % interval.
#[derive(Clone, Copy, Debug, Serialize, PartialEq)]
pub struct Interval {
    pub value: f64,
    pub ci: [f64; 2],
}

/// Standard normal CDF (Abramowitz & Stegun 7.1.26 for erf, |error| < 1.5e-7).
pub(crate) fn normal_cdf(z: f64) -> f64 {
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
pub(crate) fn normal_quantile(p: f64) -> f64 {
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

/// The p-quantile (0..=1) of sorted values, linear between order statistics; an infinite
/// neighbour is taken as it is (a ratio whose denominator fell below its noise is +inf).
pub(crate) fn quantile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let x = p.clamp(0.0, 1.0) * (sorted.len() - 1) as f64;
    let (i, f) = (x.floor() as usize, x - x.floor());
    let j = (i + 1).min(sorted.len() - 1);
    let (a, b) = (sorted[i], sorted[j]);
    if f == 0.0 || a == b {
        a
    } else if a.is_infinite() || b.is_infinite() {
        if f < 0.5 { a } else { b }
    } else {
        a * (1.0 - f) + b * f
    }
}

impl Interval {
    /// The bias-corrected percentile interval of `value` from its bootstrap `replicates`: the
    /// percentiles are moved by how far the replicates' median sits from the estimate (a
    /// ratio, or a square root of a variance, is skewed at low sample counts). `inflate`
    /// scales each replicate's distance from the estimate first (see
    /// `super::bootstrap::inflation`). NaN replicates are dropped; infinite ones are kept.
    pub fn new(value: f64, replicates: impl IntoIterator<Item = f64>, inflate: f64) -> Interval {
        let mut reps: Vec<f64> = replicates
            .into_iter()
            .filter(|x| !x.is_nan())
            .map(|x| {
                if value.is_finite() && x.is_finite() {
                    value + (x - value) * inflate
                } else {
                    x
                }
            })
            .collect();
        if reps.is_empty() {
            return Interval {
                value,
                ci: [f64::NAN; 2],
            };
        }
        reps.sort_by(f64::total_cmp);
        let n = reps.len() as f64;
        let below = reps.iter().filter(|&&x| x < value).count() as f64;
        let equal = reps.iter().filter(|&&x| x == value).count() as f64;
        let p0 = ((below + 0.5 * equal) / n).clamp(0.5 / n, 1.0 - 0.5 / n);
        let z0 = normal_quantile(p0);
        let z = normal_quantile(0.5 + 0.5 * CONFIDENCE);
        Interval {
            value,
            ci: [
                quantile(&reps, normal_cdf(2.0 * z0 - z)),
                quantile(&reps, normal_cdf(2.0 * z0 + z)),
            ],
        }
    }

    /// The same interval under a monotone map (e.g. a variance's interval as a std's).
    pub fn map(self, f: impl Fn(f64) -> f64) -> Interval {
        Interval {
            value: f(self.value),
            ci: self.ci.map(f),
        }
    }

    /// The interval with its ends held at or above `floor` (a ratio of stds is never below 0,
    /// but a bootstrap interval widened about its estimate can reach there).
    pub fn at_least(self, floor: f64) -> Interval {
        Interval {
            value: self.value,
            ci: self.ci.map(|c| c.max(floor)),
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

    /// Whether `x` lies inside the interval.
    pub fn contains(&self, x: f64) -> bool {
        self.ci[0] <= x && x <= self.ci[1]
    }
}

/// A std from a variance estimate that may be negative (noise larger than the signal): 0 then.
pub(crate) fn root(variance: f64) -> f64 {
    variance.max(0.0).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_cdf_and_quantile() {
        assert!((normal_cdf(1.959_964) - 0.975).abs() < 1e-6);
        assert!((normal_cdf(0.0) - 0.5).abs() < 1e-9);
        assert!((normal_quantile(0.975) - 1.959_964).abs() < 1e-4);
        assert!((normal_quantile(0.1) + 1.281_552).abs() < 1e-4);
    }

    #[test]
    fn quantiles_medians_and_infinite_replicates() {
        let s = [1.0, 2.0, 3.0, 4.0];
        assert_eq!(quantile(&s, 0.0), 1.0);
        assert_eq!(quantile(&s, 1.0), 4.0);
        assert!((quantile(&s, 0.5) - 2.5).abs() < 1e-12);
        assert_eq!(quantile(&[1.0, f64::INFINITY], 0.75), f64::INFINITY);
        assert_eq!(quantile(&[1.0, f64::INFINITY], 0.25), 1.0);
        assert_eq!(median(vec![3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(vec![4.0, 1.0, 2.0, 3.0]), 2.5);
        assert!(median(Vec::new()).is_nan());
        // A tenth of the replicates infinite: the upper bound is infinite, the lower is not.
        let reps = (0..100).map(|i| {
            if i % 10 == 0 {
                f64::INFINITY
            } else {
                1.0 + i as f64 / 100.0
            }
        });
        let iv = Interval::new(1.5, reps, 1.0);
        assert!(iv.ci[0].is_finite() && iv.ci[1].is_infinite(), "{iv:?}");
    }

    #[test]
    fn inflation_widens_about_the_estimate() {
        let reps: Vec<f64> = (0..1000).map(|i| i as f64 / 999.0).collect();
        let a = Interval::new(0.5, reps.clone(), 1.0);
        let b = Interval::new(0.5, reps, 2.0);
        assert!((b.ci[1] - 0.5) > 1.9 * (a.ci[1] - 0.5));
        assert!((0.5 - b.ci[0]) > 1.9 * (0.5 - a.ci[0]));
    }
}
