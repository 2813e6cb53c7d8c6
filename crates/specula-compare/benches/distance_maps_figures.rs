//! The distance-maps paper's figures as tables, in one run on one machine:
//!
//! - Figure 17-7: the mirror teapot in a box (`teapot-box`) with at most 1, 2 and 3 bounces,
//!   each against the reference cut to the same depth;
//! - Figure 17-6: linear/secant steps 15/1, 15/10, 80/1 and 80/10 (depth 2);
//! - the speed of min-max acceleration (the paper: 25 → 50 fps), and of the default settings
//!   against the reference renderer for the same image.
//!
//!   cargo bench -p specula-compare --bench distance_maps_figures
//!
//! Prints Markdown tables (recorded in docs/methods/distance-maps.md). Errors as `compare` measures them:
//! linear radiance clamped to [0, 1], over the pixels whose primary ray hits the teapot. Frame
//! time: median of 3 frames after 1 warm-up frame, from the technique's own stage timings;
//! reference: its CPU render time (all cores) for the same image, BVH build included.

use std::time::Instant;

use specula_compare::metrics::{flip_map, measure, Metrics};
use specula_methods::{apply_parameters, by_name, LiveScene};
use specula_scene::Scene;
use specula_trace::reference::primary_hits;
use specula_trace::{render, Image, RenderSettings, SceneAccel};

const WIDTH: u32 = 640;
const HEIGHT: u32 = 480;

struct Run {
    metrics: Metrics,
    median_ms: f64,
    /// Median time of the tracing pass alone, and of the min-max reduction (0 when off).
    tracing_ms: f64,
    min_max_ms: f64,
}

fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

fn reference(scene: &Scene, max_depth: u32) -> (Image, f64) {
    let start = Instant::now();
    let accel = SceneAccel::new(scene);
    let image = render(
        scene,
        &accel,
        &RenderSettings {
            width: WIDTH,
            height: HEIGHT,
            spp: 1,
            max_depth,
        },
        &|_, _| {},
    );
    (image, start.elapsed().as_secs_f64() * 1e3)
}

fn run(
    ctx: &specula_methods::Context,
    scene: &Scene,
    mask: &[bool],
    exact: &Image,
    params: &[String],
) -> Run {
    let mut technique = by_name("distance-maps").expect("distance-maps exists");
    // The paper redraws its maps every frame (a moving scene): time that.
    apply_parameters(technique.as_mut(), &["dynamic=true".to_string()]).expect("valid");
    apply_parameters(technique.as_mut(), params).expect("valid parameters");
    let live = LiveScene::new(scene.clone());
    technique.prepare(ctx, &live).expect("prepare");
    let (mut times, mut tracing, mut min_max) = (Vec::new(), Vec::new(), Vec::new());
    let mut image = None;
    for frame in 0..4 {
        let f = technique
            .render(ctx, &live, &scene.camera, WIDTH, HEIGHT)
            .expect("render");
        if frame >= 1 {
            times.push(f.total_milliseconds());
            let stage = |name: &str| {
                f.stages
                    .iter()
                    .find(|s| s.stage == name)
                    .map_or(0.0, |s| s.milliseconds)
            };
            tracing.push(stage("tracing"));
            min_max.push(stage("min-max"));
        }
        image = Some(f.image(ctx).expect("readback"));
    }
    let image = image.expect("rendered");
    Run {
        metrics: measure(exact, &image, &flip_map(exact, &image), mask),
        median_ms: median(times),
        tracing_ms: median(tracing),
        min_max_ms: median(min_max),
    }
}

fn row(label: &str, r: &Run) -> String {
    format!(
        "| {label} | {:.4} | {:.1} | {:.4} | {:.1} % | {:.1} |",
        r.metrics.rmse,
        r.metrics.psnr_db.unwrap_or(f64::INFINITY),
        r.metrics.mean_flip,
        100.0 * r.metrics.share_flip_over_0_1,
        r.median_ms
    )
}

fn main() {
    let Ok(gpu) = specula_gpu::GpuContext::new() else {
        eprintln!("!!! SKIPPED: no Vulkan adapter (install mesa-vulkan-drivers libvulkan1) !!!");
        return;
    };
    let description = gpu.describe();
    let ctx = specula_methods::Context::with_gpu(gpu);
    let scene = specula_scene::load("teapot-box").expect("built-in scene");
    let accel = SceneAccel::new(&scene);
    let mask: Vec<bool> = primary_hits(&scene, &accel, WIDTH, HEIGHT)
        .iter()
        .map(|h| {
            h.is_some_and(|h| scene.materials[scene.meshes[h.mesh as usize].material].is_specular())
        })
        .collect();
    println!(
        "distance-maps on teapot-box at {WIDTH}x{HEIGHT} on {}; {} teapot pixels",
        description,
        mask.iter().filter(|&&m| m).count()
    );
    let header = "| setting | RMSE | PSNR dB | mean FLIP | FLIP > 0.1 | frame ms (median of 3) |\n|---|---|---|---|---|---|";

    println!(
        "\nFigure 17-7: maximum depth, each against the reference at the same depth\n\n{header}"
    );
    let mut references = Vec::new();
    for depth in 1..=3u32 {
        let (exact, reference_ms) = reference(&scene, depth);
        let r = run(&ctx, &scene, &mask, &exact, &[format!("max_depth={depth}")]);
        println!(
            "{} (reference {reference_ms:.1} ms)",
            row(&format!("max_depth={depth}"), &r)
        );
        references.push((exact, reference_ms));
    }
    let (exact2, _) = &references[1];

    println!("\nFigure 17-6: linear/secant steps, max_depth=2\n\n{header}");
    for (linear, secant) in [(15, 1), (15, 10), (80, 1), (80, 10)] {
        let r = run(
            &ctx,
            &scene,
            &mask,
            exact2,
            &[
                format!("linear_steps={linear}"),
                format!("secant_steps={secant}"),
                "max_depth=2".into(),
            ],
        );
        println!("{}", row(&format!("{linear}/{secant}"), &r));
    }

    println!("\nMin-max acceleration and the reference, same run, max_depth=2\n\n{header}");
    let with = run(
        &ctx,
        &scene,
        &mask,
        exact2,
        &["min_max=true".into(), "max_depth=2".into()],
    );
    let without = run(
        &ctx,
        &scene,
        &mask,
        exact2,
        &["min_max=false".into(), "max_depth=2".into()],
    );
    println!("{}", row("min_max=true", &with));
    println!("{}", row("min_max=false", &without));
    for (label, r) in [("min_max=true", &with), ("min_max=false", &without)] {
        println!(
            "{label}: tracing pass {:.1} ms, min-max reduction {:.1} ms (medians)",
            r.tracing_ms, r.min_max_ms
        );
    }
    let (_, reference_ms) = reference(&scene, 2);
    println!(
        "\nmin-max speed-up of the frame {:.2}×, of the tracing pass {:.2}×; reference (CPU, max depth 2) {reference_ms:.1} ms; distance-maps default {:.1} ms: {:.2}× the reference's speed",
        without.median_ms / with.median_ms,
        without.tracing_ms / with.tracing_ms,
        with.median_ms,
        reference_ms / with.median_ms
    );
}
