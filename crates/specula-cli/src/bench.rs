//! `specula bench`: per method, a warm-up then N timed frames; the median and the spread (min,
//! max) of the frame time and of each stage. A method with a `dynamic` parameter is timed twice:
//! static (its scene-only maps kept, as in a still scene) and dynamic (redrawn every frame, as
//! the papers do for moving scenes).

use anyhow::Result;
use serde::Serialize;
use specula_methods::{Context, LiveScene};
use specula_scene::Scene;

/// Frames rendered and thrown away before timing (pipeline creation, first-use costs).
const WARM_UP_FRAMES: u32 = 2;

#[derive(Debug, Serialize)]
pub struct Spread {
    pub median_ms: f64,
    pub min_ms: f64,
    pub max_ms: f64,
}

#[derive(Debug, Serialize)]
pub struct MethodBench {
    pub method: String,
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
}

fn spread(mut values: Vec<f64>) -> Spread {
    values.sort_by(f64::total_cmp);
    let n = values.len();
    let median = if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    };
    Spread {
        median_ms: median,
        min_ms: values[0],
        max_ms: values[n - 1],
    }
}

pub fn run(
    scene: Scene,
    ctx: &Context,
    methods: &[String],
    parameters: &[String],
    width: u32,
    height: u32,
    frames: u32,
) -> Result<Vec<MethodBench>> {
    let live = LiveScene::new(scene);
    let camera = live.scene().camera.clone();
    let adapter = ctx.describe();
    let mut results = Vec::new();
    for name in methods {
        let info = specula_methods::method(name)?;
        let modes: &[&str] = if info.param("dynamic").is_some() {
            &["static", "dynamic"]
        } else {
            &["-"]
        };
        for mode in modes {
            let mut technique = (info.create)();
            specula_methods::apply_parameters(technique.as_mut(), parameters)?;
            if *mode != "-" {
                specula_methods::apply_setting(
                    technique.as_mut(),
                    &format!("dynamic={}", *mode == "dynamic"),
                )?;
            }
            let start = std::time::Instant::now();
            technique.prepare(ctx, &live)?;
            let prepare_ms = start.elapsed().as_secs_f64() * 1e3;
            let bar = indicatif::ProgressBar::new((WARM_UP_FRAMES + frames) as u64);
            bar.set_message(format!("{name} {mode}"));
            let mut totals = Vec::new();
            let mut stages: Vec<(String, Vec<f64>)> = Vec::new();
            let mut timing = String::new();
            let mut created = 0;
            for i in 0..WARM_UP_FRAMES + frames {
                let frame = technique.render(ctx, &live, &camera, width, height)?;
                bar.inc(1);
                if i < WARM_UP_FRAMES {
                    continue;
                }
                created += frame.created.total();
                timing = format!("{:?}", frame.timing);
                totals.push(frame.total_milliseconds());
                for s in &frame.stages {
                    match stages.iter_mut().find(|(n, _)| *n == s.stage) {
                        Some((_, v)) => v.push(s.milliseconds),
                        None => stages.push((s.stage.clone(), vec![s.milliseconds])),
                    }
                }
            }
            bar.finish_and_clear();
            results.push(MethodBench {
                method: name.clone(),
                mode: mode.to_string(),
                parameters: technique.parameters(),
                frames,
                width,
                height,
                adapter: adapter.clone(),
                timing,
                prepare_ms,
                frame: spread(totals),
                stages: stages.into_iter().map(|(n, v)| (n, spread(v))).collect(),
                created,
            });
        }
    }
    Ok(results)
}

pub fn print(results: &[MethodBench]) {
    for r in results {
        let mode = if r.mode == "-" {
            String::new()
        } else {
            format!(" [{}]", r.mode)
        };
        println!(
            "{}{mode} ({}x{}, {} frames on {}, {}): prepare {:.1} ms; frame median {:.2} ms (min {:.2}, max {:.2}); GPU objects created {}",
            r.method, r.width, r.height, r.frames, r.adapter, r.timing, r.prepare_ms, r.frame.median_ms, r.frame.min_ms, r.frame.max_ms, r.created
        );
        for (stage, s) in &r.stages {
            println!(
                "    {stage:<28} median {:>9.2} ms  (min {:.2}, max {:.2})",
                s.median_ms, s.min_ms, s.max_ms
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::spread;

    #[test]
    fn spread_is_the_median_and_the_extremes() {
        let odd = spread(vec![5.0, 1.0, 9.0]);
        assert_eq!((odd.min_ms, odd.median_ms, odd.max_ms), (1.0, 5.0, 9.0));
        let even = spread(vec![10.0, 3.0, 1.0, 2.0]);
        assert_eq!((even.min_ms, even.median_ms, even.max_ms), (1.0, 2.5, 10.0));
    }
}
