//! `image-space` (Wyman): d_N and the fitted planes against closed forms, total internal
//! reflection followed (and, by the `paper` preset, not), and every built-in scene with a
//! refractor rendered. Its accuracy against the reference (FLIP) is held in specula-compare's
//! tests.

mod common;

use common::{cpu_reference, looking_down_z, prism, scene};
use glam::{Mat4, Vec2, Vec3};
use specula_core::GpuMethod;
use specula_methods::image_space::{
    fit_planes, nearby_visibility, normal_distances, ImageSpace, NearbyMode, NearbyVisibility,
};
use specula_methods::{apply_setting, Label, RenderStill, Still, Technique};
use specula_scene::{generators, Background, Material, Scene};
use specula_trace::SceneAccel;

#[test]
fn normal_distances_cross_a_sphere_and_ignore_what_is_inside() {
    // A glass sphere of radius 0.5 with a small mirror ball inside: the inverted normal meets
    // the far side after a diameter, passing through the ball.
    let mut s = scene(
        vec![
            (
                generators::sphere(0.5, 48, 24),
                Material::glass("glass", 1.5),
                Mat4::IDENTITY,
            ),
            (
                generators::sphere(0.1, 16, 8),
                Material::mirror("inside", Vec3::ONE),
                Mat4::IDENTITY,
            ),
        ],
        Background::Color(Vec3::ZERO),
        looking_down_z(30.0),
    );
    s.finalize("test").unwrap();
    let distances = normal_distances(&s, &SceneAccel::new(&s));
    assert_eq!(distances[0].len(), 3 * s.meshes[0].triangles.len());
    assert!(distances[1].is_empty(), "a mirror has no d_N");
    // Each vertex's normal points through the centre at the antipodal vertex: a diameter, to
    // float rounding (measured 2.4e-7 at worst; the bound allows a few times that).
    for &d in &distances[0] {
        assert!((d - 1.0).abs() < 1e-6, "d_N {d}");
    }
}

#[test]
fn planes_fitted_to_a_room_are_its_walls_and_a_ball_faces_the_eye() {
    let mut s = scene(
        vec![
            (
                generators::cuboid(Vec3::new(4.0, 2.0, 6.0)),
                Material::diffuse("room", Vec3::ONE),
                Mat4::IDENTITY,
            ),
            (
                generators::sphere(0.3, 24, 12),
                Material::diffuse("ball", Vec3::ONE),
                Mat4::from_translation(Vec3::new(1.0, 0.0, 0.0)),
            ),
        ],
        Background::Color(Vec3::ZERO),
        looking_down_z(30.0),
    );
    s.finalize("test").unwrap();
    let planes = fit_planes(&s);
    // Six walls (areas 24, 24, 12, 12, 8, 8 m²) and the ball's eye-facing disc (1.13 m²).
    assert_eq!(planes.len(), 7, "{planes:?}");
    for wall in &planes[..6] {
        let n = Vec3::from_array(wall.normal);
        assert!((n.length() - 1.0).abs() < 1e-5);
        let axis = n.abs().max_element();
        assert!((axis - 1.0).abs() < 1e-5, "a wall's normal is an axis: {n}");
        let half = Vec3::new(2.0, 1.0, 3.0).dot(n.abs());
        assert!((wall.offset.abs() - half).abs() < 1e-4, "{wall:?}");
    }
    let ball = planes[6];
    assert_eq!(ball.normal, [0.0; 3]);
    assert!(Vec3::from_array(ball.center).distance(Vec3::new(1.0, 0.0, 0.0)) < 1e-4);
    assert!(
        (ball.radius - 0.3 * 3f32.sqrt()).abs() < 0.01,
        "{}",
        ball.radius
    );
}

/// The right-angle prism of the closed-form tests: rays entering its top leg meet the
/// hypotenuse at 45°, past the critical angle at n = 1.5, and turn to +X, towards a white panel;
/// behind the prism a red wall, which a refraction through the hypotenuse would show. Only the
/// panel and the wall are lit (unlit materials, black background).
fn prism_before_a_panel_and_a_red_wall() -> Scene {
    let panel = (
        generators::plane(Vec2::splat(6.0), 1),
        Material::unlit("panel", Vec3::ONE),
        Mat4::from_translation(Vec3::new(3.0, 0.0, 0.0))
            * Mat4::from_rotation_z(std::f32::consts::FRAC_PI_2),
    );
    let wall = (
        generators::plane(Vec2::splat(20.0), 1),
        Material::unlit("red wall", Vec3::new(1.0, 0.0, 0.0)),
        Mat4::from_translation(Vec3::new(0.0, 0.0, -3.0))
            * Mat4::from_rotation_x(std::f32::consts::FRAC_PI_2),
    );
    let mut s = scene(
        vec![
            panel,
            wall,
            (prism(), Material::glass("prism", 1.5), Mat4::IDENTITY),
        ],
        Background::Color(Vec3::ZERO),
        looking_down_z(14.0),
    );
    s.finalize("test").unwrap();
    s
}

/// The pixels the reference shows as internally reflected in the prism scene (the white panel
/// seen through the prism: white-ish, little red).
fn internally_reflected_pixels(s: &Scene, width: u32, height: u32) -> Vec<usize> {
    let reference = cpu_reference(s, width, height, 8);
    let pixels: Vec<usize> = (0..reference.pixels.len())
        .filter(|&i| reference.pixels[i].z > 0.5)
        .collect();
    assert!(pixels.len() > 100, "{} TIR pixels", pixels.len());
    pixels
}

/// How many of `pixels` show the white panel.
fn showing_the_panel(still: &Still, pixels: &[usize]) -> usize {
    pixels
        .iter()
        .filter(|&&i| {
            let p = still.image.pixels[i];
            p.z > 0.5 && p.x - p.z < 0.3
        })
        .count()
}

fn counter(still: &Still, name: &str) -> u64 {
    still
        .counters
        .iter()
        .find(|(n, _)| n == name)
        .unwrap_or_else(|| panic!("no counter {name}"))
        .1
}

#[test]
fn total_internal_reflection_is_followed_not_refracted() {
    let Some(ctx) = specula_methods::test_context("image-space TIR") else {
        return;
    };
    let s = prism_before_a_panel_and_a_red_wall();
    let (w, h) = (48, 48);
    let tir_pixels = internally_reflected_pixels(&s, w, h);
    let mut technique = ImageSpace::new(NearbyMode::Iterative);
    let still = technique.render_still(&ctx, &s, w, h).unwrap();
    assert!(
        counter(&still, "total internal reflections followed") > 0,
        "no TIR detected"
    );
    let shown_reflected = showing_the_panel(&still, &tir_pixels);
    let share = shown_reflected as f64 / tir_pixels.len() as f64;
    println!(
        "{shown_reflected} of {} TIR pixels show the panel",
        tir_pixels.len()
    );
    // Measured 1536 of 1640 (0.937): 6.3 % missed; the bound allows twice that.
    assert!(
        share > 0.87,
        "only {share:.2} of the TIR pixels show the panel"
    );
}

#[test]
fn every_builtin_scene_with_a_refractor_renders_in_every_mode() {
    let Some(ctx) = specula_methods::test_context("image-space built-ins") else {
        return;
    };
    for name in ["spectacle-lens", "glass-dragon", "truck-cover"] {
        let scene = specula_scene::load(name).unwrap();
        for mode in ["kay-greenberg", "ray-plane", "iterative"] {
            let mut technique = GpuMethod::<ImageSpace>::default();
            apply_setting(&mut technique, &format!("mode={mode}")).unwrap();
            let still = technique.render_still(&ctx, &scene, 64, 48).unwrap();
            assert!(
                still.image.pixels.iter().all(|p| p.is_finite()),
                "{name} {mode}"
            );
            assert_eq!(technique.parameter("mode"), mode);
        }
    }
}

#[test]
fn bad_parameters_name_the_parameter_and_the_range() {
    let mut technique = GpuMethod::<ImageSpace>::default();
    for (setting, words) in [
        ("mode=raymarch", &["mode", "kay-greenberg", "iterative"][..]),
        ("seeds=0", &["seeds", "1"][..]),
        ("index=-1", &["index"][..]),
        ("texture_scale=9", &["texture_scale"][..]),
    ] {
        let message = apply_setting(&mut technique, setting)
            .unwrap_err()
            .to_string();
        for word in words {
            assert!(message.contains(word), "{setting}: {message}");
        }
    }
}

#[test]
fn a_refractor_alone_before_the_background_renders_with_every_option() {
    let Some(ctx) = specula_methods::test_context("image-space alone") else {
        return;
    };
    // No nearby geometry at all: no NG texels, no planes; every ray takes the cube map.
    let mut s = scene(
        vec![(
            generators::sphere(0.5, 32, 16),
            Material::glass("glass", 1.5),
            Mat4::IDENTITY,
        )],
        Background::Color(Vec3::new(0.2, 0.4, 0.8)),
        looking_down_z(20.0),
    );
    s.finalize("test").unwrap();
    for setting in [
        "mode=kay-greenberg",
        "mode=ray-plane",
        "layers=3",
        "parallax=false",
    ] {
        let mut technique = GpuMethod::<ImageSpace>::default();
        apply_setting(&mut technique, setting).unwrap();
        let still = technique.render_still(&ctx, &s, 32, 32).unwrap();
        let centre = still.image.get(16, 16);
        // Only the background's colour can come through (attenuated by Fresnel).
        assert!(
            centre.is_finite() && centre.z > 0.5 && centre.z > centre.x,
            "{setting}: {centre}"
        );
    }
}

#[test]
fn nearby_visibility_counts_surfaces_hidden_from_the_eye() {
    // A glass ball before a wall, with a small box between ball and wall off the axis: rays the
    // ball bends across the axis pass beside the box to wall points behind it, which the eye
    // cannot see.
    let wall = (
        generators::plane(Vec2::splat(20.0), 1),
        Material::diffuse("wall", Vec3::ONE),
        Mat4::from_translation(Vec3::new(0.0, 0.0, -2.0))
            * Mat4::from_rotation_x(std::f32::consts::FRAC_PI_2),
    );
    let ball = (
        generators::sphere(0.5, 32, 16),
        Material::glass("glass", 1.5),
        Mat4::from_translation(Vec3::new(0.0, 0.0, 1.0)),
    );
    let mut open = scene(
        vec![wall.clone(), ball.clone()],
        Background::Color(Vec3::ZERO),
        looking_down_z(20.0),
    );
    open.finalize("test").unwrap();
    let figures = nearby_visibility(&open, &SceneAccel::new(&open), 64, 64);
    assert!(figures.refractor_pixels > 500, "{figures:?}");
    assert_eq!(
        figures.hidden_from_eye, 0,
        "nothing hides the wall: {figures:?}"
    );
    let mut hidden = scene(
        vec![
            wall,
            ball,
            (
                generators::cuboid(Vec3::splat(0.4)),
                Material::diffuse("box", Vec3::ONE),
                Mat4::from_translation(Vec3::new(0.6, 0.0, -1.0)),
            ),
        ],
        Background::Color(Vec3::ZERO),
        looking_down_z(20.0),
    );
    hidden.finalize("test").unwrap();
    let NearbyVisibility {
        refractor_pixels,
        reaching_nearby_geometry,
        hidden_from_eye,
    } = nearby_visibility(&hidden, &SceneAccel::new(&hidden), 64, 64);
    println!(
        "{hidden_from_eye} of {reaching_nearby_geometry} ({refractor_pixels} refractor pixels)"
    );
    assert!(hidden_from_eye > 0 && hidden_from_eye < reaching_nearby_geometry);
}

/// The paper's fourth limitation measured on the scenes with a refractor and nearby geometry
/// (docs/methods/image-space.md quotes these figures: `cargo test -p specula-methods --test image_space
/// visibility_on_the_scenes -- --nocapture`).
#[test]
fn visibility_on_the_scenes() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
    let mut names = vec!["glass-dragon".to_string(), "truck-cover".to_string()];
    for file in [
        "table1/sphere-dragon.toml",
        "table1/bunny-dragon.toml",
        "table1/sphere-plane.toml",
        "suite/glass-sphere.toml",
        "suite/glass-lens.toml",
    ] {
        names.push(root.join(file).to_string_lossy().into_owned());
    }
    for name in names {
        let s = specula_scene::load(&name).unwrap();
        let v = nearby_visibility(&s, &SceneAccel::new(&s), 160, 120);
        println!(
            "{}: {} refractor pixels, {} reach nearby geometry, {} of them hidden from the eye ({:.1} %)",
            s.name,
            v.refractor_pixels,
            v.reaching_nearby_geometry,
            v.hidden_from_eye,
            100.0 * v.hidden_from_eye as f64 / v.reaching_nearby_geometry.max(1) as f64
        );
        assert!(v.hidden_from_eye <= v.reaching_nearby_geometry);
        assert!(v.reaching_nearby_geometry <= v.refractor_pixels);
    }
}

#[test]
fn the_table1_and_figure11_scenes_load_and_render() {
    let Some(ctx) = specula_methods::test_context("image-space paper scenes") else {
        return;
    };
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
    for folder in ["table1", "figure11"] {
        let mut files: Vec<_> = std::fs::read_dir(root.join(folder))
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|x| x == "toml"))
            .collect();
        files.sort();
        assert!(files.len() >= 4, "{folder}: {files:?}");
        for file in files {
            let scene = specula_scene::load(file.to_str().unwrap()).unwrap();
            let still = GpuMethod::<ImageSpace>::default()
                .render_still(&ctx, &scene, 32, 24)
                .unwrap();
            assert!(
                still.image.pixels.iter().all(|p| p.is_finite()),
                "{}",
                file.display()
            );
        }
    }
}

#[test]
fn the_paper_preset_refracts_total_internal_reflection_to_the_zero_vector() {
    let Some(ctx) = specula_methods::test_context("image-space paper TIR") else {
        return;
    };
    // The paper refracts at the hypotenuse anyway; its refract gives the zero vector under
    // total internal reflection, every point of which is the exit point: the lookups read the
    // nearby geometry straight behind it, the red wall, never the panel the light goes to.
    let s = prism_before_a_panel_and_a_red_wall();
    let (w, h) = (48, 48);
    let tir_pixels = internally_reflected_pixels(&s, w, h);
    let mut paper = Label::parse("image-space:paper").unwrap().create().unwrap();
    let still = paper.render_still(&ctx, &s, w, h).unwrap();
    assert!(still.image.pixels.iter().all(|p| p.is_finite()));
    assert_eq!(counter(&still, "total internal reflections followed"), 0);
    let not_followed = counter(&still, "total internal reflections not followed");
    let shown = showing_the_panel(&still, &tir_pixels);
    let red = tir_pixels
        .iter()
        .filter(|&&i| {
            let p = still.image.pixels[i];
            p.x > 0.5 && p.y < 0.1 && p.z < 0.1
        })
        .count();
    println!(
        "paper: {not_followed} not followed; of {} TIR pixels {shown} show the panel, {red} the red wall",
        tir_pixels.len()
    );
    assert!(not_followed as usize >= tir_pixels.len() / 2);
    assert_eq!(shown, 0, "the paper cannot show what TIR turns towards");
    // Measured 1572 of 1640 (0.96) red, the rest on the prism's edges; the bound allows 0.9.
    assert!(
        red * 10 >= tir_pixels.len() * 9,
        "{red} of {}",
        tir_pixels.len()
    );
}

#[test]
fn the_paper_preset_shows_a_lone_refractor_as_the_background_itself() {
    let Some(ctx) = specula_methods::test_context("image-space paper alone") else {
        return;
    };
    // No nearby geometry, a one-colour background: the paper's refraction carries all the
    // light (no Fresnel reflection or loss) and every ray finds nothing nearby and takes the
    // background, even the zero vector of total internal reflection (any texel of a one-colour
    // map is that colour), so the whole image is the background's colour exactly. The
    // defaults add the first surface's reflection and take the same colour from the cube map.
    let background = Vec3::new(0.2, 0.4, 0.8);
    let mut s = scene(
        vec![(
            generators::sphere(0.5, 32, 16),
            Material::glass("glass", 1.5),
            Mat4::IDENTITY,
        )],
        Background::Color(background),
        looking_down_z(20.0),
    );
    s.finalize("test").unwrap();
    let (w, h) = (64, 48);
    let mut paper = Label::parse("image-space:paper").unwrap().create().unwrap();
    let still = paper.render_still(&ctx, &s, w, h).unwrap();
    let refracted = counter(&still, "rays that found nothing nearby")
        + counter(&still, "rays that left the view");
    println!(
        "{refracted} refracted, {} total internal reflections not followed",
        counter(&still, "total internal reflections not followed")
    );
    assert!(refracted > 300, "{refracted}");
    for (i, p) in still.image.pixels.iter().enumerate() {
        assert!(
            (*p - background).abs().max_element() < 2e-3,
            "pixel {i}: {p}"
        );
    }
}
