//! The lens against what was ordered: the focimeter's readings, the base curve, the
//! compensated order, the near figures and the standard's verdict.

use super::*;

/// The near figures where `--near` asks for them, against the target plus the add.
pub(super) fn near_of(
    setup: &Setup,
    worn: &Mesh,
    frame: &LensFrame,
    fitting_mm: glam::DVec2,
    central: &Central,
    target: Option<Rx>,
) -> Result<Option<near::NearFigures>, AnalyzeError> {
    let options = setup.options;
    let Some(near) = options.near else {
        return Ok(None);
    };
    let near_target = target.map(|rx| Rx {
        sphere_d: rx.sphere_d + options.add_d.unwrap_or(0.0),
        ..rx
    });
    near::near_figures(
        setup,
        &near,
        frame,
        options.near_reference_mm,
        fitting_mm,
        central,
        near_target.as_ref(),
        tracer(worn, options.surface)?,
        &worn.name,
    )
    .map(Some)
}

/// The compensated prescription where `--compensate` asks for it (module doc of [`wear`]).
pub(super) fn compensated_of(
    scene: &Scene,
    setup: &Setup,
    worn: &Mesh,
    target: Option<Rx>,
) -> Result<Option<Compensated>, AnalyzeError> {
    Ok(match (setup.options.compensate, target) {
        (false, _) => None,
        (true, None) => {
            return Err(AnalyzeError::BadOption {
                option: "compensate",
                reason: "needs a `prescription` to compensate (prescription, or a \
                 spectacle-lens shape's)"
                    .into(),
            })
        }
        (true, Some(target)) => Some(compensate(scene, setup.options, setup, worn, target)?),
    })
}

/// The verdict of `options.standard` on the focimeter's readings against the ordered
/// prescription (the compensated one where solved), with the add for a progressive lens;
/// refused where the standard and the lens do not go together.
pub(super) fn verdict_of(
    options: &Options,
    compensated: Option<Compensated>,
    focimeter: &[focimeter::Reading],
    add_focimeter: &[focimeter::Reading],
    progressive: Option<&zones::Progressive>,
) -> Result<Option<Verdict>, AnalyzeError> {
    Ok(match (options.standard, options.prescription) {
        (None, _) => None,
        (Some(_), None) => {
            return Err(AnalyzeError::BadOption {
                option: "standard",
                reason: "needs the ordered `prescription` (prescription S,C,A, or a \
             spectacle-lens shape's)"
                    .into(),
            })
        }
        (Some(table), Some(rx)) => {
            let ordered = compensated.map_or(rx, |c| Rx {
                prism_d: rx.prism_d,
                ..c.ordered
            });
            Some(match (options.add_d, progressive) {
                (Some(add), Some(p)) => {
                    let table = table.progressive.unwrap_or(table);
                    if !table.is_progressive() {
                        return Err(AnalyzeError::BadOption {
                            option: "standard",
                            reason: format!(
                                "{} has no tolerance for an add: judge a progressive lens \
                             against {}",
                                table.id,
                                progressive_standards()
                            ),
                        });
                    }
                    let uncertainty =
                        add_focimeter[0].uncertainty_d + add_focimeter[1].uncertainty_d;
                    standard::judge_progressive(
                        table,
                        &focimeter[0],
                        &focimeter[1],
                        &ordered,
                        p.add_d,
                        add,
                        uncertainty,
                    )
                }
                _ if table.is_progressive() => {
                    return Err(AnalyzeError::BadOption {
                        option: "standard",
                        reason: format!(
                            "{} judges progressive lenses: give the ordered `add`",
                            table.id
                        ),
                    })
                }
                _ => standard::judge(table, &focimeter[0], &focimeter[1], &ordered),
            })
        }
    })
}

/// The focimeter at the reference points of the lens as the scene places it.
pub(super) fn read_focimeter(
    tracer: &LensTracer,
    lens: &Mesh,
    options: &Options,
    ior: f64,
    fitting_point: DVec3,
) -> Result<Vec<focimeter::Reading>, AnalyzeError> {
    let frame = match (options.surface, lens.exact.as_ref()) {
        (SurfaceModel::Exact, Some(exact)) => {
            let back_vertex_z = exact.lens().map_or(0.0, |l| l.back.vertex_z);
            LensFrame::of_exact(exact.world_from_object, back_vertex_z)
        }
        _ => LensFrame {
            back_vertex: fitting_point,
            towards_eye: -options.forward,
            right: options.forward.cross(options.up).normalize(),
            up: options.up,
        },
    };
    let instrument = Focimeter {
        tracer,
        frame,
        ior,
        step_m: options.step_m,
        eye: options.eye,
    };
    let [distance, prism] = options.reference_points_mm;
    [
        ("distance reference point", distance),
        ("prism reference point", prism),
    ]
    .into_iter()
    .map(|(name, at)| {
        instrument
            .read(name, at)
            .map_err(|failure| AnalyzeError::BadOption {
                option: "`distance_reference` and `prism_reference`",
                reason: format!(
                    "the focimeter cannot read '{}' at {at:?} mm from its back vertex \
                         ({failure:?}): give a point on the lens",
                    lens.name
                ),
            })
    })
    .collect()
}

/// An exact lens's base curve (its front's mean curvature times n − 1 and 0.53).
pub(super) fn base_curve(lens: &Mesh, n: f64) -> Option<BaseCurve> {
    let exact = lens.exact.as_ref()?.lens()?;
    let [k1, k2] = exact.front.vertex_curvatures();
    let c = 0.5 * (k1 + k2);
    Some(BaseCurve {
        lens_index_d: (n - 1.0) * c,
        tooling_index_d: (TOOLING_INDEX - 1.0) * c,
    })
}

/// The compensated prescription for the lens worn as `worn` (module doc of [`wear`]).
pub(super) fn compensate(
    scene: &Scene,
    options: &Options,
    setup: &Setup,
    worn: &Mesh,
    target: Rx,
) -> Result<Compensated, AnalyzeError> {
    let name = &scene.meshes[options.lens].name;
    let blank = scene
        .prescriptions
        .iter()
        .find(|(n, _)| n == name)
        .map(|(_, p)| p.clone());
    let (Some(blank), Some(exact)) = (blank, worn.exact.as_ref()) else {
        return Err(AnalyzeError::BadOption {
            option: "compensate",
            reason: format!(
                "'{name}' was not made from a prescription (a spectacle-lens shape): there is \
                 no blank to make the ordered lens on"
            ),
        });
    };
    wear::compensate(target, &blank, |ordered| {
        let tracer = LensTracer::exact(ordered.exact_lens(), exact.world_from_object);
        let trial = Setup::new(tracer, options, setup.indices, name)?;
        let frame = trial.frame(0.0, 0.0);
        let matrix = trial
            .vergence(&frame, &trial.primary, options.step_m * 0.5)
            .map_err(|failure| AnalyzeError::BadOption {
                option: "compensate",
                reason: format!("the ordered lens's fitting point fails ({failure:?})"),
            })?;
        let power = Power::from_matrix(matrix[0], matrix[1], matrix[2]);
        Ok(Rx::new(power.sphere_d, power.cylinder_d, power.axis_deg).power_vector())
    })
}
