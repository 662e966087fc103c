//! What `compare` writes and prints: `stats.csv`, the renders' extra EXR channels, and the
//! summary for people.

use std::fmt;
use std::path::Path;

use super::CompareSummary;
use crate::analysis::error::{Estimates, Interval};
use crate::app::AppError;
use crate::image_io::write_atomically;

/// The noise floor's measured over predicted variance beyond which (interval and all) the noise
/// estimate is reported as unreliable.
pub const NOISE_CHECK_RANGE: (f64, f64) = (0.8, 1.25);

/// `stats.csv`: one line per analysed row; per scenario the paper's mean and std (the
/// columns of earlier versions, first), then the noise, the corrected std with its interval,
/// whether the row is a glint outlier, and the corrected variance the std is the root of
/// (negative where the noise exceeded the signal: such a row's std reads 0 and is below the
/// noise, not zero).
pub(super) fn write_stats_csv(path: &Path, e: &Estimates) -> Result<(), AppError> {
    Ok(write_atomically(path, |w| {
        use std::io::Write;
        write!(w, "elevation_deg")?;
        for sc in &e.scenarios {
            write!(w, ",mean_{0},std_{0}", sc.name)?;
        }
        for sc in &e.scenarios {
            write!(
                w,
                ",noise_{0},std_corrected_{0},std_corrected_lo_{0},std_corrected_hi_{0},glint_{0},variance_corrected_{0}",
                sc.name
            )?;
        }
        writeln!(w)?;
        for i in 0..e.rows {
            write!(w, "{:.6}", e.scenarios[0].rows[i].elevation_deg)?;
            for sc in &e.scenarios {
                let r = &sc.rows[i];
                write!(w, ",{:.9},{:.9}", r.mean, r.std)?;
            }
            for sc in &e.scenarios {
                let r = &sc.rows[i];
                write!(
                    w,
                    ",{:.9},{:.9},{:.9},{:.9},{},{:.9e}",
                    r.noise,
                    r.std_corrected,
                    r.std_corrected_ci[0],
                    r.std_corrected_ci[1],
                    u8::from(r.glint),
                    r.variance_corrected
                )?;
            }
            writeln!(w)?;
        }
        Ok(())
    })?)
}

/// The EXR channels beside RGB: `Y.variance`, and each batch's mean luminance as `Y.batchB`
/// (what the estimator reads, so a comparison can be analysed again without rendering).
pub(super) fn film_channels(film: &crate::render::film::Film) -> Vec<(String, Vec<f32>)> {
    let mut out = vec![("Y.variance".to_string(), film.var_y.clone())];
    if let Some(b) = &film.batches {
        for j in 0..b.k {
            let v = b.luminance.iter().skip(j).step_by(b.k).copied().collect();
            out.push((format!("Y.batch{j}"), v));
        }
    }
    out
}

/// A ratio as printed: two decimals, "inf" for an unbounded one, "n/a" for none.
pub(super) fn num(x: f64) -> String {
    if x.is_finite() {
        format!("{x:.2}")
    } else if x == f64::INFINITY {
        "inf".into()
    } else {
        "n/a".into()
    }
}

/// A ratio and its interval as printed: "1.68 [1.40, 2.02]".
pub(super) fn ratio(i: &Interval) -> String {
    format!("{} [{}, {}]", num(i.value), num(i.ci[0]), num(i.ci[1]))
}

impl crate::app::Remarks for CompareSummary {
    fn notes(&self) -> Vec<String> {
        let mut n = Vec::new();
        if self.baseline_noise_share > super::BASELINE_NOISE_SHARE {
            n.push(format!(
                "the baseline's own noise ({:.2e}) is {:.0}% of the smallest difference it ranks (more than {:.0}%): the estimates stay unbiased, their intervals are wide; more --spp narrows them",
                self.baseline_noise,
                100.0 * self.baseline_noise_share,
                100.0 * super::BASELINE_NOISE_SHARE
            ));
        }
        n
    }
    fn warnings(&self) -> Vec<String> {
        let check = &self.noise_model_check;
        let mut w = Vec::new();
        if check.ci[1] < NOISE_CHECK_RANGE.0 || check.ci[0] > NOISE_CHECK_RANGE.1 {
            w.push(format!(
                "the noise floor's measured / predicted variance is {} [{}, {}], well away from 1: the noise estimate is unreliable here (heavy-tailed samples, usually a bright sun's glint); trust the summary without glint rows, clip the sun or render more samples",
                num(check.value),
                num(check.ci[0]),
                num(check.ci[1])
            ));
        }
        if let Some(t) = &self.truth
            && t.wrong_side_share > super::truth::MAX_WRONG_SIDE_SHARE
        {
            w.push(format!(
                "{:.3}% of the truth's hits had a wrong-side event (more than {}%): it is not free of the policy it is meant to judge",
                100.0 * t.wrong_side_share,
                100.0 * super::truth::MAX_WRONG_SIDE_SHARE
            ));
        }
        w
    }
}

impl fmt::Display for CompareSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let ci = |i: &Interval| format!("{:.5} [{:.5}, {:.5}]", i.value, i.ci[0], i.ci[1]);
        writeln!(
            f,
            "compare: {} rows from {} to {} degrees at {} spp; std of the luminance difference from the baseline over the band",
            self.rows, self.rows_deg.0, self.rows_deg.1, self.spp
        )?;
        let sa = &self.sampling;
        if sa.max_boost > 1 {
            writeln!(
                f,
                "  samples: {} of {} analysed pixels boosted (up to {}x, after pilots at {} spp in {:.2} s): {:.0} spp on average there, {:.2}x a uniform render's samples",
                sa.boosted_pixels,
                sa.analysed_pixels,
                sa.max_boost,
                sa.pilot_spp,
                sa.seconds_pilot,
                sa.mean_spp_analysed,
                sa.cost_factor
            )?;
        }
        writeln!(
            f,
            "  (paper's statistic, noise included | noise-corrected RMS over rows, 95% interval of the converged value | RMS noise)"
        )?;
        for e in &self.estimates.scenarios {
            writeln!(
                f,
                "  {:<18} {:>9.5} | {} | {:.5} | {:>2} of {} rows noisier than their signal{}",
                e.name,
                e.std,
                if e.significant {
                    ci(&e.std_corrected)
                } else {
                    format!("< {:.5}", e.std_corrected.ci[1])
                },
                e.noise,
                e.noisy_rows,
                e.rows.len(),
                if e.significant {
                    ""
                } else {
                    "  (not significantly different from the baseline)"
                }
            )?;
        }
        writeln!(
            f,
            "  noise model check (noise floor, measured / predicted variance): {}",
            ci(&self.noise_model_check)
        )?;
        let r = &self.improvement;
        writeln!(
            f,
            "  improvement ratio (low unmapped / low mapped): paper's statistic {}; corrected {}",
            num(r.plain),
            ratio(&r.corrected),
        )?;
        writeln!(
            f,
            "    over rows: median {}, {:.0}% trimmed mean {}; trend {}, residual {}",
            ratio(&r.median_rows),
            100.0 * crate::analysis::error::TRIM,
            ratio(&r.trimmed),
            ratio(&r.trend),
            ratio(&r.residual)
        )?;
        if r.significant {
            writeln!(f, "  normal mapping's effect is significant at 95%")?;
        } else {
            match r.spp_to_resolve {
                Some(n) => writeln!(
                    f,
                    "  NOT significant at 95%: about {n} spp would resolve it if the ratio stays near {:.2}",
                    r.corrected.value
                )?,
                None => writeln!(f, "  NOT significant at 95%")?,
            }
        }
        let glint = &self.estimates.scenarios[0].glint_rows_deg;
        if !glint.is_empty() {
            let rows: Vec<String> = glint.iter().map(|e| format!("{e:.2}")).collect();
            writeln!(
                f,
                "  {} of {} rows cross the sun's glint (at {} degrees); without them the corrected ratio is {}",
                glint.len(),
                self.rows,
                rows.join(", "),
                ratio(&r.without_glint)
            )?;
        }
        if let (Some(t), Some(est)) = (&self.truth, &self.estimates_vs_truth) {
            writeln!(
                f,
                "  against the truth ({} surface, {} normals, {}x the samples; {} of {} hits with a wrong-side event): corrected std | band mean difference",
                t.surface, t.normals, t.boost, t.wrong_side_events, t.counters.hits
            )?;
            for e in &est.scenarios {
                writeln!(
                    f,
                    "  {:<18} {} | {}",
                    e.name,
                    ci(&e.std_corrected),
                    ci(&e.mean)
                )?;
            }
        }
        for sc in &self.scenarios {
            writeln!(
                f,
                "  {:<18} {:>9} triangles  tessellation {:.2} s  BVH {:.2} s  render {:.2} s",
                sc.name.name(),
                sc.triangles,
                sc.seconds_tessellation,
                sc.seconds_build,
                sc.seconds_render
            )?;
        }
        if let Some(t) = &self.truth {
            writeln!(
                f,
                "  {:<18} exact surface       BVH {:.2} s  render {:.2} s  ({} samples)",
                "truth", t.seconds_build, t.seconds_render, t.samples
            )?;
        }
        let dir = self.stats_csv.parent().unwrap_or(Path::new("."));
        write!(
            f,
            "  wrote {} {} {} and the renders in {}",
            self.stats_csv.display(),
            self.stats_png.display(),
            self.sheet_png.display(),
            dir.display()
        )
    }
}
