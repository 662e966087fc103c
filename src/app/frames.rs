//! `vastocean render --frames START:END:STEP`: an animation. The scene is prepared once at
//! START (ocean, tessellation, a BVH that can be refitted); every later frame moves the ocean
//! to its time, displaces the same vertices anew from their texture coordinates and refits the
//! BVH instead of rebuilding it (the tessellation's topology depends on the camera only).
//! Frames are written as they finish, `PREFIX.0001.exr` / `.png`, and `PREFIX.json` describes
//! the sequence so far (rewritten after every frame), so an interrupted sequence keeps its
//! finished frames and says which they are.

use std::fmt;
use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use super::{AppError, check_outputs, with_extension};
use crate::config::SceneConfig;
use crate::image_io::{commit_all, png_exposure, stage_exr_with, stage_json, stage_png};
use crate::render::pipeline::{FrameUpdate, Setup, mean_luminance, prepare_with};

/// Most frames one sequence may have (four digits in the file names).
pub const MAX_FRAMES: usize = 9999;

/// Ocean times START, START + STEP, ... up to END (inclusive, within rounding), seconds.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct FrameRange {
    pub start_s: f64,
    pub end_s: f64,
    pub step_s: f64,
}

impl FrameRange {
    /// The frames' times, rounded to the nanosecond so that 0:1:0.1 gives 0.3, not
    /// 0.30000000000000004 (which would print and land in the JSON as such).
    pub fn times(&self) -> Vec<f64> {
        let n = ((self.end_s - self.start_s) / self.step_s + 1e-9).floor() as usize + 1;
        (0..n)
            .map(|i| ((self.start_s + i as f64 * self.step_s) * 1e9).round() / 1e9)
            .collect()
    }
}

/// Parses START:END:STEP (seconds of ocean time), e.g. `0:2:0.04` for 51 frames at 25 fps.
pub fn parse_frames(s: &str) -> Result<FrameRange, String> {
    let bad = || {
        format!(
            "frames are START:END:STEP in seconds with STEP > 0 and END >= START, e.g. 0:2:0.04 (got `{s}`)"
        )
    };
    let v: Vec<f64> = s
        .split(':')
        .map(|x| x.trim().parse::<f64>().map_err(|_| bad()))
        .collect::<Result<_, _>>()?;
    let [start_s, end_s, step_s] = v[..] else {
        return Err(bad());
    };
    if !(start_s.is_finite() && end_s.is_finite() && step_s.is_finite())
        || step_s <= 0.0
        || end_s < start_s
    {
        return Err(bad());
    }
    let r = FrameRange {
        start_s,
        end_s,
        step_s,
    };
    let n = ((end_s - start_s) / step_s).floor() + 1.0;
    if n > MAX_FRAMES as f64 {
        return Err(format!(
            "{s} makes {n} frames; at most {MAX_FRAMES} fit the four-digit file names"
        ));
    }
    Ok(r)
}

/// An animation job.
#[derive(Clone, Debug)]
pub struct FramesJob {
    pub scene: SceneConfig,
    /// Output prefix: PREFIX.0001.exr, PREFIX.0001.png, ... and PREFIX.json.
    pub out: PathBuf,
    pub progress: bool,
    pub frames: FrameRange,
}

/// One finished frame.
#[derive(Clone, Debug, Serialize)]
pub struct FrameRecord {
    /// 1-based, as in the file names.
    pub index: usize,
    pub time_s: f64,
    pub exr: PathBuf,
    pub png: PathBuf,
    /// Moving the scene here from the previous frame (zero for the first, which was built).
    pub update: FrameUpdate,
    pub seconds_trace: f64,
    pub rays: u64,
    pub mrays_per_s: f64,
    pub mean_luminance: f64,
    pub noise_rms: Option<f64>,
    pub nan_count: u64,
    pub escaped_below_horizon: u64,
    pub warnings: Vec<String>,
    /// Where a mounted camera (`camera.mount`) stood and looked at this frame.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub camera: Option<crate::config::CameraConfig>,
}

/// The sequence's JSON (`PREFIX.json`).
#[derive(Clone, Debug, Serialize)]
pub struct SequenceReport {
    pub frames_planned: usize,
    pub range: FrameRange,
    pub frames: Vec<FrameRecord>,
    pub backend: String,
    pub embree_version: Option<String>,
    pub triangles: usize,
    pub vertices: usize,
    pub width: usize,
    pub height: usize,
    pub spp: u32,
    /// Building the first frame: ocean, tessellation, BVH (for Embree, of refit quality).
    pub setup_seconds_ocean: f64,
    pub setup_seconds_tessellation: f64,
    pub setup_seconds_build: f64,
    /// Median over the later frames of geometry update + refit, and the first frame's
    /// tessellation + BVH build (a rebuild would repeat it) over that: how much the refit
    /// saves per frame. `None` with one frame.
    pub median_seconds_update: Option<f64>,
    pub rebuild_over_update: Option<f64>,
    pub seconds_total: f64,
    /// The PNGs' exposure, stops: `render.exposure`, or what `auto` chose for the first frame
    /// (one exposure for the sequence, so the frames do not flicker).
    pub png_exposure_stops: Option<f32>,
    pub json: PathBuf,
    /// The sea state's range notes (see `crate::ocean::Spectrum::range_notes`).
    pub ocean_notes: Vec<String>,
    /// Frame files beyond this sequence's last that an earlier, longer sequence with the same
    /// prefix left (they are not this sequence's and are left alone).
    pub stale_frames: Vec<PathBuf>,
    pub config: SceneConfig,
}

impl super::Remarks for SequenceReport {
    fn notes(&self) -> Vec<String> {
        super::sea_state_note(&self.ocean_notes)
            .into_iter()
            .collect()
    }
    fn warnings(&self) -> Vec<String> {
        let mut w: Vec<String> = self
            .frames
            .iter()
            .flat_map(|r| &r.warnings)
            .collect::<std::collections::BTreeSet<_>>()
            .into_iter()
            .cloned()
            .collect();
        if let (Some(first), Some(last)) = (self.stale_frames.first(), self.stale_frames.last()) {
            w.push(format!(
                "{} .. {} are from an earlier, longer sequence with this prefix, not from this one (left alone; remove them before making a video)",
                first.display(),
                last.display()
            ));
        }
        w
    }
}

/// Frame files of an earlier sequence past frame `frames`: PREFIX.NNNN.exr/.png for NNNN from
/// `frames + 1` on, as long as either exists.
fn stale_frames(out: &Path, frames: usize) -> Vec<PathBuf> {
    let mut found = Vec::new();
    for index in frames + 1..=MAX_FRAMES {
        let files: Vec<PathBuf> = ["exr", "png"]
            .iter()
            .map(|ext| frame_path(out, index, ext))
            .filter(|p| p.exists())
            .collect();
        if files.is_empty() {
            break;
        }
        found.extend(files);
    }
    found
}

fn frame_path(out: &Path, index: usize, ext: &str) -> PathBuf {
    with_extension(out, &format!(".{index:04}.{ext}"))
}

/// Renders the sequence; each frame's two files are committed as soon as it finishes, and the
/// JSON after them.
pub fn run(job: &FramesJob) -> Result<SequenceReport, AppError> {
    job.scene.validate()?;
    if job.scene.render.surface == crate::config::SurfaceKind::Exact {
        // (its prisms and pyramids are built for one ocean time; a frame would need new ones)
        return Err(AppError::input(
            "--frames renders the mesh (render.surface = \"mesh\"); the exact surface renders \
             one time at a time",
        ));
    }
    super::check_prefix(&job.out)?;
    let times = job.frames.times();
    let json = with_extension(&job.out, ".json");
    let mut outputs = vec![json.clone()];
    for i in 1..=times.len() {
        outputs.push(frame_path(&job.out, i, "exr"));
        outputs.push(frame_path(&job.out, i, "png"));
    }
    check_outputs(&outputs)?;
    let start = Instant::now();
    let mut cfg = job.scene.clone();
    cfg.ocean.time_s = times[0];
    let mut prepared = prepare_with(
        &cfg,
        Setup {
            refittable: true,
            progress: job.progress,
            ..Setup::default()
        },
    )?;
    let pool = super::output_pool(cfg.render.threads)?;
    let mesh = prepared.accel.mesh();
    let mut report = SequenceReport {
        frames_planned: times.len(),
        range: job.frames,
        frames: Vec::new(),
        backend: prepared.accel.name().to_string(),
        embree_version: prepared.embree_version.clone(),
        triangles: mesh.triangle_count(),
        vertices: mesh.vertex_count(),
        width: 0,
        height: 0,
        spp: cfg.render.spp,
        setup_seconds_ocean: prepared.seconds_ocean,
        setup_seconds_tessellation: prepared.seconds_tessellation,
        setup_seconds_build: prepared.seconds_build,
        median_seconds_update: None,
        rebuild_over_update: None,
        seconds_total: 0.0,
        png_exposure_stops: cfg.render.exposure,
        json: json.clone(),
        ocean_notes: Vec::new(),
        stale_frames: stale_frames(&job.out, times.len()),
        config: cfg.clone(),
    };
    for (i, &time_s) in times.iter().enumerate() {
        let index = i + 1;
        let update = if i == 0 {
            FrameUpdate::default()
        } else if cfg.camera.mount.is_some() {
            let update;
            (prepared, update) = prepared.remount_to(&cfg, time_s)?;
            update
        } else {
            prepared.advance_to(time_s, cfg.camera.height_m)?
        };
        cfg.ocean.time_s = time_s;
        if job.progress {
            eprintln!("frame {index}/{} at t = {time_s} s", times.len());
        }
        let r = prepared.render(&cfg, job.progress)?;
        let (exr, png) = (
            frame_path(&job.out, index, "exr"),
            frame_path(&job.out, index, "png"),
        );
        let image = &r.film.image;
        let (exposure, stops) = pool.install(|| png_exposure(report.png_exposure_stops, image));
        report.png_exposure_stops = Some(stops);
        let mut channels = vec![("Y.variance", &r.film.var_y[..])];
        channels.extend(r.aovs.channels());
        let compression = cfg.render.exr_compression;
        let staged = vec![
            pool.install(|| stage_exr_with(&exr, image, &channels, compression))?,
            pool.install(|| stage_png(&png, image, exposure))?,
        ];
        commit_all(staged)?;
        report.width = r.report.width;
        report.height = r.report.height;
        report.frames.push(FrameRecord {
            index,
            time_s,
            exr,
            png,
            update,
            seconds_trace: r.report.seconds_trace,
            rays: r.report.rays,
            mrays_per_s: r.report.mrays_per_s,
            mean_luminance: mean_luminance(image),
            noise_rms: r.report.noise_rms,
            nan_count: r.report.nan_count,
            escaped_below_horizon: r.report.escaped_below_horizon,
            warnings: r.report.warnings,
            camera: prepared.mounted.clone(),
        });
        report.ocean_notes = r.report.ocean_notes;
        summarize(&mut report);
        report.seconds_total = start.elapsed().as_secs_f64();
        commit_all(vec![stage_json(&json, &report)?])?;
    }
    Ok(report)
}

fn summarize(r: &mut SequenceReport) {
    let mut updates: Vec<f64> = r
        .frames
        .iter()
        .skip(1)
        .map(|f| f.update.seconds_geometry + f.update.seconds_refit)
        .collect();
    if updates.is_empty() {
        return;
    }
    let median = crate::analysis::error::median(std::mem::take(&mut updates));
    r.median_seconds_update = Some(median);
    r.rebuild_over_update =
        Some((r.setup_seconds_tessellation + r.setup_seconds_build) / median.max(1e-12));
}

impl fmt::Display for SequenceReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "rendered {} of {} frames, {} x {} at {} spp: {} triangles ({}), {:.1} s in all",
            self.frames.len(),
            self.frames_planned,
            self.width,
            self.height,
            self.spp,
            self.triangles,
            super::backend_label(self.embree_version.as_deref()),
            self.seconds_total
        )?;
        writeln!(
            f,
            "  first frame built: ocean {:.2} s, tessellation {:.2} s, BVH {:.2} s",
            self.setup_seconds_ocean, self.setup_seconds_tessellation, self.setup_seconds_build
        )?;
        writeln!(
            f,
            "  frame      t (s)   ocean (s)   geometry (s)   refit (s)   trace (s)   Mrays/s   mean Y"
        )?;
        for r in &self.frames {
            writeln!(
                f,
                "  {:>5} {:>10.3} {:>11.3} {:>14.3} {:>11.4} {:>11.2} {:>9.2} {:>8.4}",
                r.index,
                r.time_s,
                r.update.seconds_ocean,
                r.update.seconds_geometry,
                r.update.seconds_refit,
                r.seconds_trace,
                r.mrays_per_s,
                r.mean_luminance
            )?;
        }
        let mounted = self.frames.iter().any(|r| r.camera.is_some());
        if let (true, Some(u)) = (mounted, self.median_seconds_update) {
            writeln!(
                f,
                "  the camera rides an object: each frame tessellated and built anew around it, {u:.3} s per frame (median)"
            )?;
        } else if let (Some(u), Some(x)) = (self.median_seconds_update, self.rebuild_over_update) {
            writeln!(
                f,
                "  geometry update + refit {u:.3} s per frame (median): {x:.1}x faster than the first frame's tessellation + build"
            )?;
        }
        write!(
            f,
            "  wrote {} .. {} and {}",
            frame_path(&self.config_out(), 1, "exr").display(),
            frame_path(&self.config_out(), self.frames.len().max(1), "png").display(),
            self.json.display()
        )
    }
}

impl SequenceReport {
    /// The output prefix (the JSON's path without `.json`).
    fn config_out(&self) -> PathBuf {
        self.json.with_extension("")
    }
}
