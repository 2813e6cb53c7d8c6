//! A mesh file's length unit and up axis in a scene file (`unit`, `up` on a mesh shape), and the
//! warnings for sizes that point at a wrong unit: they name what to do, and no shipped scene
//! (built-in or under scenes/) gives one.

use std::path::{Path, PathBuf};

use glam::Vec3;
use specula_scene::{load, Scene};

mod support;
use support::{assert_mentions, error_of, write, TOML_SCENE};

/// A triangle 10 × 20 × 30 units, its normal given along +Z.
const TRIANGLE_OBJ: &str = "v 0 0 0\nv 10 0 0\nv 0 20 30\nvn 0 0 1\nf 1//1 2//1 3//1\n";

/// A scene placing `mesh_file` with the mesh shape's extra keys `shape_keys`, the object's
/// `placement` keys and a mirror material.
fn mesh_scene(mesh_file: &str, shape_keys: &str, placement: &str) -> String {
    format!(
        r#"
[camera]
eye = [0, 1, 4]
target = [0, 0, 0]
[materials.chrome]
type = "mirror"
[[objects]]
name = "part"
material = "chrome"
{placement}
shape = {{ type = "mesh", file = "{mesh_file}"{shape_keys} }}
"#
    )
}

fn load_in(dir: &Path, name: &str, text: &str) -> Scene {
    let path = write(dir, name, text);
    load(path.to_str().unwrap()).unwrap_or_else(|e| panic!("{e}"))
}

fn part(scene: &Scene) -> &specula_scene::Mesh {
    scene.meshes.iter().find(|m| m.name == "part").unwrap()
}

/// The warnings this feature adds, told apart from every other warning by their wording.
fn unit_warnings(scene: &Scene) -> Vec<&String> {
    scene
        .warnings
        .iter()
        .filter(|w| w.contains("is implausible") || w.contains("look like millimetres"))
        .collect()
}

#[test]
fn each_unit_scales_the_mesh_to_metres() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "t.obj", TRIANGLE_OBJ);
    for (unit, metres) in [("mm", 1e-3), ("cm", 1e-2), ("m", 1.0), ("in", 0.0254)] {
        let text = mesh_scene("t.obj", &format!(", unit = \"{unit}\""), "");
        let scene = load_in(dir.path(), "s.toml", &text);
        let extent = part(&scene).bounds().extent();
        let wanted = Vec3::new(10.0, 20.0, 30.0) * metres;
        assert!(
            (extent - wanted).abs().max_element() <= wanted.max_element() * 1e-6,
            "unit = {unit}: extent {extent}, wanted {wanted}"
        );
    }
}

#[test]
fn the_unit_applies_in_the_file_before_the_object_s_placement() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "t.obj", TRIANGLE_OBJ);
    let text = mesh_scene(
        "t.obj",
        ", unit = \"mm\"",
        "translate = [1, 0, 0]\nscale = 2",
    );
    let scene = load_in(dir.path(), "s.toml", &text);
    // The file's (10, 0, 0) is 10 mm; the object's scale doubles it, then its translation
    // moves it by a metre: placement numbers stay metres whatever the file's unit.
    let corner = part(&scene).positions[1];
    assert!(
        (corner - Vec3::new(1.02, 0.0, 0.0)).length() < 1e-6,
        "{corner}"
    );
}

#[test]
fn up_z_turns_the_file_s_z_onto_world_y() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "t.obj", TRIANGLE_OBJ);
    let text = mesh_scene("t.obj", ", unit = \"cm\", up = \"z\"", "");
    let mesh = part(&load_in(dir.path(), "s.toml", &text)).clone();
    // File (x, y, z) → world (x, z, −y): +Z up becomes +Y up, and +Y (often the depth axis
    // in a Z-up file) points away from a camera on +Z.
    let top = mesh.positions[2];
    assert!((top - Vec3::new(0.0, 0.3, -0.2)).length() < 1e-6, "{top}");
    assert!(
        mesh.normals.iter().all(|n| (*n - Vec3::Y).length() < 1e-6),
        "the file's +Z normals turn to +Y: {:?}",
        mesh.normals
    );
    let default = mesh_scene("t.obj", "", "");
    let unturned = part(&load_in(dir.path(), "y.toml", &default)).positions[2];
    assert_eq!(
        unturned,
        Vec3::new(0.0, 20.0, 30.0),
        "up = y is the default"
    );
}

#[test]
fn a_bad_unit_or_up_names_the_key_path_and_the_allowed_values() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "t.obj", TRIANGLE_OBJ);
    let cases = [
        (
            ", unit = \"km\"",
            vec![
                "objects[0].shape",
                "unit",
                "\"km\"",
                "\"mm\", \"cm\", \"m\" or \"in\"",
            ],
        ),
        (
            ", unit = \"MM\"",
            vec!["objects[0].shape", "unit", "\"MM\"", "\"mm\""],
        ),
        (
            ", up = \"x\"",
            vec!["objects[0].shape", "up", "\"x\"", "\"y\" or \"z\""],
        ),
        // Not a string, or a misspelt key: serde's errors, which name the line.
        (
            ", unit = 1000",
            vec!["line 11", "unit = 1000", "expected a string"],
        ),
        (", units = \"mm\"", vec!["line 11", "unknown field `units`"]),
    ];
    for (i, (keys, parts)) in cases.iter().enumerate() {
        let name = format!("bad{i}.toml");
        let message = error_of(&write(dir.path(), &name, mesh_scene("t.obj", keys, "")));
        assert_mentions(&message, &[name.as_str()]);
        assert_mentions(&message, parts);
    }
    write(dir.path(), "quad.obj", TRIANGLE_OBJ);
    let fitted = TOML_SCENE.replace("fit = 0.5", "fit = 0.5, unit = \"mm\"");
    assert_mentions(
        &error_of(&write(dir.path(), "fit.toml", fitted)),
        &["fit.toml", "objects[8].shape", "fit", "unit", "not both"],
    );
}

/// The door mirror's size, 200 × 130 mm, as a flat quad in a file in millimetres.
const MILLIMETRE_MIRROR_OBJ: &str =
    "v -100 -65 0\nv 100 -65 0\nv 100 65 0\nv -100 65 0\nf 1 2 3 4\n";

#[test]
fn a_mirror_in_millimetres_read_as_metres_is_warned_of_by_name_and_size() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "mirror.obj", MILLIMETRE_MIRROR_OBJ);
    let scene = load_in(dir.path(), "s.toml", &mesh_scene("mirror.obj", "", ""));
    let warnings = unit_warnings(&scene);
    assert_eq!(warnings.len(), 2, "{warnings:?}");
    assert_mentions(
        warnings[0],
        &[
            "mirror.obj",
            "200 m across",
            "look like millimetres",
            "unit = \"mm\"",
        ],
    );
    assert_mentions(
        warnings[1],
        &[
            "s.toml",
            "mirror 'part'",
            "200 m across",
            "over 5 m",
            "unit = \"mm\"",
        ],
    );
    let placed = mesh_scene("mirror.obj", ", unit = \"mm\"", "");
    let scene = load_in(dir.path(), "mm.toml", &placed);
    assert!(unit_warnings(&scene).is_empty(), "{:?}", scene.warnings);
}

#[test]
fn a_lens_under_a_millimetre_is_warned_of_and_a_large_diffuse_part_is_not() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "mirror.obj", MILLIMETRE_MIRROR_OBJ);
    let text = r#"
[camera]
eye = [0, 1, 4]
target = [0, 0, 0]
[materials.glass]
type = "dielectric"
ior = 1.5
[materials.paint]
type = "diffuse"
[[lights]]
type = "point"
position = [0, 3, 0]
intensity = 5
[[objects]]
name = "grain"
material = "glass"
shape = { type = "sphere", radius = 0.0002 }
[[objects]]
name = "wall"
material = "paint"
shape = { type = "box", size = [40, 3, 0.2] }
[[objects]]
name = "car"
material = "paint"
shape = { type = "mesh", file = "mirror.obj", unit = "mm", up = "z" }
"#;
    let scene = load_in(dir.path(), "s.toml", text);
    let warnings = unit_warnings(&scene);
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert_mentions(
        warnings[0],
        &["s.toml", "glass 'grain'", "0.000400 m across", "under 1 mm"],
    );
}

#[test]
fn a_bare_mesh_file_in_millimetres_is_warned_of_and_one_in_metres_is_not() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(
        dir.path(),
        "bracket.stl",
        stl_of(MILLIMETRE_MIRROR_OBJ, 1.0),
    );
    let scene = load(path.to_str().unwrap()).unwrap();
    let warnings = unit_warnings(&scene);
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert_mentions(
        warnings[0],
        &[
            "bracket.stl",
            "200 m across",
            "look like millimetres",
            "unit = \"mm\"",
        ],
    );
    let path = write(
        dir.path(),
        "metres.stl",
        stl_of(MILLIMETRE_MIRROR_OBJ, 1e-3),
    );
    let scene = load(path.to_str().unwrap()).unwrap();
    assert!(unit_warnings(&scene).is_empty(), "{:?}", scene.warnings);
}

/// An ASCII STL of an OBJ's quad (its first two triangles), scaled by `scale`.
fn stl_of(obj: &str, scale: f32) -> String {
    let v: Vec<Vec3> = obj
        .lines()
        .filter_map(|l| l.strip_prefix("v "))
        .map(|l| {
            let n: Vec<f32> = l.split(' ').map(|x| x.parse().unwrap()).collect();
            Vec3::new(n[0], n[1], n[2]) * scale
        })
        .collect();
    let mut stl = String::from("solid quad\n");
    for [a, b, c] in [[0, 1, 2], [0, 2, 3]] {
        stl += "facet normal 0 0 1\nouter loop\n";
        for p in [v[a], v[b], v[c]] {
            stl += &format!("vertex {} {} {}\n", p.x, p.y, p.z);
        }
        stl += "endloop\nendfacet\n";
    }
    stl + "endsolid quad\n"
}

/// Every scene file (`.toml`, `.step`, `.stp`) under `dir`, recursively.
fn scene_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap().flatten() {
        let path = entry.path();
        if path.is_dir() {
            scene_files(&path, out);
        } else if path
            .extension()
            .is_some_and(|e| ["toml", "step", "stp"].contains(&&*e.to_string_lossy()))
        {
            out.push(path);
        }
    }
}

#[test]
fn no_shipped_scene_gives_a_unit_warning() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut files = Vec::new();
    scene_files(&root.join("scenes"), &mut files);
    files.sort();
    assert!(files.len() >= 40, "found only {files:?}");
    // The benchmark scenes read the large meshes of ../shared, beside the repository.
    let shared = root.join("../shared/meshes");
    let mut loaded = 0;
    for file in &files {
        let text = std::fs::read_to_string(file).unwrap();
        if text.contains("shared/meshes") && !shared.is_dir() {
            eprintln!(
                "{}: not loaded, {} is absent",
                file.display(),
                shared.display()
            );
            continue;
        }
        let scene = load(file.to_str().unwrap()).unwrap_or_else(|e| panic!("{e}"));
        let warnings = unit_warnings(&scene);
        assert!(warnings.is_empty(), "{}: {warnings:?}", file.display());
        loaded += 1;
    }
    for name in specula_scene::builtin::names() {
        let scene = load(name).unwrap();
        assert!(
            unit_warnings(&scene).is_empty(),
            "{name}: {:?}",
            scene.warnings
        );
    }
    eprintln!(
        "{loaded} of {} scene files loaded without a unit warning",
        files.len()
    );
}
