//! `compare --realizations N`: the comparison over N ocean realizations of one sea state (ocean
//! seeds `render.ocean_seed`, +1, ...), each a whole comparison in its own folder, pooled into
//! one figure whose interval holds the spread between seas as well as the sample noise (see
//! `crate::analysis::error::realizations`).

use std::fmt;
use std::path::PathBuf;
use std::time::Instant;

use serde::Serialize;

use super::report::{num, ratio};
use super::{CompareJob, CompareSummary};
use crate::analysis::error::Interval;
use crate::analysis::error::realizations::{pooled_ratio, pooled_std};
use crate::app::AppError;
use crate::image_io::write_json;

/// One realization's figures (its whole summary is in its folder).
#[derive(Clone, Debug, Serialize)]
pub struct Realization {
    pub ocean_seed: u64,
    /// Its corrected improvement ratio and the interval of this one image.
    pub improvement_ratio: Interval,
    pub improvement_significant: bool,
    /// Corrected band variances: what the pooled stds average.
    pub variance_corrected: Variances,
    pub summary: PathBuf,
}

/// One realization's corrected band variance of each scenario against the baseline.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Variances {
    pub high_unmapped: f64,
    pub low_mapped: f64,
    pub low_unmapped: f64,
    pub noise_floor: f64,
    /// With `--filtered`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub low_filtered: Option<f64>,
    /// With `--exact`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub low_exact: Option<f64>,
    /// With `--exact --filtered`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub low_exact_filtered: Option<f64>,
}

/// `summary.json` of a comparison over realizations. JSON has no infinity: an unbounded
/// interval end is null.
#[derive(Clone, Debug, Serialize)]
pub struct RealizationsSummary {
    pub commit: &'static str,
    /// Per ocean seed.
    pub realizations: Vec<Realization>,
    /// The geometric mean of the realizations' corrected ratios (low unmapped / low mapped),
    /// with a 95 % interval (Student's t on N - 1 degrees of freedom, in logs): it is meant to
    /// cover the sea state's ratio at this camera and sky, the differences between seas and
    /// each one's sample noise both inside.
    pub improvement_ratio_corrected: f64,
    pub improvement_ratio_ci: [f64; 2],
    /// The interval excludes 1.
    pub improvement_significant: bool,
    /// The per-seed ratios' smallest, quartiles and largest.
    pub improvement_ratio_spread: [f64; 5],
    /// Root of the mean band variance over realizations, with the roots of its t interval (not
    /// the ratio's pool: the ratio of these two stds weights the seas by how much they differ,
    /// the pooled ratio weights them alike).
    pub std_high_unmapped_corrected: Interval,
    pub std_low_mapped_corrected: Interval,
    pub std_low_unmapped_corrected: Interval,
    pub std_noise_floor_corrected: Interval,
    /// With `--filtered`: the low tessellation with filtered normals, pooled the same way.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub std_low_filtered_corrected: Option<Interval>,
    /// With `--exact`: the exact surface in the low tessellation, pooled the same way.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub std_low_exact_corrected: Option<Interval>,
    /// With `--exact --filtered`: the exact surface with filtered normals, pooled the same way.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub std_low_exact_filtered_corrected: Option<Interval>,
    pub rows_deg: (f64, f64),
    pub spp: u32,
    pub seconds_total: f64,
}

/// Runs the comparison for `n` ocean seeds from the scene's, each into `job.out/ocean-seed-S`,
/// and pools them into `job.out/summary.json`.
pub fn run(job: &CompareJob, n: usize) -> Result<RealizationsSummary, AppError> {
    if n < 2 {
        return Err(AppError::input(format!(
            "pooling realizations needs at least 2 (--realizations {n}); one is a plain comparison"
        )));
    }
    if job.against == super::Against::Truth {
        return Err(AppError::input(
            "--against truth and --truth-from measure one sea against its truth; --realizations \
             pools several seas, and does not pool figures against a truth: run one comparison \
             per ocean seed (render.ocean_seed) instead",
        ));
    }
    super::check(job)?;
    let t = Instant::now();
    let first = job.scene.render.ocean_seed;
    let mut runs: Vec<(u64, CompareSummary)> = Vec::with_capacity(n);
    for i in 0..n as u64 {
        let seed = first.wrapping_add(i);
        if job.progress {
            eprintln!("compare: realization {} of {n} (ocean seed {seed})", i + 1);
        }
        // The sample seed stays: common random numbers across the seas. Each ratio's own
        // sample noise is then shared in part between them, which the spread between seas could
        // understate; at the spp a comparison needs it is far below that spread.
        let mut one = job.clone();
        one.scene.render.ocean_seed = seed;
        one.out = job.out.join(format!("ocean-seed-{seed}"));
        runs.push((seed, super::run(&one)?));
    }
    let summary = pool(job, runs, t.elapsed().as_secs_f64());
    write_json(&job.out.join("summary.json"), &summary)?;
    Ok(summary)
}

/// The pooled figures of finished comparisons.
fn pool(job: &CompareJob, runs: Vec<(u64, CompareSummary)>, seconds: f64) -> RealizationsSummary {
    let realizations: Vec<Realization> = runs
        .iter()
        .map(|(seed, s)| {
            let e = &s.estimates.scenarios;
            let v = |i: usize| e[i].variance_corrected.value;
            let named = |sc: super::Scenario| {
                e.iter()
                    .find(|f| f.name == sc.name())
                    .map(|f| f.variance_corrected.value)
            };
            Realization {
                ocean_seed: *seed,
                improvement_ratio: s.improvement.corrected,
                improvement_significant: s.improvement.significant,
                variance_corrected: Variances {
                    high_unmapped: v(0),
                    low_mapped: v(1),
                    low_unmapped: v(2),
                    noise_floor: v(3),
                    low_filtered: named(super::Scenario::LowFiltered),
                    low_exact: named(super::Scenario::LowExact),
                    low_exact_filtered: named(super::Scenario::LowExactFiltered),
                },
                summary: job
                    .out
                    .join(format!("ocean-seed-{seed}"))
                    .join("summary.json"),
            }
        })
        .collect();
    let column = |f: fn(&Variances) -> f64| -> Vec<f64> {
        realizations
            .iter()
            .map(|r| f(&r.variance_corrected))
            .collect()
    };
    let optional = |f: fn(&Variances) -> Option<f64>| {
        realizations
            .iter()
            .map(|r| f(&r.variance_corrected))
            .collect::<Option<Vec<f64>>>()
            .map(|v| pooled_std(&v))
    };
    let mut each: Vec<f64> = realizations
        .iter()
        .map(|r| r.improvement_ratio.value)
        .collect();
    let ratio = pooled_ratio(&each);
    each.sort_by(f64::total_cmp);
    let q = |p: f64| crate::analysis::error::quantile(&each, p);
    RealizationsSummary {
        commit: crate::app::commit(),
        improvement_ratio_corrected: ratio.value,
        improvement_ratio_ci: ratio.ci,
        improvement_significant: ratio.excludes(1.0),
        improvement_ratio_spread: [q(0.0), q(0.25), q(0.5), q(0.75), q(1.0)],
        std_high_unmapped_corrected: pooled_std(&column(|v| v.high_unmapped)),
        std_low_mapped_corrected: pooled_std(&column(|v| v.low_mapped)),
        std_low_unmapped_corrected: pooled_std(&column(|v| v.low_unmapped)),
        std_noise_floor_corrected: pooled_std(&column(|v| v.noise_floor)),
        std_low_filtered_corrected: optional(|v| v.low_filtered),
        std_low_exact_corrected: optional(|v| v.low_exact),
        std_low_exact_filtered_corrected: optional(|v| v.low_exact_filtered),
        realizations,
        rows_deg: job.rows_deg,
        spp: job.scene.render.spp,
        seconds_total: seconds,
    }
}

impl fmt::Display for RealizationsSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let std = |i: &Interval| format!("{:.5} [{:.5}, {:.5}]", i.value, i.ci[0], i.ci[1]);
        writeln!(
            f,
            "compare over {} ocean realizations: rows {} to {} degrees at {} spp",
            self.realizations.len(),
            self.rows_deg.0,
            self.rows_deg.1,
            self.spp
        )?;
        for r in &self.realizations {
            writeln!(
                f,
                "  ocean seed {:<4} improvement ratio {}{}",
                r.ocean_seed,
                ratio(&r.improvement_ratio),
                if r.improvement_significant {
                    ""
                } else {
                    "  (not significant)"
                }
            )?;
        }
        writeln!(
            f,
            "  noise-corrected band std, root of the mean variance over realizations [95% interval]: high unmapped {}, low mapped {}, low unmapped {}, noise floor {}",
            std(&self.std_high_unmapped_corrected),
            std(&self.std_low_mapped_corrected),
            std(&self.std_low_unmapped_corrected),
            std(&self.std_noise_floor_corrected)
        )?;
        if let Some(filtered) = &self.std_low_filtered_corrected {
            writeln!(f, "  low filtered {}", std(filtered))?;
        }
        if let Some(exact) = &self.std_low_exact_corrected {
            writeln!(f, "  low exact {}", std(exact))?;
        }
        if let Some(exact) = &self.std_low_exact_filtered_corrected {
            writeln!(f, "  low exact filtered {}", std(exact))?;
        }
        let pooled = Interval {
            value: self.improvement_ratio_corrected,
            ci: self.improvement_ratio_ci,
        };
        let s = &self.improvement_ratio_spread;
        write!(
            f,
            "  pooled improvement ratio (low unmapped / low mapped, geometric mean) {} for the sea state (the seas' spread and the sample noise inside); per-seed ratios {} to {}, median {}; {}",
            ratio(&pooled),
            num(s[0]),
            num(s[4]),
            num(s[2]),
            if self.improvement_significant {
                "significant at 95%"
            } else {
                "NOT significant at 95%"
            }
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fewer_than_two_realizations_are_refused_before_any_work() {
        let job = CompareJob {
            scene: Default::default(),
            high: Default::default(),
            low: Default::default(),
            rows_deg: (0.0, -5.0),
            max_boost: 64,
            filtered: false,
            exact: false,
            against: crate::app::compare::Against::PaperHigh,
            truth_boost: crate::app::compare::DEFAULT_TRUTH_BOOST,
            truth_from: None,
            out: std::env::temp_dir().join("vastocean-realizations-refused"),
            progress: false,
        };
        let e = run(&job, 1).unwrap_err();
        assert_eq!(e.exit_code(), 2, "{e}");
        assert!(e.to_string().contains("--realizations"), "{e}");
        // and one sea's truth cannot serve several
        let reused = CompareJob {
            against: super::super::Against::Truth,
            truth_from: Some(std::env::temp_dir()),
            ..job
        };
        let e = run(&reused, 2).unwrap_err();
        assert_eq!(e.exit_code(), 2, "{e}");
        assert!(e.to_string().contains("--against truth"), "{e}");
    }
}
