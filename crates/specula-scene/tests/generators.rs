//! Analytic generators: positions lie on the exact surfaces and normals are the exact analytic
//! normals; invalid parameters are errors.

use glam::Vec3;
use specula_scene::generators::{self, LensSpec};

#[test]
fn sphere_vertices_and_normals_are_exact() {
    let mesh = generators::sphere(2.0, 24, 12);
    for (p, n) in mesh.positions.iter().zip(&mesh.normals) {
        assert!((p.length() - 2.0).abs() < 1e-5);
        assert!((*n - *p / 2.0).length() < 1e-5);
    }
    mesh.validate("sphere").unwrap();
}

#[test]
fn caps_lie_on_their_sphere_with_normals_towards_the_reflecting_side() {
    for concave in [false, true] {
        let r = 0.5;
        let mesh = generators::spherical_cap(r, 0.4, concave, 8, 32).unwrap();
        let center = if concave { Vec3::Z * r } else { -Vec3::Z * r };
        for (p, n) in mesh.positions.iter().zip(&mesh.normals) {
            assert!(((*p - center).length() - r).abs() < 1e-5);
            assert!(n.z > 0.0, "reflecting side faces +Z");
            let radial = (*p - center).normalize();
            assert!((n.dot(radial).abs() - 1.0).abs() < 1e-5);
        }
        let aperture = mesh.bounds().extent().x;
        assert!((aperture - 0.4).abs() < 1e-3);
    }
    assert!(generators::spherical_cap(0.5, 1.2, false, 8, 32).is_err());
}

#[test]
fn door_mirror_patch_has_49_vertices_with_unit_normals_facing_the_viewer() {
    let mesh = generators::bicubic_patch(&generators::door_mirror_control_points(), 6);
    assert_eq!(mesh.positions.len(), 49);
    assert_eq!(mesh.triangles.len(), 72);
    for n in &mesh.normals {
        assert!((n.length() - 1.0).abs() < 1e-5 && n.z > 0.5);
    }
    // Normals agree with the tessellated faces' orientation.
    for t in 0..mesh.triangles.len() {
        let face = mesh.face_normal_scaled(t);
        assert!(face.dot(mesh.normals[mesh.triangles[t][0] as usize]) > 0.0);
    }
}

#[test]
fn lens_surfaces_lie_on_their_spheres() {
    let spec = LensSpec {
        front_radius: 0.1,
        back_radius: -0.15,
        center_thickness: 0.01,
        diameter: 0.04,
        rings: 8,
        segments: 32,
    };
    let mesh = generators::lens(&spec).unwrap();
    let (c1, c2) = (Vec3::Z * 0.1, Vec3::Z * (0.01 - 0.15));
    let mut front = 0;
    let mut back = 0;
    for (p, n) in mesh.positions.iter().zip(&mesh.normals) {
        if ((*p - c1).length() - 0.1).abs() < 1e-6 && n.z < -0.5 {
            front += 1;
            assert!((*n - (*p - c1) / 0.1).length() < 1e-5);
        } else if ((*p - c2).length() - 0.15).abs() < 1e-6 && n.z > 0.5 {
            back += 1;
            assert!((*n - (*p - c2) / 0.15).length() < 1e-5);
        }
    }
    assert_eq!(front, 33 * 9);
    assert_eq!(back, 33 * 9);
    assert_eq!(mesh.bounds().extent().x, 0.04);
}

#[test]
fn impossible_lenses_are_errors() {
    let good = LensSpec {
        front_radius: 0.1,
        back_radius: -0.1,
        center_thickness: 0.002,
        diameter: 0.04,
        rings: 4,
        segments: 16,
    };
    let crossing = generators::lens(&good).unwrap_err().to_string();
    assert!(crossing.contains("edge thickness"), "{crossing}");
    let too_curved = LensSpec {
        front_radius: 0.01,
        ..good
    };
    assert!(generators::lens(&too_curved)
        .unwrap_err()
        .to_string()
        .contains("front radius"));
    let flat = LensSpec {
        front_radius: f32::INFINITY,
        back_radius: f32::INFINITY,
        ..good
    };
    assert!(generators::lens(&flat).is_ok());
}

#[test]
fn teapot_has_32_patches_and_outward_normals() {
    assert_eq!(generators::teapot_patches().len(), 32);
    let mesh = generators::teapot(6);
    mesh.validate("teapot").unwrap();
    let bounds = mesh.bounds();
    assert!((bounds.max.y - 3.15).abs() < 1e-4 && bounds.min.y.abs() < 1e-4);
    // Around the body (away from spout and handle), normals point away from the Y axis.
    let body: Vec<_> = mesh
        .positions
        .iter()
        .zip(&mesh.normals)
        .filter(|(p, _)| p.x.abs() < 1.0 && p.y > 0.5 && p.y < 2.0)
        .collect();
    assert!(body.len() > 20);
    for (p, n) in body {
        assert!(
            n.dot(Vec3::new(p.x, 0.0, p.z)) > 0.0,
            "normal {n:?} at {p:?} points inwards"
        );
    }
}

#[test]
fn box_and_plane() {
    let b = generators::cuboid(Vec3::new(1.0, 2.0, 3.0));
    assert_eq!(b.triangles.len(), 12);
    assert_eq!(b.bounds().extent(), Vec3::new(1.0, 2.0, 3.0));
    let p = generators::plane(glam::Vec2::new(2.0, 4.0), 3);
    assert_eq!(p.triangles.len(), 18);
    assert!(p.normals.iter().all(|n| *n == Vec3::Y));
}
