//! `compare` end to end on a built-in scene, with the JSON checked against its schema.

use specula_compare::{compare, Options};

fn assert_matches_schema(path: &std::path::Path) {
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let schema: serde_json::Value =
        serde_json::from_str(include_str!("../../../docs/compare.schema.json")).unwrap();
    let validator = jsonschema::validator_for(&schema).unwrap();
    let errors: Vec<String> = validator
        .iter_errors(&json)
        .map(|e| format!("{e} at {}", e.instance_path()))
        .collect();
    assert!(errors.is_empty(), "{errors:?}");
}

#[test]
fn compare_writes_a_report_and_json_that_matches_the_schema() {
    let Some(ctx) = specula_methods::test_context("compare end to end") else {
        return;
    };
    let scene = specula_scene::load("door-mirror").unwrap();
    let options = Options {
        width: 64,
        height: 48,
        methods: vec!["envmap".into()],
        spp: 1,
        max_depth: 8,
        parameters: vec![],
        frames: 3,
    };
    let comparison = compare(&scene, &ctx, &options, &|_| {}).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let html = comparison.write_report(dir.path()).unwrap();
    let text = std::fs::read_to_string(&html).unwrap();
    assert!(text.contains("data:image/png;base64,") && text.contains("envmap"));
    for file in [
        "reference.png",
        "envmap.png",
        "envmap-flip.png",
        "report.json",
    ] {
        assert!(dir.path().join(file).exists(), "{file} missing");
    }
    assert_matches_schema(&dir.path().join("report.json"));
    let m = &comparison.report.methods[0];
    let metrics = m
        .metrics
        .as_ref()
        .expect("envmap shades its mirrors itself");
    assert!(metrics.mask_pixels > 100 && m.delegated.is_empty());
    assert_eq!(metrics.mask_pixels, comparison.report.mirror_pixels);
    // Measured 2026-11-30: 0.047; bound 2x.
    assert!(
        metrics.mean_flip < 0.095,
        "envmap on the door mirror: mean FLIP {}",
        metrics.mean_flip
    );
    let r = &comparison.report;
    // Like with like: the reference's time is the median of its warm frames, its BVH build and
    // first frame apart; a method's likewise, and the speed-up divides the two medians.
    assert_eq!(r.frames, 3);
    for (what, spread, total) in [
        ("reference", r.reference.frame, r.reference.total_ms),
        ("envmap", m.frame, m.total_ms),
    ] {
        assert_eq!(spread.median_ms, total, "{what}");
        assert!(
            0.0 < spread.min_ms
                && spread.min_ms <= spread.median_ms
                && spread.median_ms <= spread.max_ms,
            "{what}: {spread:?}"
        );
    }
    assert!(r.reference.build_ms > 0.0 && r.reference.first_frame_ms > 0.0);
    assert!(m.prepare_ms > 0.0 && m.first_frame_ms > 0.0);
    let expected = r.reference.total_ms / m.total_ms;
    assert!(
        (m.speedup_over_reference - expected).abs() <= 1e-9 * expected,
        "speed-up {} is not reference time / method time {expected}",
        m.speedup_over_reference
    );
    let base = r
        .gpu_trace
        .as_ref()
        .expect("gpu-trace timed as the base only");
    assert_eq!(Some(base.frame.median_ms), r.gpu_trace_ms);
    assert!(base.prepare_ms > 0.0 && base.first_frame_ms > 0.0);
    // gpu-trace was timed as the second base although not compared.
    let gpu_trace_ms = r.gpu_trace_ms.expect("a GPU run times gpu-trace");
    let ratio = m.speedup_over_gpu_trace.unwrap();
    assert!((ratio - gpu_trace_ms / m.total_ms).abs() <= 1e-9 * ratio);
    assert!(text.contains("vs gpu-trace") && text.contains("warm / warm"));
}

#[test]
fn delegated_surfaces_are_reported_apart_with_their_delegate() {
    let Some(ctx) = specula_methods::test_context("compare delegation") else {
        return;
    };
    // The suite's glass sphere: its only specular surface is glass, which c3rc hands to
    // envmap.
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes/suite/glass-sphere.toml");
    let scene = specula_scene::load(path.to_str().unwrap()).unwrap();
    let options = Options {
        width: 48,
        height: 36,
        methods: vec!["c3rc".into(), "envmap".into()],
        spp: 1,
        max_depth: 8,
        parameters: vec![],
        frames: 1,
    };
    let comparison = compare(&scene, &ctx, &options, &|_| {}).unwrap();
    let r = &comparison.report;
    assert!(
        r.refractor_pixels > 100 && r.mirror_pixels == 0,
        "{} refractor, {} mirror pixels",
        r.refractor_pixels,
        r.mirror_pixels
    );
    let (c3rc, envmap) = (&r.methods[0], &r.methods[1]);
    assert_eq!(c3rc.metrics, None, "c3rc shades no glass itself");
    assert_eq!(c3rc.delegated.len(), 1);
    let d = &c3rc.delegated[0];
    assert_eq!(
        (d.material, d.delegate.as_str()),
        (specula_methods::SurfaceClass::Refractor, "envmap")
    );
    assert!(envmap.delegated.is_empty());
    // envmap's shading on those pixels: c3rc's figure there is envmap's.
    assert_eq!(Some(&d.metrics), envmap.metrics.as_ref());
    let dir = tempfile::tempdir().unwrap();
    let html = std::fs::read_to_string(comparison.write_report(dir.path()).unwrap()).unwrap();
    assert!(html.contains("refractor pixels") && html.contains("shaded by envmap"));
    assert_matches_schema(&dir.path().join("report.json"));
}

#[test]
fn unknown_methods_are_named_with_the_valid_ones() {
    let Some(ctx) = specula_methods::test_context("compare unknown method") else {
        return;
    };
    let scene = specula_scene::load("door-mirror").unwrap();
    let options = Options {
        width: 16,
        height: 16,
        methods: vec!["magic".into()],
        spp: 1,
        max_depth: 8,
        parameters: vec![],
        frames: 1,
    };
    let message = compare(&scene, &ctx, &options, &|_| {})
        .err()
        .unwrap()
        .to_string();
    assert!(
        message.contains("magic") && message.contains("envmap") && message.contains("reference"),
        "{message}"
    );
}

#[test]
fn parameters_reach_the_methods_that_have_them_and_unknown_ones_are_errors() {
    let Some(ctx) = specula_methods::test_context("compare parameters") else {
        return;
    };
    let scene = specula_scene::load("door-mirror").unwrap();
    let options = |parameters: Vec<String>| Options {
        width: 32,
        height: 24,
        methods: vec!["envmap".into(), "pvrr".into()],
        spp: 1,
        max_depth: 8,
        parameters,
        frames: 1,
    };
    let comparison = compare(
        &scene,
        &ctx,
        &options(vec!["exit=sphere".into(), "max_fov=30".into()]),
        &|_| {},
    )
    .unwrap();
    let methods = &comparison.report.methods;
    assert_eq!(methods[0].parameters["exit"], "sphere");
    assert_eq!(methods[1].parameters["max_fov"], "30");
    let message = compare(&scene, &ctx, &options(vec!["sharpness=2".into()]), &|_| {})
        .err()
        .unwrap()
        .to_string();
    assert!(
        message.contains("sharpness=2") && message.contains("envmap, pvrr"),
        "{message}"
    );
}

#[test]
fn one_method_runs_under_several_labels_keyed_in_rows_images_and_json() {
    let Some(ctx) = specula_methods::test_context("compare labels") else {
        return;
    };
    let scene = specula_scene::load("door-mirror").unwrap();
    let options = |methods: &[&str], parameters: &[&str]| Options {
        width: 32,
        height: 24,
        methods: methods.iter().map(|m| m.to_string()).collect(),
        spp: 1,
        max_depth: 8,
        parameters: parameters.iter().map(|p| p.to_string()).collect(),
        frames: 1,
    };
    let comparison = compare(
        &scene,
        &ctx,
        &options(&["c3rc", "c3rc:paper"], &["c3rc:paper.points=5000"]),
        &|_| {},
    )
    .unwrap();
    let rows = &comparison.report.methods;
    let labels: Vec<&str> = rows.iter().map(|m| m.label.as_str()).collect();
    assert_eq!(labels, ["c3rc", "c3rc:paper"]);
    assert_eq!(
        (rows[0].method.as_str(), rows[1].method.as_str()),
        ("c3rc", "c3rc")
    );
    assert_eq!(rows[0].preset, None);
    assert_eq!(rows[1].preset.as_deref(), Some("paper"));
    // The preset, then the setting for that label only.
    assert_eq!(rows[0].parameters["trace_self"], "true");
    assert_eq!(rows[1].parameters["trace_self"], "false");
    assert_eq!(rows[1].parameters["points"], "5000");
    assert_eq!(rows[0].parameters["points"], "100000");
    let dir = tempfile::tempdir().unwrap();
    comparison.write_report(dir.path()).unwrap();
    for file in [
        "c3rc.png",
        "c3rc-flip.png",
        "c3rc-paper.png",
        "c3rc-paper-flip.png",
    ] {
        assert!(dir.path().join(file).exists(), "{file} missing");
    }
    assert_matches_schema(&dir.path().join("report.json"));

    let error = |methods: &[&str], parameters: &[&str]| {
        compare(&scene, &ctx, &options(methods, parameters), &|_| {})
            .err()
            .unwrap()
            .to_string()
    };
    let twice = error(&["c3rc:paper", "envmap", "c3rc:paper"], &[]);
    assert!(twice.contains("'c3rc:paper' is given twice"), "{twice}");
    let unknown = error(&["pvrr:fast"], &[]);
    assert!(
        unknown.contains("pvrr:fast") && unknown.contains("pvrr:paper"),
        "{unknown}"
    );
    let empty = error(&["pvrr:"], &[]);
    assert!(empty.contains("valid: pvrr:paper"), "{empty}");
    let elsewhere = error(&["c3rc"], &["c3rc:paper.points=5000"]);
    assert!(elsewhere.contains("not in this run (c3rc)"), "{elsewhere}");
}

/// One failing method does not stop the scene: without a GPU, pvrr fails (it needs one) and
/// its row holds the error, while vertex tracing (a CPU method) is measured and reported; the
/// JSON (schema version 4) and the page both carry the failure.
#[test]
fn a_failing_method_gets_its_error_in_its_row_and_the_others_still_report() {
    let ctx = specula_methods::Context { gpu: None };
    let scene = specula_scene::load("door-mirror").unwrap();
    let options = Options {
        width: 48,
        height: 36,
        methods: vec!["pvrr".into(), "vertex-tracing".into()],
        spp: 1,
        max_depth: 8,
        parameters: vec![],
        frames: 1,
    };
    let comparison = compare(&scene, &ctx, &options, &|_| {}).unwrap();
    let r = &comparison.report;
    assert_eq!(r.failed.len(), 1, "{:?}", r.failed);
    let failure = &r.failed[0];
    assert_eq!(
        (failure.label.as_str(), failure.method.as_str()),
        ("pvrr", "pvrr")
    );
    eprintln!("pvrr without a GPU: {}", failure.error);
    assert!(failure.error.contains("GPU"), "{}", failure.error);
    assert_eq!(r.methods.len(), 1);
    assert_eq!(r.methods[0].label, "vertex-tracing");
    let metrics = r.methods[0].metrics.as_ref().unwrap();
    assert!(
        metrics.mask_pixels > 50 && metrics.mean_flip < 0.05,
        "{metrics:?}"
    );
    assert_eq!(comparison.method_images.len(), 1);
    let dir = tempfile::tempdir().unwrap();
    let html = std::fs::read_to_string(comparison.write_report(dir.path()).unwrap()).unwrap();
    assert!(
        html.contains("<tr class=\"failed\"><td>pvrr</td>"),
        "{html}"
    );
    assert!(!dir.path().join("pvrr.png").exists());
    assert_matches_schema(&dir.path().join("report.json"));
}

/// A scene with no mirror or glass says how to make one and names its objects, before the
/// reference is rendered; one whose mirrors are out of view says so instead.
#[test]
fn nothing_to_compare_says_why_and_what_to_do() {
    let ctx = specula_methods::Context { gpu: None };
    let options = Options {
        width: 16,
        height: 12,
        methods: vec!["vertex-tracing".into()],
        spp: 1,
        max_depth: 8,
        parameters: vec![],
        frames: 1,
    };
    let mut scene = specula_scene::load("door-mirror").unwrap();
    let mirror = scene.meshes.iter().position(|m| m.name == "door mirror");
    let mut looking_away = scene.clone();
    looking_away.camera.target = 2.0 * looking_away.camera.eye - looking_away.camera.target;
    let away = compare(&looking_away, &ctx, &options, &|_| {})
        .err()
        .unwrap()
        .to_string();
    assert!(
        away.ends_with("nothing to compare; its mirrors and glass ('door mirror') are out of the camera's view"),
        "{away}"
    );
    let mirror = mirror.expect("the door mirror");
    let diffuse = scene.materials.len();
    scene.materials.push(specula_scene::Material::diffuse(
        "grey",
        glam::Vec3::splat(0.5),
    ));
    scene.meshes[mirror].material = diffuse;
    let none = compare(&scene, &ctx, &options, &|_| {})
        .err()
        .unwrap()
        .to_string();
    assert!(
        none.contains("make an object one with `material` NAME=mirror (or NAME=glass:IOR); its objects are: 'door mirror', "),
        "{none}"
    );
}
