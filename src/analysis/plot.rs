//! Pictures of a comparison, drawn with plotters: the statistics plot (the paper's Figure 5:
//! azimuth-averaged mean and standard deviation of the luminance difference against elevation,
//! the latter noise-corrected with its 95 % interval; green = high unmapped, blue = low mapped,
//! yellow = low unmapped, grey = noise floor) and the
//! contact sheet of the four renders (the paper's Figure 4). Text is drawn with ab_glyph from
//! Debian's DejaVu Sans (package fonts-dejavu-core, installed by `make setup`).

use std::path::Path;
use std::sync::OnceLock;

use plotters::prelude::*;
use plotters::style::{FontStyle, register_font};

use super::error::{RowEstimate, ScenarioEstimate};
use crate::image_io::{RgbImage, tonemap, write_png_rgb8};

const FONT_PATHS: [&str; 2] = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
];

/// Registers the label font once per process.
fn font() -> Result<(), String> {
    static FONT: OnceLock<Result<(), String>> = OnceLock::new();
    FONT.get_or_init(|| {
        let bytes = FONT_PATHS.iter().find_map(|p| std::fs::read(p).ok()).ok_or_else(|| {
            format!("no font for plot labels at {}: install Debian's fonts-dejavu-core (`make setup`)", FONT_PATHS[0])
        })?;
        // plotters keeps registered fonts for the life of the process.
        let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
        register_font("sans-serif", FontStyle::Normal, bytes).map_err(|_| "DejaVu Sans is not a usable font".to_string())
    })
    .clone()
}

/// Draws into an RGB buffer and writes it as PNG (atomically).
pub(crate) fn draw_png(
    path: &Path,
    size: (u32, u32),
    draw: impl FnOnce(DrawingArea<BitMapBackend, plotters::coord::Shift>) -> Result<(), String>,
) -> Result<(), String> {
    font()?;
    let mut buf = vec![255u8; (size.0 * size.1 * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, size).into_drawing_area();
        draw(root.clone())?;
        root.present().map_err(|e| e.to_string())?;
    }
    write_png_rgb8(path, size.0, size.1, &buf).map_err(|e| e.to_string())
}

/// Each scenario's curve, by its name: the paper's Figure 5 colours for its scenarios, and
/// the optional ones beside them.
const CURVES: [(&str, &str, RGBColor); 6] = [
    (
        "high_unmapped",
        "high tessellation, unmapped",
        RGBColor(0, 160, 60),
    ),
    (
        "low_mapped",
        "low tessellation, mapped",
        RGBColor(30, 80, 220),
    ),
    (
        "low_unmapped",
        "low tessellation, unmapped",
        RGBColor(225, 180, 0),
    ),
    (
        "noise_floor",
        "noise floor (baseline, other seed)",
        RGBColor(150, 150, 150),
    ),
    (
        "low_filtered",
        "low tessellation, filtered",
        RGBColor(150, 60, 200),
    ),
    (
        "low_exact",
        "low tessellation, exact surface",
        RGBColor(220, 40, 40),
    ),
];

/// The label and colour of scenario `name` (a scenario the table lacks: its name, in black).
fn curve(name: &str) -> (String, RGBColor) {
    CURVES
        .iter()
        .find(|c| c.0 == name)
        .map_or((name.to_string(), BLACK), |c| (c.1.to_string(), c.2))
}

/// Two panels against elevation: the mean of Y(scenario) - Y(baseline), and its standard
/// deviation: noise-corrected (solid) inside its 95 % interval (shaded), and the paper's
/// statistic with the noise in it (thin).
pub fn stats_plot(
    path: &Path,
    scenarios: &[ScenarioEstimate],
    rows_deg: (f64, f64),
) -> Result<(), String> {
    draw_png(path, (1400, 560), |root| {
        let e = |e: DrawingAreaErrorKind<_>| e.to_string();
        root.fill(&WHITE).map_err(e)?;
        let (left, right) = root.split_horizontally(700);
        for (panel, title, pick) in [
            (left, "mean of luminance difference", 0usize),
            (
                right,
                "std of luminance difference (solid: noise-corrected, 95% band; thin: with noise)",
                1,
            ),
        ] {
            let values = |r: &RowEstimate| -> Vec<f64> {
                if pick == 0 {
                    vec![r.mean]
                } else {
                    vec![r.std, r.std_corrected_ci[0], r.std_corrected_ci[1]]
                }
            };
            let (mut lo, mut hi) = scenarios
                .iter()
                .flat_map(|s| &s.rows)
                .flat_map(values)
                .filter(|v| v.is_finite())
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                    (a.min(v), b.max(v))
                });
            if pick == 1 {
                lo = 0.0;
            }
            // An empty or flat series (identical images) still needs a non-empty axis range.
            if !lo.is_finite() || !hi.is_finite() {
                (lo, hi) = (0.0, 1e-6);
            } else if hi <= lo {
                hi = lo + 1e-6;
            }
            let pad = 0.05 * (hi - lo);
            let mut chart = ChartBuilder::on(&panel)
                .caption(title, ("sans-serif", if pick == 0 { 22 } else { 15 }))
                .margin(12)
                .x_label_area_size(44)
                .y_label_area_size(80)
                .build_cartesian_2d(
                    rows_deg.1..rows_deg.0,
                    (lo - if pick == 0 { pad } else { 0.0 })..(hi + pad),
                )
                .map_err(e)?;
            chart
                .configure_mesh()
                .x_desc("elevation (degrees)")
                .y_desc("relative luminance difference")
                .label_style(("sans-serif", 15))
                .axis_desc_style(("sans-serif", 16))
                .draw()
                .map_err(e)?;
            for sc in scenarios {
                let (label, color) = curve(&sc.name);
                let rows = &sc.rows;
                if pick == 1 {
                    let band: Vec<(f64, f64)> = rows
                        .iter()
                        .map(|r| (r.elevation_deg, r.std_corrected_ci[1]))
                        .chain(
                            rows.iter()
                                .rev()
                                .map(|r| (r.elevation_deg, r.std_corrected_ci[0])),
                        )
                        .collect();
                    chart
                        .draw_series(std::iter::once(Polygon::new(band, color.mix(0.2).filled())))
                        .map_err(e)?;
                    chart
                        .draw_series(LineSeries::new(
                            rows.iter().map(|r| (r.elevation_deg, r.std)),
                            color.mix(0.6).stroke_width(1),
                        ))
                        .map_err(e)?;
                }
                let y = |r: &RowEstimate| if pick == 0 { r.mean } else { r.std_corrected };
                chart
                    .draw_series(LineSeries::new(
                        rows.iter().map(|r| (r.elevation_deg, y(r))),
                        color.stroke_width(2),
                    ))
                    .map_err(e)?
                    .label(label)
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(3))
                    });
            }
            draw_legend(&mut chart, SeriesLabelPosition::UpperLeft, 14).map_err(e)?;
        }
        Ok(())
    })
}

/// The renders stacked top to bottom with a caption above each, tone-mapped with one exposure.
pub fn contact_sheet(
    path: &Path,
    images: &[&RgbImage],
    labels: &[String],
    exposure: f32,
) -> Result<(), String> {
    const CAPTION: u32 = 30;
    let w = images.iter().map(|i| i.width).max().unwrap_or(1) as u32;
    let h: u32 = images.iter().map(|i| i.height as u32 + CAPTION).sum();
    draw_png(path, (w, h), |root| {
        let e = |e: DrawingAreaErrorKind<_>| e.to_string();
        root.fill(&WHITE).map_err(e)?;
        let mut y0 = 0i32;
        for (img, label) in images.iter().zip(labels) {
            root.draw(&Text::new(
                label.as_str(),
                (8, y0 + 6),
                ("sans-serif", 18).into_font().color(&BLACK),
            ))
            .map_err(e)?;
            y0 += CAPTION as i32;
            for y in 0..img.height {
                for x in 0..img.width {
                    let [r, g, b] = tonemap(img.get(x, y), exposure);
                    root.draw_pixel((x as i32, y0 + y as i32), &RGBColor(r, g, b))
                        .map_err(e)?;
                }
            }
            y0 += img.height as i32;
        }
        Ok(())
    })
}

/// Draws a chart's legend (its series labels) in a white box at `position`.
pub(crate) fn draw_legend<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
    font_size: u32,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", font_size))
        .position(position)
        .draw()
}
