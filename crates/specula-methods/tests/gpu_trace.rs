//! `gpu-trace` renders what the CPU reference renders: PSNR (on radiance clamped to [0, 1], as
//! `compare` computes it) against the CPU reference, one sample per pixel, on every built-in
//! and suite scene, in both of its modes. `GPU_TRACE_TEST_SIZE=320x240` runs the every-scene
//! test at the size (docs/methods/gpu-trace.md has its figures); the default is 80×60.

mod common;

use std::path::Path;

use common::{cpu_reference, looking_down_z, prism, scene, wall};
use glam::{Mat4, Vec2, Vec3};
use specula_methods::gpu_trace::{GpuTrace, Mode};
use specula_methods::{Context, LiveScene, RenderStill, Still, Technique};
use specula_scene::{generators, Background, Material, MaterialKind, Scene, Texture};
use specula_trace::Image;

const WIDTH: u32 = 80;
const HEIGHT: u32 = 60;

/// PSNR in dB over all pixels, radiance clamped to [0, 1]; infinite for identical images.
fn psnr(reference: &Image, test: &Image) -> f64 {
    let squared: f64 = reference
        .pixels
        .iter()
        .zip(&test.pixels)
        .map(|(a, b)| {
            let d = a.clamp(Vec3::ZERO, Vec3::ONE) - b.clamp(Vec3::ZERO, Vec3::ONE);
            (d.length_squared() / 3.0) as f64
        })
        .sum();
    let rmse = (squared / reference.pixels.len() as f64).sqrt();
    20.0 * (1.0 / rmse).log10()
}

/// The every-scene test's image size: `GPU_TRACE_TEST_SIZE` (WIDTHxHEIGHT), else 80×60.
fn every_scene_size() -> (u32, u32) {
    std::env::var("GPU_TRACE_TEST_SIZE")
        .ok()
        .and_then(|s| {
            let (w, h) = s.split_once('x')?;
            Some((w.parse().ok()?, h.parse().ok()?))
        })
        .unwrap_or((WIDTH, HEIGHT))
}

fn scenes() -> Vec<(String, Scene)> {
    let mut scenes: Vec<(String, Scene)> = specula_scene::builtin::names()
        .into_iter()
        .map(|n| (n.to_string(), specula_scene::load(n).unwrap()))
        .collect();
    let suite = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/suite");
    let mut files: Vec<_> = std::fs::read_dir(suite)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    for file in files {
        let name = file.file_stem().unwrap().to_string_lossy().to_string();
        scenes.push((name, specula_scene::load(file.to_str().unwrap()).unwrap()));
    }
    scenes
}

#[test]
fn gpu_trace_equals_the_cpu_reference_on_every_scene() {
    let Some(ctx) = specula_methods::test_context("gpu-trace") else {
        return;
    };
    let (width, height) = every_scene_size();
    let mut worst = f64::INFINITY;
    for (name, scene) in scenes() {
        let reference = cpu_reference(&scene, width, height, 8);
        for mode in [Mode::Megakernel, Mode::Wavefront] {
            let still = GpuTrace::new(mode, 8)
                .render_still(&ctx, &scene, width, height)
                .unwrap();
            assert!(still.image.pixels.iter().all(|p| p.is_finite()), "{name}");
            let db = psnr(&reference, &still.image);
            println!("{name} {mode:?}: {db:.1} dB");
            worst = worst.min(db);
        }
    }
    println!("worst {worst:.1} dB");
    // At 80×60, measured 2026-12-01 on lavapipe: worst 84.8 dB (glass-dragon), every other
    // scene >= 110 dB; the bound allows twice that RMSE (6 dB less). At other sizes a pixel at
    // the edge of a glare can see another surface in single precision (truck-cover: 50.3 dB at
    // 320×240, docs/methods/gpu-trace.md), so there the bound is the 45 dB.
    let floor = if every_scene_size() == (WIDTH, HEIGHT) {
        79.0
    } else {
        45.0
    };
    assert!(
        worst >= floor,
        "worst PSNR {worst:.1} dB (bound {floor} dB)"
    );
}

/// The centre pixel of a `size` × `size` gpu-trace image, after checking that the whole image
/// equals the CPU reference's to 1e-4 (largest difference measured: 4.5e-5, an equirectangular
/// lookup, where the GPU's acos and atan2 round differently from the CPU's).
fn centre(ctx: &Context, s: &Scene, size: u32, max_depth: u32) -> Vec3 {
    let mut technique = GpuTrace::new(Mode::Megakernel, max_depth);
    let image = technique.render_still(ctx, s, size, size).unwrap().image;
    let reference = cpu_reference(s, size, size, max_depth);
    for (a, b) in image.pixels.iter().zip(&reference.pixels) {
        assert!((*a - *b).abs().max_element() < 1e-4, "{a} vs CPU {b}");
    }
    image.get(size / 2, size / 2)
}

#[test]
fn gpu_trace_matches_closed_form_optics() {
    let Some(ctx) = specula_methods::test_context("gpu-trace closed form") else {
        return;
    };
    // Mirror without Fresnel: exactly F0 times what it sees; max_depth 0 follows no bounce.
    let (mesh, m) = wall(4.0);
    let f0 = Vec3::new(0.9, 0.5, 0.2);
    let sky = Vec3::new(0.2, 0.4, 0.8);
    let mirror = Material::new("mirror", MaterialKind::Mirror { fresnel: false }, f0);
    let s = scene(
        vec![(mesh, mirror, m)],
        Background::Color(sky),
        looking_down_z(10.0),
    );
    assert!((centre(&ctx, &s, 5, 8) - f0 * sky).length() < 1e-6);
    assert_eq!(centre(&ctx, &s, 5, 0), Vec3::ZERO);

    // Glass slab at normal incidence: T² / (1 − R²) (the depth limit cuts the series after
    // R⁶, below 1e-8).
    let (backdrop, m) = wall(20.0);
    let behind = Mat4::from_translation(Vec3::new(0.0, 0.0, -3.0)) * m;
    let s = scene(
        vec![
            (
                backdrop.clone(),
                Material::unlit("white", Vec3::ONE),
                behind,
            ),
            (
                generators::cuboid(Vec3::new(3.0, 3.0, 0.5)),
                Material::glass("glass", 1.5),
                Mat4::from_translation(Vec3::new(0.0, 0.0, 1.0)),
            ),
        ],
        Background::Color(Vec3::ZERO),
        looking_down_z(5.0),
    );
    let (r, t) = (0.04f32, 0.96f32);
    let got = centre(&ctx, &s, 5, 8);
    assert!(
        (got - Vec3::splat(t * t / (1.0 - r * r)))
            .abs()
            .max_element()
            < 1e-4,
        "{got}"
    );

    // Critical angle: the prism turns the centre ray by total internal reflection towards a
    // white panel at +X. Paths reaching it: in, TIR, out (T²), and once back and forth
    // between the legs (T² R²); the next round trip passes max_depth 8. At n = 1.5 the
    // critical angle is 41.8° < 45°; at n = 1.3 it is 50.3° > 45° and the hypotenuse lets
    // most light out, away from the panel.
    let panel = (
        generators::plane(Vec2::splat(6.0), 1),
        Material::unlit("panel", Vec3::ONE),
        Mat4::from_translation(Vec3::new(3.0, 0.0, 0.0))
            * Mat4::from_rotation_z(std::f32::consts::FRAC_PI_2),
    );
    let prism_scene = |ior: f32| {
        scene(
            vec![
                panel.clone(),
                (prism(), Material::glass("prism", ior), Mat4::IDENTITY),
            ],
            Background::Color(Vec3::ZERO),
            looking_down_z(2.0),
        )
    };
    let tir = centre(&ctx, &prism_scene(1.5), 5, 8);
    let expected = t * t * (1.0 + r * r);
    assert!(
        (tir - Vec3::splat(expected)).abs().max_element() < 1e-4,
        "{tir} vs {expected}"
    );
    let below_critical = centre(&ctx, &prism_scene(1.3), 5, 8);
    assert!(
        below_critical.max_element() < 0.5 * expected,
        "{below_critical}"
    );
}

#[test]
fn gpu_trace_maps_a_distant_environment_as_the_reference() {
    let Some(ctx) = specula_methods::test_context("gpu-trace environment") else {
        return;
    };
    // A sky whose colour is its own texture coordinate: each direction's (u, v) reads back.
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
    for (target, uv) in [
        (Vec3::new(0.0, 0.0, -1.0), Vec2::new(0.5, 0.5)),
        (Vec3::new(-1.0, 0.0, 0.0), Vec2::new(0.25, 0.5)),
        (Vec3::new(0.0, 1.0, -1.0), Vec2::new(0.5, 0.25)),
    ] {
        s.camera.target = s.camera.eye + target;
        let got = centre(&ctx, &s, 3, 1) / 2.0;
        assert!((got - uv.extend(0.0)).length() < 1e-3, "{got} vs {uv}");
    }
    // A mirror sphere and a glass sphere under it: the whole image equals the CPU's.
    s.camera = looking_down_z(40.0);
    for material in [
        Material::mirror("chrome", Vec3::splat(0.9)),
        Material::glass("glass", 1.5),
    ] {
        let mut with_sphere = s.clone();
        let mut sphere = generators::sphere(1.0, 48, 24);
        sphere.material = with_sphere.materials.len();
        with_sphere.materials.push(material);
        with_sphere.meshes.push(sphere);
        let image = GpuTrace::new(Mode::Megakernel, 8)
            .render_still(&ctx, &with_sphere, WIDTH, HEIGHT)
            .unwrap()
            .image;
        let db = psnr(&cpu_reference(&with_sphere, WIDTH, HEIGHT, 8), &image);
        println!("with sphere: {db:.1} dB");
        // Measured 90.7 and 90.8 dB; twice that RMSE is 6 dB less.
        assert!(db >= 84.0, "{db:.1} dB");
    }
}

#[test]
fn gpu_trace_follows_moves_and_a_camera_change_uploads_nothing() {
    let Some(ctx) = specula_methods::test_context("gpu-trace moves") else {
        return;
    };
    let scene = specula_scene::load("glass-dragon").unwrap();
    let mut live = LiveScene::new(scene);
    let mut technique: Box<dyn Technique> = Box::new(GpuTrace::new(Mode::Megakernel, 8));
    technique.prepare(&ctx, &live).unwrap();
    let camera = live.scene().camera.clone();
    technique
        .render(&ctx, &live, &camera, WIDTH, HEIGHT)
        .unwrap();
    // Another eye: no GPU object is made and nothing but the camera is written.
    let mut moved_camera = camera.clone();
    moved_camera.eye += Vec3::new(0.3, 0.1, 0.0);
    let frame = technique
        .render(&ctx, &live, &moved_camera, WIDTH, HEIGHT)
        .unwrap();
    assert_eq!(frame.created().total(), 0);
    // Move the glass bunny: the next frame equals the CPU reference of the moved scene.
    let bunny = live
        .scene()
        .meshes
        .iter()
        .position(|m| live.scene().materials[m.material].is_specular())
        .unwrap();
    for _ in 0..3 {
        live.translate_object(ctx.gpu.as_ref(), bunny, Vec3::new(0.15, 0.0, 0.05))
            .unwrap();
        live.rotate_object(ctx.gpu.as_ref(), bunny, Vec3::Y, 20.0)
            .unwrap();
    }
    let frame = technique
        .render(&ctx, &live, &camera, WIDTH, HEIGHT)
        .unwrap();
    let image = frame.image(&ctx).unwrap();
    let reference = cpu_reference(live.scene(), WIDTH, HEIGHT, 8);
    let db = psnr(&reference, &image);
    println!("after the moves: {db:.1} dB");
    // Measured 130.4 dB; twice that RMSE is 6 dB less.
    assert!(db >= 124.0, "after the moves: {db:.1} dB");
}

#[test]
fn rays_past_the_stack_or_queues_are_dropped_counted_and_warned() {
    let Some(ctx) = specula_methods::test_context("gpu-trace drops") else {
        return;
    };
    let scene = specula_scene::load("glass-dragon").unwrap();
    let dropped = |still: &Still| {
        still
            .counters
            .iter()
            .find(|(name, _)| name.starts_with("rays dropped"))
            .unwrap()
            .1
    };
    // The default depth fits the megakernel's stack: nothing dropped.
    let exact = GpuTrace::new(Mode::Megakernel, 8)
        .render_still(&ctx, &scene, WIDTH, HEIGHT)
        .unwrap();
    assert_eq!(dropped(&exact), 0);
    assert!(exact.warnings.is_empty());
    // Depth 30 inside glass outgrows 16 pending rays; a wavefront queue of one ray per pixel
    // overflows where the dispersive spectacle lens, filling the view, splits each ray in six.
    let lens = specula_scene::load("spectacle-lens").unwrap();
    for (mode, depth, scene) in [(Mode::Megakernel, 30, &scene), (Mode::Wavefront, 8, &lens)] {
        let mut technique = GpuTrace::new(mode, depth);
        technique.params.queue_factor = 1;
        let still = technique.render_still(&ctx, scene, WIDTH, HEIGHT).unwrap();
        assert!(dropped(&still) > 0, "{mode:?}");
        assert!(still.warnings.iter().any(|w| w.contains("dropped")));
        assert!(still.image.pixels.iter().all(|p| p.is_finite()));
    }
}
