//! The STEP reader: shapes written as rational B-spline faces load at their size and place with
//! their vertices on the analytic surface and their triangles within the chord tolerance, in
//! any unit; a file from another CAD system loads with its faces and names; broken files are
//! errors naming the file and the instance.

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

use glam::DVec3;
use specula_scene::loaders::step::write::{NurbsPatch, RationalArc, StepWriter};
use specula_scene::loaders::step::{self, StepOptions, DEFAULT_TOLERANCE_MM};
use specula_scene::units::LengthUnit;
use specula_scene::Mesh;

/// A sphere's band from −45° to +45° of latitude over half a turn (two spans each way round),
/// radius `r` about `centre`.
fn sphere_patch(r: f64, centre: DVec3) -> NurbsPatch {
    NurbsPatch::sphere_region(r, (0.0, PI), 2, (-FRAC_PI_4, FRAC_PI_4)).map_points(|p| p + centre)
}

/// Half a cylinder of radius `r` and height `h` on +Z.
fn cylinder_patch(r: f64, h: f64) -> NurbsPatch {
    NurbsPatch::revolved(
        &RationalArc::new(0.0, PI, 2),
        &[(r, 0.0, 1.0), (r, h, 1.0)],
        vec![0.0, 0.0, 1.0, 1.0],
        1,
    )
}

/// A quarter of a torus about +Z (major radius `big`, minor `small`): its outer half.
fn torus_patch(big: f64, small: f64) -> NurbsPatch {
    let tube = RationalArc::new(-FRAC_PI_2, FRAC_PI_2, 2);
    let profile: Vec<_> = tube
        .points
        .iter()
        .map(|&(x, y, w)| (big + small * x, small * y, w))
        .collect();
    NurbsPatch::revolved(
        &RationalArc::new(0.0, FRAC_PI_2, 1),
        &profile,
        tube.knots,
        2,
    )
}

fn file_of(name: &str, patch: &NurbsPatch, unit: LengthUnit) -> String {
    let mut writer = StepWriter::new();
    let face = writer.patch_face(patch);
    writer.body(name, &[face], false);
    writer.finish(unit)
}

fn load(text: &str) -> Mesh {
    let mut file = step::parse("test.step", text, &StepOptions::default()).unwrap();
    assert_eq!(file.faces, 1);
    assert_eq!(file.meshes.len(), 1);
    file.meshes.remove(0)
}

/// The largest distance of a vertex, and of a triangle's centroid, from the surface that
/// `distance` measures (metres).
fn deviations(mesh: &Mesh, distance: impl Fn(DVec3) -> f64) -> (f64, f64) {
    let p = |i: u32| mesh.positions[i as usize].as_dvec3();
    let vertex = mesh
        .positions
        .iter()
        .map(|v| distance(v.as_dvec3()).abs())
        .fold(0.0, f64::max);
    let chord = mesh
        .triangles
        .iter()
        .map(|&[a, b, c]| distance((p(a) + p(b) + p(c)) / 3.0).abs())
        .fold(0.0, f64::max);
    (vertex, chord)
}

/// Every triangle winds anticlockwise about its vertices' (exact) normals.
fn assert_faces_out(mesh: &Mesh) {
    for &[a, b, c] in &mesh.triangles {
        let [pa, pb, pc] = [a, b, c].map(|i| mesh.positions[i as usize]);
        let facet = (pb - pa).cross(pc - pa);
        let n = mesh.normals[a as usize] + mesh.normals[b as usize] + mesh.normals[c as usize];
        assert!(
            facet.dot(n) > 0.0,
            "a triangle faces against its face's normal"
        );
    }
}

const TOLERANCE_M: f64 = DEFAULT_TOLERANCE_MM * 1e-3;

#[test]
fn a_rational_b_spline_sphere_in_millimetres_loads_on_the_sphere_in_metres() {
    let centre_mm = DVec3::new(10.0, 20.0, 30.0);
    let mesh = load(&file_of(
        "ball",
        &sphere_patch(50.0, centre_mm),
        LengthUnit::Mm,
    ));
    let centre = centre_mm * 1e-3;
    let (vertex, chord) = deviations(&mesh, |p| (p - centre).length() - 0.05);
    // Vertices are evaluated on the surface: only f32 storage of positions separates them.
    assert!(vertex < 8e-9, "vertex off the sphere by {vertex} m");
    assert!(
        chord <= TOLERANCE_M * 1.05,
        "a triangle strays {chord} m, tolerance {TOLERANCE_M}"
    );
    let bounds = mesh.bounds();
    // Half a turn from +X through +Y, latitude ±45°: x in [−r, r], y in [0, r], z in ±r sin 45°.
    let expected_min = centre + DVec3::new(-0.05, 0.0, -0.05 * FRAC_PI_4.sin());
    let expected_max = centre + DVec3::new(0.05, 0.05, 0.05 * FRAC_PI_4.sin());
    assert!(
        (bounds.min.as_dvec3() - expected_min).abs().max_element() < TOLERANCE_M,
        "{bounds:?}"
    );
    assert!(
        (bounds.max.as_dvec3() - expected_max).abs().max_element() < TOLERANCE_M,
        "{bounds:?}"
    );
    assert_faces_out(&mesh);
    // The normals face away from the centre (the patch's Su × Sv).
    let p0 = mesh.positions[0].as_dvec3();
    assert!(mesh.normals[0].as_dvec3().dot(p0 - centre) > 0.0);
}

#[test]
fn a_rational_b_spline_cylinder_and_torus_load_on_their_surfaces() {
    let cylinder = load(&file_of(
        "tube",
        &cylinder_patch(40.0, 60.0),
        LengthUnit::Mm,
    ));
    let (vertex, chord) = deviations(&cylinder, |p| p.truncate().length() - 0.04);
    assert!(
        vertex < 8e-9 && chord <= TOLERANCE_M * 1.05,
        "cylinder: {vertex} {chord}"
    );
    let height = cylinder.bounds().extent().z as f64;
    assert!((height - 0.06).abs() < 1e-7, "cylinder height {height}");
    assert_faces_out(&cylinder);

    let torus = load(&file_of("ring", &torus_patch(60.0, 15.0), LengthUnit::Mm));
    let distance = |p: DVec3| {
        let ring = p.truncate().length() - 0.06;
        (ring * ring + p.z * p.z).sqrt() - 0.015
    };
    let (vertex, chord) = deviations(&torus, distance);
    assert!(
        vertex < 8e-9 && chord <= TOLERANCE_M * 1.05,
        "torus: {vertex} {chord}"
    );
    let outer = torus
        .positions
        .iter()
        .map(|p| p.truncate().length())
        .fold(0.0f32, f32::max);
    assert!(
        (outer as f64 - 0.075).abs() < TOLERANCE_M,
        "outer radius {outer}"
    );
    assert_faces_out(&torus);
}

#[test]
fn millimetres_metres_and_inches_give_the_same_world() {
    let patch_mm = sphere_patch(50.0, DVec3::new(5.0, -3.0, 8.0));
    let in_mm = load(&file_of("ball", &patch_mm, LengthUnit::Mm));
    for (unit, per_mm) in [
        (LengthUnit::M, 1e-3),
        (LengthUnit::In, 1.0 / 25.4),
        (LengthUnit::Cm, 0.1),
    ] {
        let other = load(&file_of(
            "ball",
            &patch_mm.clone().map_points(|p| p * per_mm),
            unit,
        ));
        let a = in_mm.bounds();
        let b = other.bounds();
        assert!(
            (a.min - b.min).abs().max_element() < 1e-6
                && (a.max - b.max).abs().max_element() < 1e-6,
            "{unit:?}: {a:?} against {b:?}"
        );
    }
}

#[test]
fn a_unit_given_by_the_scene_overrides_the_files() {
    let text = file_of("ball", &sphere_patch(50.0, DVec3::ZERO), LengthUnit::Mm);
    let options = StepOptions {
        unit: Some(LengthUnit::M),
        // The 50 m sphere this makes, cut to 50 mm rather than the default's 0.05 mm.
        tolerance_mm: 50.0,
        ..StepOptions::default()
    };
    let file = step::parse("test.step", &text, &options).unwrap();
    let extent = file.meshes[0].bounds().extent().x;
    assert!(
        (extent - 100.0).abs() < 0.1,
        "taken as metres: {extent} m across"
    );
}

#[test]
fn bodies_take_their_products_names_and_one_can_be_chosen() {
    let mut writer = StepWriter::new();
    let a = writer.patch_face(&sphere_patch(50.0, DVec3::ZERO));
    writer.body("mirror glass", &[a], false);
    let b = writer.patch_face(&cylinder_patch(40.0, 60.0));
    writer.body("housing", &[b], false);
    let text = writer.finish(LengthUnit::Mm);
    let all = step::parse("two.step", &text, &StepOptions::default()).unwrap();
    let names: Vec<&str> = all.meshes.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["mirror glass", "housing"]);
    let options = StepOptions {
        body: Some("housing".into()),
        ..StepOptions::default()
    };
    let one = step::parse("two.step", &text, &options).unwrap();
    assert_eq!(one.meshes.len(), 1);
    assert_eq!(one.meshes[0].name, "housing");
    let options = StepOptions {
        body: Some("door".into()),
        ..StepOptions::default()
    };
    let error = step::parse("two.step", &text, &options)
        .unwrap_err()
        .to_string();
    assert!(
        error.contains("two.step")
            && error.contains("no body named 'door'")
            && error.contains("mirror glass, housing"),
        "{error}"
    );
}

#[test]
fn the_face_map_names_each_triangles_face_and_each_vertexs_place_on_it() {
    let mesh = load(&file_of(
        "ball",
        &sphere_patch(50.0, DVec3::ZERO),
        LengthUnit::Mm,
    ));
    let cad = mesh.cad.as_ref().expect("a STEP mesh keeps its faces");
    cad.validate(mesh.triangles.len(), mesh.positions.len())
        .unwrap();
    for (v, p) in mesh.positions.iter().enumerate() {
        let exact = cad.point_world(v, 0);
        // f32 positions: 0.05 m holds to about 4e-9 m.
        assert!((exact - p.as_dvec3()).length() < 1e-8, "vertex {v}");
    }
}

/// The sample from another CAD system (tests/data/step/README.md): a 10 mm cube and a
/// cylinder of radius 5 mm, height 10 mm, two products in one file, in metres.
#[test]
fn a_file_from_another_cad_system_loads_with_its_faces_and_names() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/step/red_cube_blue_cylinder.step");
    let file = step::read(&path, &StepOptions::default()).unwrap();
    assert_eq!(file.faces, 9, "6 cube faces and 3 cylinder faces");
    let mut names: Vec<&str> = file.meshes.iter().map(|m| m.name.as_str()).collect();
    names.sort();
    assert_eq!(names, ["blue_cylinder", "red_cube"]);
    let cube = file.meshes.iter().find(|m| m.name == "red_cube").unwrap();
    let extent = cube.bounds().extent();
    assert!(
        (extent - glam::Vec3::splat(0.01)).abs().max_element() < 1e-6,
        "cube {extent}"
    );
    let cylinder = file
        .meshes
        .iter()
        .find(|m| m.name == "blue_cylinder")
        .unwrap();
    let bounds = cylinder.bounds();
    // Axis along +Z through (0.01, 0.005), radius 5 mm, from z = 0 to 10 mm.
    let axis = glam::Vec3::new(0.01, 0.005, 0.0);
    for p in &cylinder.positions {
        let r = (*p - axis).truncate().length();
        assert!(r < 0.005 + 1e-6, "{p}: {r} from the axis");
    }
    assert!((bounds.extent().z - 0.01).abs() < 1e-6, "{bounds:?}");
    assert_faces_out(cube);
}

fn replace_face_surface(
    text: &str,
    face_line_start: &str,
    new_surface: &str,
    extra: &str,
) -> String {
    let mut out = String::new();
    for line in text.lines() {
        if line.starts_with(face_line_start) {
            // ADVANCED_FACE('',(#b),#s,.T.)
            let (head, tail) = line.rsplit_once("),#").unwrap();
            let rest = tail.split_once(',').unwrap().1;
            out.push_str(&format!("{head}),{new_surface},{rest}\n"));
        } else if line == "ENDSEC;" && out.contains("DATA;") {
            out.push_str(extra);
            out.push_str("ENDSEC;\n");
        } else {
            out.push_str(line);
            out.push('\n');
        }
    }
    out
}

fn face_line(text: &str) -> String {
    let line = text
        .lines()
        .find(|l| l.contains("= ADVANCED_FACE"))
        .unwrap();
    format!("{} = ADVANCED_FACE", line.split(" = ").next().unwrap())
}

#[test]
fn broken_files_are_errors_naming_the_file_and_the_instance() {
    let text = file_of("ball", &sphere_patch(50.0, DVec3::ZERO), LengthUnit::Mm);
    let error = |text: &str| {
        step::parse("bad.step", text, &StepOptions::default())
            .unwrap_err()
            .to_string()
    };

    let truncated = error(&text[..text.len() / 2]);
    assert!(
        truncated.starts_with("bad.step: ") && truncated.contains("cut short"),
        "{truncated}"
    );

    let face = face_line(&text);
    let face_id = face.split(' ').next().unwrap();
    let dangling = error(&replace_face_surface(&text, &face, "#9001", ""));
    assert!(
        dangling.contains(&format!(
            "{face_id} = ADVANCED_FACE refers to #9001, which is not in the file"
        )),
        "{dangling}"
    );

    let surface = text
        .lines()
        .find(|l| l.contains("RATIONAL_B_SPLINE_SURFACE"))
        .unwrap()
        .split(' ')
        .next()
        .unwrap();
    let offset = error(&replace_face_surface(
        &text,
        &face,
        "#9000",
        &format!("#9000 = OFFSET_SURFACE('',{surface},2.,.F.);\n"),
    ));
    assert!(
        offset.starts_with("bad.step: #9000 = OFFSET_SURFACE (the surface of ")
            && offset.contains("Export the part with its surfaces as B-splines"),
        "{offset}"
    );

    let not_step = error("solid cube\nendsolid\n");
    assert!(
        not_step.contains("does not begin with ISO-10303-21"),
        "{not_step}"
    );

    let no_bodies = error("ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION((''),'2;1');\nFILE_NAME('','',(''),(''),'','','');\nFILE_SCHEMA(('AUTOMOTIVE_DESIGN'));\nENDSEC;\nDATA;\n#1 = CARTESIAN_POINT('',(0.,0.,0.));\nENDSEC;\nEND-ISO-10303-21;\n");
    assert!(
        no_bodies.contains("no solid, surface model or shell"),
        "{no_bodies}"
    );
}

/// The CAD examples in scenes/cad/ are what `loaders::step::examples` writes
/// (`SPECULA_REGENERATE=1` rewrites them), and load with all their faces, at their size.
#[test]
fn the_cad_examples_are_the_writers_and_load_with_every_face() {
    use specula_scene::loaders::step::examples;
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cad");
    for (name, text, faces, size_mm) in [
        (
            "door-mirror.step",
            examples::door_mirror(),
            4,
            [200.0, 130.0],
        ),
        (
            "spectacle-lens.step",
            examples::spectacle_lens(),
            6,
            [50.0, 36.0],
        ),
    ] {
        let path = root.join(name);
        if std::env::var_os("SPECULA_REGENERATE").is_some() {
            std::fs::create_dir_all(&root).unwrap();
            std::fs::write(&path, &text).unwrap();
        }
        let committed = std::fs::read_to_string(&path).unwrap();
        assert!(
            committed == text,
            "{name} is not what the writer writes: run with SPECULA_REGENERATE=1"
        );
        let file = step::read(&path, &StepOptions::default()).unwrap();
        assert_eq!(file.faces, faces, "{name}");
        assert_eq!(file.meshes.len(), 1, "{name}");
        let mesh = &file.meshes[0];
        assert_eq!(mesh.cad.as_ref().unwrap().faces.len(), faces, "{name}");
        let extent = mesh.bounds().extent();
        for (axis, want) in size_mm.iter().enumerate() {
            let got = extent[axis] as f64 * 1e3;
            assert!(
                (got - want).abs() < 0.5,
                "{name}: {got} mm along axis {axis}, want {want}"
            );
        }
        assert_faces_out(mesh);
    }
    // The lens is a closed solid: with every face's outside out, its triangles enclose a
    // positive volume, about its 50 mm × 36 mm times its mean thickness (1.2 mm at the
    // corners, 2.2 mm at the centre).
    let lens = step::read(&root.join("spectacle-lens.step"), &StepOptions::default()).unwrap();
    let mesh = &lens.meshes[0];
    let volume_mm3: f64 = mesh
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize].as_dvec3() * 1e3);
            a.dot(b.cross(c)) / 6.0
        })
        .sum();
    assert!(
        (50.0 * 36.0 * 1.2..50.0 * 36.0 * 2.2).contains(&volume_mm3),
        "lens volume {volume_mm3} mm³"
    );
}

/// A scene file places a STEP file's bodies: the unit it gives overrides the file's, `up = "z"`
/// turns +Z onto +Y, `body` picks one; what is wrong names the scene's key and the file.
#[test]
fn a_scene_file_places_a_step_file_with_its_unit_axis_and_body() {
    let dir = tempfile::tempdir().unwrap();
    let mut writer = StepWriter::new();
    let a = writer.patch_face(&cylinder_patch(40.0, 60.0));
    writer.body("tube", &[a], false);
    let b = writer.patch_face(&sphere_patch(50.0, DVec3::new(0.0, 0.0, 200.0)));
    writer.body("ball", &[b], false);
    std::fs::write(dir.path().join("part.step"), writer.finish(LengthUnit::Mm)).unwrap();
    let scene_with = |shape: &str| {
        let text = format!("[materials.grey]\ntype = \"diffuse\"\n\n[[objects]]\nname = \"part\"\nmaterial = \"grey\"\ntranslate = [1.0, 0.0, 0.0]\nshape = {{ type = \"step\", file = \"part.step\"{shape} }}\n");
        specula_scene::loaders::toml_scene::parse("scene.toml", &text, dir.path())
    };
    let scene = scene_with(", body = \"tube\", up = \"z\"").unwrap();
    assert_eq!(scene.meshes.len(), 1);
    let bounds = scene.meshes[0].bounds();
    // The tube's axis was +Z, 60 mm long: now +Y, moved 1 m along X.
    assert!(
        (bounds.extent().y - 0.06).abs() < 1e-6 && (bounds.center().x - 1.0).abs() < 0.03,
        "{bounds:?}"
    );
    let cad = scene.meshes[0]
        .cad
        .as_ref()
        .expect("the placed mesh keeps its faces");
    let moved = cad.point_world(0, 0);
    assert!(
        (moved - scene.meshes[0].positions[0].as_dvec3()).length() < 1e-7,
        "the faces move with the mesh"
    );

    let both = scene_with(", unit = \"cm\"").unwrap();
    let names: Vec<&str> = both.meshes.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["part/tube", "part/ball"]);
    assert!(
        (both.meshes[0].bounds().extent().z - 0.6).abs() < 1e-5,
        "60 file units taken as cm"
    );

    let missing = scene_with(", body = \"lid\"").unwrap_err().to_string();
    assert!(
        missing.contains("objects[0].shape")
            && missing.contains("no body named 'lid'")
            && missing.contains("tube, ball"),
        "{missing}"
    );
    let bad_unit = scene_with(", unit = \"ft\"").unwrap_err().to_string();
    assert!(
        bad_unit.contains("ft") && bad_unit.contains("mm"),
        "{bad_unit}"
    );
    std::fs::remove_file(dir.path().join("part.step")).unwrap();
    let no_file = scene_with("").unwrap_err().to_string();
    assert!(
        no_file.contains("part.step") && no_file.contains("cannot read"),
        "{no_file}"
    );
}

/// A closed solid whose faces run an edge the same way has a face turned inside out: loaded,
/// with a warning naming the shell and the two faces; the example lens has none.
#[test]
fn a_solid_with_a_face_turned_inside_out_is_named_in_a_warning() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes/cad/spectacle-lens.step");
    let text = std::fs::read_to_string(&path).unwrap();
    let good = step::parse("lens.step", &text, &StepOptions::default()).unwrap();
    assert!(good.warnings.is_empty(), "{:?}", good.warnings);
    // The first face turned over: its surface's sense and its loop's both reversed, so that it
    // still bounds its area but faces into the solid.
    let bound = text
        .lines()
        .find(|l| l.contains("FACE_OUTER_BOUND"))
        .unwrap();
    let bound_id = bound.split(' ').next().unwrap();
    let face = text
        .lines()
        .find(|l| l.contains(&format!("ADVANCED_FACE('',({bound_id})")))
        .unwrap();
    let turned = text
        .replacen(bound, &bound.replace(".T.)", ".F.)"), 1)
        .replacen(face, &face.replace(".T.)", ".F.)"), 1);
    let file = step::parse("lens.step", &turned, &StepOptions::default()).unwrap();
    assert_eq!(file.faces, 6);
    let warning = file.warnings.join("\n");
    assert!(
        warning.contains("lens.step: #")
            && warning.contains("= CLOSED_SHELL: faces #")
            && warning.contains("turned inside out"),
        "{warning}"
    );
}

/// A tolerance finer than truck cuts curves to (a millionth of a file unit, or of a circle's
/// radius; it panicked below that) is raised with a warning: this file is in metres.
#[test]
fn a_tolerance_finer_than_truck_cuts_a_large_circle_is_raised_with_a_warning() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/step/red_cube_blue_cylinder.step");
    let text = std::fs::read_to_string(path).unwrap();
    let options = StepOptions {
        tolerance_mm: 1e-6,
        ..StepOptions::default()
    };
    let file = step::parse("cylinder.step", &text, &options).unwrap();
    let warning = file.warnings.join("\n");
    assert!(
        warning
            .contains("body 'blue_cylinder': chord tolerance raised from 0.000001 mm to 0.0010 mm, a millionth of a file unit"),
        "{warning}"
    );
    assert_eq!(file.faces, 9);
}
