//! A mesh file in millimetres placed with `unit = "mm"` is the same mirror as the file in metres:
//! `scenes/car-door-mirror.toml`'s door mirror, written as an OBJ twice (metres, and ×1000 for
//! millimetres), judged by `mirror-view` against UN R46 class III as the scene's header does,
//! gives the same figures both ways; without `unit` the millimetre file is a 200 m mirror and
//! the scene says so.

mod by_name;

use std::path::Path;

use serde_json::Value;
use specula_scene::{Mesh, Scene};

/// Figures from the two files may differ by the f32 rounding of a vertex read in millimetres and
/// scaled to metres: a relative 1e-7 a coordinate, 0.1 µm at the mirror's metre from the origin.
const RELATIVE_TOLERANCE: f64 = 1e-5;
/// ... and, where a figure is a difference of nearly equal ones (the mirror rules' deviations of
/// the fitted radii from r, tenths of a millimetre, and their uncertainties), that rounding
/// noise whole: measured up to 5.4e-7 (metres, or 1/m for the convexity check).
const ABSOLUTE_TOLERANCE: f64 = 1e-6;

/// The scene file's door mirror shape, `shape = { type = "patch", ..., control = [...] }`.
fn door_mirror_shape(scene_text: &str) -> &str {
    let object = scene_text
        .find("name = \"door mirror\"")
        .expect("the scene has a door mirror");
    let start = object + scene_text[object..].find("shape = ").unwrap();
    let end = start + scene_text[start..].find("] }").unwrap() + "] }".len();
    &scene_text[start..end]
}

/// The door mirror as a mesh in its own coordinates (before the object's placement): the patch
/// the scene file generates, in a scene of its own.
fn door_mirror_mesh(scene_text: &str) -> Mesh {
    let alone = format!(
        "[camera]\neye = [0, 0, 1]\ntarget = [0, 0, 0]\n[materials.mirror]\ntype = \"mirror\"\n\
         [[objects]]\nname = \"door mirror\"\nmaterial = \"mirror\"\n{}",
        door_mirror_shape(scene_text)
    );
    let scene = specula_scene::loaders::toml_scene::parse("mirror alone", &alone, Path::new("."))
        .unwrap_or_else(|e| panic!("{e}"));
    let mesh = scene.meshes.into_iter().next().unwrap();
    assert_eq!(mesh.positions.len(), 49, "the 6 × 6 patch");
    mesh
}

/// `mesh` as OBJ text, its coordinates multiplied by `per_metre` (1000 for millimetres), with
/// its normals so that the file's mirror is shaded as the patch is.
fn obj_text(mesh: &Mesh, per_metre: f64) -> String {
    let mut obj = String::new();
    for p in &mesh.positions {
        let [x, y, z] = p.to_array().map(|c| f64::from(c) * per_metre);
        obj += &format!("v {x} {y} {z}\n");
    }
    for n in &mesh.normals {
        obj += &format!("vn {} {} {}\n", n.x, n.y, n.z);
    }
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| i + 1);
        obj += &format!("f {a}//{a} {b}//{b} {c}//{c}\n");
    }
    obj
}

fn load(path: &Path) -> Scene {
    specula_scene::load(path.to_str().unwrap()).unwrap_or_else(|e| panic!("{e}"))
}

/// The figures of `mirror-view` on `scene`'s door mirror, with the options of the example in
/// the scene file's header.
fn mirror_view_json(scene: &Scene) -> Value {
    let options = [
        ("mirror", "door mirror"),
        ("regulation", "r46-iii"),
        ("forward", "0,0,-1"),
        ("r_point", "-0.37,0.55,0"),
        ("outermost", "-0.95,0.6,1.5"),
        ("vehicle", "car body"),
        ("vehicle", "roof"),
        ("vehicle", "A-pillar"),
        ("vehicle", "door handle"),
        ("vehicle", "rear wing"),
        ("vehicle", "mirror housing"),
    ];
    serde_json::from_str(&by_name::run_json("mirror-view", scene, &options)).unwrap()
}

/// Every difference between two reports, by JSON path: numbers beyond both tolerances, and
/// anything else not equal. Returns how many numbers were compared.
fn compare(path: &str, a: &Value, b: &Value, differences: &mut Vec<String>) -> usize {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            if (x - y).abs() > (RELATIVE_TOLERANCE * x.abs().max(y.abs())).max(ABSOLUTE_TOLERANCE) {
                differences.push(format!("{path}: {x} and {y}"));
            }
            1
        }
        (Value::Object(x), Value::Object(y)) if x.len() == y.len() => x
            .iter()
            .map(|(key, value)| match y.get(key) {
                Some(other) => compare(&format!("{path}.{key}"), value, other, differences),
                None => {
                    differences.push(format!("{path}.{key}: only in the first"));
                    0
                }
            })
            .sum(),
        (Value::Array(x), Value::Array(y)) if x.len() == y.len() => x
            .iter()
            .zip(y)
            .enumerate()
            .map(|(i, (u, v))| compare(&format!("{path}[{i}]"), u, v, differences))
            .sum(),
        _ if a == b => 0,
        _ => {
            differences.push(format!("{path}: {a} and {b}"));
            0
        }
    }
}

#[test]
fn a_millimetre_mirror_placed_with_unit_mm_gives_the_metre_mirror_s_figures() {
    let scenes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
    let car = std::fs::read_to_string(scenes.join("car-door-mirror.toml")).unwrap();
    let mirror = door_mirror_mesh(&car);
    let dir = tempfile::tempdir().unwrap();
    let scene_with = |file: &str, obj: String, shape: &str| {
        std::fs::write(dir.path().join(file), obj).unwrap();
        let text = car.replace(door_mirror_shape(&car), shape);
        let path = dir.path().join(file.replace(".obj", ".toml"));
        std::fs::write(&path, text).unwrap();
        load(&path)
    };
    let metres = scene_with(
        "metres.obj",
        obj_text(&mirror, 1.0),
        r#"shape = { type = "mesh", file = "metres.obj" }"#,
    );
    let millimetres = scene_with(
        "millimetres.obj",
        obj_text(&mirror, 1000.0),
        r#"shape = { type = "mesh", file = "millimetres.obj", unit = "mm" }"#,
    );
    for scene in [&metres, &millimetres] {
        assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    }

    let (mut a, mut b) = (mirror_view_json(&metres), mirror_view_json(&millimetres));
    for report in [&mut a, &mut b] {
        let scene = report.get_mut("scene").expect("the report names its scene");
        *scene = Value::Null;
    }
    let mut differences = Vec::new();
    let numbers = compare("", &a, &b, &mut differences);
    assert!(differences.is_empty(), "{differences:#?}");
    // Not a vacuous comparison: the mirror was seen and judged, with many figures.
    assert!(numbers > 50, "{numbers} numbers compared");
    assert_eq!(a["regulation"]["verdict"], "pass", "{a:#}");
    assert!(a["solid_angle_sr"].as_f64().unwrap() > 0.1, "{a:#}");
    eprintln!(
        "{numbers} numbers equal within a relative {RELATIVE_TOLERANCE} or {ABSOLUTE_TOLERANCE}"
    );

    // The same millimetre file without `unit`: a 200 m mirror, and the scene says so.
    std::fs::write(
        dir.path().join("unitless.toml"),
        car.replace(
            door_mirror_shape(&car),
            "shape = { type = \"mesh\", file = \"millimetres.obj\" }",
        ),
    )
    .unwrap();
    let unitless = load(&dir.path().join("unitless.toml"));
    let warnings = &unitless.warnings;
    assert_eq!(warnings.len(), 2, "{warnings:#?}");
    // The file spans 200 units; the mirror, turned 17° as placed, spans 194 m of world x.
    let file = ["millimetres.obj", "200 m across", "look like millimetres"];
    let mirror = [
        "unitless.toml",
        "mirror 'door mirror' is 194 m across",
        "over 5 m",
    ];
    for (warning, parts) in warnings.iter().zip([&file, &mirror]) {
        for part in parts.iter().chain(&["unit = \"mm\""]) {
            assert!(
                warning.contains(part),
                "{warning:?} should mention {part:?}"
            );
        }
    }
}
