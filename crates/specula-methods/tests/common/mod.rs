//! Helpers shared by the method tests: small hand-built scenes and the CPU reference.
// Each test binary uses a different subset.
#![allow(dead_code)]

use glam::{Mat4, Vec2, Vec3};
use specula_scene::{generators, Background, Camera, Material, Mesh, Scene};
use specula_trace::{render, Image, RenderSettings, SceneAccel};

/// The CPU reference at one sample per pixel.
pub fn cpu_reference(scene: &Scene, width: u32, height: u32, max_depth: u32) -> Image {
    render(
        scene,
        &SceneAccel::new(scene),
        &RenderSettings {
            width,
            height,
            spp: 1,
            max_depth,
        },
        &|_, _| {},
    )
}

/// A scene of `objects` (mesh, material, world_from_object) seen by `camera`.
pub fn scene(
    objects: Vec<(Mesh, Material, Mat4)>,
    background: Background,
    camera: Camera,
) -> Scene {
    let mut s = Scene::new("test");
    s.camera = camera;
    s.background = background;
    for (mut mesh, material, world_from_object) in objects {
        mesh.transform(world_from_object);
        mesh.material = s.materials.len();
        s.materials.push(material);
        s.meshes.push(mesh);
    }
    s
}

pub fn looking_down_z(fov_y_deg: f32) -> Camera {
    Camera {
        eye: Vec3::new(0.0, 0.0, 5.0),
        target: Vec3::ZERO,
        up: Vec3::Y,
        fov_y_deg,
        aspect: None,
    }
}

/// A wall facing +Z at z = 0.
pub fn wall(size: f32) -> (Mesh, Mat4) {
    (
        generators::plane(Vec2::splat(size), 1),
        Mat4::from_rotation_x(std::f32::consts::FRAC_PI_2),
    )
}

/// A right-angle glass prism (legs 1 m along X and Z, 1 m tall along Y), its right angle at
/// (0.5, ·, 0.5): a ray going −Z enters the top leg face at normal incidence, meets the
/// hypotenuse at 45° and, past the critical angle, is turned to +X, leaving through the other
/// leg at normal incidence.
pub fn prism() -> Mesh {
    let corners = [(-0.5, 0.5), (0.5, 0.5), (0.5, -0.5)];
    let positions: Vec<Vec3> = [-0.5f32, 0.5]
        .iter()
        .flat_map(|&y| corners.map(|(x, z)| Vec3::new(x, y, z)))
        .collect();
    let mut triangles = vec![[0u32, 1, 2], [3, 4, 5]];
    for (a, b) in [(0u32, 1u32), (1, 2), (2, 0)] {
        triangles.push([a, b, b + 3]);
        triangles.push([a, b + 3, a + 3]);
    }
    let centroid = positions.iter().sum::<Vec3>() / positions.len() as f32;
    for t in &mut triangles {
        let [p0, p1, p2] = t.map(|i| positions[i as usize]);
        if (p1 - p0)
            .cross(p2 - p0)
            .dot((p0 + p1 + p2) / 3.0 - centroid)
            < 0.0
        {
            t.swap(1, 2);
        }
    }
    let mut mesh = Mesh {
        exact: None,
        cad: None,
        name: "prism".into(),
        positions,
        normals: Vec::new(),
        uvs: Vec::new(),
        triangles,
        material: 0,
    };
    mesh.make_flat();
    mesh
}
