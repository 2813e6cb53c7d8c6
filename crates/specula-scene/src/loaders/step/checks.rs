//! Geometry that would send truck's conversion or tessellation into NaNs or a runaway
//! subdivision (a fuzzing finding: a zero `DIRECTION` as a plane's reference direction
//! exhausted memory), refused before it is converted, naming the instance.

use super::entities::{list, real, reference, Entities};
use truck_stepio::r#in::ruststep::ast::Parameter;

/// Coordinates beyond this (in file units) are taken as a broken number, not a part.
const MAX_COORDINATE: f64 = 1e12;

pub(super) fn check_geometry(entities: &Entities) -> Result<(), String> {
    for (id, _) in entities.instances() {
        let wrong = |what: &str| Err(format!("{}: {what}", entities.describe(id)));
        if let Some(params) = entities.record(id, "CARTESIAN_POINT") {
            let ok = params.get(1).and_then(list).is_some_and(|xs| {
                xs.iter()
                    .all(|x| real(x).is_some_and(|x| x.is_finite() && x.abs() < MAX_COORDINATE))
            });
            if !ok {
                return wrong("a coordinate that is not a finite number under 1e12");
            }
        }
        if let Some(params) = entities.record(id, "DIRECTION") {
            if direction(params.get(1).and_then(list)).is_none() {
                return wrong("a direction of zero length, or not of finite numbers");
            }
        }
        if let Some(params) = entities.record(id, "VECTOR") {
            if !params
                .get(2)
                .and_then(real)
                .is_some_and(|m| m.is_finite() && m > 0.0)
            {
                return wrong("a vector whose magnitude is not a positive number");
            }
        }
        if let Some(params) = entities.record(id, "AXIS2_PLACEMENT_3D") {
            let axis = params
                .get(2)
                .and_then(reference)
                .and_then(|d| direction_of(entities, d));
            let reference_direction = params
                .get(3)
                .and_then(reference)
                .and_then(|d| direction_of(entities, d));
            if let (Some(a), Some(r)) = (axis, reference_direction) {
                if cross_length(a, r) < 1e-9 {
                    return wrong("its axis and reference direction are parallel: no frame");
                }
            }
        }
        for (name, radii) in [
            ("CIRCLE", &[2][..]),
            ("SPHERICAL_SURFACE", &[2]),
            ("CYLINDRICAL_SURFACE", &[2]),
            ("TOROIDAL_SURFACE", &[2, 3]),
            ("ELLIPSE", &[2, 3]),
        ] {
            if let Some(params) = entities.record(id, name) {
                let ok = radii.iter().all(|&i| {
                    params
                        .get(i)
                        .and_then(real)
                        .is_some_and(|r| r.is_finite() && r > 0.0 && r < MAX_COORDINATE)
                });
                if !ok {
                    return wrong("a radius that is not a positive number");
                }
            }
        }
        if let Err(what) =
            b_spline_curve(entities, id).and_then(|()| b_spline_surface(entities, id))
        {
            return wrong(&what);
        }
        for name in ["RATIONAL_B_SPLINE_SURFACE", "RATIONAL_B_SPLINE_CURVE"] {
            if let Some(params) = entities.record(id, name) {
                let mut weights = Vec::new();
                collect_reals(params, &mut weights);
                if weights.is_empty() || !weights.iter().all(|w| w.is_finite() && *w > 0.0) {
                    return wrong("a weight that is not a positive number");
                }
            }
        }
    }
    Ok(())
}

/// A B-spline curve's parameters, simple or complex: degree, control points, multiplicities
/// and knots agree (Σ multiplicities = points + degree + 1, knots rising).
fn b_spline_curve(entities: &Entities, id: u64) -> Result<(), String> {
    let (degree, points, multiplicities, knots) = if let Some(p) = entities
        .record(id, "B_SPLINE_CURVE_WITH_KNOTS")
        .filter(|p| p.len() >= 8)
    {
        (p.get(1), p.get(2), p.get(6), p.get(7))
    } else if let (Some(curve), Some(k)) = (
        entities.record(id, "B_SPLINE_CURVE"),
        entities.record(id, "B_SPLINE_CURVE_WITH_KNOTS"),
    ) {
        (curve.first(), curve.get(1), k.first(), k.get(1))
    } else {
        return Ok(());
    };
    let points = points.and_then(list).map_or(0, <[_]>::len);
    knot_vector(degree.and_then(real), points, multiplicities, knots)
}

/// A B-spline surface's parameters, simple or complex, as [`b_spline_curve`]'s in each
/// direction, its control net rectangular.
fn b_spline_surface(entities: &Entities, id: u64) -> Result<(), String> {
    let (degrees, net, multiplicities, knots) = if let Some(p) = entities
        .record(id, "B_SPLINE_SURFACE_WITH_KNOTS")
        .filter(|p| p.len() >= 12)
    {
        (
            (p.get(1), p.get(2)),
            p.get(3),
            (p.get(8), p.get(9)),
            (p.get(10), p.get(11)),
        )
    } else if let (Some(surface), Some(k)) = (
        entities.record(id, "B_SPLINE_SURFACE"),
        entities.record(id, "B_SPLINE_SURFACE_WITH_KNOTS"),
    ) {
        (
            (surface.first(), surface.get(1)),
            surface.get(2),
            (k.first(), k.get(1)),
            (k.get(2), k.get(3)),
        )
    } else {
        return Ok(());
    };
    let rows: Vec<usize> = net
        .and_then(list)
        .map(|rows| rows.iter().map(|r| list(r).map_or(0, <[_]>::len)).collect())
        .unwrap_or_default();
    if rows.is_empty() || rows.iter().any(|&n| n != rows[0]) {
        return Err("a control net whose rows are not all of one length".into());
    }
    knot_vector(
        degrees.0.and_then(real),
        rows.len(),
        multiplicities.0,
        knots.0,
    )?;
    knot_vector(degrees.1.and_then(real), rows[0], multiplicities.1, knots.1)
}

fn knot_vector(
    degree: Option<f64>,
    points: usize,
    multiplicities: Option<&Parameter>,
    knots: Option<&Parameter>,
) -> Result<(), String> {
    let degree = degree
        .filter(|d| d.fract() == 0.0 && (1.0..=25.0).contains(d))
        .ok_or("a degree that is not a whole number from 1 to 25")? as usize;
    let numbers = |p: Option<&Parameter>| -> Vec<f64> {
        p.and_then(list)
            .and_then(|xs| xs.iter().map(real).collect())
            .unwrap_or_default()
    };
    let (multiplicities, knots) = (numbers(multiplicities), numbers(knots));
    let total: f64 = multiplicities.iter().sum();
    // Some writers repeat a knot rather than raise its multiplicity: non-decreasing is enough.
    let increasing = knots.windows(2).all(|w| w[0] <= w[1])
        && knots.iter().all(|k| k.is_finite())
        && knots.last() > knots.first();
    let whole = multiplicities
        .iter()
        .all(|&m| m.fract() == 0.0 && m >= 1.0 && m <= (degree + 1) as f64);
    if points <= degree
        || knots.len() < 2
        || knots.len() != multiplicities.len()
        || !increasing
        || !whole
        || total != (points + degree + 1) as f64
    {
        return Err(format!(
            "a B-spline whose degree ({degree}), {points} control points, knot multiplicities and knots do not agree (the multiplicities must add up to points + degree + 1, each at most degree + 1, the knots rise)"
        ));
    }
    Ok(())
}

fn direction(
    components: Option<&[truck_stepio::r#in::ruststep::ast::Parameter]>,
) -> Option<[f64; 3]> {
    let xs: Vec<f64> = components?.iter().map(real).collect::<Option<_>>()?;
    let mut d = [0.0; 3];
    for (k, x) in xs.iter().take(3).enumerate() {
        d[k] = *x;
    }
    let length = d.iter().map(|x| x * x).sum::<f64>().sqrt();
    (xs.len() >= 2 && length.is_finite() && length > 1e-12).then(|| d.map(|x| x / length))
}

fn direction_of(entities: &Entities, id: u64) -> Option<[f64; 3]> {
    direction(entities.record(id, "DIRECTION")?.get(1).and_then(list))
}

fn cross_length(a: [f64; 3], b: [f64; 3]) -> f64 {
    let c = [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ];
    c.iter().map(|x| x * x).sum::<f64>().sqrt()
}

fn collect_reals(params: &[truck_stepio::r#in::ruststep::ast::Parameter], out: &mut Vec<f64>) {
    for p in params {
        match list(p) {
            Some(inner) => collect_reals(inner, out),
            None => out.extend(real(p)),
        }
    }
}

/// The largest radius of the file's circles, ellipses and elementary surfaces (file units):
/// truck cuts a circle to at best a millionth of its radius (it panics below), so this bounds
/// the chord tolerance from below.
pub(super) fn largest_radius(entities: &Entities) -> f64 {
    let mut largest: f64 = 0.0;
    for (id, _) in entities.instances() {
        for (name, radii) in [
            ("CIRCLE", &[2][..]),
            ("ELLIPSE", &[2, 3]),
            ("SPHERICAL_SURFACE", &[2]),
            ("CYLINDRICAL_SURFACE", &[2]),
            ("CONICAL_SURFACE", &[2]),
            ("TOROIDAL_SURFACE", &[2, 3]),
        ] {
            if let Some(params) = entities.record(id, name) {
                for &i in radii {
                    if let Some(r) = params.get(i).and_then(real).filter(|r| r.is_finite()) {
                        largest = largest.max(r.abs());
                    }
                }
            }
        }
    }
    largest
}

/// The largest coordinate of the file's points (file units): a tessellation finer than a
/// millionth of it is finer than a part needs and, on a point flung far off by a broken file,
/// would take minutes.
pub(super) fn largest_coordinate(entities: &Entities) -> f64 {
    let mut largest: f64 = 0.0;
    for (id, _) in entities.instances() {
        if let Some(xs) = entities
            .record(id, "CARTESIAN_POINT")
            .and_then(|p| p.get(1))
            .and_then(list)
        {
            for x in xs.iter().filter_map(real) {
                largest = largest.max(x.abs());
            }
        }
    }
    largest
}
