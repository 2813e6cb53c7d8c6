//! The lens analysis's plots: contour maps over the gaze grid (mean power, cylinder with its
//! axis, prism with its base, lateral colour) and the distortion picture. Each map is drawn as
//! the wearer looks through the lens: h to the wearer's right, v up. Iso-lines come from the
//! `contour` crate ([`crate::figure::iso_lines`]) and carry their values; values between cell
//! centres come from bilinear interpolation; cells outside the lens are grey.

use image::{Rgb, RgbImage};

use super::zones::LensMap;
use super::{Cell, Eye, Report};
use crate::figure::{iso_labels, iso_lines, round_step, Axis, ColourBar, Figure, Mark, Plot};

/// What a map shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Map {
    MeanPower,
    Cylinder,
    Prism,
    LateralColour,
    /// Against a prescription: the cylinder the wearer gets but did not order.
    UnwantedCylinder,
}

impl Map {
    pub const ALL: [Map; 5] = [
        Map::MeanPower,
        Map::Cylinder,
        Map::Prism,
        Map::LateralColour,
        Map::UnwantedCylinder,
    ];

    /// The maps a report has: the unwanted cylinder only against a prescription.
    pub fn of(report: &Report) -> Vec<Map> {
        Map::ALL
            .into_iter()
            .filter(|m| *m != Map::UnwantedCylinder || report.prescription.is_some())
            .collect()
    }

    /// The plot's file name.
    pub fn name(self) -> &'static str {
        match self {
            Map::MeanPower => "mean-power",
            Map::Cylinder => "cylinder",
            Map::Prism => "prism",
            Map::LateralColour => "lateral-colour",
            Map::UnwantedCylinder => "unwanted-cylinder",
        }
    }

    fn what(self) -> &'static str {
        match self {
            Map::MeanPower => "mean power (D)",
            Map::Cylinder => "cylinder (D, its magnitude; ticks: the axis)",
            Map::Prism => "prism (Δ; arrows point to the base)",
            Map::LateralColour => "lateral colour (arcmin)",
            Map::UnwantedCylinder => "unwanted cylinder against the prescription (D)",
        }
    }

    /// The value a cell shows.
    pub fn value(self, cell: &Cell) -> Option<f64> {
        match self {
            Map::MeanPower => cell.mean_power_d,
            Map::Cylinder => cell.cylinder_d.map(f64::abs),
            Map::Prism => cell.prism_d.map(|[h, v]| h.hypot(v)),
            Map::LateralColour => cell.lateral_colour_arcmin,
            Map::UnwantedCylinder => cell.unwanted_cylinder_d,
        }
    }
}

const OUTSIDE: Rgb<u8> = Rgb([200, 200, 200]);
const INK: [u8; 3] = [0, 0, 0];

/// The grid's layout on a map: pixels per cell and the gaze extent.
struct Layout {
    columns: usize,
    rows: usize,
    cell_px: f32,
    width: u32,
    height: u32,
}

impl Layout {
    fn new(report: &Report) -> Layout {
        Layout::sized(report.columns, report.rows)
    }

    fn sized(columns: usize, rows: usize) -> Layout {
        let cell_px = (480.0 / columns.max(rows) as f32).clamp(6.0, 48.0).round();
        Layout {
            columns,
            rows,
            cell_px,
            width: (cell_px * columns as f32) as u32,
            height: (cell_px * rows as f32) as u32,
        }
    }

    /// The grid coordinate of a pixel's centre.
    fn grid(&self, x: u32, y: u32) -> [f64; 2] {
        [
            f64::from((x as f32 + 0.5) / self.cell_px - 0.5),
            f64::from((self.height as f32 - y as f32 - 0.5) / self.cell_px - 0.5),
        ]
    }
}

type Axes = (Axis, Axis);

/// The gaze axes of a map over `report`'s grid, and its grid coordinates in gaze degrees.
fn gaze_axes(report: &Report) -> (Axes, impl Fn([f64; 2]) -> (f64, f64)) {
    let step = report.gaze.step_deg;
    let half = step * 0.5;
    let (h, v) = (report.gaze.horizontal(), report.gaze.vertical());
    let axes = (
        Axis::new(
            "gaze h (°, the wearer's right)",
            (h[0] - half, h[h.len() - 1] + half),
        ),
        Axis::new("gaze v (°, up)", (v[0] - half, v[v.len() - 1] + half)),
    );
    let (h0, v0) = (h[0], v[0]);
    (axes, move |at: [f64; 2]| {
        (h0 + at[0] * step, v0 + at[1] * step)
    })
}

/// `values`' iso-line at `level` as marks: the lines in `colour`, `width` pixels wide, and
/// their value written on them when `labelled`.
fn iso_marks(
    values: &[Option<f64>],
    (columns, rows): (usize, usize),
    level: f64,
    to_axes: &impl Fn([f64; 2]) -> (f64, f64),
    (colour, width, labelled): ([u8; 3], u32, bool),
) -> Vec<Mark> {
    let lines = iso_lines(values, columns, rows, level);
    let mut marks: Vec<Mark> = lines
        .iter()
        .map(|line| Mark::Line {
            points: line.iter().map(|p| to_axes(*p)).collect(),
            colour,
            width,
        })
        .collect();
    if labelled {
        marks.extend(iso_labels(&lines, level, to_axes));
    }
    marks
}

/// `values` bilinearly at grid coordinate `at` (clamped to the grid); None where a corner is
/// outside the lens.
fn sample(values: &[Option<f64>], columns: usize, rows: usize, at: [f64; 2]) -> Option<f64> {
    let x = at[0].clamp(0.0, (columns - 1) as f64);
    let y = at[1].clamp(0.0, (rows - 1) as f64);
    if columns < 2 || rows < 2 {
        return values[y.round() as usize * columns + x.round() as usize];
    }
    let (i, j) = (
        (x.floor() as usize).min(columns - 2),
        (y.floor() as usize).min(rows - 2),
    );
    let (fx, fy) = (x - i as f64, y - j as f64);
    let v = |di: usize, dj: usize| values[(j + dj) * columns + i + di];
    let (a, b, c, d) = (v(0, 0)?, v(1, 0)?, v(0, 1)?, v(1, 1)?);
    Some((a * (1.0 - fx) + b * fx) * (1.0 - fy) + (c * (1.0 - fx) + d * fx) * fy)
}

/// `values` (one per cell of `report`'s grid) at gaze (`h_deg`, `v_deg`), bilinearly; None
/// beyond the grid's cells or next to a cell outside the lens.
pub fn value_at(report: &Report, values: &[Option<f64>], h_deg: f64, v_deg: f64) -> Option<f64> {
    let step = report.gaze.step_deg;
    let (h0, v0) = (
        -((report.columns / 2) as f64) * step,
        -((report.rows / 2) as f64) * step,
    );
    let at = [(h_deg - h0) / step, (v_deg - v0) / step];
    let inside = |a: f64, n: usize| a >= -0.5 && a <= n as f64 - 0.5;
    if !(inside(at[0], report.columns) && inside(at[1], report.rows)) {
        return None;
    }
    sample(values, report.columns, report.rows, at)
}

/// A round contour interval for values spanning `lo`..`hi` (about eight lines).
pub fn interval(lo: f64, hi: f64) -> f64 {
    round_step(((hi - lo) / 8.0).max(1e-6))
}

/// The contour interval of `map` over `report`: about eight lines, and for a vergence (mean
/// power, cylinder) no finer than twice the finite differences' change, so that no line
/// follows their noise.
pub fn map_interval(report: &Report, map: Map, lo: f64, hi: f64) -> f64 {
    let step = interval(lo, hi);
    match map {
        Map::MeanPower | Map::Cylinder | Map::UnwantedCylinder => {
            step.max(round_step(2.0 * report.finite_difference_change_d))
        }
        Map::Prism | Map::LateralColour => step,
    }
}

/// The range a map's colour scale spans: its values' (0 to 1 without any; widened by ±0.5
/// where they are all equal).
fn value_range(values: &[Option<f64>]) -> (f64, f64) {
    let (mut lo, mut hi) = values
        .iter()
        .flatten()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(*v), hi.max(*v))
        });
    if !lo.is_finite() {
        (lo, hi) = (0.0, 1.0);
    }
    if hi - lo < 1e-9 {
        (lo, hi) = (lo - 0.5, hi + 0.5);
    }
    (lo, hi)
}

/// A map of one quantity over the gaze grid (module doc).
pub fn lens_map(report: &Report, map: Map) -> Plot {
    let layout = Layout::new(report);
    let grid = (layout.columns, layout.rows);
    let values: Vec<Option<f64>> = report.grid.iter().map(|c| map.value(c)).collect();
    let (lo, hi) = value_range(&values);
    let bar = ColourBar {
        label: map.what().to_string(),
        range: (lo, hi),
        log: false,
    };
    let png = RgbImage::from_fn(layout.width, layout.height, |x, y| {
        match sample(&values, layout.columns, layout.rows, layout.grid(x, y)) {
            Some(v) => Rgb(bar.colour(v)),
            None => OUTSIDE,
        }
    });
    let (axes, to_gaze) = gaze_axes(report);
    let step = map_interval(report, map, lo, hi);
    let mut marks = Vec::new();
    let mut level = (lo / step).ceil() * step;
    while level <= hi {
        marks.extend(iso_marks(&values, grid, level, &to_gaze, (INK, 1, true)));
        level += step;
    }
    marks.extend(axis_and_base_marks(report, map, step, &layout, &to_gaze));
    let mut figure = Figure::new(
        format!(
            "'{}', {} eye: {} over the gaze, as the wearer looks; iso-lines every {step}",
            report.lens,
            match report.eye {
                Eye::Right => "right",
                Eye::Left => "left",
            },
            map.what()
        ),
        png,
    );
    figure.axes = Some(axes);
    figure.marks = marks;
    figure.colour_bar = Some(bar);
    figure.legend = match map {
        Map::Cylinder => vec![("the cylinder's axis (ticks)".into(), MARK.0)],
        Map::Prism => vec![("towards the prism's base (arrows)".into(), MARK.0)],
        _ => Vec::new(),
    };
    figure.legend.push(("outside the lens".into(), OUTSIDE.0));
    figure.plot()
}

/// The cylinder's axis as a tick, or the prism's base as an arrow, on every few cells so that
/// they do not crowd; in gaze degrees.
fn axis_and_base_marks(
    report: &Report,
    map: Map,
    step: f64,
    layout: &Layout,
    to_gaze: &impl Fn([f64; 2]) -> (f64, f64),
) -> Vec<Mark> {
    let every = layout.columns.max(layout.rows).div_ceil(12).max(1);
    let reach = 0.42 * every as f64 * report.gaze.step_deg;
    let side = match report.eye {
        Eye::Right => 1.0,
        Eye::Left => -1.0,
    };
    let largest_prism = report
        .grid
        .iter()
        .filter_map(|c| c.prism_d.map(|[h, v]| h.hypot(v)))
        .fold(0.0, f64::max);
    let line = |points: Vec<(f64, f64)>| Mark::Line {
        points,
        colour: MARK.0,
        width: 2,
    };
    let mut marks = Vec::new();
    for (k, cell) in report.grid.iter().enumerate() {
        let (i, j) = (k % layout.columns, k / layout.columns);
        if i % every != 0 || j % every != 0 {
            continue;
        }
        let (cx, cy) = to_gaze([i as f64, j as f64]);
        match map {
            Map::Cylinder => {
                if let (Some(axis), Some(cylinder)) = (cell.axis_deg, cell.cylinder_d) {
                    if cylinder.abs() < 0.5 * step {
                        continue;
                    }
                    // TABO from the examiner's right (the wearer's left), on a map as the
                    // wearer looks: (−cos θ, sin θ), v up.
                    let a = axis.to_radians();
                    let (dx, dy) = (-a.cos() * reach, a.sin() * reach);
                    marks.push(line(vec![(cx - dx, cy - dy), (cx + dx, cy + dy)]));
                }
            }
            Map::Prism => {
                if let Some([h, v]) = cell.prism_d {
                    let magnitude = h.hypot(v);
                    if largest_prism <= 0.0 || magnitude < 1e-3 * largest_prism {
                        continue;
                    }
                    // Base out is towards the temple: the wearer's right for the right eye.
                    let base = (h * side / magnitude, v / magnitude);
                    let length = reach * magnitude / largest_prism;
                    let tip = (cx + base.0 * length, cy + base.1 * length);
                    let (back, across) = (
                        (-base.0 * 0.35 * reach, -base.1 * 0.35 * reach),
                        (-base.1 * 0.2 * reach, base.0 * 0.2 * reach),
                    );
                    marks.push(line(vec![
                        (tip.0 + back.0 + across.0, tip.1 + back.1 + across.1),
                        tip,
                        (tip.0 + back.0 - across.0, tip.1 + back.1 - across.1),
                    ]));
                    marks.push(line(vec![(cx, cy), tip]));
                }
            }
            Map::MeanPower | Map::LateralColour | Map::UnwantedCylinder => {}
        }
    }
    marks
}

/// A map over the lens's own coordinates ([`crate::lens::zones::LensMap`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LensCoordinateMap {
    /// Mean power, iso-lines every 0.25 D, with the |power error| = 0.25 D line (the clear
    /// zone's edge) in white.
    MeanPower,
    /// Unwanted cylinder, iso-lines at 0.25 D and every 0.50 D from 0.50 D, the 0.50 D and
    /// 1.00 D lines drawn thick.
    UnwantedCylinder,
}

impl LensCoordinateMap {
    pub const ALL: [LensCoordinateMap; 2] = [
        LensCoordinateMap::MeanPower,
        LensCoordinateMap::UnwantedCylinder,
    ];

    pub fn name(self) -> &'static str {
        match self {
            LensCoordinateMap::MeanPower => "lens-mean-power",
            LensCoordinateMap::UnwantedCylinder => "lens-cylinder",
        }
    }
}

const CORRIDOR: Rgb<u8> = Rgb([255, 255, 255]);
const MARK: Rgb<u8> = Rgb([230, 30, 120]);

/// A map over the lens map's points (x to the wearer's right, y up, mm), with the corridor
/// (white), the fitting point (a cross), the reference points and the near point's crossing
/// (circles); None without a lens map.
pub fn lens_coordinate_map(report: &Report, kind: LensCoordinateMap) -> Option<Plot> {
    let map = report.lens_map.as_ref()?;
    let reference = map.reference.power_vector();
    let deviation = |c: &Cell| {
        let got = crate::lens::Rx::new(c.sphere_d?, c.cylinder_d?, c.axis_deg?).power_vector();
        Some((
            got[0] - reference[0],
            2.0 * (got[1] - reference[1]).hypot(got[2] - reference[2]),
        ))
    };
    let values: Vec<Option<f64>> = map
        .points
        .iter()
        .map(|p| match kind {
            LensCoordinateMap::MeanPower => p.cell.mean_power_d,
            LensCoordinateMap::UnwantedCylinder => deviation(&p.cell).map(|d| d.1),
        })
        .collect();
    let grid = (map.columns, map.rows);
    let layout = Layout::sized(map.columns, map.rows);
    let (lo, hi) = value_range(&values);
    let (what, lines) = match kind {
        LensCoordinateMap::MeanPower => (
            "mean power (D)",
            "iso-lines every 0.25 D; white: |power error| 0.25 D",
        ),
        LensCoordinateMap::UnwantedCylinder => (
            "unwanted cylinder (D)",
            "iso-lines at 0.25, 0.50 (thick), 1.00 (thick), then every 0.50 D",
        ),
    };
    let bar = ColourBar {
        label: what.to_string(),
        range: (lo, hi),
        log: false,
    };
    let png = RgbImage::from_fn(layout.width, layout.height, |x, y| {
        match sample(&values, map.columns, map.rows, layout.grid(x, y)) {
            Some(v) => Rgb(bar.colour(v)),
            None => OUTSIDE,
        }
    });
    let to_mm = |at: [f64; 2]| {
        (
            map.origin_mm[0] + at[0] * map.step_mm,
            map.origin_mm[1] + at[1] * map.step_mm,
        )
    };
    let levels: Vec<f64> = match kind {
        LensCoordinateMap::MeanPower => {
            let first = (lo / 0.25).ceil() as i64;
            (first..=(hi / 0.25).floor() as i64)
                .map(|k| k as f64 * 0.25)
                .collect()
        }
        LensCoordinateMap::UnwantedCylinder => std::iter::once(0.25)
            .chain((1..).map(|k| k as f64 * 0.5).take_while(|l| *l <= hi))
            .collect(),
    };
    let mut marks = Vec::new();
    for &level in &levels {
        let thick = kind == LensCoordinateMap::UnwantedCylinder && (level == 0.5 || level == 1.0);
        let width = if thick { 2 } else { 1 };
        marks.extend(iso_marks(&values, grid, level, &to_mm, (INK, width, true)));
    }
    if kind == LensCoordinateMap::MeanPower {
        let error: Vec<Option<f64>> = map
            .points
            .iter()
            .map(|p| deviation(&p.cell).map(|d| d.0.abs()))
            .collect();
        marks.extend(iso_marks(
            &error,
            grid,
            0.25,
            &to_mm,
            (CORRIDOR.0, 2, false),
        ));
    }
    marks.extend(lens_marks(map, report, &layout));
    let half = 0.5 * map.step_mm;
    let mut figure = Figure::new(
        format!(
            "'{}': {what} over the lens (as worn, from the eye's side); {lines}",
            report.lens
        ),
        png,
    );
    figure.axes = Some((
        Axis::new(
            "x (mm, the wearer's right)",
            (
                map.origin_mm[0] - half,
                map.origin_mm[0] + (map.columns - 1) as f64 * map.step_mm + half,
            ),
        ),
        Axis::new(
            "y (mm, up)",
            (
                map.origin_mm[1] - half,
                map.origin_mm[1] + (map.rows - 1) as f64 * map.step_mm + half,
            ),
        ),
    ));
    figure.marks = marks;
    figure.colour_bar = Some(bar);
    if report.progressive.is_some() {
        figure
            .legend
            .push(("corridor (white line)".into(), CORRIDOR.0));
    }
    figure.legend.extend([
        (
            "fitting point +; reference points, near point o".into(),
            MARK.0,
        ),
        ("off the lens".into(), OUTSIDE.0),
    ]);
    Some(figure.plot())
}

/// The corridor (white), the fitting point (a cross), the reference points and the near
/// crossing (circles) on a map over the lens, in mm.
fn lens_marks(map: &LensMap, report: &Report, layout: &Layout) -> Vec<Mark> {
    let mut marks = Vec::new();
    if let Some(p) = &report.progressive {
        marks.push(Mark::Line {
            points: p.corridor_mm.iter().map(|q| (q[0], q[1])).collect(),
            colour: CORRIDOR.0,
            width: 2,
        });
    }
    let r = 0.6 * f64::from(layout.cell_px.max(6.0)) / f64::from(layout.cell_px) * map.step_mm;
    let circle = |at: [f64; 2]| Mark::Line {
        points: (0..=24)
            .map(|k| {
                let a = f64::from(k) / 24.0 * std::f64::consts::TAU;
                (at[0] + r * a.cos(), at[1] + r * a.sin())
            })
            .collect(),
        colour: MARK.0,
        width: 2,
    };
    let [fx, fy] = report.fitting_point_mm;
    for points in [
        vec![(fx - r, fy), (fx + r, fy)],
        vec![(fx, fy - r), (fx, fy + r)],
    ] {
        marks.push(Mark::Line {
            points,
            colour: MARK.0,
            width: 2,
        });
    }
    if let Some(p) = &report.progressive {
        marks.push(circle(p.distance_reference_mm));
        marks.push(circle(p.near_reference_mm));
    }
    if let Some(n) = &report.near {
        marks.push(circle(n.point_on_lens_mm));
    }
    marks
}

/// The distortion picture: straight object-space lines (constant horizontal or vertical
/// tangent of the object direction, a square grid) drawn where the wearer sees them, on the
/// gaze's tangent screen (tan h, tan v), where a lens without distortion draws them straight
/// and evenly spaced. Grey: outside the lens.
pub fn distortion(report: &Report) -> Plot {
    let layout = Layout::new(report);
    let grid = (layout.columns, layout.rows);
    let (h, v) = (report.gaze.horizontal(), report.gaze.vertical());
    let half = report.gaze.step_deg.to_radians() * 0.5;
    let tan_range = |values: &[f64]| {
        (
            (values[0].to_radians() - half).tan(),
            (values[values.len() - 1].to_radians() + half).tan(),
        )
    };
    let ((x0, x1), (y0, y1)) = (tan_range(&h), tan_range(&v));
    let scale = 480.0 / (x1 - x0).max(y1 - y0);
    let (width, height) = (
        (((x1 - x0) * scale).round() as u32).max(8),
        (((y1 - y0) * scale).round() as u32).max(8),
    );
    // Tangent-screen coordinates to grid coordinates, and back.
    let grid_of = |tx: f64, ty: f64| {
        [
            (tx.atan().to_degrees() - h[0]) / report.gaze.step_deg,
            (ty.atan().to_degrees() - v[0]) / report.gaze.step_deg,
        ]
    };
    let tangent_of = |at: [f64; 2]| {
        (
            (h[0] + at[0] * report.gaze.step_deg).to_radians().tan(),
            (v[0] + at[1] * report.gaze.step_deg).to_radians().tan(),
        )
    };
    let inside: Vec<Option<f64>> = report
        .grid
        .iter()
        .map(|c| (!c.outside).then_some(1.0))
        .collect();
    let png = RgbImage::from_fn(width, height, |x, y| {
        let tx = x0 + (f64::from(x) + 0.5) / scale;
        let ty = y1 - (f64::from(y) + 0.5) / scale;
        match sample(&inside, layout.columns, layout.rows, grid_of(tx, ty)) {
            Some(_) => Rgb([255, 255, 255]),
            None => OUTSIDE,
        }
    });
    let object = |axis: usize| -> Vec<Option<f64>> {
        report
            .grid
            .iter()
            .map(|c| c.object_tangent.map(|t| t[axis]))
            .collect()
    };
    let (object_x, object_y) = (object(0), object(1));
    let span = |values: &[Option<f64>]| {
        values
            .iter()
            .flatten()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                (a.min(*v), b.max(*v))
            })
    };
    let (ax, bx) = span(&object_x);
    let (ay, by) = span(&object_y);
    let step = if ax.is_finite() {
        interval(ax.min(ay), bx.max(by)) * 0.5
    } else {
        1.0
    };
    let mut marks = Vec::new();
    for (values, (lo, hi)) in [(&object_x, (ax, bx)), (&object_y, (ay, by))] {
        if !lo.is_finite() {
            continue;
        }
        let mut level = (lo / step).ceil() * step;
        while level <= hi {
            marks.extend(iso_marks(values, grid, level, &tangent_of, (INK, 1, false)));
            level += step;
        }
    }
    let mut figure = Figure::new(
        format!(
            "'{}': straight object lines (every {step} in tangent) as the wearer sees them, on \
             the gaze's tangent screen",
            report.lens
        ),
        png,
    );
    figure.axes = Some((
        Axis::new("tan h (the wearer's right)", (x0, x1)),
        Axis::new("tan v (up)", (y0, y1)),
    ));
    figure.marks = marks;
    figure.legend = vec![("outside the lens".into(), OUTSIDE.0)];
    figure.plot()
}
