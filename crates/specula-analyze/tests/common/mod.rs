//! Scenes the lens tests share: a lens before a camera that looks through it as the wearer.

use glam::{Mat4, Vec3};
use specula_scene::spectacle::spectacle_lens;
use specula_scene::{Camera, Material, MaterialKind, Mesh, Prescription, Scene};

/// `lens` (its own frame: light along +Z, back vertex at z = `thickness`) before a camera
/// 12 mm behind the back vertex looking along −Z, placed by `world_from_lens`.
pub fn scene_of(mut lens: Mesh, n: f64, thickness: f64, world_from_lens: Mat4) -> Scene {
    let mut scene = Scene::new("lens standards");
    let n = n as f32;
    scene.materials.push(Material::new(
        "glass",
        MaterialKind::Dielectric {
            ior: Vec3::new(n - 0.01, n, n + 0.01),
            thin_walled: false,
        },
        Vec3::ONE,
    ));
    lens.name = "lens".into();
    lens.material = 0;
    lens.transform(world_from_lens);
    scene.meshes.push(lens);
    scene.camera = Camera {
        eye: Vec3::new(0.0, 0.0, thickness as f32 + 0.012),
        target: Vec3::new(0.0, 0.0, -1.0),
        up: Vec3::Y,
        fov_y_deg: 50.0,
        aspect: None,
    };
    scene
}

/// `p`'s lens placed by `world_from_lens`, the prescription kept for the analysis.
pub fn spectacles(p: &Prescription, world_from_lens: Mat4) -> Scene {
    let mut scene = scene_of(
        spectacle_lens(p, 24, 96).unwrap(),
        p.index,
        p.center_thickness,
        world_from_lens,
    );
    scene.prescriptions.push(("lens".into(), p.clone()));
    scene
}
