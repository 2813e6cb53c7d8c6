//! How far a lens's figures can be trusted: the finite differences' change between the bundle's
//! two widths, and the surface's own uncertainty (a mesh against its smooth fit; a sag grid's
//! interpolation).

use super::*;

/// The largest change of a vergence between the bundle's step and half of it over the centre
/// and the grid, dioptres.
pub(super) fn largest_fd_change(centre: &Cell, grid: &[Cell]) -> f64 {
    std::iter::once(centre)
        .chain(grid)
        .map(|c| c.fd_change_d)
        .fold(0.0, f64::max)
}

/// Where a sag grid is coarse for its surface's curvature: the power uncertainty it brings.
#[derive(Clone, Debug, Serialize)]
pub struct SagGridUncertainty {
    /// The largest power uncertainty over the lens map's points (the focimeter's readings where
    /// there is no map), dioptres.
    pub largest_d: f64,
    /// Points are marked where it exceeds this: (n − 1) × the sag grid's curvature limit
    /// ([`specula_scene::freeform::MAX_CURVATURE_ERROR`]), dioptres.
    pub marked_above_d: f64,
    /// The share of the lens map's points marked, and the box around them (lens frame, mm;
    /// None: none marked).
    pub marked_share: f64,
    pub marked_box_mm: Option<[[f64; 2]; 2]>,
}

/// A sag-grid lens: each focimeter reading's power uncertainty grows by the grid's there
/// (into every verdict that uses it), and the lens map's points where it exceeds the grid's
/// limit are marked (None for a lens without a sag grid).
pub(super) fn sag_grid_uncertainty(
    lens: &Mesh,
    ior: f64,
    readings: [&mut [focimeter::Reading]; 2],
    lens_map: Option<&zones::LensMap>,
) -> Option<SagGridUncertainty> {
    use specula_scene::exact_lens::SurfaceShape;
    let exact = lens.exact.as_ref()?.lens()?;
    let gridded = [&exact.front, &exact.back].iter().any(|s| {
        matches!(
            &s.shape,
            SurfaceShape::Freeform(specula_scene::freeform::Freeform::SagGrid(_))
        )
    });
    if !gridded {
        return None;
    }
    let at = |mm: [f64; 2]| exact.power_uncertainty_d(mm[0] * 1e-3, mm[1] * 1e-3, ior);
    let mut largest: f64 = 0.0;
    for reading in readings.into_iter().flatten() {
        let u = at(reading.at_mm);
        reading.uncertainty_d += u;
        largest = largest.max(u);
    }
    let marked_above_d = (ior - 1.0) * specula_scene::freeform::MAX_CURVATURE_ERROR;
    let (mut marked, mut total) = (0usize, 0usize);
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for point in lens_map.iter().flat_map(|m| &m.points) {
        if point.cell.outside {
            continue;
        }
        total += 1;
        let u = at(point.at_mm);
        largest = largest.max(u);
        if u > marked_above_d {
            marked += 1;
            for k in 0..2 {
                lo[k] = lo[k].min(point.at_mm[k]);
                hi[k] = hi[k].max(point.at_mm[k]);
            }
        }
    }
    Some(SagGridUncertainty {
        largest_d: largest,
        marked_above_d,
        marked_share: marked as f64 / total.max(1) as f64,
        marked_box_mm: (marked > 0).then_some([lo, hi]),
    })
}

/// A mesh lens's add readings, their powers' uncertainties grown by their change when the
/// other of the mesh and its smooth fit is read (the add is their difference, so its
/// uncertainty, the sum of theirs, takes in the surface's).
pub(super) fn add_surface_uncertainty(
    lens: &Mesh,
    options: &Options,
    ior: f64,
    add_focimeter: &mut [focimeter::Reading],
) -> Result<(), AnalyzeError> {
    let other = match options.surface {
        _ if add_focimeter.is_empty() => return Ok(()),
        SurfaceModel::Exact => return Ok(()),
        SurfaceModel::Mesh => SurfaceModel::Smooth,
        SurfaceModel::Smooth => SurfaceModel::Mesh,
    };
    let (others, _) = read_add(&tracer(lens, other)?, lens, options, ior)?;
    for (reading, other) in add_focimeter.iter_mut().zip(&others) {
        reading.uncertainty_d += (reading.sphere_d - other.sphere_d)
            .abs()
            .max((reading.cylinder_d - other.cylinder_d).abs());
    }
    Ok(())
}

/// A mesh lens's surface uncertainty (the `surface_uncertainty_d` of [`Report`]; None on the
/// exact surface): the largest change of a power over the grid and the focimeter's readings
/// when the other of the mesh and its smooth fit is traced; the readings' uncertainties grow
/// by their change.
#[allow(clippy::too_many_arguments)]
pub(super) fn surface_uncertainty(
    setup: &Setup,
    lens: &Mesh,
    worn: &Mesh,
    central: &Central,
    target: Option<&Rx>,
    (centre, grid): (&Cell, &[Cell]),
    focimeter: &mut [focimeter::Reading],
    fitting_point: DVec3,
) -> Result<Option<f64>, AnalyzeError> {
    let options = setup.options;
    let other = match options.surface {
        SurfaceModel::Exact => return Ok(None),
        SurfaceModel::Mesh => SurfaceModel::Smooth,
        SurfaceModel::Smooth => SurfaceModel::Mesh,
    };
    let other_setup = Setup::new(tracer(worn, other)?, options, setup.indices, &lens.name)?;
    let (other_centre, other_grid) = other_setup.grid(central, target, &|_| {});
    let other_placed = tracer(lens, other)?;
    let other_readings =
        read_focimeter(&other_placed, lens, options, setup.indices.y, fitting_point)?;
    let mut change =
        cells_change(std::iter::once((centre, &other_centre)).chain(grid.iter().zip(&other_grid)));
    for (reading, other) in focimeter.iter_mut().zip(&other_readings) {
        let powers = (reading.sphere_d - other.sphere_d)
            .abs()
            .max((reading.cylinder_d - other.cylinder_d).abs());
        change = change.max(powers);
        reading.uncertainty_d += powers;
        reading.prism_uncertainty_d += (reading.prism_d[0] - other.prism_d[0])
            .abs()
            .max((reading.prism_d[1] - other.prism_d[1]).abs());
        if reading.cylinder_d.abs() > 1e-6 {
            let d = (reading.axis_deg - other.axis_deg).rem_euclid(180.0);
            reading.axis_uncertainty_deg += d.min(180.0 - d);
        }
    }
    Ok(Some(change))
}

/// The largest change of a sphere, cylinder or mean power between paired cells inside both.
pub(super) fn cells_change<'c>(pairs: impl Iterator<Item = (&'c Cell, &'c Cell)>) -> f64 {
    let change = |a: Option<f64>, b: Option<f64>| match (a, b) {
        (Some(a), Some(b)) => (a - b).abs(),
        _ => 0.0,
    };
    pairs
        .map(|(a, b)| {
            change(a.sphere_d, b.sphere_d)
                .max(change(a.cylinder_d, b.cylinder_d))
                .max(change(a.mean_power_d, b.mean_power_d))
        })
        .fold(0.0, f64::max)
}
