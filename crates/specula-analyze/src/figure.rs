//! A figure as a report shows it, drawn with `plotters` into a PNG (its bitmap backend, text
//! from a font compiled in: `epaint_default_fonts`' Ubuntu Light, registered from bytes so that
//! no system font is needed) and an SVG (its SVG backend, the raster embedded as a PNG): a
//! title; the raster filling the plotting area pixel for pixel; labelled axes with ticks; marks
//! over the raster in axis units (lines, iso-lines with their values, filled boxes, text); a
//! colour bar with its ticks and label; and a legend.
//!
//! Colour scales are `colorous`' viridis ([`scale_colour`]); iso-lines come from the `contour`
//! crate ([`iso_lines`]).

use base64::Engine;
use image::RgbImage;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::FontStyle;

/// The family every text of a figure is written in.
const FONT: &str = "sans-serif";
const TITLE_PX: f64 = 16.0;
const TEXT_PX: f64 = 13.0;
const LEGEND_ROW: u32 = 18;
const BAR_HEIGHT: u32 = 14;
/// Room for the colour bar, its ticks and its label.
const BAR_AREA: u32 = BAR_HEIGHT + 44;

/// A plot: the PNG (text drawn in) and the SVG (vector text around the embedded raster).
pub struct Plot {
    pub png: RgbImage,
    pub svg: String,
}

/// An axis: its label and the values at its two ends (left then right, bottom then top: a
/// `y` axis from a larger to a smaller value runs down the page).
#[derive(Clone, Debug)]
pub struct Axis {
    pub label: String,
    pub ends: (f64, f64),
}

impl Axis {
    pub fn new(label: impl Into<String>, ends: (f64, f64)) -> Axis {
        Axis {
            label: label.into(),
            ends,
        }
    }
}

/// A colour scale shown as a bar under the plot.
#[derive(Clone, Debug)]
pub struct ColourBar {
    pub label: String,
    /// The values at the scale's two ends.
    pub range: (f64, f64),
    /// Whether the scale runs over the logarithm of the value.
    pub log: bool,
}

impl ColourBar {
    /// The colour of `value` on this scale.
    pub fn colour(&self, value: f64) -> [u8; 3] {
        scale_colour(self.fraction(value))
    }

    /// Where `value` lies along the scale, 0 to 1.
    pub fn fraction(&self, value: f64) -> f64 {
        let (lo, hi) = self.range;
        let t = if self.log {
            (value.max(lo).ln() - lo.ln()) / (hi.ln() - lo.ln())
        } else {
            (value - lo) / (hi - lo)
        };
        if t.is_finite() {
            t.clamp(0.0, 1.0)
        } else {
            1.0
        }
    }
}

/// Something drawn over the raster, in axis units (in raster pixels, y down, for a figure
/// without axes).
#[derive(Clone, Debug)]
pub enum Mark {
    Line {
        points: Vec<(f64, f64)>,
        colour: [u8; 3],
        width: u32,
    },
    /// A filled box between two corners.
    Box {
        corners: [(f64, f64); 2],
        colour: [u8; 3],
    },
    /// Text centred at a point, on a thin halo of `halo` so that it reads over any colour.
    Text {
        at: (f64, f64),
        text: String,
        colour: [u8; 3],
        halo: [u8; 3],
    },
}

/// A figure: everything [`Figure::plot`] draws.
pub struct Figure {
    pub title: String,
    /// The x and y axes; none: the raster alone, marks in its pixels.
    pub axes: Option<(Axis, Axis)>,
    pub raster: RgbImage,
    pub marks: Vec<Mark>,
    pub colour_bar: Option<ColourBar>,
    pub legend: Vec<(String, [u8; 3])>,
}

impl Figure {
    pub fn new(title: impl Into<String>, raster: RgbImage) -> Figure {
        Figure {
            title: title.into(),
            axes: None,
            raster,
            marks: Vec::new(),
            colour_bar: None,
            legend: Vec::new(),
        }
    }

    /// Draws the figure as PNG and SVG.
    pub fn plot(&self) -> Plot {
        register_font();
        let layout = Layout::of(self);
        let (width, height) = layout.size;
        let mut pixels = vec![255u8; (width * height * 3) as usize];
        {
            let root = BitMapBackend::with_buffer(&mut pixels, (width, height)).into_drawing_area();
            self.draw(&root, &layout, true)
                .expect("a figure draws into memory");
            root.present().expect("a figure draws into memory");
        }
        let png = RgbImage::from_raw(width, height, pixels).expect("the buffer's size");
        let mut svg = String::new();
        {
            let root = SVGBackend::with_string(&mut svg, (width, height)).into_drawing_area();
            self.draw(&root, &layout, false)
                .expect("a figure draws into memory");
            root.present().expect("a figure draws into memory");
        }
        Plot {
            png,
            svg: embed_raster(&svg, &self.raster, layout.plot_origin),
        }
    }

    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        layout: &Layout,
        blit: bool,
    ) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
        root.fill(&WHITE)?;
        let title = TextStyle::from((FONT, TITLE_PX).into_font()).color(&BLACK);
        for (k, line) in layout.title_lines.iter().enumerate() {
            root.draw(&Text::new(
                line.clone(),
                (8, 6 + k as i32 * (TITLE_PX as i32 + 4)),
                title.clone(),
            ))?;
        }
        let (w, h) = self.raster.dimensions();
        let (left, top) = layout.plot_origin;
        // The chart's area: the raster with the axes' labels left of and below it.
        let chart_area = root.clone().shrink(
            (left - layout.y_label_px, top),
            (layout.y_label_px + w, h + layout.x_label_px),
        );
        let (x_ends, y_ends) = match &self.axes {
            Some((x, y)) => (x.ends, y.ends),
            None => ((0.0, f64::from(w)), (f64::from(h), 0.0)),
        };
        let mut chart = ChartBuilder::on(&chart_area)
            .x_label_area_size(layout.x_label_px)
            .y_label_area_size(layout.y_label_px)
            .build_cartesian_2d(x_ends.0..x_ends.1, y_ends.0..y_ends.1)?;
        if let Some((x, y)) = &self.axes {
            let label = TextStyle::from((FONT, TEXT_PX).into_font()).color(&BLACK);
            // About one tick per 70 pixels across, 40 up.
            let (x_ticks, y_ticks) = (((w / 70).max(3)) as usize, ((h / 32).max(3)) as usize);
            let (x_step, y_step) = (tick_step(x.ends, x_ticks), tick_step(y.ends, y_ticks));
            chart
                .configure_mesh()
                .disable_mesh()
                .x_desc(x.label.as_str())
                .y_desc(y.label.as_str())
                .x_labels(x_ticks)
                .y_labels(y_ticks)
                .label_style(label.clone())
                .axis_desc_style(label)
                .x_label_formatter(&|v| tick(*v, x_step))
                .y_label_formatter(&|v| tick(*v, y_step))
                .draw()?;
        }
        if blit {
            root.draw(
                &BitMapElement::with_ref((left as i32, top as i32), (w, h), self.raster.as_raw())
                    .expect("the raster's size"),
            )?;
        }
        let mut texts = Vec::new();
        for mark in &self.marks {
            // A text that would overlap one drawn already (crowded iso-lines) is left out.
            if let Mark::Text { at, .. } = mark {
                let (x, y) = chart.backend_coord(at);
                if texts
                    .iter()
                    .any(|(u, v): &(i32, i32)| (x - u).abs() < 30 && (y - v).abs() < 14)
                {
                    continue;
                }
                texts.push((x, y));
            }
            draw_mark(root, &mut chart, mark)?;
        }
        root.draw(&Rectangle::new(
            [
                (left as i32 - 1, top as i32 - 1),
                ((left + w) as i32, (top + h) as i32),
            ],
            BLACK.stroke_width(1),
        ))?;
        let mut y = (top + h + layout.x_label_px + 8) as i32;
        if let Some(bar) = &self.colour_bar {
            draw_colour_bar(root, bar, (left as i32, y), w)?;
            y += BAR_AREA as i32;
        }
        draw_legend(root, &self.legend, (left as i32, y))?;
        Ok(())
    }
}

/// Where a figure's parts go, in pixels.
struct Layout {
    size: (u32, u32),
    title_lines: Vec<String>,
    /// The raster's top-left corner.
    plot_origin: (u32, u32),
    x_label_px: u32,
    y_label_px: u32,
}

impl Layout {
    fn of(figure: &Figure) -> Layout {
        let (w, h) = figure.raster.dimensions();
        let (x_label_px, y_label_px) = if figure.axes.is_some() {
            (44, 70)
        } else {
            (0, 0)
        };
        let width = (y_label_px + w + 24).max(420);
        // About 0.45 em a character in the title's font.
        let per_line = ((width - 16) as f64 / (TITLE_PX * 0.45)) as usize;
        let title_lines = wrap(&figure.title, per_line.max(16));
        let top = 12 + title_lines.len() as u32 * (TITLE_PX as u32 + 4);
        let bar = if figure.colour_bar.is_some() {
            BAR_AREA
        } else {
            0
        };
        let legend = LEGEND_ROW * figure.legend.len() as u32;
        Layout {
            size: (width, top + h + x_label_px + 8 + bar + legend + 8),
            title_lines,
            plot_origin: (y_label_px.max(12), top),
            x_label_px,
            y_label_px,
        }
    }
}

/// `text` broken at spaces into lines of at most `per_line` characters.
fn wrap(text: &str, per_line: usize) -> Vec<String> {
    let mut lines: Vec<String> = vec![String::new()];
    for word in text.split(' ') {
        let current = lines.last_mut().expect("one line at least");
        if !current.is_empty() && current.chars().count() + 1 + word.chars().count() > per_line {
            lines.push(word.to_string());
        } else {
            if !current.is_empty() {
                current.push(' ');
            }
            current.push_str(word);
        }
    }
    lines
}

/// The spacing of the ticks plotters puts on an axis between `ends` when asked for `count`.
fn tick_step(ends: (f64, f64), count: usize) -> f64 {
    use plotters::coord::ranged1d::Ranged;
    let range =
        plotters::coord::types::RangedCoordf64::from(ends.0.min(ends.1)..ends.0.max(ends.1));
    let ticks = range.key_points(count);
    ticks
        .windows(2)
        .map(|pair| (pair[1] - pair[0]).abs())
        .fold(f64::INFINITY, f64::min)
        .min((ends.1 - ends.0).abs())
}

/// A tick's label: as many decimals as the ticks' `step` needs, and no "-0".
fn tick(v: f64, step: f64) -> String {
    let decimals = (-step.max(1e-12).log10().floor()).clamp(0.0, 6.0) as usize;
    let text = format!("{v:.decimals$}");
    if text
        .trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        text.trim_start_matches('-').to_string()
    } else {
        text.replace('-', "−")
    }
}

fn rgb([r, g, b]: [u8; 3]) -> RGBColor {
    RGBColor(r, g, b)
}

fn draw_mark<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    chart: &mut ChartContext<
        DB,
        Cartesian2d<plotters::coord::types::RangedCoordf64, plotters::coord::types::RangedCoordf64>,
    >,
    mark: &Mark,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    match mark {
        Mark::Line {
            points,
            colour,
            width,
        } => {
            chart.draw_series(std::iter::once(PathElement::new(
                points.clone(),
                rgb(*colour).stroke_width(*width),
            )))?;
            // The bitmap backend leaves a one-pixel line's joints out: put them in.
            if *width == 1 {
                chart.draw_series(points.iter().map(|p| Pixel::new(*p, rgb(*colour))))?;
            }
        }
        Mark::Box { corners, colour } => {
            chart.draw_series(std::iter::once(Rectangle::new(
                *corners,
                rgb(*colour).filled(),
            )))?;
        }
        Mark::Text {
            at,
            text,
            colour,
            halo,
        } => {
            let centre = plotters::style::text_anchor::Pos::new(
                plotters::style::text_anchor::HPos::Center,
                plotters::style::text_anchor::VPos::Center,
            );
            let (ink, halo) = (rgb(*colour), rgb(*halo));
            let font = (FONT, TEXT_PX - 1.0).into_font();
            let halo_style = TextStyle::from(font.clone()).color(&halo).pos(centre);
            let ink_style = TextStyle::from(font).color(&ink).pos(centre);
            // Text in pixels, so that its halo is one pixel wide at any scale.
            let (x, y) = chart.backend_coord(at);
            for (dx, dy) in [(-1, 0), (1, 0), (0, -1), (0, 1)] {
                root.draw(&Text::new(
                    text.clone(),
                    (x + dx, y + dy),
                    halo_style.clone(),
                ))?;
            }
            root.draw(&Text::new(text.clone(), (x, y), ink_style))?;
        }
    }
    Ok(())
}

/// The colour bar under the plot at `(x, y)`, `width` wide: the scale, ticks at round values
/// (powers of ten on a log scale) and the label.
fn draw_colour_bar<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    bar: &ColourBar,
    (x, y): (i32, i32),
    width: u32,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let steps = width.clamp(2, 256);
    for k in 0..steps {
        let x0 = x + (k * width / steps) as i32;
        let x1 = x + ((k + 1) * width / steps) as i32;
        let t = (f64::from(k) + 0.5) / f64::from(steps);
        root.draw(&Rectangle::new(
            [(x0, y), (x1, y + BAR_HEIGHT as i32)],
            rgb(scale_colour(t)).filled(),
        ))?;
    }
    root.draw(&Rectangle::new(
        [(x, y), (x + width as i32, y + BAR_HEIGHT as i32)],
        BLACK.stroke_width(1),
    ))?;
    let text = TextStyle::from((FONT, TEXT_PX).into_font()).color(&BLACK);
    let centred = text.pos(plotters::style::text_anchor::Pos::new(
        plotters::style::text_anchor::HPos::Center,
        plotters::style::text_anchor::VPos::Top,
    ));
    for value in bar_ticks(bar) {
        let tx = x + (bar.fraction(value) * f64::from(width)).round() as i32;
        root.draw(&PathElement::new(
            vec![(tx, y + BAR_HEIGHT as i32), (tx, y + BAR_HEIGHT as i32 + 4)],
            BLACK.stroke_width(1),
        ))?;
        root.draw(&Text::new(
            format_value(value),
            (tx, y + BAR_HEIGHT as i32 + 5),
            centred.clone(),
        ))?;
    }
    root.draw(&Text::new(
        bar.label.clone(),
        (x + width as i32 / 2, y + BAR_HEIGHT as i32 + 22),
        centred,
    ))?;
    Ok(())
}

/// The colour bar's tick values: round steps over a linear scale, powers of ten (or the ends)
/// over a log one.
fn bar_ticks(bar: &ColourBar) -> Vec<f64> {
    let (lo, hi) = bar.range;
    if !(lo.is_finite() && hi.is_finite()) || hi <= lo {
        return vec![lo];
    }
    if bar.log && lo <= 0.0 {
        return vec![lo, hi];
    }
    if bar.log {
        let decades = lo.log10().floor() as i32..=hi.log10().ceil() as i32;
        let within = |v: &f64| *v >= lo * (1.0 - 1e-9) && *v <= hi * (1.0 + 1e-9);
        let powers: Vec<f64> = decades
            .clone()
            .map(|e| 10f64.powi(e))
            .filter(within)
            .collect();
        if powers.len() >= 3 {
            return powers;
        }
        // Few decades: 1, 2 and 5 in each.
        let ticks: Vec<f64> = decades
            .flat_map(|e| [1.0, 2.0, 5.0].map(|m| m * 10f64.powi(e)))
            .filter(within)
            .collect();
        return if ticks.len() >= 2 {
            ticks
        } else {
            vec![lo, hi]
        };
    }
    let step = round_step((hi - lo) / 6.0);
    let first = (lo / step).ceil() as i64;
    let last = (hi / step).floor() as i64;
    (first..=last).map(|k| k as f64 * step).collect()
}

/// A value for a tick or a label: plain where it reads so, else in scientific notation.
pub fn format_value(v: f64) -> String {
    let a = v.abs();
    let text = if a == 0.0 {
        "0".to_string()
    } else if !(1e-3..1e5).contains(&a) {
        format!("{v:.1e}").replace(".0e", "e")
    } else {
        let decimals = (2.0 - a.log10().floor()).clamp(0.0, 4.0) as usize;
        let s = format!("{v:.decimals$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    };
    text.replace('-', "−")
}

fn draw_legend<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    legend: &[(String, [u8; 3])],
    (x, y): (i32, i32),
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let text = TextStyle::from((FONT, TEXT_PX).into_font()).color(&BLACK);
    for (k, (label, colour)) in legend.iter().enumerate() {
        let row = y + (k as u32 * LEGEND_ROW) as i32;
        root.draw(&Rectangle::new(
            [(x, row + 2), (x + 12, row + 14)],
            rgb(*colour).filled(),
        ))?;
        root.draw(&Rectangle::new(
            [(x, row + 2), (x + 12, row + 14)],
            RGBColor(90, 90, 90).stroke_width(1),
        ))?;
        root.draw(&Text::new(label.clone(), (x + 18, row + 1), text.clone()))?;
    }
    Ok(())
}

/// Puts the raster into the SVG as an embedded PNG, just above the page's white background
/// (so that axes and marks are drawn over it).
fn embed_raster(svg: &str, raster: &RgbImage, (left, top): (u32, u32)) -> String {
    let data = base64::engine::general_purpose::STANDARD.encode(png_bytes(raster));
    let image = format!(
        "<image x=\"{left}\" y=\"{top}\" width=\"{}\" height=\"{}\" \
         style=\"image-rendering:pixelated\" href=\"data:image/png;base64,{data}\"/>\n",
        raster.width(),
        raster.height()
    );
    let background_end = svg
        .find("<rect")
        .and_then(|at| svg[at..].find("/>").map(|end| at + end + 2))
        .expect("the SVG starts with its background");
    let mut out = String::with_capacity(svg.len() + image.len());
    out.push_str(&svg[..background_end]);
    out.push('\n');
    out.push_str(&image);
    out.push_str(&svg[background_end..]);
    out
}

/// PNG bytes of `png`.
pub fn png_bytes(png: &RgbImage) -> Vec<u8> {
    let mut bytes = Vec::new();
    png.write_to(
        &mut std::io::Cursor::new(&mut bytes),
        image::ImageFormat::Png,
    )
    .expect("a PNG encodes in memory");
    bytes
}

/// Registers the compiled-in font for every figure's text, once.
fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        for style in [FontStyle::Normal, FontStyle::Bold] {
            plotters::style::register_font(FONT, style, epaint_default_fonts::UBUNTU_LIGHT)
                .unwrap_or_else(|_| panic!("the compiled-in font loads"));
        }
    });
}

/// The colour of `t` in [0, 1] on the viridis scale (dark blue through teal and green to
/// yellow): perceptually even, and readable in grey and by most colour-blind readers.
pub fn scale_colour(t: f64) -> [u8; 3] {
    let c = colorous::VIRIDIS.eval_continuous(t.clamp(0.0, 1.0));
    [c.r, c.g, c.b]
}

/// 1, 2 or 5 times a power of ten, the nearest at or above `raw`.
pub fn round_step(raw: f64) -> f64 {
    let power = 10f64.powf(raw.max(1e-12).log10().floor());
    let m = raw / power;
    power
        * if m <= 1.0 {
            1.0
        } else if m <= 2.0 {
            2.0
        } else if m <= 5.0 {
            5.0
        } else {
            10.0
        }
}

/// The iso-line at `level` over a `columns` × `rows` grid of values (row-major, row 0 first),
/// as polylines in grid coordinates (column, row; value centres at whole numbers), traced by
/// the `contour` crate. Lines stop where they would enter a cell without a value or leave the
/// grid.
pub fn iso_lines(
    values: &[Option<f64>],
    columns: usize,
    rows: usize,
    level: f64,
) -> Vec<Vec<[f64; 2]>> {
    if columns < 2 || rows < 2 || values.iter().all(Option::is_none) {
        return Vec::new();
    }
    let filled = fill_missing(values, columns, rows);
    let lines = contour::ContourBuilder::new(columns, rows, true)
        .lines(&filled, &[level])
        .expect("the grid's size matches its values");
    let valid = |p: [f64; 2]| {
        let inside = |a: f64, n: usize| a >= -1e-9 && a <= (n - 1) as f64 + 1e-9;
        inside(p[0], columns)
            && inside(p[1], rows)
            && values[p[1].round() as usize * columns + p[0].round() as usize].is_some()
    };
    let mut polylines = Vec::new();
    for line in &lines {
        for string in &line.geometry().0 {
            let mut current: Vec<[f64; 2]> = Vec::new();
            for c in &string.0 {
                // The contour crate puts value k at coordinate k + 0.5.
                let p = [c.x - 0.5, c.y - 0.5];
                if valid(p) {
                    current.push(p);
                } else if current.len() > 1 {
                    polylines.push(std::mem::take(&mut current));
                } else {
                    current.clear();
                }
            }
            if current.len() > 1 {
                polylines.push(current);
            }
        }
    }
    polylines
}

/// `values` with each missing one replaced by a neighbour's, spreading outwards, so that the
/// contour tracer sees a whole grid (its lines there are cut off by [`iso_lines`]).
fn fill_missing(values: &[Option<f64>], columns: usize, rows: usize) -> Vec<f64> {
    let mut filled: Vec<Option<f64>> = values.to_vec();
    while filled.iter().any(Option::is_none) {
        let before = filled.clone();
        if before.iter().all(Option::is_none) {
            return vec![0.0; values.len()];
        }
        for j in 0..rows {
            for i in 0..columns {
                if before[j * columns + i].is_some() {
                    continue;
                }
                let neighbours = [
                    (i > 0).then(|| before[j * columns + i - 1]),
                    (i + 1 < columns).then(|| before[j * columns + i + 1]),
                    (j > 0).then(|| before[(j - 1) * columns + i]),
                    (j + 1 < rows).then(|| before[(j + 1) * columns + i]),
                ];
                filled[j * columns + i] = neighbours.into_iter().flatten().flatten().next();
            }
        }
    }
    filled.into_iter().map(|v| v.expect("filled")).collect()
}

/// Labels for iso-lines: the level written at the middle of each line long enough to carry
/// it, `to_axes` taking grid coordinates to the figure's.
pub fn iso_labels(
    lines: &[Vec<[f64; 2]>],
    level: f64,
    to_axes: &impl Fn([f64; 2]) -> (f64, f64),
) -> Vec<Mark> {
    lines
        .iter()
        .filter(|line| line.len() >= 6)
        .map(|line| Mark::Text {
            at: to_axes(line[line.len() / 2]),
            text: format_value(level),
            colour: [0, 0, 0],
            halo: [255, 255, 255],
        })
        .collect()
}

/// `text` safe in HTML and SVG.
pub fn html_escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_figure_has_its_text_axes_bar_and_legend() {
        let raster = RgbImage::from_pixel(200, 120, image::Rgb([200, 200, 200]));
        let bare = Figure::new("", raster.clone()).plot();
        let mut figure = Figure::new(
            "a title long enough to wrap onto a second line of the page, which is at least 420 \
             pixels wide",
            raster,
        );
        figure.axes = Some((
            Axis::new("x (m)", (0.0, 10.0)),
            Axis::new("y (m)", (0.0, 6.0)),
        ));
        figure.colour_bar = Some(ColourBar {
            label: "value (D)".into(),
            range: (-1.0, 2.0),
            log: false,
        });
        figure.legend = vec![("one".into(), [255, 0, 0])];
        figure.marks.push(Mark::Line {
            points: vec![(1.0, 1.0), (9.0, 5.0)],
            colour: [255, 0, 255],
            width: 2,
        });
        let plot = figure.plot();
        assert!(plot.png.height() > bare.png.height() + 80);
        let dark = |png: &RgbImage| png.pixels().filter(|p| p.0.iter().all(|c| *c < 80)).count();
        assert!(
            dark(&plot.png) > dark(&bare.png) + 500,
            "{} {}",
            dark(&plot.png),
            dark(&bare.png)
        );
        // The line is drawn over the raster; the raster fills the plotting area.
        assert!(plot.png.pixels().any(|p| p.0 == [255, 0, 255]));
        for text in ["x (m)", "y (m)", "value (D)", "one", "<image"] {
            assert!(plot.svg.contains(text), "{text} in the SVG");
        }
        assert_eq!(plot.svg.matches("<image").count(), 1);
    }

    #[test]
    fn iso_lines_of_a_plane_are_straight_where_the_level_lies() {
        // v = column: the level 1.5 runs between columns 1 and 2, down the whole grid.
        let (columns, rows) = (4, 3);
        let values: Vec<Option<f64>> = (0..rows)
            .flat_map(|_| (0..columns).map(|i| Some(i as f64)))
            .collect();
        let lines = iso_lines(&values, columns, rows, 1.5);
        assert_eq!(lines.len(), 1, "{lines:?}");
        for p in &lines[0] {
            assert!((p[0] - 1.5).abs() < 1e-9, "{lines:?}");
        }
        let span = lines[0].iter().map(|p| p[1]).fold(0.0f64, f64::max)
            - lines[0].iter().map(|p| p[1]).fold(f64::INFINITY, f64::min);
        assert!((span - 2.0).abs() < 1e-9, "{lines:?}");
        // A missing cell cuts the line short of it.
        let mut holed = values.clone();
        holed[2 * columns + 2] = None;
        for line in iso_lines(&holed, columns, rows, 1.5) {
            for p in line {
                assert!(p[1] < 1.5 + 1e-9, "the line enters the missing cell: {p:?}");
            }
        }
    }

    #[test]
    fn ticks_and_values_read_plainly() {
        assert_eq!(tick(2.5, 0.5), "2.5");
        assert_eq!(tick(-0.0, 0.2), "0.0");
        assert_eq!(tick(-2.0, 2.0), "−2");
        assert_eq!(tick(20.0, 10.0), "20");
        // The ticks' own spacing sets the decimals: plotters puts 0.5, 1.0, 1.5 on this axis.
        assert_eq!(tick(1.5, tick_step((0.05, 1.65), 3)), "1.5");
        assert_eq!(format_value(0.25), "0.25");
        assert_eq!(format_value(12000.0), "12000");
        assert_eq!(format_value(1e6), "1e6");
        assert_eq!(format_value(1.5e-5), "1.5e−5");
        assert_eq!(round_step(0.9), 1.0);
        assert_eq!(round_step(2.1), 5.0);
    }
}
