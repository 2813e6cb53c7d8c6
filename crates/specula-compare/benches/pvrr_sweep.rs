//! pvrr's scalable-accuracy claim as a table: the door mirror tessellated ever finer, with the
//! error on the mirror's pixels against the reference and the frame time of each, in one run.
//!
//!   cargo bench -p specula-compare --bench pvrr_sweep
//!
//! Prints a Markdown table (recorded in docs/methods/pvrr.md); RMSE and PSNR as `compare` measures
//! them (linear radiance clamped to [0, 1]), over the pixels whose primary ray hits the mirror. Frame time: median of 5 frames after
//! 2 warm-up frames, from the technique's own stage timings.

use std::time::Instant;

use specula_compare::metrics::{flip_map, measure};
use specula_methods::{by_name, LiveScene};
use specula_trace::reference::primary_hits;
use specula_trace::{render, RenderSettings, SceneAccel};

const SIZE: u32 = 512;

fn main() {
    let Ok(ctx) = specula_gpu::GpuContext::new() else {
        eprintln!("!!! SKIPPED: no Vulkan adapter (install mesa-vulkan-drivers libvulkan1) !!!");
        return;
    };
    println!("pvrr on door-mirror at {SIZE}x{SIZE} on {}", ctx.describe());
    let ctx = specula_methods::Context::with_gpu(ctx);
    println!("| mirror vertices | RMSE (mirror pixels) | PSNR dB | pvrr frame ms (median of 5) | reference ms |");
    println!("|---|---|---|---|---|");
    for quads in [6u32, 13, 27, 56] {
        let scene = specula_scene::builtin::door_mirror_tessellated(quads).expect("scene builds");
        let mirror = scene
            .meshes
            .iter()
            .position(|m| m.name == "door mirror")
            .expect("mirror");
        let start = Instant::now();
        let accel = SceneAccel::new(&scene);
        let reference = render(
            &scene,
            &accel,
            &RenderSettings {
                width: SIZE,
                height: SIZE,
                spp: 1,
                max_depth: 8,
            },
            &|_, _| {},
        );
        let reference_ms = start.elapsed().as_secs_f64() * 1e3;
        let mut pvrr = by_name("pvrr").expect("pvrr exists");
        let live = LiveScene::new(scene.clone());
        pvrr.prepare(&ctx, &live).expect("prepare");
        let mut times = Vec::new();
        let mut image = None;
        for frame in 0..7 {
            let f = pvrr
                .render(&ctx, &live, &scene.camera, SIZE, SIZE)
                .expect("render");
            if frame >= 2 {
                times.push(f.total_milliseconds());
            }
            image = Some(f.image(&ctx).expect("readback"));
        }
        times.sort_by(f64::total_cmp);
        let image = image.expect("rendered");
        let hits = primary_hits(&scene, &accel, SIZE, SIZE);
        let mask: Vec<bool> = hits
            .iter()
            .map(|h| h.is_some_and(|h| h.mesh as usize == mirror))
            .collect();
        let metrics = measure(&reference, &image, &flip_map(&reference, &image), &mask);
        println!(
            "| {} | {:.4} | {:.1} | {:.1} | {reference_ms:.1} |",
            (quads + 1) * (quads + 1),
            metrics.rmse,
            metrics.psnr_db.unwrap_or(f64::INFINITY),
            times[times.len() / 2]
        );
    }
}
