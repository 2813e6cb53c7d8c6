//! `specula`: renders reflections and refractions on curved mirrors and lenses, and measures
//! how accurate and fast each technique is. See README.md for the commands.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use specula_gpu::GpuContext;
use specula_methods::{Context as Devices, Label, LiveScene, MethodInfo};
use specula_scene::builtin::{self, DEFAULT_SCENE};
use specula_scene::Scene;
use specula_trace::Image;

mod analyze;
mod bench;
mod materials;

use materials::Materials;

#[derive(Parser)]
#[command(
    name = "specula",
    version,
    about = "Accurate, measured reflections and refractions on curved mirrors and lenses",
    after_help = "Examples:\n  specula render                      # the default scene with the exact reference -> out.png\n  specula compare door-mirror         # every technique against the reference -> specula-report/\n  specula analyze lens spectacle-lens --lens \"spectacle lens\" --prescription -3.00 --standard iso-8980-1\n\nEvery command and option: docs/cli.md"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// List the built-in scenes.
    #[command(after_help = "Example:\n  specula scenes")]
    Scenes,
    /// List every method with its parameters: kind and range, default, what a change redoes.
    #[command(after_help = "Example:\n  specula methods")]
    Methods,
    /// Render a scene to PNG (sRGB, clamped) and optionally EXR (linear float).
    #[command(
        after_help = "Example:\n  specula render door-mirror --method pvrr -W 640 -o pvrr.png --exr pvrr.exr"
    )]
    Render(RenderArgs),
    /// Render the reference and each method from the same camera; report error and speed.
    /// Several scenes, or a folder of .toml scenes, give one report with a methods × scenes table.
    #[command(
        after_help = "Example:\n  specula compare door-mirror --methods envmap,pvrr,pvrr:paper --report compare-report"
    )]
    Compare(CompareArgs),
    /// Open the interactive viewer: move the eye and objects, switch techniques, compare with
    /// the reference (split and FLIP error views). `--script FILE` runs TOML steps and exits.
    #[command(after_help = "Example:\n  specula view truck-cover --method vertex-tracing")]
    View {
        #[arg(default_value = DEFAULT_SCENE)]
        scene: String,
        /// Technique shown first (`specula methods` lists them; T cycles in the window).
        #[arg(long, short, default_value = "envmap")]
        method: String,
        /// Window size in pixels, WIDTHxHEIGHT.
        #[arg(long, default_value = "640x480", value_parser = parse_size)]
        size: (u32, u32),
        /// Run the [[step]] tables of this TOML file (method, param, orbit, translate, rotate,
        /// frames, drag, view, screenshot) and exit; see crates/specula-viewer/src/script.rs.
        #[arg(long)]
        script: Option<PathBuf>,
        /// The technique's resolution while the view or an object moves, as a fraction of the
        /// window's width and height (full resolution once still).
        #[arg(long, default_value_t = 0.5, value_parser = parse_scale)]
        interaction_scale: f32,
        #[command(flatten)]
        materials: Materials,
    },
    /// Time each method: warm-up, then N frames; median and spread per method and stage, and
    /// each method's speed-up over the CPU reference and over gpu-trace (both always timed too).
    #[command(
        after_help = "Example:\n  specula bench door-mirror --methods envmap,pvrr --frames 20 --markdown bench.md"
    )]
    Bench(BenchArgs),
    /// Answer a design question with exact rays: `mirror-view` (what a mirror shows from the
    /// eye points, or its verdict against UN R46 / FMVSS 111), `glare` (a source or the sun
    /// reflected in a cover, in cd/m², and the display's contrast under it), `lens` (a
    /// spectacle lens as worn, against ANSI Z80.1 / ISO 8980).
    #[command(
        subcommand,
        after_help = "Example:\n  specula analyze mirror-view door-mirror --mirror \"door mirror\" --eyebox 0.3,0.15,5,3 --report mirror-report"
    )]
    Analyze(analyze::Kind),
}

// The subcommands' arguments. (Their help text comes from the `Command` variants' doc
// comments; these structs have none, so that they cannot override it.)

#[derive(clap::Args)]
struct RenderArgs {
    /// Built-in scene name, a .toml scene file, or a mesh/scene/CAD file (.gltf .glb .obj .ply .stl .step .stp).
    #[arg(default_value = DEFAULT_SCENE)]
    scene: String,
    /// Method to render with, or METHOD:PRESET (`specula methods` lists them).
    #[arg(help_heading = "Method", long, short, default_value = "reference")]
    method: String,
    /// Image width in pixels.
    #[arg(help_heading = "Image", short = 'W', long, default_value_t = 640, value_parser = clap::value_parser!(u32).range(1..=16384))]
    width: u32,
    /// Image height in pixels (default: from the width and the camera's aspect ratio, else 480).
    #[arg(help_heading = "Image", short = 'H', long, value_parser = clap::value_parser!(u32).range(1..=16384))]
    height: Option<u32>,
    /// Samples per pixel of the reference: 1 = one ray through each pixel centre; more =
    /// stratified jitter (the reference's `spp` parameter).
    #[arg(help_heading = "Image", long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=4096))]
    spp: u32,
    /// Maximum number of specular bounces on a reference path (its `max_depth` parameter).
    #[arg(help_heading = "Image", long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(0..=64))]
    max_depth: u32,
    /// A technique parameter, NAME=VALUE (repeatable), e.g. `-p resolution=512`.
    #[arg(help_heading = "Method", short = 'p', long = "param")]
    params: Vec<String>,
    /// PNG output file.
    #[arg(help_heading = "Output", short, long, default_value = "out.png")]
    output: PathBuf,
    /// Also write linear float RGB to this OpenEXR file.
    #[arg(help_heading = "Output", long)]
    exr: Option<PathBuf>,
    /// A progressive method's steps as an image sequence: DIR/step-000.png, ... and
    /// DIR/steps.csv with the time and rays of each step (the step time is the method's
    /// `budget_ms`, 100 unless `-p budget_ms=N` says otherwise).
    #[arg(help_heading = "Output", long, value_name = "DIR")]
    sequence: Option<PathBuf>,
    #[command(flatten)]
    materials: Materials,
    #[command(flatten)]
    distributed: DistributedArgs,
}

#[derive(clap::Args)]
struct CompareArgs {
    /// Built-in scene names, scene or mesh files, or folders of .toml scenes.
    #[arg(default_value = DEFAULT_SCENE)]
    scenes: Vec<String>,
    /// Comma-separated methods (default: every method); a method may run several times under
    /// labels METHOD:PRESET, e.g. `c3rc,c3rc:paper` (`specula methods` lists the presets).
    #[arg(help_heading = "Methods", long, value_delimiter = ',')]
    methods: Option<Vec<String>>,
    /// Run each method's published algorithm (its `paper` preset) beside it, as METHOD:paper.
    #[arg(help_heading = "Methods", long)]
    paper: bool,
    /// Folder for report.html, report.json and the images.
    #[arg(help_heading = "Output", long, default_value = "specula-report")]
    report: PathBuf,
    /// A technique parameter, NAME=VALUE (repeatable), e.g. `-p resolution=512`: applied after
    /// the presets to every method that has it; LABEL.NAME=VALUE (`-p c3rc:paper.points=5000`)
    /// to that label only.
    #[arg(help_heading = "Methods", short = 'p', long = "param")]
    params: Vec<String>,
    /// Also write the JSON report here.
    #[arg(help_heading = "Output", long)]
    json: Option<PathBuf>,
    #[arg(help_heading = "Images and timing", short = 'W', long, default_value_t = 320, value_parser = clap::value_parser!(u32).range(1..=16384))]
    width: u32,
    #[arg(help_heading = "Images and timing", short = 'H', long, value_parser = clap::value_parser!(u32).range(1..=16384))]
    height: Option<u32>,
    /// Samples per pixel of the reference.
    #[arg(help_heading = "Images and timing", long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=4096))]
    spp: u32,
    #[arg(help_heading = "Images and timing", long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(0..=64))]
    max_depth: u32,
    /// Warm frames timed per method, the reference's included, after a first frame timed apart:
    /// each time is their median (with the spread), each speed-up a warm median over a warm
    /// median.
    #[arg(help_heading = "Images and timing", long, default_value_t = specula_compare::DEFAULT_FRAMES, value_parser = clap::value_parser!(u32).range(1..=1000))]
    frames: u32,
    #[command(flatten)]
    materials: Materials,
}

#[derive(clap::Args)]
struct BenchArgs {
    /// Built-in scene names or scene/mesh files.
    #[arg(default_value = DEFAULT_SCENE)]
    scenes: Vec<String>,
    /// Comma-separated methods (default: every method), or labels METHOD:PRESET as in
    /// `compare`.
    #[arg(help_heading = "Methods", long, value_delimiter = ',')]
    methods: Option<Vec<String>>,
    /// Time each method's published algorithm (its `paper` preset) beside it, as METHOD:paper.
    #[arg(help_heading = "Methods", long)]
    paper: bool,
    #[arg(help_heading = "Frames", long, default_value_t = 20, value_parser = clap::value_parser!(u32).range(1..=100000))]
    frames: u32,
    /// A technique parameter, NAME=VALUE (repeatable), e.g. `-p resolution=512`; LABEL.NAME=VALUE
    /// for one label only, as in `compare`.
    #[arg(help_heading = "Methods", short = 'p', long = "param")]
    params: Vec<String>,
    /// Write the report (adapter, driver, date, every run) as JSON here.
    #[arg(help_heading = "Output", long)]
    json: Option<PathBuf>,
    /// Write the runs as a markdown table here.
    #[arg(help_heading = "Output", long)]
    markdown: Option<PathBuf>,
    #[arg(help_heading = "Frames", short = 'W', long, default_value_t = 640, value_parser = clap::value_parser!(u32).range(1..=16384))]
    width: u32,
    #[arg(help_heading = "Frames", short = 'H', long, value_parser = clap::value_parser!(u32).range(1..=16384))]
    height: Option<u32>,
    #[command(flatten)]
    materials: Materials,
}

/// Distributed vertex tracing over MPI (`mpirun -np N specula render SCENE --method
/// vertex-tracing --distributed`); built with `--features mpi`.
#[derive(clap::Args)]
struct DistributedArgs {
    /// Run vertex-tracing as MPI master (rank 0) and workers.
    #[arg(
        help_heading = "Distributed vertex tracing (MPI; built with --features mpi)",
        long
    )]
    distributed: bool,
    /// Frames to render (packages are re-sized after each from the workers' measured speeds).
    #[arg(help_heading = "Distributed vertex tracing (MPI; built with --features mpi)", long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=100000))]
    frames: u32,
    /// JSON report of the distributed run: per frame, each worker's packages, triangles, busy
    /// time and speed, the imbalance, and lost ranks.
    #[arg(
        help_heading = "Distributed vertex tracing (MPI; built with --features mpi)",
        long,
        value_name = "FILE"
    )]
    report: Option<PathBuf>,
    /// A worker that leaves a package unanswered this long is lost (its packages go to the
    /// others).
    #[arg(help_heading = "Distributed vertex tracing (MPI; built with --features mpi)", long, default_value_t = 30000, value_parser = clap::value_parser!(u64).range(1..))]
    worker_timeout_ms: u64,
    /// Packages each worker asks for per frame at the frame's start.
    #[arg(help_heading = "Distributed vertex tracing (MPI; built with --features mpi)", long, default_value_t = 4, value_parser = clap::value_parser!(u64).range(1..=10000))]
    packages_per_worker: u64,
    /// Testing aid: RANK:FACTOR makes that worker FACTOR times slower (it sleeps).
    #[arg(help_heading = "Distributed vertex tracing (MPI; built with --features mpi)", long, value_name = "RANK:FACTOR", value_parser = parse_slow_rank)]
    slow_rank: Option<(usize, f64)>,
    /// Testing aid: RANK:N makes that worker die on receiving its N-th package.
    #[arg(help_heading = "Distributed vertex tracing (MPI; built with --features mpi)", long, value_name = "RANK:N", value_parser = parse_fail_rank)]
    fail_rank: Option<(usize, u32)>,
}

fn parse_rank_pair(text: &str) -> Result<(usize, &str), String> {
    let (rank, value) = text
        .split_once(':')
        .ok_or_else(|| format!("expected RANK:VALUE, got '{text}'"))?;
    let rank = rank
        .parse::<usize>()
        .ok()
        .filter(|&r| r >= 1)
        .ok_or_else(|| format!("expected a worker rank (1 or more), got '{rank}'"))?;
    Ok((rank, value))
}

fn parse_slow_rank(text: &str) -> Result<(usize, f64), String> {
    let (rank, factor) = parse_rank_pair(text)?;
    let factor = factor
        .parse::<f64>()
        .ok()
        .filter(|f| f.is_finite() && *f >= 1.0)
        .ok_or_else(|| format!("expected a slow-down factor of 1 or more, got '{factor}'"))?;
    Ok((rank, factor))
}

fn parse_fail_rank(text: &str) -> Result<(usize, u32), String> {
    let (rank, n) = parse_rank_pair(text)?;
    let n = n
        .parse::<u32>()
        .ok()
        .filter(|n| *n >= 1)
        .ok_or_else(|| format!("expected a package number of 1 or more, got '{n}'"))?;
    Ok((rank, n))
}

/// `WIDTHxHEIGHT`, each from 1 to 16384.
pub(crate) fn parse_size(text: &str) -> Result<(u32, u32), String> {
    let (w, h) = text
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WIDTHxHEIGHT, e.g. 640x480, got '{text}'"))?;
    let side = |s: &str| {
        s.trim()
            .parse::<u32>()
            .ok()
            .filter(|v| (1..=16384).contains(v))
            .ok_or_else(|| format!("'{s}' is not a whole number from 1 to 16384"))
    };
    Ok((side(w)?, side(h)?))
}

/// A fraction from 0.125 to 1.
fn parse_scale(text: &str) -> Result<f32, String> {
    text.trim()
        .parse::<f32>()
        .ok()
        .filter(|v| (0.125..=1.0).contains(v))
        .ok_or_else(|| format!("expected a number from 0.125 to 1, got '{text}'"))
}

/// Scene `name` with the `--material` overrides (with `several` scenes in the run, those whose
/// object it has), its warnings printed.
pub(crate) fn load_scene(name: &str, materials: &Materials, several: bool) -> Result<Scene> {
    let mut scene = specula_scene::load(name).with_context(|| format!("loading scene '{name}'"))?;
    materials.apply(&mut scene, several)?;
    for warning in &scene.warnings {
        eprintln!("warning: {warning}");
    }
    Ok(scene)
}

/// The height for `width` keeping the camera's aspect ratio (4:3 when it has none).
fn height_for(scene: &Scene, width: u32, height: Option<u32>) -> u32 {
    let aspect = scene.camera.aspect.unwrap_or(4.0 / 3.0);
    height.unwrap_or(((width as f32 / aspect).round() as u32).clamp(1, 16384))
}

/// The devices `methods` need: a GPU only where one of them needs it.
fn context_for(methods: &[&MethodInfo]) -> Result<Devices> {
    if !methods.iter().any(|m| m.needs_gpu) {
        if !methods.iter().any(|m| m.gpu_optional) {
            return Ok(Devices::default());
        }
        // A method that uses a GPU where there is one runs on the CPU alone where there is not.
        return Ok(match GpuContext::new() {
            Ok(gpu) => {
                eprintln!("GPU: {}", gpu.describe());
                Devices::with_gpu(gpu)
            }
            Err(e) => {
                eprintln!("no GPU ({e}): running on the CPU alone");
                Devices::default()
            }
        });
    }
    let gpu = GpuContext::new()?;
    eprintln!("GPU: {}", gpu.describe());
    Ok(Devices::with_gpu(gpu))
}

/// The labels of a run, from `--methods` (or `default`), with each one's `paper` preset
/// beside it where `paper` asks for it and it is not there already.
fn run_labels(
    methods: &Option<Vec<String>>,
    default: impl FnOnce() -> Vec<String>,
    paper: bool,
) -> Result<Vec<Label>> {
    let given = methods.clone().unwrap_or_else(default);
    let mut labels = Label::parse_list(&given)?;
    if paper {
        let mut with_paper = Vec::new();
        for label in &labels {
            with_paper.push(*label);
            if let Some(preset) = label
                .info
                .preset("paper")
                .filter(|_| label.preset.is_none())
            {
                let paper = Label {
                    info: label.info,
                    preset: Some(preset),
                };
                if !labels.contains(&paper) {
                    with_paper.push(paper);
                }
            }
        }
        labels = with_paper;
    }
    Ok(labels)
}

fn label_names(labels: &[Label]) -> Vec<String> {
    labels.iter().map(Label::to_string).collect()
}

/// `specula methods`: every registered method and its parameters, from the registry's specs.
fn print_methods() {
    for m in specula_methods::METHODS {
        let mut traits = Vec::new();
        if m.exact {
            traits.push("exact");
        }
        traits.push(match (m.needs_gpu, m.gpu_optional) {
            (true, _) => "GPU",
            (false, true) => "CPU, GPU where present",
            (false, false) => "CPU",
        });
        if m.progressive {
            traits.push("progressive");
        }
        print!(
            "{}",
            wrap(
                &format!("{} ({}): {}", m.name, traits.join(", "), m.summary),
                4
            )
        );
        for p in m.params {
            let takes = format!(
                "    {:<18} {} (default {}); change redoes: {}",
                p.name,
                p.kind.describe(),
                p.default,
                p.invalidates.describe()
            );
            print!("{}", wrap(&takes, 23));
            print!("{}", wrap(&format!("    {:<18} {}", "", p.doc), 23));
        }
        for preset in m.presets {
            let line = format!("  preset {}:{}: {}", m.name, preset.name, preset.summary);
            print!("{}", wrap(&line, 6));
            for setting in preset.settings {
                let name = setting.split_once('=').map_or(*setting, |(n, _)| n);
                let default = m.param(name).map_or("?", |p| p.default);
                println!("      {setting:<28} instead of {default}");
            }
        }
    }
}

fn print_comparison(r: &specula_compare::Report) {
    println!(
        "{} at {}x{}, {} reflector/refractor pixels; reference warm frame {:.1} ms (median of {}, {:.1}-{:.1}; BVH build {:.1} ms, first frame {:.1} ms apart)",
        r.scene,
        r.width,
        r.height,
        r.mask_pixels,
        r.reference.total_ms,
        r.frames,
        r.reference.frame.min_ms,
        r.reference.frame.max_ms,
        r.reference.build_ms,
        r.reference.first_frame_ms
    );
    println!(
        "frame ms: the median of {} warm frames; speed-ups divide warm medians",
        r.frames
    );
    println!(
        "{:<16}{:>9}{:>11}{:>11}{:>11}{:>12}{:>10}{:>14}",
        "method",
        "RMSE",
        "PSNR dB",
        "mean FLIP",
        "FLIP>0.1",
        "frame ms",
        "speed-up",
        "vs gpu-trace"
    );
    for warning in r.methods.iter().flat_map(|m| &m.warnings) {
        eprintln!("warning: {warning}");
    }
    let figures = |m: &specula_compare::Metrics| {
        format!(
            "{:>9.4}{:>11}{:>11.4}{:>10.1}%",
            m.rmse,
            m.psnr_db
                .map(|p| format!("{p:.1}"))
                .unwrap_or_else(|| "inf".into()),
            m.mean_flip,
            m.share_flip_over_0_1 * 100.0
        )
    };
    for m in &r.methods {
        println!(
            "{:<16}{:>42}{:>12.2}{:>9.2}x{:>14}",
            m.label,
            m.metrics
                .as_ref()
                .map(figures)
                .unwrap_or_else(|| "all delegated (below)".into()),
            m.total_ms,
            m.speedup_over_reference,
            m.speedup_over_gpu_trace
                .map(|v| format!("{v:.2}x"))
                .unwrap_or_else(|| "-".into())
        );
        for d in &m.delegated {
            println!(
                "{:<16}{:>42}  {} pixels shaded by {}: its figure, not {}'s",
                format!("  {}", d.material),
                figures(&d.metrics),
                d.metrics.mask_pixels,
                d.delegate,
                m.label
            );
        }
    }
    for f in &r.failed {
        println!("{:<16}failed: {}", f.label, f.error);
    }
}

/// The methods × scenes table: mean FLIP (warm median frame ms) per cell.
fn print_suite(summary: &specula_compare::suite::SuiteReport) {
    println!("Each cell: mean FLIP (the median of the warm frames' times, ms); the reference is timed warm alike");
    let width = summary
        .scenes
        .iter()
        .map(|r| r.scene.len().max(r.source.len().min(40)))
        .max()
        .unwrap_or(5)
        .max(5);
    print!("{:<width$}{:>16}", "scene", "reference (ms)");
    for m in &summary.methods {
        print!("{:>22}", format!("{m} FLIP (ms)"));
    }
    println!();
    for row in &summary.scenes {
        if let Some(error) = &row.error {
            println!("{:<width$}  error: {error}", row.source);
            continue;
        }
        print!("{:<width$}{:>16.1}", row.scene, row.reference_ms);
        for m in &summary.methods {
            match row.methods.iter().find(|c| &c.label == m) {
                Some(c) => print!("{:>22}", format!("{} ({:.1})", c.flip_text(), c.total_ms)),
                None if row.failure(m).is_some() => print!("{:>22}", "failed"),
                None => print!("{:>22}", "-"),
            }
        }
        println!();
        for f in &row.failed {
            println!("{:<width$}  {} failed: {}", "", f.label, f.error);
        }
    }
}

fn spinner() -> ProgressBar {
    let bar = ProgressBar::new_spinner();
    bar.set_style(
        ProgressStyle::with_template("{spinner} {msg} ({elapsed})").expect("valid template"),
    );
    bar.enable_steady_tick(std::time::Duration::from_millis(120));
    bar
}

fn main() -> std::process::ExitCode {
    quiet_on_a_closed_pipe();
    match run(Cli::parse()) {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}

/// `specula methods | head`: output to a pipe its reader closed ends the program quietly, as
/// other Unix tools do, instead of a panic on the next line printed. Rust ignores SIGPIPE by
/// default; this puts the system's default action back.
fn quiet_on_a_closed_pipe() {
    #[cfg(unix)]
    // SAFETY: signal() with SIG_DFL installs no handler of ours; it runs before any thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Scenes => {
            print_scenes();
            Ok(())
        }
        Command::Methods => {
            print_methods();
            print_ray_queries();
            Ok(())
        }
        Command::Render(args) => render(args),
        Command::Compare(args) => compare(args),
        Command::View {
            scene,
            method,
            size,
            script,
            interaction_scale,
            materials,
        } => Ok(specula_viewer::run(specula_viewer::Options {
            scene,
            method,
            size,
            script,
            interaction_scale,
            materials: materials.materials,
        })?),
        Command::Bench(args) => bench(args),
        Command::Analyze(kind) => analyze::run(kind),
    }
}

/// `specula scenes`: the built-in scenes, the default marked.
fn print_scenes() {
    for (name, description) in builtin::list() {
        let marker = if name == DEFAULT_SCENE {
            " (default)"
        } else {
            ""
        };
        print!("{}", wrap(&format!("{name:<22}{description}{marker}"), 22));
    }
}

/// The width the listings fit in.
const LISTING_COLUMNS: usize = 100;

/// `line` broken at spaces into lines of at most [`LISTING_COLUMNS`] characters (a word longer
/// than that stands alone), the lines after the first indented by `indent` spaces; each line
/// ends with a newline.
fn wrap(line: &str, indent: usize) -> String {
    let body = line.trim_start();
    let mut out = String::new();
    let mut current = line[..line.len() - body.len()].to_string();
    let mut first = true;
    // Split on single spaces so that padding (runs of spaces) is kept within a line.
    for word in body.split(' ') {
        let fits = current.chars().count() + 1 + word.chars().count() <= LISTING_COLUMNS;
        if !first && !fits && !word.is_empty() && !current.trim().is_empty() {
            out.push_str(current.trim_end());
            out.push('\n');
            current = " ".repeat(indent);
        } else if !first {
            current.push(' ');
        }
        current.push_str(word);
        first = false;
    }
    out.push_str(current.trim_end());
    out.push('\n');
    out
}

/// The end of `specula methods`: the GPU, and whether it offers hardware ray queries
/// (reported, not used: gpu_trace's module doc says why).
fn print_ray_queries() {
    match GpuContext::new() {
        Ok(gpu) => print!(
            "\n{}",
            wrap(
                &format!(
                    "GPU: {}; hardware ray queries: {}",
                    gpu.describe(),
                    if specula_methods::gpu_trace::ray_queries_supported(&gpu) {
                        "offered (gpu-trace still traverses its BVH in compute shaders)"
                    } else {
                        "not offered (gpu-trace traverses its BVH in compute shaders)"
                    }
                ),
                4
            )
        ),
        Err(e) => print!("\n{}", wrap(&format!("no GPU: {e}"), 4)),
    }
}

/// `specula render`: one frame (or, with `--sequence`, a progressive method's steps) written
/// as PNG and optionally EXR, with a line of its timings and counters; `--distributed` runs
/// vertex tracing over MPI instead.
fn render(args: RenderArgs) -> Result<()> {
    let scene = load_scene(&args.scene, &args.materials, false)?;
    let (width, height) = (args.width, height_for(&scene, args.width, args.height));
    let label = Label::parse(&args.method)?;
    let method = label.to_string();
    if args.distributed.distributed {
        return render_distributed(scene, height, label, &args);
    }
    let mut technique = technique_for_render(label, &args)?;
    let ctx = context_for(&[label.info])?;
    let start = Instant::now();
    let live = LiveScene::new(scene);
    let build = start.elapsed();
    let scene = live.scene();
    let bar = spinner();
    bar.set_message(format!("rendering with {method}"));
    technique.prepare(&ctx, &live)?;
    let start = Instant::now();
    let frame = match &args.sequence {
        Some(dir) => write_sequence(technique.as_mut(), &ctx, &live, width, height, dir, &bar)?,
        None => technique.render(&ctx, &live, &scene.camera, width, height)?,
    };
    let image: Image = frame.image(&ctx)?;
    bar.finish_and_clear();
    for warning in &frame.warnings {
        eprintln!("warning: {warning}");
    }
    let counters: Vec<String> = frame
        .counters
        .iter()
        .map(|(name, value)| format!("{name} {value}"))
        .collect();
    let summary = format!(
        "BVH {:.1} ms, {method} {width}x{height} in {:.1} ms ({})",
        build.as_secs_f64() * 1e3,
        start.elapsed().as_secs_f64() * 1e3,
        counters.join(", ")
    );
    save_image(&image, &args.output, args.exr.as_deref())?;
    eprintln!(
        "{}: {} triangles, {summary} -> {}{}",
        scene.name,
        scene.triangle_count(),
        args.output.display(),
        args.exr
            .as_ref()
            .map(|e| format!(", {}", e.display()))
            .unwrap_or_default()
    );
    Ok(())
}

/// The technique `render` draws with: `label`'s (its preset applied), with the reference's
/// `--spp` and `--max-depth` where it is exact, the `-p` parameters, and a step time for
/// `--sequence`.
fn technique_for_render(
    label: Label,
    args: &RenderArgs,
) -> Result<Box<dyn specula_methods::Technique>> {
    let (method, spp, max_depth) = (&args.method, args.spp, args.max_depth);
    let info = label.info;
    specula_methods::check_settings(&[label], &args.params)?;
    let mut technique = label.create()?;
    if info.exact {
        if spp > 1 && info.param("spp").is_none() {
            anyhow::bail!(
                "{method} traces one ray per pixel centre; --spp {spp} needs the CPU reference"
            );
        }
        specula_methods::apply_known_parameters(
            technique.as_mut(),
            &[format!("spp={spp}"), format!("max_depth={max_depth}")],
        )?;
    }
    for setting in label.settings_for(&args.params) {
        specula_methods::apply_setting(technique.as_mut(), setting)?;
    }
    if args.sequence.is_some() && !info.progressive {
        anyhow::bail!("--sequence needs a progressive method; {method} draws each frame at once");
    }
    if args.sequence.is_some() && technique.parameter("budget_ms") == "0" {
        specula_methods::apply_setting(technique.as_mut(), "budget_ms=100")?;
    }
    Ok(technique)
}

/// Writes `image` as PNG to `output` and, when asked, as OpenEXR to `exr`.
fn save_image(image: &Image, output: &Path, exr: Option<&Path>) -> Result<()> {
    image.save_png(output)?;
    if let Some(exr) = exr {
        image.save_exr(exr)?;
    }
    Ok(())
}

/// `specula compare`: one scene's report, or with several scenes (or a folder) the suite's.
/// By default every method but the CPU reference, which is the ground truth; gpu-trace among
/// them shows its own error (none) and is the base of the second speed-up.
fn compare(args: CompareArgs) -> Result<()> {
    let labels = run_labels(
        &args.methods,
        || {
            let mut all = specula_methods::approximate_methods();
            all.insert(0, specula_methods::gpu_trace::INFO.name.to_string());
            all
        },
        args.paper,
    )?;
    specula_methods::check_settings(&labels, &args.params)?;
    let methods = label_names(&labels);
    let mut infos: Vec<&MethodInfo> = labels.iter().map(|l| l.info).collect();
    infos.push(specula_methods::exact_method());
    let is_suite = args.scenes.len() > 1 || args.scenes.iter().any(|s| PathBuf::from(s).is_dir());
    if is_suite {
        return compare_suite(&args, &methods, &infos);
    }
    let scene = load_scene(&args.scenes[0], &args.materials, false)?;
    let ctx = context_for(&infos)?;
    let bar = spinner();
    let options = compare_options(&args, &methods, &scene);
    let comparison = specula_compare::compare(&scene, &ctx, &options, &|stage| {
        bar.set_message(format!("rendering {stage}"))
    })
    .map_err(compare_error)?;
    bar.finish_and_clear();
    let html = comparison.write_report(&args.report)?;
    if let Some(json) = &args.json {
        comparison.write_json(json)?;
    }
    print_comparison(&comparison.report);
    println!("report: {}", html.display());
    let failed = &comparison.report.failed;
    if !failed.is_empty() {
        let labels: Vec<&str> = failed.iter().map(|f| f.label.as_str()).collect();
        anyhow::bail!(
            "{} failed (see above); the other methods' figures are in the report",
            labels.join(", ")
        );
    }
    Ok(())
}

/// A compare error in the command line's words: an option named `` `name` `` as its flag.
fn compare_error(e: specula_compare::CompareError) -> anyhow::Error {
    match e {
        specula_compare::CompareError::EmptyMask { .. } => {
            anyhow::anyhow!(analyze::flags_in(&e.to_string()))
        }
        other => other.into(),
    }
}

/// What `compare` measures `scene` with.
fn compare_options(
    args: &CompareArgs,
    methods: &[String],
    scene: &Scene,
) -> specula_compare::Options {
    specula_compare::Options {
        parameters: args.params.clone(),
        width: args.width,
        height: height_for(scene, args.width, args.height),
        methods: methods.to_vec(),
        spp: args.spp,
        max_depth: args.max_depth,
        frames: args.frames,
    }
}

/// `specula compare` over several scenes: each scene's report in its own folder, then the
/// summary (methods × scenes) as HTML, optionally JSON, and a table; fails after the summary
/// when any scene failed.
fn compare_suite(args: &CompareArgs, methods: &[String], infos: &[&MethodInfo]) -> Result<()> {
    let sources = specula_compare::suite::expand_scenes(&args.scenes)?;
    args.materials.check_in(&sources)?;
    let ctx = context_for(infos)?;
    let rows = compare_each_scene(&sources, &ctx, args, methods)?;
    let summary = specula_compare::suite::SuiteReport {
        schema_version: specula_compare::suite::SCHEMA_VERSION,
        adapter: ctx.describe(),
        methods: methods.to_vec(),
        scenes: rows,
    };
    let html = specula_compare::suite::write_summary(&args.report, &summary)?;
    if let Some(json) = &args.json {
        std::fs::write(json, serde_json::to_string_pretty(&summary)?)
            .with_context(|| format!("writing {}", json.display()))?;
    }
    print_suite(&summary);
    println!("report: {}", html.display());
    let failed = summary.scenes.iter().filter(|r| r.error.is_some()).count();
    if failed > 0 {
        anyhow::bail!(
            "{failed} of {} scenes failed (see above)",
            summary.scenes.len()
        );
    }
    let failed_methods: usize = summary.scenes.iter().map(|r| r.failed.len()).sum();
    if failed_methods > 0 {
        anyhow::bail!(
            "{failed_methods} method runs failed (see above); the others' figures are in the report"
        );
    }
    Ok(())
}

/// Compares each of `sources` in turn under a progress bar, writing its report into its own
/// folder of `--report`; a scene that fails to load or compare gives a row holding its error.
/// Prints a line per scene.
fn compare_each_scene(
    sources: &[String],
    ctx: &Devices,
    args: &CompareArgs,
    methods: &[String],
) -> Result<Vec<specula_compare::suite::SuiteRow>> {
    let bar = ProgressBar::new(sources.len() as u64);
    bar.set_style(
        ProgressStyle::with_template("{bar:30} {pos}/{len} {msg} ({elapsed})")
            .expect("valid template"),
    );
    let mut rows = Vec::new();
    let mut taken = Vec::new();
    for source in sources {
        bar.set_message(source.clone());
        let outcome = specula_scene::load(source)
            .map_err(anyhow::Error::from)
            .and_then(|mut scene| {
                args.materials.apply(&mut scene, true)?;
                for warning in &scene.warnings {
                    bar.suspend(|| eprintln!("warning: {source}: {warning}"));
                }
                specula_compare::compare(
                    &scene,
                    ctx,
                    &compare_options(args, methods, &scene),
                    &|stage| bar.set_message(format!("{source}: {stage}")),
                )
                .map_err(compare_error)
            })
            .map_err(|e| format!("{e:#}"));
        let row = specula_compare::suite::scene_row(
            &args.report,
            source,
            outcome.as_ref().map_err(String::as_str),
            &mut taken,
        )?;
        let line = match &row.error {
            Some(e) => format!("error: {source}: {e}"),
            None => format!(
                "{}: {}",
                row.scene,
                row.methods
                    .iter()
                    .map(|c| format!("{} {}", c.label, c.flip_text()))
                    .chain(row.failed.iter().map(|f| format!("{} failed", f.label)))
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        };
        // Printed through the bar so that it works with and without a terminal.
        bar.suspend(|| eprintln!("{line}"));
        rows.push(row);
        bar.inc(1);
    }
    bar.finish_and_clear();
    Ok(rows)
}

/// `specula bench`: every method asked for (and the exact bases) timed on each scene; the
/// table printed, the report optionally written as JSON and markdown.
fn bench(args: BenchArgs) -> Result<()> {
    let labels = run_labels(
        &args.methods,
        || {
            specula_methods::METHODS
                .iter()
                .map(|m| m.name.to_string())
                .collect()
        },
        args.paper,
    )?;
    specula_methods::check_settings(&labels, &args.params)?;
    let methods = label_names(&labels);
    let asked: Vec<&MethodInfo> = labels.iter().map(|l| l.info).collect();
    let ctx = context_for(&asked)?;
    let timed = bench::with_bases(&methods, ctx.gpu.is_some());
    let several = args.scenes.len() > 1;
    if several {
        args.materials.check_in(&args.scenes)?;
    }
    let mut runs = Vec::new();
    let mut failed = Vec::new();
    for source in &args.scenes {
        let scene = load_scene(source, &args.materials, several)?;
        let height = height_for(&scene, args.width, args.height);
        let (scene_runs, scene_failed) = bench::run(
            scene,
            &ctx,
            &timed,
            &methods,
            &args.params,
            args.width,
            height,
            args.frames,
        )?;
        runs.extend(scene_runs);
        failed.extend(scene_failed);
    }
    bench::add_ratios(&mut runs);
    bench::print(&runs, &failed);
    let report = bench_report(&ctx, runs, failed);
    if let Some(json) = &args.json {
        std::fs::write(json, serde_json::to_string_pretty(&report)?)
            .with_context(|| format!("writing {}", json.display()))?;
    }
    if let Some(markdown) = &args.markdown {
        std::fs::write(markdown, bench::markdown(&report))
            .with_context(|| format!("writing {}", markdown.display()))?;
    }
    if !report.failed.is_empty() {
        anyhow::bail!(
            "{} runs failed (see above); the others were timed",
            report.failed.len()
        );
    }
    Ok(())
}

/// The bench report of `runs`: the adapter and driver of `ctx`, today's date, and whether the
/// adapter offers hardware ray queries.
fn bench_report(
    ctx: &Devices,
    runs: Vec<bench::MethodBench>,
    failed: Vec<bench::BenchFailure>,
) -> bench::BenchReport {
    bench::BenchReport {
        schema_version: bench::SCHEMA_VERSION,
        adapter: ctx.describe(),
        driver: ctx
            .gpu
            .as_ref()
            .map(|g| {
                format!("{} {}", g.adapter_info.driver, g.adapter_info.driver_info)
                    .trim()
                    .to_string()
            })
            .unwrap_or_default(),
        date: bench::utc_date(),
        ray_queries: ctx
            .gpu
            .as_ref()
            .is_some_and(specula_methods::gpu_trace::ray_queries_supported),
        runs,
        failed,
    }
}

/// `render --distributed`: vertex tracing over MPI
/// (`specula_methods::vertex_tracing::distributed`), `height` pixels high; rank 0 writes the
/// image and the report.
fn render_distributed(scene: Scene, height: u32, label: Label, args: &RenderArgs) -> Result<()> {
    use specula_methods::vertex_tracing::{VertexTracing, INFO};
    if label.info.name != INFO.name {
        anyhow::bail!("--distributed runs {}, not {label}", INFO.name);
    }
    specula_methods::check_settings(&[label], &args.params)?;
    let mut technique = VertexTracing::default();
    let preset = label.preset.map_or(&[][..], |p| p.settings);
    for setting in preset
        .iter()
        .copied()
        .chain(label.settings_for(&args.params))
    {
        specula_methods::apply_setting(&mut technique, setting)?;
    }
    #[cfg(feature = "mpi")]
    {
        use specula_methods::vertex_tracing::distributed::{self, Outcome};
        let d = &args.distributed;
        let options = distributed::Options {
            frames: d.frames,
            width: args.width,
            height,
            params: technique.params,
            packages_per_worker: d.packages_per_worker as usize,
            timeout: std::time::Duration::from_millis(d.worker_timeout_ms),
            slow: d.slow_rank,
            fail: d.fail_rank,
        };
        // The files are written while MPI still runs: finalising can hang on a dead rank.
        let write_outputs: distributed::Deliver = Box::new(|image, report| {
            let written = (|| -> Result<()> {
                save_image(image, &args.output, args.exr.as_deref())?;
                if let Some(path) = &d.report {
                    std::fs::write(path, serde_json::to_string_pretty(report)?)
                        .with_context(|| format!("writing {}", path.display()))?;
                }
                Ok(())
            })();
            written.map_err(Into::into)
        });
        match distributed::run(scene, &options, write_outputs)? {
            Outcome::Master { report, .. } => {
                eprintln!(
                    "distributed vertex tracing: {} ranks, {} frame(s) -> {}{}",
                    report.ranks(),
                    report.frames(),
                    args.output.display(),
                    if report.lost_ranks().is_empty() {
                        String::new()
                    } else {
                        format!("; lost ranks {:?}", report.lost_ranks())
                    }
                );
                Ok(())
            }
            Outcome::Worker => Ok(()),
        }
    }
    #[cfg(not(feature = "mpi"))]
    {
        let _ = (scene, height, technique);
        anyhow::bail!(
            "this specula was built without MPI: build it with `cargo build --release --features mpi` (needs OpenMPI: apt-get install openmpi-bin libopenmpi-dev libclang-dev)"
        )
    }
}

/// Renders a progressive method's steps until it converges, writing each step's image as
/// DIR/step-NNN.png and a line of DIR/steps.csv (its time, and its rays as the method counts
/// them: vertex-tracing counts the whole image so far, the reference each call's). Returns the
/// last frame.
fn write_sequence(
    technique: &mut dyn specula_methods::Technique,
    ctx: &Devices,
    live: &LiveScene,
    width: u32,
    height: u32,
    dir: &Path,
    bar: &ProgressBar,
) -> Result<specula_methods::Frame> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let mut csv = String::from(
        "step,image,milliseconds,total milliseconds,rays traced,shadow rays,samples\n",
    );
    let counter = |frame: &specula_methods::Frame, name: &str| {
        frame
            .counters
            .iter()
            .find(|(n, _)| n.starts_with(name))
            .map_or(0, |(_, v)| *v)
    };
    let mut total_ms = 0.0;
    for step in 0.. {
        let clock = Instant::now();
        let frame = technique.render(ctx, live, &live.scene().camera, width, height)?;
        let ms = clock.elapsed().as_secs_f64() * 1e3;
        total_ms += ms;
        let name = format!("step-{step:03}.png");
        frame.image(ctx)?.save_png(&dir.join(&name))?;
        csv.push_str(&format!(
            "{step},{name},{ms:.1},{total_ms:.1},{},{},{}\n",
            counter(&frame, specula_methods::COUNTER_RAYS_TRACED),
            counter(&frame, specula_methods::COUNTER_SHADOW_RAYS),
            counter(&frame, "samples")
        ));
        bar.set_message(format!("step {step}: {total_ms:.0} ms"));
        if frame.converged {
            let path = dir.join("steps.csv");
            std::fs::write(&path, csv).with_context(|| format!("writing {}", path.display()))?;
            return Ok(frame);
        }
    }
    unreachable!("the loop returns")
}

#[cfg(test)]
mod cli_reference_tests {
    use super::Cli;

    /// docs/cli.md: every command's and subcommand's help, as clap renders it from the definitions
    /// above. A test holds the file to them; `SPECULA_REGENERATE=1` writes it again.
    fn cli_reference() -> String {
        use clap::CommandFactory;
        fn section(out: &mut String, command: &mut clap::Command, path: &str) {
            let help = command.render_long_help().to_string();
            out.push_str(&format!(
                "\n## `{path}`\n\n```text\n{}\n```\n",
                help.trim_end()
            ));
            let names: Vec<String> = command
                .get_subcommands()
                .filter(|c| c.get_name() != "help" && !c.is_hide_set())
                .map(|c| c.get_name().to_string())
                .collect();
            for name in names {
                let sub = command.find_subcommand_mut(&name).expect("listed above");
                section(out, sub, &format!("{path} {name}"));
            }
        }
        let mut out = String::from(
            "# specula's commands\n\nEvery command and option, as `specula help` prints them \
             (generated from the command's definitions: `SPECULA_REGENERATE=1 cargo test -p \
             specula-cli --bin specula cli_reference` writes this file again; a test holds it \
             current).\n",
        );
        let mut command = Cli::command().term_width(100);
        command.build();
        section(&mut out, &mut command, "specula");
        out
    }

    /// docs/cli.md is what the command's definitions print now.
    #[test]
    fn docs_cli_md_is_the_commands_help_as_it_is_now() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/cli.md");
        let now = cli_reference();
        if std::env::var_os("SPECULA_REGENERATE").is_some() {
            std::fs::write(&path, &now).unwrap();
        }
        let written = std::fs::read_to_string(&path).unwrap_or_default();
        assert!(
            written == now,
            "docs/cli.md is out of date: run SPECULA_REGENERATE=1 cargo test -p specula-cli --bin specula cli_reference"
        );
    }
}
