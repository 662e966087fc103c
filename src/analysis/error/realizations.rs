//! Figures pooled over ocean realizations. One comparison's interval holds the converged value
//! of one image: one sea, drawn once from its spectrum. A sea state's figure is a mean over its
//! realizations, and its interval must hold the spread between them as well.
//!
//! Each realization gives its own ratio r_i (with its sample noise) and band variances. The
//! pooled ratio is the geometric mean of the r_i, its interval Student's t on N - 1 degrees of
//! freedom around the mean of ln r_i: a ratio's noise is about as large either way in log terms
//! (the ratio inverted reads the same), and the scatter of the r_i over seas holds both the
//! differences between seas and each one's sample noise. (The ratio of the mean variances was
//! tried first: seas differ so much in how much glint they carry that with four of them the mean
//! variance of the denominator was not resolved from 0, and its interval was unbounded where
//! every sea's own ratio lay between 1.2 and 2.)

use super::interval::{CONFIDENCE, Interval, normal_quantile, root};

/// Student's t quantile, two-sided at [`CONFIDENCE`], for `df` degrees of freedom: exact for
/// 1 and 2, Cornish-Fisher to the fourth order beyond (Abramowitz & Stegun 26.7.5; within 0.2 %
/// of the tables from 3 on).
pub fn t_quantile(df: usize) -> f64 {
    let p = 0.5 + 0.5 * CONFIDENCE;
    match df {
        0 => f64::INFINITY,
        1 => (std::f64::consts::PI * (p - 0.5)).tan(),
        2 => (2.0 * p - 1.0) / (2.0 * p * (1.0 - p)).sqrt(),
        _ => {
            let (z, n) = (normal_quantile(p), df as f64);
            let g1 = (z.powi(3) + z) / 4.0;
            let g2 = (5.0 * z.powi(5) + 16.0 * z.powi(3) + 3.0 * z) / 96.0;
            let g3 = (3.0 * z.powi(7) + 19.0 * z.powi(5) + 17.0 * z.powi(3) - 15.0 * z) / 384.0;
            let g4 = (79.0 * z.powi(9) + 776.0 * z.powi(7) + 1482.0 * z.powi(5)
                - 1920.0 * z.powi(3)
                - 945.0 * z)
                / 92160.0;
            z + g1 / n + g2 / n.powi(2) + g3 / n.powi(3) + g4 / n.powi(4)
        }
    }
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len() as f64
}

/// Sample variance (N - 1 in the denominator).
fn variance(v: &[f64]) -> f64 {
    let m = mean(v);
    v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64
}

/// The mean of `values` (one per realization) with its t interval. A single value has an
/// unbounded interval: one sea says nothing of the spread between seas.
pub fn pooled_mean(values: &[f64]) -> Interval {
    let n = values.len();
    let m = mean(values);
    if n < 2 {
        return Interval {
            value: m,
            ci: [f64::NEG_INFINITY, f64::INFINITY],
        };
    }
    let half = t_quantile(n - 1) * (variance(values) / n as f64).sqrt();
    Interval {
        value: m,
        ci: [m - half, m + half],
    }
}

/// A pooled band std: the root of the mean band variance, its interval the roots of the
/// mean's (a bound below 0 reads as 0).
pub fn pooled_std(variances: &[f64]) -> Interval {
    pooled_mean(variances).map(root)
}

/// The geometric mean of per-realization ratios, with the t interval of their logs mapped
/// back. A ratio that is infinite (its denominator not resolved from its noise) or 0 leaves
/// nothing to average in logs: the pool is then unbounded, [0, inf], about the median ratio.
/// A NaN ratio (nothing measured) makes the pool NaN.
pub fn pooled_ratio(ratios: &[f64]) -> Interval {
    if ratios.iter().any(|r| r.is_nan()) {
        return Interval {
            value: f64::NAN,
            ci: [f64::NAN; 2],
        };
    }
    let logs: Vec<f64> = ratios.iter().map(|&r| r.max(0.0).ln()).collect();
    if logs.iter().all(|l| l.is_finite()) {
        pooled_mean(&logs).map(f64::exp)
    } else {
        let mut sorted = ratios.to_vec();
        sorted.sort_by(f64::total_cmp);
        Interval {
            value: super::quantile(&sorted, 0.5),
            ci: [0.0, f64::INFINITY],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    #[test]
    fn t_quantiles_match_the_tables() {
        for (df, t) in [
            (1, 12.706),
            (2, 4.303),
            (3, 3.182),
            (4, 2.776),
            (5, 2.571),
            (7, 2.365),
            (10, 2.228),
            (30, 2.042),
            (1000, 1.962),
        ] {
            assert!(
                (t_quantile(df) / t - 1.0).abs() < 2e-3,
                "{df}: {}",
                t_quantile(df)
            );
        }
    }

    #[test]
    fn a_pooled_mean_holds_the_truth_95_times_in_100() {
        let mut rng = Rng::keyed(&[5]);
        let trials = 4000;
        let covered = (0..trials)
            .filter(|_| {
                let v: Vec<f64> = (0..4).map(|_| 2.0 + rng.gauss()).collect();
                pooled_mean(&v).contains(2.0)
            })
            .count();
        let share = covered as f64 / trials as f64;
        assert!((share - 0.95).abs() < 0.015, "{share}");
    }

    /// Per-realization ratios spread log-normally about a known geometric mean, as those of
    /// four seas: the interval covers it at its nominal rate. (With four, it always spans their
    /// range, since no log lies further than 1.5 s from their mean and t_3 s / 2 is 1.59 s.)
    #[test]
    fn a_pooled_ratio_holds_the_geometric_mean_at_its_nominal_rate() {
        let mut rng = Rng::keyed(&[9]);
        let (trials, rho) = (4000, 1.8_f64);
        let covered = (0..trials)
            .filter(|_| {
                let r: Vec<f64> = (0..4).map(|_| rho * (0.3 * rng.gauss()).exp()).collect();
                pooled_ratio(&r).contains(rho)
            })
            .count();
        let share = covered as f64 / trials as f64;
        assert!((share - 0.95).abs() < 0.015, "{share}");
    }

    #[test]
    fn an_unresolved_ratio_leaves_the_pool_unbounded() {
        let p = pooled_ratio(&[1.5, f64::INFINITY, 1.2, 1.4]);
        assert_eq!((p.value, p.ci), (1.45, [0.0, f64::INFINITY]));
        let p = pooled_ratio(&[0.0, f64::INFINITY, 1.2]);
        assert_eq!((p.value, p.ci), (1.2, [0.0, f64::INFINITY]));
        assert!(pooled_ratio(&[1.5, f64::NAN]).value.is_nan());
        // One realization: nothing known of the spread between seas.
        let p = pooled_ratio(&[2.0]);
        assert!(
            (p.value - 2.0).abs() < 1e-12 && p.ci == [0.0, f64::INFINITY],
            "{p:?}"
        );
        // Resolved: bounded, about the geometric mean.
        let p = pooled_ratio(&[1.0, 4.0]);
        assert!(
            (p.value - 2.0).abs() < 1e-12 && p.ci[1].is_finite(),
            "{p:?}"
        );
    }

    #[test]
    fn identical_realizations_give_a_point() {
        let r = pooled_ratio(&[2.0, 2.0, 2.0]);
        assert_eq!((r.value, r.ci), (2.0, [2.0, 2.0]));
        let s = pooled_std(&[4.0, 4.0]);
        assert_eq!((s.value, s.ci), (2.0, [2.0, 2.0]));
    }
}
