//! The `specula` binary end to end: the contract's commands, outputs and error handling.

use std::process::Command;

fn specula() -> Command {
    Command::new(env!("CARGO_BIN_EXE_specula"))
}

/// Every line of a listing fits in 100 columns.
fn fits_in_100_columns(text: &str) {
    for line in text.lines() {
        assert!(
            line.chars().count() <= 100,
            "{} columns: {line}",
            line.chars().count()
        );
    }
}

#[test]
fn scenes_lists_every_built_in_scene_one_line_each() {
    let out = specula().arg("scenes").output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    let names = specula_scene::builtin::names();
    // One entry a scene, its description wrapped (indented) to fit 100 columns.
    let entries = text.lines().filter(|l| !l.starts_with(' ')).count();
    assert_eq!(entries, names.len());
    fits_in_100_columns(&text);
    for name in names {
        assert!(
            text.lines().any(|l| l.starts_with(name)),
            "{name} missing from:\n{text}"
        );
    }
}

#[test]
fn render_writes_png_and_exr_of_the_requested_size() {
    let dir = tempfile::tempdir().unwrap();
    let (png, exr) = (dir.path().join("o.png"), dir.path().join("o.exr"));
    let out = specula()
        .args([
            "render",
            "spectacle-lens",
            "-W",
            "40",
            "-H",
            "24",
            "--spp",
            "2",
            "--max-depth",
            "4",
            "-o",
        ])
        .arg(&png)
        .arg("--exr")
        .arg(&exr)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let png_image = image::open(&png).unwrap();
    assert_eq!((png_image.width(), png_image.height()), (40, 24));
    let exr_image = image::open(&exr).unwrap().to_rgb32f();
    assert_eq!((exr_image.width(), exr_image.height()), (40, 24));
    assert!(exr_image
        .pixels()
        .all(|p| p.0.iter().all(|c| c.is_finite() && *c >= 0.0)));
    assert!(
        exr_image.pixels().any(|p| p.0.iter().any(|c| *c > 0.01)),
        "not all black"
    );
    // The PNG is the EXR's linear radiance clamped to [0, 1] and sRGB-encoded (to one 8-bit
    // step: the EXR may hold half floats).
    let srgb = |c: f32| {
        let c = c.clamp(0.0, 1.0);
        let encoded = if c <= 0.0031308 {
            12.92 * c
        } else {
            1.055 * c.powf(1.0 / 2.4) - 0.055
        };
        encoded * 255.0
    };
    let png_rgb = png_image.to_rgb8();
    for (p, q) in exr_image.pixels().zip(png_rgb.pixels()) {
        for (linear, byte) in p.0.iter().zip(q.0) {
            assert!(
                (srgb(*linear) - byte as f32).abs() <= 1.0,
                "linear {linear} written as {byte}"
            );
        }
    }
}

#[test]
fn render_defaults_to_the_door_mirror_and_keeps_the_camera_aspect() {
    let dir = tempfile::tempdir().unwrap();
    let out = specula()
        .current_dir(dir.path())
        .args(["render", "-W", "32"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stderr).contains("door-mirror"));
    let img = image::open(dir.path().join("out.png")).unwrap();
    assert_eq!((img.width(), img.height()), (32, 24));
}

#[test]
fn bad_input_is_a_clear_error_not_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.obj");
    std::fs::write(&bad, "v 0 0 0\nv 1 0 nan\nv 0 1 0\nf 1 2 3\n").unwrap();
    let cases: Vec<(Vec<String>, &str)> = vec![
        (
            vec!["render".into(), bad.display().to_string()],
            "bad.obj:2",
        ),
        (vec!["render".into(), "nowhere.glb".into()], "nowhere.glb"),
        (vec!["render".into(), "no-such-scene".into()], "door-mirror"),
        (
            vec!["render".into(), "--method".into(), "magic".into()],
            "valid methods: reference",
        ),
        (vec!["render".into(), "-W".into(), "0".into()], "0"),
        (
            vec![
                "render".into(),
                "--method".into(),
                "envmap".into(),
                "-p".into(),
                "exit=portal".into(),
            ],
            "expected one of none, sphere, slab",
        ),
        (
            vec![
                "render".into(),
                "--method".into(),
                "envmap".into(),
                "-p".into(),
                "colour=1".into(),
            ],
            "parameters are resolution, exit, dynamic, two_level_maps, shadow_resolution",
        ),
        (
            vec![
                "render".into(),
                "--method".into(),
                "envmap".into(),
                "-p".into(),
                "resolution".into(),
            ],
            "NAME=VALUE",
        ),
        (
            ["render", "--distributed", "--method", "envmap"]
                .map(String::from)
                .to_vec(),
            "--distributed runs vertex-tracing, not envmap",
        ),
        (
            ["render", "--distributed", "--slow-rank", "0:2"]
                .map(String::from)
                .to_vec(),
            "expected a worker rank (1 or more), got '0'",
        ),
        (
            ["render", "--distributed", "--fail-rank", "2:x"]
                .map(String::from)
                .to_vec(),
            "expected a package number of 1 or more, got 'x'",
        ),
        (
            ["render", "--method", "envmap", "--sequence", "steps"]
                .map(String::from)
                .to_vec(),
            "--sequence needs a progressive method",
        ),
        (
            ["render", "--method", "c3rc:fast"]
                .map(String::from)
                .to_vec(),
            "unknown preset in 'c3rc:fast'; valid: c3rc:paper",
        ),
        (
            ["compare", "--methods", "pvrr:"].map(String::from).to_vec(),
            "unknown preset in 'pvrr:'; valid: pvrr:paper",
        ),
        (
            ["bench", "--methods", "envmap:paper"]
                .map(String::from)
                .to_vec(),
            "envmap has no presets",
        ),
        (
            ["compare", "--methods", "c3rc:paper,envmap,c3rc:paper"]
                .map(String::from)
                .to_vec(),
            "'c3rc:paper' is given twice",
        ),
        (
            ["compare", "--methods", "c3rc", "-p", "c3rc:paper.points=10"]
                .map(String::from)
                .to_vec(),
            "names a label that is not in this run (c3rc)",
        ),
        (
            [
                "compare",
                "--methods",
                "c3rc,c3rc:paper",
                "-p",
                "c3rc:paper.magic=1",
            ]
            .map(String::from)
            .to_vec(),
            "c3rc's parameters are points",
        ),
        (
            [
                "render",
                "--method",
                "vertex-tracing",
                "-p",
                "visibility=maybe",
            ]
            .map(String::from)
            .to_vec(),
            "expected one of auto, cpu, gpu",
        ),
    ];
    for (args, expected) in cases {
        let out = specula()
            .current_dir(dir.path())
            .args(&args)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(!stderr.contains("panicked"), "{args:?} panicked: {stderr}");
        assert!(
            stderr.contains(expected),
            "{args:?}: {stderr:?} should mention {expected:?}"
        );
    }
}

fn has_gpu(test: &str) -> bool {
    specula_gpu::test_context(test).is_some()
}

#[test]
fn render_with_a_gpu_method() {
    if !has_gpu("render_with_a_gpu_method") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let out = specula()
        .current_dir(dir.path())
        .args([
            "render",
            "teapot-box",
            "--method",
            "envmap",
            "-W",
            "48",
            "-p",
            "resolution=32",
            "-p",
            "exit=sphere",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let img = image::open(dir.path().join("out.png")).unwrap();
    assert_eq!((img.width(), img.height()), (48, 36));
}

#[test]
fn compare_with_no_arguments_reports_every_method_on_the_default_scene() {
    if !has_gpu("compare_with_no_arguments") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let out = specula()
        .current_dir(dir.path())
        .args(["compare", "-W", "64", "--json", "r.json"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("door-mirror") && stdout.contains("envmap"),
        "{stdout}"
    );
    assert!(dir.path().join("specula-report/report.html").exists());
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("r.json")).unwrap()).unwrap();
    // Every method but the CPU reference, gpu-trace first: it agrees with the reference (≥ 79 dB in gpu_trace's test).
    let names: Vec<&str> = json["methods"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["method"].as_str().unwrap())
        .collect();
    let mut expected = vec!["gpu-trace"];
    expected.extend(
        specula_methods::METHODS
            .iter()
            .filter(|m| !m.exact)
            .map(|m| m.name),
    );
    assert_eq!(names, expected);
    assert!(json["methods"][0]["metrics"]["psnr_db"]
        .as_f64()
        .is_none_or(|db| db > 45.0));
    assert!(json["methods"][1]["speedup_over_gpu_trace"]
        .as_f64()
        .is_some());
}

#[test]
fn compare_over_a_folder_writes_one_table_and_a_row_per_failed_scene() {
    if !has_gpu("compare_over_a_folder") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let scenes = dir.path().join("scenes");
    std::fs::create_dir(&scenes).unwrap();
    std::fs::write(scenes.join("a-lens.toml"), "base = \"spectacle-lens\"\n").unwrap();
    std::fs::write(scenes.join("b-broken.toml"), "objects = 3\n").unwrap();
    std::fs::write(scenes.join("notes.txt"), "not a scene").unwrap();
    let out = specula()
        .current_dir(dir.path())
        .args([
            "compare",
            "door-mirror",
            "scenes",
            "--methods",
            "envmap",
            "-W",
            "32",
            "--report",
            "suite",
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    // The broken scene fails the command, after the others were compared and written.
    assert!(!out.status.success());
    assert!(
        stderr.contains("b-broken.toml") && stderr.contains("1 of 3 scenes failed"),
        "{stderr}"
    );
    let report = dir.path().join("suite");
    for page in [
        "report.html",
        "door-mirror/report.html",
        "a-lens/report.html",
    ] {
        assert!(report.join(page).exists(), "{page} missing");
    }
    let html = std::fs::read_to_string(report.join("report.html")).unwrap();
    assert!(html.contains("href=\"a-lens/report.html\"") && html.contains("b-broken.toml"));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(report.join("report.json")).unwrap())
            .unwrap();
    let schema: serde_json::Value =
        serde_json::from_str(include_str!("../../../docs/compare-suite.schema.json")).unwrap();
    let validator = jsonschema::validator_for(&schema).unwrap();
    let errors: Vec<String> = validator
        .iter_errors(&json)
        .map(|e| format!("{e} at {}", e.instance_path()))
        .collect();
    assert!(errors.is_empty(), "{errors:?}");
    let rows = json["scenes"].as_array().unwrap();
    assert_eq!(rows.len(), 3);
    assert_eq!(rows[0]["scene"], "door-mirror");
    assert!(rows[0]["methods"][0]["mean_flip"].as_f64().unwrap() > 0.0);
    assert!(rows[1]["error"].is_null());
    assert!(rows[2]["error"].as_str().unwrap().contains("objects"));
}

#[test]
fn bench_reports_median_and_spread_per_stage() {
    if !has_gpu("bench_reports_median_and_spread") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let out = specula()
        .current_dir(dir.path())
        .args([
            "bench",
            "door-mirror",
            "--methods",
            "envmap",
            "--frames",
            "3",
            "-W",
            "32",
            "--json",
            "b.json",
            "--markdown",
            "b.md",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("b.json")).unwrap()).unwrap();
    // envmap keeps scene-only maps, so it is timed static and dynamic; the two exact methods
    // are timed too, as the ratios' bases; warm frames create no GPU objects.
    assert!(json["date"].as_str().unwrap().starts_with("20"));
    assert!(json["ray_queries"].is_boolean());
    let runs = json["runs"].as_array().unwrap();
    let names: Vec<(&str, &str)> = runs
        .iter()
        .map(|r| (r["method"].as_str().unwrap(), r["mode"].as_str().unwrap()))
        .collect();
    assert_eq!(
        names,
        [
            ("envmap", "static"),
            ("envmap", "dynamic"),
            ("reference", "-"),
            ("gpu-trace", "-")
        ]
    );
    for run in runs {
        assert_eq!(run["frames"], 3);
        assert_eq!(run["created"], 0, "{run}");
        assert!(!run["stages"].as_array().unwrap().is_empty());
        // Each ratio is the exact method's median over this run's.
        let median = run["frame"]["median_ms"].as_f64().unwrap();
        for (base, key) in [(2, "speedup_over_reference"), (3, "speedup_over_gpu_trace")] {
            let base_median = runs[base]["frame"]["median_ms"].as_f64().unwrap();
            let ratio = run[key].as_f64().unwrap();
            assert!(
                (ratio - base_median / median).abs() < 1e-9 * ratio.max(1.0),
                "{run}"
            );
        }
    }
    assert!(runs[0]["stages"].as_array().unwrap().len() >= 3);
    // The exact methods count their rays: the same rays, so the same count per frame.
    for exact in &runs[2..] {
        assert!(exact["rays_per_second"].as_f64().unwrap() > 0.0, "{exact}");
    }
    let markdown = std::fs::read_to_string(dir.path().join("b.md")).unwrap();
    assert_eq!(markdown.matches("| door-mirror |").count(), 4, "{markdown}");
}

#[test]
fn bench_parameters_go_to_the_methods_asked_for_not_to_the_added_bases() {
    if !has_gpu("bench_parameters_go_to_the_methods_asked_for") {
        return;
    }
    // image-space and gpu-trace both have a `mode`; gpu-trace, timed as a base, keeps its own.
    let dir = tempfile::tempdir().unwrap();
    let out = specula()
        .current_dir(dir.path())
        .args([
            "bench",
            "glass-dragon",
            "--methods",
            "image-space",
            "-p",
            "mode=ray-plane",
            "--frames",
            "1",
            "-W",
            "32",
            "--json",
            "b.json",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("b.json")).unwrap()).unwrap();
    let mode_of = |method: &str| {
        let run = json["runs"]
            .as_array()
            .unwrap()
            .iter()
            .find(|r| r["method"] == method)
            .unwrap();
        let parameters = run["parameters"].as_array().unwrap();
        parameters
            .iter()
            .find(|p| p[0] == "mode")
            .map(|p| p[1].as_str().unwrap().to_string())
            .unwrap()
    };
    assert_eq!(mode_of("image-space"), "ray-plane");
    assert_eq!(mode_of("gpu-trace"), "megakernel");
    // A parameter no asked-for method has is still an error.
    let out = specula()
        .args([
            "bench",
            "glass-dragon",
            "--methods",
            "envmap",
            "-p",
            "seeds=3",
            "-W",
            "16",
        ])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("seeds=3"));
}

#[test]
fn bench_paper_times_each_method_beside_its_published_algorithm() {
    let dir = tempfile::tempdir().unwrap();
    let out = specula()
        .current_dir(dir.path())
        .args([
            "bench",
            "truck-cover",
            "--methods",
            "vertex-tracing",
            "--paper",
            "-p",
            "vertex-tracing:paper.epsilon=0.05",
            "--frames",
            "1",
            "-W",
            "24",
            "--json",
            "b.json",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("b.json")).unwrap()).unwrap();
    assert_eq!(json["schema_version"], 4);
    assert_eq!(json["failed"], serde_json::json!([]));
    let runs = json["runs"].as_array().unwrap();
    let run = |label: &str| {
        runs.iter()
            .find(|r| r["label"] == label)
            .unwrap_or_else(|| panic!("no run of {label}: {json}"))
    };
    let parameter = |label: &str, name: &str| {
        run(label)["parameters"]
            .as_array()
            .unwrap()
            .iter()
            .find(|p| p[0] == name)
            .map(|p| p[1].as_str().unwrap().to_string())
            .unwrap()
    };
    assert_eq!(run("vertex-tracing:paper")["method"], "vertex-tracing");
    assert_eq!(run("vertex-tracing:paper")["preset"], "paper");
    assert!(run("vertex-tracing")["preset"].is_null());
    assert_eq!(parameter("vertex-tracing:paper", "tree_weight"), "0");
    assert_eq!(parameter("vertex-tracing:paper", "epsilon"), "0.05");
    assert_eq!(parameter("vertex-tracing", "epsilon"), "0.03");
    assert!(
        run("vertex-tracing:paper")["speedup_over_reference"]
            .as_f64()
            .unwrap()
            > 0.0
    );
}

#[test]
fn methods_lists_every_method_with_its_parameters_from_the_registry() {
    let out = specula().arg("methods").output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    fits_in_100_columns(&text);
    // Lines wrapped to fit are read joined: every run of white space as one space.
    let words = |t: &str| t.split_whitespace().collect::<Vec<_>>().join(" ");
    let joined = words(&text);
    for info in specula_methods::METHODS {
        assert!(
            text.lines()
                .any(|l| l.starts_with(&format!("{} (", info.name))),
            "{text}"
        );
        for p in info.params {
            let takes = format!(
                "{} {} (default {}); change redoes: {}",
                p.name,
                p.kind.describe(),
                p.default,
                p.invalidates.describe()
            );
            assert!(
                joined.contains(&words(&takes)),
                "{}.{} missing: {text}",
                info.name,
                p.name
            );
            assert!(joined.contains(&words(p.doc)), "{}", p.doc);
        }
    }
    assert!(text.contains("reference (exact, CPU, progressive)"));
    for info in specula_methods::METHODS {
        for preset in info.presets {
            assert!(
                joined.contains(&words(&format!(
                    "preset {}:{}: {}",
                    info.name, preset.name, preset.summary
                ))),
                "{}:{} missing: {text}",
                info.name,
                preset.name
            );
            for setting in preset.settings {
                let name = setting.split_once('=').unwrap().0;
                let default = info.param(name).unwrap().default;
                assert!(
                    text.lines().any(|l| l.trim_start().starts_with(setting)
                        && l.trim_end().ends_with(&format!("instead of {default}"))),
                    "{}:{} {setting} missing: {text}",
                    info.name,
                    preset.name
                );
            }
        }
    }
}

#[test]
fn sequence_writes_every_step_and_piped_output_draws_no_progress_bar() {
    // CPU visibility: runs without a GPU.
    let dir = tempfile::tempdir().unwrap();
    let out = specula()
        .current_dir(dir.path())
        .args([
            "render",
            "truck-cover",
            "--method",
            "vertex-tracing",
            "-W",
            "64",
            "-H",
            "48",
            "-p",
            "visibility=cpu",
            "-p",
            "budget_ms=1",
            "--sequence",
            "steps",
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    // Piped: no progress bar (it redraws with carriage returns and escape sequences).
    assert!(
        !stderr.contains('\r') && !stderr.contains('\u{1b}'),
        "{stderr:?}"
    );
    let steps = dir.path().join("steps");
    let csv = std::fs::read_to_string(steps.join("steps.csv")).unwrap();
    let mut lines = csv.lines();
    assert!(
        lines.next().unwrap().starts_with("step,image,milliseconds"),
        "{csv}"
    );
    let rows: Vec<&str> = lines.collect();
    assert!(!rows.is_empty(), "{csv}");
    for (i, row) in rows.iter().enumerate() {
        let name = format!("step-{i:03}.png");
        assert!(row.contains(&name), "{row}");
        let image = image::open(steps.join(&name)).unwrap();
        assert_eq!((image.width(), image.height()), (64, 48));
    }
}

#[test]
fn gpu_methods_without_a_vulkan_adapter_say_what_to_install() {
    // No Vulkan driver visible to the loader: no adapter.
    let dir = tempfile::tempdir().unwrap();
    let none = dir.path().join("no-such-icd.json");
    let out = specula()
        .current_dir(dir.path())
        .args(["render", "--method", "envmap", "-W", "16"])
        .env("VK_ICD_FILENAMES", &none)
        .env("VK_DRIVER_FILES", &none)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(
        stderr.contains("apt-get install mesa-vulkan-drivers"),
        "{stderr}"
    );
}

/// `specula methods | head`: a reader that closes the pipe early ends the program quietly (by
/// the pipe's signal, as other Unix tools end), not with a panic's message and backtrace. The
/// reader here is gone before the first line is written.
#[cfg(unix)]
#[test]
fn writing_to_a_closed_pipe_ends_quietly() {
    use std::os::unix::process::ExitStatusExt;
    let mut child = specula()
        .arg("methods")
        .env("NODEVICE_SELECT", "1")
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(out.status.signal(), Some(13), "{:?}: {stderr}", out.status);
}

/// An OBJ with no materials, as a CAD export gives one: a floor, a ball and a pair of balls in
/// one object (octahedra), each named by its `o` line.
fn bare_obj(dir: &std::path::Path) -> std::path::PathBuf {
    let mut text =
        String::from("o floor\nv -2 0 -2\nv 2 0 -2\nv 2 0 2\nv -2 0 2\nf 1 3 2\nf 1 4 3\n");
    let mut vertices = 4;
    let mut ball = |text: &mut String, [x, y, z]: [f32; 3], r: f32| {
        for [dx, dy, dz] in [
            [0.0, -r, 0.0],
            [0.0, r, 0.0],
            [r, 0.0, 0.0],
            [-r, 0.0, 0.0],
            [0.0, 0.0, r],
            [0.0, 0.0, -r],
        ] {
            text.push_str(&format!("v {} {} {}\n", x + dx, y + dy, z + dz));
        }
        let v = |i: usize| vertices + i;
        for [a, b, c] in [[1, 3, 5], [1, 5, 4], [1, 4, 6], [1, 6, 3]] {
            text.push_str(&format!("f {} {} {}\n", v(a), v(b), v(c)));
        }
        for [a, b, c] in [[2, 5, 3], [2, 4, 5], [2, 6, 4], [2, 3, 6]] {
            text.push_str(&format!("f {} {} {}\n", v(a), v(b), v(c)));
        }
        vertices += 6;
    };
    text.push_str("o ball\n");
    ball(&mut text, [0.0, 1.0, 0.0], 1.0);
    text.push_str("o pair\n");
    ball(&mut text, [-1.4, 0.3, 1.0], 0.25);
    ball(&mut text, [1.4, 0.3, 1.0], 0.25);
    let path = dir.join("bare.obj");
    std::fs::write(&path, text).unwrap();
    path
}

fn run(dir: &std::path::Path, args: &[&str]) -> (bool, String) {
    let out = specula().current_dir(dir).args(args).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(!stderr.contains("panicked"), "{args:?} panicked: {stderr}");
    (out.status.success(), stderr)
}

#[test]
fn material_makes_an_object_of_a_bare_file_a_mirror_or_glass() {
    let dir = tempfile::tempdir().unwrap();
    bare_obj(dir.path());
    let render = |out: &str, materials: &[&str]| {
        let mut args = vec!["render", "bare.obj", "-W", "64", "-H", "48", "-o", out];
        for m in materials {
            args.extend(["--material", m]);
        }
        let (ok, stderr) = run(dir.path(), &args);
        assert!(ok, "{args:?}: {stderr}");
        (image::open(dir.path().join(out)).unwrap().to_rgb8(), stderr)
    };
    let (plain, _) = render("plain.png", &[]);
    let (mirror, _) = render("mirror.png", &["ball=mirror"]);
    let (glass, _) = render("glass.png", &["ball=diffuse", "ball=glass:1.5"]);
    let differing = |a: &image::RgbImage, b: &image::RgbImage| {
        a.pixels().zip(b.pixels()).filter(|(p, q)| p != q).count()
    };
    // The ball covers about 100 of the 3072 pixels (88 change as a mirror, 84 more as glass).
    let (shows, glass_shows) = (differing(&plain, &mirror), differing(&mirror, &glass));
    assert!(shows > 50, "the mirror does not show ({shows} pixels)");
    assert!(
        glass_shows > 50,
        "the glass is the mirror ({glass_shows} pixels)"
    );
    // The pair is one object of two balls: made a mirror, it is split as a file's mirror is.
    let (_, stderr) = render("pair.png", &["pair=mirror"]);
    assert!(
        stderr.contains("mesh 'pair' holds 2 separate objects: split into 'pair#1'...'pair#2'"),
        "{stderr}"
    );
}

#[test]
fn a_bad_material_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    bare_obj(dir.path());
    let syntax = "expected NAME=mirror|glass:IOR|thin-glass:IOR|diffuse|unlit, got";
    let cases: Vec<(Vec<&str>, String)> =
        vec![
        (
            vec!["render", "bare.obj", "--material", "ball"],
            format!("{syntax} 'ball'"),
        ),
        (
            vec!["render", "bare.obj", "--material", "ball=chrome"],
            format!("{syntax} 'ball=chrome'"),
        ),
        (
            vec!["compare", "bare.obj", "--material", "ball=glass"],
            format!("{syntax} 'ball=glass'"),
        ),
        (
            vec!["bench", "bare.obj", "--material", "ball=glass:0"],
            "the index of refraction must be a finite number above 0".into(),
        ),
        (
            vec!["view", "bare.obj", "--material", "=mirror"],
            format!("{syntax} '=mirror'"),
        ),
        (
            vec!["analyze", "lens", "bare.obj", "--material", "ball=thin-glass:x"],
            "the index of refraction must be a finite number above 0 (glass is about 1.5), got 'x'"
                .into(),
        ),
        (
            vec!["render", "bare.obj", "--material", "bal=mirror", "-W", "8"],
            "--material: bare.obj: no object 'bal' to make mirror; the scene's objects are: \
             'floor', 'ball', 'pair'"
                .into(),
        ),
        (
            vec![
                "compare",
                "bare.obj",
                "door-mirror",
                "--material",
                "bal=mirror",
                "--report",
                "suite",
            ],
            "--material bal=mirror: none of the 2 scenes has an object 'bal'; their objects are: \
             'floor', 'ball', 'pair', 'door mirror'"
                .into(),
        ),
    ];
    for (args, expected) in cases {
        let (ok, stderr) = run(dir.path(), &args);
        assert!(!ok, "{args:?} succeeded");
        assert!(stderr.contains(&expected), "{args:?}: {stderr}");
    }
    // The suite was refused before it ran.
    assert!(!dir.path().join("suite").exists());
}

#[test]
fn compare_of_a_bare_file_says_how_to_make_a_mirror() {
    let dir = tempfile::tempdir().unwrap();
    bare_obj(dir.path());
    let compare = ["compare", "bare.obj", "--methods", "vertex-tracing"];
    let small = ["-W", "32", "-H", "24", "--frames", "1"];
    let (ok, stderr) = run(dir.path(), &[&compare[..], &small].concat());
    assert!(!ok);
    assert!(
        stderr.contains(
            "the scene has no mirror or dielectric surface in view: nothing to compare; it has \
             none: make an object one with --material NAME=mirror (or NAME=glass:IOR); its \
             objects are: 'floor', 'ball', 'pair'"
        ),
        "{stderr}"
    );
    let (ok, stderr) = run(
        dir.path(),
        &[&compare[..], &small, &["--material", "ball=mirror"]].concat(),
    );
    assert!(ok, "{stderr}");
    // Several scenes: each takes the materials whose object it has (door-mirror has no ball).
    let (ok, stderr) = run(
        dir.path(),
        &[
            &compare[..],
            &small,
            &[
                "door-mirror",
                "--material",
                "ball=mirror",
                "--report",
                "suite",
            ],
        ]
        .concat(),
    );
    assert!(ok, "{stderr}");
    assert!(dir.path().join("suite/bare/report.html").exists());
}

#[test]
fn an_analysis_of_an_object_that_is_not_specular_says_how_to_make_it_one() {
    let dir = tempfile::tempdir().unwrap();
    bare_obj(dir.path());
    let cases = [
        (
            vec!["analyze", "mirror-view", "bare.obj", "--mirror", "ball"],
            "--mirror 'ball' is diffuse, not a mirror; make it one with --material ball=mirror \
             on the command line, a material of `type = \"mirror\"` in a scene file, or `illum 3` \
             (or 5) in its OBJ material (F0 from `Ks`)",
        ),
        (
            vec!["analyze", "lens", "bare.obj", "--lens", "ball"],
            "--lens 'ball' is diffuse, not a refractor (a solid dielectric); make it one with \
             --material ball=glass:1.5 (its index of refraction) on the command line",
        ),
        (
            vec![
                "analyze",
                "glare",
                "bare.obj",
                "--surface",
                "ball",
                "--source",
                "floor",
            ],
            "--surface 'ball' is diffuse, not a mirror or a glass (a surface that reflects \
             specularly); make it one with --material ball=mirror or --material ball=glass:1.5 \
             on the command line",
        ),
    ];
    for (args, expected) in cases {
        let (ok, stderr) = run(dir.path(), &args);
        assert!(!ok, "{args:?} succeeded");
        assert!(stderr.contains(expected), "{args:?}: {stderr}");
    }
    let (ok, stderr) = run(
        dir.path(),
        &[
            "analyze",
            "mirror-view",
            "bare.obj",
            "--mirror",
            "ball",
            "--material",
            "ball=mirror",
            "--eyebox",
            "0.1,0.1,2,2",
        ],
    );
    assert!(ok, "{stderr}");
}
