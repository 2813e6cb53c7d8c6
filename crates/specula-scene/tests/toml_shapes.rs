//! TOML scenes' generated shapes on good and bad input: rooms, merged and checker shapes,
//! spectacle lenses and free-form lens surfaces; each bad case a clear error naming the file,
//! the object and what is wrong.

use specula_scene::{load, MaterialKind};

mod support;
use support::{assert_mentions, error_of, write, TOML_SCENE};

const SHAPES_SCENE: &str = r#"
[materials.walls]
type = "diffuse"
checker = { squares = 4, colors = [0.9, 0.1] }
[materials.chrome]
type = "mirror"
[[objects]]
name = "room"
material = "walls"
shape = { type = "room", size = [4.0, 2.0, 3.0] }
[[objects]]
name = "pair"
material = "chrome"
shape = { type = "merged", parts = [
  { translate = [-1.0, 1.0, 0.0], shape = { type = "sphere", radius = 0.3, segments = 16, rings = 8 } },
  { translate = [1.0, 1.0, 0.0], scale = 0.5, shape = { type = "box", size = [1.0, 1.0, 1.0] } },
] }
[[objects]]
name = "faceted"
material = "walls"
flat = true
translate = [0.0, 1.0, 1.0]
shape = { type = "sphere", radius = 0.2, segments = 12, rings = 6 }
"#;

#[test]
fn toml_room_merged_flat_and_checker_shapes() {
    let dir = tempfile::tempdir().unwrap();
    let scene =
        specula_scene::load(write(dir.path(), "s.toml", SHAPES_SCENE).to_str().unwrap()).unwrap();
    let mesh = |name: &str| scene.meshes.iter().find(|m| m.name == name).unwrap();
    // The room: the inside of the box, floor at y = 0, every normal pointing inwards.
    let room = mesh("room");
    let bounds = room.bounds();
    assert_eq!((bounds.min.y, bounds.max.y), (0.0, 2.0));
    assert_eq!((bounds.min.x, bounds.max.z), (-2.0, 1.5));
    let centre = glam::Vec3::new(0.0, 1.0, 0.0);
    for (p, n) in room.positions.iter().zip(&room.normals) {
        assert!(
            n.dot(centre - *p) > 0.0,
            "normal {n} at {p} points outwards"
        );
    }
    // The checker: squares alternate between the two colours, four per UV unit.
    let texture = &scene.textures[scene.materials[room.material].texture.unwrap()];
    let at = |u: f32, v: f32| texture.sample(glam::Vec2::new(u, v)).x;
    assert!((at(0.1, 0.1) - 0.9).abs() < 1e-6 && (at(0.35, 0.1) - 0.1).abs() < 1e-6);
    assert!((at(1.1, 0.1) - 0.9).abs() < 1e-6, "the texture repeats");
    // The merged mirror mesh is one mesh in the file, split into its two objects on load.
    let (first, second) = (mesh("pair#1"), mesh("pair#2"));
    assert_eq!(
        first.triangles.len() + second.triangles.len(),
        16 * 8 * 2 - 2 * 16 + 12
    );
    assert!(
        (second.bounds().extent().x - 0.5).abs() < 1e-6,
        "the part's scale"
    );
    assert!(
        (first.bounds().center().x + 1.0).abs() < 1e-5,
        "the part's translation"
    );
    // Flat: three vertices per triangle, each carrying its face normal.
    let faceted = mesh("faceted");
    assert_eq!(faceted.positions.len(), 3 * faceted.triangles.len());
    for t in 0..faceted.triangles.len() {
        let face = faceted.face_normal_scaled(t).normalize();
        for i in faceted.triangles[t] {
            assert!(faceted.normals[i as usize].dot(face) > 0.9999);
        }
    }
}

#[test]
fn toml_checker_and_merged_errors_name_the_path() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (
            SHAPES_SCENE.replace("squares = 4", "squares = 0"),
            vec!["materials.walls.checker.squares", "0 is not from 1 to 256"],
        ),
        (
            SHAPES_SCENE.replace("checker = {", "texture = \"x.png\"\nchecker = {"),
            vec!["materials.walls", "either texture or checker"],
        ),
        (
            SHAPES_SCENE.replace("scale = 0.5", "scale = 0.0"),
            vec!["objects[1].shape", "parts[1]", "singular"],
        ),
        (
            SHAPES_SCENE.replace(
                "shape = { type = \"box\", size = [1.0, 1.0, 1.0] }",
                "shape = { type = \"lens\", front_radius = 0.1, back_radius = -0.1, center_thickness = 0.01, diameter = 0.3 }",
            ),
            vec!["objects[1].shape", "parts[1]", "lens"],
        ),
    ];
    for (k, (text, parts)) in cases.iter().enumerate() {
        let path = write(dir.path(), &format!("bad{k}.toml"), text);
        assert_mentions(&error_of(&path), parts);
    }
}

const SPECTACLES: &str = r#"
name = "spectacles"
[camera]
eye = [0, 0, 0]
target = [0, 0, -1]
[materials.crown]
type = "dielectric"
ior = 1.6
abbe = 42
[[objects]]
name = "right lens"
translate = [0, 0, -0.014]
shape = { type = "spectacle-lens", sphere = -2.0, cylinder = -1.0, axis = 30, index = 1.6, abbe = 42, center_thickness = 0.002, base_curve = 4.0, diameter = 0.05, rings = 12, segments = 48 }
[[objects]]
name = "left lens"
material = "crown"
translate = [0.065, 0, -0.014]
shape = { type = "spectacle-lens", sphere = -2.0, index = 1.6, abbe = 42, center_thickness = 0.002, base_curve = 4.0, diameter = 0.05, rings = 12, segments = 48 }
"#;

#[test]
fn toml_spectacle_lenses_keep_their_prescription_and_make_their_glass() {
    let dir = tempfile::tempdir().unwrap();
    let scene = load(write(dir.path(), "s.toml", SPECTACLES).to_str().unwrap()).unwrap();
    assert_eq!(scene.prescriptions.len(), 2);
    let (name, right) = &scene.prescriptions[0];
    assert_eq!(name, "right lens");
    assert_eq!(
        (right.sphere, right.cylinder, right.axis_deg),
        (-2.0, -1.0, 30.0)
    );
    // Made from its index and Abbe number: n_C, n_d, n_F with n_F − n_C = (n_d − 1) / V.
    let glass = &scene.materials[scene.meshes[0].material];
    let MaterialKind::Dielectric { ior, .. } = glass.kind else {
        panic!("{glass:?}")
    };
    assert!((ior.y - 1.6).abs() < 1e-6 && ((ior.z - ior.x) - 0.6 / 42.0).abs() < 1e-6);
    assert_eq!(
        scene.materials[scene.meshes[1].material].name, "crown",
        "a given material that agrees is kept"
    );
}

#[test]
fn toml_spectacle_lens_errors_name_the_object_and_what_is_wrong() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (
            SPECTACLES.replace("ior = 1.6\nabbe = 42", "ior = 1.5\nabbe = 42"),
            vec!["objects[1].material", "'crown'", "make them agree"],
        ),
        (
            SPECTACLES.replace("sphere = -2.0, index", "sphere = 8.0, index"),
            vec!["objects[1].shape", "edge would be", "mm thick"],
        ),
        (
            SPECTACLES.replace(
                "base_curve = 4.0, diameter = 0.05, rings = 12, segments = 48 }\n[[objects]]",
                "base_curve = 40.0, diameter = 0.05, rings = 12, segments = 48 }\n[[objects]]",
            ),
            vec!["objects[0].shape", "does not reach"],
        ),
        (
            SPECTACLES.replace(
                "shape = { type = \"spectacle-lens\", sphere = -2.0, cylinder",
                "shape = { type = \"spectacle-lens\", cylinder",
            ),
            vec!["s.toml", "sphere"],
        ),
    ];
    for (text, wanted) in cases {
        let message = error_of(&write(dir.path(), "s.toml", text));
        assert_mentions(&message, &wanted);
    }
    let scaled = SPECTACLES.replacen(
        "translate = [0, 0, -0.014]\n",
        "translate = [0, 0, -0.014]\nscale = [-1, 1, 1]\n",
        1,
    );
    assert_mentions(
        &error_of(&write(dir.path(), "x.toml", scaled)),
        &["objects[0].scale", "would change its powers"],
    );
    let other = TOML_SCENE.replacen("material = \"grey\"\n", "", 1);
    assert_mentions(
        &error_of(&write(dir.path(), "m.toml", other)),
        &["material: missing", "spectacle-lens"],
    );
}

/// A free-form front's errors in a scene: the grid's file, row and column; a grid that does
/// not cover the lens; a polynomial that tilts the surface; a base curve that disagrees.
#[test]
fn toml_free_form_lens_surfaces_refuse_bad_grids_naming_the_file_row_and_column() {
    let dir = tempfile::tempdir().unwrap();
    // A sphere of curvature 4 / 0.6 1/m sampled every 5 mm over ±30 mm.
    let nodes: Vec<f64> = (-6..=6).map(|k| f64::from(k) * 5.0).collect();
    let c = 4.0 / 0.6 / 1000.0;
    let csv = |bad: Option<(usize, usize, &str)>| {
        let mut text = String::from("y\\x");
        for x in &nodes {
            text.push_str(&format!(",{x}"));
        }
        text.push('\n');
        for (j, y) in nodes.iter().enumerate() {
            text.push_str(&format!("{y}"));
            for (i, x) in nodes.iter().enumerate() {
                let r2 = x * x + y * y;
                let sag = c * r2 / (1.0 + (1.0 - c * c * r2).sqrt());
                match bad {
                    Some((row, column, cell)) if row == j && column == i => {
                        text.push_str(&format!(",{cell}"))
                    }
                    _ => text.push_str(&format!(",{sag:.9}")),
                }
            }
            text.push('\n');
        }
        text
    };
    let scene = |front: &str| {
        SPECTACLES.replacen(
            "base_curve = 4.0, diameter = 0.05, rings = 12, segments = 48 }",
            &format!("diameter = 0.05, rings = 12, segments = 48, front = {front} }}"),
            1,
        )
    };
    write(dir.path(), "good.csv", csv(None));
    let good = load(
        write(dir.path(), "g.toml", scene("{ sag_grid = \"good.csv\" }"))
            .to_str()
            .unwrap(),
    )
    .unwrap();
    let base = good.prescriptions[0].1.base_curve;
    assert!((base - 4.0).abs() < 0.01, "{base}");
    write(dir.path(), "nan.csv", csv(Some((3, 5, "NaN"))));
    write(dir.path(), "hole.csv", csv(Some((7, 2, ""))));
    let cases = [
        (
            "{ sag_grid = \"nan.csv\" }",
            vec!["nan.csv", "row 5", "column 7"],
        ),
        (
            "{ sag_grid = \"hole.csv\" }",
            vec!["hole.csv", "row 9", "column 4"],
        ),
        ("{ sag_grid = \"missing.csv\" }", vec!["missing.csv"]),
        (
            "{ polynomial = [[1, 0, 0.01]] }",
            vec!["objects[0].shape", "polynomial[0]", "tilt"],
        ),
        (
            "{ progressive = { add = -2.0, corridor_length = 0.014, blend_width = 0.008 } }",
            vec!["progressive.add", "positive"],
        ),
    ];
    for (front, wanted) in cases {
        let message = error_of(&write(dir.path(), "bad.toml", scene(front)));
        assert_mentions(&message, &wanted);
    }
}
