//! `specula view --script` under Xvfb (lavapipe): the viewer's screenshots after moving the
//! door mirror through the update path equal `specula render` of a scene file with the mirror
//! at the moved pose, for every GPU technique; bad scripts fail naming the step.
//!
//! Skipped (loudly) where `xvfb-run` is missing, except under CI, which installs it.

use std::path::Path;
use std::process::Command;

use specula_trace::Image;

fn specula() -> Command {
    Command::new(env!("CARGO_BIN_EXE_specula"))
}

/// `xvfb-run -a specula view ...`, or None (after a SKIPPED line) without Xvfb.
fn viewer(test: &str) -> Option<Command> {
    let found = Command::new("xvfb-run").arg("--help").output().is_ok();
    if !found {
        assert!(
            std::env::var_os("CI").is_none(),
            "{test}: xvfb-run missing under CI (scripts/setup.sh installs it)"
        );
        eprintln!("\n!!!!!!!! SKIPPED {test}: xvfb-run not installed !!!!!!!!\n");
        return None;
    }
    let mut command = Command::new("xvfb-run");
    command
        .args(["-a", "-s", "-screen 0 1024x768x24"])
        .arg(env!("CARGO_BIN_EXE_specula"))
        .arg("view")
        .env("NODEVICE_SELECT", "1");
    Some(command)
}

fn run_ok(mut command: Command) -> String {
    let out = command.output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(out.status.success(), "{command:?} failed:\n{stderr}");
    stderr
}

fn mean_flip(a: &Path, b: &Path) -> f64 {
    let (a, b) = (Image::load(a).unwrap(), Image::load(b).unwrap());
    assert_eq!(
        (a.width, a.height),
        (b.width, b.height),
        "image sizes differ"
    );
    let flip = specula_compare::metrics::flip_map(&a, &b);
    flip.iter().map(|&v| v as f64).sum::<f64>() / flip.len() as f64
}

const METHODS: [&str; 3] = ["pvrr", "envmap", "distance-maps"];
const MOVE_BY: [f32; 3] = [0.03, 0.02, 0.0];
const TURN_DEGREES: f32 = 12.0;
const SIZE: (u32, u32) = (200, 150);

/// Measured 2026-11-30 on lavapipe: pvrr 0.0000, envmap 0.0000, distance-maps 0.0000 (the
/// images are identical), image-space on glass-dragon 0.0000, c3rc on mirror-teapot-bunny
/// 0.0000; the bound is the issue's.
const MAX_MEAN_FLIP: f64 = 0.01;

#[test]
fn viewer_screenshots_after_a_move_match_the_renderer_at_the_moved_pose() {
    screenshots_after_a_move_match_the_renderer("door-mirror", "door mirror", MOVE_BY, &METHODS);
}

#[test]
fn c3rc_follows_a_moved_nearby_object_in_the_viewer() {
    // The dragon beside the teapot: its points keep their tree and move with it (a move large
    // enough to show at this size).
    screenshots_after_a_move_match_the_renderer(
        "mirror-teapot-bunny",
        "dragon",
        [-0.15, 0.0, 0.4],
        &["c3rc"],
    );
}

#[test]
fn image_space_follows_a_moved_refractor_in_the_viewer() {
    // The bunny is small in its view: a larger move, so that it shows.
    screenshots_after_a_move_match_the_renderer(
        "glass-dragon",
        "glass bunny",
        [0.12, 0.0, 0.04],
        &["image-space"],
    );
}

/// Moves and turns `object` of built-in `scene` in the viewer's script mode after a first
/// frame of each method, and holds each screenshot to `specula render` at the moved pose.
fn screenshots_after_a_move_match_the_renderer(
    scene_name: &str,
    object: &str,
    move_by: [f32; 3],
    methods: &[&str],
) {
    let Some(mut view) = viewer(&format!("screenshots after a move ({scene_name})")) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let [x, y, z] = move_by;
    // Every technique draws a frame at the original pose first, so that the move reaches it
    // through the update path (kept maps made stale), not through a first prepare.
    let mut script = String::new();
    for m in methods {
        script += &format!("[[step]]\nmethod = \"{m}\"\n[[step]]\nframes = 1\n");
    }
    script += &format!(
        "[[step]]\ntranslate = {{ object = \"{object}\", by = [{x}, {y}, {z}] }}\n\
         [[step]]\nrotate = {{ object = \"{object}\", axis = [0, 1, 0], degrees = {TURN_DEGREES} }}\n"
    );
    for m in methods {
        script += &format!(
            "[[step]]\nmethod = \"{m}\"\n[[step]]\nframes = 2\n[[step]]\nscreenshot = \"{}\"\n",
            dir.path().join(format!("view-{m}.png")).display()
        );
    }
    let script_path = dir.path().join("move.toml");
    std::fs::write(&script_path, script).unwrap();
    run_ok({
        view.args([
            scene_name,
            "--size",
            &format!("{}x{}", SIZE.0, SIZE.1),
            "--script",
        ])
        .arg(&script_path);
        view
    });

    let scene = dir.path().join("moved.toml");
    std::fs::write(
        &scene,
        format!(
            "base = \"{scene_name}\"\n\
             [[move]]\nobject = \"{object}\"\ntranslate = [{x}, {y}, {z}]\n\
             [[move]]\nobject = \"{object}\"\nrotate = {{ axis = [0, 1, 0], degrees = {TURN_DEGREES} }}\n"
        ),
    )
    .unwrap();
    for m in methods {
        let (moved, original) = (
            dir.path().join(format!("render-{m}.png")),
            dir.path().join(format!("original-{m}.png")),
        );
        for (scene, out) in [(scene.to_str().unwrap(), &moved), (scene_name, &original)] {
            let mut render = specula();
            render
                .args(["render", scene, "-m", m])
                .args(["-W", &SIZE.0.to_string(), "-H", &SIZE.1.to_string()])
                .arg("-o")
                .arg(out)
                .env("NODEVICE_SELECT", "1");
            run_ok(render);
        }
        let shot = dir.path().join(format!("view-{m}.png"));
        let error = mean_flip(&moved, &shot);
        // The move must show: otherwise the comparison above proves nothing.
        let moved_by = mean_flip(&original, &shot);
        eprintln!("{m}: mean FLIP against the renderer {error:.4}; against the unmoved pose {moved_by:.4}");
        assert!(
            error <= MAX_MEAN_FLIP,
            "{m}: mean FLIP {error} > {MAX_MEAN_FLIP}"
        );
        assert!(
            moved_by > 10.0 * MAX_MEAN_FLIP,
            "{m}: the move barely shows ({moved_by})"
        );
    }
}

#[test]
fn bad_script_steps_fail_naming_the_step() {
    let Some(_) = viewer("bad_script_steps_fail_naming_the_step") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (
            "[[step]]\nframes = 1\n[[step]]\nmethod = \"raytrace\"\n",
            "step 2",
            "raytrace",
        ),
        (
            "[[step]]\ntranslate = { object = \"wing\", by = [0, 1, 0] }\n",
            "step 1",
            "wing",
        ),
        ("[[step]]\nparam = \"zoom=2\"\n", "step 1", "zoom"),
    ];
    for (i, (text, step, what)) in cases.iter().enumerate() {
        let path = dir.path().join(format!("bad{i}.toml"));
        std::fs::write(&path, text).unwrap();
        let mut view = viewer("bad_script_steps_fail_naming_the_step").unwrap();
        view.args(["door-mirror", "--size", "64x48", "-m", "envmap", "--script"])
            .arg(&path);
        let out = view.output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{text:?} should fail");
        assert!(
            stderr.contains(step) && stderr.contains(what),
            "{text:?}: {stderr} should name {step} and {what}"
        );
    }
}
