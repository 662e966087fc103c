//! `vastocean render`: one scene end to end (ocean, tessellation, BVH, path tracing) into
//! `PREFIX.exr` (linear RGB, plus `Y.variance`: the variance of each pixel's mean luminance),
//! `PREFIX.png` (tone-mapped preview) and `PREFIX.json` (the sidecar: every parameter, timings
//! per phase, ray counts, noise, guards).

use std::fmt;
use std::path::PathBuf;

use super::{AppError, check_outputs, with_extension};
use crate::config::SceneConfig;
use crate::image_io::{commit_all, png_exposure, stage_exr_with, stage_json, stage_png};
use crate::render::film::Samples;
use crate::render::pipeline::{PassInfo, RenderReport, Setup, prepare_with};

/// A render job.
#[derive(Clone, Debug)]
pub struct RenderJob {
    pub scene: SceneConfig,
    /// Output prefix: writes PREFIX.exr, PREFIX.png and PREFIX.json.
    pub out: PathBuf,
    /// Show a progress bar on stderr.
    pub progress: bool,
    /// Render only pass K of N (1-based) into PREFIX.pass (see [`super::passes`]).
    pub pass: Option<(usize, usize)>,
}

/// Renders the scene and writes its three files; returns the sidecar.
/// The three files appear together or not at all: all are staged, then renamed in one commit
/// (an existing set is replaced whole, or left untouched when anything fails).
pub fn run(job: &RenderJob) -> Result<RenderReport, AppError> {
    job.scene.validate()?;
    super::check_prefix(&job.out)?;
    if let Some((k, n)) = job.pass {
        if !job.scene.render.aovs.is_empty() {
            return Err(AppError::input(
                "render.aovs (--aov) is written by a whole render, not by its passes: \
                 render the layers without --pass (one sample per pixel is enough)",
            ));
        }
        return run_pass(job, k, n);
    }
    let (exr, png, json) = (
        with_extension(&job.out, ".exr"),
        with_extension(&job.out, ".png"),
        with_extension(&job.out, ".json"),
    );
    check_outputs(&[exr.clone(), png.clone(), json.clone()])?;
    let setup = Setup {
        progress: job.progress,
        ..Setup::default()
    };
    let prepared = prepare_with(&job.scene, setup)?;
    let mut r = prepared.render(&job.scene, job.progress)?;
    let pool = super::output_pool(job.scene.render.threads)?;
    // Freeing the ocean's layers and the BVH (50 ms on one core for the default scene) goes on
    // beside the writing of the files; the two images are encoded side by side.
    std::thread::scope(|s| -> Result<(), AppError> {
        s.spawn(move || drop(prepared));
        let image = &r.film.image;
        let mut channels = vec![("Y.variance", &r.film.var_y[..])];
        channels.extend(r.aovs.channels());
        let (staged_exr, staged_png) = pool.install(|| {
            rayon::join(
                || stage_exr_with(&exr, image, &channels, job.scene.render.exr_compression),
                || {
                    let (exposure, stops) = png_exposure(job.scene.render.exposure, image);
                    stage_png(&png, image, exposure).map(|s| (s, stops))
                },
            )
        });
        let (staged_exr, (staged_png, stops)) = (staged_exr?, staged_png?);
        r.report.png_exposure_stops = Some(stops);
        r.report.exr = exr;
        r.report.png = png;
        r.report.json = json.clone();
        let staged_json = stage_json(&json, &r.report)?;
        commit_all(vec![staged_exr, staged_png, staged_json])?;
        Ok(())
    })?;
    Ok(r.report)
}

/// Renders pass `k` of `n` into PREFIX.pass.
fn run_pass(job: &RenderJob, k: usize, n: usize) -> Result<RenderReport, AppError> {
    let file = with_extension(&job.out, ".pass");
    let scene_spp = job.scene.render.spp;
    if super::passes::pass_samples(k, n, scene_spp) == 0 {
        return Err(AppError::input(format!(
            "pass {k} of {n} holds no samples at {scene_spp} spp (pass K takes samples K-1, K-1+N, ...): split into at most {scene_spp} passes"
        )));
    }
    check_outputs(std::slice::from_ref(&file))?;
    let samples = Samples {
        pass: k - 1,
        passes: n,
        boost: None,
    };
    let prepared = prepare_with(
        &job.scene,
        Setup {
            refittable: false,
            progress: job.progress,
            ..Setup::default()
        },
    )?;
    let (r, states) = prepared.render_samples(&job.scene, 0, samples, true, job.progress)?;
    let mut report = r.report;
    let spp = super::passes::pass_samples(k, n, job.scene.render.spp);
    report.spp = spp;
    report.passes = Some(PassInfo {
        passes: n,
        held: vec![k],
        missing: Vec::new(),
        samples_per_pixel: spp,
    });
    report.pass_file = Some(file.clone());
    super::passes::write_pass(&file, &report, &states)?;
    Ok(report)
}

/// The noise of a render in words a person can act on: how uncertain a pixel is, relative to the
/// image, and how many samples would halve it (the standard error falls as 1/sqrt(spp)).
pub fn noise_line(rms: f64, relative: f64, spp: u32) -> String {
    let mut line = format!(
        "noise: a pixel's luminance is uncertain by {:.1}% of the image's mean (RMS standard error {rms:.2e}); --spp {} would halve it",
        100.0 * relative,
        4 * u64::from(spp)
    );
    if relative > 1.0 {
        line.push_str(
            "; above 100% a few very bright samples (sun glints found by chance) carry most of it, and the figure itself is uncertain",
        );
    }
    line
}

/// What to do about a mapped sea whose noise is the sun's glints found by chance (above its
/// mean): filtered normals, which converge to the same image, integrate the waves below a
/// pixel at every hit.
fn glint_hint(sea_relative: f64, normals: crate::config::NormalMode) -> &'static str {
    use crate::config::NormalMode;
    if sea_relative > 1.0 && normals == NormalMode::Mapped {
        "; --normals filtered integrates the waves below each pixel instead of finding their \
         glints by chance (on the default scene a ninth of the noise for 1.8x the trace; \
         docs/filtered.md)"
    } else {
        ""
    }
}

impl super::Remarks for RenderReport {
    fn notes(&self) -> Vec<String> {
        super::sea_state_note(&self.ocean_notes)
            .into_iter()
            .chain(crate::render::report::fold_note(self.folded_fraction))
            .collect()
    }
    fn warnings(&self) -> Vec<String> {
        self.warnings.clone()
    }
}

impl fmt::Display for RenderReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "rendered {} x {} at {} spp: {} triangles ({}), {:.1} M rays at {:.2} Mrays/s",
            self.width,
            self.height,
            self.spp,
            self.triangles,
            super::backend_label(self.embree_version.as_deref()),
            self.rays as f64 / 1e6,
            self.mrays_per_s
        )?;
        writeln!(
            f,
            "  seconds: ocean {:.2}, tessellation {:.2}, BVH {:.2}{}{}, trace {:.2} (normal mapping ~{:.2}, {:.1}%), total {:.2}",
            self.seconds_ocean,
            self.seconds_tessellation,
            self.seconds_build,
            if self.objects.is_empty() {
                String::new()
            } else {
                format!(", objects {:.2}", self.seconds_objects)
            },
            // (a render of an ocean whose levels are built spends a few microseconds here)
            if self.seconds_levels >= 0.005 {
                format!(", filtered normals' levels {:.2}", self.seconds_levels)
            } else {
                String::new()
            },
            self.seconds_trace,
            self.seconds_normal_map,
            100.0 * self.normal_map_share,
            self.seconds_total
        )?;
        if let (Some(n), Some(r)) = (self.noise_rms, self.noise_rms_relative) {
            writeln!(f, "  {}", noise_line(n, r, self.spp))?;
        }
        if let (Some(n), Some(r)) = (self.noise_rms_sea, self.noise_rms_sea_relative) {
            writeln!(
                f,
                "  noise on the sea (pixels below the horizon): {:.1}% of the sea's mean (RMS standard error {n:.2e}){}",
                100.0 * r,
                glint_hint(r, self.config.render.normals)
            )?;
        }
        writeln!(
            f,
            "  NaN samples {}, wrong-side directions {}, truncated paths {}, camera rays escaping below the horizon {}",
            self.nan_count, self.wrong_side_count, self.truncated_paths, self.escaped_below_horizon
        )?;
        for o in &self.objects {
            writeln!(f, "  object {o}")?;
        }
        match (&self.pass_file, &self.passes) {
            (Some(file), Some(p)) => write!(
                f,
                "  wrote pass {:?} of {} to {} (merge the passes with `vastocean merge`)",
                p.held,
                p.passes,
                file.display()
            ),
            _ => write!(
                f,
                "  wrote {} {} {}",
                self.exr.display(),
                self.png.display(),
                self.json.display()
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::NormalMode;

    #[test]
    fn a_glint_noisy_sea_points_to_filtered_normals_and_no_other_does() {
        assert!(glint_hint(19.3, NormalMode::Mapped).contains("--normals filtered"));
        assert_eq!(glint_hint(1.5, NormalMode::Vertex), "");
        assert_eq!(glint_hint(0.7, NormalMode::Mapped), "");
        assert_eq!(glint_hint(2.4, NormalMode::Filtered), "");
    }
}
