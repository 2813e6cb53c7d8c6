//! A whole reference image against an independent oracle: every pixel of a scene whose light
//! can be written in closed form, computed here without the renderer (analytic rays against
//! the objects' planes, this file's own Fresnel formula, the glass slab's paths summed up to
//! the renderer's depth limit). The scene: a tilted glass slab (a box), a tilted mirror
//! (constant F0) and a diffuse square under a directional light, side by side before an
//! equirectangular sky, so that every reflected and transmitted ray sees only the sky and no
//! surface shadows another.
//!
//! (This replaces golden images that were the renderer's own earlier output.)

use glam::{Mat4, Vec2, Vec3};
use specula_scene::{generators, Background, Camera, Light, Material, MaterialKind, Scene};
use specula_scene::{Mesh, Texture};
use specula_trace::{render, RenderSettings, SceneAccel};

const SIZE: u32 = 96;
const MAX_DEPTH: u32 = 8;
const IOR: f32 = 1.5;

/// Unpolarised Fresnel reflectance for a ray meeting an interface at `cos_i` from a medium of
/// index `n1` into `n2` (1 under total internal reflection), written out from the Fresnel
/// equations.
fn fresnel(cos_i: f32, n1: f32, n2: f32) -> f32 {
    let sin_t = n1 / n2 * (1.0 - cos_i * cos_i).max(0.0).sqrt();
    if sin_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin_t * sin_t).sqrt();
    let rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
    let rp = (n2 * cos_i - n1 * cos_t) / (n2 * cos_i + n1 * cos_t);
    0.5 * (rs * rs + rp * rp)
}

/// A flat rectangle: centre, unit normal, two unit edge directions and half sizes.
struct Rect {
    centre: Vec3,
    normal: Vec3,
    axes: [Vec3; 2],
    half: [f32; 2],
}

impl Rect {
    /// The ray parameter where `origin + t dir` meets the rectangle at least `margin` inside
    /// its edges; `Err(())` where it meets the rectangle's plane within `margin` of an edge (a
    /// pixel this test skips), `Ok(None)` where it misses.
    fn hit(&self, origin: Vec3, dir: Vec3, margin: f32) -> Result<Option<f32>, ()> {
        let denominator = dir.dot(self.normal);
        if denominator.abs() < 1e-6 {
            return Ok(None);
        }
        let t = (self.centre - origin).dot(self.normal) / denominator;
        if t <= 0.0 {
            return Ok(None);
        }
        let local = origin + dir * t - self.centre;
        let (a, b) = (local.dot(self.axes[0]).abs(), local.dot(self.axes[1]).abs());
        if a > self.half[0] + margin || b > self.half[1] + margin {
            Ok(None)
        } else if a > self.half[0] - margin || b > self.half[1] - margin {
            Err(())
        } else {
            Ok(Some(t))
        }
    }
}

fn rect(world_from_object: Mat4, size: Vec2) -> Rect {
    // generators::plane lies in XZ facing +Y.
    Rect {
        centre: world_from_object.transform_point3(Vec3::ZERO),
        normal: world_from_object.transform_vector3(Vec3::Y).normalize(),
        axes: [
            world_from_object.transform_vector3(Vec3::X).normalize(),
            world_from_object.transform_vector3(Vec3::Z).normalize(),
        ],
        half: [size.x * 0.5, size.y * 0.5],
    }
}

fn sky() -> Texture {
    Texture::procedural("sky", 128, 64, |uv| {
        Vec3::new(
            0.2 + 0.7 * uv.x,
            0.9 - 0.7 * uv.y,
            0.3 + 0.4 * (uv.x * 6.0).sin().abs(),
        )
    })
}

/// The light a parallel glass slab sends back along a ray that meets its face at `cos_i`,
/// towards `sky(transmitted)` and `sky(reflected)`: every path of reflections and
/// refractions, as far as the renderer follows them (a hit at depth `MAX_DEPTH` gives 0).
/// `depth` is the depth of the next surface hit; `inside` whether it is met from inside.
fn slab(depth: u32, inside: bool, front: bool, r: f32, sky: [Vec3; 2]) -> Vec3 {
    if depth >= MAX_DEPTH {
        return Vec3::ZERO;
    }
    let [transmitted, reflected] = sky;
    if !inside {
        // The front face from outside: reflect to the sky, or enter towards the back face.
        return r * reflected + (1.0 - r) * slab(depth + 1, true, false, r, sky);
    }
    // Inside: leave (through the back: the transmitted direction; through the front: the
    // reflected one), or reflect towards the other face.
    let leaving = if front { reflected } else { transmitted };
    (1.0 - r) * leaving + r * slab(depth + 1, true, !front, r, sky)
}

#[test]
fn the_reference_image_matches_a_closed_form_pixel_for_pixel() {
    let mut scene = Scene::new("closed form");
    scene.camera = Camera {
        eye: Vec3::ZERO,
        target: Vec3::new(0.0, 0.0, -1.0),
        up: Vec3::Y,
        fov_y_deg: 50.0,
        aspect: None,
    };
    scene.textures.push(sky());
    scene.background = Background::Equirect {
        texture: 0,
        intensity: 1.0,
    };
    let irradiance = Vec3::new(2.0, 1.8, 1.5);
    let to_light = Vec3::new(0.2, 0.4, 1.0).normalize();
    scene.lights.push(Light::Directional {
        direction: -to_light,
        irradiance,
    });
    scene.ambient = Vec3::splat(0.05);
    let mut add = |mesh: Mesh, material: Material, world_from_object: Mat4| {
        let mut mesh = mesh;
        mesh.transform(world_from_object);
        mesh.material = scene.materials.len();
        scene.materials.push(material);
        scene.meshes.push(mesh);
    };
    // The slab: 0.7 × 0.7 × 0.04 m, turned 25° about Y and 10° about X.
    let thickness = 0.04;
    let slab_pose = Mat4::from_translation(Vec3::new(-0.45, 0.0, -2.5))
        * Mat4::from_rotation_y(25f32.to_radians())
        * Mat4::from_rotation_x(10f32.to_radians());
    add(
        generators::cuboid(Vec3::new(0.7, 0.7, thickness)),
        Material::new(
            "glass",
            MaterialKind::Dielectric {
                ior: Vec3::splat(IOR),
                thin_walled: false,
            },
            Vec3::ONE,
        ),
        slab_pose,
    );
    // The mirror: 0.5 m square facing the eye, tilted.
    let f0 = Vec3::new(0.9, 0.75, 0.6);
    let mirror_pose = Mat4::from_translation(Vec3::new(0.4, 0.3, -2.5))
        * Mat4::from_rotation_y(-20f32.to_radians())
        * Mat4::from_rotation_x(75f32.to_radians());
    add(
        generators::plane(Vec2::splat(0.5), 1),
        Material::new("mirror", MaterialKind::Mirror { fresnel: false }, f0),
        mirror_pose,
    );
    // The diffuse square below it.
    let albedo = Vec3::new(0.6, 0.5, 0.4);
    let diffuse_pose = Mat4::from_translation(Vec3::new(0.4, -0.35, -2.5))
        * Mat4::from_rotation_y(-15f32.to_radians())
        * Mat4::from_rotation_x(80f32.to_radians());
    add(
        generators::plane(Vec2::splat(0.5), 1),
        Material::diffuse("paper", albedo),
        diffuse_pose,
    );
    scene.finalize("closed form").unwrap();

    let accel = SceneAccel::new(&scene);
    let settings = RenderSettings {
        width: SIZE,
        height: SIZE,
        spp: 1,
        max_depth: MAX_DEPTH,
    };
    let image = render(&scene, &accel, &settings, &|_, _| {});

    let sky_of = |d: Vec3| scene.background.radiance(d, &scene.textures);
    // The slab's front face (the box's +Z face before the pose) and the two squares.
    let front = Rect {
        centre: slab_pose.transform_point3(Vec3::new(0.0, 0.0, thickness * 0.5)),
        normal: slab_pose.transform_vector3(Vec3::Z).normalize(),
        axes: [
            slab_pose.transform_vector3(Vec3::X).normalize(),
            slab_pose.transform_vector3(Vec3::Y).normalize(),
        ],
        half: [0.35, 0.35],
    };
    let mirror = rect(mirror_pose, Vec2::splat(0.5));
    let paper = rect(diffuse_pose, Vec2::splat(0.5));
    // Inside the slab a path drifts sideways; its weight after the few reflections that could
    // reach the rim from 8 cm in is below 1e-4.
    let margins = [0.08, 0.01, 0.01];
    let (mut checked, mut worst, mut sum) = ([0usize; 3], [0.0f32; 3], [0.0f32; 3]);
    for y in 0..SIZE {
        for x in 0..SIZE {
            let d = scene
                .camera
                .ray_direction(x as f32 + 0.5, y as f32 + 0.5, SIZE, SIZE);
            let mut expected = None;
            let mut skip = false;
            for (k, surface) in [&front, &mirror, &paper].into_iter().enumerate() {
                match surface.hit(Vec3::ZERO, d, margins[k]) {
                    Err(()) => skip = true,
                    Ok(Some(_)) => {
                        let n = if d.dot(surface.normal) < 0.0 {
                            surface.normal
                        } else {
                            -surface.normal
                        };
                        let cos_i = -d.dot(n);
                        let reflected = d + 2.0 * cos_i * n;
                        expected = Some((
                            k,
                            match k {
                                0 => slab(
                                    0,
                                    false,
                                    true,
                                    fresnel(cos_i, 1.0, IOR),
                                    [sky_of(d), sky_of(reflected)],
                                ),
                                1 => f0 * sky_of(reflected),
                                _ => {
                                    let cos_light = surface.normal.dot(to_light).max(0.0);
                                    albedo
                                        * (irradiance * cos_light / std::f32::consts::PI
                                            + scene.ambient)
                                }
                            },
                        ));
                    }
                    Ok(None) => {}
                }
            }
            if skip {
                continue;
            }
            let (k, expected) = expected.unwrap_or((3, sky_of(d)));
            if k == 3 {
                continue;
            }
            let error = (image.get(x, y) - expected).abs().max_element();
            checked[k] += 1;
            worst[k] = worst[k].max(error);
            sum[k] += error;
        }
    }
    eprintln!(
        "closed form: pixels checked (slab, mirror, diffuse) {checked:?}, largest errors {worst:?}, mean {:?}",
        [0, 1, 2].map(|k| sum[k] / checked[k].max(1) as f32)
    );
    for (k, name) in ["slab", "mirror", "diffuse"].into_iter().enumerate() {
        assert!(checked[k] > 150, "{name}: only {} pixels", checked[k]);
    }
    // Measured 2026-11-30: largest errors 1.8e-7, 1.8e-7, 3.0e-8 (float rounding; the
    // eprintln above); bounds 2x.
    for (k, name) in ["slab", "mirror", "diffuse"].into_iter().enumerate() {
        assert!(
            worst[k] < MAX_ERROR[k],
            "{name}: largest error {}",
            worst[k]
        );
    }
}

/// Largest per-pixel error (radiance) for the slab, the mirror and the diffuse square.
const MAX_ERROR: [f32; 3] = [3.6e-7, 3.6e-7, 6.0e-8];
