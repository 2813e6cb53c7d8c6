//! The one analysis interface: the registry, the declarations every front end is made from,
//! the docs' option tables made from them, and one run of each analysis through the trait
//! equal to the functions it wraps.

mod by_name;

use specula_analyze::analysis::{self, EyePoints, ANALYSES};
use specula_analyze::regulation::{REGULATIONS, REGULATION_NAMES};
use specula_params::ParamSet;
use specula_trace::SceneAccel;

#[test]
fn the_registry_lists_each_analysis_once_with_options_that_parse_their_defaults() {
    let names: Vec<&str> = ANALYSES.iter().map(|a| a.name).collect();
    assert_eq!(&names[..3], ["mirror-view", "glare", "lens"]);
    for info in ANALYSES {
        assert_eq!(names.iter().filter(|n| **n == info.name).count(), 1);
        let analysis = (info.create)();
        assert_eq!(analysis.info().name, info.name);
        let mut seen = Vec::new();
        for spec in info.all_options() {
            assert!(
                !seen.contains(&spec.name),
                "{}: {} twice",
                info.name,
                spec.name
            );
            seen.push(spec.name);
            assert!(!spec.doc.is_empty(), "{}.{}", info.name, spec.name);
            // The default, as text, is what the option holds by default.
            let held = analysis
                .options()
                .get(spec.name)
                .or_else(|| EyePoints::default().get(spec.name))
                .unwrap();
            if !spec.default.is_empty() && !spec.required {
                let parsed = spec.parse(info.name, spec.default).unwrap();
                assert_eq!(held, parsed.to_string(), "{}.{}", info.name, spec.name);
            }
        }
    }
    let table: Vec<&str> = REGULATIONS.iter().map(|r| r.name).collect();
    assert_eq!(REGULATION_NAMES, table.as_slice());
    let standards: Vec<&str> = specula_analyze::lens::standard::STANDARDS
        .iter()
        .map(|t| t.id)
        .collect();
    assert_eq!(specula_analyze::lens::standard::NAMES, standards.as_slice());
}

/// The lines that open and close an analysis's option table in its docs page.
const TABLE_BEGIN: &str = "<!-- The option table: made from the declarations by `specula_analyze::analysis::options_table`;\n`SPECULA_REGENERATE=1 cargo test -p specula-analyze --test analysis` writes it again. -->\n";
const TABLE_END: &str = "<!-- end of the option table -->\n";

/// Each analysis's docs page (docs/analyses/NAME.md) holds the option table its declarations
/// make, as they are now: the flags, the script keys, kinds, units, defaults and help.
#[test]
fn every_analysis_page_holds_its_option_table() {
    let regenerate = std::env::var_os("SPECULA_REGENERATE").is_some();
    let docs = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/analyses");
    let mut stale = Vec::new();
    for info in ANALYSES.iter().filter(|a| !a.test_only) {
        let path = docs.join(format!("{}.md", info.name));
        let page = std::fs::read_to_string(&path).unwrap();
        let start = page
            .find(TABLE_BEGIN)
            .unwrap_or_else(|| panic!("{}: no option table", path.display()))
            + TABLE_BEGIN.len();
        let end = start + page[start..].find(TABLE_END).expect("the table closes");
        let table = analysis::options_table(info);
        if page[start..end] == table {
            continue;
        }
        if regenerate {
            let written = format!("{}{table}{}", &page[..start], &page[end..]);
            std::fs::write(&path, written).unwrap();
        } else {
            stale.push(path.display().to_string());
        }
    }
    assert!(
        stale.is_empty(),
        "option tables out of date in {stale:?}: run SPECULA_REGENERATE=1 cargo test -p \
         specula-analyze --test analysis"
    );
}

/// The lines that open and close the viewer's table of an `analysis` step's keys.
const KEYS_BEGIN: &str = "<!-- The analysis step's keys: made from the declarations by `cargo test -p specula-analyze --test analysis`\n(`SPECULA_REGENERATE=1` writes it again). -->\n";
const KEYS_END: &str = "<!-- end of the analysis step's keys -->\n";

/// Every key an `analysis` step takes, for each analysis: the option names, kinds and units.
fn script_keys_table() -> String {
    let mut table = String::from(
        "| key | analyses | takes | unit |\n|---|---|---|---|\n| `kind` | all | the analysis's name, or `off` | |\n",
    );
    let mut rows: Vec<(String, Vec<&str>, String, &str)> = Vec::new();
    for info in ANALYSES.iter().filter(|a| !a.test_only) {
        for spec in info.all_options() {
            let mut takes = spec.kind.describe();
            if spec.repeatable {
                takes.push_str(", an array");
            }
            match rows.iter_mut().find(|r| r.0 == spec.name && r.2 == takes) {
                Some(row) => row.1.push(info.name),
                None => rows.push((spec.name.to_string(), vec![info.name], takes, spec.unit)),
            }
        }
    }
    for (key, analyses, takes, unit) in rows {
        table.push_str(&format!(
            "| `{key}` | {} | {} | {unit} |\n",
            analyses.join(", "),
            takes.replace('|', "\\|")
        ));
    }
    table.push_str("| `map` | lens | `mean-power` or `cylinder`: what the overlay draws | |\n");
    table
}

/// docs/viewer.md lists every key an `analysis` step takes, as the declarations make them.
#[test]
fn the_viewer_page_lists_every_analysis_step_key() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/viewer.md");
    let page = std::fs::read_to_string(&path).unwrap();
    let start = page.find(KEYS_BEGIN).expect("docs/viewer.md: no key table") + KEYS_BEGIN.len();
    let end = start + page[start..].find(KEYS_END).expect("the table closes");
    let table = script_keys_table();
    if page[start..end] != table && std::env::var_os("SPECULA_REGENERATE").is_some() {
        std::fs::write(&path, format!("{}{table}{}", &page[..start], &page[end..])).unwrap();
        return;
    }
    assert!(
        page[start..end] == table,
        "docs/viewer.md's key table is out of date: run SPECULA_REGENERATE=1 cargo test -p \
         specula-analyze --test analysis"
    );
}

/// Runs analysis `name` with `options` on `scene` through the trait.
fn run(name: &str, scene: &specula_scene::Scene, options: &[(&str, &str)]) -> String {
    by_name::run_json(name, scene, options)
}

#[test]
fn a_run_through_the_trait_gives_the_wrapped_function_s_report() {
    use specula_analyze::analysis::eye_points::Eyes;
    use specula_analyze::frame::VehicleFrame;
    use specula_analyze::mirror_view::{self, Precision};
    let scene = specula_scene::load("door-mirror").unwrap();
    let json = run(
        "mirror-view",
        &scene,
        &[("mirror", "door mirror"), ("ocular", "true")],
    );
    let mirror = specula_analyze::object(&scene, "mirror", "door mirror").unwrap();
    let frame = VehicleFrame::new(&scene.camera, None).unwrap();
    let eyes = Eyes::Ocular.points(scene.camera.eye, &frame).unwrap();
    let options = mirror_view::Options::new(&scene, mirror, frame, Precision::REPORT);
    let direct =
        mirror_view::analyze(&scene, &SceneAccel::new(&scene), &eyes, &options, &|_| {}).unwrap();
    assert_eq!(json, serde_json::to_string_pretty(&direct.report).unwrap());
}

#[test]
fn options_that_do_not_go_together_are_refused_naming_them() {
    let scene = specula_scene::load("door-mirror").unwrap();
    let check = |name: &str, options: &[(&str, &str)]| {
        let mut analysis = analysis::by_name(name).unwrap();
        let mut eyes = EyePoints::default();
        for (option, value) in options {
            if let Err(e) = analysis.set_option(&mut eyes, option, value) {
                return e.to_string();
            }
        }
        analysis.check(&scene, &eyes).unwrap_err().to_string()
    };
    let cases = [
        (
            check(
                "mirror-view",
                &[
                    ("mirror", "door mirror"),
                    ("ocular", "true"),
                    ("eyebox", "1,1,2,2"),
                ],
            ),
            "ocular: give one of `eye`, `eyebox`, `ocular`, `r_point` and `eyellipse`, not `eyebox` and `ocular`",
        ),
        (
            check(
                "mirror-view",
                &[("mirror", "door mirror"), ("outermost", "1,2,3")],
            ),
            "outermost: lays out a regulation's fields: give `regulation` too",
        ),
        (
            check(
                "mirror-view",
                &[
                    ("mirror", "door mirror"),
                    ("regulation", "r46-ii"),
                    ("vehicle", "nope"),
                ],
            ),
            "unknown vehicle 'nope'",
        ),
        (
            check(
                "mirror-view",
                &[
                    ("mirror", "door mirror"),
                    ("regulation", "fmvss111"),
                    ("r_point", "0,0,0"),
                ],
            ),
            "r_point: fmvss111 judges from the driver's eyes",
        ),
        (
            check(
                "mirror-view",
                &[("mirror", "door mirror"), ("regulation", "r47")],
            ),
            "regulation: r47: expected one of r46-i",
        ),
        (
            check("mirror-view", &[("mirror", "door mirror"), ("range", "x")]),
            "range: x: expected a number",
        ),
        (
            check(
                "glare",
                &[
                    ("surface", "door mirror"),
                    ("sun", "10,20"),
                    ("source", "ground"),
                ],
            ),
            "sun: give one of `source`, `sun` and `sun_sweep`, not `source` and `sun`",
        ),
        (
            check(
                "glare",
                &[
                    ("surface", "door mirror"),
                    ("sun", "10,20"),
                    ("latitude", "50"),
                ],
            ),
            "latitude: a solar day takes `latitude`, `heading` and `date` together, with `sun_sweep`",
        ),
        (
            check("lens", &[("lens", "door mirror")]),
            "lens 'door mirror'",
        ),
        (
            check("toy", &[("least_share", "2")]),
            "least_share: 2: expected a number from 0 to 1",
        ),
    ];
    for (message, wanted) in cases {
        assert!(
            message.contains(wanted),
            "{message:?} should say {wanted:?}"
        );
    }
}
