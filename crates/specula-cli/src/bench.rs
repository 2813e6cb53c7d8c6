//! `specula bench`: per scene, a warm-up then N timed rounds of one frame of each method (so
//! that a drift of the machine's speed during the run slows them alike); the median and the
//! spread (min, max) of each method's frame time and of each stage. Every method is prepared
//! before the first round and kept until the last (memory holds them all at once). A method with a `dynamic` parameter is
//! timed twice: static (its scene-only maps kept, as in a still scene) and dynamic (redrawn every
//! frame, as the papers do for moving scenes).
//!
//! Every run is also put beside the two exact methods of the same scene, timed in the same
//! process: its speed-up over the CPU `reference` and over `gpu-trace` (the exact answer on the
//! same GPU), each the exact method's median frame time over the run's. Methods that count
//! their rays (the exact ones) also get rays per second (closest-hit and shadow rays alike).

use anyhow::Result;
use serde::Serialize;
use specula_methods::{Context, Label, LiveScene};

/// The version of [`BenchReport`]'s JSON. 3: runs are keyed by `label` (`c3rc`,
/// `c3rc:paper`), with the method and the preset it ran. 4: `failed` lists the runs that
/// failed, with their errors.
pub const SCHEMA_VERSION: u32 = 4;
use specula_scene::Scene;

/// The exact methods every run is compared with: the CPU reference and gpu-trace.
fn cpu_reference() -> &'static str {
    specula_methods::exact_method().name
}

fn gpu_trace() -> &'static str {
    specula_methods::gpu_trace::INFO.name
}

/// Frames rendered and thrown away before timing (pipeline creation, first-use costs).
const WARM_UP_FRAMES: u32 = 2;

pub use specula_compare::Spread;

#[derive(Debug, Serialize)]
pub struct MethodBench {
    pub scene: String,
    /// `method`, or `method:preset`.
    pub label: String,
    pub method: String,
    /// The preset it ran (null: the method's defaults).
    pub preset: Option<String>,
    /// "static", "dynamic", or "-" for a method without scene-only maps.
    pub mode: String,
    pub parameters: Vec<(String, String)>,
    pub frames: u32,
    pub width: u32,
    pub height: u32,
    pub adapter: String,
    pub timing: String,
    pub prepare_ms: f64,
    pub frame: Spread,
    pub stages: Vec<(String, Spread)>,
    /// GPU textures + buffers + bind groups created over the timed frames.
    pub created: u64,
    /// What the technique counted in the last timed frame (its `Frame::counters`).
    pub counters: Vec<(String, u64)>,
    /// The CPU reference's median frame time over this run's, on the same scene.
    pub speedup_over_reference: Option<f64>,
    /// gpu-trace's median frame time over this run's, on the same scene and GPU.
    pub speedup_over_gpu_trace: Option<f64>,
    /// Closest-hit plus shadow rays of the last frame over the median frame time (methods that
    /// count rays).
    pub rays_per_second: Option<f64>,
}

/// A method that failed on a scene (to prepare, or to render a frame): its row holds the
/// error; the other methods are timed without it.
#[derive(Debug, Serialize)]
pub struct BenchFailure {
    pub scene: String,
    pub label: String,
    pub mode: String,
    /// The error and its causes, outermost first.
    pub error: String,
}

/// A whole `specula bench` run: where and when, and every run of every scene.
#[derive(Debug, Serialize)]
pub struct BenchReport {
    pub schema_version: u32,
    pub adapter: String,
    pub driver: String,
    /// UTC, YYYY-MM-DD.
    pub date: String,
    /// Whether the adapter offers hardware ray queries (gpu-trace does not use them).
    pub ray_queries: bool,
    pub runs: Vec<MethodBench>,
    /// The runs that failed, each with its error (version 4).
    pub failed: Vec<BenchFailure>,
}

/// Today's UTC date as YYYY-MM-DD.
pub fn utc_date() -> String {
    civil_date(
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map(|d| d.as_secs())
            .unwrap_or(0),
    )
}

/// The UTC date of a Unix time (civil-from-days, Howard Hinnant's algorithm).
fn civil_date(seconds: u64) -> String {
    let z = (seconds / 86_400) as i64 + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!("{year:04}-{month:02}-{day:02}")
}

/// The methods a bench times: those asked for, then the exact ones the ratios need (gpu-trace
/// only where there is a GPU).
pub fn with_bases(methods: &[String], has_gpu: bool) -> Vec<String> {
    let mut all = methods.to_vec();
    for base in [cpu_reference(), gpu_trace()] {
        if (base != gpu_trace() || has_gpu) && !all.iter().any(|m| m == base) {
            all.push(base.to_string());
        }
    }
    all
}

/// Fills each run's speed-ups from the exact methods' runs on its scene.
pub fn add_ratios(runs: &mut [MethodBench]) {
    let median_of = |runs: &[MethodBench], scene: &str, method: &str| {
        runs.iter()
            .find(|r| r.scene == scene && r.label == method)
            .map(|r| r.frame.median_ms)
    };
    for i in 0..runs.len() {
        let (scene, median) = (runs[i].scene.clone(), runs[i].frame.median_ms);
        let ratio = |base: Option<f64>| base.filter(|_| median > 0.0).map(|b| b / median);
        runs[i].speedup_over_reference = ratio(median_of(runs, &scene, cpu_reference()));
        runs[i].speedup_over_gpu_trace = ratio(median_of(runs, &scene, gpu_trace()));
    }
}

fn spread(values: Vec<f64>) -> Spread {
    Spread::of(values)
}

/// One method (and mode) being timed.
struct Timed {
    label: Label,
    mode: &'static str,
    technique: Box<dyn specula_methods::Technique>,
    prepare_ms: f64,
    totals: Vec<f64>,
    stages: Vec<(String, Vec<f64>)>,
    timing: String,
    created: u64,
    rays: Option<u64>,
    counters: Vec<(String, u64)>,
}

impl Timed {
    /// A warm frame's time, stages, counters and what it created.
    fn record(&mut self, frame: &specula_methods::Frame) {
        let count = |name: &str| frame.counters.iter().find(|(n, _)| n == name).map(|c| c.1);
        if let (Some(closest), Some(shadow)) = (
            count(specula_methods::COUNTER_RAYS_TRACED),
            count(specula_methods::COUNTER_SHADOW_RAYS),
        ) {
            self.rays = Some(closest + shadow);
        }
        self.created += frame.created().total();
        self.counters = frame.counters.clone();
        self.timing = format!("{:?}", frame.timing);
        self.totals.push(frame.total_milliseconds());
        for s in &frame.stages {
            match self.stages.iter_mut().find(|(n, _)| *n == s.stage) {
                Some((_, v)) => v.push(s.milliseconds),
                None => self.stages.push((s.stage.clone(), vec![s.milliseconds])),
            }
        }
    }

    /// The method's figures over its warm frames.
    fn into_bench(
        self,
        scene_name: &str,
        adapter: &str,
        frames: u32,
        width: u32,
        height: u32,
    ) -> MethodBench {
        let frame = spread(self.totals);
        let rays_per_second = self
            .rays
            .filter(|_| frame.median_ms > 0.0)
            .map(|r| r as f64 / (frame.median_ms * 1e-3));
        MethodBench {
            scene: scene_name.to_string(),
            label: self.label.to_string(),
            method: self.label.info.name.to_string(),
            preset: self.label.preset.map(|p| p.name.to_string()),
            mode: self.mode.to_string(),
            parameters: self.technique.parameters(),
            frames,
            width,
            height,
            adapter: adapter.to_string(),
            timing: self.timing,
            prepare_ms: self.prepare_ms,
            frame,
            stages: self
                .stages
                .into_iter()
                .map(|(n, v)| (n, spread(v)))
                .collect(),
            created: self.created,
            counters: self.counters,
            speedup_over_reference: None,
            speedup_over_gpu_trace: None,
            rays_per_second,
        }
    }
}

/// Times the labels `methods` on `scene`; a method that fails to prepare or to render a frame
/// is a failure with its error, and the others are timed on. The `parameters` (checked beforehand with
/// `specula_methods::check_settings`) go to the labels in `asked` they reach, after their
/// presets; the exact bases added to the list without being asked for keep their defaults (so
/// that, say, image-space's `-p mode=ray-plane` is not handed to gpu-trace's own `mode`).
#[allow(clippy::too_many_arguments)]
pub fn run(
    scene: Scene,
    ctx: &Context,
    methods: &[String],
    asked: &[String],
    parameters: &[String],
    width: u32,
    height: u32,
    frames: u32,
) -> Result<(Vec<MethodBench>, Vec<BenchFailure>)> {
    let scene_name = scene.name.clone();
    let live = LiveScene::new(scene);
    let camera = live.scene().camera.clone();
    let adapter = ctx.describe();
    let mut timed = Vec::new();
    let mut failed = Vec::new();
    let failure =
        |label: &Label, mode: &str, error: specula_methods::TechniqueError| BenchFailure {
            scene: scene_name.clone(),
            label: label.to_string(),
            mode: mode.to_string(),
            error: specula_compare::error_chain(&error),
        };
    for name in methods {
        let label = Label::parse(name)?;
        let modes: &[&'static str] = if label.info.param("dynamic").is_some() {
            &["static", "dynamic"]
        } else {
            &["-"]
        };
        for &mode in modes {
            let mut technique = if asked.contains(name) {
                label.create_with(parameters)?
            } else {
                label.create()?
            };
            if mode != "-" {
                specula_methods::apply_setting(
                    technique.as_mut(),
                    &format!("dynamic={}", mode == "dynamic"),
                )?;
            }
            let start = std::time::Instant::now();
            if let Err(error) = technique.prepare(ctx, &live) {
                failed.push(failure(&label, mode, error));
                continue;
            }
            let prepare_ms = start.elapsed().as_secs_f64() * 1e3;
            timed.push(Timed {
                label: Label::parse(name)?,
                mode,
                technique,
                prepare_ms,
                totals: Vec::new(),
                stages: Vec::new(),
                timing: String::new(),
                created: 0,
                rays: None,
                counters: Vec::new(),
            });
        }
    }
    let bar =
        indicatif::ProgressBar::new(((WARM_UP_FRAMES + frames) as usize * timed.len()) as u64);
    bar.set_message(scene_name.clone());
    // Round by round, one frame of each method: a machine whose speed drifts during the run
    // (another tenant, the clock) slows every method alike, so their ratios hold.
    for round in 0..WARM_UP_FRAMES + frames {
        let mut failed_now = Vec::new();
        for (k, t) in timed.iter_mut().enumerate() {
            let frame = match t.technique.render(ctx, &live, &camera, width, height) {
                Ok(frame) => frame,
                Err(error) => {
                    failed.push(failure(&t.label, t.mode, error));
                    failed_now.push(k);
                    continue;
                }
            };
            bar.inc(1);
            if round < WARM_UP_FRAMES {
                continue;
            }
            t.record(&frame);
        }
        for k in failed_now.into_iter().rev() {
            timed.remove(k);
        }
    }
    bar.finish_and_clear();
    let runs = timed
        .into_iter()
        .map(|t| t.into_bench(&scene_name, &adapter, frames, width, height))
        .collect();
    Ok((runs, failed))
}

pub fn print(results: &[MethodBench], failed: &[BenchFailure]) {
    for r in results {
        let mode = mode_suffix(&r.mode);
        println!(
            "{}: {}{mode} ({}x{}, {} frames on {}, {}): prepare {:.1} ms; frame median {:.2} ms (min {:.2}, max {:.2}); {}; GPU objects created {}",
            r.scene, r.label, r.width, r.height, r.frames, r.adapter, r.timing, r.prepare_ms, r.frame.median_ms, r.frame.min_ms, r.frame.max_ms, ratios(r), r.created
        );
        for (stage, s) in &r.stages {
            println!(
                "    {stage:<28} median {:>9.2} ms  (min {:.2}, max {:.2})",
                s.median_ms, s.min_ms, s.max_ms
            );
        }
    }
    for f in failed {
        let mode = mode_suffix(&f.mode);
        println!("{}: {}{mode} failed: {}", f.scene, f.label, f.error);
    }
}

/// " [static]" or " [dynamic]" after a label; nothing for a method without modes ("-").
fn mode_suffix(mode: &str) -> String {
    if mode == "-" {
        String::new()
    } else {
        format!(" [{mode}]")
    }
}

fn speedup(value: Option<f64>) -> String {
    value
        .map(|v| format!("{v:.3}x"))
        .unwrap_or_else(|| "-".into())
}

/// "speed-up over reference Ax, over gpu-trace Bx[, N Mrays/s]".
fn ratios(r: &MethodBench) -> String {
    let mut text = format!(
        "speed-up over {} {}, over {} {}",
        cpu_reference(),
        speedup(r.speedup_over_reference),
        gpu_trace(),
        speedup(r.speedup_over_gpu_trace)
    );
    if let Some(rays) = r.rays_per_second {
        text.push_str(&format!(", {:.2} Mrays/s", rays / 1e6));
    }
    text
}

/// The report as a markdown table: one row per scene, method and mode.
pub fn markdown(report: &BenchReport) -> String {
    let mut out = format!(
        "Adapter: {} (driver: {}); ray queries: {}; {}.\n\n",
        report.adapter,
        if report.driver.is_empty() {
            "-"
        } else {
            &report.driver
        },
        if report.ray_queries { "yes" } else { "no" },
        report.date
    );
    out.push_str("| scene | label | mode | size | frame ms (median) | min–max ms | speed-up over reference | speed-up over gpu-trace | Mrays/s |\n");
    out.push_str("|---|---|---|---|---:|---:|---:|---:|---:|\n");
    for r in &report.runs {
        out.push_str(&format!(
            "| {} | {} | {} | {}×{} | {:.2} | {:.2}–{:.2} | {} | {} | {} |\n",
            r.scene,
            r.label,
            r.mode,
            r.width,
            r.height,
            r.frame.median_ms,
            r.frame.min_ms,
            r.frame.max_ms,
            speedup(r.speedup_over_reference),
            speedup(r.speedup_over_gpu_trace),
            r.rays_per_second
                .map(|v| format!("{:.2}", v / 1e6))
                .unwrap_or_else(|| "-".into())
        ));
    }
    for f in &report.failed {
        out.push_str(&format!(
            "| {} | {} | {} | failed: {} | | | | | |\n",
            f.scene,
            f.label,
            f.mode,
            f.error.replace('|', "\\|")
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn civil_dates() {
        assert_eq!(civil_date(0), "1970-01-01");
        // A leap day, and a date late in a year.
        assert_eq!(civil_date(951_782_400), "2000-02-29");
        assert_eq!(civil_date(1_796_040_000), "2026-11-30");
    }

    fn run(scene: &str, method: &str, median_ms: f64) -> MethodBench {
        MethodBench {
            scene: scene.into(),
            label: method.into(),
            method: method.into(),
            preset: None,
            mode: "-".into(),
            parameters: Vec::new(),
            frames: 1,
            width: 1,
            height: 1,
            adapter: String::new(),
            timing: String::new(),
            prepare_ms: 0.0,
            frame: spread(vec![median_ms]),
            stages: Vec::new(),
            created: 0,
            counters: Vec::new(),
            speedup_over_reference: None,
            speedup_over_gpu_trace: None,
            rays_per_second: None,
        }
    }

    #[test]
    fn ratios_are_the_exact_methods_medians_over_the_runs_of_the_same_scene() {
        let mut runs = vec![
            run("a", "envmap", 2.0),
            run("a", cpu_reference(), 100.0),
            run("a", gpu_trace(), 10.0),
            run("b", "envmap", 4.0),
            run("b", cpu_reference(), 40.0),
        ];
        add_ratios(&mut runs);
        assert_eq!(runs[0].speedup_over_reference, Some(50.0));
        assert_eq!(runs[0].speedup_over_gpu_trace, Some(5.0));
        assert_eq!(runs[2].speedup_over_gpu_trace, Some(1.0));
        assert_eq!(runs[3].speedup_over_reference, Some(10.0));
        assert_eq!(
            runs[3].speedup_over_gpu_trace, None,
            "no gpu-trace run on b"
        );
    }

    /// A method that fails is a row with its error; the others are timed on.
    #[test]
    fn a_failing_method_is_a_row_with_its_error_and_the_others_are_timed() {
        let ctx = Context { gpu: None };
        let scene = specula_scene::load("door-mirror").unwrap();
        let methods = vec!["pvrr".to_string(), cpu_reference().to_string()];
        let (runs, failed) = super::run(scene, &ctx, &methods, &methods, &[], 32, 24, 1).unwrap();
        assert_eq!(failed.len(), 1);
        assert_eq!(failed[0].label, "pvrr");
        assert!(failed[0].error.contains("GPU"), "{}", failed[0].error);
        assert_eq!(runs.len(), 1);
        assert_eq!(runs[0].label, cpu_reference());
        assert!(runs[0].frame.median_ms > 0.0);
        let report = BenchReport {
            schema_version: SCHEMA_VERSION,
            adapter: String::new(),
            driver: String::new(),
            date: utc_date(),
            ray_queries: false,
            runs,
            failed,
        };
        assert!(markdown(&report).contains("| door-mirror | pvrr | - | failed: "));
    }
}
