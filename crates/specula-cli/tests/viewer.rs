//! `specula view --script` under Xvfb (lavapipe): the viewer's screenshots after moving an
//! object through the update path equal `specula render` of a scene file with the object at the
//! moved pose (byte for byte; c3rc to within 2 pixels, see `bounds`), for pvrr, envmap and
//! distance-maps on door-mirror, c3rc on mirror-teapot-bunny and image-space on glass-dragon;
//! the analysis panel's figures are `specula analyze`'s and its overlay follows a move; bad
//! scripts fail naming the step.
//!
//! Where `xvfb-run` is missing the tests fail, unless the runner opts out with
//! `SPECULA_ALLOW_SKIP=xvfb`.

use std::path::Path;
use std::process::Command;

use specula_trace::Image;

fn specula() -> Command {
    Command::new(env!("CARGO_BIN_EXE_specula"))
}

/// `xvfb-run -a specula view ...`, or None where Xvfb or a GPU adapter is missing and the runner
/// allowed the skip.
fn viewer(test: &str) -> Option<Command> {
    viewer_on(test, "1024x768x24")
}

/// The same on an Xvfb screen of `screen` (WIDTHxHEIGHTxDEPTH).
fn viewer_on(test: &str, screen: &str) -> Option<Command> {
    // The viewer draws with wgpu: it needs an adapter as much as a display.
    specula_gpu::test_context(test)?;
    let found = Command::new("xvfb-run").arg("--help").output().is_ok();
    if !found {
        specula_testkit::missing(
            specula_testkit::Requirement::Xvfb,
            test,
            "`xvfb-run --help` could not be run",
        );
        return None;
    }
    let mut command = Command::new("xvfb-run");
    command
        .args(["-a", "-s", &format!("-screen 0 {screen}")])
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

/// How far two PNG files differ: mean and largest per-pixel FLIP, and how many pixels differ in
/// any 8-bit channel.
struct Difference {
    mean_flip: f64,
    max_flip: f64,
    differing_pixels: usize,
}

fn difference(a: &Path, b: &Path) -> Difference {
    let (bytes_a, bytes_b) = (
        image::open(a).unwrap().to_rgb8(),
        image::open(b).unwrap().to_rgb8(),
    );
    assert_eq!(
        bytes_a.dimensions(),
        bytes_b.dimensions(),
        "image sizes differ"
    );
    let differing_pixels = bytes_a
        .pixels()
        .zip(bytes_b.pixels())
        .filter(|(p, q)| p != q)
        .count();
    let (a, b) = (Image::load(a).unwrap(), Image::load(b).unwrap());
    let flip = specula_compare::metrics::flip_map(&a, &b);
    Difference {
        mean_flip: flip.iter().map(|&v| v as f64).sum::<f64>() / flip.len() as f64,
        max_flip: flip.iter().fold(0.0f64, |m, &v| m.max(v as f64)),
        differing_pixels,
    }
}

const METHODS: [&str; 3] = ["pvrr", "envmap", "distance-maps"];
const MOVE_BY: [f32; 3] = [0.03, 0.02, 0.0];
const TURN_DEGREES: f32 = 12.0;
const SIZE: (u32, u32) = (200, 150);

/// How far a screenshot may be from `specula render` at the moved pose: (pixels of the
/// 200 × 150 PNGs that differ in any 8-bit channel, largest per-pixel FLIP, mean FLIP).
/// Measured 2026-12-01 on lavapipe under Xvfb, five runs alike: pvrr, envmap, distance-maps
/// (door-mirror) and image-space (glass-dragon) byte-identical; c3rc (mirror-teapot-bunny) one
/// pixel differed, FLIP 0.0096 there, mean FLIP 0.000004 (the moved dragon keeps its kd-tree and
/// maps its points through the move, where the renderer builds them at the moved pose: a
/// rounding moves one splat). c3rc measured again 2026-12-02, after its exact hits and a
/// camera for every triangle (issue 29), three runs alike: 8 pixels, largest FLIP 0.2138, mean
/// 0.000177 (the rounding now decides some projections of tiny triangles' cameras, and with
/// exact hits another nominated triangle changes a pixel wholly; a dragon left unmoved gives a
/// mean of 0.13). Bounds: 2× those, and identical where they were identical. Both
/// images must come from the same adapter (the viewer takes one that can present to Xvfb's
/// window; on lavapipe it is the renderer's).
fn bounds(method: &str) -> (usize, f64, f64) {
    match method {
        "c3rc" => (16, 0.43, 3.6e-4),
        _ => (0, 0.0, 0.0),
    }
}
/// The move itself must change the image by more than this mean FLIP (measured 0.116–0.147).
const MIN_MOVE_FLIP: f64 = 0.1;

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
        let error = difference(&moved, &shot);
        // The move must show: otherwise the comparison above proves nothing.
        let moved_by = difference(&original, &shot).mean_flip;
        eprintln!(
            "{m}: against the renderer mean FLIP {:.6}, largest {:.6}, {} of {} pixels differ; \
             against the unmoved pose mean FLIP {moved_by:.4}",
            error.mean_flip,
            error.max_flip,
            error.differing_pixels,
            SIZE.0 * SIZE.1
        );
        let (max_pixels, max_flip, max_mean) = bounds(m);
        assert!(
            error.differing_pixels <= max_pixels,
            "{m}: {} pixels differ (at most {max_pixels})",
            error.differing_pixels
        );
        assert!(
            error.max_flip <= max_flip,
            "{m}: a pixel's FLIP {} > {max_flip}",
            error.max_flip
        );
        assert!(
            error.mean_flip <= max_mean,
            "{m}: mean FLIP {} > {max_mean}",
            error.mean_flip
        );
        assert!(
            moved_by > MIN_MOVE_FLIP,
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
        (
            "[[step]]\nanalysis = { kind = \"mirror-view\", mirror = \"wing mirror\" }\n",
            "step 1",
            "the scene's objects are: door mirror",
        ),
        (
            "[[step]]\nanalysis = { kind = \"glare\", surface = \"door mirror\" }\n",
            "step 1",
            "glare needs a source",
        ),
        (
            "[[step]]\ncamera = \"analysis\"\n",
            "step 1",
            "no analysis is on",
        ),
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

/// The share of pixels near `colour` (within 40 in every 8-bit channel) in `shot` that are not
/// near it in `plain`: what an overlay of that colour covers.
fn drawn_over(plain: &Path, shot: &Path, colour: [u8; 3]) -> f64 {
    let (plain, shot) = (
        image::open(plain).unwrap().to_rgb8(),
        image::open(shot).unwrap().to_rgb8(),
    );
    let near = |p: &image::Rgb<u8>| (0..3).all(|c| p.0[c].abs_diff(colour[c]) <= 40);
    let count = plain
        .pixels()
        .zip(shot.pixels())
        .filter(|(a, b)| !near(a) && near(b))
        .count();
    count as f64 / (shot.width() * shot.height()) as f64
}

#[test]
fn the_analysis_panel_shows_the_command_s_figures_and_its_overlay_follows_a_turned_mirror() {
    let test =
        "the_analysis_panel_shows_the_command_s_figures_and_its_overlay_follows_a_turned_mirror";
    let Some(mut view) = viewer(test) else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let script = dir.path().join("analysis.toml");
    let shot = |name: &str| dir.path().join(name).display().to_string();
    std::fs::write(
        &script,
        format!(
            r#"
[[step]]
method = "reference"
[[step]]
analysis = {{ kind = "mirror-view", mirror = "door mirror", ocular = true, region = [1, 2, 5, 20] }}
[[step]]
camera = "analysis"
[[step]]
screenshot = "{before}"
[[step]]
panel = true
[[step]]
frames = 1
[[step]]
window_screenshot = "{window}"
[[step]]
panel = false
[[step]]
rotate = {{ object = "door mirror", axis = [0, 1, 0], degrees = 6 }}
[[step]]
screenshot = "{after}"
[[step]]
analysis = {{ kind = "off" }}
[[step]]
screenshot = "{plain}"
"#,
            plain = shot("plain.png"),
            before = shot("before.png"),
            after = shot("after.png"),
            window = shot("window.png"),
        ),
    )
    .unwrap();
    view.args(["door-mirror", "--size", "320x200", "--script"])
        .arg(&script);
    let log = run_ok(view);

    // The command, with the same options, gives the figures the panel printed.
    let json = dir.path().join("mirror-view.json");
    let out = specula()
        .args([
            "analyze",
            "mirror-view",
            "door-mirror",
            "--mirror",
            "door mirror",
            "--ocular",
            "--region",
            "1,2,5,20",
            "--json",
        ])
        .arg(&json)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let figure = |name: &str| report[name].as_f64().unwrap();
    let expected = format!(
        "horizontal {:.2}°, vertical {:.2}°, {:.4} sr, ground {:.2} m², region seen by any {:.1} %, by all {:.1} %, blind {:.2} m²",
        figure("horizontal_deg"),
        figure("vertical_deg"),
        figure("solid_angle_sr"),
        figure("ground_area_m2"),
        figure("region_seen_by_any") * 100.0,
        figure("region_seen_by_all") * 100.0,
        figure("blind_area_m2"),
    );
    assert!(
        log.contains(&format!("step 2: mirror-view of 'door mirror': {expected}")),
        "the panel's figures should be the command's: {expected}\n{log}"
    );
    let after_line = log
        .lines()
        .find(|l| l.starts_with("step 10: mirror-view"))
        .unwrap_or_else(|| panic!("the turned mirror's figures: {log}"));
    assert!(
        !after_line.contains(&expected),
        "turning the mirror changes the figures"
    );

    // The overlay: the blind part (red) and the seen part of the region (green) are drawn over
    // the plain view, and turning the mirror moves them.
    let (plain, before, after) = (
        dir.path().join("plain.png"),
        dir.path().join("before.png"),
        dir.path().join("after.png"),
    );
    let (red, green) = ([187, 96, 93], [67, 150, 66]);
    let (blind, seen) = (
        drawn_over(&plain, &before, red),
        drawn_over(&plain, &before, green),
    );
    eprintln!("the overlay covers {blind:.4} of the view in red, {seen:.4} in green");
    assert!(blind > 0.02 && seen > 0.02, "{blind}, {seen}");
    // With the panel docked, the view keeps two thirds of the window at least.
    let technique_width: u32 = log
        .lines()
        .find(|l| l.starts_with("step 6: 1 frames"))
        .and_then(|l| l.split("(technique at ").nth(1))
        .and_then(|rest| rest.split('x').next())
        .and_then(|w| w.parse().ok())
        .unwrap_or_else(|| panic!("the frame's line names the technique's size: {log}"));
    assert!(
        3 * technique_width >= 2 * 320,
        "the view keeps {technique_width} of 320 pixels"
    );
    // The window as shown: the view and its overlay under the panel.
    let window = image::open(dir.path().join("window.png"))
        .unwrap()
        .to_rgb8();
    assert_eq!(window.dimensions(), (320, 200));
    let differs = difference(&before, &dir.path().join("window.png"));
    assert!(
        differs.differing_pixels > 1000,
        "the panels: {} pixels",
        differs.differing_pixels
    );
    let moved = difference(&before, &after);
    assert!(
        moved.differing_pixels > 500,
        "{} pixels changed",
        moved.differing_pixels
    );
}

/// One analysis as each front end is asked for it: its kind, the scene, and its options by
/// name with their values as text (a repeatable one's values `;`-separated).
struct Asked {
    kind: &'static str,
    scene: &'static str,
    options: &'static [(&'static str, &'static str)],
}

impl Asked {
    /// The scene as every front end is given it: a built-in name, or the file's full path.
    fn scene(&self) -> String {
        match self.scene.ends_with(".toml") {
            true => Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../..")
                .join(self.scene)
                .display()
                .to_string(),
            false => self.scene.to_string(),
        }
    }

    /// The command line: `--name value` (repeated for each of a repeatable option's values).
    fn command(&self, json: &Path) -> Command {
        let mut command = specula();
        command
            .args(["analyze", self.kind])
            .arg(self.scene())
            .arg("--json")
            .arg(json);
        for (name, value) in self.options {
            for v in value.split(';') {
                command.arg(format!("--{}", name.replace('_', "-"))).arg(v);
            }
        }
        command
    }

    /// A viewer script's `analysis` step: the same options by name, as TOML.
    fn script_step(&self) -> String {
        let values: Vec<String> = self
            .options
            .iter()
            .map(|(name, value)| {
                let items: Vec<String> = value.split(';').map(|v| format!("{v:?}")).collect();
                match value.contains(';') || *name == "vehicle" {
                    true => format!("{name} = [{}]", items.join(", ")),
                    false => format!("{name} = {}", items[0]),
                }
            })
            .collect();
        format!(
            "analysis = {{ kind = \"{}\", {} }}",
            self.kind,
            values.join(", ")
        )
    }

    /// The library: the analysis by name, its options set by name, run.
    fn library(&self) -> String {
        use specula_analyze::analysis::{self, EyePoints, RunContext};
        let scene = specula_scene::load(&self.scene()).unwrap();
        let mut analysis = analysis::by_name(self.kind).unwrap();
        let mut eyes = EyePoints::default();
        for (name, value) in self.options {
            analysis.set_option(&mut eyes, name, value).unwrap();
        }
        let accel = specula_trace::SceneAccel::new(&scene);
        let cancel = std::sync::atomic::AtomicBool::new(false);
        let context = RunContext {
            progress: &|_| {},
            cancel: &cancel,
        };
        analysis.run(&scene, &accel, &eyes, &context).unwrap().json
    }
}

/// The three front ends on the one input model: the same analysis, asked with the defaults
/// (no eye points, no outermost point, no side), gives the same JSON document (verdict and
/// figures, byte for byte) from the command, a viewer script and the library.
#[test]
fn the_command_a_viewer_script_and_the_library_give_the_same_json() {
    let test = "the_command_a_viewer_script_and_the_library_give_the_same_json";
    let Some(_) = viewer(test) else {
        return;
    };
    let cases = [
        Asked {
            kind: "mirror-view",
            scene: "scenes/car-door-mirror.toml",
            options: &[
                ("mirror", "door mirror"),
                ("regulation", "r46-iii"),
                ("vehicle", "car body;A-pillar"),
            ],
        },
        Asked {
            kind: "glare",
            scene: "truck-cover",
            options: &[("surface", "cover glass"), ("source", "side window")],
        },
        Asked {
            kind: "lens",
            scene: "scenes/spectacles-wrap.toml",
            options: &[("lens", "right lens"), ("standard", "iso-8980-1")],
        },
        // The test-only toy: one folder and one registry line reach every front end.
        Asked {
            kind: "toy",
            scene: "door-mirror",
            options: &[("height", "1"), ("least_share", "0.5")],
        },
    ];
    let dir = tempfile::tempdir().unwrap();
    for (k, asked) in cases.iter().enumerate() {
        let command_json = dir.path().join(format!("command-{k}.json"));
        let out = asked.command(&command_json).output().unwrap();
        assert!(
            out.status.success(),
            "{}: {}",
            asked.kind,
            String::from_utf8_lossy(&out.stderr)
        );
        let script_json = dir.path().join(format!("script-{k}.json"));
        let script = dir.path().join(format!("script-{k}.toml"));
        std::fs::write(
            &script,
            format!(
                "[[step]]\n{}\n[[step]]\nanalysis_json = {:?}\n",
                asked.script_step(),
                script_json.display().to_string()
            ),
        )
        .unwrap();
        let mut view = viewer(test).unwrap();
        view.arg(asked.scene())
            .args(["--size", "64x48", "-m", "envmap", "--script"])
            .arg(&script);
        run_ok(view);
        let from_command = std::fs::read_to_string(&command_json).unwrap();
        let from_script = std::fs::read_to_string(&script_json).unwrap();
        let from_library = asked.library();
        let value: serde_json::Value = serde_json::from_str(&from_command).unwrap();
        eprintln!(
            "{}: verdict {} from the command, the script and the library",
            asked.kind,
            value["regulation"]["verdict"]
                .as_str()
                .or(value["verdict"]["verdict"].as_str())
                .or(value["verdict"].as_str())
                .unwrap_or("none (figures only)")
        );
        assert_eq!(
            from_command, from_script,
            "{}: command and script",
            asked.kind
        );
        assert_eq!(
            from_command, from_library,
            "{}: command and library",
            asked.kind
        );
    }
}

/// The toy analysis's options reach the command's help with no code of its own there.
#[test]
fn the_toy_analysis_s_options_are_in_the_command_s_help() {
    let out = specula()
        .args(["analyze", "toy", "--help"])
        .output()
        .unwrap();
    let help = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success());
    for wanted in [
        "--height <VALUE>",
        "the height the eye points must lie above [unit: m]",
        "--least-share <VALUE>",
        "[default: 1]",
        "--eyebox <W,H,NX,NY>",
    ] {
        assert!(help.contains(wanted), "{wanted:?} in\n{help}");
    }
}

/// The exact colour `rgb` in `shot`, counted in the columns `x0..x1`.
fn count_colour(shot: &image::RgbImage, rgb: [u8; 3], columns: std::ops::Range<u32>) -> usize {
    shot.enumerate_pixels()
        .filter(|(x, _, p)| columns.contains(x) && p.0 == rgb)
        .count()
}

/// At 1280 × 800 with the panel docked, an R46 verdict: the panel's verdict (its fail colour)
/// is inside the window, the eye points it names are the JSON's, the overlay's legend shows
/// each of its colours, and a window screenshot taken right after the mirror turns equals one
/// taken after it settled.
#[test]
fn the_panel_shows_the_verdict_its_eye_points_and_the_overlay_s_legend() {
    let test = "the_panel_shows_the_verdict_its_eye_points_and_the_overlay_s_legend";
    let Some(mut view) = viewer_on(test, "1280x800x24") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name).display().to_string();
    let script = dir.path().join("panel.toml");
    std::fs::write(
        &script,
        format!(
            r#"
[[step]]
method = "reference"
[[step]]
analysis = {{ kind = "mirror-view", mirror = "door mirror", regulation = "r46-iii", forward = [0, 0, -1], r_point = [-0.37, 0.55, 0], outermost = [-0.95, 0.6, 1.5], vehicle = ["car body", "A-pillar"], tolerance = 0.02, tolerance_deg = 0.1 }}
[[step]]
analysis_json = "{json}"
[[step]]
camera = "analysis"
[[step]]
panel = true
[[step]]
window_screenshot = "{first}"
[[step]]
rotate = {{ object = "door mirror", axis = [0, 1, 0], degrees = 3 }}
[[step]]
window_screenshot = "{right_after}"
[[step]]
frames = 20
[[step]]
window_screenshot = "{settled}"
"#,
            json = path("r46.json"),
            first = path("first.png"),
            right_after = path("right-after.png"),
            settled = path("settled.png"),
        ),
    )
    .unwrap();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/car-door-mirror.toml");
    view.arg(&scene)
        .args(["--size", "1280x800", "--script"])
        .arg(&script);
    let log = run_ok(view);

    // The eye points the panel names are the JSON's.
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path("r46.json")).unwrap()).unwrap();
    let eyes: Vec<String> = report["eyes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| {
            let p: Vec<f64> = e["position"]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_f64().unwrap())
                .collect();
            format!("({:.3}, {:.3}, {:.3})", p[0], p[1], p[2])
        })
        .collect();
    let shown = format!("eye points (r_point): {}", eyes.join(", "));
    assert!(log.contains(&shown), "{shown:?} in\n{log}");
    assert_eq!(report["regulation"]["verdict"], "fail");

    let first = image::open(path("first.png")).unwrap().to_rgb8();
    assert_eq!(first.dimensions(), (1280, 800));
    // The panel is the window's left part: the verdict's fail colour (egui's light red) in it.
    let verdict = count_colour(&first, [255, 128, 128], 0..400);
    assert!(
        verdict > 50,
        "{verdict} pixels of the verdict's colour in the panel"
    );
    // The legend's swatches, each at full colour.
    for (name, rgb) in [
        ("seen", [23, 190, 207]),
        ("region seen", [44, 190, 44]),
        ("blind", [214, 39, 40]),
    ] {
        let n = count_colour(&first, rgb, 0..1280);
        assert!(n >= 100, "the legend's {name} swatch: {n} pixels");
    }
    // Right after a change, the window shows the settled result.
    let (right_after, settled) = (path("right-after.png"), path("settled.png"));
    let d = difference(Path::new(&right_after), Path::new(&settled));
    assert_eq!(
        d.differing_pixels, 0,
        "right after the turn and settled differ"
    );
    assert_ne!(
        difference(Path::new(&path("first.png")), Path::new(&settled)).differing_pixels,
        0,
        "the turn changes the window"
    );
}

/// `view --material` gives the scene opened the materials `render --material` gives it: the
/// screenshot is the renderer's image of the ball made a mirror, not of the plain file; an
/// object the scene lacks fails the script naming the scene's objects.
#[test]
fn view_material_gives_the_scene_the_renderers_materials() {
    let Some(mut view) = viewer("view --material") else {
        return;
    };
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("bare.obj");
    // A floor and a ball (an octahedron), with no materials.
    std::fs::write(
        &obj,
        "o floor\nv -2 0 -2\nv 2 0 -2\nv 2 0 2\nv -2 0 2\nf 1 3 2\nf 1 4 3\n\
         o ball\nv 0 0 0\nv 0 2 0\nv 1 1 0\nv -1 1 0\nv 0 1 1\nv 0 1 -1\n\
         f 5 7 9\nf 5 9 8\nf 5 8 10\nf 5 10 7\nf 6 9 7\nf 6 8 9\nf 6 10 8\nf 6 7 10\n",
    )
    .unwrap();
    let shot = dir.path().join("view.png");
    let script = dir.path().join("shot.toml");
    std::fs::write(
        &script,
        format!(
            "[[step]]\nframes = 2\n[[step]]\nscreenshot = \"{}\"\n",
            shot.display()
        ),
    )
    .unwrap();
    let size = ["--size", "64x48", "-m", "envmap", "--script"];
    view.arg(&obj)
        .args(["--material", "ball=mirror"])
        .args(size)
        .arg(&script);
    run_ok(view);
    let (mirror, plain) = (dir.path().join("mirror.png"), dir.path().join("plain.png"));
    for (out, materials) in [(&mirror, &["--material", "ball=mirror"][..]), (&plain, &[])] {
        let mut render = specula();
        render
            .arg("render")
            .arg(&obj)
            .args(materials)
            .args(["-m", "envmap", "-W", "64", "-H", "48", "-o"])
            .arg(out)
            .env("NODEVICE_SELECT", "1");
        run_ok(render);
    }
    assert_eq!(difference(&mirror, &shot).differing_pixels, 0);
    assert!(difference(&plain, &shot).differing_pixels > 50);

    let mut unknown = viewer("view --material").unwrap();
    unknown
        .arg(&obj)
        .args(["--material", "bal=mirror"])
        .args(size)
        .arg(&script);
    let out = unknown.output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        stderr.contains("no object 'bal' to make mirror; the scene's objects are: 'floor', 'ball'"),
        "{stderr}"
    );
}
