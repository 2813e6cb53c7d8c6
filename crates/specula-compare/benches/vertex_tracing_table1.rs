//! Vertex tracing's Table 1 (Ullmann et al. 2001) on `truck-cover`: the reference tracing the
//! reflector's pixels against the preview, refinement without and with triangle filling —
//! time, samples (rays aimed at a vertex or a pixel), rays, speed-up and error, in one run.
//!
//!   cargo bench -p specula-compare --bench vertex_tracing_table1 [-- WIDTH HEIGHT [SCENE]]
//!
//! What is timed is what the paper counts: shading the reflector (vertex rays, refinement,
//! filling and interpolation) against the reference tracing the same pixels at the same
//! resolution, both with every rayon thread; the ID buffer and the rest of the scene, which
//! both need, are timed apart. Times are medians of 3 runs. Error: mean FLIP over the
//! reflector's pixels against the reference. Each vertex row's composition (the faces'
//! pixels shaded from their corners) is timed apart too, on the CPU and, where the run has a
//! GPU adapter (lavapipe included), on its raster (`composition=gpu`), in rows of their own.

use std::time::Instant;

use rayon::prelude::*;
use specula_compare::metrics::{flip_map, measure};
use specula_methods::vertex_tracing::compose::RasterComposition;
use specula_methods::vertex_tracing::{FramePhases, PackageCounters, Params, VertexTracing};
use specula_methods::LiveScene;
use specula_trace::reference::{pixel_radiance, rays_traced_on_this_thread, Tracer};

const RUNS: usize = 3;

fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .collect();
    let width: u32 = args.first().and_then(|a| a.parse().ok()).unwrap_or(1024);
    let height: u32 = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(768);
    let name = args.get(2).map_or("truck-cover", String::as_str);
    let scene = specula_scene::load(name).expect("scene loads");
    let live = LiveScene::new(scene);
    let camera = live.scene().camera.clone();
    let mut defaults = VertexTracing::default();
    // Table 1 times the vertex method: every reflector by its vertices (what `tracing=auto`
    // also chooses for the cover at 1024 x 768; at small sizes it would trace it per pixel).
    defaults.params.tracing = specula_methods::vertex_tracing::ReflectorTracing::Vertices;
    let max_depth = defaults.params.max_depth;

    let start = Instant::now();
    let phases = FramePhases::visibility(&live, &camera, width, height, defaults.params, max_depth);
    let visibility_ms = start.elapsed().as_secs_f64() * 1e3;
    let start = Instant::now();
    let rest = phases.rest_of_scene();
    let rest_ms = start.elapsed().as_secs_f64() * 1e3;
    let reflector_vertices: usize = live
        .scene()
        .meshes
        .iter()
        .filter(|m| live.scene().materials[m.material].is_specular())
        .map(|m| m.positions.len())
        .sum();
    let pixels: Vec<u32> = phases.reflector_pixels().collect();

    // The reference: every reflector pixel traced.
    let tracer = Tracer {
        scene: live.scene(),
        accel: live.accel(),
        max_depth,
    };
    let pixel_rays = camera.pixel_rays(width, height);
    let mut reference = rest.clone();
    let mut reference_times = Vec::new();
    let mut reference_rays = 0;
    for _ in 0..RUNS {
        let start = Instant::now();
        let traced: Vec<(u32, glam::Vec3, u64)> = pixels
            .par_iter()
            .map(|&k| {
                let before = rays_traced_on_this_thread();
                let c = pixel_radiance(&tracer, &pixel_rays, k % width, k / width, 1);
                let after = rays_traced_on_this_thread();
                (k, c, after.0 - before.0 + after.1 - before.1)
            })
            .collect();
        reference_times.push(start.elapsed().as_secs_f64() * 1e3);
        reference_rays = traced.iter().map(|t| t.2).sum::<u64>();
        for (k, c, _) in traced {
            reference.pixels[k as usize] = c;
        }
    }
    let reference_ms = median(reference_times);
    let mask: Vec<bool> = {
        let mut mask = vec![false; (width * height) as usize];
        for &k in &pixels {
            mask[k as usize] = true;
        }
        mask
    };

    println!(
        "vertex tracing, Table 1: {name} at {width}x{height}, {} reflector pixels, {reflector_vertices} reflector vertices as built, {} rayon threads",
        pixels.len(),
        rayon::current_num_threads()
    );
    println!("ID buffer (CPU primary rays) {visibility_ms:.1} ms and rest of the scene {rest_ms:.1} ms, apart from the times below");
    println!();
    let gpu = match specula_gpu::GpuContext::new() {
        Ok(gpu) => {
            println!("GPU for composition on the raster: {}", gpu.describe());
            Some(gpu)
        }
        Err(e) => {
            println!("no GPU: composition on the CPU only ({e})");
            None
        }
    };
    let mut composer = gpu.as_ref().map(RasterComposition::new);
    println!();
    println!("| rendered image | composition | time (ms) | of which composition (ms) | samples | rays (all kinds) | speed-up | mean FLIP (reflector) |");
    println!("|---|---|---|---|---|---|---|---|");
    println!(
        "| reference ray tracing | | {reference_ms:.1} | | {} | {reference_rays} | 1 | 0 |",
        pixels.len()
    );
    // The last row is the published algorithm: the `paper` preset's settings (every step
    // beyond the paper off: whole ray trees, texture colours compared as colours, ...).
    let mut published = VertexTracing::default();
    let preset = specula_methods::vertex_tracing::INFO
        .preset("paper")
        .expect("vertex-tracing has a paper preset");
    for setting in preset.settings {
        specula_methods::apply_setting(&mut published, setting).expect("the preset applies");
    }
    let paper = published.params;
    let steps = [
        ("preview", false, false, defaults.params),
        (
            "refinement without triangle filling",
            true,
            false,
            defaults.params,
        ),
        (
            "refinement with triangle filling",
            true,
            true,
            defaults.params,
        ),
        ("with filling, vertex-tracing:paper", true, true, paper),
    ];
    for (label, refine, fill, base) in steps {
        let settings = Params {
            refine,
            fill,
            ..base
        };
        for on_gpu in [false, true] {
            let mut raster = match (&gpu, &mut composer) {
                (Some(gpu), Some(composer)) if on_gpu => Some((gpu, composer)),
                _ if on_gpu => continue,
                _ => None,
            };
            let mut times = Vec::new();
            let mut composition_times = Vec::new();
            let mut image = rest.clone();
            let mut totals = PackageCounters::default();
            for _ in 0..RUNS {
                let start = Instant::now();
                // The technique's own cut (package_triangles = 0).
                let again = raster
                    .as_mut()
                    .map(|(gpu, composer)| (*gpu, &mut **composer));
                let (counters, composition_ms) = phases
                    .shade_reflector(settings, &mut image, again)
                    .expect("the reflector is shaded");
                totals = counters;
                times.push(start.elapsed().as_secs_f64() * 1e3);
                composition_times.push(composition_ms);
            }
            let ms = median(times);
            let flip = flip_map(&reference, &image);
            let metrics = measure(&reference, &image, &flip, &mask);
            println!(
                "| {label} | {} | {ms:.1} | {:.1} | {} | {} | {:.1} | {:.4} |",
                if on_gpu { "GPU raster" } else { "CPU" },
                median(composition_times),
                totals.vertex_rays + totals.filled_pixels,
                totals.vertex_rays + totals.rays + totals.shadow_rays,
                reference_ms / ms,
                metrics.mean_flip
            );
        }
    }
}
