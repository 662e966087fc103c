//! One render spread over many processes or machines: `vastocean render --pass K/N` renders the
//! samples s = K-1 mod N of every pixel into a pass file, and `vastocean merge` adds the pass
//! files up into exactly the render one process would have made (radiance sums are fixed-point
//! integers, see `crate::render::film`, so the order of the passes does not matter: the merged
//! image of all N passes is bit-identical to a single render's).
//!
//! A pass file is `VASTOCEAN-PASS 1\n`, the length of a JSON header (u64, little-endian), the
//! header (the pass's render report: its scene, counters and timings, and which pass it is),
//! then one [`PixelState`] per pixel, row-major. It is written atomically: an interrupted pass
//! leaves no file, so rerunning the passes that have none redoes exactly what is missing.

use std::fmt;
use std::io::Write;
use std::path::{Path, PathBuf};

use super::{AppError, check_outputs, with_extension};
use crate::image_io::{commit_all, png_exposure, stage, stage_exr_with, stage_json, stage_png};
use crate::render::film::{Film, PixelState};
use crate::render::pipeline::{PassInfo, RenderReport, mean_luminance, warnings};

const MAGIC: &[u8] = b"VASTOCEAN-PASS 1\n";

/// Parses `K/N` (1 <= K <= N <= 4096).
pub fn parse_pass(s: &str) -> Result<(usize, usize), String> {
    let bad = || format!("a pass is K/N with 1 <= K <= N <= 4096, e.g. 3/8 (got `{s}`)");
    let (k, n) = s.split_once('/').ok_or_else(bad)?;
    let (k, n): (usize, usize) = (
        k.trim().parse().map_err(|_| bad())?,
        n.trim().parse().map_err(|_| bad())?,
    );
    if k == 0 || k > n || n > 4096 {
        return Err(bad());
    }
    Ok((k, n))
}

/// Samples per pixel of pass `k` (1-based) of `n` of a `spp`-sample render.
pub fn pass_samples(k: usize, n: usize, spp: u32) -> u32 {
    (k as u32 - 1..spp).step_by(n).count() as u32
}

/// Writes a pass file (atomically).
pub fn write_pass(
    path: &Path,
    report: &RenderReport,
    states: &[PixelState],
) -> Result<(), AppError> {
    let header = serde_json::to_vec(report).map_err(|e| AppError::Run(e.into()))?;
    let staged = stage(path, |w| {
        w.write_all(MAGIC)?;
        w.write_all(&(header.len() as u64).to_le_bytes())?;
        w.write_all(&header)?;
        let mut buf = Vec::with_capacity(PixelState::BYTES * 4096);
        for chunk in states.chunks(4096) {
            buf.clear();
            chunk.iter().for_each(|s| s.to_bytes(&mut buf));
            w.write_all(&buf)?;
        }
        Ok(())
    })?;
    commit_all(vec![staged])?;
    Ok(())
}

/// A pass file's header (its render report), read without its pixels.
pub struct Pass {
    pub path: PathBuf,
    pub report: RenderReport,
    /// Where the pixel states start in the file.
    body_offset: u64,
}

/// Reads a pass file's header and checks the file's size; anything unexpected is bad input.
pub fn read_pass(path: &Path) -> Result<Pass, AppError> {
    use std::io::Read;
    let bad = |why: String| AppError::input(format!("{}: {why}", path.display()));
    let mut f = std::fs::File::open(path).map_err(|e| bad(format!("cannot read it: {e}")))?;
    let size = f.metadata().map_err(|e| bad(e.to_string()))?.len();
    let mut magic = vec![0u8; MAGIC.len()];
    if f.read_exact(&mut magic).is_err() || magic != MAGIC {
        return Err(bad("not a vastocean pass file".into()));
    }
    let mut len = [0u8; 8];
    f.read_exact(&mut len)
        .map_err(|_| bad("truncated header".into()))?;
    let len = u64::from_le_bytes(len);
    if len > size {
        return Err(bad("truncated header".into()));
    }
    let mut header = vec![0u8; len as usize];
    f.read_exact(&mut header)
        .map_err(|_| bad("truncated header".into()))?;
    let report: RenderReport =
        serde_json::from_slice(&header).map_err(|e| bad(format!("bad header: {e}")))?;
    if report.passes.is_none() {
        return Err(bad("its header names no pass".into()));
    }
    let body_offset = MAGIC.len() as u64 + 8 + len;
    let expected = (report.width * report.height * PixelState::BYTES) as u64;
    if size - body_offset != expected {
        return Err(bad(format!(
            "{} bytes of pixel data for {} x {} pixels (expected {expected}): cut short?",
            size - body_offset,
            report.width,
            report.height
        )));
    }
    Ok(Pass {
        path: path.to_path_buf(),
        report,
        body_offset,
    })
}

impl Pass {
    /// Adds this pass's pixel states into `states` (or fills it, when empty).
    fn add_states_to(&self, states: &mut Vec<PixelState>) -> Result<(), AppError> {
        use std::io::{Read, Seek, SeekFrom};
        let fail =
            |e: std::io::Error| AppError::Run(format!("{}: {e}", self.path.display()).into());
        let mut f = std::io::BufReader::new(std::fs::File::open(&self.path).map_err(fail)?);
        f.seek(SeekFrom::Start(self.body_offset)).map_err(fail)?;
        let pixels = self.report.width * self.report.height;
        let fresh = states.is_empty();
        let mut buf = vec![0u8; PixelState::BYTES * 4096];
        let mut done = 0;
        while done < pixels {
            let m = (pixels - done).min(4096);
            let chunk = &mut buf[..m * PixelState::BYTES];
            f.read_exact(chunk).map_err(fail)?;
            for (j, b) in chunk.chunks_exact(PixelState::BYTES).enumerate() {
                let st = PixelState::from_bytes(b);
                if fresh {
                    states.push(st);
                } else {
                    states[done + j].merge(&st);
                }
            }
            done += m;
        }
        Ok(())
    }
}

/// A merge job.
#[derive(Clone, Debug)]
pub struct MergeJob {
    pub passes: Vec<PathBuf>,
    /// Output prefix: PREFIX.exr, PREFIX.png, PREFIX.json, as a render writes.
    pub out: PathBuf,
}

/// Checks that passes belong to one render: the same scene (whatever threads, exposure and EXR
/// compression each asked for), the same image, seed, samples and number of passes, and no
/// pass twice.
fn check_same_render(passes: &[Pass]) -> Result<(), AppError> {
    let first = &passes[0];
    let info = |p: &Pass| p.report.passes.clone().expect("read_pass checked");
    let key = |p: &Pass| {
        let mut c = p.report.config.clone();
        c.render.threads = 0;
        // the PNG's exposure is merge's own (the passes write no PNG)
        c.render.exposure = None;
        c.render.exr_compression = Default::default();
        c
    };
    let mut seen: Vec<(usize, &Path)> = Vec::new();
    for p in passes {
        let (a, b) = (info(first), info(p));
        if b.passes != a.passes {
            return Err(AppError::input(format!(
                "{} is one of {} passes, {} one of {}: not the same render",
                p.path.display(),
                b.passes,
                first.path.display(),
                a.passes
            )));
        }
        if key(p) != key(first) {
            return Err(AppError::input(format!(
                "{} and {} render different scenes (compare the `config` of their headers)",
                p.path.display(),
                first.path.display()
            )));
        }
        for &k in &b.held {
            if let Some((_, other)) = seen.iter().find(|(s, _)| *s == k) {
                return Err(AppError::input(format!(
                    "pass {k} of {} is given twice ({} and {})",
                    b.passes,
                    other.display(),
                    p.path.display()
                )));
            }
            seen.push((k, &p.path));
        }
    }
    Ok(())
}

/// Merges pass files into a render's three files; returns the merged sidecar.
pub fn merge(job: &MergeJob) -> Result<RenderReport, AppError> {
    if job.passes.is_empty() {
        return Err(AppError::input("merge needs at least one pass file"));
    }
    super::check_prefix(&job.out)?;
    let (exr, png, json) = (
        with_extension(&job.out, ".exr"),
        with_extension(&job.out, ".png"),
        with_extension(&job.out, ".json"),
    );
    check_outputs(&[exr.clone(), png.clone(), json.clone()])?;
    let passes = job
        .passes
        .iter()
        .map(|p| read_pass(p))
        .collect::<Result<Vec<_>, _>>()?;
    check_same_render(&passes)?;

    // One pass's pixels in memory at a time.
    let mut states = Vec::new();
    for p in &passes {
        p.add_states_to(&mut states)?;
    }
    let mut r = passes[0].report.clone();
    let n = r.passes.as_ref().map_or(1, |i| i.passes);
    let mut held: Vec<usize> = passes
        .iter()
        .flat_map(|p| p.report.passes.as_ref().unwrap().held.clone())
        .collect();
    held.sort_unstable();
    let total = r.config.render.spp;
    let samples_per_pixel = held.iter().map(|&k| pass_samples(k, n, total)).sum();
    r.spp = samples_per_pixel;
    r.passes = Some(PassInfo {
        passes: n,
        missing: (1..=n).filter(|k| !held.contains(k)).collect(),
        held,
        samples_per_pixel,
    });
    // Counts and times add up over the passes (times are the sum over processes).
    let rest = &passes[1..];
    for p in rest {
        let o = &p.report;
        r.counters += o.counters;
        r.rejected_rays += o.rejected_rays;
        r.seconds_ocean += o.seconds_ocean;
        r.seconds_tessellation += o.seconds_tessellation;
        r.seconds_build += o.seconds_build;
        r.seconds_trace += o.seconds_trace;
        r.seconds_normal_map += o.seconds_normal_map;
        r.seconds_total += o.seconds_total;
    }
    let c = r.counters;
    r.rays = c.rays;
    r.nan_count = c.nan;
    r.wrong_side_count = c.wrong_side;
    r.backfacing_shading_count = c.backfacing_shading;
    r.truncated_paths = c.truncated;
    r.skipped_rays = c.skipped;
    r.skipped_rising_rays = c.skipped_rising;
    r.skipped_above_rays = c.skipped_above;
    r.escaped_below_horizon = c.escaped_below_horizon;
    r.self_hits = c.self_hits;
    r.mrays_per_s = c.rays as f64 / r.seconds_trace.max(1e-12) / 1e6;
    r.normal_map_share = r.seconds_normal_map / r.seconds_trace.max(1e-12);
    r.warnings = warnings(r.folded_fraction, c.escaped_below_horizon);

    let film = Film::from_states(r.width, r.height, samples_per_pixel, &states);
    r.noise_rms = film.noise_rms();
    r.noise_rms_relative = film.noise_rms().map(|v| v / mean_luminance(&film.image));
    let camera = crate::render::Camera::new(
        r.config.camera.aimed(),
        r.config.camera.width,
        r.config.camera.aspect,
    );
    let sea = film.noise_rms_sea(&camera);
    (r.noise_rms_sea, r.noise_rms_sea_relative) = (sea.map(|n| n.0), sea.map(|n| n.1));
    r.exr = exr.clone();
    r.png = png.clone();
    r.json = json.clone();
    r.pass_file = None;
    let image = &film.image;
    let (exposure, stops) = png_exposure(r.config.render.exposure, image);
    r.png_exposure_stops = Some(stops);
    let staged = vec![
        stage_exr_with(
            &exr,
            image,
            &[("Y.variance", &film.var_y)],
            r.config.render.exr_compression,
        )?,
        stage_png(&png, image, exposure)?,
        stage_json(&json, &r)?,
    ];
    commit_all(staged)?;
    Ok(r)
}

/// How a merged render is printed: the render's report and which passes it holds.
pub struct Merged(pub RenderReport);

impl fmt::Display for Merged {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(p) = &self.0.passes {
            writeln!(
                f,
                "merged {} of {} passes: {} of {} samples per pixel",
                p.held.len(),
                p.passes,
                p.samples_per_pixel,
                self.0.config.render.spp
            )?;
        }
        write!(f, "{}", self.0)
    }
}

impl super::Remarks for Merged {
    fn notes(&self) -> Vec<String> {
        self.0.notes()
    }
    fn warnings(&self) -> Vec<String> {
        let mut w = self.0.warnings();
        if let Some(p) = self.0.passes.as_ref().filter(|p| !p.missing.is_empty()) {
            w.push(format!(
                "missing passes {:?}: the image has fewer samples than a whole render",
                p.missing
            ));
        }
        w
    }
}

impl serde::Serialize for Merged {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.0.serialize(s)
    }
}
