//! Geometry that would send truck's conversion or tessellation into NaNs or a runaway
//! subdivision (a fuzzing finding: a zero `DIRECTION` as a plane's reference direction
//! exhausted memory), refused before it is converted, naming the instance.

use super::entities::{list, real, reference, Entities};

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
