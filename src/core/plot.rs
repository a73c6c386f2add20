//! PNG figures (plotters). Every figure is written atomically beside the CSV it illustrates.

use crate::core::error::{Error, Result};
use crate::core::output::write_atomic_via_path;
use plotters::prelude::*;
use std::path::Path;

/// One curve of a line plot.
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend label.
    pub label: String,
    /// Points `(x, y)`.
    pub points: Vec<(f64, f64)>,
    /// Draw markers instead of a line (measured or sampled data).
    pub markers: bool,
    /// A shaded band instead: the polygon `points` (upper edge left to right, then the lower
    /// edge right to left), see [`Series::band`].
    pub band: bool,
    /// Colour index into [`series_colour`]; by default the series' position in the plot.
    pub colour: Option<usize>,
    /// Draw the line dashed (e.g. the unstable part of a branch).
    pub dashed: bool,
}

impl Series {
    /// A line series.
    pub fn line(label: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self {
            label: label.into(),
            points,
            markers: false,
            band: false,
            colour: None,
            dashed: false,
        }
    }

    /// A marker (scatter) series.
    pub fn markers(label: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self {
            label: label.into(),
            points,
            markers: true,
            band: false,
            colour: None,
            dashed: false,
        }
    }

    /// A shaded band between `lower` and `upper` at each `x`: `(x, lower, upper)` (e.g. a 95 %
    /// confidence interval), drawn translucent in the series colour.
    pub fn band(label: impl Into<String>, points: &[(f64, f64, f64)]) -> Self {
        let upper = points.iter().map(|&(x, _, hi)| (x, hi));
        let lower = points.iter().rev().map(|&(x, lo, _)| (x, lo));
        Self {
            label: label.into(),
            points: upper.chain(lower).collect(),
            markers: false,
            band: true,
            colour: None,
            dashed: false,
        }
    }

    /// The same series drawn in colour `i` of [`series_colour`] (e.g. a band and its mean line).
    pub fn with_colour(mut self, i: usize) -> Self {
        self.colour = Some(i);
        self
    }

    /// The same line drawn dashed. A series with an empty label has no legend entry (e.g. the
    /// further pieces of a curve drawn in parts).
    pub fn dashed(mut self) -> Self {
        self.dashed = true;
        self
    }
}

/// Axis scale.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scale {
    /// Linear axis.
    Linear,
    /// Logarithmic (base 10) axis; values must be positive.
    Log,
}

/// Layout of a line plot.
#[derive(Debug, Clone)]
pub struct LinePlot<'a> {
    /// Title above the plot.
    pub title: &'a str,
    /// Axis labels, with units, e.g. `"pressure (MPa)"`.
    pub x_label: &'a str,
    /// Y-axis label, with unit.
    pub y_label: &'a str,
    /// Scale of the x axis.
    pub x_scale: Scale,
    /// Scale of the y axis.
    pub y_scale: Scale,
}

/// The length unit that shows a displacement of magnitude `max_abs_m` (m) with 1–3 digits
/// before the decimal point: `(factor from m, unit)`, one of nm, µm, mm, m.
pub fn length_unit(max_abs_m: f64) -> (f64, &'static str) {
    match max_abs_m.abs() {
        v if v < 1e-6 => (1e9, "nm"),
        v if v < 1e-3 => (1e6, "µm"),
        v if v < 1.0 => (1e3, "mm"),
        _ => (1.0, "m"),
    }
}

/// Tick label of `v` on a linear axis spanning `span`: as many decimals as the tick spacing
/// (about a tenth of the span) needs, and never a negative zero ("-0.0").
pub fn tick_label(v: f64, span: f64) -> String {
    let step = (span.abs() / 10.0).max(f64::MIN_POSITIVE);
    if !(1e-4..1e6).contains(&step) && v != 0.0 {
        return format!("{v:.2e}");
    }
    let decimals = (-step.log10().floor()).max(0.0) as usize;
    let s = format!("{v:.decimals$}");
    if s.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        s.trim_start_matches('-').to_string()
    } else {
        s
    }
}

fn plot_err(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::Data(format!("{}: plotting failed: {e}", path.display()))
}

fn range(vals: impl Iterator<Item = f64>, scale: Scale) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in vals.filter(|v| v.is_finite() && (scale == Scale::Linear || *v > 0.0)) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (if scale == Scale::Log { 1.0 } else { 0.0 }, 1.0);
    }
    match scale {
        Scale::Linear => {
            let pad = if hi > lo {
                0.05 * (hi - lo)
            } else {
                0.5 * lo.abs().max(1.0)
            };
            (lo - pad, hi + pad)
        }
        Scale::Log => {
            if hi > lo {
                (lo / 1.2, hi * 1.2)
            } else {
                (lo / 2.0, hi * 2.0)
            }
        }
    }
}

/// Colour of the `i`-th series.
pub fn series_colour(i: usize) -> RGBColor {
    const C: [RGBColor; 8] = [
        RGBColor(31, 119, 180),
        RGBColor(255, 127, 14),
        RGBColor(44, 160, 44),
        RGBColor(214, 39, 40),
        RGBColor(148, 103, 189),
        RGBColor(140, 86, 75),
        RGBColor(227, 119, 194),
        RGBColor(127, 127, 127),
    ];
    C[i % C.len()]
}

fn draw_series<'a, DB: DrawingBackend + 'a, X, Y>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<X, Y>>,
    series: &[Series],
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>>
where
    X: Ranged<ValueType = f64>,
    Y: Ranged<ValueType = f64>,
{
    for (i, s) in series.iter().enumerate() {
        let colour = series_colour(s.colour.unwrap_or(i));
        let pts: Vec<(f64, f64)> = s
            .points
            .iter()
            .copied()
            .filter(|(x, y)| x.is_finite() && y.is_finite())
            .collect();
        if s.band {
            chart
                .draw_series(std::iter::once(Polygon::new(
                    pts,
                    colour.mix(0.25).filled(),
                )))?
                .label(s.label.clone())
                .legend(move |(x, y)| {
                    Rectangle::new([(x, y - 5), (x + 20, y + 5)], colour.mix(0.25).filled())
                });
        } else if s.markers {
            chart
                .draw_series(pts.iter().map(|&p| Circle::new(p, 3, colour.filled())))?
                .label(s.label.clone())
                .legend(move |(x, y)| Circle::new((x + 10, y), 3, colour.filled()));
        } else if s.dashed {
            let drawn =
                chart.draw_series(DashedLineSeries::new(pts, 6, 4, colour.stroke_width(2)))?;
            if !s.label.is_empty() {
                drawn.label(s.label.clone()).legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 7, y)], colour.stroke_width(2))
                });
            }
        } else {
            let drawn = chart.draw_series(LineSeries::new(pts, colour.stroke_width(2)))?;
            if !s.label.is_empty() {
                drawn
                    .label(s.label.clone())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour));
            }
        }
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperLeft)
        .draw()?;
    Ok(())
}

/// Draw one chart of several series into a drawing area.
fn draw_panel<DB: DrawingBackend>(
    path: &Path,
    area: &DrawingArea<DB, plotters::coord::Shift>,
    layout: &LinePlot<'_>,
    series: &[Series],
) -> Result<()> {
    let xr = range(
        series.iter().flat_map(|s| s.points.iter().map(|p| p.0)),
        layout.x_scale,
    );
    let yr = range(
        series.iter().flat_map(|s| s.points.iter().map(|p| p.1)),
        layout.y_scale,
    );
    let mut builder = ChartBuilder::on(area);
    builder
        .caption(layout.title, ("sans-serif", 22))
        .margin(15)
        .x_label_area_size(50)
        .y_label_area_size(80);
    // Linear axes: labels without "-0.0" and with the decimals the ticks need.
    let (xs, ys) = (xr.1 - xr.0, yr.1 - yr.0);
    let x_fmt = |v: &f64| tick_label(*v, xs);
    let y_fmt = |v: &f64| tick_label(*v, ys);
    macro_rules! finish {
        ($chart:expr) => {{
            let mut chart = $chart.map_err(|e| plot_err(path, e))?;
            let mut mesh = chart.configure_mesh();
            mesh.x_desc(layout.x_label).y_desc(layout.y_label);
            if layout.x_scale == Scale::Linear {
                mesh.x_label_formatter(&x_fmt);
            }
            if layout.y_scale == Scale::Linear {
                mesh.y_label_formatter(&y_fmt);
            }
            mesh.draw().map_err(|e| plot_err(path, e))?;
            draw_series(&mut chart, series).map_err(|e| plot_err(path, e))?;
        }};
    }
    match (layout.x_scale, layout.y_scale) {
        (Scale::Linear, Scale::Linear) => {
            finish!(builder.build_cartesian_2d(xr.0..xr.1, yr.0..yr.1))
        }
        (Scale::Log, Scale::Linear) => {
            finish!(builder.build_cartesian_2d((xr.0..xr.1).log_scale(), yr.0..yr.1))
        }
        (Scale::Linear, Scale::Log) => {
            finish!(builder.build_cartesian_2d(xr.0..xr.1, (yr.0..yr.1).log_scale()))
        }
        (Scale::Log, Scale::Log) => {
            finish!(builder.build_cartesian_2d((xr.0..xr.1).log_scale(), (yr.0..yr.1).log_scale()))
        }
    }
    Ok(())
}

/// Draw a line plot of several series into a PNG (atomically).
pub fn line_plot(path: &Path, layout: &LinePlot<'_>, series: &[Series]) -> Result<()> {
    write_atomic_via_path(path, |tmp| {
        let root = BitMapBackend::new(tmp, (900, 650)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
        draw_panel(path, &root, layout, series)?;
        root.present().map_err(|e| plot_err(path, e))?;
        Ok(())
    })
}

/// Several line plots stacked vertically in one PNG (atomically), e.g. the amplitude and the
/// phase of a frequency response.
pub fn stacked_line_plots(path: &Path, panels: &[(LinePlot<'_>, Vec<Series>)]) -> Result<()> {
    if panels.is_empty() {
        return Err(Error::param("panels", "at least one panel"));
    }
    write_atomic_via_path(path, |tmp| {
        let root = BitMapBackend::new(tmp, (900, 480 * panels.len() as u32)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
        let areas = root.split_evenly((panels.len(), 1));
        for (area, (layout, series)) in areas.iter().zip(panels) {
            draw_panel(path, area, layout, series)?;
        }
        root.present().map_err(|e| plot_err(path, e))?;
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_labels_have_no_negative_zero() {
        assert_eq!(tick_label(-1e-17, 1.0), "0.0");
        assert_eq!(tick_label(-0.0, 10.0), "0");
        assert_eq!(tick_label(-0.25, 1.0), "-0.2");
        assert_eq!(tick_label(150.0, 400.0), "150");
        assert_eq!(tick_label(2e-5, 1e-4), "2.00e-5");
        assert_eq!(tick_label(0.002, 0.01), "0.002");
        assert_eq!(length_unit(1e-7), (1e9, "nm"));
        assert_eq!(length_unit(2e-5), (1e6, "µm"));
        assert_eq!(length_unit(0.02), (1e3, "mm"));
    }

    #[test]
    fn writes_png() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.png");
        let s = vec![
            Series::line("x²", (1..50).map(|i| (i as f64, (i * i) as f64)).collect()),
            Series::markers("x", (1..50).map(|i| (i as f64, i as f64)).collect()),
            Series::band(
                "x ± 10 %",
                &(1..50)
                    .map(|i| (i as f64, 0.9 * i as f64, 1.1 * i as f64))
                    .collect::<Vec<_>>(),
            ),
        ];
        let layout = LinePlot {
            title: "test",
            x_label: "x (m)",
            y_label: "y (Pa)",
            x_scale: Scale::Log,
            y_scale: Scale::Log,
        };
        line_plot(&p, &layout, &s).unwrap();
        let img = image::open(&p).unwrap();
        assert_eq!(img.width(), 900);
    }
}

/// Layout of a heat map (a field on a grid, e.g. heights or pressures).
#[derive(Debug, Clone)]
pub struct HeatMap<'a> {
    /// Title above the map.
    pub title: &'a str,
    /// Label of the colour bar with unit, e.g. `"height (µm)"`.
    pub value_label: &'a str,
    /// Factor applied to values for display (e.g. 1e6 for m → µm).
    pub value_scale: f64,
    /// Factor applied to lengths for the axes (e.g. 1e6 for m → µm) and its unit label.
    pub length_scale: f64,
    /// Unit label of the axes after `length_scale` (e.g. "µm").
    pub length_unit: &'a str,
}

/// Map a value in [0, 1] to a colour (viridis).
fn colour_of(t: f64) -> RGBColor {
    use plotters::style::colors::colormaps::{ColorMap, ViridisRGB};
    ViridisRGB.get_color(t.clamp(0.0, 1.0))
}

/// Draw a heat map of `field` (shape `(nx, ny)`, `[[i, j]]` at `(i·dx, j·dy)`; x to the right,
/// y upwards) with a colour bar, into a PNG (atomically). The field is resampled (nearest
/// point) to the plot's pixel size, at most 700 pixels per side.
pub fn heatmap(
    path: &Path,
    field: &ndarray::Array2<f64>,
    dx: f64,
    dy: f64,
    layout: &HeatMap<'_>,
) -> Result<()> {
    let (nx, ny) = field.dim();
    if nx == 0 || ny == 0 {
        return Err(Error::param("field", "heat map of an empty field"));
    }
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in field.iter().filter(|v| v.is_finite()) {
        lo = lo.min(*v);
        hi = hi.max(*v);
    }
    if !lo.is_finite() {
        lo = 0.0;
        hi = 1.0;
    }
    if hi <= lo {
        hi = lo + 1.0;
    }
    let side = 700.0;
    let (fx, fy) = (nx as f64 * dx, ny as f64 * dy);
    let w = ((fx / fx.max(fy)) * side).max(50.0) as u32;
    let h = ((fy / fx.max(fy)) * side).max(50.0) as u32;
    let render = |pw: u32, ph: u32| -> Vec<u8> {
        let mut img = image::RgbImage::new(pw.max(1), ph.max(1));
        let (pw, ph) = (img.width(), img.height());
        for (px, py, pixel) in img.enumerate_pixels_mut() {
            let i = (((px as f64 + 0.5) / pw as f64 * nx as f64) as usize).min(nx - 1);
            let jj = (((py as f64 + 0.5) / ph as f64 * ny as f64) as usize).min(ny - 1);
            let v = field[[i, ny - 1 - jj]];
            let c = if v.is_finite() {
                colour_of((v - lo) / (hi - lo))
            } else {
                RGBColor(255, 255, 255)
            };
            *pixel = image::Rgb([c.0, c.1, c.2]);
        }
        img.into_raw()
    };
    let ls = layout.length_scale;
    let (lx, ly) = (nx as f64 * dx * ls, ny as f64 * dy * ls);
    write_atomic_via_path(path, |tmp| {
        let root = BitMapBackend::new(tmp, (w + 260, h + 120)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
        let (left, right) = root.split_horizontally(w + 110);
        let mut chart = ChartBuilder::on(&left)
            .caption(layout.title, ("sans-serif", 20))
            .margin(10)
            .x_label_area_size(45)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..lx, 0.0..ly)
            .map_err(|e| plot_err(path, e))?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc(format!("x ({})", layout.length_unit))
            .y_desc(format!("y ({})", layout.length_unit))
            .draw()
            .map_err(|e| plot_err(path, e))?;
        let area = chart.plotting_area();
        let (pw, ph) = area.dim_in_pixel();
        let elem: BitMapElement<(f64, f64)> =
            BitMapElement::with_owned_buffer((0.0, ly), (pw, ph), render(pw, ph))
                .ok_or_else(|| plot_err(path, "bitmap size"))?;
        area.draw(&elem).map_err(|e| plot_err(path, e))?;
        // Colour bar.
        let vs = layout.value_scale;
        let mut bar = ChartBuilder::on(&right)
            .margin_top(40)
            .margin_bottom(55)
            .margin_right(10)
            .y_label_area_size(70)
            .build_cartesian_2d(0.0..1.0, lo * vs..hi * vs)
            .map_err(|e| plot_err(path, e))?;
        bar.configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .y_desc(layout.value_label)
            .draw()
            .map_err(|e| plot_err(path, e))?;
        let steps = 200;
        bar.draw_series((0..steps).map(|k| {
            let t0 = k as f64 / steps as f64;
            let t1 = (k + 1) as f64 / steps as f64;
            let c = colour_of(t0);
            Rectangle::new(
                [
                    (0.0, (lo + t0 * (hi - lo)) * vs),
                    (1.0, (lo + t1 * (hi - lo)) * vs),
                ],
                c.filled(),
            )
        }))
        .map_err(|e| plot_err(path, e))?;
        root.present().map_err(|e| plot_err(path, e))?;
        Ok(())
    })
}

#[cfg(test)]
mod heatmap_tests {
    use super::*;

    #[test]
    fn writes_heatmap_png() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("h.png");
        let f =
            ndarray::Array2::from_shape_fn((64, 32), |(i, j)| (i as f64 * 0.1).sin() + j as f64);
        let layout = HeatMap {
            title: "heights",
            value_label: "height (µm)",
            value_scale: 1e6,
            length_scale: 1e6,
            length_unit: "µm",
        };
        heatmap(&p, &f, 1e-6, 2e-6, &layout).unwrap();
        assert!(image::open(&p).is_ok());
    }
}
