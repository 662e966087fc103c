//! The benchmark charts, drawn with plotters from plain series: BVH build time against
//! triangle count (log-log, with a slope-1 reference), and the speed / accuracy frontier (run
//! time on a log axis against error with its interval, the Pareto front drawn, chosen points
//! labelled).

use std::path::Path;

use plotters::prelude::*;

use super::plot::{draw_legend, draw_png};

/// Colours of successive series.
const PALETTE: [RGBColor; 8] = [
    RGBColor(30, 80, 220),
    RGBColor(0, 160, 60),
    RGBColor(225, 150, 0),
    RGBColor(200, 40, 40),
    RGBColor(130, 60, 180),
    RGBColor(0, 150, 170),
    RGBColor(120, 120, 120),
    RGBColor(0, 0, 0),
];

/// An axis label of a log scale: 3 significant digits, no float noise ("0.3", "20", "1e6").
fn log_label(v: &f64) -> String {
    let v = *v;
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let digits = v.abs().log10().floor();
    if !(-3.0..5.0).contains(&digits) {
        return format!("{v:.0e}");
    }
    let decimals = (2.0 - digits).max(0.0) as usize;
    let s = format!("{v:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// A named series of (x, y) points.
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
}

fn log_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        return (1.0, 10.0);
    }
    (lo / 1.5, hi * 1.5)
}

/// Log-log lines, one per series, with a dashed line of slope 1 through the first series'
/// first point (time proportional to size).
pub fn log_log(
    path: &Path,
    title: &str,
    x_desc: &str,
    y_desc: &str,
    series: &[Series],
) -> Result<(), String> {
    draw_png(path, (1100, 700), |root| {
        let e = |e: DrawingAreaErrorKind<_>| e.to_string();
        root.fill(&WHITE).map_err(e)?;
        let xs = log_range(series.iter().flat_map(|s| s.points.iter().map(|p| p.0)));
        let ys = log_range(series.iter().flat_map(|s| s.points.iter().map(|p| p.1)));
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 22))
            .margin(14)
            .x_label_area_size(48)
            .y_label_area_size(80)
            .build_cartesian_2d((xs.0..xs.1).log_scale(), (ys.0..ys.1).log_scale())
            .map_err(e)?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc(y_desc)
            .x_label_formatter(&log_label)
            .y_label_formatter(&log_label)
            .label_style(("sans-serif", 15))
            .axis_desc_style(("sans-serif", 16))
            .draw()
            .map_err(e)?;
        if let Some(&(x0, y0)) = series.first().and_then(|s| s.points.first()) {
            let line = [(xs.0, y0 * xs.0 / x0), (xs.1, y0 * xs.1 / x0)];
            chart
                .draw_series(DashedLineSeries::new(line, 6, 4, BLACK.mix(0.5).into()))
                .map_err(e)?
                .label("slope 1 (time proportional to triangles)")
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.mix(0.5)));
        }
        for (s, color) in series.iter().zip(PALETTE.iter().cycle()) {
            let color = *color;
            chart
                .draw_series(LineSeries::new(s.points.clone(), color.stroke_width(2)))
                .map_err(e)?
                .label(s.label.as_str())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(3))
                });
            chart
                .draw_series(s.points.iter().map(|&p| Circle::new(p, 3, color.filled())))
                .map_err(e)?;
        }
        draw_legend(&mut chart, SeriesLabelPosition::UpperLeft, 14).map_err(e)?;
        Ok(())
    })
}

/// One configuration on the frontier chart.
pub struct FrontierPoint {
    pub seconds: f64,
    pub error: f64,
    pub error_ci: [f64; 2],
    /// Which colour group (e.g. mapped / vertex normals).
    pub group: usize,
    pub pareto: bool,
    /// Drawn next to the point when set.
    pub label: Option<String>,
}

/// Run time (log x) against error with interval bars; one colour per group, the Pareto front
/// joined by a black line.
pub fn frontier(
    path: &Path,
    title: &str,
    y_desc: &str,
    groups: &[&str],
    points: &[FrontierPoint],
) -> Result<(), String> {
    draw_png(path, (1200, 760), |root| {
        let e = |e: DrawingAreaErrorKind<_>| e.to_string();
        root.fill(&WHITE).map_err(e)?;
        let xs = log_range(points.iter().map(|p| p.seconds));
        // room on the right for the labels of the slowest points
        let xs = match points.iter().any(|p| p.label.is_some()) {
            true => (xs.0, xs.1 * 2.5),
            false => xs,
        };
        let y_hi = points
            .iter()
            .map(|p| p.error_ci[1].max(p.error))
            .filter(|v| v.is_finite())
            .fold(1e-6, f64::max)
            * 1.08;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 20))
            .margin(14)
            .x_label_area_size(48)
            .y_label_area_size(80)
            .build_cartesian_2d((xs.0..xs.1).log_scale(), 0.0..y_hi)
            .map_err(e)?;
        chart
            .configure_mesh()
            .x_label_formatter(&log_label)
            .x_desc("run time, seconds (ocean + tessellation + BVH + filtered normals' levels + trace; log scale)")
            .y_desc(y_desc)
            .label_style(("sans-serif", 15))
            .axis_desc_style(("sans-serif", 16))
            .draw()
            .map_err(e)?;
        let mut front: Vec<(f64, f64)> = points
            .iter()
            .filter(|p| p.pareto)
            .map(|p| (p.seconds, p.error))
            .collect();
        front.sort_by(|a, b| a.0.total_cmp(&b.0));
        chart
            .draw_series(LineSeries::new(front, BLACK.stroke_width(1)))
            .map_err(e)?
            .label("Pareto front")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
        for (g, name) in groups.iter().enumerate() {
            let color = PALETTE[g % PALETTE.len()];
            let mine: Vec<&FrontierPoint> = points.iter().filter(|p| p.group == g).collect();
            chart
                .draw_series(mine.iter().map(|p| {
                    PathElement::new(
                        vec![(p.seconds, p.error_ci[0]), (p.seconds, p.error_ci[1])],
                        color.mix(0.6).stroke_width(1),
                    )
                }))
                .map_err(e)?;
            chart
                .draw_series(
                    mine.iter()
                        .map(|p| Circle::new((p.seconds, p.error), 4, color.filled())),
                )
                .map_err(e)?
                .label(*name)
                .legend(move |(x, y)| Circle::new((x + 10, y), 4, color.filled()));
        }
        for p in points.iter().filter(|p| p.label.is_some()) {
            chart
                .draw_series(std::iter::once(Text::new(
                    p.label.clone().unwrap_or_default(),
                    (p.seconds, p.error),
                    ("sans-serif", 13).into_font().color(&BLACK),
                )))
                .map_err(e)?;
        }
        draw_legend(&mut chart, SeriesLabelPosition::UpperRight, 14).map_err(e)?;
        Ok(())
    })
}

/// One case on the study's scatter chart.
pub struct ScatterPoint {
    pub x: f64,
    pub x_ci: [f64; 2],
    pub y: f64,
    pub y_ci: [f64; 2],
    /// Which colour group (e.g. which sky).
    pub group: usize,
}

/// The paper's Figure 10: one point per case with its interval bars on both axes, coloured by
/// group, with the line y = x (below it, y is the smaller). Log-log axes, as the cases span
/// orders of magnitude (sky maps in different units); values and bounds at or below zero are
/// drawn at the bottom of the axis.
pub fn scatter(
    path: &Path,
    title: &str,
    x_desc: &str,
    y_desc: &str,
    groups: &[&str],
    points: &[ScatterPoint],
) -> Result<(), String> {
    draw_png(path, (1250, 900), |root| {
        let e = |e: DrawingAreaErrorKind<_>| e.to_string();
        root.fill(&WHITE).map_err(e)?;
        let (lo, hi) = log_range(
            points
                .iter()
                .flat_map(|p| [p.x, p.y, p.x_ci[0], p.x_ci[1], p.y_ci[0], p.y_ci[1]]),
        );
        let clamp = |v: f64| if v.is_finite() { v.clamp(lo, hi) } else { lo };
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 17))
            .margin(14)
            .x_label_area_size(48)
            .y_label_area_size(80)
            .build_cartesian_2d((lo..hi).log_scale(), (lo..hi).log_scale())
            .map_err(e)?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc(y_desc)
            .x_label_formatter(&log_label)
            .y_label_formatter(&log_label)
            .label_style(("sans-serif", 15))
            .axis_desc_style(("sans-serif", 16))
            .draw()
            .map_err(e)?;
        chart
            .draw_series(LineSeries::new([(lo, lo), (hi, hi)], BLACK.stroke_width(1)))
            .map_err(e)?
            .label("equal (below: mapping helps)")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
        // More groups than the palette has colours: cycle the palette, and the marker shape
        // (circle, triangle, cross) by which round of the palette it is.
        for (g, name) in groups.iter().enumerate() {
            let color = PALETTE[g % PALETTE.len()];
            let shape = g / PALETTE.len() % 3;
            let mine: Vec<&ScatterPoint> = points.iter().filter(|p| p.group == g).collect();
            chart
                .draw_series(mine.iter().flat_map(|p| {
                    let (x, y) = (clamp(p.x), clamp(p.y));
                    [
                        PathElement::new(
                            vec![(clamp(p.x_ci[0]), y), (clamp(p.x_ci[1]), y)],
                            color.mix(0.45).stroke_width(1),
                        ),
                        PathElement::new(
                            vec![(x, clamp(p.y_ci[0])), (x, clamp(p.y_ci[1]))],
                            color.mix(0.45).stroke_width(1),
                        ),
                    ]
                }))
                .map_err(e)?;
            let marker = move |c: (f64, f64)| -> DynElement<'static, BitMapBackend, (f64, f64)> {
                match shape {
                    0 => Circle::new(c, 5, color.filled()).into_dyn(),
                    1 => TriangleMarker::new(c, 6, color.filled()).into_dyn(),
                    _ => Cross::new(c, 5, color.stroke_width(2)).into_dyn(),
                }
            };
            chart
                .draw_series(mine.iter().map(|p| marker((clamp(p.x), clamp(p.y)))))
                .map_err(e)?
                .label(*name)
                .legend(move |(x, y)| match shape {
                    0 => Circle::new((x + 10, y), 5, color.filled()).into_dyn(),
                    1 => TriangleMarker::new((x + 10, y), 6, color.filled()).into_dyn(),
                    _ => Cross::new((x + 10, y), 5, color.stroke_width(2)).into_dyn(),
                });
        }
        draw_legend(&mut chart, SeriesLabelPosition::UpperLeft, 13).map_err(e)?;
        Ok(())
    })
}
