//! `vastocean ocean`: builds the FFT layers of a sea state and reports the spectrum's and the
//! realization's statistics, optionally with a preview PNG seen from above.

use std::fmt;
use std::path::PathBuf;

use serde::Serialize;

use super::AppError;
use crate::ocean::repeat::{RepeatCorrelation, profile_csv, repeat_correlation};
use crate::ocean::slopes::NOT_READ;
use crate::ocean::{OceanParams, OceanSummary, Surface, write_preview_png};

/// An ocean job.
#[derive(Clone, Debug)]
pub struct OceanJob {
    pub params: OceanParams,
    pub seed: u64,
    /// Write the preview here, covering this many metres (default: the coarsest layer), each of
    /// its two panels this many pixels square.
    pub png: Option<(PathBuf, Option<f64>, u32)>,
    /// Write the surface along a line here: from (x0, z0) to (x1, z1), world metres, n points.
    pub profile: Option<(PathBuf, [f64; 2], [f64; 2], usize)>,
    /// Split the slopes for a pixel footprint this wide on the sea, m.
    pub footprint_m: Option<f64>,
}

/// The mean square slope as filtered normals split it for one footprint: what the layers'
/// mapped normals keep and what the rough lobe takes (`crate::ocean::slopes`).
#[derive(Clone, Debug, Serialize)]
pub struct FootprintSlopes {
    /// The footprint's width on the sea, m, and the std of the Gaussian that filters it.
    pub width_m: f64,
    pub sigma_m: f64,
    pub resolved_mss: f64,
    pub unresolved_mss: f64,
    pub layers: Vec<LayerSplit>,
}

/// One layer's share of [`FootprintSlopes`].
#[derive(Clone, Debug, Serialize)]
pub struct LayerSplit {
    /// Which of its low-passed levels the resolved waves are read from: 0 its own texels, l
    /// its l-th level, a fraction a blend of two, one past the last level not read at all.
    pub level: f64,
    pub resolved_mss: f64,
    pub unresolved_mss: f64,
}

impl FootprintSlopes {
    /// The split a filtered render with the `smith` lobe makes of the sea's slopes for a
    /// footprint `width_m` wide, with the default filter width (the `mapped` lobe splits the
    /// slopes as read the same way).
    pub fn new(surface: &Surface, width_m: f64) -> FootprintSlopes {
        let slopes = surface.slopes();
        let sigma_m = width_m * crate::config::render::FILTER_WIDTH_BOX as f64;
        let split = slopes.split(sigma_m as f32);
        let layers: Vec<LayerSplit> = slopes
            .layers()
            .iter()
            .zip(split.levels.iter().zip(split.blend))
            .map(|(l, (&level, blend))| {
                let [xx, _, zz] = l.total();
                let (level, blend) = if level == NOT_READ {
                    (l.levels() + 1, 0.0)
                } else {
                    (level as usize, blend)
                };
                let [u, _, v] = l.unresolved(level, blend as f64);
                LayerSplit {
                    level: level as f64 + blend as f64,
                    resolved_mss: xx + zz - (u + v),
                    unresolved_mss: u + v,
                }
            })
            .collect();
        FootprintSlopes {
            width_m,
            sigma_m,
            resolved_mss: layers.iter().map(|l| l.resolved_mss).sum(),
            unresolved_mss: layers.iter().map(|l| l.unresolved_mss).sum(),
            layers,
        }
    }
}

/// What was generated.
#[derive(Clone, Debug, Serialize)]
pub struct OceanReport {
    #[serde(flatten)]
    pub summary: OceanSummary,
    /// How much the summed surface repeats itself (see `crate::ocean::repeat`).
    pub repeat_correlation: RepeatCorrelation,
    /// Where the sea state lies outside the range the spectrum's models were fitted on (see
    /// `crate::ocean::Spectrum::range_notes`).
    pub range_notes: Vec<String>,
    /// With `--footprint`: the slopes' split for it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub footprint: Option<FootprintSlopes>,
    #[serde(skip)]
    pub params: OceanParams,
    #[serde(skip)]
    pub png: Option<PathBuf>,
}

impl super::Remarks for OceanReport {
    fn notes(&self) -> Vec<String> {
        let mut notes: Vec<String> = super::sea_state_note(&self.range_notes)
            .into_iter()
            .collect();
        let r = &self.repeat_correlation;
        if r.max > REPEAT_NOTE {
            let lag = if r.along_wind.correlation >= r.across_wind.correlation {
                r.along_wind.lag_m
            } else {
                r.across_wind.lag_m
            };
            let peak = self.params.shortest_peak_wavelength();
            let advice = if self.params.layers_auto {
                format!(
                    "its {peak:.1} m peak is too short for the layers auto chooses to hide their periods (docs/ocean.md, \"How much the sea repeats\")"
                )
            } else {
                format!("--layers auto chooses layers for its {peak:.1} m peak")
            };
            notes.push(format!(
                "the sea repeats itself (correlation {:.2} at a lag of {lag:.0} m); {advice}",
                r.max
            ));
        }
        notes.extend(crate::render::report::fold_note(
            self.summary.folded_fraction,
        ));
        notes
    }
    fn warnings(&self) -> Vec<String> {
        let mut w = Vec::new();
        if self.summary.folded_fraction >= crate::render::report::FOLD_WARNING {
            w.push(format!(
                "{:.3}% of the surface folds over itself (Jacobian <= 0); lower --choppiness to avoid it",
                100.0 * self.summary.folded_fraction
            ));
        }
        w
    }
}

/// A repeat correlation above this is noted (a layer that holds this share of the variance
/// repeats visibly).
pub const REPEAT_NOTE: f64 = 0.2;

pub fn run(job: &OceanJob) -> Result<OceanReport, AppError> {
    job.params.validate()?;
    if let Some((path, ..)) = &job.png {
        super::check_outputs(std::slice::from_ref(path))?;
    }
    if let Some((path, from, to, n)) = &job.profile {
        if !(from.iter().chain(to).all(|v| v.is_finite()) && (2..=10_000_000).contains(n)) {
            return Err(AppError::input(format!(
                "a profile is X0,Z0,X1,Z1,N with finite ends and 2 <= N <= 10000000 (got {from:?} {to:?} {n})"
            )));
        }
        super::check_outputs(std::slice::from_ref(path))?;
    }
    if let Some(w) = job.footprint_m
        && !(w >= 0.0 && w.is_finite())
    {
        return Err(AppError::input(format!(
            "--footprint is a width in metres, finite and >= 0 (got {w})"
        )));
    }
    let surface = Surface::new(&job.params, job.seed)?;
    let summary = surface.summary().clone();
    let sampler = surface.sampler([0.0, 0.0]);
    let longest_peak = summary
        .partitions
        .iter()
        .map(|q| q.peak_wavelength_m)
        .fold(0.0, f64::max);
    let repeat_correlation = repeat_correlation(&sampler, job.params.wind_dir_deg, longest_peak);
    let range_notes = surface
        .spectrum()
        .map_or_else(Vec::new, |s| s.range_notes());
    if let Some((path, from, to, n)) = &job.profile {
        let csv = profile_csv(&sampler, *from, *to, *n);
        crate::image_io::write_atomically(path, |w| std::io::Write::write_all(w, csv.as_bytes()))?;
    }
    if let Some((path, extent, size)) = &job.png {
        let extent = extent.unwrap_or(job.params.layers[0].size_m);
        write_preview_png(&surface, path, *size, extent)?;
    }
    Ok(OceanReport {
        summary,
        repeat_correlation,
        range_notes,
        footprint: job.footprint_m.map(|w| FootprintSlopes::new(&surface, w)),
        params: job.params.clone(),
        png: job.png.as_ref().map(|p| p.0.clone()),
    })
}

impl fmt::Display for OceanReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (p, s) = (&self.params, &self.summary);
        let preset = p.preset().and_then(|q| Some((q, q.row()?)));
        if let Some((q, row)) = preset {
            writeln!(f, "sea state: {q} ({})", row.name)?;
        }
        writeln!(
            f,
            "ocean: wind {:.4} m/s, fetch {:.4} km, depth {} m, seed {}",
            p.wind_speed, p.fetch_km, p.depth_m, s.seed
        )?;
        writeln!(
            f,
            "  layer   size (m)     n   spacing (m)   band k (rad/m)      spectrum RMS   realization RMS   ({} layering)",
            p.layering
        )?;
        for (i, l) in s.layers.iter().enumerate() {
            writeln!(
                f,
                "  {i:>5} {:>10.2} {:>5} {:>13.4} {:>9.3} - {:<9.3} {:>11.4} m {:>15.4} m",
                l.size_m, l.n, l.spacing_m, l.k_min, l.k_max, l.spectrum_rms_m, l.realization_rms_m
            )?;
        }
        writeln!(
            f,
            "  spectrum RMS      {:.4} m (over the layers' bands; model spectrum {:.4} m, amplitude scale {:.4})",
            s.spectrum_rms_m, s.model_rms_m, s.amplitude_scale
        )?;
        writeln!(
            f,
            "  realization RMS   {:.4} m (sampled surface {:.4} m)",
            s.realization_rms_m, s.sampled_rms_m
        )?;
        writeln!(
            f,
            "  mean square slope {:.5} spectrum, {:.5} grid points, {:.5} as read ({}: {:+.1} % of the spectrum's)",
            s.mss_spectrum,
            s.mss_grid,
            s.mss_lookup,
            p.interp,
            100.0 * (s.mss_lookup / s.mss_spectrum - 1.0)
        )?;
        writeln!(
            f,
            "    the bilinear height surface's own slopes (the exact surface's tangent plane): {:.5} ({:+.1} %)",
            s.mss_surface,
            100.0 * (s.mss_surface / s.mss_spectrum - 1.0)
        )?;
        if let Some(cm) = s.cox_munk_mss {
            writeln!(
                f,
                "    Cox & Munk's clean sea at this wind: {cm:.5}; the spectrum, cut off at {:.0} rad/m ({:.1} cm waves), has {:.0} % of it",
                s.spectrum_cutoff_rad_m,
                100.0 * std::f64::consts::TAU / s.spectrum_cutoff_rad_m.max(1e-30),
                100.0 * s.mss_spectrum / cm
            )?;
        }
        for (i, l) in s.layers.iter().enumerate() {
            writeln!(
                f,
                "    layer {i}: {:.5} spectrum, {:.5} grid points, {:.5} as read ({:+.1} %), {:.5} surface ({:+.1} %)",
                l.mss_spectrum,
                l.mss_grid,
                l.mss_lookup,
                100.0 * (l.mss_lookup / l.mss_spectrum - 1.0),
                l.mss_surface,
                100.0 * (l.mss_surface / l.mss_spectrum - 1.0)
            )?;
        }
        if let Some(fp) = &self.footprint {
            writeln!(
                f,
                "    through a {} m footprint (Gaussian std {:.3} m): {:.5} resolved by the mapped normals, {:.5} in the rough lobe",
                fp.width_m, fp.sigma_m, fp.resolved_mss, fp.unresolved_mss
            )?;
            for (i, l) in fp.layers.iter().enumerate() {
                writeln!(
                    f,
                    "    layer {i}: {:.5} resolved, {:.5} in the lobe (read from level {:.2})",
                    l.resolved_mss, l.unresolved_mss, l.level
                )?;
            }
        }
        match s.hs_target_m {
            Some(t) => writeln!(f, "  Hs                {:.3} m (target {t:.3} m)", s.hs_m)?,
            None => writeln!(f, "  Hs                {:.3} m", s.hs_m)?,
        }
        if s.partitions.len() > 1 {
            for q in &s.partitions {
                writeln!(
                    f,
                    "    {:<9} Hs {:.3} m ({:.0} % of the variance), peak {:.1} s / {:.1} m, towards {:.0} deg",
                    q.name,
                    q.hs_m,
                    100.0 * q.variance_share,
                    q.peak_period_s,
                    q.peak_wavelength_m,
                    q.direction_deg
                )?;
            }
        }
        writeln!(f, "  peak wavelength   {:.2} m", s.peak_wavelength_m)?;
        writeln!(f, "  folded fraction   {:.5}", s.folded_fraction)?;
        let r = &self.repeat_correlation;
        writeln!(
            f,
            "  repeat correlation {:.3} (along the wind {:.3} at {:.0} m, across {:.3} at {:.0} m; lags from {:.0} m)",
            r.max,
            r.along_wind.correlation,
            r.along_wind.lag_m,
            r.across_wind.correlation,
            r.across_wind.lag_m,
            r.min_lag_m
        )?;
        write!(f, "  generated in      {:.3} s", s.seconds)?;
        if let Some(png) = &self.png {
            write!(f, "\n  preview           {}", png.display())?;
        }
        Ok(())
    }
}
