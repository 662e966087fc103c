//! What a render reports: the JSON sidecar ([`RenderReport`], also what `--json` prints), which
//! sample passes it holds, its warnings, and the images before anything is written.

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use super::film::Film;
use super::{Camera, Counters};
use crate::config::SceneConfig;

/// Which sample passes a render holds (see `vastocean render --pass`, `vastocean merge`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PassInfo {
    /// Passes the render was split into.
    pub passes: usize,
    /// The passes it holds, 1-based.
    pub held: Vec<usize>,
    /// The passes it lacks (the image then has fewer samples than `spp`).
    pub missing: Vec<usize>,
    /// Samples per pixel the held passes add up to.
    pub samples_per_pixel: u32,
}

/// The JSON sidecar of a render (also printed by `vastocean render --json`).
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RenderReport {
    pub width: usize,
    pub height: usize,
    pub spp: u32,
    pub seed: u64,
    pub threads: usize,
    /// "embree" or "rust".
    pub backend: String,
    pub embree_version: Option<String>,
    pub triangles: usize,
    pub vertices: usize,
    pub rings: usize,
    pub mesh_bytes: usize,
    pub tessellation_max_distance_m: f64,
    pub seconds_ocean: f64,
    pub seconds_tessellation: f64,
    pub seconds_build: f64,
    /// Reading, placing and building the objects (0 without any).
    #[serde(default)]
    pub seconds_objects: f64,
    /// Building the layers' low-passed levels and slope tables that filtered normals read, on
    /// their first render of an ocean (0 for other normals; microseconds once built).
    #[serde(default)]
    pub seconds_levels: f64,
    pub seconds_trace: f64,
    /// Wall-clock seconds the mapped normals add to the trace, estimated from single and
    /// paired timed batches (`Counters::normal_map_thread_seconds`; thread-seconds divided by the thread
    /// count).
    pub seconds_normal_map: f64,
    /// `seconds_normal_map` as a share of `seconds_trace`.
    pub normal_map_share: f64,
    /// Sum of the phases above (ocean, tessellation, BVH build, trace).
    pub seconds_total: f64,
    /// The PNG preview's exposure, stops (`render.exposure`, or what `auto` chose); absent
    /// where no PNG was written (a pass file).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub png_exposure_stops: Option<f32>,
    pub rays: u64,
    pub mrays_per_s: f64,
    /// RMS over the image of the standard error of the pixel luminance (from each pixel's
    /// sample variance); `None` with one sample per pixel.
    pub noise_rms: Option<f64>,
    /// `noise_rms` over the image's mean luminance.
    pub noise_rms_relative: Option<f64>,
    /// `noise_rms` over the pixels that look at the sea (centre below the horizon), and that
    /// over the sea's mean luminance. Absent from reports written before it.
    #[serde(default)]
    pub noise_rms_sea: Option<f64>,
    #[serde(default)]
    pub noise_rms_sea_relative: Option<f64>,
    pub nan_count: u64,
    /// Share of the sea surface that folds over itself (Jacobian <= 0).
    pub folded_fraction: f64,
    /// Camera rays pointing below the horizon (of the sea's troughs) that met no water: holes
    /// in the tessellation. Should be 0.
    pub escaped_below_horizon: u64,
    /// Rays spawned at a hit that met their own triangle again. Should be 0.
    pub self_hits: u64,
    /// Where the sea state lies outside the range the spectrum's models were fitted on (see
    /// `crate::ocean::Spectrum::range_notes`): printed as one note, the render is valid.
    #[serde(default, alias = "ocean_warnings")]
    pub ocean_notes: Vec<String>,
    /// What may be wrong with the render (folding, holes), printed on stderr.
    pub warnings: Vec<String>,
    /// Rays the backend refused for a NaN or infinite origin or direction (answered as misses).
    pub rejected_rays: u64,
    pub wrong_side_count: u64,
    pub backfacing_shading_count: u64,
    pub truncated_paths: u64,
    /// Steepest slope of the mesh; rays in the water descending more steeply than it, and rays
    /// leaving a hit into the air rising more steeply (`skipped_rising_rays`), are not traced.
    pub skip_slope: Option<f32>,
    pub skipped_rays: u64,
    #[serde(default)]
    pub skipped_rising_rays: u64,
    /// The mesh's highest vertex; rays leaving upwards from above it are not traced.
    #[serde(default)]
    pub skip_above_y: Option<f32>,
    #[serde(default)]
    pub skipped_above_rays: u64,
    /// Downwelling irradiance of the sky and the water-leaving radiance it gives (R_rs x E_d).
    pub sky_irradiance: [f32; 3],
    pub upwelling: [f32; 3],
    pub counters: Counters,
    /// A pinhole image's horizon: per column, the row (fractional, from the top edge) where
    /// the smooth sea's horizon crosses the column's centre, null outside the image.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub horizon_row_px: Option<Vec<Option<f32>>>,
    /// The objects on the sea and where they were placed.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub objects: Vec<crate::objects::ObjectReport>,
    /// For a pass or a merge of passes: which.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub passes: Option<PassInfo>,
    /// The pass file a `--pass` render wrote (instead of the three files below).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pass_file: Option<PathBuf>,
    pub exr: PathBuf,
    pub png: PathBuf,
    pub json: PathBuf,
    pub config: SceneConfig,
}

/// The images and counts of a render, before anything is written.
pub struct Rendered {
    pub film: Film,
    pub camera: Camera,
    pub report: RenderReport,
    /// The layers for training data the scene asked for (`render.aovs`).
    pub aovs: super::aov::AovLayers,
}

/// A folded share below this is noted, not warned of: a few of the 512^2 points the estimate
/// reads, at the steepest crests of a steep sea (reads that keep the sea's slopes, prefiltered
/// or bicubic, find them on the paper's case 50 where bilinear reads smooth them away). The
/// threshold is a judgement, not a measured visibility: a hundredth of a per cent of the sea.
pub const FOLD_WARNING: f64 = 1e-4;

/// The note a surface that folds below [`FOLD_WARNING`] gets.
pub fn fold_note(folded_fraction: f64) -> Option<String> {
    (folded_fraction > 0.0 && folded_fraction < FOLD_WARNING).then(|| {
        format!(
            "{:.4}% of the sea surface folds over itself (Jacobian <= 0) at its steepest crests, below the {:.2}% from which a render warns of it",
            100.0 * folded_fraction,
            100.0 * FOLD_WARNING
        )
    })
}

/// What a render warns of: folding from [`FOLD_WARNING`] up, and holes.
pub fn warnings(folded_fraction: f64, escaped_below_horizon: u64) -> Vec<String> {
    let mut w = Vec::new();
    if folded_fraction >= FOLD_WARNING {
        w.push(format!(
            "{:.3}% of the sea surface folds over itself (Jacobian <= 0); lower ocean.choppiness to avoid it",
            100.0 * folded_fraction
        ));
    }
    if escaped_below_horizon > 0 {
        w.push(format!(
            "{escaped_below_horizon} camera rays below the horizon met no water (holes in the tessellation)"
        ));
    }
    w
}

/// Mean relative luminance of an image (for relative noise figures; at least 1e-30).
pub fn mean_luminance(img: &crate::image_io::RgbImage) -> f64 {
    let sum: f64 = img
        .pixels
        .iter()
        .map(|&p| crate::color::luminance(p) as f64)
        .sum();
    (sum / img.pixels.len().max(1) as f64).max(1e-30)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_fold_below_the_warning_is_noted_and_from_it_warned_of() {
        assert_eq!(fold_note(0.0), None);
        assert!(warnings(0.0, 0).is_empty());
        // case 50's prefiltered sea: 2 of the 512^2 points
        let few = 2.0 / (512.0 * 512.0);
        assert!(fold_note(few).unwrap().contains("0.0008%"));
        assert!(warnings(few, 0).is_empty());
        assert_eq!(fold_note(FOLD_WARNING), None);
        let w = warnings(FOLD_WARNING, 0);
        assert!(w.len() == 1 && w[0].contains("folds over itself"), "{w:?}");
    }
}
