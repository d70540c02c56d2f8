//! Figures of the HTML report, drawn with `plotters` into inline SVG strings.

use plotters::coord::ranged1d::{AsRangedCoord, ValueFormatter};
use plotters::coord::Shift;
use plotters::prelude::*;

/// Ideal run (green, as in the Rerun and Foxglove views).
pub const IDEAL: RGBColor = RGBColor(46, 160, 64);
/// Simulated run (orange).
pub const SIM: RGBColor = RGBColor(240, 130, 0);
/// Goal, thresholds, failures (red).
pub const RED: RGBColor = RGBColor(210, 30, 40);
/// Neutral series (blue).
pub const BLUE: RGBColor = RGBColor(31, 100, 200);
/// Start marker (grey).
pub const GREY: RGBColor = RGBColor(90, 90, 90);
/// A recorded run's path (`[compare] reference`).
pub const REAL: RGBColor = RGBColor(140, 140, 148);

const PALETTE: [RGBColor; 8] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(23, 190, 207),
];

/// Colour of plan label `k` (segment shading, legend).
pub(crate) fn label_color(k: usize) -> RGBColor {
    PALETTE[k % PALETTE.len()]
}

/// Series colour `k` for charts with several neutral lines.
pub(crate) fn series_color(k: usize) -> RGBColor {
    PALETTE[k % PALETTE.len()]
}

/// One line of a time chart; `None` values break the line.
pub struct Line<'a> {
    /// Legend name (empty: none, as for a line that shares its neighbour's).
    pub name: String,
    /// Times, s.
    pub t: &'a [f32],
    /// Values (already in display units).
    pub v: Vec<Option<f64>>,
    /// Colour.
    pub color: RGBColor,
    /// Zero-order hold between samples (commands).
    pub step: bool,
}

/// A horizontal reference line (threshold).
pub struct HLine {
    /// Height.
    pub y: f64,
    /// Legend name (empty: none).
    pub name: String,
    /// Colour.
    pub color: RGBColor,
}

/// A shaded time span (plan segment) with its label index.
pub type Shade = (f64, f64, usize);

/// A chart could not be drawn (plotters refused; drawing into a string has
/// no I/O, so this is an internal failure).
#[derive(Debug, thiserror::Error)]
// The message has always shown plotters' own description of the failure,
// which is its `Debug` form (its `Display` drops the backend's detail).
#[error("plot failed: {source}")]
pub struct PlotError {
    /// What plotters reported.
    #[source]
    source: Box<dyn std::error::Error + Send + Sync>,
}

type Res<T> = Result<T, PlotError>;

/// The legend every chart uses: upper right, translucent white box.
fn legend<'a, DB, CT>(chart: &mut ChartContext<'a, DB, CT>) -> Res<()>
where
    DB: DrawingBackend + 'a,
    DB::ErrorType: 'static,
    CT: CoordTranslate,
{
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.85))
        .border_style(RGBColor(200, 200, 200))
        .label_font(("sans-serif", 11))
        .draw()
        .map_err(err)
}

fn err<E: std::error::Error + Send + Sync + 'static>(e: E) -> PlotError {
    PlotError {
        source: Box::new(e),
    }
}

/// Finite [min, max] of values, padded; never empty.
fn range(vals: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in vals.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (-1.0, 1.0);
    }
    let span = hi - lo;
    if span <= 1e-12 * lo.abs().max(hi.abs()).max(1e-300) {
        let pad = (0.1 * lo.abs()).max(1e-9);
        return (lo - pad, hi + pad);
    }
    (lo - 0.06 * span, hi + 0.06 * span)
}

/// Contiguous runs of finite points.
fn runs(t: &[f32], v: &[Option<f64>], step: bool) -> Vec<Vec<(f64, f64)>> {
    let mut out: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut cur: Vec<(f64, f64)> = Vec::new();
    for (k, (&tk, vk)) in t.iter().zip(v).enumerate() {
        match vk {
            Some(y) if y.is_finite() => {
                if step {
                    if let Some(&(_, prev)) = cur.last() {
                        cur.push((tk as f64, prev));
                    }
                }
                cur.push((tk as f64, *y));
                let _ = k;
            }
            _ => {
                if !cur.is_empty() {
                    out.push(std::mem::take(&mut cur));
                }
            }
        }
    }
    if !cur.is_empty() {
        out.push(cur);
    }
    out
}

fn svg(
    w: u32,
    h: u32,
    draw: impl FnOnce(DrawingArea<SVGBackend<'_>, Shift>) -> Res<()>,
) -> Res<String> {
    let mut buf = String::new();
    {
        let root = SVGBackend::with_string(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(err)?;
        draw(root.clone())?;
        root.present().map_err(err)?;
    }
    Ok(buf)
}

/// A chart over time: lines, threshold lines, shaded plan segments.
pub(crate) fn time_chart(
    title: &str,
    y_desc: &str,
    lines: &[Line<'_>],
    hlines: &[HLine],
    shades: &[Shade],
    t_end: f64,
) -> Res<String> {
    let (y0, y1) = range(
        lines
            .iter()
            .flat_map(|l| l.v.iter().flatten().copied())
            .chain(hlines.iter().map(|h| h.y)),
    );
    let entries = lines.iter().filter(|l| !l.name.is_empty()).count()
        + hlines.iter().filter(|h| !h.name.is_empty()).count();
    // About 176 px of plot area: the legend's rows get their own band above the data.
    let y1 = y1 + (y1 - y0) * headroom(entries, 176.0);
    let t_end = if t_end > 0.0 { t_end } else { 1.0 };
    svg(560, 240, |root| {
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 15))
            .margin(6)
            .x_label_area_size(30)
            .y_label_area_size(62)
            .build_cartesian_2d(0.0..t_end, y0..y1)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc("t (s)")
            .y_desc(y_desc)
            .label_style(("sans-serif", 11))
            .axis_desc_style(("sans-serif", 12))
            // Only the labelled grid lines: the light ones were a third of the
            // report's bytes and add little to a 560-pixel chart.
            .max_light_lines(0)
            .bold_line_style(RGBColor(215, 215, 215))
            .y_label_formatter(&|v| tick(*v))
            .draw()
            .map_err(err)?;
        chart
            .draw_series(shades.iter().map(|&(a, b, k)| {
                Rectangle::new([(a, y0), (b, y1)], label_color(k).mix(0.10).filled())
            }))
            .map_err(err)?;
        for h in hlines {
            let s = chart
                .draw_series(DashedLineSeries::new(
                    [(0.0, h.y), (t_end, h.y)],
                    6,
                    4,
                    h.color.stroke_width(1),
                ))
                .map_err(err)?;
            if !h.name.is_empty() {
                let c = h.color;
                s.label(h.name.clone())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 14, y)], c));
            }
        }
        for l in lines {
            let c = l.color;
            let mut first = true;
            for run in runs(l.t, &l.v, l.step) {
                let s = chart
                    .draw_series(LineSeries::new(run, c.stroke_width(1)))
                    .map_err(err)?;
                if first && !l.name.is_empty() {
                    s.label(l.name.clone()).legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 14, y)], c.stroke_width(2))
                    });
                    first = false;
                }
            }
        }
        legend(&mut chart)?;
        Ok(())
    })
}

/// How much to extend a value axis (as a fraction of its span) so that a
/// legend of `entries` rows in the upper right corner sits above the data, on
/// a plot area `plot_px` high (a legend on the data hid a car's speed bump).
fn headroom(entries: usize, plot_px: f64) -> f64 {
    if entries == 0 {
        return 0.0;
    }
    let legend_px = (10.0 + 16.0 * entries as f64).min(0.6 * plot_px);
    legend_px / (plot_px - legend_px)
}

/// Tick label: short, without float noise.
fn tick(v: f64) -> String {
    let a = v.abs();
    // Float noise around zero (e.g. -1.1e-16 on a metre axis) reads as 0.
    if a < 1e-12 {
        "0".into()
    } else if !(1e-3..1e5).contains(&a) {
        format!("{v:.1e}")
    } else {
        let s = format!("{v:.4}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        s.to_string()
    }
}

/// A polyline in the plane.
pub struct Path2<'a> {
    /// Legend name.
    pub name: &'a str,
    /// Points.
    pub points: Vec<(f64, f64)>,
    /// Colour.
    pub color: RGBColor,
    /// Width in px.
    pub width: u32,
}

/// A marker in the plane.
pub struct Marker<'a> {
    /// Legend name.
    pub name: &'a str,
    /// Where.
    pub at: (f64, f64),
    /// Heading arrow (world yaw, rad), if any.
    pub heading: Option<f64>,
    /// Colour.
    pub color: RGBColor,
}

/// The planar path, equal axis scales: paths, overlays, start/goal markers.
pub(crate) fn path_chart(paths: &[Path2<'_>], markers: &[Marker<'_>]) -> Res<String> {
    let pts = || {
        paths
            .iter()
            .flat_map(|p| p.points.iter().copied())
            .chain(markers.iter().map(|m| m.at))
            .filter(|(x, y)| x.is_finite() && y.is_finite())
    };
    let (mut x0, mut x1) = range(pts().map(|p| p.0));
    let (mut y0, mut y1) = range(pts().map(|p| p.1));
    // A band above the paths for the legend (one row per distinct name).
    let mut names: Vec<&str> = paths.iter().map(|p| p.name).collect();
    names.extend(markers.iter().map(|m| m.name));
    names.retain(|n| !n.is_empty());
    names.sort();
    names.dedup();
    y1 += (y1 - y0).max(x1 - x0) * headroom(names.len(), 490.0);
    // Equal scales: widen the narrower axis (plot area is square).
    let (w, h) = (x1 - x0, y1 - y0);
    if w > h {
        let c = 0.5 * (y0 + y1);
        (y0, y1) = (c - 0.5 * w, c + 0.5 * w);
    } else {
        let c = 0.5 * (x0 + x1);
        (x0, x1) = (c - 0.5 * h, c + 0.5 * h);
    }
    let arrow = 0.06 * (x1 - x0);
    svg(600, 580, |root| {
        let mut chart = ChartBuilder::on(&root)
            .caption("planar path: ideal vs simulated", ("sans-serif", 15))
            .margin(8)
            .x_label_area_size(32)
            .y_label_area_size(56)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc("x (m)")
            .y_desc("y (m)")
            .label_style(("sans-serif", 11))
            .axis_desc_style(("sans-serif", 12))
            // Only the labelled grid lines: the light ones were a third of the
            // report's bytes and add little to a 560-pixel chart.
            .max_light_lines(0)
            .bold_line_style(RGBColor(215, 215, 215))
            .x_label_formatter(&|v| tick(*v))
            .y_label_formatter(&|v| tick(*v))
            .draw()
            .map_err(err)?;
        // One legend entry per name: a scene's obstacles share one (a door's
        // wall segments each drawn as several rings would fill the legend
        // and cover the plot).
        let mut named: Vec<&str> = Vec::new();
        for p in paths {
            let c = p.color;
            let wdt = p.width;
            let series = chart
                .draw_series(LineSeries::new(
                    p.points.iter().copied(),
                    c.stroke_width(wdt),
                ))
                .map_err(err)?;
            if !p.name.is_empty() && !named.contains(&p.name) {
                named.push(p.name);
                series.label(p.name).legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 14, y)], c.stroke_width(2))
                });
            }
        }
        for m in markers {
            let c = m.color;
            let series = chart
                .draw_series([Circle::new(m.at, 5, c.filled())])
                .map_err(err)?;
            // Several robots' starts and goals: one entry each.
            if !named.contains(&m.name) {
                named.push(m.name);
                series
                    .label(m.name)
                    .legend(move |(x, y)| Circle::new((x + 7, y), 4, c.filled()));
            }
            if let Some(hd) = m.heading {
                let tip = (m.at.0 + arrow * hd.cos(), m.at.1 + arrow * hd.sin());
                chart
                    .draw_series([PathElement::new(vec![m.at, tip], c.stroke_width(2))])
                    .map_err(err)?;
            }
        }
        legend(&mut chart)?;
        Ok(())
    })
}

/// Histogram of `values` with `bins` equal bins; optional vertical line (e.g. success limit).
pub(crate) fn histogram(
    title: &str,
    x_desc: &str,
    values: &[f64],
    bins: usize,
    vline: Option<(f64, &str)>,
) -> Res<String> {
    let finite: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    let (mut lo, mut hi) = range(finite.iter().copied().chain(vline.map(|v| v.0)));
    if finite.is_empty() {
        (lo, hi) = (0.0, 1.0);
    }
    let bins = bins.max(1);
    let width = (hi - lo) / bins as f64;
    let mut counts = vec![0u32; bins];
    for v in &finite {
        let k = (((v - lo) / width) as usize).min(bins - 1);
        counts[k] += 1;
    }
    let top = counts.iter().copied().max().unwrap_or(0).max(1) as f64 * 1.15;
    svg(560, 260, |root| {
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 15))
            .margin(6)
            .x_label_area_size(30)
            .y_label_area_size(44)
            .build_cartesian_2d(lo..hi, 0.0..top)
            .map_err(err)?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc("variants")
            .label_style(("sans-serif", 11))
            .axis_desc_style(("sans-serif", 12))
            // Only the labelled grid lines: the light ones were a third of the
            // report's bytes and add little to a 560-pixel chart.
            .max_light_lines(0)
            .x_label_formatter(&|v| tick(*v))
            .draw()
            .map_err(err)?;
        chart
            .draw_series(counts.iter().enumerate().map(|(k, &c)| {
                let a = lo + k as f64 * width;
                Rectangle::new([(a, 0.0), (a + width, c as f64)], BLUE.mix(0.6).filled())
            }))
            .map_err(err)?;
        if let Some((x, name)) = vline {
            chart
                .draw_series(DashedLineSeries::new(
                    [(x, 0.0), (x, top)],
                    6,
                    4,
                    RED.stroke_width(2),
                ))
                .map_err(err)?
                .label(name)
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 14, y)], RED));
            legend(&mut chart)?;
        }
        Ok(())
    })
}

/// Scatter of `(x, y, success)`, successes green, failures red; optional horizontal limit.
pub(crate) fn scatter(
    title: &str,
    x_desc: &str,
    y_desc: &str,
    pts: &[(f64, f64, bool)],
    hline: Option<(f64, &str)>,
) -> Res<String> {
    let (x0, x1) = range(pts.iter().map(|p| p.0));
    let axes = Axes {
        title,
        x_desc,
        y_desc,
        names: ["success", "failure"],
        // Only the labelled grid lines: the light ones were a third of the
        // report's bytes and add little to a 560-pixel chart.
        light_grid: false,
    };
    scatter_on(&axes, x0..x1, (x0, x1), |x| x.is_finite(), pts, hline)
}

/// [`scatter`] on a logarithmic x axis (x > 0 only: a margin search's
/// levels span decades, the edge is where they crowd).
pub(crate) fn scatter_log_x(
    title: &str,
    x_desc: &str,
    y_desc: &str,
    pts: &[(f64, f64, bool)],
    hline: Option<(f64, &str)>,
) -> Res<String> {
    let on_axis = |x: f64| x > 0.0 && x.is_finite();
    let xs = pts.iter().map(|p| p.0).filter(|x| on_axis(*x));
    let (lo, hi) = xs.fold((f64::INFINITY, 0.0f64), |(a, b), x| (a.min(x), b.max(x)));
    let (x0, x1) = if lo.is_finite() && hi > 0.0 {
        (lo / 1.5, hi * 1.5)
    } else {
        (1e-3, 1.0)
    };
    let axes = Axes {
        title,
        x_desc,
        y_desc,
        names: ["pass", "fail"],
        light_grid: true,
    };
    let (bold, light) = log_ticks(x0, x1);
    let x = (x0..x1)
        .log_scale()
        .with_key_points(bold)
        .with_light_points(light);
    scatter_on(&axes, x, (x0, x1), on_axis, pts, hline)
}

/// Labelled ticks 1, 2, 5 × 10^k within [x0, x1] (every 1..9 × 10^k when
/// that leaves fewer than two) and light grid lines at 1..9 × 10^k: plotters'
/// own log axis labels only from the first power of ten on, which leaves a
/// range like 0.013–0.25 with labels at 0.1 and 0.2 alone.
fn log_ticks(x0: f64, x1: f64) -> (Vec<f64>, Vec<f64>) {
    let decades = x0.log10().floor() as i32..=x1.log10().ceil() as i32;
    let within = |mantissas: &[f64]| -> Vec<f64> {
        decades
            .clone()
            .flat_map(|e| mantissas.iter().map(move |m| m * 10f64.powi(e)))
            .filter(|v| (x0..=x1).contains(v))
            .collect()
    };
    let every: Vec<f64> = (1..10).map(f64::from).collect();
    let mut bold = within(&[1.0, 2.0, 5.0]);
    if bold.len() < 2 {
        bold = within(&every);
    }
    (bold, within(&every))
}

/// Titles, legend names (pass, fail) and grid of a scatter chart.
struct Axes<'s> {
    title: &'s str,
    x_desc: &'s str,
    y_desc: &'s str,
    names: [&'s str; 2],
    light_grid: bool,
}

/// A scatter chart on the x axis `x` (spanning `xs`): the points whose x
/// `on_axis` accepts, green when they pass and red when they fail, a dashed
/// red line at `hline`, and the legend; shared by the linear and the
/// logarithmic x axis.
fn scatter_on<XR>(
    axes: &Axes<'_>,
    x: XR,
    (x0, x1): (f64, f64),
    on_axis: impl Fn(f64) -> bool,
    pts: &[(f64, f64, bool)],
    hline: Option<(f64, &str)>,
) -> Res<String>
where
    XR: AsRangedCoord<Value = f64>,
    XR::CoordDescType: ValueFormatter<f64>,
{
    let (y0, y1) = range(pts.iter().map(|p| p.1).chain(hline.map(|h| h.0)));
    // Headroom for the legend, so it never hides points.
    let y1 = y1 + 0.3 * (y1 - y0);
    svg(560, 260, |root| {
        let mut chart = ChartBuilder::on(&root)
            .caption(axes.title, ("sans-serif", 15))
            .margin(6)
            .x_label_area_size(30)
            .y_label_area_size(56)
            .build_cartesian_2d(x, y0..y1)
            .map_err(err)?;
        let mut mesh = chart.configure_mesh();
        mesh.x_desc(axes.x_desc)
            .y_desc(axes.y_desc)
            .label_style(("sans-serif", 11))
            .axis_desc_style(("sans-serif", 12))
            .x_label_formatter(&|v| tick(*v))
            .y_label_formatter(&|v| tick(*v));
        if axes.light_grid {
            mesh.light_line_style(RGBColor(238, 238, 238));
        } else {
            mesh.max_light_lines(0);
        }
        mesh.draw().map_err(err)?;
        for (ok, color, name) in [(true, IDEAL, axes.names[0]), (false, RED, axes.names[1])] {
            let sel: Vec<(f64, f64)> = pts
                .iter()
                .filter(|p| p.2 == ok && on_axis(p.0) && p.1.is_finite())
                .map(|p| (p.0, p.1))
                .collect();
            if sel.is_empty() {
                continue;
            }
            chart
                .draw_series(sel.into_iter().map(|p| Circle::new(p, 3, color.filled())))
                .map_err(err)?
                .label(name)
                .legend(move |(x, y)| Circle::new((x + 7, y), 3, color.filled()));
        }
        if let Some((y, name)) = hline {
            chart
                .draw_series(DashedLineSeries::new(
                    [(x0, y), (x1, y)],
                    6,
                    4,
                    RED.stroke_width(1),
                ))
                .map_err(err)?
                .label(name)
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 14, y)], RED));
        }
        legend(&mut chart)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The text of every `<text>` element of an SVG, trimmed.
    fn svg_texts(svg: &str) -> Vec<&str> {
        svg.split("<text")
            .skip(1)
            .filter_map(|t| t.split_once('>').and_then(|(_, r)| r.split_once('<')))
            .map(|(t, _)| t.trim())
            .collect()
    }

    #[test]
    fn log_axis_labels_every_decade_it_spans() {
        let (bold, light) = log_ticks(0.0134, 0.25);
        assert_eq!(bold.len(), 4, "{bold:?}");
        for (b, want) in bold.iter().zip([0.02, 0.05, 0.1, 0.2]) {
            assert!((b / want - 1.0).abs() < 1e-12, "{bold:?}");
        }
        assert_eq!(light.len(), 10, "{light:?}"); // 0.02..0.09, 0.1, 0.2
                                                  // Between 2 and 5 there is no 1-2-5 tick: every integer mantissa.
        let (bold, _) = log_ticks(2.1, 4.8);
        assert_eq!(bold, vec![3.0, 4.0]);
        let svg = scatter_log_x(
            "t",
            "x",
            "y",
            &[(0.02, 1.0, true), (0.17, 2.0, false)],
            None,
        )
        .unwrap();
        let texts = svg_texts(&svg);
        for label in ["0.02", "0.05", "0.1", "0.2"] {
            assert!(texts.contains(&label), "{label} missing: {texts:?}");
        }
    }

    /// Paths that share a name share one legend entry (a door's segments
    /// are all "obstacles"); an unnamed path has none.
    #[test]
    fn a_legend_names_each_path_name_once() {
        // Two robots' goals and starts: one entry each too.
        let marker = |name, y: f64| Marker {
            name,
            at: (0.5, y),
            heading: None,
            color: RED,
        };
        let path = |name, y: f64| Path2 {
            name,
            points: vec![(0.0, y), (1.0, y)],
            color: IDEAL,
            width: 1,
        };
        let svg = path_chart(
            &[
                path("obstacles", 0.0),
                path("obstacles", 1.0),
                path("obstacles", 2.0),
                path("", 3.0),
                path("ideal", 4.0),
            ],
            &[
                marker("goal", 0.0),
                marker("goal", 1.0),
                marker("start", 2.0),
                marker("start", 3.0),
            ],
        )
        .unwrap();
        let texts = svg_texts(&svg);
        for name in ["obstacles", "ideal", "goal", "start"] {
            assert_eq!(
                texts.iter().filter(|t| **t == name).count(),
                1,
                "{name}: {texts:?}"
            );
        }
    }

    #[test]
    fn runs_break_at_missing_values() {
        let t = [0.0f32, 1.0, 2.0, 3.0, 4.0];
        let v = [Some(1.0), Some(2.0), None, Some(3.0), Some(f64::NAN)];
        assert_eq!(
            runs(&t, &v, false),
            vec![vec![(0.0, 1.0), (1.0, 2.0)], vec![(3.0, 3.0)]]
        );
        // Steps hold the previous value until the next sample.
        assert_eq!(
            runs(&t[..2], &v[..2], true),
            vec![vec![(0.0, 1.0), (1.0, 1.0), (1.0, 2.0)]]
        );
    }

    #[test]
    fn charts_are_svg_with_the_series() {
        let t = [0.0f32, 1.0, 2.0];
        let line = Line {
            name: "x ideal".into(),
            t: &t,
            v: vec![Some(0.0), Some(1.0), Some(0.5)],
            color: IDEAL,
            step: false,
        };
        let h = HLine {
            y: 0.8,
            name: "limit".into(),
            color: RED,
        };
        let s = time_chart("x", "x (m)", &[line], &[h], &[(0.0, 1.0, 0)], 2.0).unwrap();
        assert!(s.starts_with("<svg") && s.contains("x ideal") && s.contains("limit"));
        assert!(s.contains("<polyline"));
        // Degenerate ranges still draw.
        assert!(histogram("h", "e", &[], 10, None)
            .unwrap()
            .starts_with("<svg"));
        assert!(scatter("s", "a", "b", &[(1.0, 1.0, true)], Some((0.5, "max"))).is_ok());
        let s = scatter_log_x(
            "s",
            "a",
            "b",
            &[(1e-6, 1.0, true), (0.1, 2.0, false), (0.0, 0.0, true)],
            None,
        )
        .unwrap();
        assert!(s.starts_with("<svg") && s.contains("fail"));
    }
}
