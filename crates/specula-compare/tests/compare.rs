//! `compare` end to end on a built-in scene, with the JSON checked against its schema.

use specula_compare::{compare, Options};

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
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("report.json")).unwrap())
            .unwrap();
    let schema: serde_json::Value =
        serde_json::from_str(include_str!("../../../docs/compare.schema.json")).unwrap();
    let validator = jsonschema::validator_for(&schema).unwrap();
    let errors: Vec<String> = validator
        .iter_errors(&json)
        .map(|e| format!("{e} at {}", e.instance_path()))
        .collect();
    assert!(errors.is_empty(), "{errors:?}");
    let m = &comparison.report.methods[0];
    assert!(m.metrics.mask_pixels > 100);
    // Measured 2026-11-30: 0.047; bound 2x.
    assert!(
        m.metrics.mean_flip < 0.095,
        "envmap on the door mirror: mean FLIP {}",
        m.metrics.mean_flip
    );
    let r = &comparison.report;
    let expected = r.reference.total_ms / m.total_ms;
    assert!(
        (m.speedup_over_reference - expected).abs() <= 1e-9 * expected,
        "speed-up {} is not reference time / method time {expected}",
        m.speedup_over_reference
    );
    // gpu-trace was timed as the second base although not compared.
    let gpu_trace_ms = r.gpu_trace_ms.expect("a GPU run times gpu-trace");
    let ratio = m.speedup_over_gpu_trace.unwrap();
    assert!((ratio - gpu_trace_ms / m.total_ms).abs() <= 1e-9 * ratio);
    assert!(text.contains("vs gpu-trace"));
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
