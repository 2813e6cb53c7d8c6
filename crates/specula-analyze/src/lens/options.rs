//! The lens analysis's options checked, and the defaults a scene gives (its camera's primary
//! gaze, a spectacle-lens shape's prescription and reference points).

use super::*;

pub(crate) fn validate(options: &Options) -> Result<(), AnalyzeError> {
    let g = options.gaze;
    let fine = |v: f64| v.is_finite() && v >= 0.0;
    if !(fine(g.h_max_deg) && fine(g.v_max_deg) && g.step_deg.is_finite() && g.step_deg > 0.0)
        || g.h_max_deg >= 89.0
        || g.v_max_deg >= 89.0
    {
        return Err(AnalyzeError::BadOption {
            option: "gaze",
            reason: format!(
                "H_MAX,V_MAX,STEP = {},{},{}: the maxima must be between 0 and 89 degrees and \
                 the step positive",
                g.h_max_deg, g.v_max_deg, g.step_deg
            ),
        });
    }
    let cells = g.horizontal().len() as f64 * g.vertical().len() as f64;
    if cells > 1e6 {
        return Err(AnalyzeError::BadOption {
            option: "gaze",
            reason: format!("{cells} gaze directions: take a larger step"),
        });
    }
    if let Some(d) = options.object_distance_m {
        if !(d.is_finite() && d > 0.0) {
            return Err(AnalyzeError::BadOption {
                option: "object_distance",
                reason: format!("{d} m: give a positive distance (or leave it out: infinity)"),
            });
        }
    }
    let (f, u) = (options.forward, options.up);
    let unit = |v: DVec3| v.is_finite() && (v.length() - 1.0).abs() < 1e-6;
    if !(unit(f) && unit(u) && f.dot(u).abs() < 1e-6) {
        return Err(AnalyzeError::BadOption {
            option: "forward and up",
            reason: format!("{f} and {u} must be perpendicular unit vectors"),
        });
    }
    if !(options.step_m.is_finite() && options.step_m > 0.0) {
        return Err(AnalyzeError::BadOption {
            option: "step_mm",
            reason: format!("{} m: the bundle needs a positive width", options.step_m),
        });
    }
    if !options.rotation_centre.is_finite() {
        return Err(AnalyzeError::BadOption {
            option: "rotation_centre",
            reason: "not a point".into(),
        });
    }
    options.wear.check()?;
    validate_near_and_add(options)?;
    for (option, value) in [
        (
            "rotation_behind_cornea",
            Some(options.rotation_behind_cornea_m),
        ),
        ("refraction_vertex", options.refraction_vertex_m),
    ] {
        if value.is_some_and(|v| !(v.is_finite() && v > 0.0)) {
            return Err(AnalyzeError::BadOption {
                option,
                reason: format!(
                    "{} mm: the distance must be positive",
                    value.unwrap_or(f64::NAN) * 1e3
                ),
            });
        }
    }
    if let Some(rx) = options.prescription {
        let values = [
            rx.sphere_d,
            rx.cylinder_d,
            rx.axis_deg,
            rx.prism_d[0],
            rx.prism_d[1],
        ];
        if values.iter().any(|v| !v.is_finite()) {
            return Err(AnalyzeError::BadOption {
                option: "prescription",
                reason: format!("{values:?}: every value must be a number"),
            });
        }
    }
    if options
        .reference_points_mm
        .iter()
        .flatten()
        .any(|v| !v.is_finite())
    {
        return Err(AnalyzeError::BadOption {
            option: "`distance_reference` and `prism_reference`",
            reason: "a reference point must be two numbers (mm)".into(),
        });
    }
    Ok(())
}

/// The near point's, the lens map's and the add's options.
pub(super) fn validate_near_and_add(options: &Options) -> Result<(), AnalyzeError> {
    if let Some(near) = options.near {
        if !(near.distance_m.is_finite() && near.distance_m > 0.0) {
            return Err(AnalyzeError::BadOption {
                option: "near",
                reason: format!(
                    "{} m: the near point must be in front of the eyes (a positive distance)",
                    near.distance_m
                ),
            });
        }
        if !(near.half_pd_m.is_finite() && near.half_pd_m >= 0.0 && near.half_pd_m < 0.1) {
            return Err(AnalyzeError::BadOption {
                option: "pd",
                reason: format!(
                    "{} mm: the interpupillary distance must be between 0 and 200 mm",
                    near.half_pd_m * 2e3
                ),
            });
        }
        if near
            .down_deg
            .is_some_and(|d| !(d.is_finite() && d.abs() < 80.0))
        {
            return Err(AnalyzeError::BadOption {
                option: "near_down",
                reason: "the near point's depression must be between −80° and 80°".into(),
            });
        }
    }
    if let Some(step) = options.lens_step_mm {
        if !(step.is_finite() && step >= 0.05) {
            return Err(AnalyzeError::BadOption {
                option: "lens_step",
                reason: format!("{step} mm: the lens map's spacing must be at least 0.05 mm"),
            });
        }
    }
    if let Some(add) = options.add_d {
        if !(add.is_finite() && add > 0.0 && add <= 6.0) {
            return Err(AnalyzeError::BadOption {
                option: "add",
                reason: format!("{add} D: an addition is between 0 and 6.00 D"),
            });
        }
    }
    if options
        .near_reference_mm
        .is_some_and(|p| !p.iter().all(|v| v.is_finite()))
    {
        return Err(AnalyzeError::BadOption {
            option: "near_reference",
            reason: "the near reference point must be two numbers (mm)".into(),
        });
    }
    Ok(())
}

/// The primary gaze and up of `camera`: its view direction, and its up made perpendicular
/// (refused where they are parallel: the axes and prisms would have no orientation).
pub fn primary_frame(camera: &Camera) -> Result<(DVec3, DVec3), AnalyzeError> {
    let forward = (camera.target - camera.eye).as_dvec3().normalize();
    let up = camera.up.as_dvec3();
    let up = (up - forward * up.dot(forward))
        .try_normalize()
        .filter(|_| forward.is_finite())
        .ok_or_else(|| AnalyzeError::BadOption {
            option: "camera",
            reason: format!(
                "the camera's up {} is parallel to its view direction: the wearer's up (for \
                 the axis and the prism) is undefined",
                camera.up
            ),
        })?;
    Ok((forward, up))
}

/// The default options for `lens` in `scene`: the right eye, its centre of rotation 27 mm
/// behind the back vertex on the camera's view axis, a 30° × 30° grid every 2.5°, an object at
/// infinity, a 0.5 mm bundle, and the prescription the lens was made from, if any.
pub fn default_options(scene: &Scene, lens: usize) -> Result<Options, AnalyzeError> {
    default_options_with(scene, lens, true)
}

/// [`default_options`], finding the back vertex only where `find_centre` (else the rotation
/// centre is the camera's eye, for the caller to replace).
pub fn default_options_with(
    scene: &Scene,
    lens: usize,
    find_centre: bool,
) -> Result<Options, AnalyzeError> {
    indices(scene, lens)?;
    let (forward, up) = primary_frame(&scene.camera)?;
    let rotation_centre = if find_centre {
        rotation_centre_behind(
            scene,
            lens,
            DEFAULT_VERTEX_DISTANCE_M,
            DEFAULT_ROTATION_BEHIND_CORNEA_M,
        )?
    } else {
        scene.camera.eye.as_dvec3()
    };
    let mesh = &scene.meshes[lens];
    let made_from = scene
        .prescriptions
        .iter()
        .find(|(name, _)| *name == mesh.name)
        .map(|(_, p)| p);
    let mm = |p: Option<glam::DVec2>| p.map(|p| (p * 1e3).to_array());
    Ok(Options {
        lens,
        eye: Eye::Right,
        rotation_centre,
        rotation_behind_cornea_m: DEFAULT_ROTATION_BEHIND_CORNEA_M,
        forward,
        up,
        gaze: Gaze {
            h_max_deg: 30.0,
            v_max_deg: 30.0,
            step_deg: 2.5,
        },
        object_distance_m: None,
        step_m: 5e-4,
        surface: best_surface(mesh),
        wear: Wear::default(),
        prescription: made_from.map(Rx::of),
        refraction_vertex_m: None,
        compensate: false,
        standard: None,
        reference_points_mm: [
            mm(made_from.and_then(|p| p.distance_reference)).unwrap_or([0.0; 2]),
            [0.0; 2],
        ],
        near_reference_mm: mm(made_from.and_then(|p| p.near_reference)),
        add_d: made_from.and_then(|p| p.add_d),
        near: None,
        lens_step_mm: Some(DEFAULT_LENS_STEP_MM),
    })
}
