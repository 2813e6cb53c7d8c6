//! A progressive lens's figures: the lens map, the add read at the near reference point, the
//! corridor and zones, and their standards.

use super::*;

/// The lens map of the worn lens over its disc (None without a step), refused where the step
/// leaves fewer than two points across the radius or more than a million.
pub(super) fn lens_map_of(
    setup: &Setup,
    frame: &LensFrame,
    worn: &Mesh,
    central: &Central,
    reference: &Rx,
) -> Result<Option<zones::LensMap>, AnalyzeError> {
    let Some(step) = setup.options.lens_step_mm else {
        return Ok(None);
    };
    let rim = rim_mm(worn, frame);
    let points = (2.0 * (rim / step).floor() + 1.0).powi(2);
    if step > 0.5 * rim || points > 1e6 {
        return Err(AnalyzeError::BadOption {
            option: "lens_step",
            reason: format!(
                "{step} mm over a lens {rim:.1} mm in radius: the lens map needs a step of at \
                 most half the radius and at most a million points"
            ),
        });
    }
    Ok(Some(zones::lens_map(
        setup, frame, rim, step, central, reference,
    )))
}

/// A progressive lens's add (the focimeter on its progressive side) and figures from the lens
/// map, with an ordered add; nothing without one.
pub(super) fn progressive_figures(
    placed: &LensTracer,
    lens: &Mesh,
    options: &Options,
    ior: f64,
    lens_map: Option<&zones::LensMap>,
    fitting_mm: glam::DVec2,
) -> Result<(Vec<focimeter::Reading>, Option<zones::Progressive>), AnalyzeError> {
    let Some(add) = options.add_d else {
        return Ok((Vec::new(), None));
    };
    let (mut readings, side) = read_add(placed, lens, options, ior)?;
    add_surface_uncertainty(lens, options, ior, &mut readings)?;
    let map = lens_map.ok_or_else(|| AnalyzeError::BadOption {
        option: "add",
        reason: "a progressive lens's figures come from the lens map: give `lens_step`".into(),
    })?;
    let figures = zones::progressive(map, [&readings[0], &readings[1]], side, add, fitting_mm)
        .ok_or_else(|| AnalyzeError::BadOption {
            option: "`distance_reference` and `near_reference`",
            reason: format!(
                "the reference points {:?} and {:?} mm must lie on the lens map, inside the \
                 lens",
                readings[0].at_mm, readings[1].at_mm
            ),
        })?;
    Ok((readings, Some(figures)))
}

/// The standards that judge an add, for an error.
pub(super) fn progressive_standards() -> String {
    standard::STANDARDS
        .iter()
        .filter(|t| t.is_progressive() || t.progressive.is_some())
        .map(|t| t.id)
        .collect::<Vec<_>>()
        .join(" or ")
}

/// The lens's own frame as worn: an exact lens's, else the fitting point's with the primary
/// gaze and up.
pub(super) fn worn_frame(worn: &Mesh, setup: &Setup) -> LensFrame {
    match worn.exact.as_ref().and_then(|e| Some((e, e.lens()?))) {
        Some((exact, lens)) => LensFrame::of_exact(exact.world_from_object, lens.back.vertex_z),
        None => LensFrame {
            back_vertex: setup.primary.points[0],
            towards_eye: -setup.options.forward,
            right: setup.right,
            up: setup.options.up,
        },
    }
}

/// How far the lens reaches from its axis in `frame`, mm: an exact lens's rim, else its
/// farthest vertex.
pub(super) fn rim_mm(worn: &Mesh, frame: &LensFrame) -> f64 {
    match worn.exact.as_ref().and_then(|e| e.lens()) {
        Some(lens) => lens.rim() * 1e3,
        None => worn
            .positions
            .iter()
            .map(|p| frame.mm_of(p.as_dvec3()).length())
            .fold(0.0, f64::max),
    }
}

/// The lens's own power at a cell, as a prescription (no power where the cell is outside).
pub(super) fn own_power(cell: &Cell) -> Rx {
    Rx::new(
        cell.sphere_d.unwrap_or(0.0),
        cell.cylinder_d.unwrap_or(0.0),
        cell.axis_deg.unwrap_or(0.0),
    )
}

/// The focimeter at the distance and near reference points on the progressive surface's side
/// of the lens as the scene places it, and which side that is; refused where the lens has no
/// free-form surface or no near reference point.
pub(super) fn read_add(
    placed: &LensTracer,
    lens: &Mesh,
    options: &Options,
    ior: f64,
) -> Result<(Vec<focimeter::Reading>, &'static str), AnalyzeError> {
    let exact = lens.exact.as_ref().and_then(|e| Some((e, e.lens()?)));
    let freeform = |s: &specula_scene::exact_lens::LensSurface| {
        matches!(s.shape, specula_scene::SurfaceShape::Freeform(_))
    };
    let (frame, side) = match exact {
        Some((e, l)) if freeform(&l.front) => (
            LensFrame::from_front(e.world_from_object, l.front.vertex_z),
            "front",
        ),
        Some((e, l)) if freeform(&l.back) => {
            (LensFrame::of_exact(e.world_from_object, l.back.vertex_z), "back")
        }
        _ => {
            return Err(AnalyzeError::BadOption {
                option: "add",
                reason: format!(
                    "an add without a progressive surface: '{}' has no free-form front or back (a spectacle-lens shape's `front` or `back` = a sag grid, a polynomial or a progressive design)",
                    lens.name
                ),
            })
        }
    };
    let Some(near_at) = options.near_reference_mm else {
        return Err(AnalyzeError::BadOption {
            option: "add",
            reason: format!(
                "the add is read at the near reference point, which '{}' does not give: pass `near_reference` X,Y (mm) or set the spectacle-lens's near_reference",
                lens.name
            ),
        });
    };
    let far_at = options.reference_points_mm[0];
    if near_at[1] >= far_at[1] {
        return Err(AnalyzeError::BadOption {
            option: "near_reference",
            reason: format!(
                "{near_at:?} mm is not below the distance reference point {far_at:?} mm: a \
                 progressive lens's near zone lies below its far zone"
            ),
        });
    }
    let instrument = Focimeter {
        tracer: placed,
        frame,
        ior,
        step_m: options.step_m,
        eye: options.eye,
    };
    let readings = [
        ("distance reference point", options.reference_points_mm[0]),
        ("near reference point", near_at),
    ]
    .into_iter()
    .map(|(name, at)| {
        instrument
            .read(name, at)
            .map_err(|failure| AnalyzeError::BadOption {
                option: "`distance_reference` and `near_reference`",
                reason: format!(
                    "the focimeter cannot read '{}' at {at:?} mm on its {side} ({failure:?}): give a point on the lens",
                    lens.name
                ),
            })
    })
    .collect::<Result<Vec<_>, _>>()?;
    Ok((readings, side))
}
