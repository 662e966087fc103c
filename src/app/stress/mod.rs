//! `vastocean stress`: renders a matrix of extreme scenes and checks invariants on every cell
//! (numerical stability). The matrix varies one axis at a time around a base scene (camera
//! 2 m up at the world origin, the default sea, the sun 3 degrees up, the equirectangular camera,
//! Embree, paper-low) and adds the crossings of extremes most likely to break something:
//!
//! - axes: camera height (0.05 m to 10 km), world position (0, 1e5, 1e7 m, and a whole multiple
//!   of every layer period), sea state (calm 0.5 m/s to a 25 m/s storm), sun elevation (-10 to
//!   90 degrees), camera (equirectangular; pinhole looking down, level, up), backend (Embree,
//!   Rust), tessellation (paper-low, auto, paper-high in the full matrix);
//! - invariants on every cell: no NaN or infinite sample or pixel; no camera ray below the
//!   horizon escapes to the sky (`escaped_below_horizon`); no ray spawned at a hit meets its own
//!   triangle again (`self_hits`); and where a cell says so: a white furnace (a uniform sky of
//!   radiance 1: no pixel may exceed it), a bit-identical image to another cell (a world offset
//!   that is a whole multiple of every layer period), agreement within noise with another cell
//!   (the Rust backend against Embree), or a refusal (a camera below the crests must be refused
//!   as bad input, not rendered).

use std::fmt;
use std::path::PathBuf;
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;

use super::AppError;
use crate::config::{Backend, LodChoice, NormalMode, SceneConfig, SurfaceKind};
use crate::render::pipeline::{Rendered, prepare};

mod matrix;
pub use matrix::matrix;

/// A check a cell makes besides the ones every cell makes.
#[derive(Clone, Debug, PartialEq)]
pub enum Extra {
    None,
    /// Uniform sky of radiance 1: no pixel's luminance may exceed 1.
    Furnace,
    /// The image must equal the named cell's bit for bit.
    Identical(&'static str),
    /// The image's mean luminance must agree with the named cell's within 4 standard errors.
    Agrees(&'static str),
    /// The scene must be refused as bad input (exit code 2).
    Refused,
}

/// One scene of the matrix.
#[derive(Clone, Debug)]
pub struct Cell {
    pub name: &'static str,
    /// The axis it varies and its value, for the table.
    pub axis: &'static str,
    pub value: String,
    pub scene: SceneConfig,
    pub extra: Extra,
}

/// A stress run.
#[derive(Clone, Debug)]
pub struct StressJob {
    pub cells: Vec<Cell>,
    /// Folder for `stress.csv`.
    pub out: PathBuf,
    pub progress: bool,
}

/// One cell's outcome.
#[derive(Clone, Debug, Serialize)]
pub struct CellResult {
    pub name: String,
    pub axis: String,
    pub value: String,
    pub passed: bool,
    /// Why it failed (empty when it passed).
    pub problems: Vec<String>,
    /// The refusal's message, for cells that expect one.
    pub refused: Option<String>,
    pub triangles: usize,
    pub nan_samples: u64,
    pub non_finite_pixels: usize,
    pub escaped_below_horizon: u64,
    pub self_hits: u64,
    pub wrong_side: u64,
    pub max_luminance: f64,
    pub mean_luminance: f64,
    /// |difference of mean luminance| over its standard error, against the `Agrees` cell.
    pub agreement_z: Option<f64>,
    /// Whether the image equals the `Identical` cell's bit for bit.
    pub identical: Option<bool>,
    pub seconds: f64,
}

/// What `vastocean stress` prints.
#[derive(Clone, Debug, Serialize)]
pub struct StressReport {
    pub cells: usize,
    pub failed: usize,
    pub seconds: f64,
    pub csv: PathBuf,
    pub results: Vec<CellResult>,
}
impl StressJob {
    /// The base scene of every cell: `width` pixels wide, `spp` samples.
    pub fn base(width: usize, spp: u32) -> SceneConfig {
        let mut s = SceneConfig::default();
        s.camera.width = width;
        s.render.spp = spp;
        if !cfg!(feature = "embree") {
            s.render.backend = Backend::Rust;
        }
        s
    }

    /// Keeps only the named cells and those they compare with; an unknown name is bad input.
    pub fn select(&mut self, names: &[String]) -> Result<(), AppError> {
        for n in names {
            if !self.cells.iter().any(|c| c.name == n) {
                let all: Vec<&str> = self.cells.iter().map(|c| c.name).collect();
                return Err(AppError::input(format!(
                    "no stress cell `{n}`; the cells are: {}",
                    all.join(", ")
                )));
            }
        }
        let mut keep: Vec<&str> = names.iter().map(String::as_str).collect();
        for c in &self.cells {
            if let (true, Extra::Identical(o) | Extra::Agrees(o)) =
                (keep.contains(&c.name), &c.extra)
            {
                keep.push(o);
            }
        }
        let keep: Vec<String> = keep.iter().map(|s| s.to_string()).collect();
        self.cells.retain(|c| keep.iter().any(|k| k == c.name));
        Ok(())
    }

    /// Every cell on the exact displaced surface (`render.surface = "exact"`, docs/exact.md)
    /// instead of the mesh. The cells it cannot render are left out, with the cells that
    /// compare with them: vertex normals (the exact surface has no vertices; it shades with
    /// mapped, filtered or geometric normals) and paper-high (the exact surface is found inside
    /// the coarse tessellation's triangles; 22 M prisms would test nothing more).
    pub fn on_exact_surface(&mut self) {
        let can = |c: &Cell| {
            c.scene.render.normals != NormalMode::Vertex
                && c.scene.lod.preset != LodChoice::PaperHigh
        };
        let dropped: Vec<&str> = self
            .cells
            .iter()
            .filter(|c| !can(c))
            .map(|c| c.name)
            .collect();
        self.cells.retain(|c| {
            can(c)
                && !matches!(c.extra, Extra::Identical(o) | Extra::Agrees(o) if dropped.contains(&o))
        });
        for c in &mut self.cells {
            c.scene.render.surface = SurfaceKind::Exact;
        }
    }

    /// Every cell's ocean read with `interp` (`ocean.interp`; no cell sets its own).
    pub fn reading(&mut self, interp: crate::ocean::Interp) {
        for c in &mut self.cells {
            c.scene.ocean.interp = interp;
        }
    }

    /// The quick matrix (256 px, 8 spp; paper-high left out): seconds on 2 cores.
    pub fn quick(out: PathBuf) -> StressJob {
        StressJob {
            cells: matrix(&Self::base(256, 8), false),
            out,
            progress: false,
        }
    }

    /// The full matrix (1024 px, 16 spp, more values per axis, paper-high, more Rust cells).
    pub fn full(out: PathBuf) -> StressJob {
        StressJob {
            cells: matrix(&Self::base(1024, 16), true),
            out,
            progress: false,
        }
    }
}

/// Mean luminance and its standard error (from the per-pixel variances) of a render.
fn mean_and_se(r: &Rendered) -> (f64, f64) {
    let n = r.film.image.pixels.len().max(1) as f64;
    let mean = r
        .film
        .image
        .pixels
        .iter()
        .map(|&p| crate::color::luminance(p) as f64)
        .sum::<f64>()
        / n;
    let var: f64 = r.film.var_y.iter().map(|&v| v as f64).sum::<f64>() / (n * n);
    (mean, var.sqrt())
}

/// Renders every cell and checks it; writes `stress.csv`.
pub fn run(job: &StressJob) -> Result<StressReport, AppError> {
    super::check_output_dir(&job.out)?;
    for c in &job.cells {
        c.scene.validate()?;
    }
    let t0 = Instant::now();
    let bar = if job.progress {
        ProgressBar::new(job.cells.len() as u64)
    } else {
        ProgressBar::hidden()
    };
    bar.set_style(
        ProgressStyle::with_template("stress {bar:40} {pos}/{len} cells  {msg}  {elapsed}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    // Images kept for the cells that others compare with.
    let wanted: Vec<&str> = job
        .cells
        .iter()
        .filter_map(|c| match c.extra {
            Extra::Identical(n) | Extra::Agrees(n) => Some(n),
            _ => None,
        })
        .collect();
    let mut kept: Vec<(&str, Rendered)> = Vec::new();
    // Cells that compare with a later one run after it.
    let mut order: Vec<&Cell> = job.cells.iter().collect();
    order.sort_by_key(|c| matches!(c.extra, Extra::Identical(_) | Extra::Agrees(_)));
    let mut results = Vec::new();
    for cell in order {
        bar.set_message(cell.name);
        let t = Instant::now();
        let outcome = prepare(&cell.scene).and_then(|p| p.render(&cell.scene, false));
        let mut r = CellResult {
            name: cell.name.into(),
            axis: cell.axis.into(),
            value: cell.value.clone(),
            passed: true,
            problems: Vec::new(),
            refused: None,
            triangles: 0,
            nan_samples: 0,
            non_finite_pixels: 0,
            escaped_below_horizon: 0,
            self_hits: 0,
            wrong_side: 0,
            max_luminance: 0.0,
            mean_luminance: 0.0,
            agreement_z: None,
            identical: None,
            seconds: 0.0,
        };
        match (outcome, &cell.extra) {
            (Err(e), Extra::Refused) => {
                let e = AppError::from(e);
                if e.exit_code() == 2 {
                    r.refused = Some(e.to_string());
                } else {
                    r.problems.push(format!("failed instead of refusing: {e}"));
                }
            }
            (Err(e), _) => r.problems.push(format!("did not render: {e}")),
            (Ok(_), Extra::Refused) => r
                .problems
                .push("rendered a scene it must refuse (the camera is below the crests)".into()),
            (Ok(rendered), extra) => {
                check(&rendered, extra, &kept, &mut r);
                if wanted.contains(&cell.name) {
                    kept.push((cell.name, rendered));
                }
            }
        }
        r.seconds = t.elapsed().as_secs_f64();
        r.passed = r.problems.is_empty();
        results.push(r);
        bar.inc(1);
    }
    bar.finish_and_clear();
    // Back in the matrix's order.
    results.sort_by_key(|r| job.cells.iter().position(|c| c.name == r.name));
    let csv = job.out.join("stress.csv");
    write_csv(&csv, &results)?;
    Ok(StressReport {
        cells: results.len(),
        failed: results.iter().filter(|r| !r.passed).count(),
        seconds: t0.elapsed().as_secs_f64(),
        csv,
        results,
    })
}

/// The invariants of one rendered cell.
fn check(rendered: &Rendered, extra: &Extra, kept: &[(&str, Rendered)], r: &mut CellResult) {
    let rep = &rendered.report;
    let pixels = &rendered.film.image.pixels;
    r.triangles = rep.triangles;
    r.nan_samples = rep.nan_count;
    r.non_finite_pixels = pixels
        .iter()
        .filter(|p| !p.iter().all(|c| c.is_finite()))
        .count();
    r.escaped_below_horizon = rep.escaped_below_horizon;
    r.self_hits = rep.self_hits;
    r.wrong_side = rep.wrong_side_count;
    r.max_luminance = pixels
        .iter()
        .map(|&p| crate::color::luminance(p) as f64)
        .fold(0.0, f64::max);
    let (mean, se) = mean_and_se(rendered);
    r.mean_luminance = mean;
    if r.nan_samples > 0 || r.non_finite_pixels > 0 {
        r.problems.push(format!(
            "{} NaN/infinite samples, {} non-finite pixels",
            r.nan_samples, r.non_finite_pixels
        ));
    }
    if r.escaped_below_horizon > 0 {
        r.problems.push(format!(
            "{} camera rays below the horizon escaped to the sky",
            r.escaped_below_horizon
        ));
    }
    if r.self_hits > 0 {
        r.problems
            .push(format!("{} rays met their own triangle again", r.self_hits));
    }
    let other = |name: &str| kept.iter().find(|(n, _)| *n == name).map(|(_, k)| k);
    match extra {
        // f32 sums of weights that add to 1 may round a hair above it.
        Extra::Furnace if r.max_luminance > 1.0 + 1e-4 => r.problems.push(format!(
            "a pixel's luminance {:.6} exceeds the uniform sky's 1",
            r.max_luminance
        )),
        Extra::Identical(name) => match other(name) {
            Some(k) => {
                let same = k.film.image.pixels == *pixels;
                r.identical = Some(same);
                if !same {
                    r.problems.push(format!(
                        "the image differs from {name}'s (not bit-identical)"
                    ));
                }
            }
            None => r
                .problems
                .push(format!("{name} did not render to compare with")),
        },
        Extra::Agrees(name) => match other(name) {
            Some(k) => {
                let (m2, se2) = mean_and_se(k);
                let d = (mean - m2).abs();
                let z = if d == 0.0 {
                    0.0
                } else {
                    d / (se * se + se2 * se2).sqrt()
                };
                r.agreement_z = Some(z);
                if z.is_nan() || z >= 4.0 {
                    r.problems.push(format!(
                        "mean luminance {mean:.6} vs {name}'s {m2:.6}: {z:.1} standard errors apart"
                    ));
                }
            }
            None => r
                .problems
                .push(format!("{name} did not render to compare with")),
        },
        _ => {}
    }
}

fn write_csv(path: &std::path::Path, rows: &[CellResult]) -> Result<(), AppError> {
    use std::io::Write;
    Ok(crate::image_io::write_atomically(path, |w| {
        writeln!(
            w,
            "cell,axis,value,passed,triangles,nan_samples,non_finite_pixels,escaped_below_horizon,self_hits,wrong_side,max_luminance,mean_luminance,agreement_z,identical,refused,seconds,problems"
        )?;
        for r in rows {
            let opt = |v: Option<String>| v.unwrap_or_default();
            writeln!(
                w,
                "{},{},\"{}\",{},{},{},{},{},{},{},{:.6},{:.6},{},{},\"{}\",{:.2},\"{}\"",
                r.name,
                r.axis,
                r.value.replace('"', "'"),
                r.passed,
                r.triangles,
                r.nan_samples,
                r.non_finite_pixels,
                r.escaped_below_horizon,
                r.self_hits,
                r.wrong_side,
                r.max_luminance,
                r.mean_luminance,
                opt(r.agreement_z.map(|z| format!("{z:.3}"))),
                opt(r.identical.map(|b| b.to_string())),
                opt(r.refused.clone()).replace('"', "'"),
                r.seconds,
                r.problems.join("; ").replace('"', "'"),
            )?;
        }
        Ok(())
    })?)
}

impl fmt::Display for StressReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "{:<28} {:<15} {:>6} {:>9} {:>4} {:>7} {:>9} {:>10} {:>7}",
            "cell",
            "axis",
            "result",
            "triangles",
            "NaN",
            "escaped",
            "self-hits",
            "max lum",
            "seconds"
        )?;
        for r in &self.results {
            let result = match (&r.refused, r.passed) {
                (Some(_), true) => "refused",
                (_, true) => "pass",
                (_, false) => "FAIL",
            };
            writeln!(
                f,
                "{:<28} {:<15} {:>6} {:>9} {:>4} {:>7} {:>9} {:>10.4} {:>7.2}",
                r.name,
                r.axis,
                result,
                r.triangles,
                r.nan_samples + r.non_finite_pixels as u64,
                r.escaped_below_horizon,
                r.self_hits,
                r.max_luminance,
                r.seconds
            )?;
            for p in &r.problems {
                writeln!(f, "    {p}")?;
            }
        }
        write!(
            f,
            "{} cells, {} failed, {:.1} s; table in {}",
            self.cells,
            self.failed,
            self.seconds,
            self.csv.display()
        )
    }
}
