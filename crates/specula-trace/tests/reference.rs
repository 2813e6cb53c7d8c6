//! The reference renderer's shading against closed-form answers, one material at a time.

use glam::{Mat4, Vec2, Vec3};
use specula_scene::generators;
use specula_scene::{Background, Camera, Light, Material, MaterialKind, Mesh, Scene, Texture};
use specula_trace::reference::pixel_samples;
use specula_trace::{render, Image, RenderSettings, SceneAccel};

fn scene(objects: Vec<(Mesh, Material, Mat4)>, background: Background, camera: Camera) -> Scene {
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

fn looking_down_z(fov_y_deg: f32) -> Camera {
    Camera {
        eye: Vec3::new(0.0, 0.0, 5.0),
        target: Vec3::ZERO,
        up: Vec3::Y,
        fov_y_deg,
        aspect: None,
    }
}

fn render_small(scene: &Scene, size: u32, max_depth: u32) -> Image {
    let accel = SceneAccel::new(scene);
    let settings = RenderSettings {
        width: size,
        height: size,
        spp: 1,
        max_depth,
    };
    render(scene, &accel, &settings, &|_, _| {})
}

/// A wall facing +Z at z = 0.
fn wall(size: f32) -> (Mesh, Mat4) {
    (
        generators::plane(Vec2::splat(size), 1),
        Mat4::from_rotation_x(std::f32::consts::FRAC_PI_2),
    )
}

#[test]
fn lambertian_wall_under_a_point_light_matches_albedo_over_pi_times_irradiance() {
    let (mesh, m) = wall(4.0);
    let mut s = scene(
        vec![(
            mesh,
            Material::diffuse("wall", Vec3::new(0.5, 0.25, 1.0)),
            m,
        )],
        Background::Color(Vec3::ZERO),
        looking_down_z(10.0),
    );
    let light_at = Vec3::new(0.0, 0.0, 2.0);
    s.lights.push(Light::Point {
        position: light_at,
        intensity: Vec3::splat(8.0),
    });
    s.ambient = Vec3::splat(0.1);
    let image = render_small(&s, 9, 8);
    // The centre pixel's ray hits the wall at the origin, straight below the light.
    let expected = Vec3::new(0.5, 0.25, 1.0) * (8.0 / 4.0 / std::f32::consts::PI + 0.1);
    assert!(
        (image.get(4, 4) - expected).length() < 1e-4,
        "{:?} vs {expected:?}",
        image.get(4, 4)
    );
}

#[test]
fn hard_shadows_block_the_light() {
    let (mesh, m) = wall(4.0);
    let blocker = generators::cuboid(Vec3::splat(0.2));
    let mut s = scene(
        vec![
            (mesh, Material::diffuse("wall", Vec3::ONE), m),
            (
                blocker,
                Material::diffuse("blocker", Vec3::ONE),
                Mat4::from_translation(Vec3::new(0.0, 1.0, 1.0)),
            ),
        ],
        Background::Color(Vec3::ZERO),
        looking_down_z(10.0),
    );
    s.lights.push(Light::Point {
        position: Vec3::new(0.0, 2.0, 2.0),
        intensity: Vec3::splat(8.0),
    });
    let image = render_small(&s, 9, 8);
    assert_eq!(
        image.get(4, 4),
        Vec3::ZERO,
        "the cube shades the wall point below it"
    );
}

#[test]
fn mirror_without_fresnel_reflects_exactly_f0_times_what_it_sees() {
    let (mesh, m) = wall(4.0);
    let f0 = Vec3::new(0.9, 0.5, 0.2);
    let material = Material::new("mirror", MaterialKind::Mirror { fresnel: false }, f0);
    let s = scene(
        vec![(mesh, material, m)],
        Background::Color(Vec3::new(0.2, 0.4, 0.8)),
        looking_down_z(10.0),
    );
    let image = render_small(&s, 5, 8);
    assert!((image.get(2, 2) - f0 * Vec3::new(0.2, 0.4, 0.8)).length() < 1e-6);
    assert_eq!(
        render_small(&s, 5, 0).get(2, 2),
        Vec3::ZERO,
        "max depth 0 follows no bounce"
    );
}

#[test]
fn glass_slab_at_normal_incidence_transmits_t_squared_over_one_minus_r_squared() {
    let (backdrop, m) = wall(20.0);
    let slab = generators::cuboid(Vec3::new(3.0, 3.0, 0.5));
    let s = scene(
        vec![
            (
                backdrop,
                Material::unlit("white", Vec3::ONE),
                Mat4::from_translation(Vec3::new(0.0, 0.0, -3.0)) * m,
            ),
            (
                slab,
                Material::glass("glass", 1.5),
                Mat4::from_translation(Vec3::new(0.0, 0.0, 1.0)),
            ),
        ],
        Background::Color(Vec3::ZERO),
        looking_down_z(5.0),
    );
    // Incoherent sum over internal reflections: T² (1 + R² + R⁴ + …) = T² / (1 − R²); the
    // depth limit of 8 cuts the series after R⁶, below 1e-8.
    let (r, t) = (0.04f32, 0.96f32);
    let expected = t * t / (1.0 - r * r);
    let got = render_small(&s, 5, 8).get(2, 2);
    assert!(
        (got - Vec3::splat(expected)).abs().max_element() < 1e-4,
        "{got:?} vs {expected}"
    );
}

#[test]
fn dispersion_splits_colours_and_plain_glass_does_not() {
    // A sphere in front of a half-white, half-black backdrop: refraction bends the edge.
    let backdrop = Texture::procedural("edge", 64, 64, |uv| {
        if uv.x < 0.5 {
            Vec3::ONE
        } else {
            Vec3::ZERO
        }
    });
    let render_with = |ior: Vec3| {
        let (mesh, m) = wall(6.0);
        let mut s = scene(
            vec![
                (
                    mesh,
                    Material::unlit("edge", Vec3::ONE),
                    Mat4::from_translation(Vec3::new(0.0, 0.0, -2.0)) * m,
                ),
                (
                    generators::sphere(1.0, 96, 48),
                    Material::new(
                        "glass",
                        MaterialKind::Dielectric {
                            ior,
                            thin_walled: false,
                        },
                        Vec3::ONE,
                    ),
                    Mat4::IDENTITY,
                ),
            ],
            Background::Color(Vec3::ZERO),
            looking_down_z(30.0),
        );
        s.textures.push(backdrop.clone());
        s.materials[0].texture = Some(0);
        render_small(&s, 48, 8)
    };
    let plain = render_with(Vec3::splat(1.5));
    assert!(
        plain.pixels.iter().all(|p| (p.x - p.z).abs() < 1e-6),
        "no colour without dispersion"
    );
    let dispersive = render_with(Vec3::new(1.45, 1.5, 1.6));
    let fringe = dispersive
        .pixels
        .iter()
        .map(|p| (p.x - p.z).abs())
        .fold(0.0, f32::max);
    assert!(
        fringe > 0.2,
        "dispersion gives colour fringes (largest R−B {fringe})"
    );
}

#[test]
fn equirectangular_background_maps_directions_as_documented() {
    // A sky whose colour is its own texture coordinate, (u, v, 0): bilinear lookups of a
    // linear function are exact, so each direction's (u, v) can be read back.
    let sky = Texture::procedural("sky", 360, 180, |uv| Vec3::new(uv.x, uv.y, 0.0));
    let mut s = scene(
        vec![],
        Background::Equirect {
            texture: 0,
            intensity: 2.0,
        },
        looking_down_z(1.0),
    );
    s.textures.push(sky);
    // Looking down −Z: the image centre, u = 0.5, on the horizon, v = 0.5.
    let centre = render_small(&s, 3, 1).get(1, 1) / 2.0;
    assert!(
        (centre - Vec3::new(0.5, 0.5, 0.0)).length() < 1e-3,
        "{centre:?}"
    );
    // Looking towards −X: u = 0.25; looking up 45°: v = 0.25.
    s.camera.target = s.camera.eye + Vec3::new(-1.0, 0.0, 0.0);
    let left = render_small(&s, 3, 1).get(1, 1) / 2.0;
    assert!(
        (left - Vec3::new(0.25, 0.5, 0.0)).length() < 1e-3,
        "{left:?}"
    );
    s.camera.target = s.camera.eye + Vec3::new(0.0, 1.0, -1.0);
    let up = render_small(&s, 3, 1).get(1, 1) / 2.0;
    assert!((up - Vec3::new(0.5, 0.25, 0.0)).length() < 1e-3, "{up:?}");
}

#[test]
fn one_sample_is_the_pixel_centre_and_more_are_stratified_in_both_axes() {
    assert_eq!(pixel_samples(3, 7, 1), vec![Vec2::splat(0.5)]);
    for spp in [2u32, 5, 16] {
        let samples = pixel_samples(3, 7, spp);
        assert_eq!(samples.len(), spp as usize);
        for axis in 0..2 {
            let mut strata: Vec<u32> = samples
                .iter()
                .map(|s| (s[axis] * spp as f32) as u32)
                .collect();
            strata.sort();
            assert_eq!(
                strata,
                (0..spp).collect::<Vec<_>>(),
                "one sample per stratum"
            );
        }
        assert_eq!(samples, pixel_samples(3, 7, spp), "deterministic");
    }
}

#[test]
fn thin_sheet_transmits_like_a_thick_slab_at_normal_incidence() {
    // A sheet's 2R/(1+R) reflectance leaves (1−R)/(1+R) = T²/(1−R²) transmitted: the same as
    // the slab above, with no thickness.
    let (backdrop, m) = wall(20.0);
    let (sheet, sheet_m) = wall(3.0);
    let thin = Material::new(
        "sheet",
        MaterialKind::Dielectric {
            ior: Vec3::splat(1.5),
            thin_walled: true,
        },
        Vec3::ONE,
    );
    let s = scene(
        vec![
            (
                backdrop,
                Material::unlit("white", Vec3::ONE),
                Mat4::from_translation(Vec3::new(0.0, 0.0, -3.0)) * m,
            ),
            (
                sheet,
                thin,
                Mat4::from_translation(Vec3::new(0.0, 0.0, 1.0)) * sheet_m,
            ),
        ],
        Background::Color(Vec3::ZERO),
        looking_down_z(5.0),
    );
    let expected = 0.96f32 / 1.04;
    let got = render_small(&s, 5, 8).get(2, 2);
    assert!(
        (got - Vec3::splat(expected)).abs().max_element() < 1e-5,
        "{got:?} vs {expected}"
    );
}
