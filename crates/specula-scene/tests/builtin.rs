//! Built-in scenes: all load cleanly and reproduce their papers' set-ups.

use specula_scene::{builtin, MaterialKind};

#[test]
fn every_built_in_scene_loads_without_warnings() {
    for name in builtin::names() {
        let scene = specula_scene::load(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(scene.warnings.is_empty(), "{name}: {:?}", scene.warnings);
        assert!(
            scene.materials.iter().any(|m| m.is_specular()),
            "{name} has a mirror or lens"
        );
        assert!(!builtin::list()
            .iter()
            .find(|s| s.0 == name)
            .unwrap()
            .1
            .is_empty());
    }
    assert!(builtin::names().contains(&builtin::DEFAULT_SCENE));
}

#[test]
fn door_mirror_is_a_49_vertex_free_form_mirror_with_red_markers() {
    let scene = specula_scene::load("door-mirror").unwrap();
    let mirror = scene
        .meshes
        .iter()
        .find(|m| m.name == "door mirror")
        .unwrap();
    assert_eq!(mirror.positions.len(), 49);
    assert!(matches!(
        scene.materials[mirror.material].kind,
        MaterialKind::Mirror { .. }
    ));
    assert!(
        scene
            .meshes
            .iter()
            .filter(|m| m.name == "marker ball")
            .count()
            >= 3
    );
}

#[test]
fn spectacle_lens_is_about_2000_triangles_6_to_7_cm_from_the_eye() {
    let scene = specula_scene::load("spectacle-lens").unwrap();
    let lens = scene
        .meshes
        .iter()
        .find(|m| m.name == "spectacle lens")
        .unwrap();
    assert!(
        (1800..=2200).contains(&lens.triangles.len()),
        "{} triangles",
        lens.triangles.len()
    );
    let nearest = lens
        .positions
        .iter()
        .map(|p| (*p - scene.camera.eye).length())
        .fold(f32::INFINITY, f32::min);
    assert!(
        (0.06..=0.07).contains(&nearest),
        "lens {nearest} m from the eye"
    );
    match scene.materials[lens.material].kind {
        MaterialKind::Dielectric { ior, .. } => assert!(ior.z > ior.x, "dispersive"),
        ref other => panic!("{other:?}"),
    }
}
