//! Plots of the measures, drawn with `plotters` into an RGB buffer (at twice the size,
//! then box-downsampled for anti-aliased lines) with the embedded font:
//!
//! - [`line_plot`]: named series `(x, y)` with a legend, linear or logarithmic y (open
//!   fraction, broken saliva elements against time, a K_glue sweep);
//! - [`profile_plot`]: a quantity along the mouth width at several times, one curve per
//!   time coloured by time, with a colour bar (the lip gap profiles);
//! - [`heatmap_plot`]: the same data as a map, position across, time up, colour = value.

use super::raster::Image;
use super::text::register_plot_font;
use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::ops::Range;

/// Drawing scale: plots are drawn this many times larger, then downsampled.
const SS: u32 = 2;

/// Tableau 10, the default series colours.
pub const PALETTE: [[u8; 3]; 10] = [
    [31, 119, 180],
    [255, 127, 14],
    [44, 160, 44],
    [214, 39, 40],
    [148, 103, 189],
    [140, 86, 75],
    [227, 119, 194],
    [127, 127, 127],
    [188, 189, 34],
    [23, 190, 207],
];

/// The viridis colour map (perceptually uniform, colour-blind safe) at `t` in `[0, 1]`.
pub fn viridis(t: f64) -> [u8; 3] {
    const V: [[f64; 3]; 11] = [
        [68.0, 1.0, 84.0],
        [72.0, 36.0, 117.0],
        [65.0, 68.0, 135.0],
        [53.0, 95.0, 141.0],
        [42.0, 120.0, 142.0],
        [33.0, 145.0, 140.0],
        [34.0, 168.0, 132.0],
        [68.0, 191.0, 112.0],
        [122.0, 209.0, 81.0],
        [189.0, 223.0, 38.0],
        [253.0, 231.0, 37.0],
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    } * 10.0;
    let i = (t.floor() as usize).min(9);
    let s = t - i as f64;
    std::array::from_fn(|k| (V[i][k] + (V[i + 1][k] - V[i][k]) * s).round() as u8)
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LegendPosition {
    UpperLeft,
    UpperRight,
    LowerLeft,
    LowerRight,
    /// No legend.
    Hidden,
}

/// One named curve.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    pub name: String,
    /// Points in drawing order; a non-finite value (or `y <= 0` on a log axis) breaks the line.
    pub points: Vec<(f64, f64)>,
    /// `None`: the next colour of [`PALETTE`].
    pub colour: Option<[u8; 3]>,
    pub dashed: bool,
    /// Draw a dot at each point.
    pub markers: bool,
}

impl Series {
    pub fn new(name: impl Into<String>, points: Vec<(f64, f64)>) -> Series {
        Series {
            name: name.into(),
            points,
            colour: None,
            dashed: false,
            markers: false,
        }
    }
    pub fn colour(mut self, c: [u8; 3]) -> Series {
        self.colour = Some(c);
        self
    }
    pub fn dashed(mut self) -> Series {
        self.dashed = true;
        self
    }
    pub fn markers(mut self) -> Series {
        self.markers = true;
        self
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct PlotSpec {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub series: Vec<Series>,
    pub log_y: bool,
    /// Axis ranges; `None`: from the data (with 5% padding).
    pub x_range: Option<(f64, f64)>,
    pub y_range: Option<(f64, f64)>,
    pub width: u32,
    pub height: u32,
    pub legend: LegendPosition,
}

impl PlotSpec {
    /// An 800 x 500 plot with no series yet, legend at the upper left.
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
    ) -> PlotSpec {
        PlotSpec {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            series: Vec::new(),
            log_y: false,
            x_range: None,
            y_range: None,
            width: 800,
            height: 500,
            legend: LegendPosition::UpperLeft,
        }
    }
}

/// Curves of a quantity along a line (the mouth width) at several times.
#[derive(Clone, Debug, PartialEq)]
pub struct ProfileSpec {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    /// Label of the colour bar, e.g. "time (s)".
    pub colour_label: String,
    /// Positions along the line (the same for every profile).
    pub x: Vec<f64>,
    /// `(time, values at x)`, one per output frame.
    pub profiles: Vec<(f64, Vec<f64>)>,
    /// Value range; `None`: from the data.
    pub y_range: Option<(f64, f64)>,
    pub width: u32,
    pub height: u32,
}

impl ProfileSpec {
    /// An 800 x 500 plot with no data yet.
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
        colour_label: impl Into<String>,
    ) -> ProfileSpec {
        ProfileSpec {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            colour_label: colour_label.into(),
            x: Vec::new(),
            profiles: Vec::new(),
            y_range: None,
            width: 800,
            height: 500,
        }
    }
}

fn rgb(c: [u8; 3]) -> RGBColor {
    RGBColor(c[0], c[1], c[2])
}

/// Splits points into runs of drawable points.
fn segments(points: &[(f64, f64)], log_y: bool) -> Vec<Vec<(f64, f64)>> {
    let mut out = Vec::new();
    let mut cur = Vec::new();
    for &(x, y) in points {
        if x.is_finite() && y.is_finite() && (!log_y || y > 0.0) {
            cur.push((x, y));
        } else if !cur.is_empty() {
            out.push(std::mem::take(&mut cur));
        }
    }
    if !cur.is_empty() {
        out.push(cur);
    }
    out
}

/// Data range with padding; a degenerate or empty range is widened.
fn auto_range(values: impl Iterator<Item = f64>, log: bool) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite() && (!log || *v > 0.0)) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return if log { (0.1, 10.0) } else { (0.0, 1.0) };
    }
    if log {
        if hi <= lo {
            return (lo / 10.0, hi * 10.0);
        }
        let f = (hi / lo).powf(0.05);
        (lo / f, hi * f)
    } else {
        if hi <= lo {
            let d = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
            return (lo - d, hi + d);
        }
        let d = 0.05 * (hi - lo);
        (lo - d, hi + d)
    }
}

fn valid_range(r: (f64, f64), log: bool) -> (f64, f64) {
    let (a, b) = r;
    if a.is_finite() && b.is_finite() && b > a && (!log || a > 0.0) {
        (a, b)
    } else {
        auto_range([a, b].into_iter(), log)
    }
}

type Area<'a> = DrawingArea<BitMapBackend<'a>, Shift>;
type PlotResult = std::result::Result<(), Box<dyn std::error::Error>>;

/// Runs `draw` on a white `width x height` canvas drawn at `SS` times the size.
fn canvas(width: u32, height: u32, draw: impl FnOnce(&Area) -> PlotResult) -> Image {
    register_plot_font();
    let (w, h) = (width.max(64) * SS, height.max(64) * SS);
    let mut buf = vec![255u8; 3 * w as usize * h as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        let r = root
            .fill(&WHITE)
            .map_err(|e| e.into())
            .and_then(|_| draw(&root));
        if let Err(e) = r {
            panic!("plotting into an in-memory buffer failed: {e}");
        }
        root.present().expect("presenting an in-memory plot");
    }
    Image {
        width: w,
        height: h,
        rgb: buf,
    }
    .downsample(SS)
}

fn font(size: u32) -> TextStyle<'static> {
    ("sans-serif", (size * SS) as f64).into_font().color(&BLACK)
}

/// A line plot of named series with a title, axis labels and a legend.
pub fn line_plot(spec: &PlotSpec) -> Image {
    let xr = valid_range(
        spec.x_range.unwrap_or_else(|| {
            auto_range(
                spec.series
                    .iter()
                    .flat_map(|s| s.points.iter().map(|p| p.0)),
                false,
            )
        }),
        false,
    );
    let yr = valid_range(
        spec.y_range.unwrap_or_else(|| {
            auto_range(
                spec.series
                    .iter()
                    .flat_map(|s| s.points.iter().map(|p| p.1)),
                spec.log_y,
            )
        }),
        spec.log_y,
    );
    canvas(spec.width, spec.height, |root| {
        if spec.log_y {
            line_chart(root, spec, xr.0..xr.1, (yr.0..yr.1).log_scale())
        } else {
            line_chart(root, spec, xr.0..xr.1, yr.0..yr.1)
        }
    })
}

fn styled_mesh<'a, X, Y>(
    chart: &mut ChartContext<'a, BitMapBackend<'a>, Cartesian2d<X, Y>>,
    x_label: &str,
    y_label: &str,
) -> PlotResult
where
    X: Ranged<ValueType = f64> + ValueFormatter<f64>,
    Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .label_style(font(14))
        .axis_desc_style(font(16))
        .bold_line_style(RGBColor(220, 220, 220).stroke_width(SS))
        .light_line_style(RGBColor(242, 242, 242).stroke_width(SS))
        .max_light_lines(4)
        .axis_style(BLACK.stroke_width(SS))
        .x_labels(8)
        .y_labels(8)
        .draw()?;
    Ok(())
}

fn line_chart<Y>(root: &Area, spec: &PlotSpec, xr: Range<f64>, yr: Y) -> PlotResult
where
    Y: AsRangedCoord<Value = f64>,
    Y::CoordDescType: ValueFormatter<f64>,
{
    let mut chart = ChartBuilder::on(root)
        .caption(&spec.title, font(20))
        .margin(12 * SS)
        .x_label_area_size(52 * SS)
        .y_label_area_size(78 * SS)
        .build_cartesian_2d(xr, yr)?;
    styled_mesh(&mut chart, &spec.x_label, &spec.y_label)?;
    let mut named = false;
    for (i, s) in spec.series.iter().enumerate() {
        let c = rgb(s.colour.unwrap_or(PALETTE[i % PALETTE.len()]));
        let style = c.stroke_width(2 * SS);
        for seg in segments(&s.points, spec.log_y) {
            if s.dashed {
                chart.draw_series(DashedLineSeries::new(seg.clone(), 9 * SS, 6 * SS, style))?;
            } else {
                chart.draw_series(LineSeries::new(seg.clone(), style))?;
            }
            if s.markers {
                chart.draw_series(seg.iter().map(|p| Circle::new(*p, 3 * SS, c.filled())))?;
            }
        }
        if !s.name.is_empty() {
            named = true;
            let dashed = s.dashed;
            chart
                .draw_series(std::iter::once(PathElement::new(
                    Vec::<(f64, f64)>::new(),
                    style,
                )))?
                .label(s.name.clone())
                .legend(move |(x, y)| {
                    let len = 24 * SS as i32;
                    if dashed {
                        let d = 6 * SS as i32;
                        EmptyElement::at((x, y))
                            + PathElement::new(vec![(0, 0), (d, 0)], style)
                            + PathElement::new(vec![(len - d, 0), (len, 0)], style)
                    } else {
                        EmptyElement::at((x, y))
                            + PathElement::new(vec![(0, 0), (len / 2, 0)], style)
                            + PathElement::new(vec![(len / 2, 0), (len, 0)], style)
                    }
                });
        }
    }
    let pos = match spec.legend {
        LegendPosition::UpperLeft => Some(SeriesLabelPosition::UpperLeft),
        LegendPosition::UpperRight => Some(SeriesLabelPosition::UpperRight),
        LegendPosition::LowerLeft => Some(SeriesLabelPosition::LowerLeft),
        LegendPosition::LowerRight => Some(SeriesLabelPosition::LowerRight),
        LegendPosition::Hidden => None,
    };
    if let (true, Some(pos)) = (named, pos) {
        chart
            .configure_series_labels()
            .position(pos)
            .margin(10 * SS)
            .legend_area_size(30 * SS)
            .label_font(font(14))
            .background_style(WHITE.mix(0.9))
            .border_style(RGBColor(160, 160, 160).stroke_width(SS))
            .draw()?;
    }
    Ok(())
}

/// Draws a vertical colour bar for `range` (viridis) with its label, in `area`.
fn colour_bar(area: &Area, range: (f64, f64), label: &str, top: u32, bottom: u32) -> PlotResult {
    let mut bar = ChartBuilder::on(area)
        .margin_top(top)
        .margin_bottom(bottom)
        .margin_right(8 * SS)
        .y_label_area_size(0)
        .right_y_label_area_size(62 * SS)
        .build_cartesian_2d(0.0..1.0, range.0..range.1)?;
    bar.configure_mesh()
        .disable_x_mesh()
        .disable_y_mesh()
        .disable_x_axis()
        .label_style(font(13))
        .axis_style(BLACK.stroke_width(SS))
        .y_labels(6)
        .draw()?;
    let n = 128;
    let (a, b) = range;
    bar.draw_series((0..n).map(|i| {
        let y0 = a + (b - a) * i as f64 / n as f64;
        let y1 = a + (b - a) * (i + 1) as f64 / n as f64;
        Rectangle::new(
            [(0.0, y0), (1.0, y1)],
            rgb(viridis((i as f64 + 0.5) / n as f64)).filled(),
        )
    }))?;
    bar.draw_series(std::iter::once(Rectangle::new(
        [(0.0, a), (1.0, b)],
        BLACK.stroke_width(SS),
    )))?;
    // The label reads bottom to top, like the y axis label of the plot.
    let (w, h) = area.dim_in_pixel();
    let mid = (top as i32 + h as i32 - bottom as i32) / 2;
    let style = font(15)
        .transform(FontTransform::Rotate270)
        .pos(Pos::new(HPos::Center, VPos::Center));
    area.draw_text(label, &style, (w as i32 - 14 * SS as i32, mid))?;
    Ok(())
}

fn time_range(times: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for t in times.filter(|t| t.is_finite()) {
        lo = lo.min(t);
        hi = hi.max(t);
    }
    if !lo.is_finite() {
        (0.0, 1.0)
    } else if hi <= lo {
        (lo - 0.5, lo + 0.5)
    } else {
        (lo, hi)
    }
}

/// Colour bar width, and the chart margins the bar repeats to line up with the plot.
const BAR_W: u32 = 120;

/// Profiles of a quantity along the mouth width, one curve per time coloured by time
/// (viridis, early = dark purple, late = yellow), with a colour bar.
pub fn profile_plot(spec: &ProfileSpec) -> Image {
    let xr = valid_range(auto_range_exact(spec.x.iter().copied()), false);
    let yr = valid_range(
        spec.y_range.unwrap_or_else(|| {
            auto_range(
                spec.profiles.iter().flat_map(|p| p.1.iter().copied()),
                false,
            )
        }),
        false,
    );
    let tr = time_range(spec.profiles.iter().map(|p| p.0));
    canvas(spec.width, spec.height, |root| {
        let (w, _) = root.dim_in_pixel();
        let (left, right) = root.split_horizontally(w.saturating_sub(BAR_W * SS));
        let mut chart = ChartBuilder::on(&left)
            .caption(&spec.title, font(20))
            .margin(12 * SS)
            .x_label_area_size(52 * SS)
            .y_label_area_size(78 * SS)
            .build_cartesian_2d(xr.0..xr.1, yr.0..yr.1)?;
        styled_mesh(&mut chart, &spec.x_label, &spec.y_label)?;
        for (t, values) in &spec.profiles {
            let c = rgb(viridis((t - tr.0) / (tr.1 - tr.0)));
            let pts: Vec<(f64, f64)> = spec.x.iter().copied().zip(values.iter().copied()).collect();
            for seg in segments(&pts, false) {
                chart.draw_series(LineSeries::new(seg, c.stroke_width(2 * SS)))?;
            }
        }
        // Line the bar up with the plotting area: caption + margin on top, label area below.
        let top = chart.plotting_area().get_pixel_range().1.start as u32;
        let bottom =
            (left.dim_in_pixel().1 as i32 - chart.plotting_area().get_pixel_range().1.end) as u32;
        colour_bar(&right, tr, &spec.colour_label, top, bottom)
    })
}

/// The profiles as a map: position along x, time up, colour = value (viridis), with a
/// colour bar for the values. Cells are centred on the sample positions and times.
pub fn heatmap_plot(spec: &ProfileSpec) -> Image {
    let xr = valid_range(auto_range_exact(spec.x.iter().copied()), false);
    let tr = time_range(spec.profiles.iter().map(|p| p.0));
    let vr = valid_range(
        spec.y_range.unwrap_or_else(|| {
            auto_range_exact(spec.profiles.iter().flat_map(|p| p.1.iter().copied()))
        }),
        false,
    );
    // Cell bounds: midpoints between samples.
    let bounds = |v: &[f64]| -> Vec<(f64, f64)> {
        (0..v.len())
            .map(|i| {
                let lo = if i == 0 {
                    if v.len() > 1 {
                        v[0] - 0.5 * (v[1] - v[0])
                    } else {
                        v[0] - 0.5
                    }
                } else {
                    0.5 * (v[i - 1] + v[i])
                };
                let hi = if i + 1 == v.len() {
                    if v.len() > 1 {
                        v[i] + 0.5 * (v[i] - v[i - 1])
                    } else {
                        v[i] + 0.5
                    }
                } else {
                    0.5 * (v[i] + v[i + 1])
                };
                (lo, hi)
            })
            .collect()
    };
    let xb = bounds(&spec.x);
    let times: Vec<f64> = spec.profiles.iter().map(|p| p.0).collect();
    let tb = bounds(&times);
    let x_lo = xb.first().map(|b| b.0.min(xr.0)).unwrap_or(xr.0);
    let x_hi = xb.last().map(|b| b.1.max(xr.1)).unwrap_or(xr.1);
    let t_lo = tb.first().map(|b| b.0).unwrap_or(tr.0);
    let t_hi = tb.last().map(|b| b.1).unwrap_or(tr.1);
    let (t_lo, t_hi) = valid_range((t_lo.min(t_hi), t_hi.max(t_lo)), false);
    canvas(spec.width, spec.height, |root| {
        let (w, _) = root.dim_in_pixel();
        let (left, right) = root.split_horizontally(w.saturating_sub(BAR_W * SS));
        let mut chart = ChartBuilder::on(&left)
            .caption(&spec.title, font(20))
            .margin(12 * SS)
            .x_label_area_size(52 * SS)
            .y_label_area_size(78 * SS)
            .build_cartesian_2d(x_lo..x_hi, t_lo..t_hi)?;
        for (j, (_, values)) in spec.profiles.iter().enumerate() {
            let (t0, t1) = tb[j];
            chart.draw_series(values.iter().zip(&xb).filter(|(v, _)| v.is_finite()).map(
                |(v, &(x0, x1))| {
                    let c = viridis((v - vr.0) / (vr.1 - vr.0));
                    Rectangle::new([(x0, t0), (x1, t1)], rgb(c).filled())
                },
            ))?;
        }
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc(&spec.x_label)
            .y_desc(&spec.colour_label)
            .label_style(font(14))
            .axis_desc_style(font(16))
            .axis_style(BLACK.stroke_width(SS))
            .x_labels(8)
            .y_labels(8)
            .draw()?;
        let top = chart.plotting_area().get_pixel_range().1.start as u32;
        let bottom =
            (left.dim_in_pixel().1 as i32 - chart.plotting_area().get_pixel_range().1.end) as u32;
        colour_bar(&right, vr, &spec.y_label, top, bottom)
    })
}

/// Range of the finite values without padding.
fn auto_range_exact(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        (0.0, 1.0)
    } else if hi <= lo {
        let d = if lo == 0.0 { 1.0 } else { 0.1 * lo.abs() };
        (lo - d, hi + d)
    } else {
        (lo, hi)
    }
}
