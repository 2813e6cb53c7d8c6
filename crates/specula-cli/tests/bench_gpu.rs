//! `scripts/bench-gpu.sh --small` end to end on whatever adapter this machine has (lavapipe in
//! CI): every method on every built-in scene, gpu-trace's rays per second on the dragon, one
//! JSON and one markdown file.

use std::path::Path;
use std::process::{Command, Stdio};

#[test]
fn bench_gpu_script_runs_every_method_on_every_scene_at_a_small_size() {
    if specula_gpu::test_context("bench-gpu.sh").is_none() {
        return;
    }
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let out = tempfile::tempdir().unwrap();
    let status = Command::new(root.join("scripts/bench-gpu.sh"))
        .args(["--small", "--out"])
        .arg(out.path())
        .env("SPECULA", env!("CARGO_BIN_EXE_specula"))
        .env("DRAGON", root.join("scenes/meshes/dragon_res4.obj"))
        .stdout(Stdio::null())
        .status()
        .unwrap();
    assert!(status.success());
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.path().join("bench-gpu.json")).unwrap())
            .unwrap();
    let runs = json["scenes"]["runs"].as_array().unwrap();
    for scene in specula_scene::builtin::names() {
        for method in specula_methods::METHODS {
            let modes: Vec<&str> = runs
                .iter()
                .filter(|r| r["scene"] == scene && r["method"] == method.name)
                .map(|r| r["mode"].as_str().unwrap())
                .collect();
            let expected: &[&str] = if method.param("dynamic").is_some() {
                &["static", "dynamic"]
            } else {
                &["-"]
            };
            assert_eq!(modes, expected, "{scene} {}", method.name);
        }
    }
    for run in runs {
        assert!(
            run["speedup_over_gpu_trace"].as_f64().unwrap() > 0.0,
            "{run}"
        );
        assert!(
            run["speedup_over_reference"].as_f64().unwrap() > 0.0,
            "{run}"
        );
        assert_eq!(
            (run["width"].as_u64(), run["height"].as_u64()),
            (Some(160), Some(90))
        );
    }
    assert!(json["scenes"]["driver"].is_string() && json["scenes"]["date"].is_string());
    let dragon = &json["dragon"]["runs"];
    let gpu_trace = dragon
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["method"] == "gpu-trace")
        .unwrap();
    assert!(gpu_trace["rays_per_second"].as_f64().unwrap() > 0.0);
    for composition in ["composition_cpu", "composition_gpu"] {
        let vertex_tracing = json[composition]["runs"]
            .as_array()
            .unwrap()
            .iter()
            .find(|r| r["method"] == "vertex-tracing")
            .unwrap_or_else(|| panic!("{composition}: no vertex-tracing run"));
        assert!(
            vertex_tracing["frame"]["median_ms"].as_f64().unwrap() > 0.0,
            "{composition}"
        );
    }
    let markdown = std::fs::read_to_string(out.path().join("bench-gpu.md")).unwrap();
    assert!(markdown.contains("Adapter: ") && markdown.contains("| stanford-dragon | gpu-trace |"));
}
