//! Near vision: both eyes turn to a near point on the midline.
//!
//! The eyes' centres of rotation lie `half_pd` either side of the midline, the chosen eye's at
//! the analysis's centre of rotation, along the primary right. The near point is on the
//! midline, `distance` from the point between the centres, lowered by `down` from the primary
//! gaze: given, else so that the chosen eye's line of sight crosses the back surface at the
//! height of the lens's near reference point (a secant search), else straight ahead. The eye
//! turns until the chief ray's object-space line passes through the near point (Newton's
//! method on the miss, 1e-9 m); the bundle then starts from the near point itself.
//!
//! Reported: where the line of sight crosses the lens (lens frame, mm) and its inset (towards
//! the nose from the fitting point), the vergences there from the near object (the exit
//! vergences at the vertex sphere), the object's own vergence there, the lens's power for it
//! (the mean exit vergence less the object's), the power error against the target plus the
//! ordered add, and the prism (base out, base up positive).

use glam::{DVec2, DVec3};
use serde::Serialize;

use super::focimeter::LensFrame;
use super::tracer::LensTracer;
use super::wear::Rx;
use super::zones::angles;
use super::{figures, AnalyzeError, Cell, Central, Eye, Options, Setup};

/// Where the eyes look at near (module doc).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Near {
    pub distance_m: f64,
    /// Half the interpupillary distance, metres.
    pub half_pd_m: f64,
    /// The near point's depression below the primary gaze; None: from the near reference
    /// point, else 0.
    pub down_deg: Option<f64>,
}

/// The near figures.
#[derive(Clone, Debug, Serialize)]
pub struct NearFigures {
    pub distance_m: f64,
    pub pd_mm: f64,
    pub down_deg: f64,
    pub near_point: [f64; 3],
    /// Where the line of sight crosses the back surface, lens frame, mm.
    pub point_on_lens_mm: [f64; 2],
    /// Towards the nose from the fitting point, mm.
    pub inset_mm: f64,
    /// The near object's vergence at the vertex sphere (negative: diverging).
    pub object_vergence_d: f64,
    /// The lens's mean power for the near object: mean exit vergence less the object's (None
    /// where the bundle fails).
    pub power_d: Option<f64>,
    /// The gaze's figures from the near object (exit vergences, prism, and the power error
    /// against the target plus the add).
    pub cell: Cell,
}

/// The figures at `near` (module doc). `setup` is the far analysis's, `frame` the worn lens's.
#[allow(clippy::too_many_arguments)]
pub(super) fn near_figures(
    setup: &Setup,
    near: &Near,
    frame: &LensFrame,
    near_reference_mm: Option<[f64; 2]>,
    fitting_mm: DVec2,
    central: &Central,
    target: Option<&Rx>,
    tracer: LensTracer,
    name: &str,
) -> Result<NearFigures, AnalyzeError> {
    let o = setup.options;
    let side = match o.eye {
        Eye::Right => 1.0,
        Eye::Left => -1.0,
    };
    let between = o.rotation_centre - setup.right * (side * near.half_pd_m);
    let point = |down_deg: f64| {
        let d = down_deg.to_radians();
        between + (o.forward * d.cos() - o.up * d.sin()) * near.distance_m
    };
    let refuse = |reason: String| AnalyzeError::BadOption {
        option: "near",
        reason,
    };
    let front = (setup.primary.points[1] - o.rotation_centre).length();
    if near.distance_m < front + 0.01 {
        return Err(refuse(format!(
            "{} m puts the near point at or behind the lens, whose front is {front:.4} m from \
             the eye: give more than {:.3} m",
            near.distance_m,
            front + 0.01
        )));
    }
    let crossing = |down: f64| -> Result<([f64; 2], DVec2), AnalyzeError> {
        let gaze = aim_at(setup, point(down)).ok_or_else(|| {
            refuse(format!(
                "the eye cannot look through the lens at the near point {:.3} m away, {down:.1}° \
                 down",
                near.distance_m
            ))
        })?;
        let frame_g = setup.frame(gaze[0], gaze[1]);
        let chief = setup
            .chief(&frame_g, setup.indices.y)
            .map_err(|f| refuse(format!("the line of sight to the near point fails ({f:?})")))?;
        let q = chief.points[0] - frame.back_vertex;
        Ok((gaze, DVec2::new(q.dot(frame.right), q.dot(frame.up)) * 1e3))
    };
    let down = match (near.down_deg, near_reference_mm) {
        (Some(d), _) => d,
        (None, None) => 0.0,
        (None, Some([_, y_ref])) => {
            // The secant on the crossing's height.
            let (mut a, mut b) = (10.0, 30.0);
            let (mut fa, mut fb) = (crossing(a)?.1.y - y_ref, crossing(b)?.1.y - y_ref);
            for _ in 0..30 {
                if (fb - fa).abs() < 1e-15 || fb.abs() < 1e-6 {
                    break;
                }
                let c = b - fb * (b - a) / (fb - fa);
                (a, fa) = (b, fb);
                b = c.clamp(-60.0, 75.0);
                fb = crossing(b)?.1.y - y_ref;
            }
            b
        }
    };
    let (gaze, on_lens) = crossing(down)?;
    let near_point = point(down);
    let distance = (near_point - o.rotation_centre).length();
    let options = Options {
        object_distance_m: Some(distance),
        ..o.clone()
    };
    let near_setup = Setup::new(tracer, &options, setup.indices, name).map_err(|e| match e {
        AnalyzeError::BadOption { reason, .. } => refuse(reason),
        other => other,
    })?;
    let cell = figures(&near_setup, gaze[0], gaze[1], central, target);
    let vertex_point =
        o.rotation_centre + near_setup.frame(gaze[0], gaze[1]).gaze * setup.vertex_sphere_radius;
    let object_vergence = -1.0 / (near_point - vertex_point).length();
    Ok(NearFigures {
        distance_m: near.distance_m,
        pd_mm: near.half_pd_m * 2e3,
        down_deg: down,
        near_point: near_point.to_array(),
        point_on_lens_mm: on_lens.to_array(),
        inset_mm: -side * (on_lens.x - fitting_mm.x),
        object_vergence_d: object_vergence,
        power_d: cell.mean_power_d.map(|m| m - object_vergence),
        cell,
    })
}

/// The gaze (h, v degrees) whose chief ray's object-space line passes through `target`:
/// Newton's method on its miss across the line, from the straight line to it.
fn aim_at(setup: &Setup, target: DVec3) -> Option<[f64; 2]> {
    let o = setup.options;
    let miss = |g: [f64; 2]| -> Option<DVec2> {
        let frame = setup.frame(g[0], g[1]);
        let chief = setup.chief(&frame, setup.indices.y).ok()?;
        let off = target - chief.points[1];
        let across = off - chief.dir * off.dot(chief.dir);
        Some(DVec2::new(across.dot(frame.right), across.dot(frame.up)))
    };
    let mut g = angles(setup, (target - o.rotation_centre).normalize());
    for _ in 0..20 {
        let m = miss(g)?;
        if m.length() < 1e-9 {
            return Some(g);
        }
        let e = 1e-3;
        let mh = (miss([g[0] + e, g[1]])? - m) / e;
        let mv = (miss([g[0], g[1] + e])? - m) / e;
        let det = mh.x * mv.y - mv.x * mh.y;
        if det.abs() < 1e-300 {
            return None;
        }
        g[0] -= (m.x * mv.y - mv.x * m.y) / det;
        g[1] -= (mh.x * m.y - m.x * mh.y) / det;
    }
    (miss(g)?.length() < 1e-7).then_some(g)
}
