//! The lens map, the clear zones and a progressive lens's figures.
//!
//! **The lens map** samples the lens in its own frame (x to the wearer's right, y up, mm from
//! the back vertex; as worn for a tilted or wrapped lens) every `lens_step_mm` over its disc:
//! at each point the eye turns until its chief ray crosses the back surface there (Newton's
//! method on the crossing's miss, to within 1e-4 mm),
//! and the point gets that gaze's figures (module doc of [`super`]). Power errors and unwanted
//! cylinder are against the target, or, without a prescription, against the lens's own power
//! at the fitting point.
//!
//! **Clear zones**, for three criteria (unwanted cylinder ≤ 0.25 D, ≤ 0.50 D, |power error|
//! ≤ 0.25 D): the lens area where it holds (map points × step²), the gaze solid angle where
//! it holds over the gaze grid (each gaze cell's solid angle on the tangent screen,
//! sec²h sec²v Δh Δv / (1 + tan²h + tan²v)^{3/2}), and the horizontal clear width through
//! the fitting point (the run of the fitting point's row that holds it, its ends interpolated
//! between samples).
//!
//! **Progressive figures** (with an ordered add), from the map: the corridor is, row by row
//! from the distance reference point to the near reference point, the point of least
//! unwanted cylinder within 8 mm of the line joining them; the map's add is the mean power at
//! the near reference point less that at the distance reference point; the corridor length is
//! from the fitting point down to where the corridor's mean power first reaches 85 % and 95 %
//! of that add over the far mean power; the corridor width at 0.50 and 1.00 D is the run
//! around the corridor with unwanted cylinder at most that, on the row where the corridor has
//! half the add; the far and near zone widths are the runs at 0.50 D on the reference points'
//! rows; the largest unwanted cylinder is over the whole map. The measured add is the
//! focimeter's mean power (sphere + cylinder / 2, on the progressive surface's side) at the
//! near reference point less that at the distance reference point: the mean, because a
//! spherical far zone has no meridian to read the sphere in, and because the near zone's
//! small cylinder (unwanted, not ordered) should not move the add.

use glam::{DVec2, DVec3};
use serde::Serialize;

use super::focimeter::{LensFrame, Reading};
use super::wear::Rx;
use super::{figures, Cell, Central, Setup};

/// One point of the lens map.
#[derive(Clone, Debug, Serialize)]
pub struct MapPoint {
    /// In the lens's frame, mm from the back vertex (x right, y up).
    pub at_mm: [f64; 2],
    pub cell: Cell,
}

/// The lens map (module doc).
#[derive(Clone, Debug, Serialize)]
pub struct LensMap {
    pub step_mm: f64,
    pub columns: usize,
    pub rows: usize,
    /// The first point's coordinates (the lowest row's leftmost), mm.
    pub origin_mm: [f64; 2],
    /// What power errors and unwanted cylinder are taken against.
    pub reference: Rx,
    /// Row by row from the lowest y, each from the smallest x.
    pub points: Vec<MapPoint>,
}

impl LensMap {
    /// `value` of the map bilinearly at `at_mm`; None next to a point outside the lens.
    pub fn sample(&self, at_mm: DVec2, value: impl Fn(&Cell) -> Option<f64>) -> Option<f64> {
        let g = (at_mm - DVec2::from(self.origin_mm)) / self.step_mm;
        let (columns, rows) = (self.columns, self.rows);
        if columns < 2
            || rows < 2
            || g.x < 0.0
            || g.y < 0.0
            || g.x > (columns - 1) as f64
            || g.y > (rows - 1) as f64
        {
            return None;
        }
        let (i, j) = (
            (g.x.floor() as usize).min(columns - 2),
            (g.y.floor() as usize).min(rows - 2),
        );
        let (fx, fy) = (g.x - i as f64, g.y - j as f64);
        let v = |di: usize, dj: usize| value(&self.points[(j + dj) * columns + i + di].cell);
        let (a, b, c, d) = (v(0, 0)?, v(1, 0)?, v(0, 1)?, v(1, 1)?);
        Some((a * (1.0 - fx) + b * fx) * (1.0 - fy) + (c * (1.0 - fx) + d * fx) * fy)
    }

    fn row_of(&self, y_mm: f64) -> usize {
        (((y_mm - self.origin_mm[1]) / self.step_mm).round().max(0.0) as usize).min(self.rows - 1)
    }

    fn column_of(&self, x_mm: f64) -> usize {
        (((x_mm - self.origin_mm[0]) / self.step_mm).round().max(0.0) as usize)
            .min(self.columns - 1)
    }

    /// The run of row `row` around column `column` where `holds`, mm, its ends interpolated
    /// linearly between the last point that holds and the first that does not (`margin`
    /// gives how far inside the criterion a point is: positive inside); 0 where the column
    /// itself fails.
    fn run_width(&self, row: usize, column: usize, margin: impl Fn(&Cell) -> Option<f64>) -> f64 {
        let at = |i: usize| margin(&self.points[row * self.columns + i].cell);
        if at(column).is_none_or(|m| m < 0.0) {
            return 0.0;
        }
        let end = |step: isize| {
            let mut i = column as isize;
            loop {
                let next = i + step;
                if next < 0 || next >= self.columns as isize {
                    return i as f64;
                }
                match (at(i as usize), at(next as usize)) {
                    (Some(inside), Some(outside)) if outside < 0.0 => {
                        return i as f64 + step as f64 * inside / (inside - outside);
                    }
                    (_, None) => return i as f64,
                    _ => i = next,
                }
            }
        };
        (end(1) - end(-1)) * self.step_mm
    }
}

/// A lens's map over its disc of radius `rim_mm` (module doc).
pub(super) fn lens_map(
    setup: &Setup,
    frame: &LensFrame,
    rim_mm: f64,
    step_mm: f64,
    central: &Central,
    reference: &Rx,
) -> LensMap {
    use rayon::prelude::*;
    let n = (rim_mm / step_mm).floor() as i64;
    let values: Vec<f64> = (-n..=n).map(|k| k as f64 * step_mm).collect();
    let points: Vec<MapPoint> = values
        .par_iter()
        .flat_map_iter(|&y| values.iter().map(move |&x| (x, y)))
        .map(|(x, y)| {
            let gaze = (x.hypot(y) <= rim_mm - 0.5 * step_mm)
                .then(|| gaze_through(setup, frame, [x, y]))
                .flatten();
            let cell = match gaze {
                Some([h, v]) => figures(setup, h, v, central, Some(reference)),
                // Off the lens: the gaze straight at the point.
                None => {
                    let point = frame.back_vertex + (frame.right * x + frame.up * y) * 1e-3;
                    let dir = (point - setup.options.rotation_centre).normalize();
                    Cell::outside(angles(setup, dir))
                }
            };
            MapPoint {
                at_mm: [x, y],
                cell,
            }
        })
        .collect();
    LensMap {
        step_mm,
        columns: values.len(),
        rows: values.len(),
        origin_mm: [values[0], values[0]],
        reference: *reference,
        points,
    }
}

/// The gaze (h, v degrees) whose chief ray crosses the back surface at `at_mm` in `frame`.
pub(super) fn gaze_through(setup: &Setup, frame: &LensFrame, at_mm: [f64; 2]) -> Option<[f64; 2]> {
    let o = setup.options;
    let want = DVec2::from(at_mm) * 1e-3;
    // Where the line from the centre through the point `aim` of the back vertex's plane
    // crosses the back surface, in the lens's (right, up).
    let crossing = |aim: DVec2| -> Option<(DVec2, DVec3)> {
        let p = frame.back_vertex + frame.right * aim.x + frame.up * aim.y;
        let dir = (p - o.rotation_centre).normalize();
        let chief = setup
            .tracer
            .trace(o.rotation_centre, dir, setup.indices.y)
            .ok()?;
        let q = chief.points[0] - frame.back_vertex;
        Some((DVec2::new(q.dot(frame.right), q.dot(frame.up)), dir))
    };
    // Newton's method, the Jacobian by forward differences over 1 µm.
    let mut aim = want;
    for _ in 0..12 {
        let (at, dir) = crossing(aim)?;
        let miss = want - at;
        if miss.length() < 1e-7 {
            return Some(angles(setup, dir));
        }
        let e = 1e-6;
        let dx = (crossing(aim + DVec2::X * e)?.0 - at) / e;
        let dy = (crossing(aim + DVec2::Y * e)?.0 - at) / e;
        let det = dx.x * dy.y - dy.x * dx.y;
        if det.abs() < 1e-12 {
            return None;
        }
        aim += DVec2::new(
            (miss.x * dy.y - dy.x * miss.y) / det,
            (dx.x * miss.y - miss.x * dx.y) / det,
        );
    }
    None
}

/// A direction's gaze angles on the primary tangent screen, degrees.
pub(super) fn angles(setup: &Setup, dir: DVec3) -> [f64; 2] {
    let forward = dir.dot(setup.options.forward);
    [
        dir.dot(setup.right).atan2(forward).to_degrees(),
        dir.dot(setup.options.up).atan2(forward).to_degrees(),
    ]
}

/// One criterion's clear zone.
#[derive(Clone, Debug, Serialize)]
pub struct ClearZone {
    /// "unwanted cylinder ≤ 0.25 D", "unwanted cylinder ≤ 0.50 D" or "|power error| ≤ 0.25 D".
    pub criterion: &'static str,
    pub lens_area_mm2: f64,
    pub solid_angle_sr: f64,
    /// Through the fitting point, along the lens's x.
    pub horizontal_width_mm: f64,
}

/// How far inside each criterion a cell is (positive inside), against `reference`.
pub(super) const CRITERIA: [&str; 3] = [
    "unwanted cylinder ≤ 0.25 D",
    "unwanted cylinder ≤ 0.50 D",
    "|power error| ≤ 0.25 D",
];

fn margin(criterion: usize, cell: &Cell, reference: &Rx) -> Option<f64> {
    let (error, unwanted) = deviation(cell, reference)?;
    Some(match criterion {
        0 => 0.25 - unwanted,
        1 => 0.50 - unwanted,
        _ => 0.25 - error.abs(),
    })
}

/// A cell's power error and unwanted cylinder against `reference`: its own where it was
/// computed against a target, else from its powers.
fn deviation(cell: &Cell, reference: &Rx) -> Option<(f64, f64)> {
    if let (Some(e), Some(u)) = (cell.power_error_d, cell.unwanted_cylinder_d) {
        return Some((e, u));
    }
    let got = Rx::new(cell.sphere_d?, cell.cylinder_d?, cell.axis_deg?).power_vector();
    let want = reference.power_vector();
    let (dj0, dj45) = (got[1] - want[1], got[2] - want[2]);
    Some((got[0] - want[0], 2.0 * dj0.hypot(dj45)))
}

/// The clear zones over the map and the gaze grid (module doc).
pub(super) fn clear_zones(
    map: &LensMap,
    grid: &[Cell],
    gaze_step_deg: f64,
    fitting_mm: DVec2,
) -> Vec<ClearZone> {
    let step = gaze_step_deg.to_radians();
    let solid_angle = |cell: &Cell| {
        let [h, v] = cell.gaze_deg.map(f64::to_radians);
        let (th, tv) = (h.tan(), v.tan());
        (1.0 + th * th) * (1.0 + tv * tv) * step * step / (1.0 + th * th + tv * tv).powf(1.5)
    };
    let (row, column) = (map.row_of(fitting_mm.y), map.column_of(fitting_mm.x));
    (0..CRITERIA.len())
        .map(|k| {
            let holds = |cell: &Cell| margin(k, cell, &map.reference).is_some_and(|m| m >= 0.0);
            ClearZone {
                criterion: CRITERIA[k],
                lens_area_mm2: map.points.iter().filter(|p| holds(&p.cell)).count() as f64
                    * map.step_mm
                    * map.step_mm,
                solid_angle_sr: grid.iter().filter(|c| holds(c)).map(solid_angle).sum(),
                horizontal_width_mm: map.run_width(row, column, |c| margin(k, c, &map.reference)),
            }
        })
        .collect()
}

/// A progressive lens's figures (module doc), in the JSON's terms.
#[derive(Clone, Debug, Serialize)]
pub struct Progressive {
    /// The ordered addition.
    pub ordered_add_d: f64,
    /// The measured add (focimeter, on the progressive surface's side).
    pub add_d: f64,
    /// Which side the focimeter measured the add on: "front" or "back".
    pub measured_on: &'static str,
    /// The focimeter's mean powers at the distance and the near reference points (the
    /// progressive surface's side).
    pub far_power_d: f64,
    pub near_power_d: f64,
    pub distance_reference_mm: [f64; 2],
    pub near_reference_mm: [f64; 2],
    /// The map's (as worn) add: mean power at the near less at the distance reference point.
    pub map_add_d: f64,
    pub corridor_length_mm_85: Option<f64>,
    pub corridor_length_mm_95: Option<f64>,
    /// On the row where the corridor has half the add; None where it never does.
    pub corridor_width_mm_050: Option<f64>,
    pub corridor_width_mm_100: Option<f64>,
    pub far_zone_width_mm_050: f64,
    pub near_zone_width_mm_050: f64,
    pub max_unwanted_cylinder_d: f64,
    pub max_unwanted_cylinder_at_mm: [f64; 2],
    /// The corridor's points, from the distance to the near reference point's row, mm.
    pub corridor_mm: Vec<[f64; 2]>,
}

/// The progressive figures of `map` (module doc); None where a reference point lies off the
/// lens map.
pub(super) fn progressive(
    map: &LensMap,
    readings: [&Reading; 2],
    measured_on: &'static str,
    ordered_add_d: f64,
    fitting_mm: DVec2,
) -> Option<Progressive> {
    let [far, near] = readings;
    let (far_at, near_at) = (DVec2::from(far.at_mm), DVec2::from(near.at_mm));
    let unwanted = |c: &Cell| deviation(c, &map.reference).map(|d| d.1);
    let mean = |c: &Cell| c.mean_power_d;
    let far_mean = map.sample(far_at, mean)?;
    let map_add = map.sample(near_at, mean)? - far_mean;
    // The corridor, row by row from the far to the near reference point.
    let (top, bottom) = (map.row_of(far_at.y), map.row_of(near_at.y));
    let mut corridor = Vec::new();
    for row in (bottom..=top).rev() {
        let y = map.origin_mm[1] + row as f64 * map.step_mm;
        let along = ((far_at.y - y) / (far_at.y - near_at.y)).clamp(0.0, 1.0);
        let line_x = far_at.x + (near_at.x - far_at.x) * along;
        let best = (0..map.columns)
            .filter(|&i| (map.origin_mm[0] + i as f64 * map.step_mm - line_x).abs() <= 8.0)
            .filter_map(|i| {
                let cell = &map.points[row * map.columns + i].cell;
                Some((i, unwanted(cell)?, mean(cell)?))
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))?;
        corridor.push((row, best.0, best.2));
    }
    let at = |row: usize, column: usize| {
        [
            map.origin_mm[0] + column as f64 * map.step_mm,
            map.origin_mm[1] + row as f64 * map.step_mm,
        ]
    };
    // Where the corridor's mean power first reaches `share` of the add, below the fitting
    // point, interpolated between rows.
    let reaches = |share: f64| {
        let level = far_mean + share * map_add;
        corridor
            .windows(2)
            .find(|w| w[0].2 < level && w[1].2 >= level)
            .map(|w| {
                let (ya, yb) = (at(w[0].0, w[0].1)[1], at(w[1].0, w[1].1)[1]);
                let y = ya + (yb - ya) * (level - w[0].2) / (w[1].2 - w[0].2);
                fitting_mm.y - y
            })
    };
    // The row where the corridor has half the add; none where it never gets there.
    let half = corridor
        .iter()
        .find(|c| map_add > 0.01 && c.2 >= far_mean + 0.5 * map_add)
        .copied();
    let width = |row: usize, column: usize, limit: f64| {
        map.run_width(row, column, |c| unwanted(c).map(|u| limit - u))
    };
    let (worst_at, worst) = map
        .points
        .iter()
        .filter_map(|p| Some((p.at_mm, unwanted(&p.cell)?)))
        .max_by(|a, b| a.1.total_cmp(&b.1))?;
    let mean_power = |r: &Reading| r.sphere_d + 0.5 * r.cylinder_d;
    Some(Progressive {
        ordered_add_d,
        add_d: mean_power(near) - mean_power(far),
        measured_on,
        far_power_d: mean_power(far),
        near_power_d: mean_power(near),
        distance_reference_mm: far.at_mm,
        near_reference_mm: near.at_mm,
        map_add_d: map_add,
        corridor_length_mm_85: reaches(0.85),
        corridor_length_mm_95: reaches(0.95),
        corridor_width_mm_050: half.map(|h| width(h.0, h.1, 0.5)),
        corridor_width_mm_100: half.map(|h| width(h.0, h.1, 1.0)),
        far_zone_width_mm_050: width(top, map.column_of(far_at.x), 0.5),
        near_zone_width_mm_050: width(bottom, map.column_of(near_at.x), 0.5),
        max_unwanted_cylinder_d: worst,
        max_unwanted_cylinder_at_mm: worst_at,
        corridor_mm: corridor.iter().map(|&(r, c, _)| at(r, c)).collect(),
    })
}
