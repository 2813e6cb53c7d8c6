//! `specula analyze` end to end: the JSON against its schema, the ocular points, and bad input.

use std::process::Command;

fn specula() -> Command {
    Command::new(env!("CARGO_BIN_EXE_specula"))
}

fn assert_matches_schema(json: &serde_json::Value, schema: &str) {
    let schema: serde_json::Value = serde_json::from_str(schema).unwrap();
    let validator = jsonschema::validator_for(&schema).unwrap();
    let errors: Vec<String> = validator
        .iter_errors(json)
        .map(|e| format!("{e} at {}", e.instance_path()))
        .collect();
    assert!(errors.is_empty(), "{errors:?}");
}

/// Runs `specula COMMAND... ARGS` for each case: it must fail, without a panic, and say
/// `expected`.
fn assert_each_fails_naming(command: &[&str], cases: &[(Vec<&str>, &str)]) {
    for (args, expected) in cases {
        let out = specula().args(command).args(args).output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(!stderr.contains("panicked"), "{args:?} panicked: {stderr}");
        assert!(
            stderr.contains(expected),
            "{args:?}: {stderr:?} should mention {expected:?}"
        );
    }
}

/// The report folder's report.json is `--json`'s document.
fn assert_report_json_is(report: &std::path::Path, json: &serde_json::Value) {
    let text = std::fs::read_to_string(report.join("report.json")).unwrap();
    let same: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert!(
        &same == json,
        "{}/report.json is not --json's document",
        report.display()
    );
}

#[test]
fn mirror_view_from_the_ocular_points_writes_json_that_matches_the_schema() {
    let dir = tempfile::tempdir().unwrap();
    let out = specula()
        .current_dir(dir.path())
        .args([
            "analyze",
            "mirror-view",
            "door-mirror",
            "--mirror",
            "door mirror",
            "--ocular",
            "--region",
            "-4,2,4,30",
            // 2 %: converges within the ray budget at both eye points (0.5 % does at one).
            "--tolerance",
            "0.02",
            "--json",
            "view.json",
            "--report",
            "report",
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let text = std::fs::read_to_string(dir.path().join("view.json")).unwrap();
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_matches_schema(
        &json,
        include_str!("../../../docs/analyze-mirror-view.schema.json"),
    );
    let eyes = json["eyes"].as_array().unwrap();
    assert_eq!(eyes.len(), 2);
    // The report folder: the same JSON, each plot as PNG and SVG, the page linking them.
    let report = dir.path().join("report");
    let same: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(report.join("report.json")).unwrap())
            .unwrap();
    assert_eq!(same, json);
    for plot in ["ground", "mirror"] {
        let png = image::open(report.join(format!("{plot}.png"))).unwrap();
        assert!(png.width() >= 16 && png.height() >= 16);
        let svg = std::fs::read_to_string(report.join(format!("{plot}.svg"))).unwrap();
        assert!(svg.starts_with("<svg") && svg.contains("data:image/png;base64,"));
    }
    let html = std::fs::read_to_string(report.join("report.html")).unwrap();
    assert!(
        html.contains("ground.svg")
            && html.contains("mirror.svg")
            && html.contains("all eye points")
    );
    let x = |k: usize, i: usize| eyes[k]["position"][i].as_f64().unwrap();
    let apart = ((x(0, 0) - x(1, 0)).powi(2) + (x(0, 2) - x(1, 2)).powi(2)).sqrt();
    assert!(
        (apart - 0.065).abs() < 1e-5,
        "ocular points {apart} m apart"
    );
    // Ambinocular: the union is at least each eye's, the intersection at most.
    let figure = |v: &serde_json::Value, name: &str| v[name].as_f64().unwrap();
    for eye in eyes {
        assert!(eye["converged"].as_bool().unwrap());
        for name in ["horizontal_deg", "solid_angle_sr", "ground_area_m2"] {
            assert!(
                figure(&json, name) >= figure(eye, name) * 0.999,
                "{name}: all {} < one eye {}",
                json[name],
                eye[name]
            );
        }
        assert!(figure(&json, "region_seen_by_any") >= figure(eye, "region_seen_by_any"));
        assert!(figure(&json, "region_seen_by_all") <= figure(eye, "region_seen_by_any"));
    }
}

#[test]
fn bad_mirror_view_input_is_a_clear_error() {
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["--mirror", "mirrr"],
            "unknown --mirror 'mirrr'; the scene's objects are: door mirror",
        ),
        (
            vec!["--mirror", "ground"],
            "--mirror 'ground' is diffuse, not a mirror",
        ),
        (
            vec!["--mirror", "door mirror", "--eyebox", "0.3,0.1,0,3"],
            "at least one point",
        ),
        (
            vec!["--mirror", "door mirror", "--region", "1,2,1,5"],
            "has no area",
        ),
        (vec!["--mirror", "door mirror", "--range", "0"], "--range"),
        (
            vec!["--mirror", "building"],
            "--mirror 'building' names 20 objects of the scene",
        ),
        (
            vec!["--mirror", "door mirror", "--tolerance", "0"],
            "--tolerance: 0: a tolerance must be a positive number",
        ),
        (vec!["--mirror", "door mirror", "--eye", "1,2"], "X,Y,Z"),
        (
            vec!["--mirror", "door mirror", "--forward", "0,1,0"],
            "no horizontal part",
        ),
    ];
    assert_each_fails_naming(&["analyze", "mirror-view", "door-mirror"], &cases);
}

/// The car example's options: R46 class III from the R point, the body's parts named.
const CAR: &[&str] = &[
    "analyze",
    "mirror-view",
    "../../scenes/car-door-mirror.toml",
    "--mirror",
    "door mirror",
    "--regulation",
    "r46-iii",
    "--forward",
    "0,0,-1",
    "--r-point",
    "-0.37,0.55,0",
    "--outermost",
    "-0.95,0.6,1.5",
    "--vehicle",
    "car body",
    "--vehicle",
    "roof",
    "--vehicle",
    "A-pillar",
    "--vehicle",
    "door handle",
    "--vehicle",
    "rear wing",
    "--vehicle",
    "mirror housing",
];

#[test]
fn the_car_example_s_a_pillar_takes_a_share_of_the_fields_and_the_allowance_decides() {
    let dir = tempfile::tempdir().unwrap();
    let json_path = dir.path().join("car.json");
    let report = dir.path().join("car-report");
    let out = specula()
        .args(CAR)
        .arg("--json")
        .arg(&json_path)
        .arg("--report")
        .arg(&report)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json_path).unwrap()).unwrap();
    assert_matches_schema(
        &json,
        include_str!("../../../docs/analyze-mirror-view.schema.json"),
    );
    assert_eq!(json["surface"], "exact");
    assert_report_json_is(&report, &json);
    // The page leads with the verdict and names each field with its own.
    let html = std::fs::read_to_string(report.join("report.html")).unwrap();
    let banner = html
        .find("<div class=\"verdict fail\"><b>FAIL</b>")
        .unwrap();
    assert!(banner < html.find("What the mirror shows").unwrap());
    for name in [
        "4 m wide from 20 m behind to the horizon",
        "1 m wide from 4 m behind to the horizon",
    ] {
        assert!(html.contains(name), "{name}");
    }
    assert!(html.contains("<h2>Why</h2>") && html.contains("not less than the 10.00 %"));
    // The terminal's first line is the verdict.
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.lines().next().unwrap().ends_with("FAILS"),
        "{stdout}"
    );
    let verdict = &json["regulation"];
    let fields = verdict["fields"].as_array().unwrap();
    assert_eq!(fields.len(), 2);
    let number = |f: &serde_json::Value, k: &str| f[k].as_f64().unwrap();
    for f in fields {
        let (seen, hidden, u) = (
            number(f, "seen_share"),
            number(f, "hidden_by_vehicle_share"),
            number(f, "seen_share_uncertainty"),
        );
        // What the pillar hides, the mirror's edge does not: together they are the field.
        assert!(hidden > 0.01, "{f}");
        assert!((seen + hidden - 1.0).abs() <= u + 1e-3, "{f}");
        // The allowance (71/127/EEC Annex III): under 10 % excused, over it not.
        let excused = hidden < 0.10;
        assert_eq!(f["passed"].as_bool().unwrap(), excused, "{f}");
        assert_eq!(f["horizon_seen"], true);
    }
    // One field each way, so both branches of the allowance are shown.
    let excused: Vec<bool> = fields
        .iter()
        .map(|f| number(f, "hidden_by_vehicle_share") < 0.10)
        .collect();
    assert!(
        excused.contains(&true) && excused.contains(&false),
        "{excused:?}"
    );
    assert_eq!(verdict["passed"], false);
    // r = 1.6 m by construction (the control points' parabola): the exact patch says so.
    let check = |name: &str| {
        verdict["mirror_checks"]
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c["name"] == name)
            .unwrap_or_else(|| panic!("no check '{name}' in {verdict}"))
            .clone()
    };
    let radius = check("radius of curvature r");
    assert_eq!(radius["passed"], true);
    assert_eq!(radius["verdict"], "pass");
    assert_eq!(radius["unit"], "m");
    assert!(
        radius["measured"].as_str().unwrap().contains("1600 mm"),
        "{radius}"
    );
}

#[test]
fn the_door_mirror_s_pose_search_finds_poses_whose_fields_pass() {
    let out = specula()
        .args([
            "analyze",
            "mirror-view",
            "door-mirror",
            "--mirror",
            "door mirror",
            "--regulation",
            "r46-iii",
            "--forward",
            "0,0,-1",
            "--r-point",
            "0.28,-0.575,0.75",
            "--outermost",
            "0.08,-0.5,0.3",
            "--adjust",
            "0,0,-0.03",
            "--adjust-step",
            "10",
            "--json",
            "/dev/stdout",
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let text = String::from_utf8_lossy(&out.stdout);
    let json: serde_json::Value = serde_json::from_str(&text[text.find('{').unwrap()..]).unwrap();
    let a = &json["adjustment"];
    assert_eq!(a["poses"].as_array().unwrap().len(), 25);
    let passing = a["passing_poses"].as_u64().unwrap();
    assert!(passing > 0 && passing < 25, "{passing}");
    let best = &a["best"];
    assert_eq!(best["fields_passed"], true);
    for (key, range) in [
        ("yaw_deg", "passing_yaw_deg"),
        ("pitch_deg", "passing_pitch_deg"),
    ] {
        let v = best[key].as_f64().unwrap();
        let r = a[range].as_array().unwrap();
        assert!(r[0].as_f64().unwrap() <= v && v <= r[1].as_f64().unwrap());
    }
    // Its radius (about 0.4 m) is below class III's 1.2 m: no pose makes the mirror pass.
    assert_eq!(json["regulation"]["passed"], false);
    assert_eq!(json["regulation"]["verdict"], "fail");
    let radius = json["regulation"]["mirror_checks"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["name"] == "radius of curvature r")
        .unwrap();
    assert_eq!(radius["verdict"], "fail", "{radius}");
    // Every pose counted as passing was confirmed at the command's tolerances.
    for pose in a["poses"].as_array().unwrap() {
        if pose["fields_passed"] == true {
            assert_eq!(pose["confirmed_verdict"], "pass", "{pose}");
        }
    }
}

#[test]
fn bad_regulation_input_is_a_clear_error() {
    let base = [
        "--mirror",
        "door mirror",
        "--forward",
        "0,0,-1",
        "--regulation",
    ];
    let with = |rest: &[&'static str]| {
        let mut v: Vec<&str> = base.to_vec();
        v.extend_from_slice(rest);
        v
    };
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            with(&["r46-vii", "--r-point", "0.28,-0.575,0.75"]),
            // The declaration's choices, checked by the command line before anything runs.
            "invalid value 'r46-vii' for '--regulation <VALUE>'\n  [possible values: r46-i, r46-ii, r46-iii, r46-iv, r46-v, fmvss111, fmvss111-convex]",
        ),
        // A rule with no field has no pose to search for.
        (
            with(&[
                "fmvss111-convex",
                "--eye",
                "0.28,0.06,0.75",
                "--adjust",
                "0,0,-0.03",
            ]),
            "--adjust: fmvss111-convex prescribes no field",
        ),
        // Eyes behind the mirror (it faces +Z).
        (
            with(&[
                "r46-iii",
                "--r-point",
                "0.2,-0.6,-0.5",
                "--outermost",
                "0.08,0,0",
            ]),
            "--r-point: it puts an eye point at",
        ),
        // ... and inside it.
        (
            with(&[
                "r46-iii",
                "--r-point",
                "0.0,-0.635,0.0",
                "--outermost",
                "0.08,0,0",
            ]),
            "inside the mirror's bounds",
        ),
        (
            with(&[
                "r46-iii",
                "--eyellipse",
                "0.28,0.06,0.75,0.1,0,0.05",
                "--outermost",
                "0.08,0,0",
            ]),
            "--eyellipse: semi-axes",
        ),
        // The mirror is on the left: an outermost point to the right of the eyes is wrong.
        (
            with(&[
                "r46-iii",
                "--r-point",
                "0.28,-0.575,0.75",
                "--outermost",
                "0.6,0,0",
            ]),
            "--outermost: [0.6, 0, 0] lies",
        ),
        (
            with(&[
                "r46-iii",
                "--r-point",
                "0.28,-0.575,0.75",
                "--outermost",
                "0.08,0,0",
                "--adjust",
                "3,0,0",
            ]),
            "--adjust: the pivot [3, 0, 0] is",
        ),
        (
            with(&["r46-iii", "--r-point", "0.28,-0.575,0.75"]),
            "--outermost: the field '4 m wide from 20 m behind to the horizon'",
        ),
        (
            with(&["fmvss111", "--r-point", "0.28,-0.575,0.75"]),
            "--r-point: fmvss111 judges from the driver's eyes",
        ),
        (
            with(&[
                "r46-iii",
                "--r-point",
                "0.28,-0.575,0.75",
                "--vehicle",
                "door mirror",
            ]),
            "--vehicle: 'door mirror' is the mirror",
        ),
    ];
    assert_each_fails_naming(&["analyze", "mirror-view", "door-mirror"], &cases);
}

#[test]
fn glare_over_an_eyebox_writes_json_that_matches_the_schema() {
    let dir = tempfile::tempdir().unwrap();
    let out = specula()
        .current_dir(dir.path())
        .args([
            "analyze",
            "glare",
            "truck-cover",
            "--surface",
            "cover glass",
            "--source",
            "side window",
            "--eyebox",
            "0.3,0.15,3,2",
            "--size",
            "96x72",
            "--json",
            "glare.json",
            "--report",
            "report",
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("glare.json")).unwrap())
            .unwrap();
    assert_matches_schema(
        &json,
        include_str!("../../../docs/analyze-glare.schema.json"),
    );
    let eyes = json["eyes"].as_array().unwrap();
    assert_eq!(eyes.len(), 6);
    let report = dir.path().join("report");
    assert_report_json_is(&report, &json);
    for plot in ["eyebox", "worst"] {
        let png = image::open(report.join(format!("{plot}.png"))).unwrap();
        assert!(png.width() >= 8 && png.height() >= 8);
        let svg = std::fs::read_to_string(report.join(format!("{plot}.svg"))).unwrap();
        assert!(svg.starts_with("<svg") && svg.contains("data:image/png;base64,"));
    }
    let html = std::fs::read_to_string(report.join("report.html")).unwrap();
    assert!(html.contains("eyebox.svg") && html.contains("worst.svg"));
    let with = eyes.iter().filter(|e| e["glare"] == true).count();
    assert!((json["share_with_glare"].as_f64().unwrap() - with as f64 / 6.0).abs() < 1e-12);
}

#[test]
fn a_sun_sweep_over_a_solar_day_writes_json_that_matches_the_schema_and_its_plots() {
    let dir = tempfile::tempdir().unwrap();
    let out = specula()
        .current_dir(dir.path())
        .args([
            "analyze",
            "glare",
            "truck-cover",
            "--surface",
            "cover glass",
            "--sun-sweep",
            "-180,180,5,65,20",
            "--latitude",
            "48",
            "--heading",
            "270",
            "--date",
            "2026-06-21",
            "--time-step",
            "30",
            "--display",
            "dial",
            "--symbol-luminance",
            "300",
            "--background-luminance",
            "10",
            "--min-contrast",
            "3",
            "--eyebox",
            "0.2,0.1,2,1",
            "--size",
            "64x48",
            "--json",
            "glare.json",
            "--report",
            "report",
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("glare.json")).unwrap())
            .unwrap();
    assert_matches_schema(
        &json,
        include_str!("../../../docs/analyze-glare.schema.json"),
    );
    let sweep = &json["sweep"];
    // 19 azimuths × 4 elevations; the day every half hour while the sun is up.
    assert_eq!(sweep["positions"].as_array().unwrap().len(), 19 * 4);
    let times = sweep["day"]["times"].as_array().unwrap();
    assert!(times.len() > 20 && times.len() < 40, "{}", times.len());
    let report = dir.path().join("report");
    for plot in ["eyebox", "worst", "sweep", "polar"] {
        let png = image::open(report.join(format!("{plot}.png"))).unwrap();
        assert!(png.width() >= 8 && png.height() >= 8);
    }
    let html = std::fs::read_to_string(report.join("report.html")).unwrap();
    assert!(html.contains("sweep.svg") && html.contains("polar.svg"));
    assert!(html.contains("apparent solar time"));
}

#[test]
fn bad_glare_input_is_a_clear_error() {
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["--surface", "cover", "--source", "side window"],
            "unknown --surface 'cover'; the scene's objects are:",
        ),
        (
            vec!["--surface", "cover glass", "--source", "sun"],
            "unknown --source 'sun'",
        ),
        (
            vec!["--surface", "side window", "--source", "cover glass"],
            "--surface 'side window' is unlit, not a mirror or a glass",
        ),
        (
            vec![
                "--surface",
                "cover glass",
                "--source",
                "side window",
                "--eyebox",
                "0.3,0.1,3,0",
            ],
            "at least one point",
        ),
        (
            vec![
                "--surface",
                "cover glass",
                "--source",
                "side window",
                "--threshold=-1",
            ],
            "--threshold",
        ),
        (
            vec!["--surface", "cover glass", "--sun", "120,-5"],
            "--sun: elevation -5°: the sun is below the horizon",
        ),
        (
            vec!["--surface", "cover glass", "--sun-sweep", "0,90,10,40,0"],
            "--sun-sweep: step 0°: a sweep needs a positive step",
        ),
        (
            vec![
                "--surface",
                "cover glass",
                "--source",
                "side window",
                "--source-luminance=-20",
            ],
            "--source-luminance: -20 cd/m²: a luminance must be a finite number above 0",
        ),
        (
            vec![
                "--surface",
                "cover glass",
                "--sun",
                "180,10",
                "--display",
                "dial",
                "--symbol-luminance=-300",
                "--background-luminance",
                "10",
                "--min-contrast",
                "3",
            ],
            "--symbol-luminance: -300 cd/m²",
        ),
        (
            vec![
                "--surface",
                "cover glass",
                "--sun",
                "180,10",
                "--display",
                "side window",
                "--symbol-luminance",
                "300",
                "--background-luminance",
                "10",
                "--min-contrast",
                "3",
            ],
            "--display: 'side window' is not behind 'cover glass'",
        ),
        (
            vec![
                "--surface",
                "cover glass",
                "--sun",
                "180,10",
                "--display",
                "dial",
            ],
            "--symbol-luminance",
        ),
    ];
    assert_each_fails_naming(&["analyze", "glare", "truck-cover"], &cases);
}

#[test]
fn lens_writes_json_that_matches_the_schema_and_a_report() {
    let dir = tempfile::tempdir().unwrap();
    let out = specula()
        .current_dir(dir.path())
        .args([
            "analyze",
            "lens",
            "spectacle-lens",
            "--lens",
            "spectacle lens",
            "--gaze",
            "30,20,5",
            "--eye",
            "left",
            "--json",
            "lens.json",
            "--report",
            "report",
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("0, 0") && stdout.contains("-3.018"),
        "{stdout}"
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("lens.json")).unwrap())
            .unwrap();
    assert_matches_schema(
        &json,
        include_str!("../../../docs/analyze-lens.schema.json"),
    );
    assert_eq!(json["grid"].as_array().unwrap().len(), 13 * 9);
    assert_eq!(json["eye"], "left");
    assert_report_json_is(&dir.path().join("report"), &json);
    // Looking out (to the wearer's left, the left eye's temple) through a minus lens: base out.
    let out_cell = json["grid"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["gaze_deg"][0] == -20.0 && c["gaze_deg"][1] == 0.0)
        .unwrap();
    assert!(out_cell["prism_d"][0].as_f64().unwrap() > 1.0, "{out_cell}");
    for name in [
        "report.html",
        "mean-power.png",
        "mean-power.svg",
        "cylinder.svg",
        "prism.svg",
        "lateral-colour.svg",
        "distortion.png",
        "distortion.svg",
    ] {
        assert!(dir.path().join("report").join(name).is_file(), "{name}");
    }
}

#[test]
fn bad_lens_input_is_a_clear_error() {
    let dir = tempfile::tempdir().unwrap();
    let impossible = dir.path().join("impossible.toml");
    std::fs::write(
        &impossible,
        "[[objects]]\nname = \"lens\"\nshape = { type = \"spectacle-lens\", sphere = 10.0, \
         index = 1.5, abbe = 58, center_thickness = 0.002, base_curve = 12.0, diameter = 0.07 }\n",
    )
    .unwrap();
    let cases = [
        (
            vec!["spectacle-lens", "--lens", "monocle"],
            "unknown --lens 'monocle'; the scene's objects are: (its lenses) spectacle lens",
        ),
        (
            vec!["spectacle-lens", "--lens", "colour chart"],
            "--lens 'colour chart' is unlit, not a refractor",
        ),
        (
            vec![
                "spectacle-lens",
                "--lens",
                "spectacle lens",
                "--rotation-centre",
                "0,0,-0.066",
            ],
            "lies inside 'spectacle lens'",
        ),
        (
            vec![
                "spectacle-lens",
                "--lens",
                "spectacle lens",
                "--rotation-centre",
                "0,0,-0.5",
            ],
            "does not see through",
        ),
        (
            vec![
                "spectacle-lens",
                "--lens",
                "spectacle lens",
                "--gaze",
                "30,30,0",
            ],
            "--gaze",
        ),
        (
            vec![
                "spectacle-lens",
                "--lens",
                "spectacle lens",
                "--object-distance=-0.4",
            ],
            "--object-distance",
        ),
        (
            vec![impossible.to_str().unwrap(), "--lens", "lens"],
            "edge would be",
        ),
        (
            vec!["door-mirror", "--lens", "door mirror"],
            "not a refractor",
        ),
    ];
    assert_each_fails_naming(&["analyze", "lens"], &cases);
}

#[test]
fn the_example_spectacles_give_back_their_prescription_at_the_centre() {
    let scene =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/spectacles.toml");
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("lens.json");
    let out = specula()
        .args(["analyze", "lens"])
        .arg(&scene)
        .args(["--lens", "right lens", "--gaze", "10,10,10", "--json"])
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
    let centre = &report["centre"];
    let figure = |name: &str| centre[name].as_f64().unwrap();
    assert_eq!(report["prescription"]["axis_deg"], 30.0);
    // Measured 2026-12-02: −3.0001 / −1.0000 × 30.00.
    assert!((figure("sphere_d") + 3.0).abs() < 3e-4, "{centre}");
    assert!((figure("cylinder_d") + 1.0).abs() < 3e-4, "{centre}");
    assert!((figure("axis_deg") - 30.0).abs() < 0.05, "{centre}");
    assert!(figure("unwanted_cylinder_d") < 3e-4, "{centre}");
}

fn spectacles_wrap() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/spectacles-wrap.toml")
}

#[test]
fn a_wrapped_lens_is_judged_against_its_compensated_prescription() {
    // −4.00 / −1.00 × 90 worn at 10° pantoscopic tilt and 5° wrap: the lens made to the
    // prescription passes as ordered, but not against the compensated prescription a lab
    // should have made for this frame.
    let dir = tempfile::tempdir().unwrap();
    let verdict = |extra: &[&str]| {
        let json = dir.path().join("lens.json");
        let out = specula()
            .args(["analyze", "lens"])
            .arg(spectacles_wrap())
            .args([
                "--lens",
                "right lens",
                "--gaze",
                "0,0,1",
                "--pantoscopic",
                "10",
            ])
            .args(["--wrap", "5", "--focimeter", "--json"])
            .arg(&json)
            .args(extra)
            .output()
            .unwrap();
        let stdout = String::from_utf8_lossy(&out.stdout).to_string();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(
            stdout.contains("focimeter at the distance reference point"),
            "{stdout}"
        );
        let report: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        report
    };
    let ordered = verdict(&["--standard", "ansi-z80.1"]);
    assert_eq!(ordered["schema_version"], 3);
    assert_eq!(ordered["verdict"]["edition"], "ANSI Z80.1-2015");
    assert_eq!(ordered["verdict"]["passed"], true);
    let checks = ordered["verdict"]["checks"].as_array().unwrap();
    let quantities: Vec<&str> = checks
        .iter()
        .map(|c| c["quantity"].as_str().unwrap())
        .collect();
    assert_eq!(quantities, ["sphere", "cylinder", "axis", "prism"]);
    let reading = &ordered["focimeter"][0];
    // Measured 2026-12-04: −4.0000 / −1.0000 × 90.00 (the exact surfaces).
    assert!(
        (reading["sphere_d"].as_f64().unwrap() + 4.0).abs() < 1e-3,
        "{reading}"
    );
    assert!(
        (reading["cylinder_d"].as_f64().unwrap() + 1.0).abs() < 1e-3,
        "{reading}"
    );
    let compensated = verdict(&["--standard", "iso-8980-1", "--compensate"]);
    assert_matches_schema(
        &compensated,
        include_str!("../../../docs/analyze-lens.schema.json"),
    );
    assert_eq!(compensated["verdict"]["passed"], false);
    let ordered_sphere = compensated["compensated"]["ordered"]["sphere_d"]
        .as_f64()
        .unwrap();
    // Measured 2026-12-04: −3.827 / −1.080 × 86.0.
    assert!((ordered_sphere + 3.827).abs() < 0.002, "{ordered_sphere}");
    let failed: Vec<&serde_json::Value> = compensated["verdict"]["checks"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["passed"] == false)
        .collect();
    assert_eq!(failed.len(), 1, "{failed:?}");
    assert_eq!(failed[0]["quantity"], "sphere");
    assert!(failed[0]["margin"].as_f64().unwrap() < 0.0);
}

#[test]
fn bad_lens_options_are_refused_saying_why() {
    let refused = |extra: &[&str], expected: &[&str]| {
        let out = specula()
            .args(["analyze", "lens"])
            .arg(spectacles_wrap())
            .args(["--lens", "right lens", "--gaze", "0,0,1"])
            .args(extra)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr).to_string();
        assert!(!out.status.success(), "{extra:?} was accepted");
        for e in expected {
            assert!(stderr.contains(e), "{extra:?}: {stderr}");
        }
    };
    refused(
        &["--standard", "din-58208"],
        &[
            "invalid value 'din-58208' for '--standard <VALUE>'",
            "ansi-z80.1, iso-8980-1",
        ],
    );
    refused(&["--prescription=-2,-1"], &["needs its axis"]);
    refused(&["--prescription=-2,-1,90,2XX"], &["BO, BI, BU or BD"]);
    refused(&["--pantoscopic", "31"], &["--pantoscopic", "at most 30"]);
    refused(&["--wrap=-45"], &["--wrap", "at most 30"]);
    refused(
        &["--vertex-distance", "0"],
        &["--vertex-distance", "must be positive"],
    );
    refused(&["--near=-0.4"], &["--near", "in front of the eyes"]);
    refused(&["--near", "0.01"], &["--near", "at or behind the lens"]);
    refused(&["--add", "2"], &["an add without a progressive surface"]);
    refused(&["--lens-step", "0"], &["--lens-step", "at least 0.05 mm"]);
}

#[test]
fn a_progressive_lens_gets_its_add_corridor_zones_near_figures_and_verdict() {
    let dir = tempfile::tempdir().unwrap();
    let out = specula()
        .current_dir(dir.path())
        .args(["analyze", "lens"])
        .arg(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/progressive.toml"))
        .args(["--lens", "right lens", "--gaze", "20,30,5", "--near", "0.4"])
        .args([
            "--standard",
            "ansi-z80.1",
            "--json",
            "lens.json",
            "--report",
            "report",
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let stdout = String::from_utf8_lossy(&out.stdout);
    for line in [
        "progressive: add",
        "near point 0.400 m away",
        "clear where",
        "PASS",
    ] {
        assert!(stdout.contains(line), "{line}: {stdout}");
    }
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("lens.json")).unwrap())
            .unwrap();
    assert_matches_schema(
        &json,
        include_str!("../../../docs/analyze-lens.schema.json"),
    );
    let add = json["progressive"]["add_d"].as_f64().unwrap();
    // Measured 2026-12-04: 1.9759 D on the front.
    assert!((add - 1.9759).abs() < 1e-3, "{add}");
    assert_eq!(json["progressive"]["measured_on"], "front");
    let quantities: Vec<&str> = json["verdict"]["checks"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c["quantity"].as_str().unwrap())
        .collect();
    assert_eq!(quantities, ["sphere", "cylinder", "prism", "add"]);
    assert!(json["near"]["inset_mm"].as_f64().unwrap() > 1.0);
    assert_eq!(json["clear_zones"].as_array().unwrap().len(), 3);
    for name in [
        "lens-mean-power.svg",
        "lens-cylinder.svg",
        "lens-mean-power.png",
    ] {
        assert!(dir.path().join("report").join(name).is_file(), "{name}");
    }
}

/// A simple car (a box) with a flat 250 × 130 mm mirror on its left, turned `yaw_deg` about
/// the vertical: 21.26° aims the mirror's view 5.5° outward from straight back, 2.5° down.
fn simple_car_with_a_flat_mirror(yaw_deg: f32) -> String {
    format!(
        r#"name = "simple car with a flat mirror"
[camera]
eye = [-3.0, 2.0, 3.0]
target = [-0.9, 0.9, -0.6]
[materials.mirror]
type = "mirror"
color = 0.9
[materials.paint]
type = "diffuse"
color = [0.6, 0.08, 0.06]
[[objects]]
name = "road"
material = "paint"
shape = {{ type = "plane", size = [60.0, 200.0] }}
[[objects]]
name = "car body"
material = "paint"
translate = [0.0, 0.625, 0.25]
shape = {{ type = "box", size = [1.8, 0.65, 4.5] }}
[[objects]]
name = "mirror"
material = "mirror"
translate = [-1.05, 1.0, -0.6]
rotate_deg = [84.93, {yaw_deg}, 0.0]
shape = {{ type = "plane", size = [0.25, 0.13] }}
"#
    )
}

/// A pair of flat mirrors on a simple car against FMVSS 111's driver's-side field, one aimed
/// to see it whole and one turned 3° too far out: each report's report.json says whether it
/// passed, and its page leads with PASS or FAIL and names the field.
#[test]
fn a_flat_mirror_that_passes_fmvss_111_and_one_that_fails_say_so_in_their_reports() {
    let dir = tempfile::tempdir().unwrap();
    for (yaw, passes) in [(21.26f32, true), (24.26, false)] {
        let scene = dir.path().join(format!("car-{yaw}.toml"));
        std::fs::write(&scene, simple_car_with_a_flat_mirror(yaw)).unwrap();
        let report = dir.path().join(format!("report-{yaw}"));
        let out = specula()
            .args(["analyze", "mirror-view"])
            .arg(&scene)
            .args(["--mirror", "mirror", "--regulation", "fmvss111"])
            .args(["--forward", "0,0,-1", "--eye", "-0.37,1.185,0"])
            .args(["--outermost", "-0.9,0.6,0", "--vehicle", "car body"])
            .args(["--tolerance", "0.001", "--report"])
            .arg(&report)
            .output()
            .unwrap();
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(report.join("report.json")).unwrap())
                .unwrap();
        let regulation = &json["regulation"];
        assert_eq!(regulation["passed"], passes, "yaw {yaw}: {stdout}");
        let word = if passes { "PASS" } else { "FAIL" };
        assert_eq!(regulation["verdict"], word.to_lowercase());
        let html = std::fs::read_to_string(report.join("report.html")).unwrap();
        assert!(
            html.contains(&format!(
                "<div class=\"verdict {}\"><b>{word}</b>",
                word.to_lowercase()
            )),
            "yaw {yaw}"
        );
        assert!(html.contains("2.4 m wide from 10.7 m behind the eyes to the horizon"));
        assert!(stdout
            .lines()
            .next()
            .unwrap()
            .ends_with(if passes { "PASSES" } else { "FAILS" }));
    }
}

/// `analyze KIND` over several scenes: a row per scene and check in `--csv`, each check's value
/// the scene's own run's (its `--json` alone), a report folder per scene, one summary table;
/// a scene that cannot be analysed is an error row and a failing exit status, the others still
/// run.
#[test]
fn several_scenes_give_a_csv_row_per_scene_and_check_and_a_report_each() {
    let dir = tempfile::tempdir().unwrap();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    // A third scene: the built-in door mirror turned 5° about its centre.
    let turned = dir.path().join("turned.toml");
    std::fs::write(
        &turned,
        "base = \"door-mirror\"\n[[move]]\nobject = \"door mirror\"\nrotate = { axis = [0, 1, 0], degrees = 5 }\n",
    )
    .unwrap();
    let scenes = [
        root.join("scenes/car-door-mirror.toml")
            .display()
            .to_string(),
        "door-mirror".to_string(),
        turned.display().to_string(),
    ];
    let options = [
        "--mirror",
        "door mirror",
        "--ocular",
        "--region",
        "1,2,5,20",
    ];
    let (csv, report) = (dir.path().join("out.csv"), dir.path().join("reports"));
    let out = specula()
        .args(["analyze", "mirror-view"])
        .args(&scenes)
        .args(options)
        .arg("--csv")
        .arg(&csv)
        .arg("--report")
        .arg(&report)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        stdout.contains("scene") && stdout.contains("5 figures"),
        "{stdout}"
    );
    let text = std::fs::read_to_string(&csv).unwrap();
    let rows: Vec<Vec<&str>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    let checks = [
        ("horizontal extent", "horizontal_deg", 1.0),
        ("vertical extent", "vertical_deg", 1.0),
        ("solid angle", "solid_angle_sr", 1.0),
        ("ground area", "ground_area_m2", 1.0),
        ("region seen by any eye point", "region_seen_by_any", 100.0),
    ];
    assert_eq!(rows.len(), scenes.len() * checks.len(), "{text}");
    for (k, scene) in scenes.iter().enumerate() {
        let json = dir.path().join(format!("{k}.json"));
        let alone = specula()
            .args(["analyze", "mirror-view", scene])
            .args(options)
            .arg("--json")
            .arg(&json)
            .output()
            .unwrap();
        assert!(alone.status.success());
        let figures: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        for (row, (check, key, scale)) in rows[k * checks.len()..].iter().zip(checks) {
            assert_eq!(
                (row[0], row[1], row[2]),
                (scene.as_str(), "mirror-view", check)
            );
            let value: f64 = row[4].parse().unwrap();
            assert_eq!(
                value,
                figures[key].as_f64().unwrap() * scale,
                "{scene}: {check}"
            );
        }
        let folder = match k {
            0 => "car-door-mirror",
            1 => "door-mirror",
            _ => "turned",
        };
        assert!(report.join(folder).join("report.html").exists(), "{folder}");
    }
    // The turned mirror sees another field than the built-in one.
    assert_ne!(rows[5][4], rows[10][4]);

    // A scene without the mirror: an error row, the others run, the exit status fails.
    let out = specula()
        .args(["analyze", "mirror-view", "door-mirror", "truck-cover"])
        .args(options)
        .arg("--csv")
        .arg(&csv)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        stderr.contains("truck-cover") && stderr.contains("1 of 2 scenes"),
        "{stderr}"
    );
    let text = std::fs::read_to_string(&csv).unwrap();
    assert!(text.contains("truck-cover,mirror-view,,error"), "{text}");
    assert_eq!(
        text.lines()
            .filter(|l| l.starts_with("door-mirror,"))
            .count(),
        5
    );

    // Outputs that cannot be written are refused before anything runs.
    for output in [
        ["--csv", "/proc/nope/out.csv"],
        ["--json", "/proc/nope/out.json"],
        ["--report", "/proc/nope/report"],
    ] {
        let out = specula()
            .args(["analyze", "mirror-view", "door-mirror"])
            .args(options)
            .args(output)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && stderr.contains(output[1]),
            "{output:?}: {stderr}"
        );
        // Nothing was computed: no report's text was printed.
        assert!(
            out.stdout.is_empty(),
            "{output:?}: {}",
            String::from_utf8_lossy(&out.stdout)
        );
    }
}

/// An eye point that sees nothing of the mirror (here behind it) is a warning naming it, in
/// the terminal and the JSON, and the run's verdict is undecided rather than silent zeros.
#[test]
fn an_eye_point_that_sees_nothing_of_the_mirror_is_a_warning_and_undecided() {
    let dir = tempfile::tempdir().unwrap();
    let (json, csv) = (
        dir.path().join("behind.json"),
        dir.path().join("behind.csv"),
    );
    let out = specula()
        .args([
            "analyze",
            "mirror-view",
            "door-mirror",
            "--mirror",
            "door mirror",
        ])
        .args(["--eye", "0,0,-5", "--eye", "0,0,0.5", "--json"])
        .arg(&json)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        stdout.contains(
            "warning: eye point (0.000, 0.000, -5.000) sees nothing of the mirror 'door mirror'"
        ),
        "{stdout}"
    );
    assert!(
        !stdout.contains("(0.000, 0.000, 0.500) sees nothing"),
        "{stdout}"
    );
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_matches_schema(
        &report,
        include_str!("../../../docs/analyze-mirror-view.schema.json"),
    );
    let warnings = report["warnings"].as_array().unwrap();
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    // The run's verdict in the summary of several scenes.
    let out = specula()
        .args(["analyze", "mirror-view", "door-mirror", "door-mirror"])
        .args(["--mirror", "door mirror", "--eye", "0,0,-5", "--csv"])
        .arg(&csv)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout
            .lines()
            .any(|l| l.starts_with("door-mirror") && l.contains("undecided")),
        "{stdout}"
    );
}
