//! `gpu-trace` renders what the CPU reference renders: PSNR (on radiance clamped to [0, 1], as
//! `compare` computes it) against the CPU reference, one sample per pixel, on every built-in
//! and suite scene, in both of its modes.

use std::path::Path;

use specula_methods::gpu_trace::{GpuTrace, Mode};
use specula_methods::{Context, RenderStill, Still};
use specula_scene::Scene;
use specula_trace::{render, Image, RenderSettings, SceneAccel};

const WIDTH: u32 = 80;
const HEIGHT: u32 = 60;

/// PSNR in dB over all pixels, radiance clamped to [0, 1]; infinite for identical images.
fn psnr(reference: &Image, test: &Image) -> f64 {
    let squared: f64 = reference
        .pixels
        .iter()
        .zip(&test.pixels)
        .map(|(a, b)| {
            let d = a.clamp(glam::Vec3::ZERO, glam::Vec3::ONE)
                - b.clamp(glam::Vec3::ZERO, glam::Vec3::ONE);
            (d.length_squared() / 3.0) as f64
        })
        .sum();
    let rmse = (squared / reference.pixels.len() as f64).sqrt();
    20.0 * (1.0 / rmse).log10()
}

fn cpu_reference(scene: &Scene, width: u32, height: u32, max_depth: u32) -> Image {
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

fn gpu(ctx: &Context, scene: &Scene, mode: Mode, max_depth: u32) -> Still {
    GpuTrace::new(mode, max_depth)
        .render_still(ctx, scene, WIDTH, HEIGHT)
        .unwrap()
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
    let mut worst = f64::INFINITY;
    for (name, scene) in scenes() {
        let reference = cpu_reference(&scene, WIDTH, HEIGHT, 8);
        for mode in [Mode::Megakernel, Mode::Wavefront] {
            let still = gpu(&ctx, &scene, mode, 8);
            assert!(still.image.pixels.iter().all(|p| p.is_finite()), "{name}");
            let db = psnr(&reference, &still.image);
            println!("{name} {mode:?}: {db:.1} dB");
            worst = worst.min(db);
        }
    }
    println!("worst {worst:.1} dB");
    assert!(worst >= 45.0, "worst PSNR {worst:.1} dB");
}
