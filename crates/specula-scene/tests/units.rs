//! A mesh file's length unit and up axis in a scene file (`unit`, `up` on a mesh shape).

use std::path::Path;

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
        // Not a string: serde's error, which names the line.
        (
            ", unit = 1000",
            vec!["line 11", "unit = 1000", "expected a string"],
        ),
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
