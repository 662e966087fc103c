//! `vastocean sky`: generate a sky map (Preetham clear, CIE overcast, partly cloudy), import an
//! HDR photograph with the ground removed, report a map's statistics, draw a contact sheet.

use std::path::{Path, PathBuf};

use super::AppError;
use crate::image_io::{RgbImage, read_exr, write_exr_half, write_png_rgb8};
use crate::sky::procedural::{SkyParams, generate as generate_map};
use crate::sky::tools::{self, Ground, SkyInfo};
use crate::sky::validate_map;

/// Reads an EXR and checks it can serve as a sky map.
fn load(path: &Path) -> Result<RgbImage, AppError> {
    let img = read_exr(path)?;
    validate_map(path, &img)?;
    Ok(img)
}

/// Generates a map `width` texels wide into `out` (half-float EXR). Returns (width, height).
pub fn generate(params: &SkyParams, width: usize, out: &Path) -> Result<(usize, usize), AppError> {
    let img = generate_map(params, width).map_err(|e| AppError::Input(e.into()))?;
    write_exr_half(out, &img)?;
    Ok((img.width, img.height))
}

/// How to import a photograph.
#[derive(Clone, Debug)]
pub struct ImportJob {
    pub photo: PathBuf,
    pub out: PathBuf,
    pub ground: Ground,
    /// Rotate the map in azimuth so its sun lands here, degrees.
    pub sun_azimuth_deg: Option<f64>,
    /// Set negative components to zero instead of refusing the photograph.
    pub clamp_negative: bool,
}

/// What an import did, in the order it happened (for the log), and the map's size.
#[derive(Clone, Debug, Default)]
pub struct ImportReport {
    pub notes: Vec<String>,
    pub width: usize,
    pub height: usize,
}

pub fn import(job: &ImportJob) -> Result<ImportReport, AppError> {
    let mut report = ImportReport::default();
    if let Some(az) = job.sun_azimuth_deg
        && !az.is_finite()
    {
        return Err(AppError::input(format!("--sun-azimuth {az} is not finite")));
    }
    let mut img = read_exr(&job.photo)?;
    if job.clamp_negative {
        let (n, worst) = tools::clamp_negative(&mut img);
        if n > 0 {
            report.notes.push(format!(
                "{}: set {n} negative components (down to {worst:e}) to zero",
                job.photo.display()
            ));
        }
    }
    validate_map(&job.photo, &img)?;
    if let Some(az) = job.sun_azimuth_deg {
        let r = tools::rotate_sun_to(&mut img, az).ok_or_else(|| {
            AppError::input(format!(
                "--sun-azimuth: {} has no sun to turn (its brightest region peaks at {:.1}x the median sky, a sun at {}x or more)",
                job.photo.display(),
                tools::brightest_region(&img).contrast,
                tools::SUN_CONTRAST
            ))
        })?;
        report.notes.push(format!(
            "rotated {} by {r:.2} degrees in azimuth",
            job.photo.display()
        ));
    }
    tools::remove_ground(&mut img, job.ground);
    write_exr_half(&job.out, &img)?;
    (report.width, report.height) = (img.width, img.height);
    Ok(report)
}

/// Statistics of a sky map.
pub fn info(file: &Path) -> Result<SkyInfo, AppError> {
    Ok(tools::info(&load(file)?))
}

/// A contact sheet of `files` into `out`; returns its (width, height).
pub fn sheet(
    files: &[PathBuf],
    thumb_width: usize,
    columns: usize,
    out: &Path,
) -> Result<(u32, u32), AppError> {
    if thumb_width < 2 || !thumb_width.is_multiple_of(2) || columns == 0 {
        return Err(AppError::input(format!(
            "--thumb-width must be even and >= 2 and --columns >= 1 (got {thumb_width}, {columns})"
        )));
    }
    let maps = files
        .iter()
        .map(|f| load(f))
        .collect::<Result<Vec<_>, _>>()?;
    let (w, h, rgb) = tools::contact_sheet(&maps, thumb_width, columns);
    write_png_rgb8(out, w, h, &rgb)?;
    Ok((w, h))
}

impl std::fmt::Display for SkyInfo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "{} x {}", self.width, self.height)?;
        writeln!(f, "  mean luminance          {:.6}", self.mean_radiance)?;
        writeln!(f, "  peak luminance          {:.6}", self.peak_radiance)?;
        match (self.sun_elevation_deg, self.sun_azimuth_deg) {
            (Some(el), Some(az)) => writeln!(
                f,
                "  sun                     elevation {el:.2} deg, azimuth {az:.2} deg ({:.0}x the median sky)",
                self.sun_contrast
            )?,
            _ => writeln!(
                f,
                "  sun                     none (the brightest region is {:.1}x the median sky; a sun is {}x or more)",
                self.sun_contrast,
                tools::SUN_CONTRAST
            )?,
        }
        write!(
            f,
            "  energy within 5 deg of the horizon  {:.4}",
            self.horizon_energy_fraction
        )
    }
}
