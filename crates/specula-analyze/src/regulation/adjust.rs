//! `adjust`: the mirror turned about a pivot over a grid of yaw and pitch, the poses that
//! pass confirmed at the run's own tolerances, the widest-margin one and, failing all, the
//! most seen.

use super::*;

/// `--adjust`: the mirror turned about a pivot.
#[derive(Clone, Copy, Debug)]
pub struct AdjustRequest {
    pub pivot: Vec3,
    pub step_deg: f32,
    pub limit_deg: f32,
}

/// One pose of the mirror and how its fields fare.
#[derive(Clone, Debug, Serialize)]
pub struct Pose {
    pub yaw_deg: f32,
    pub pitch_deg: f32,
    /// The fields' verdict at the search's tolerances.
    pub search_verdict: Outcome,
    /// The fields' verdict at the command's tolerances, for each pose the search did not fail
    /// (None: the search failed it).
    pub confirmed_verdict: Option<Outcome>,
    /// The fields pass at the command's tolerances (the mirror's own checks do not change with
    /// its pose).
    pub fields_passed: bool,
    /// The least, over the fields, of the share seen or excused.
    pub least_share: f64,
    pub least_share_field: String,
    /// The least, over the fields, of the outer and near margins, metres.
    pub least_margin_m: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct Adjustment {
    pub pivot: [f32; 3],
    /// Yaw turns about the vehicle's up axis (positive: right-hand rule), pitch about the
    /// horizontal axis in the mirror's plane, both through the pivot.
    pub yaw_axis: [f32; 3],
    pub pitch_axis: [f32; 3],
    pub step_deg: f32,
    pub limit_deg: f32,
    /// The tolerances the search ran at; every pose it did not fail is judged again at the
    /// command's, and only those confirmed there count as passing.
    pub search_tolerance: f64,
    pub poses: Vec<Pose>,
    /// The yaw and pitch ranges of the poses confirmed to pass (None: none passes).
    pub passing_yaw_deg: Option<[f32; 2]>,
    pub passing_pitch_deg: Option<[f32; 2]>,
    pub passing_poses: usize,
    /// The pose with the widest margin among those that pass; else the one that sees most.
    pub best: Pose,
    /// The best pose judged at the command's tolerances.
    pub best_verdict: Verdict,
}

/// The pivot must be near the mirror (a mirror turns about its own mounting).
pub fn check_pivot(scene: &Scene, mirror: usize, pivot: Vec3) -> Result<(), AnalyzeError> {
    let bounds = scene.meshes[mirror].bounds();
    let nearest = pivot.clamp(bounds.min, bounds.max);
    let distance = pivot.distance(nearest);
    if !pivot.is_finite() || distance > 0.5 {
        return Err(AnalyzeError::BadOption {
            option: "adjust",
            reason: format!(
                "the pivot {pivot} is {distance:.2} m from the mirror's bounds ({} to {}): a \
                 mirror turns about its own mounting, within 0.5 m of it",
                bounds.min, bounds.max
            ),
        });
    }
    Ok(())
}

/// The rigid turn of the mirror about `pivot`: yaw about `up`, then pitch about `pitch_axis`.
pub fn pose_transform(
    pivot: Vec3,
    up: Vec3,
    pitch_axis: Vec3,
    yaw_deg: f32,
    pitch_deg: f32,
) -> Mat4 {
    Mat4::from_translation(pivot)
        * Mat4::from_axis_angle(up, yaw_deg.to_radians())
        * Mat4::from_axis_angle(pitch_axis, pitch_deg.to_radians())
        * Mat4::from_translation(-pivot)
}

/// Turns the mirror over a grid of yaw × pitch within ±`limit_deg`, judging each pose at the
/// viewer's tolerances (2 %, 0.1°), and every pose that search does not fail again at the
/// request's: the passing ranges are of poses confirmed at full precision.
pub fn adjust(
    scene: &Scene,
    request: &Request,
    adjust: &AdjustRequest,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Adjustment, AnalyzeError> {
    let mirror = request.view.mirror;
    check_adjust(scene, request, adjust)?;
    let surface = MirrorSurface::new(scene, mirror, request.view.surface).expect("validated");
    let (_, normal) = mirror_centre_and_normal(&surface);
    let up = request.vehicle.frame.up;
    let pitch_axis = up
        .cross(normal)
        .try_normalize()
        .unwrap_or(request.vehicle.frame.right);
    let steps = (adjust.limit_deg / adjust.step_deg).floor() as i32;
    let angles: Vec<f32> = (-steps..=steps)
        .map(|k| k as f32 * adjust.step_deg)
        .collect();
    let grid: Vec<(f32, f32)> = angles
        .iter()
        .flat_map(|&yaw| angles.iter().map(move |&pitch| (yaw, pitch)))
        .collect();
    let search = Request {
        view: mirror_view::Options {
            tolerance: request.view.tolerance.max(0.02),
            tolerance_deg: request.view.tolerance_deg.max(0.1),
            max_samples: request.view.max_samples.min(1_000_000),
            ..request.view.clone()
        },
        ..request.clone()
    };
    let posed = |yaw: f32, pitch: f32| {
        let mut scene = scene.clone();
        scene.meshes[mirror].transform(pose_transform(adjust.pivot, up, pitch_axis, yaw, pitch));
        scene
    };
    let mut poses = Vec::with_capacity(grid.len());
    for (k, &(yaw, pitch)) in grid.iter().enumerate() {
        let scene = posed(yaw, pitch);
        let accel = SceneAccel::new(&scene);
        let judged = evaluate_quietly(&scene, &accel, &search)?;
        poses.push(pose_of(yaw, pitch, &judged.verdict, request.regulation));
        progress(k + 1, grid.len());
    }
    confirm(&mut poses, &posed, request, progress)?;
    let passing: Vec<&Pose> = poses.iter().filter(|p| p.fields_passed).collect();
    let range = |f: fn(&Pose) -> f32| {
        (!passing.is_empty()).then(|| {
            let v = passing.iter().map(|p| f(p));
            [
                v.clone().fold(f32::INFINITY, f32::min),
                v.fold(f32::NEG_INFINITY, f32::max),
            ]
        })
    };
    let best = if passing.is_empty() {
        poses
            .iter()
            .max_by(|a, b| a.least_share.total_cmp(&b.least_share))
    } else {
        passing
            .iter()
            .copied()
            .max_by(|a, b| a.least_margin_m.total_cmp(&b.least_margin_m))
    }
    .expect("at least one pose")
    .clone();
    let best_scene = posed(best.yaw_deg, best.pitch_deg);
    let best_accel = SceneAccel::new(&best_scene);
    let best_verdict = evaluate_quietly(&best_scene, &best_accel, request)?.verdict;
    Ok(Adjustment {
        pivot: adjust.pivot.to_array(),
        yaw_axis: up.to_array(),
        pitch_axis: pitch_axis.to_array(),
        step_deg: adjust.step_deg,
        limit_deg: adjust.limit_deg,
        search_tolerance: search.view.tolerance,
        passing_yaw_deg: range(|p| p.yaw_deg),
        passing_pitch_deg: range(|p| p.pitch_deg),
        passing_poses: passing.len(),
        poses,
        best,
        best_verdict,
    })
}

/// `--adjust`'s own inputs: a regulation with fields, a pivot at the mirror, a positive step.
pub(super) fn check_adjust(
    scene: &Scene,
    request: &Request,
    adjust: &AdjustRequest,
) -> Result<(), AnalyzeError> {
    if request.regulation.fields.is_empty() {
        return Err(AnalyzeError::BadOption {
            option: "adjust",
            reason: format!(
                "{} prescribes no field: there is nothing for a pose search to find (the \
                 mirror's own rules do not change with its pose)",
                request.regulation.name
            ),
        });
    }
    check_pivot(scene, request.view.mirror, adjust.pivot)?;
    if !(adjust.step_deg.is_finite() && adjust.step_deg > 0.0) {
        return Err(AnalyzeError::BadOption {
            option: "adjust_step",
            reason: format!("{}°: the step must be a positive angle", adjust.step_deg),
        });
    }
    Ok(())
}

/// Judges every pose the search did not fail again as the command judges (the request's
/// tolerances, a mesh mirror's surface uncertainty included): only those confirmed pass.
pub(super) fn confirm(
    poses: &mut [Pose],
    posed: &impl Fn(f32, f32) -> Scene,
    request: &Request,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<(), AnalyzeError> {
    let searched = poses.len();
    let total = searched
        + poses
            .iter()
            .filter(|p| p.search_verdict != Outcome::Fail)
            .count();
    let mut done = searched;
    for pose in poses
        .iter_mut()
        .filter(|p| p.search_verdict != Outcome::Fail)
    {
        let scene = posed(pose.yaw_deg, pose.pitch_deg);
        let accel = SceneAccel::new(&scene);
        let judged = evaluate(&scene, &accel, request, &|_| {})?;
        let full = pose_of(
            pose.yaw_deg,
            pose.pitch_deg,
            &judged.verdict,
            request.regulation,
        );
        *pose = Pose {
            search_verdict: pose.search_verdict,
            confirmed_verdict: Some(full.search_verdict),
            fields_passed: full.search_verdict.passed(),
            ..full
        };
        done += 1;
        progress(done, total);
    }
    Ok(())
}

/// One pose judged, without the smooth-fit rerun (the pose search compares poses on one surface).
pub(super) fn evaluate_quietly(
    scene: &Scene,
    accel: &SceneAccel,
    request: &Request,
) -> Result<Judged, AnalyzeError> {
    let surface =
        MirrorSurface::new(scene, request.view.mirror, request.view.surface).expect("validated");
    let (centre, _) = mirror_centre_and_normal(&surface);
    let view = mirror_view::analyze(scene, accel, &request.eyes, &request.view, &|_| {})?;
    let verdict = judge(
        request.regulation,
        &request.vehicle,
        &view,
        &request.eye_sets,
        &surface,
        centre,
    )?;
    Ok(Judged { verdict, view })
}

pub(super) fn pose_of(yaw: f32, pitch: f32, verdict: &Verdict, regulation: &Regulation) -> Pose {
    let share = |f: &FieldVerdict| {
        let excused = if f.figures.hidden_by_vehicle_share < regulation.allowance() {
            f.figures.hidden_by_vehicle_share
        } else {
            0.0
        };
        let beyond = f.figures.beyond_range_seen_share.unwrap_or(1.0);
        (f.figures.seen_share + excused).min(beyond)
    };
    let least = verdict
        .fields
        .iter()
        .min_by(|a, b| share(a).total_cmp(&share(b)));
    let fields = Outcome::all(verdict.fields.iter().map(|f| f.figures.verdict));
    Pose {
        yaw_deg: yaw,
        pitch_deg: pitch,
        search_verdict: fields,
        confirmed_verdict: None,
        fields_passed: false,
        least_share: least.map_or(1.0, share),
        least_share_field: least.map_or_else(String::new, |f| f.name.clone()),
        least_margin_m: verdict
            .fields
            .iter()
            .map(|f| f.figures.outer_margin_m.min(f.figures.near_margin_m))
            .fold(f64::INFINITY, f64::min),
    }
}
