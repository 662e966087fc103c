//! What `bench accuracy` writes and prints: `frontier.csv`, `frontier.png`, `summary.json` and
//! the table.

use std::fmt;
use std::time::Instant;

use super::{AccuracyJob, AccuracyReport, Match, Point, REFERENCE_NOISE_SHARE, ROWS, Reference};
use super::{figure, not_monotone};
use crate::analysis::charts::{FrontierPoint, frontier};
use crate::app::AppError;
use crate::config::{NormalMode, SurfaceKind};
use crate::image_io::{stage, write_json};

pub(super) fn write(
    job: &AccuracyJob,
    points: Vec<Point>,
    reference: Reference,
    oceans_built: usize,
    t0: Instant,
) -> Result<AccuracyReport, AppError> {
    let (csv, png, json) = (
        job.out.join("frontier.csv"),
        job.out.join("frontier.png"),
        job.out.join("summary.json"),
    );
    let staged = stage(&csv, |w| {
        use std::io::Write;
        writeln!(
            w,
            "lod,normals,surface,spp,triangles,seconds_ocean,seconds_tessellation,seconds_build,seconds_levels,seconds_trace,seconds_normal_map,seconds_total,memory_bytes,rays,error,error_lo,error_hi,bias,bias_lo,bias_hi,bias_resolved,error_plain,noise,rmse_relative,rmse_relative_lo,rmse_relative_hi,pareto"
        )?;
        for p in &points {
            writeln!(
                w,
                "{},{},{},{},{},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{},{},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{},{:.6},{:.6},{:.6},{:.6},{:.6},{}",
                p.lod,
                p.normals,
                p.surface,
                p.spp,
                p.triangles,
                p.seconds_ocean,
                p.seconds_tessellation,
                p.seconds_build,
                p.seconds_levels,
                p.seconds_trace,
                p.seconds_normal_map,
                p.seconds_total,
                p.memory_bytes,
                p.rays,
                p.error,
                p.error_ci[0],
                p.error_ci[1],
                p.bias,
                p.bias_ci[0],
                p.bias_ci[1],
                p.bias_resolved,
                p.error_plain,
                p.noise,
                p.rmse_relative,
                p.rmse_relative_ci[0],
                p.rmse_relative_ci[1],
                p.pareto
            )?;
        }
        Ok(())
    })?;
    // The groups on the chart, those the sweep has, in this order.
    let group_of = |p: &Point| match (p.surface, p.normals) {
        (SurfaceKind::Exact, NormalMode::Filtered) => 4,
        (SurfaceKind::Exact, _) => 3,
        (_, NormalMode::Mapped) => 0,
        // (bench accuracy renders no flat-shaded mesh; grouped with the unmapped)
        (_, NormalMode::Vertex | NormalMode::Geometric) => 1,
        (_, NormalMode::Filtered) => 2,
    };
    let names = [
        "mapped normals",
        "vertex normals",
        "filtered normals",
        "exact surface, mapped normals",
        "exact surface, filtered normals",
    ];
    let present: Vec<usize> = (0..names.len())
        .filter(|&g| points.iter().any(|p| group_of(p) == g))
        .collect();
    // each group's largest spp, whose points are labelled
    let last_spp = |p: &Point| match (p.surface, &job.exact) {
        (SurfaceKind::Exact, Some(x)) => x.spp.last().copied().unwrap_or(0),
        _ => job.spp.last().copied().unwrap_or(0),
    };
    let chart: Vec<FrontierPoint> = points
        .iter()
        .map(|p| FrontierPoint {
            seconds: p.seconds_total,
            error: p.error,
            error_ci: p.error_ci,
            group: present.iter().position(|&g| g == group_of(p)).unwrap_or(0),
            pareto: p.pareto,
            label: (p.lod.starts_with("paper") && p.spp == last_spp(p)).then(|| match p.surface {
                SurfaceKind::Exact => format!("  {} exact {}", p.lod, p.normals),
                SurfaceKind::Mesh => format!("  {} {}", p.lod, p.normals),
            }),
        })
        .collect();
    let groups: Vec<&str> = present.iter().map(|&g| names[g]).collect();
    frontier(
        &png,
        &format!(
            "against {} mapped, {} spp ({} px): rows 0 to -5 degrees, noise included",
            reference.lod, reference.spp, job.width
        ),
        "std of the luminance difference from the converged image",
        &groups,
        &chart,
    )
    .map_err(|m| AppError::Run(format!("cannot draw {}: {m}", png.display()).into()))?;
    let mut front: Vec<Point> = points.iter().filter(|p| p.pareto).cloned().collect();
    front.sort_by(|a, b| a.seconds_total.total_cmp(&b.seconds_total));
    let not_monotone = not_monotone(&points);
    let matches = matches(&points);
    let report = AccuracyReport {
        commit: crate::app::commit(),
        reference_noise_share: reference.noise_share,
        monotone_within_intervals: not_monotone.is_empty(),
        not_monotone,
        points,
        reference,
        front,
        matches,
        width: job.width,
        wrong_side: job.scene.render.wrong_side,
        interp: job.scene.ocean.interp,
        oceans_built,
        rows_deg: ROWS,
        seconds_total: t0.elapsed().as_secs_f64(),
        csv,
        png,
        json: json.clone(),
    };
    staged.commit()?;
    write_json(&json, &report)?;
    Ok(report)
}

/// Each mapped mesh render at its tessellation's most samples against the cheapest render of
/// every other method (filtered normals on a mesh, mapped normals on the exact surface), on any
/// mesh, that reaches its error ([`Match`]); empty without another method.
pub(super) fn matches(points: &[Point]) -> Vec<Match> {
    let method = |p: &Point| format!("{} {}", p.normals, p.surface);
    let mapped_mesh = |p: &Point| p.normals == NormalMode::Mapped && p.surface == SurfaceKind::Mesh;
    let mut methods: Vec<String> = points
        .iter()
        .filter(|p| p.normals == NormalMode::Filtered || p.surface == SurfaceKind::Exact)
        .map(method)
        .collect();
    methods.sort();
    methods.dedup();
    let name = |p: &Point| format!("{} {}", p.lod, p.spp);
    let cheapest = |m: &str, bound: f64| {
        points
            .iter()
            .filter(|q| method(q) == m && q.error <= bound)
            .min_by(|a, b| a.seconds_total.total_cmp(&b.seconds_total))
            .map(|q| (name(q), q.error, q.seconds_total))
    };
    let mut out = Vec::new();
    for p in points.iter().filter(|&p| mapped_mesh(p)) {
        let most = points
            .iter()
            .filter(|q| mapped_mesh(q) && q.lod == p.lod)
            .map(|q| q.spp)
            .max();
        if Some(p.spp) != most {
            continue;
        }
        for m in &methods {
            out.push(Match {
                mapped: name(p),
                mapped_error: p.error,
                mapped_seconds: p.seconds_total,
                method: m.clone(),
                at_most: cheapest(m, p.error),
                within: cheapest(m, p.error_ci[1]),
            });
        }
    }
    out
}

impl fmt::Display for AccuracyReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let r = &self.reference;
        writeln!(
            f,
            "speed / accuracy at {} px, wrong-side policy {}, {} reads, against {} mapped at {} spp over rows {} to {} degrees ({} triangles; its noise {:.2e}, {:.0}% of the smallest error{})",
            self.width,
            self.wrong_side,
            self.interp,
            r.lod,
            r.spp,
            self.rows_deg.0,
            self.rows_deg.1,
            r.triangles,
            r.noise_band,
            100.0 * r.noise_share,
            if r.noise_share > REFERENCE_NOISE_SHARE {
                format!(
                    ", above the {:.0}% it should be: the reference's sample cap was reached",
                    100.0 * REFERENCE_NOISE_SHARE
                )
            } else {
                String::new()
            }
        )?;
        writeln!(
            f,
            "  lod          normals   surface  spp   triangles   seconds   error, noise included [95%]   bias [95%]                  rel. RMSE [95%]           front"
        )?;
        for p in &self.points {
            writeln!(
                f,
                "  {:<12} {:<8}  {:<7} {:>4} {:>11} {:>9.2}   {:<29} {:<27} {:.4} [{:.4}, {:.4}]   {}",
                p.lod,
                p.normals.to_string(),
                p.surface.to_string(),
                p.spp,
                p.triangles,
                p.seconds_total,
                figure(p.error, p.error_ci, p.error_ci[0] > 0.0),
                figure(p.bias, p.bias_ci, p.bias_resolved),
                p.rmse_relative,
                p.rmse_relative_ci[0],
                p.rmse_relative_ci[1],
                if p.pareto { "*" } else { "" }
            )?;
        }
        if !self.matches.is_empty() {
            writeln!(
                f,
                "  the cheapest render of another method (any mesh) at a mapped render's error: at most it | inside its interval (time against the mapped render's)"
            )?;
        }
        for m in &self.matches {
            let found = |r: &Option<(String, f64, f64)>| match r {
                Some((name, e, t)) => {
                    format!("{name}: {e:.4}, {t:.2} s ({:.2}x)", t / m.mapped_seconds)
                }
                None => "none".to_string(),
            };
            writeln!(
                f,
                "  mapped {:<16} {:.4}, {:>6.2} s   {:<15} {:<34} | {}",
                m.mapped,
                m.mapped_error,
                m.mapped_seconds,
                m.method,
                found(&m.at_most),
                found(&m.within)
            )?;
        }
        if !self.monotone_within_intervals {
            writeln!(
                f,
                "  error significantly larger at more samples: {}",
                self.not_monotone.join("; ")
            )?;
        }
        write!(
            f,
            "  wrote {} {} {} in {:.0} s (commit {})",
            self.csv.display(),
            self.png.display(),
            self.json.display(),
            self.seconds_total,
            self.commit
        )
    }
}
