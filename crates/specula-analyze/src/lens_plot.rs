//! The lens analysis's plots: contour maps over the gaze grid (mean power, cylinder with its
//! axis, prism with its base, lateral colour) and the distortion picture. Each map is drawn as
//! the wearer looks through the lens: h to the wearer's right, v up. Iso-lines come from
//! marching squares over the grid's cells, values between cell centres from bilinear
//! interpolation; cells outside the lens are grey.

use glam::Vec2;
use image::{Rgb, RgbImage};

use crate::lens::zones::LensMap;
use crate::lens::{Cell, Eye, Report};
use crate::plot::{draw_line, plot_around, scale_colour, Extent, Plot};

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
const INK: Rgb<u8> = Rgb([0, 0, 0]);

/// The segments of the iso-line at `level` over a `columns` × `rows` grid of values (row-major,
/// row 0 first), in grid coordinates (column, row); cells with a missing corner have none.
pub fn iso_segments(
    values: &[Option<f64>],
    columns: usize,
    rows: usize,
    level: f64,
) -> Vec<[[f64; 2]; 2]> {
    let mut segments = Vec::new();
    for j in 0..rows.saturating_sub(1) {
        for i in 0..columns.saturating_sub(1) {
            let corner = |di: usize, dj: usize| values[(j + dj) * columns + i + di];
            let (Some(a), Some(b), Some(c), Some(d)) =
                (corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1))
            else {
                continue;
            };
            // Corners counter-clockwise from (i, j): a (0,0), b (1,0), c (1,1), d (0,1).
            let corners = [
                ([0.0, 0.0], a),
                ([1.0, 0.0], b),
                ([1.0, 1.0], c),
                ([0.0, 1.0], d),
            ];
            let mut crossings = Vec::with_capacity(4);
            for k in 0..4 {
                let (p, u) = corners[k];
                let (q, w) = corners[(k + 1) % 4];
                if (u < level) != (w < level) {
                    let t = (level - u) / (w - u);
                    crossings.push([
                        i as f64 + p[0] + (q[0] - p[0]) * t,
                        j as f64 + p[1] + (q[1] - p[1]) * t,
                    ]);
                }
            }
            match crossings.len() {
                2 => segments.push([crossings[0], crossings[1]]),
                4 => {
                    // A saddle: the centre's value says which pairs join.
                    let centre = 0.25 * (a + b + c + d);
                    // With the centre on a's (and c's) side, a and c join: the lines cut off
                    // b (edges 0 and 1) and d (edges 2 and 3).
                    if (centre < level) == (a < level) {
                        segments.push([crossings[0], crossings[1]]);
                        segments.push([crossings[2], crossings[3]]);
                    } else {
                        segments.push([crossings[0], crossings[3]]);
                        segments.push([crossings[1], crossings[2]]);
                    }
                }
                _ => {}
            }
        }
    }
    segments
}

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

    /// A grid coordinate (column, row; cell centres at whole numbers) as a pixel (row 0 at the
    /// bottom: v up).
    fn pixel(&self, at: [f64; 2]) -> Vec2 {
        Vec2::new(
            (at[0] as f32 + 0.5) * self.cell_px,
            self.height as f32 - (at[1] as f32 + 0.5) * self.cell_px,
        )
    }

    /// The grid coordinate of a pixel's centre.
    fn grid(&self, x: u32, y: u32) -> [f64; 2] {
        [
            f64::from((x as f32 + 0.5) / self.cell_px - 0.5),
            f64::from((self.height as f32 - y as f32 - 0.5) / self.cell_px - 0.5),
        ]
    }

    fn extent(&self, report: &Report) -> Extent {
        let half = (report.gaze.step_deg * 0.5) as f32;
        let (h, v) = (report.gaze.horizontal(), report.gaze.vertical());
        Extent {
            min: Vec2::new(h[0] as f32 - half, v[0] as f32 - half),
            max: Vec2::new(h[h.len() - 1] as f32 + half, v[v.len() - 1] as f32 + half),
        }
    }
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

/// 1, 2 or 5 times a power of ten, the nearest at or above `raw`.
fn round_step(raw: f64) -> f64 {
    let power = 10f64.powf(raw.max(1e-9).log10().floor());
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
    let values: Vec<Option<f64>> = report.grid.iter().map(|c| map.value(c)).collect();
    let (lo, hi) = value_range(&values);
    let mut png = RgbImage::from_fn(layout.width, layout.height, |x, y| {
        match sample(&values, layout.columns, layout.rows, layout.grid(x, y)) {
            Some(v) => Rgb(scale_colour((v - lo) / (hi - lo))),
            None => OUTSIDE,
        }
    });
    let step = map_interval(report, map, lo, hi);
    let mut level = (lo / step).ceil() * step;
    while level <= hi {
        for [a, b] in iso_segments(&values, layout.columns, layout.rows, level) {
            draw_line(&mut png, layout.pixel(a), layout.pixel(b), INK);
        }
        level += step;
    }
    // Ticks and arrows on every few cells, so that they do not crowd.
    let every = layout.columns.max(layout.rows).div_ceil(12).max(1);
    let reach = 0.42 * every as f32 * layout.cell_px;
    let side = match report.eye {
        Eye::Right => 1.0,
        Eye::Left => -1.0,
    };
    let largest_prism = report
        .grid
        .iter()
        .filter_map(|c| c.prism_d.map(|[h, v]| h.hypot(v)))
        .fold(0.0, f64::max);
    for (k, cell) in report.grid.iter().enumerate() {
        let (i, j) = (k % layout.columns, k / layout.columns);
        if i % every != 0 || j % every != 0 {
            continue;
        }
        let centre = layout.pixel([i as f64, j as f64]);
        match map {
            Map::Cylinder => {
                if let (Some(axis), Some(cylinder)) = (cell.axis_deg, cell.cylinder_d) {
                    if cylinder.abs() < 0.5 * step {
                        continue;
                    }
                    // TABO from the examiner's right (the wearer's left), on a map as the
                    // wearer looks: (−cos θ, sin θ), y down the page.
                    let a = axis.to_radians() as f32;
                    let d = Vec2::new(-a.cos(), -a.sin()) * reach;
                    draw_line(&mut png, centre - d, centre + d, INK);
                }
            }
            Map::Prism => {
                if let Some([h, v]) = cell.prism_d {
                    let magnitude = h.hypot(v);
                    if largest_prism <= 0.0 || magnitude < 1e-3 * largest_prism {
                        continue;
                    }
                    // Base out is towards the temple: the wearer's right for the right eye.
                    let base = Vec2::new((h * side) as f32, -(v as f32)).normalize();
                    let tip = centre + base * reach * (magnitude / largest_prism) as f32;
                    draw_line(&mut png, centre, tip, INK);
                    let back = -base * 0.35 * reach;
                    let across = Vec2::new(-base.y, base.x) * 0.2 * reach;
                    draw_line(&mut png, tip, tip + back + across, INK);
                    draw_line(&mut png, tip, tip + back - across, INK);
                }
            }
            Map::MeanPower | Map::LateralColour | Map::UnwantedCylinder => {}
        }
    }
    let title = format!(
        "'{}', {} eye: {} over the gaze, as the wearer looks",
        report.lens,
        match report.eye {
            Eye::Right => "right",
            Eye::Left => "left",
        },
        map.what()
    );
    let legend = vec![
        (format!("{lo:.3}"), scale_colour(0.0)),
        (
            format!("{hi:.3}; iso-lines every {step}"),
            scale_colour(1.0),
        ),
        (
            "outside the lens".into(),
            [OUTSIDE.0[0], OUTSIDE.0[1], OUTSIDE.0[2]],
        ),
    ];
    plot_around(
        png,
        &title,
        ("gaze h (°, the wearer's right)", "gaze v (°, up)"),
        Some((layout.extent(report), false)),
        &legend,
    )
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
    let (columns, rows) = (map.columns, map.rows);
    let layout = Layout::sized(columns, rows);
    let (lo, hi) = value_range(&values);
    let mut png = RgbImage::from_fn(layout.width, layout.height, |x, y| {
        match sample(&values, columns, rows, layout.grid(x, y)) {
            Some(v) => Rgb(scale_colour((v - lo) / (hi - lo))),
            None => OUTSIDE,
        }
    });
    let line = |png: &mut RgbImage, values: &[Option<f64>], level: f64, colour, thick: bool| {
        for [a, b] in iso_segments(values, columns, rows, level) {
            let (a, b) = (layout.pixel(a), layout.pixel(b));
            draw_line(png, a, b, colour);
            if thick {
                for d in [Vec2::X, Vec2::Y] {
                    draw_line(png, a + d, b + d, colour);
                }
            }
        }
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
    for &level in &levels {
        let thick = kind == LensCoordinateMap::UnwantedCylinder && (level == 0.5 || level == 1.0);
        line(&mut png, &values, level, INK, thick);
    }
    if kind == LensCoordinateMap::MeanPower {
        let error: Vec<Option<f64>> = map
            .points
            .iter()
            .map(|p| deviation(&p.cell).map(|d| d.0.abs()))
            .collect();
        line(&mut png, &error, 0.25, CORRIDOR, true);
    }
    draw_marks(&mut png, &layout, map, report);
    let half = 0.5 * map.step_mm as f32;
    let extent = Extent {
        min: Vec2::new(
            map.origin_mm[0] as f32 - half,
            map.origin_mm[1] as f32 - half,
        ),
        max: Vec2::new(
            (map.origin_mm[0] + (columns - 1) as f64 * map.step_mm) as f32 + half,
            (map.origin_mm[1] + (rows - 1) as f64 * map.step_mm) as f32 + half,
        ),
    };
    let (what, lines) = match kind {
        LensCoordinateMap::MeanPower => (
            "mean power (D)",
            "every 0.25 D; white: |power error| 0.25 D",
        ),
        LensCoordinateMap::UnwantedCylinder => (
            "unwanted cylinder (D)",
            "lines at 0.25, 0.50 (thick), 1.00 (thick), …",
        ),
    };
    let title = format!(
        "'{}': {what} over the lens (as worn, from the eye's side)",
        report.lens
    );
    let mut legend = vec![
        (format!("{lo:.2}"), scale_colour(0.0)),
        (format!("{hi:.2}; {lines}"), scale_colour(1.0)),
    ];
    if report.progressive.is_some() {
        legend.push((
            "corridor (white line)".into(),
            [CORRIDOR.0[0], CORRIDOR.0[1], CORRIDOR.0[2]],
        ));
    }
    legend.extend([
        (
            "fitting point +; references, near point o".into(),
            [MARK.0[0], MARK.0[1], MARK.0[2]],
        ),
        (
            "off the lens".into(),
            [OUTSIDE.0[0], OUTSIDE.0[1], OUTSIDE.0[2]],
        ),
    ]);
    Some(plot_around(
        png,
        &title,
        ("x (mm, the wearer's right)", "y (mm, up)"),
        Some((extent, false)),
        &legend,
    ))
}

/// The corridor (white), the fitting point (a cross), the reference points and the near
/// crossing (circles) on a map over the lens.
fn draw_marks(png: &mut RgbImage, layout: &Layout, map: &LensMap, report: &Report) {
    let to_grid = |at: [f64; 2]| {
        [
            (at[0] - map.origin_mm[0]) / map.step_mm,
            (at[1] - map.origin_mm[1]) / map.step_mm,
        ]
    };
    if let Some(p) = &report.progressive {
        for w in p.corridor_mm.windows(2) {
            let (a, b) = (layout.pixel(to_grid(w[0])), layout.pixel(to_grid(w[1])));
            draw_line(png, a, b, CORRIDOR);
            draw_line(png, a + Vec2::X, b + Vec2::X, CORRIDOR);
        }
    }
    let r = 0.6 * layout.cell_px.max(6.0);
    let circle = |png: &mut RgbImage, at: [f64; 2]| {
        let c = layout.pixel(to_grid(at));
        for k in 0..24 {
            let (a, b) = (
                k as f32 / 24.0 * std::f32::consts::TAU,
                (k + 1) as f32 / 24.0 * std::f32::consts::TAU,
            );
            let p = |t: f32| c + Vec2::new(t.cos(), t.sin()) * r;
            draw_line(png, p(a), p(b), MARK);
        }
    };
    let fitting = layout.pixel(to_grid(report.fitting_point_mm));
    draw_line(png, fitting - Vec2::X * r, fitting + Vec2::X * r, MARK);
    draw_line(png, fitting - Vec2::Y * r, fitting + Vec2::Y * r, MARK);
    if let Some(p) = &report.progressive {
        circle(png, p.distance_reference_mm);
        circle(png, p.near_reference_mm);
    }
    if let Some(n) = &report.near {
        circle(png, n.point_on_lens_mm);
    }
}

/// The distortion picture: straight object-space lines (constant horizontal or vertical
/// tangent of the object direction, a square grid) drawn where the wearer sees them, on the
/// gaze's tangent screen (tan h, tan v), where a lens without distortion draws them straight
/// and evenly spaced. Grey: outside the lens.
pub fn distortion(report: &Report) -> Plot {
    let layout = Layout::new(report);
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
    // Tangent-screen coordinates to grid coordinates and pixels.
    let grid_of = |tx: f64, ty: f64| {
        [
            (tx.atan().to_degrees() - h[0]) / report.gaze.step_deg,
            (ty.atan().to_degrees() - v[0]) / report.gaze.step_deg,
        ]
    };
    let pixel_of = |at: [f64; 2]| {
        let gh = (h[0] + at[0] * report.gaze.step_deg).to_radians().tan();
        let gv = (v[0] + at[1] * report.gaze.step_deg).to_radians().tan();
        Vec2::new(((gh - x0) * scale) as f32, ((y1 - gv) * scale) as f32)
    };
    let inside: Vec<Option<f64>> = report
        .grid
        .iter()
        .map(|c| (!c.outside).then_some(1.0))
        .collect();
    let mut png = RgbImage::from_fn(width, height, |x, y| {
        let tx = x0 + (f64::from(x) + 0.5) / scale;
        let ty = y1 - (f64::from(y) + 0.5) / scale;
        match sample(&inside, layout.columns, layout.rows, grid_of(tx, ty)) {
            Some(_) => Rgb([255, 255, 255]),
            None => OUTSIDE,
        }
    });
    let object_x: Vec<Option<f64>> = report
        .grid
        .iter()
        .map(|c| c.object_tangent.map(|t| t[0]))
        .collect();
    let object_y: Vec<Option<f64>> = report
        .grid
        .iter()
        .map(|c| c.object_tangent.map(|t| t[1]))
        .collect();
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
    for (values, (lo, hi)) in [(&object_x, (ax, bx)), (&object_y, (ay, by))] {
        if !lo.is_finite() {
            continue;
        }
        let mut level = (lo / step).ceil() * step;
        while level <= hi {
            for [a, b] in iso_segments(values, layout.columns, layout.rows, level) {
                draw_line(&mut png, pixel_of(a), pixel_of(b), INK);
            }
            level += step;
        }
    }
    let title = format!(
        "'{}': straight object lines (every {step} in tangent) as the wearer sees them, on the \
         gaze's tangent screen",
        report.lens
    );
    plot_around(
        png,
        &title,
        ("tan h (the wearer's right)", "tan v (up)"),
        Some((
            Extent {
                min: Vec2::new(x0 as f32, y0 as f32),
                max: Vec2::new(x1 as f32, y1 as f32),
            },
            false,
        )),
        &[(
            "outside the lens".into(),
            [OUTSIDE.0[0], OUTSIDE.0[1], OUTSIDE.0[2]],
        )],
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn iso_lines_of_a_plane_are_straight_where_the_level_lies() {
        // v = column: the level 1.5 runs down the middle of columns 1 and 2.
        let (columns, rows) = (4, 3);
        let values: Vec<Option<f64>> = (0..rows)
            .flat_map(|_| (0..columns).map(|i| Some(i as f64)))
            .collect();
        let segments = iso_segments(&values, columns, rows, 1.5);
        assert_eq!(segments.len(), 2);
        for [a, b] in segments {
            assert!((a[0] - 1.5).abs() < 1e-12 && (b[0] - 1.5).abs() < 1e-12);
        }
        // A saddle whose centre sides with a and c: the lines cut off b and d.
        // Row 0: a = 1, b = 0; row 1: d = 0, c = 1.
        let saddle = [Some(1.0), Some(0.0), Some(0.0), Some(1.0)];
        let lines = iso_segments(&saddle, 2, 2, 0.4);
        assert_eq!(lines.len(), 2);
        for [p, q] in lines {
            // Each line runs near b = (1, 0) or near d = (0, 1), never across the a–c diagonal.
            let mid = [(p[0] + q[0]) * 0.5, (p[1] + q[1]) * 0.5];
            assert!((mid[0] - mid[1]).abs() > 0.2, "{p:?} {q:?}");
        }
        // A missing corner drops its cells.
        let mut holed = values.clone();
        holed[1] = None;
        assert_eq!(iso_segments(&holed, columns, rows, 1.5).len(), 1);
    }
}
