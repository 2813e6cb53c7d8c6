//! `specula`: renders reflections and refractions on curved mirrors and lenses, and measures
//! how accurate and fast each technique is. See README.md for the commands.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use specula_gpu::GpuContext;
use specula_scene::builtin::{self, DEFAULT_SCENE};
use specula_scene::Scene;
use specula_trace::{render, Image, RenderSettings, SceneAccel};

mod bench;

#[derive(Parser)]
#[command(
    name = "specula",
    version,
    about = "Accurate, measured reflections and refractions on curved mirrors and lenses"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// List the built-in scenes.
    Scenes,
    /// Render a scene to PNG (sRGB, clamped) and optionally EXR (linear float).
    Render {
        /// Built-in scene name, a .toml scene file, or a mesh/scene file (.gltf .glb .obj .ply .stl).
        #[arg(default_value = DEFAULT_SCENE)]
        scene: String,
        /// Technique to render with.
        #[arg(long, short, default_value = "reference")]
        method: String,
        /// Image width in pixels.
        #[arg(short = 'W', long, default_value_t = 640, value_parser = clap::value_parser!(u32).range(1..=16384))]
        width: u32,
        /// Image height in pixels (default: from the width and the camera's aspect ratio, else 480).
        #[arg(short = 'H', long, value_parser = clap::value_parser!(u32).range(1..=16384))]
        height: Option<u32>,
        /// Samples per pixel: 1 = one ray through each pixel centre; more = stratified jitter.
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=4096))]
        spp: u32,
        /// Maximum number of specular bounces on a path.
        #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(0..=64))]
        max_depth: u32,
        /// A technique parameter, NAME=VALUE (repeatable), e.g. `-p resolution=512`.
        #[arg(short = 'p', long = "param")]
        params: Vec<String>,
        /// PNG output file.
        #[arg(short, long, default_value = "out.png")]
        output: PathBuf,
        /// Also write linear float RGB to this OpenEXR file.
        #[arg(long)]
        exr: Option<PathBuf>,
    },
    /// Render the reference and each method from the same camera; report error and speed.
    Compare {
        #[arg(default_value = DEFAULT_SCENE)]
        scene: String,
        /// Comma-separated methods (default: every method).
        #[arg(long, value_delimiter = ',')]
        methods: Option<Vec<String>>,
        /// Folder for report.html, report.json and the images.
        #[arg(long, default_value = "specula-report")]
        report: PathBuf,
        /// A technique parameter, NAME=VALUE (repeatable), e.g. `-p resolution=512`.
        #[arg(short = 'p', long = "param")]
        params: Vec<String>,
        /// Also write the JSON report here.
        #[arg(long)]
        json: Option<PathBuf>,
        #[arg(short = 'W', long, default_value_t = 320, value_parser = clap::value_parser!(u32).range(1..=16384))]
        width: u32,
        #[arg(short = 'H', long, value_parser = clap::value_parser!(u32).range(1..=16384))]
        height: Option<u32>,
        /// Samples per pixel of the reference.
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=4096))]
        spp: u32,
        #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(0..=64))]
        max_depth: u32,
    },
    /// Time each method: warm-up, then N frames; median and spread per method and stage.
    Bench {
        #[arg(default_value = DEFAULT_SCENE)]
        scene: String,
        #[arg(long, value_delimiter = ',')]
        methods: Option<Vec<String>>,
        #[arg(long, default_value_t = 20, value_parser = clap::value_parser!(u32).range(1..=100000))]
        frames: u32,
        /// A technique parameter, NAME=VALUE (repeatable), e.g. `-p resolution=512`.
        #[arg(short = 'p', long = "param")]
        params: Vec<String>,
        #[arg(long)]
        json: Option<PathBuf>,
        #[arg(short = 'W', long, default_value_t = 640, value_parser = clap::value_parser!(u32).range(1..=16384))]
        width: u32,
        #[arg(short = 'H', long, value_parser = clap::value_parser!(u32).range(1..=16384))]
        height: Option<u32>,
    },
}

fn load_scene(name: &str) -> Result<Scene> {
    let scene = specula_scene::load(name).with_context(|| format!("loading scene '{name}'"))?;
    for warning in &scene.warnings {
        eprintln!("warning: {warning}");
    }
    Ok(scene)
}

/// The height for `width` keeping the camera's aspect ratio (4:3 when it has none).
fn height_for(scene: &Scene, width: u32, height: Option<u32>) -> u32 {
    let aspect = scene.camera.aspect.unwrap_or(4.0 / 3.0);
    height.unwrap_or(((width as f32 / aspect).round() as u32).max(1))
}

fn gpu() -> Result<GpuContext> {
    let ctx = GpuContext::new()?;
    eprintln!("GPU: {}", ctx.describe());
    Ok(ctx)
}

fn all_methods() -> Vec<String> {
    specula_methods::METHODS
        .iter()
        .map(|m| m.to_string())
        .collect()
}

fn spinner() -> ProgressBar {
    let bar = ProgressBar::new_spinner();
    bar.set_style(
        ProgressStyle::with_template("{spinner} {msg} ({elapsed})").expect("valid template"),
    );
    bar.enable_steady_tick(std::time::Duration::from_millis(120));
    bar
}

fn progress_bar(len: u64, what: &str) -> ProgressBar {
    let bar = ProgressBar::new(len);
    bar.set_style(
        ProgressStyle::with_template("{msg:>10} [{bar:40}] {pos}/{len} tiles ({eta} left)")
            .expect("valid template")
            .progress_chars("=> "),
    );
    bar.set_message(what.to_string());
    bar
}

fn main() -> std::process::ExitCode {
    match run(Cli::parse()) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Scenes => {
            for (name, description) in builtin::list() {
                let marker = if name == DEFAULT_SCENE {
                    " (default)"
                } else {
                    ""
                };
                println!("{name:<22}{description}{marker}");
            }
            Ok(())
        }
        Command::Render {
            scene,
            method,
            width,
            height,
            spp,
            max_depth,
            output,
            exr,
            params,
        } => {
            let scene = load_scene(&scene)?;
            let height = height_for(&scene, width, height);
            let start = Instant::now();
            let (image, summary) = if method == "reference" {
                let accel = SceneAccel::new(&scene);
                let build = start.elapsed();
                let settings = RenderSettings {
                    width,
                    height,
                    spp,
                    max_depth,
                };
                let bar = progress_bar(0, "rendering");
                let start = Instant::now();
                let image = render(&scene, &accel, &settings, &|done, total| {
                    bar.set_length(total as u64);
                    bar.set_position(done as u64);
                });
                bar.finish_and_clear();
                let summary = format!(
                    "BVH {:.1} ms, {method} {width}x{height} {spp} spp in {:.2} s",
                    build.as_secs_f64() * 1e3,
                    start.elapsed().as_secs_f64()
                );
                (image, summary)
            } else {
                let mut technique = specula_methods::by_name(&method)?;
                specula_methods::apply_parameters(technique.as_mut(), &params)?;
                let ctx = gpu()?;
                technique.prepare(&ctx, &scene)?;
                let frame = technique.render(&ctx, &scene, &scene.camera, width, height)?;
                for warning in &frame.warnings {
                    eprintln!("warning: {warning}");
                }
                let counters: Vec<String> = frame
                    .counters
                    .iter()
                    .map(|(name, value)| format!("{name} {value}"))
                    .collect();
                let summary = format!(
                    "{method} {width}x{height} in {:.1} ms ({})",
                    frame.total_milliseconds(),
                    counters.join(", ")
                );
                (frame.image, summary)
            };
            let image: Image = image;
            image.save_png(&output)?;
            if let Some(exr) = &exr {
                image.save_exr(exr)?;
            }
            eprintln!(
                "{}: {} triangles, {summary} -> {}{}",
                scene.name,
                scene.triangle_count(),
                output.display(),
                exr.map(|e| format!(", {}", e.display()))
                    .unwrap_or_default()
            );
            Ok(())
        }
        Command::Compare {
            scene,
            methods,
            report,
            json,
            width,
            height,
            spp,
            max_depth,
            params,
        } => {
            let scene = load_scene(&scene)?;
            let options = specula_compare::Options {
                parameters: params,
                width,
                height: height_for(&scene, width, height),
                methods: methods.unwrap_or_else(all_methods),
                spp,
                max_depth,
            };
            let ctx = gpu()?;
            let bar = spinner();
            let comparison = specula_compare::compare(&scene, &ctx, &options, &|stage| {
                bar.set_message(format!("rendering {stage}"))
            })?;
            bar.finish_and_clear();
            let html = comparison.write_report(&report)?;
            if let Some(json) = &json {
                comparison.write_json(json)?;
            }
            let r = &comparison.report;
            println!(
                "{} at {}x{}, {} reflector/refractor pixels; reference {:.1} ms",
                r.scene, r.width, r.height, r.mask_pixels, r.reference.total_ms
            );
            println!(
                "{:<16}{:>9}{:>11}{:>11}{:>11}{:>12}{:>10}",
                "method", "RMSE", "PSNR dB", "mean FLIP", "FLIP>0.1", "frame ms", "speed-up"
            );
            for warning in r.methods.iter().flat_map(|m| &m.warnings) {
                eprintln!("warning: {warning}");
            }
            for m in &r.methods {
                println!(
                    "{:<16}{:>9.4}{:>11}{:>11.4}{:>10.1}%{:>12.2}{:>9.1}x",
                    m.method,
                    m.metrics.rmse,
                    m.metrics
                        .psnr_db
                        .map(|p| format!("{p:.1}"))
                        .unwrap_or_else(|| "inf".into()),
                    m.metrics.mean_flip,
                    m.metrics.share_flip_over_0_1 * 100.0,
                    m.total_ms,
                    m.speedup_over_reference
                );
            }
            println!("report: {}", html.display());
            Ok(())
        }
        Command::Bench {
            scene,
            methods,
            frames,
            json,
            width,
            height,
            params,
        } => {
            let scene = load_scene(&scene)?;
            let height = height_for(&scene, width, height);
            let ctx = gpu()?;
            let results = bench::run(
                &scene,
                &ctx,
                &methods.unwrap_or_else(all_methods),
                &params,
                width,
                height,
                frames,
            )?;
            bench::print(&results);
            if let Some(json) = json {
                std::fs::write(&json, serde_json::to_string_pretty(&results)?)
                    .with_context(|| format!("writing {}", json.display()))?;
            }
            Ok(())
        }
    }
}
