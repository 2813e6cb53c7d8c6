//! A field rasterised in its own frame and the eyes' footprints over it: what is seen within
//! the range, what the vehicle's body hides, the part beyond the range and the horizon
//! judged in direction space, and the margins.

use super::*;

/// A grid over a field's own frame: lateral s (columns) × longitudinal d (rows).
#[derive(Clone, Copy)]
pub(super) struct FieldGrid {
    s0: f64,
    d0: f64,
    ds: f64,
    dd: f64,
    columns: usize,
    rows: usize,
}

impl FieldGrid {
    fn cell(&self, column: usize, row: usize) -> (f64, f64) {
        (
            self.s0 + (column as f64 + 0.5) * self.ds,
            self.d0 + (row as f64 + 0.5) * self.dd,
        )
    }

    /// Marks the cells whose centres lie in the footprint triangles (world x, z), mapped into the
    /// field's frame.
    fn fill(
        &self,
        covered: &mut [bool],
        triangles: &[[Vec2; 3]],
        to_field: &impl Fn(Vec2) -> (f64, f64),
    ) {
        for t in triangles {
            let q = t.map(to_field);
            let (lo_s, hi_s) = (
                q[0].0.min(q[1].0).min(q[2].0),
                q[0].0.max(q[1].0).max(q[2].0),
            );
            let (lo_d, hi_d) = (
                q[0].1.min(q[1].1).min(q[2].1),
                q[0].1.max(q[1].1).max(q[2].1),
            );
            let c0 = ((lo_s - self.s0) / self.ds).floor().max(0.0) as usize;
            let c1 = (((hi_s - self.s0) / self.ds).ceil().max(0.0) as usize).min(self.columns);
            let r0 = ((lo_d - self.d0) / self.dd).floor().max(0.0) as usize;
            let r1 = (((hi_d - self.d0) / self.dd).ceil().max(0.0) as usize).min(self.rows);
            let edge = |a: (f64, f64), b: (f64, f64), p: (f64, f64)| {
                (b.0 - a.0) * (p.1 - a.1) - (b.1 - a.1) * (p.0 - a.0)
            };
            let area = edge(q[0], q[1], q[2]);
            if area == 0.0 || !area.is_finite() {
                continue;
            }
            for row in r0..r1 {
                for column in c0..c1 {
                    let p = self.cell(column, row);
                    let inside = [
                        edge(q[1], q[2], p),
                        edge(q[2], q[0], p),
                        edge(q[0], q[1], p),
                    ]
                    .iter()
                    .all(|w| w * area >= 0.0);
                    if inside {
                        covered[row * self.columns + column] = true;
                    }
                }
            }
        }
    }
}

/// One eye's cone of reflected directions, rasterised over (horizontal angle from straight
/// back, elevation), degrees.
pub(super) struct Cone {
    lo: Vec2,
    cell: Vec2,
    size: usize,
    covered: Vec<bool>,
}

pub(super) const CONE_GRID: usize = 1024;

impl Cone {
    pub(super) fn new(frame: &VehicleFrame, directions: &[[Vec3; 3]]) -> Cone {
        let back = -frame.forward;
        let angles = |d: Vec3| {
            Vec2::new(
                frame.horizontal_deg(d, back) as f32,
                frame.elevation_deg(d) as f32,
            )
        };
        let (mut lo, mut hi) = (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY));
        for d in directions.iter().flatten() {
            lo = lo.min(angles(*d));
            hi = hi.max(angles(*d));
        }
        if lo.x > hi.x {
            return Cone {
                lo: Vec2::ZERO,
                cell: Vec2::ONE,
                size: 0,
                covered: Vec::new(),
            };
        }
        let cell = ((hi - lo) / CONE_GRID as f32).max(Vec2::splat(1e-6));
        let mut cone = Cone {
            lo,
            cell,
            size: CONE_GRID,
            covered: vec![false; CONE_GRID * CONE_GRID],
        };
        for t in directions {
            let q = t.map(angles);
            // Triangles across the straight-back seam (±180°) are not behind the vehicle.
            if (q[0].x - q[1].x).abs() > 180.0 || (q[1].x - q[2].x).abs() > 180.0 {
                continue;
            }
            let lo_t = q[0].min(q[1]).min(q[2]);
            let hi_t = q[0].max(q[1]).max(q[2]);
            let first = ((lo_t - cone.lo) / cone.cell).floor().max(Vec2::ZERO);
            let last = ((hi_t - cone.lo) / cone.cell).ceil();
            let edge = |a: Vec2, b: Vec2, p: Vec2| (b - a).perp_dot(p - a);
            let area = edge(q[0], q[1], q[2]);
            if area == 0.0 {
                continue;
            }
            for row in first.y as usize..(last.y.max(0.0) as usize).min(cone.size) {
                for column in first.x as usize..(last.x.max(0.0) as usize).min(cone.size) {
                    let p = cone.lo + cone.cell * Vec2::new(column as f32 + 0.5, row as f32 + 0.5);
                    let w = [
                        edge(q[1], q[2], p),
                        edge(q[2], q[0], p),
                        edge(q[0], q[1], p),
                    ];
                    if w.iter().all(|w| w * area >= 0.0) {
                        cone.covered[row * cone.size + column] = true;
                    }
                }
            }
        }
        cone
    }

    /// Whether direction `angles` (horizontal from straight back, elevation; degrees) is in the
    /// cone: its cell, or (`strict` false) any of its 8 neighbours.
    fn contains(&self, angles: Vec2, strict: bool) -> bool {
        if self.size == 0 {
            return false;
        }
        let c = ((angles - self.lo) / self.cell).floor();
        let reach = if strict { 0 } else { 1 };
        let mut any = false;
        for dy in -reach..=reach {
            for dx in -reach..=reach {
                let (x, y) = (c.x as i64 + dx, c.y as i64 + dy);
                if x >= 0 && y >= 0 && (x as usize) < self.size && (y as usize) < self.size {
                    any |= self.covered[y as usize * self.size + x as usize];
                }
            }
        }
        any
    }
}

#[allow(clippy::too_many_arguments)]
pub(super) fn field_figures(
    spec: &FieldSpec,
    regulation: &Regulation,
    vehicle: &Vehicle,
    view: &MirrorView,
    cones: &[Cone],
    set: &[usize],
    range: f64,
    to_field: &impl Fn(Vec2) -> (f64, f64),
    origin: Vec2,
    out: Vec2,
    back: Vec2,
    mirror_centre: Vec3,
) -> FieldFigures {
    let (s_lo, s_hi) = lateral_range(spec);
    let near = spec.from_m;
    let far = spec.to_m.unwrap_or(f64::INFINITY).min(range);
    let mut figures = FieldFigures {
        seen_share: 1.0,
        seen_share_uncertainty: 0.0,
        clear_share_uncertainty: 0.0,
        blind_area_m2: 0.0,
        hidden_by_vehicle_share: 0.0,
        beyond_range_seen_share: None,
        beyond_range_uncertainty: None,
        horizon_seen: None,
        horizon_loosely_seen: None,
        outer_margin_m: 0.0,
        near_margin_m: 0.0,
        verdict: Outcome::Pass,
        passed: true,
    };
    let within = far > near;
    if within {
        seen_within_range(&mut figures, view, set, to_field, (s_lo, s_hi), (near, far));
    }
    // Beyond the range: directions from the mirror's centre to the field's far ground.
    let beyond_from = near.max(range);
    let beyond_to = spec.to_m.unwrap_or(f64::INFINITY);
    let angles_of = |d: Vec3| {
        Vec2::new(
            vehicle.frame.horizontal_deg(d, -vehicle.frame.forward) as f32,
            vehicle.frame.elevation_deg(d) as f32,
        )
    };
    let seen_direction =
        |d: Vec3, strict: bool| set.iter().any(|&k| cones[k].contains(angles_of(d), strict));
    if beyond_to > beyond_from {
        let (share, uncertainty) = beyond_range_share(
            &seen_direction,
            vehicle,
            (s_lo, s_hi),
            (beyond_from, beyond_to),
            (origin, out, back),
            mirror_centre,
        );
        figures.beyond_range_seen_share = Some(share);
        figures.beyond_range_uncertainty = Some(uncertainty);
    }
    if spec.to_m.is_none() {
        figures.horizon_seen = Some(seen_direction(-vehicle.frame.forward, true));
        figures.horizon_loosely_seen = Some(seen_direction(-vehicle.frame.forward, false));
    }
    figures.decide(regulation.allowance(), 0.0);
    figures
}

/// The field's seen share within the range on a grid over it (with the grid's own error and
/// the last refinement's change as its uncertainty), the share the vehicle hides, the blind
/// area and the margins.
pub(super) fn seen_within_range(
    figures: &mut FieldFigures,
    view: &MirrorView,
    set: &[usize],
    to_field: &impl Fn(Vec2) -> (f64, f64),
    (s_lo, s_hi): (f64, f64),
    (near, far): (f64, f64),
) {
    // The share on a grid over the field alone; the margins on one that reaches beyond its
    // outer edge and before its near end.
    let grid = FieldGrid {
        s0: s_lo,
        d0: near,
        ds: (s_hi - s_lo) / 600.0,
        dd: (far - near) / 1200.0,
        columns: 600,
        rows: 1200,
    };
    let cells = grid.columns * grid.rows;
    let (mut seen, mut clear, mut before) =
        (vec![false; cells], vec![false; cells], vec![false; cells]);
    for &k in set {
        grid.fill(&mut seen, &view.footprints[k], to_field);
        grid.fill(&mut clear, &view.clear_footprints[k], to_field);
        grid.fill(&mut before, &view.previous_footprints[k], to_field);
    }
    let count = |cells: &[bool]| cells.iter().filter(|c| **c).count() as f64;
    let hidden = seen.iter().zip(&clear).filter(|(s, c)| **c && !**s).count() as f64;
    // The grid's own error: twice the share's change on a grid of half the resolution
    // (a centre-sampled grid's error halves with its cells, so the change is about the
    // coarse grid's error, twice the fine one's: the factor 2 is a safety margin).
    let coarse = FieldGrid {
        ds: grid.ds * 2.0,
        dd: grid.dd * 2.0,
        columns: grid.columns / 2,
        rows: grid.rows / 2,
        ..grid
    };
    let mut coarse_seen = vec![false; coarse.columns * coarse.rows];
    let mut coarse_clear = coarse_seen.clone();
    for &k in set {
        coarse.fill(&mut coarse_seen, &view.footprints[k], to_field);
        coarse.fill(&mut coarse_clear, &view.clear_footprints[k], to_field);
    }
    let either = |a: &[bool], b: &[bool]| a.iter().zip(b).filter(|(x, y)| **x || **y).count();
    let total = cells as f64;
    figures.clear_share_uncertainty = 2.0
        * (either(&seen, &clear) as f64 / total
            - either(&coarse_seen, &coarse_clear) as f64 / coarse_seen.len() as f64)
            .abs();
    figures.seen_share = count(&seen) / total;
    figures.hidden_by_vehicle_share = hidden / total;
    figures.seen_share_uncertainty = 2.0
        * (figures.seen_share - count(&coarse_seen) / coarse_seen.len() as f64).abs()
        + (count(&seen) - count(&before)).abs() / total;
    figures.blind_area_m2 = (s_hi - s_lo) * (far - near) * (1.0 - figures.seen_share);
    (figures.outer_margin_m, figures.near_margin_m) =
        margins(&view.footprints, set, to_field, (s_lo, s_hi), (near, far));
}

/// The share of the field beyond the range whose directions from the mirror's centre some eye
/// point's cone holds (strictly), on a 48 × 48 grid even in lateral position and in inverse
/// distance; its uncertainty, the share held only loosely.
pub(super) fn beyond_range_share(
    seen_direction: &impl Fn(Vec3, bool) -> bool,
    vehicle: &Vehicle,
    (s_lo, s_hi): (f64, f64),
    (beyond_from, beyond_to): (f64, f64),
    (origin, out, back): (Vec2, Vec2, Vec2),
    mirror_centre: Vec3,
) -> (f64, f64) {
    let (n, mut covered, mut loose) = (48usize, 0usize, 0usize);
    let w_far = if beyond_to.is_finite() {
        1.0 / beyond_to
    } else {
        0.0
    };
    let w_near = 1.0 / beyond_from;
    for i in 0..n {
        for j in 0..n {
            let s = s_lo + (s_hi - s_lo) * (i as f64 + 0.5) / n as f64;
            let w = w_far + (w_near - w_far) * (j as f64 + 0.5) / n as f64;
            let g = origin + out * s as f32 + back * (1.0 / w) as f32;
            let p = Vec3::new(g.x, vehicle.ground_y, g.y);
            let d = (p - mirror_centre).normalize();
            covered += usize::from(seen_direction(d, true));
            loose += usize::from(seen_direction(d, false));
        }
    }
    let total = (n * n) as f64;
    (covered as f64 / total, (loose - covered) as f64 / total)
}

/// How much farther out, and how much nearer the eyes, the field (lateral `s`, longitudinal
/// `d`) could reach and still be seen whole, up to [`MARGIN_REACH_M`]: on a 2000 × 2000 grid
/// whose cell centres fall on the field's outer edge and near end, the whole columns beyond
/// the edge and the whole rows before the end (each exact to a cell).
pub(super) fn margins(
    footprints: &[Vec<[Vec2; 3]>],
    set: &[usize],
    to_field: &impl Fn(Vec2) -> (f64, f64),
    (s_lo, s_hi): (f64, f64),
    (near, far): (f64, f64),
) -> (f64, f64) {
    let n = 2000usize;
    let ds = (s_hi - s_lo + MARGIN_REACH_M) / n as f64;
    let dd = (far - near + MARGIN_REACH_M) / n as f64;
    // Column k's centre is at s_hi + (k − k_edge) ds, row j's at near + (j − j_edge) dd.
    let k_edge = ((s_hi - s_lo) / ds).round() as usize;
    let j_edge = (MARGIN_REACH_M / dd).round() as usize;
    let grid = FieldGrid {
        s0: s_hi - (k_edge as f64 + 0.5) * ds,
        d0: near - (j_edge as f64 + 0.5) * dd,
        ds,
        dd,
        columns: n,
        rows: n,
    };
    let mut seen = vec![false; n * n];
    for &k in set {
        grid.fill(&mut seen, &footprints[k], to_field);
    }
    let eps = 1e-9;
    let column_whole = |column: usize| {
        (0..n).all(|row| {
            let (_, d) = grid.cell(column, row);
            !(near - eps..=far + eps).contains(&d) || seen[row * n + column]
        })
    };
    let row_whole = |row: usize| {
        (0..n).all(|column| {
            let (s, _) = grid.cell(column, row);
            !(s_lo - eps..=s_hi + eps).contains(&s) || seen[row * n + column]
        })
    };
    let outer = if column_whole(k_edge) {
        (k_edge + 1..n).take_while(|&c| column_whole(c)).count() as f64 * ds
    } else {
        0.0
    };
    let nearer = if row_whole(j_edge) {
        (0..j_edge).rev().take_while(|&r| row_whole(r)).count() as f64 * dd
    } else {
        0.0
    };
    (outer, nearer)
}
