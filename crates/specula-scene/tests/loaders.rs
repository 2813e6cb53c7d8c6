//! Every loader on good input, and every bad-input case: each must give a clear error naming
//! the file and, where the format has one, the line or JSON path — never a panic.

use std::path::Path;

use glam::Vec3;
use specula_scene::{load, MaterialKind, SceneError};

mod support;
use support::{assert_mentions, error_of, write, TOML_SCENE};

const QUAD_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";

// ---------- OBJ ----------

#[test]
fn obj_loads_with_smooth_normals_default_camera_and_lights() {
    let dir = tempfile::tempdir().unwrap();
    let scene = load(write(dir.path(), "quad.obj", QUAD_OBJ).to_str().unwrap()).unwrap();
    assert_eq!(scene.triangle_count(), 2);
    assert!(scene.meshes[0]
        .normals
        .iter()
        .all(|n| (n.z - 1.0).abs() < 1e-6));
    assert!(scene
        .warnings
        .iter()
        .any(|w| w.contains("no camera") && w.contains("quad.obj")));
    assert!(!scene.lights.is_empty());
}

#[test]
fn shipped_bunny_loads() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/meshes/bunny.obj");
    let scene = load(path.to_str().unwrap()).unwrap();
    assert_eq!(scene.triangle_count(), 3674);
}

#[test]
fn obj_mtl_maps_to_mirror_dielectric_unlit_and_diffuse() {
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        "m.mtl",
        "newmtl chrome\nillum 3\nKs 0.9 0.8 0.7\nnewmtl glass\nillum 7\nNi 1.7\nnewmtl glow\nillum 0\nKd 1 0.5 0\nnewmtl paint\nillum 2\nKd 0.2 0.3 0.4\n",
    );
    let obj =
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nusemtl chrome\nf 1 2 3\nusemtl glass\nf 1 3 4\no b\nusemtl glow\nf 1 2 4\no c\nusemtl paint\nf 2 3 4\n";
    let scene = load(write(dir.path(), "m.obj", obj).to_str().unwrap()).unwrap();
    let kind = |name: &str| {
        scene
            .materials
            .iter()
            .find(|m| m.name == name)
            .unwrap()
            .clone()
    };
    assert_eq!(kind("chrome").kind, MaterialKind::Mirror { fresnel: true });
    assert_eq!(kind("chrome").color, Vec3::new(0.9, 0.8, 0.7));
    assert_eq!(
        kind("glass").kind,
        MaterialKind::Dielectric {
            ior: Vec3::splat(1.7),
            thin_walled: false
        }
    );
    assert_eq!(kind("glow").kind, MaterialKind::Unlit);
    assert_eq!(kind("paint").kind, MaterialKind::Diffuse);
    assert_eq!(kind("paint").color, Vec3::new(0.2, 0.3, 0.4));
}

#[test]
fn obj_bad_number_names_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(
        dir.path(),
        "bad.obj",
        "v 0 0 0\nv 1 0 0\nv 1 zero 0\nf 1 2 3\n",
    );
    assert_mentions(&error_of(&path), &["bad.obj:3", "'zero' is not a number"]);
}

#[test]
fn obj_nan_and_inf_vertices_name_the_line() {
    let dir = tempfile::tempdir().unwrap();
    for (value, name) in [("nan", "nan.obj"), ("inf", "inf.obj"), ("-inf", "ninf.obj")] {
        let path = write(
            dir.path(),
            name,
            format!("v 0 0 0\nv 1 0 0\nv 1 {value} 0\nf 1 2 3\n"),
        );
        assert_mentions(&error_of(&path), &[&format!("{name}:3"), "non-finite"]);
    }
}

#[test]
fn obj_index_out_of_range_names_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(
        dir.path(),
        "range.obj",
        "v 0 0 0\nv 1 0 0\nv 1 1 0\n\nf 1 2 7\n",
    );
    assert_mentions(&error_of(&path), &["range.obj:5", "vertex 7", "has 3"]);
    let path = write(dir.path(), "neg.obj", "v 0 0 0\nf -1 -2 -3\n");
    assert_mentions(&error_of(&path), &["neg.obj:2", "out of range"]);
}

#[test]
fn obj_truncated_face_names_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "cut.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2");
    assert_mentions(&error_of(&path), &["cut.obj:4", "2 corner(s)"]);
    let path = write(dir.path(), "cutv.obj", "v 0 0 0\nv 1 0");
    assert_mentions(&error_of(&path), &["cutv.obj:2", "at least 3 numbers"]);
}

#[test]
fn degenerate_triangles_are_dropped_with_one_warning_giving_the_count() {
    let dir = tempfile::tempdir().unwrap();
    let obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\nf 1 1 3\n";
    let scene = load(write(dir.path(), "degen.obj", obj).to_str().unwrap()).unwrap();
    assert_eq!(scene.triangle_count(), 1);
    let warnings: Vec<_> = scene
        .warnings
        .iter()
        .filter(|w| w.contains("degenerate"))
        .collect();
    assert_eq!(warnings.len(), 1);
    assert_mentions(warnings[0], &["degen.obj", "dropped 2 degenerate"]);
}

// ---------- files in general ----------

#[test]
fn missing_file_is_named() {
    let message = error_of(Path::new("/nonexistent/dir/mesh.obj"));
    assert_mentions(&message, &["/nonexistent/dir/mesh.obj", "no such file"]);
}

#[test]
fn unreadable_file_is_named() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("folder.obj");
    std::fs::create_dir(&path).unwrap();
    let message = error_of(&path);
    assert_mentions(&message, &["folder.obj", "cannot read"]);
}

#[test]
fn unknown_scene_lists_built_ins() {
    let e = load("no-such-scene").unwrap_err();
    assert!(matches!(e, SceneError::UnknownScene { .. }));
    assert_mentions(&e.to_string(), &["no-such-scene", "door-mirror", ".gltf"]);
}

// ---------- PLY ----------

const PLY_HEADER: &str = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";

#[test]
fn ply_ascii_quad_is_fan_triangulated() {
    let dir = tempfile::tempdir().unwrap();
    let ply = format!("{PLY_HEADER}0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n");
    let scene = load(write(dir.path(), "q.ply", ply).to_str().unwrap()).unwrap();
    assert_eq!(scene.triangle_count(), 2);
}

#[test]
fn ply_binary_loads_and_truncated_binary_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let header = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
    let mut bytes = header.as_bytes().to_vec();
    for v in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        for c in v {
            bytes.extend_from_slice(&c.to_le_bytes());
        }
    }
    bytes.push(3);
    for i in [0i32, 1, 2] {
        bytes.extend_from_slice(&i.to_le_bytes());
    }
    let scene = load(write(dir.path(), "b.ply", &bytes).to_str().unwrap()).unwrap();
    assert_eq!(scene.triangle_count(), 1);
    let cut = write(dir.path(), "cut.ply", &bytes[..bytes.len() - 20]);
    assert_mentions(&error_of(&cut), &["cut.ply", "truncated"]);
    let nan_at = header.len() + 12;
    bytes[nan_at..nan_at + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    let nan = write(dir.path(), "nan.ply", &bytes);
    assert_mentions(&error_of(&nan), &["nan.ply", "vertex 1", "non-finite"]);
}

#[test]
fn ply_index_out_of_range_and_nan() {
    let dir = tempfile::tempdir().unwrap();
    let ply = format!("{PLY_HEADER}0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 9\n");
    assert_mentions(
        &error_of(&write(dir.path(), "r.ply", ply)),
        &["r.ply", "face 0", "index 9"],
    );
    let ply = format!("{PLY_HEADER}0 0 0\n1 nan 0\n1 1 0\n0 1 0\n3 0 1 2\n");
    // ply-rs rejects the text 'nan' itself, naming the line.
    assert_mentions(
        &error_of(&write(dir.path(), "n.ply", ply)),
        &["n.ply", "Line 11"],
    );
    let ply = format!("{PLY_HEADER}0 0 0\n1 0 0\n");
    assert_mentions(
        &error_of(&write(dir.path(), "t.ply", ply)),
        &["t.ply", "line 12", "truncated"],
    );
}

// ---------- STL ----------

fn stl_triangles() -> Vec<stl_io::Triangle> {
    let t = |a: [f32; 3], b: [f32; 3], c: [f32; 3]| stl_io::Triangle {
        normal: stl_io::Normal::new([0.0, 0.0, 1.0]),
        vertices: [
            stl_io::Vertex::new(a),
            stl_io::Vertex::new(b),
            stl_io::Vertex::new(c),
        ],
    };
    vec![
        t([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]),
        t([0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]),
    ]
}

#[test]
fn stl_binary_and_ascii_load_welded() {
    let dir = tempfile::tempdir().unwrap();
    let mut bytes = Vec::new();
    stl_io::write_stl(&mut bytes, stl_triangles().iter()).unwrap();
    let scene = load(write(dir.path(), "b.stl", &bytes).to_str().unwrap()).unwrap();
    assert_eq!(scene.triangle_count(), 2);
    assert_eq!(scene.meshes[0].positions.len(), 4);
    let ascii = "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 1 1 0\nendloop\nendfacet\nendsolid t\n";
    let scene = load(write(dir.path(), "a.stl", ascii).to_str().unwrap()).unwrap();
    assert_eq!(scene.triangle_count(), 1);
}

#[test]
fn stl_truncated_and_nan_are_errors() {
    let dir = tempfile::tempdir().unwrap();
    let mut bytes = Vec::new();
    stl_io::write_stl(&mut bytes, stl_triangles().iter()).unwrap();
    let cut = write(dir.path(), "cut.stl", &bytes[..bytes.len() - 10]);
    assert_mentions(&error_of(&cut), &["cut.stl", "truncated"]);
    let ascii = "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex nan 0 0\nvertex 1 1 0\nendloop\nendfacet\nendsolid t\n";
    assert_mentions(
        &error_of(&write(dir.path(), "nan.stl", ascii)),
        &["nan.stl"],
    );
}

// ---------- glTF ----------

/// One triangle (no NORMAL: flat normals), six primitives with different materials, a camera,
/// a point and a directional light, and an unsupported extension.
fn gltf_json(buffer_uri: Option<&str>, buffer_len: usize) -> String {
    let uri = buffer_uri
        .map(|u| format!(r#""uri": "{u}","#))
        .unwrap_or_default();
    let prim = |m: usize| {
        format!(
            r#"{{"attributes": {{"POSITION": 0, "TEXCOORD_0": 2}}, "indices": 1, "material": {m}}}"#
        )
    };
    let prims: Vec<String> = (0..6).map(prim).collect();
    format!(
        r#"{{
  "asset": {{"version": "2.0"}},
  "extensionsUsed": ["KHR_materials_unlit", "KHR_materials_transmission", "KHR_materials_volume", "KHR_materials_ior", "KHR_materials_dispersion", "KHR_lights_punctual", "KHR_texture_transform"],
  "extensions": {{"KHR_lights_punctual": {{"lights": [
      {{"type": "point", "color": [1, 0.5, 0.25], "intensity": 4}},
      {{"type": "directional", "intensity": 2}}]}}}},
  "scene": 0,
  "scenes": [{{"nodes": [0, 1, 2, 3]}}],
  "nodes": [
    {{"camera": 0, "translation": [0, 0, 3]}},
    {{"mesh": 0, "translation": [0, 1, 0]}},
    {{"extensions": {{"KHR_lights_punctual": {{"light": 0}}}}, "translation": [0, 2, 0]}},
    {{"extensions": {{"KHR_lights_punctual": {{"light": 1}}}}, "rotation": [-0.7071068, 0, 0, 0.7071068]}}
  ],
  "cameras": [{{"type": "perspective", "perspective": {{"yfov": 0.5, "znear": 0.01, "aspectRatio": 1.5}}}}],
  "meshes": [{{"primitives": [{prims}]}}],
  "materials": [
    {{"name": "flat", "extensions": {{"KHR_materials_unlit": {{}}}}, "pbrMetallicRoughness": {{"baseColorFactor": [1, 0, 0, 1]}}}},
    {{"name": "chrome", "pbrMetallicRoughness": {{"metallicFactor": 1, "roughnessFactor": 0, "baseColorFactor": [0.9, 0.9, 0.8, 1]}}}},
    {{"name": "glass", "extensions": {{"KHR_materials_transmission": {{"transmissionFactor": 1}}, "KHR_materials_volume": {{"thicknessFactor": 0.1}}, "KHR_materials_ior": {{"ior": 1.7}}}}}},
    {{"name": "sheet", "extensions": {{"KHR_materials_transmission": {{"transmissionFactor": 1}}}}}},
    {{"name": "flint", "extensions": {{"KHR_materials_transmission": {{"transmissionFactor": 1}}, "KHR_materials_volume": {{"thicknessFactor": 0.1}}, "KHR_materials_dispersion": {{"dispersion": 0.5}}}}}},
    {{"name": "painted", "pbrMetallicRoughness": {{"baseColorTexture": {{"index": 0}}, "metallicFactor": 0, "roughnessFactor": 1}}}}
  ],
  "textures": [{{"source": 0}}],
  "images": [{{"uri": "tex.png"}}],
  "buffers": [{{{uri} "byteLength": {buffer_len}}}],
  "bufferViews": [
    {{"buffer": 0, "byteOffset": 0, "byteLength": 36}},
    {{"buffer": 0, "byteOffset": 36, "byteLength": 6}},
    {{"buffer": 0, "byteOffset": 44, "byteLength": 24}}
  ],
  "accessors": [
    {{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]}},
    {{"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}},
    {{"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC2"}}
  ]
}}"#,
        prims = prims.join(", ")
    )
}

fn gltf_buffer(third_x: f32, last_index: u16) -> Vec<u8> {
    let mut bytes = Vec::new();
    for v in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [third_x, 1.0, 0.0]] {
        for c in v {
            bytes.extend_from_slice(&c.to_le_bytes());
        }
    }
    for i in [0u16, 1, last_index] {
        bytes.extend_from_slice(&i.to_le_bytes());
    }
    bytes.extend_from_slice(&[0, 0]);
    for c in [0.0f32, 0.0, 1.0, 0.0, 1.0, 1.0] {
        bytes.extend_from_slice(&c.to_le_bytes());
    }
    bytes
}

fn write_texture(dir: &Path) {
    image::RgbImage::from_fn(2, 2, |x, _| {
        image::Rgb(if x == 0 { [255, 255, 255] } else { [0, 0, 0] })
    })
    .save(dir.join("tex.png"))
    .unwrap();
}

fn glb(json: &str, bin: &[u8]) -> Vec<u8> {
    let mut json = json.as_bytes().to_vec();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut bin = bin.to_vec();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::new();
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    out
}

#[test]
fn gltf_maps_camera_lights_materials_and_flat_normals() {
    let dir = tempfile::tempdir().unwrap();
    write_texture(dir.path());
    let bin = gltf_buffer(0.0, 2);
    write(dir.path(), "tri.bin", &bin);
    let path = write(
        dir.path(),
        "scene.gltf",
        gltf_json(Some("tri.bin"), bin.len()),
    );
    let scene = load(path.to_str().unwrap()).unwrap();
    assert_eq!(scene.camera.eye, Vec3::new(0.0, 0.0, 3.0));
    assert!((scene.camera.target - Vec3::new(0.0, 0.0, 2.0)).length() < 1e-6);
    assert!((scene.camera.fov_y_deg - 0.5f32.to_degrees()).abs() < 1e-4);
    assert_eq!(scene.camera.aspect, Some(1.5));
    assert_eq!(scene.lights.len(), 2);
    match &scene.lights[0] {
        specula_scene::Light::Point {
            position,
            intensity,
        } => {
            assert_eq!(*position, Vec3::new(0.0, 2.0, 0.0));
            assert_eq!(*intensity, Vec3::new(4.0, 2.0, 1.0));
        }
        other => panic!("expected a point light, got {other:?}"),
    }
    match &scene.lights[1] {
        specula_scene::Light::Directional { direction, .. } => {
            assert!((*direction - -Vec3::Y).length() < 1e-5)
        }
        other => panic!("expected a directional light, got {other:?}"),
    }
    let by_name = |n: &str| scene.materials.iter().find(|m| m.name == n).unwrap();
    assert_eq!(by_name("flat").kind, MaterialKind::Unlit);
    assert_eq!(by_name("flat").color, Vec3::new(1.0, 0.0, 0.0));
    assert_eq!(
        by_name("chrome").kind,
        MaterialKind::Mirror { fresnel: true }
    );
    assert_eq!(
        by_name("glass").kind,
        MaterialKind::Dielectric {
            ior: Vec3::splat(1.7),
            thin_walled: false
        }
    );
    assert_eq!(
        by_name("sheet").kind,
        MaterialKind::Dielectric {
            ior: Vec3::splat(1.5),
            thin_walled: true
        }
    );
    // dispersion 0.5 = Abbe number 40: n_F − n_C = 0.5 / 40.
    match by_name("flint").kind {
        MaterialKind::Dielectric {
            ior,
            thin_walled: false,
        } => {
            assert!((ior.z - ior.x - 0.5 / 40.0).abs() < 1e-6);
            assert!((ior.y - 1.5).abs() < 1e-6);
        }
        ref other => panic!("flint: {other:?}"),
    }
    assert_eq!(by_name("painted").kind, MaterialKind::Diffuse);
    assert!(by_name("painted").texture.is_some());
    assert_eq!(scene.meshes.len(), 6);
    let mesh = &scene.meshes[0];
    assert_eq!(
        mesh.positions[0],
        Vec3::new(0.0, 1.0, 0.0),
        "node translation applied"
    );
    assert!(
        mesh.normals.iter().all(|n| (*n - Vec3::Z).length() < 1e-6),
        "flat face normal"
    );
    assert!(scene
        .warnings
        .iter()
        .any(|w| w.contains("KHR_texture_transform") && w.contains("scene.gltf")));
    assert_eq!(
        scene
            .warnings
            .iter()
            .filter(|w| w.contains("thin-walled"))
            .count(),
        1
    );
}

#[test]
fn glb_loads_and_truncated_glb_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    write_texture(dir.path());
    let bin = gltf_buffer(0.0, 2);
    let bytes = glb(&gltf_json(None, bin.len()), &bin);
    let scene = load(write(dir.path(), "s.glb", &bytes).to_str().unwrap()).unwrap();
    assert_eq!(scene.meshes.len(), 6);
    let cut = write(dir.path(), "cut.glb", &bytes[..bytes.len() - 30]);
    assert_mentions(&error_of(&cut), &["cut.glb", "truncated"]);
}

#[test]
fn gltf_bad_index_and_nan_name_the_json_path() {
    let dir = tempfile::tempdir().unwrap();
    write_texture(dir.path());
    let bin = gltf_buffer(0.0, 9);
    let bytes = glb(&gltf_json(None, bin.len()), &bin);
    assert_mentions(
        &error_of(&write(dir.path(), "idx.glb", &bytes)),
        &["idx.glb", "meshes[0].primitives[0].indices", "index 9"],
    );
    let bin = gltf_buffer(f32::NAN, 2);
    let bytes = glb(&gltf_json(None, bin.len()), &bin);
    assert_mentions(
        &error_of(&write(dir.path(), "nan.glb", &bytes)),
        &["nan.glb", "POSITION", "not finite"],
    );
}

#[test]
fn gltf_invalid_reference_names_the_json_path() {
    let dir = tempfile::tempdir().unwrap();
    write_texture(dir.path());
    let bin = gltf_buffer(0.0, 2);
    let json = gltf_json(None, bin.len()).replace(r#""mesh": 0"#, r#""mesh": 7"#);
    assert_mentions(
        &error_of(&write(dir.path(), "ref.glb", glb(&json, &bin))),
        &["ref.glb", "nodes[1].mesh"],
    );
}

#[test]
fn gltf_without_camera_gets_a_default_framing_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    write_texture(dir.path());
    let bin = gltf_buffer(0.0, 2);
    let json = gltf_json(None, bin.len()).replace(
        r#"{"camera": 0, "translation": [0, 0, 3]}"#,
        r#"{"translation": [0, 0, 3]}"#,
    );
    let scene = load(
        write(dir.path(), "nocam.glb", glb(&json, &bin))
            .to_str()
            .unwrap(),
    )
    .unwrap();
    assert!(scene
        .warnings
        .iter()
        .any(|w| w.contains("nocam.glb") && w.contains("no camera")));
    let center = scene.bounds().center();
    assert!((scene.camera.target - center).length() < 1e-5);
}

// ---------- TOML ----------

#[test]
fn toml_scene_with_every_shape_loads() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "quad.obj", QUAD_OBJ);
    let scene = load(write(dir.path(), "s.toml", TOML_SCENE).to_str().unwrap()).unwrap();
    assert_eq!(scene.name, "all shapes");
    assert_eq!(scene.meshes.len(), 9);
    assert_eq!(scene.lights.len(), 2);
    assert_eq!(scene.ambient, Vec3::splat(0.1));
    let patch = &scene.meshes[3];
    assert_eq!(patch.positions.len(), 49);
    let quad = scene.meshes.last().unwrap().bounds();
    assert!(
        (quad.extent().max_element() - 0.5).abs() < 1e-6,
        "fit rescales to 0.5 m"
    );
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
}

#[test]
fn toml_unknown_key_names_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let text = TOML_SCENE.replace("fov_y_deg = 40", "fov_y_deg = 40\nfocal_length = 3");
    let message = error_of(&write(dir.path(), "k.toml", text));
    assert_mentions(&message, &["k.toml", "line 8", "focal_length"]);
    let text = TOML_SCENE.replace("fresnel = false", "fresnel = false\nroughness = 0.1");
    assert_mentions(
        &error_of(&write(dir.path(), "m.toml", text)),
        &["m.toml", "roughness"],
    );
    let text = TOML_SCENE.replace("radius = 0.5 }", "radius = 0.5, colour = 1 }");
    assert_mentions(
        &error_of(&write(dir.path(), "s.toml", text)),
        &["s.toml", "colour"],
    );
}

#[test]
fn toml_unknown_material_is_named_with_the_known_ones() {
    let dir = tempfile::tempdir().unwrap();
    let text = TOML_SCENE.replace(
        "material = \"grey\"\nscale = 0.1",
        "material = \"gray\"\nscale = 0.1",
    );
    let message = error_of(&write(dir.path(), "u.toml", text));
    assert_mentions(
        &message,
        &[
            "u.toml",
            "objects[7].material",
            "'gray'",
            "chrome, flint, grey",
        ],
    );
}

#[test]
fn toml_bad_shape_parameters_name_the_object() {
    let dir = tempfile::tempdir().unwrap();
    let text = TOML_SCENE.replace(
        "front_radius = 0.2, back_radius = -0.2",
        "front_radius = 0.02, back_radius = -0.2",
    );
    let message = error_of(&write(dir.path(), "l.toml", text));
    assert_mentions(&message, &["l.toml", "objects[4].shape", "front radius"]);
    let text = TOML_SCENE.replace("file = \"quad.obj\"", "file = \"missing.obj\"");
    assert_mentions(
        &error_of(&write(dir.path(), "f.toml", text)),
        &["f.toml", "objects[8].shape", "missing.obj"],
    );
}

#[test]
fn toml_without_camera_warns_and_frames_the_scene() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "quad.obj", QUAD_OBJ);
    let start = TOML_SCENE.find("[camera]").unwrap();
    let end = TOML_SCENE.find("[background]").unwrap();
    let text = format!("{}{}", &TOML_SCENE[..start], &TOML_SCENE[end..]);
    let scene = load(write(dir.path(), "c.toml", text).to_str().unwrap()).unwrap();
    assert!(scene
        .warnings
        .iter()
        .any(|w| w.contains("c.toml") && w.contains("no camera")));
}

#[test]
fn toml_syntax_error_names_the_line() {
    let dir = tempfile::tempdir().unwrap();
    let message = error_of(&write(
        dir.path(),
        "x.toml",
        "name = \"a\"\n[camera\neye = 1\n",
    ));
    assert_mentions(&message, &["x.toml", "line 2"]);
}

#[test]
fn shipped_example_scene_loads_cleanly() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/example.toml");
    let scene = load(path.to_str().unwrap()).unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    assert_eq!(scene.meshes.len(), 6);
}

#[test]
fn toml_metal_mirrors_take_f0_from_index_and_extinction() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "quad.obj", QUAD_OBJ);
    // Gold at red, green and blue (index and extinction from Johnson and Christy's tables).
    let gold = TOML_SCENE.replace(
        "color = [0.9, 0.9, 0.9]\nfresnel = false",
        "ior = [0.18, 0.42, 1.37]\nextinction = [3.42, 2.35, 1.77]",
    );
    let scene = load(write(dir.path(), "gold.toml", &gold).to_str().unwrap()).unwrap();
    let chrome = scene.materials.iter().find(|m| m.name == "chrome").unwrap();
    let expected = |n: f32, k: f32| ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k);
    for (c, (n, k)) in [(0.18, 3.42), (0.42, 2.35), (1.37, 1.77)]
        .into_iter()
        .enumerate()
    {
        assert!(
            (chrome.color[c] - expected(n, k)).abs() < 1e-6,
            "{}",
            chrome.color
        );
    }
    assert!(
        chrome.color.x > chrome.color.z,
        "gold reflects red more than blue"
    );
    let both = TOML_SCENE.replace("fresnel = false", "ior = 0.2");
    assert_mentions(
        &error_of(&write(dir.path(), "both.toml", both)),
        &["both.toml", "materials.chrome", "not both"],
    );
    let lone = TOML_SCENE.replace("color = [0.9, 0.9, 0.9]\nfresnel = false", "extinction = 3");
    assert_mentions(
        &error_of(&write(dir.path(), "lone.toml", lone)),
        &["lone.toml", "materials.chrome", "extinction needs ior"],
    );
}

#[test]
fn based_scene_moves_the_named_object_rigidly_about_its_box_centre() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(
        dir.path(),
        "moved.toml",
        r#"
base = "door-mirror"
[[move]]
object = "door mirror"
translate = [0.0, 0.1, 0.0]
[[move]]
object = "door mirror"
rotate = { axis = [0, 1, 0], degrees = 90 }
"#,
    );
    let moved = load(path.to_str().unwrap()).unwrap();
    let original = load("door-mirror").unwrap();
    let find = |s: &specula_scene::Scene| {
        s.meshes
            .iter()
            .find(|m| m.name == "door mirror")
            .unwrap()
            .clone()
    };
    let (before, after) = (find(&original), find(&moved));
    // The centre moved by the translation only; a quarter turn about +Y swaps the box's X and Z
    // extents.
    let centre_shift = after.bounds().center() - before.bounds().center();
    assert!(
        centre_shift.abs_diff_eq(Vec3::new(0.0, 0.1, 0.0), 1e-5),
        "{centre_shift}"
    );
    let (e0, e1) = (before.bounds().extent(), after.bounds().extent());
    assert!(
        (e0.x - e1.z).abs() < 1e-5 && (e0.z - e1.x).abs() < 1e-5,
        "{e0} {e1}"
    );
    // Other objects stay where they were; the camera is the built-in's.
    assert_eq!(original.camera, moved.camera);
    assert_eq!(original.meshes[1].positions, moved.meshes[1].positions);
}

#[test]
fn based_scene_replaces_a_material_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(
        dir.path(),
        "ior.toml",
        "base = \"glass-dragon\"\n[materials.glass]\ntype = \"dielectric\"\nior = 1.2\n",
    );
    let scene = load(path.to_str().unwrap()).unwrap();
    let original = load("glass-dragon").unwrap();
    let glass = |s: &specula_scene::Scene| {
        s.materials
            .iter()
            .find(|m| m.name == "glass")
            .unwrap()
            .kind
            .clone()
    };
    assert_eq!(
        glass(&scene),
        specula_scene::MaterialKind::Dielectric {
            ior: Vec3::splat(1.2),
            thin_walled: false
        }
    );
    assert_ne!(glass(&original), glass(&scene));
    assert_eq!(original.meshes.len(), scene.meshes.len());
}

#[test]
fn bad_base_and_moves_name_the_key() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        ("base = \"nowhere\"", &["base", "nowhere", "door-mirror"][..]),
        (
            "base = \"door-mirror\"\nambient = 0.3",
            &["ambient", "not allowed with base"][..],
        ),
        (
            "base = \"door-mirror\"\n[[move]]\nobject = \"wing\"\ntranslate = [0, 1, 0]",
            &["move[0]", "wing", "door mirror"][..],
        ),
        (
            "base = \"door-mirror\"\n[[move]]\nobject = \"door mirror\"",
            &["move[0]", "exactly one"][..],
        ),
        (
            "base = \"door-mirror\"\n[[move]]\nobject = \"door mirror\"\nrotate = { axis = [0, 0, 0], degrees = 5 }",
            &["move[0]", "rotate", "axis"][..],
        ),
        (
            "base = \"door-mirror\"\n[[move]]\nobject = \"door mirror\"\nscale = 2",
            &["scale"][..],
        ),
        (
            "base = \"glass-dragon\"\n[materials.crystal]\ntype = \"dielectric\"\nior = 1.2",
            &["materials.crystal", "no material", "glass"][..],
        ),
        (
            "base = \"glass-dragon\"\n[materials.glass]\ntype = \"dielectric\"\nior = -1",
            &["glass", "index of refraction"][..],
        ),
    ];
    for (i, (text, parts)) in cases.iter().enumerate() {
        let path = write(dir.path(), &format!("bad{i}.toml"), text);
        let message = error_of(&path);
        assert_mentions(&message, &[&format!("bad{i}.toml")]);
        assert_mentions(&message, parts);
    }
}

#[test]
fn sloppy_files_load_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let triangle = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    // An exporter's empty `usemtl`, and a Latin-1 byte in a comment.
    let mut obj = format!("# caf\u{e9}\n{triangle}usemtl\nf 1 2 3\n").into_bytes();
    let e_acute = obj.iter().position(|&b| b == 0xC3).unwrap();
    obj.splice(e_acute..e_acute + 2, [0xE9]);
    let path = write(dir.path(), "sloppy.obj", &obj);
    let scene = load(path.to_str().unwrap()).unwrap();
    assert_eq!(scene.triangle_count(), 1);
    let warnings = scene.warnings.join("\n");
    assert_mentions(
        &warnings,
        &["sloppy.obj:1", "not UTF-8", "sloppy.obj:5", "usemtl"],
    );
    // A PLY header line an exporter forgot to mark as a comment.
    let ply = "ply\nformat ascii 1.0\nCreated by an exporter\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    let path = write(dir.path(), "stray.ply", ply);
    let scene = load(path.to_str().unwrap()).unwrap();
    assert_eq!(scene.triangle_count(), 1);
    assert_mentions(&scene.warnings.join("\n"), &["stray.ply:3", "comment"]);
}

#[test]
fn parser_errors_are_one_readable_sentence() {
    let dir = tempfile::tempdir().unwrap();
    let ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n";
    let message = error_of(&write(dir.path(), "short.ply", ply));
    assert_mentions(&message, &["short.ply", "line 13", "truncated"]);
    assert!(
        !message.contains(" { ") && !message.contains('\t'),
        "{message}"
    );
    let message = error_of(&write(dir.path(), "utf16.obj", [0xFF, 0xFE, b'v', 0]));
    assert_mentions(&message, &["utf16.obj", "UTF-16"]);
}

#[test]
fn malformed_gltf_is_an_error_naming_the_json_path_not_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (
            r#"{"asset":{"version":"2.0"},"meshes":[{"primitives":[{"attributes":{"POSITION":7}}]}]}"#,
            "meshes[0].primitives[0].attributes.POSITION: index 7 is out of range",
        ),
        (
            r#"{"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"children":[1]},{"children":[0]}]}"#,
            "cycle in the node hierarchy",
        ),
        (
            r#"{"asset":{"version":"1.0"}}"#,
            "glTF 1.0 is not supported",
        ),
        (
            r#"{"asset":{"version":"2.0"},"extensionsRequired":["KHR_draco_mesh_compression"]}"#,
            "requires KHR_draco_mesh_compression",
        ),
    ];
    for (i, (json, expected)) in cases.iter().enumerate() {
        let message = error_of(&write(dir.path(), &format!("bad{i}.gltf"), json));
        assert_mentions(&message, &[&format!("bad{i}.gltf"), expected]);
    }
}

#[test]
fn a_wild_gltf_aspect_ratio_is_ignored_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    write_texture(dir.path());
    let bin = gltf_buffer(0.0, 2);
    write(dir.path(), "tri.bin", &bin);
    let json = gltf_json(Some("tri.bin"), bin.len())
        .replace("\"aspectRatio\": 1.5", "\"aspectRatio\": 1e9");
    let path = write(dir.path(), "wide.gltf", json);
    let scene = load(path.to_str().unwrap()).unwrap();
    assert_eq!(scene.camera.aspect, None);
    assert_mentions(
        &scene.warnings.join("\n"),
        &["aspectRatio 1000000000", "ignored"],
    );
}
