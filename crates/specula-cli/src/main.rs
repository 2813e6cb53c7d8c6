//! `specula`: renders reflections and refractions on curved mirrors and lenses, and measures
//! how accurate and fast each technique is. See README.md for the commands.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use specula_scene::builtin::{self, DEFAULT_SCENE};
use specula_trace::{render, RenderSettings, SceneAccel};

/// Methods `render` accepts. Later techniques join this list as they land.
const METHODS: &[&str] = &["reference"];

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
        /// PNG output file.
        #[arg(short, long, default_value = "out.png")]
        output: PathBuf,
        /// Also write linear float RGB to this OpenEXR file.
        #[arg(long)]
        exr: Option<PathBuf>,
    },
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
        } => {
            if !METHODS.contains(&method.as_str()) {
                bail!(
                    "unknown method '{method}'; valid methods: {}",
                    METHODS.join(", ")
                );
            }
            let scene =
                specula_scene::load(&scene).with_context(|| format!("loading scene '{scene}'"))?;
            for warning in &scene.warnings {
                eprintln!("warning: {warning}");
            }
            let aspect = scene.camera.aspect.unwrap_or(4.0 / 3.0);
            let height = height.unwrap_or(((width as f32 / aspect).round() as u32).max(1));
            let settings = RenderSettings {
                width,
                height,
                spp,
                max_depth,
            };
            let start = Instant::now();
            let accel = SceneAccel::new(&scene);
            let build = start.elapsed();
            let bar = progress_bar(0, "rendering");
            let start = Instant::now();
            let image = render(&scene, &accel, &settings, &|done, total| {
                bar.set_length(total as u64);
                bar.set_position(done as u64);
            });
            bar.finish_and_clear();
            let elapsed = start.elapsed();
            image.save_png(&output)?;
            if let Some(exr) = &exr {
                image.save_exr(exr)?;
            }
            eprintln!(
                "{}: {} triangles, BVH {:.1} ms, {method} {width}x{height} {spp} spp in {:.2} s -> {}{}",
                scene.name,
                scene.triangle_count(),
                build.as_secs_f64() * 1e3,
                elapsed.as_secs_f64(),
                output.display(),
                exr.map(|e| format!(", {}", e.display())).unwrap_or_default()
            );
            Ok(())
        }
    }
}
