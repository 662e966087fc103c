//! `study run`: one case's comparison into its folder, skipped when it is finished.

use std::fmt;
use std::path::Path;

use serde::Serialize;

use super::{case_dir, finished_summary, read_plan};
use crate::app::AppError;
use crate::app::compare::realizations::RealizationsSummary;
use crate::app::compare::{CompareJob, CompareSummary};
use crate::config::SceneConfig;

/// What `study run` did with a case.
#[derive(Clone, Debug, Serialize)]
pub enum CaseOutcome {
    /// It was finished already (its summary exists); nothing was done.
    Skipped(usize),
    Ran(usize, Box<CompareSummary>),
    /// Run for the plan's ocean realizations and pooled.
    RanPooled(usize, Box<RealizationsSummary>),
}

/// Runs case `k` (1-based) of the study in `dir` into `cases/K/`, unless it is finished and
/// `force` is not set. `threads` overrides the case's own thread count when set.
pub fn run_case(
    dir: &Path,
    k: usize,
    force: bool,
    threads: Option<usize>,
    progress: bool,
) -> Result<CaseOutcome, AppError> {
    let plan = read_plan(dir)?;
    if k == 0 || k > plan.cases {
        return Err(AppError::input(format!(
            "case {k} is not in the plan (1..={})",
            plan.cases
        )));
    }
    let cdir = case_dir(dir, k);
    if !force && finished_summary(&cdir).is_some() {
        return Ok(CaseOutcome::Skipped(k));
    }
    let mut scene = SceneConfig::load(&cdir.join("scene.toml"))?;
    if progress {
        // Plain lines: a batch job's log has no terminal.
        eprintln!("case {k}: running into {}", cdir.display());
    }
    if let Some(t) = threads {
        scene.render.threads = t;
    }
    let job = CompareJob {
        high: plan.high,
        low: plan.low,
        scene,
        rows_deg: plan.rows_deg,
        max_boost: plan.max_boost,
        filtered: false,
        exact: false,
        against: crate::app::compare::Against::PaperHigh,
        truth_boost: crate::app::compare::DEFAULT_TRUTH_BOOST,
        truth_from: None,
        out: cdir,
        progress,
    };
    // compare writes summary.json last, atomically (pooled: after every realization).
    Ok(match plan.realizations {
        0 | 1 => CaseOutcome::Ran(k, Box::new(crate::app::compare::run(&job)?)),
        n => CaseOutcome::RanPooled(
            k,
            Box::new(crate::app::compare::realizations::run(&job, n.into())?),
        ),
    })
}

impl fmt::Display for CaseOutcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (k, ratio, ci, significant, seconds, seas) = match self {
            CaseOutcome::Skipped(k) => {
                return write!(f, "case {k}: finished already (--force to rerun)");
            }
            CaseOutcome::Ran(k, s) => (
                k,
                s.improvement_ratio_corrected,
                s.improvement_ratio_ci,
                s.improvement_significant,
                s.seconds_total,
                String::new(),
            ),
            CaseOutcome::RanPooled(k, s) => (
                k,
                s.improvement_ratio_corrected,
                s.improvement_ratio_ci,
                s.improvement_significant,
                s.seconds_total,
                format!(" over {} ocean seeds", s.realizations.len()),
            ),
        };
        write!(
            f,
            "case {k}: improvement ratio {ratio:.2} [{:.2}, {:.2}]{seas}{} in {seconds:.0} s",
            ci[0],
            ci[1],
            if significant {
                ", significant"
            } else {
                ", not significant"
            },
        )
    }
}
