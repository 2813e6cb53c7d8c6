//! Vertex tracing's Figure 9 (Ullmann et al. 2001): speed-up and load imbalance against the
//! number of processors, measured for 1–3 MPI ranks and extended to 1–32 workers by the
//! discrete-event simulation (`vertex_tracing::simulate`), which is first checked against the
//! measured runs.
//!
//!   scripts/vertex-tracing-figure9.sh   (runs mpirun for 1–3 ranks, then this)
//!   cargo bench -p specula-compare --bench vertex_tracing_figure9 -- DIR
//!
//! DIR holds `ranks-1.json`, `ranks-2.json`, `ranks-3.json` (`specula render --distributed
//! --report`); the chart is written to DIR/figure9.svg and the tables printed in Markdown.
//! Speed-up is of the refinement phase (first package sent to last result composited), the
//! part the balancer distributes; the master's ID buffer and the rest of the scene are not
//! distributed (the paper's OpenGL part).

use std::path::PathBuf;

use plotters::prelude::*;
use serde_json::Value;
use specula_methods::vertex_tracing::simulate::{steady_frame, Network, WorkerSpec, Workload};

/// Loopback as seen by MPI on one machine (shared memory between ranks).
const LOOPBACK: WorkerSpec = WorkerSpec {
    speed: 1.0,
    bits_per_second: 10e9,
    latency_seconds: 20e-6,
};
const PACKAGES_PER_WORKER: usize = 4;
/// Frames simulated before the reported one (the balancer learns speeds after each).
const FRAMES: usize = 4;

struct Run {
    ranks: usize,
    refine_seconds: f64,
    /// Vertex rays and filled pixels of the frame, all packages together.
    samples: f64,
    /// Packages that did not continue their worker's previous one.
    region_starts: usize,
    triangles: usize,
    /// (start, end, seconds, pixels) of the last frame's packages.
    packages: Vec<(usize, usize, f64, usize)>,
}

/// Every frame of a run but the first (whose package sizes the balancer had not yet measured).
fn load(dir: &std::path::Path, ranks: usize) -> Vec<Run> {
    let path = dir.join(format!("ranks-{ranks}.json"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| {
        panic!(
            "{}: {e} (run scripts/vertex-tracing-figure9.sh)",
            path.display()
        )
    });
    let report: Value = serde_json::from_str(&text).expect("a report");
    let frames = report["frames"].as_array().expect("frames");
    let skip = usize::from(frames.len() > 1);
    frames[skip..]
        .iter()
        .map(|frame| {
            let records = frame["package_records"]
                .as_array()
                .expect("package records");
            let packages = records
                .iter()
                .map(|p| {
                    (
                        p["start"].as_u64().unwrap() as usize,
                        p["end"].as_u64().unwrap() as usize,
                        p["seconds"].as_f64().unwrap(),
                        p["pixels"].as_u64().unwrap() as usize,
                    )
                })
                .collect();
            let mut last_end = std::collections::HashMap::new();
            let mut region_starts = 0;
            for p in records {
                let rank = p["rank"].as_u64().unwrap();
                let (start, end) = (p["start"].as_u64().unwrap(), p["end"].as_u64().unwrap());
                if last_end.insert(rank, end) != Some(start) {
                    region_starts += 1;
                }
            }
            Run {
                region_starts,
                ranks,
                refine_seconds: frame["refine_seconds"].as_f64().unwrap(),
                samples: frame["samples"].as_f64().unwrap(),
                triangles: frame["active_triangles"].as_u64().unwrap() as usize,
                packages,
            }
        })
        .collect()
}

fn mean(values: impl Iterator<Item = f64>) -> f64 {
    let v: Vec<f64> = values.collect();
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

fn main() {
    let dir: PathBuf = std::env::args()
        .skip(1)
        .find(|a| !a.starts_with("--"))
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("target/figure9"));
    let runs: Vec<Vec<Run>> = (1..=3).map(|r| load(&dir, r)).collect();
    // A package's fixed cost: the vertices on its borders, traced again when it does not
    // continue its worker's previous package. Counted, not timed: the samples the 3-rank run
    // took beyond the 1-rank run's single package, per extra such package, at the 1-rank run's
    // seconds per sample (means over the frames).
    let seconds_per_sample = mean(
        runs[0]
            .iter()
            .map(|r| r.packages.iter().map(|p| p.2).sum::<f64>() / r.samples),
    );
    let extra_samples = (mean(runs[2].iter().map(|r| r.samples))
        - mean(runs[0].iter().map(|r| r.samples)))
    .max(0.0);
    let extra_starts = (mean(runs[2].iter().map(|r| r.region_starts as f64))
        - mean(runs[0].iter().map(|r| r.region_starts as f64)))
    .max(1.0);
    let per_package = extra_samples / extra_starts * seconds_per_sample;
    println!(
        "fixed cost of a package that does not continue its worker's last: {:.0} samples ({:.3} ms); {} frames per run after the first",
        extra_samples / extra_starts,
        per_package * 1e3,
        runs[0].len()
    );
    println!();
    println!("### Measured on this machine, and the simulation fed with each frame's package costs (means over the frames)");
    println!();
    println!("| ranks | workers | refinement s (measured) | speed-up (measured) | refinement s (simulated) | speed-up (simulated) | difference |");
    println!("|---|---|---|---|---|---|---|");
    let mut base = (0.0, 0.0);
    for frames in &runs {
        let ranks = frames[0].ranks;
        let workers = ranks.saturating_sub(1).max(1);
        let simulated = mean(frames.iter().map(|run| {
            let workload = Workload::from_packages(run.triangles, &run.packages, per_package, 0.0);
            if ranks == 1 {
                // The master alone: its one package, no messages.
                workload.total_seconds() + per_package
            } else {
                steady_frame(
                    &workload,
                    &vec![LOOPBACK; workers],
                    Network {
                        master_bits_per_second: LOOPBACK.bits_per_second,
                    },
                    PACKAGES_PER_WORKER,
                    1,
                )
                .seconds
            }
        }));
        let measured = mean(frames.iter().map(|r| r.refine_seconds));
        if ranks == 1 {
            base = (measured, simulated);
        }
        let (measured_speedup, simulated_speedup) = (base.0 / measured, base.1 / simulated);
        println!(
            "| {} | {} | {:.4} | {:.2} | {:.4} | {:.2} | {:+.1} % |",
            ranks,
            if ranks == 1 { 0 } else { workers },
            measured,
            measured_speedup,
            simulated,
            simulated_speedup,
            100.0 * (simulated_speedup / measured_speedup - 1.0)
        );
    }

    // The extension: the 1-worker run's costs (one process per core, no contention), its
    // frames' per-triangle costs averaged.
    let frame_workloads: Vec<Workload> = runs[1]
        .iter()
        .map(|r| Workload::from_packages(r.triangles, &r.packages, per_package, 0.0))
        .collect();
    let mut measured = frame_workloads[0].clone();
    for (t, seconds) in measured.seconds.iter_mut().enumerate() {
        *seconds = mean(frame_workloads.iter().map(|w| w.seconds[t]));
    }
    let paper_scale = 13.2 / measured.total_seconds();
    let scaled = Workload {
        seconds: measured.seconds.iter().map(|s| s * paper_scale).collect(),
        per_package_seconds: measured.per_package_seconds * paper_scale,
        ..measured.clone()
    };
    let link = |mbit: f64| WorkerSpec {
        speed: 1.0,
        bits_per_second: mbit * 1e6,
        latency_seconds: 0.2e-3,
    };
    type Scenario = (
        &'static str,
        Workload,
        Box<dyn Fn(usize) -> WorkerSpec>,
        f64,
    );
    let free_packages = Workload {
        per_package_seconds: 0.0,
        ..scaled.clone()
    };
    let scenarios: Vec<Scenario> = vec![
        (
            "measured frame, 1 Gbit/s links",
            measured.clone(),
            Box::new(move |_| link(1000.0)),
            1000e6,
        ),
        (
            "paper-sized frame (13.2 s on one worker), 100 Mbit/s",
            scaled.clone(),
            Box::new(move |_| link(100.0)),
            100e6,
        ),
        (
            "as above, packages without a fixed cost (what the border vertices cost)",
            free_packages,
            Box::new(move |_| link(100.0)),
            100e6,
        ),
        (
            "paper-sized frame, 10 Gbit/s links (what the network costs)",
            scaled.clone(),
            Box::new(move |_| link(10000.0)),
            10e9,
        ),
        (
            "paper-sized frame, mixed 10 and 100 Mbit/s links",
            scaled.clone(),
            Box::new(move |w| link(if w % 2 == 0 { 100.0 } else { 10.0 })),
            100e6,
        ),
        (
            "paper-sized frame, mixed links, speeds 1 and 0.5",
            scaled.clone(),
            Box::new(move |w| WorkerSpec {
                speed: if w % 2 == 0 { 1.0 } else { 0.5 },
                ..link(if w % 2 == 0 { 100.0 } else { 10.0 })
            }),
            100e6,
        ),
    ];
    let counts: Vec<usize> = vec![1, 2, 3, 4, 6, 8, 10, 12, 16, 20, 24, 28, 32];
    let mut curves = Vec::new();
    println!();
    println!("### Simulated: speed-up (frame time of one worker of speed 1 / of N workers), efficiency (speed-up / the workers' summed speed) and imbalance");
    for (name, workload, spec, master) in &scenarios {
        let network = Network {
            master_bits_per_second: *master,
        };
        let one = steady_frame(workload, &[spec(0)], network, PACKAGES_PER_WORKER, FRAMES);
        println!();
        println!("{name}: one worker {:.3} s per frame", one.seconds);
        println!();
        println!("| workers | frame s | speed-up | efficiency | imbalance |");
        println!("|---|---|---|---|---|");
        let mut points = Vec::new();
        for &n in &counts {
            let workers: Vec<WorkerSpec> = (0..n).map(spec).collect();
            let total_speed: f64 = workers.iter().map(|w| w.speed).sum();
            let frame = steady_frame(workload, &workers, network, PACKAGES_PER_WORKER, FRAMES);
            let speedup = one.seconds / frame.seconds;
            println!(
                "| {n} | {:.3} | {:.2} | {:.0} % | {:.1} % |",
                frame.seconds,
                speedup,
                100.0 * speedup / total_speed,
                100.0 * frame.imbalance
            );
            points.push((n as f64, speedup, frame.imbalance));
        }
        curves.push((name.to_string(), points));
    }
    let one_worker = mean(runs[1].iter().map(|r| r.refine_seconds));
    let measured_points: Vec<(f64, f64)> = runs[1..]
        .iter()
        .map(|frames| {
            let workers = (frames[0].ranks - 1) as f64;
            (
                workers,
                one_worker / mean(frames.iter().map(|r| r.refine_seconds)),
            )
        })
        .collect();
    let chart = dir.join("figure9.svg");
    draw(&chart, &curves, &measured_points).expect("chart drawn");
    println!();
    println!("chart: {}", chart.display());
}

type Curve = (String, Vec<(f64, f64, f64)>);

fn draw(
    path: &std::path::Path,
    curves: &[Curve],
    measured: &[(f64, f64)],
) -> Result<(), Box<dyn std::error::Error>> {
    let root = SVGBackend::new(path, (1000, 420)).into_drawing_area();
    root.fill(&WHITE)?;
    let (left, right) = root.split_horizontally(560);
    let colors = [BLUE, RED, CYAN, RGBColor(120, 120, 120), GREEN, MAGENTA];
    let mut speed = ChartBuilder::on(&left)
        .caption("(a) speed-up", ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(32)
        .y_label_area_size(40)
        .build_cartesian_2d(0f64..33f64, 0f64..33f64)?;
    speed
        .configure_mesh()
        .x_desc("workers")
        .y_desc("speed-up")
        .draw()?;
    speed
        .draw_series(LineSeries::new([(0.0, 0.0), (32.0, 32.0)], BLACK.mix(0.3)))?
        .label("ideal")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], BLACK.mix(0.3)));
    for (i, (name, points)) in curves.iter().enumerate() {
        let color = colors[i % colors.len()];
        speed
            .draw_series(LineSeries::new(points.iter().map(|p| (p.0, p.1)), color))?
            .label(name.as_str())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], color));
    }
    speed
        .draw_series(
            measured
                .iter()
                .map(|&(x, y)| Circle::new((x, y), 5, BLACK.filled())),
        )?
        .label("measured (MPI, this machine)")
        .legend(|(x, y)| Circle::new((x + 9, y), 4, BLACK.filled()));
    speed
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.9))
        .border_style(BLACK)
        .label_font(("sans-serif", 11))
        .draw()?;
    let mut imbalance = ChartBuilder::on(&right)
        .caption("(b) load imbalance", ("sans-serif", 18))
        .margin(12)
        .x_label_area_size(32)
        .y_label_area_size(40)
        .build_cartesian_2d(0f64..33f64, 0f64..30f64)?;
    imbalance
        .configure_mesh()
        .x_desc("workers")
        .y_desc("imbalance %")
        .draw()?;
    for (i, (_, points)) in curves.iter().enumerate() {
        let color = colors[i % colors.len()];
        imbalance.draw_series(LineSeries::new(
            points.iter().map(|p| (p.0, 100.0 * p.2)),
            color,
        ))?;
    }
    root.present()?;
    Ok(())
}
