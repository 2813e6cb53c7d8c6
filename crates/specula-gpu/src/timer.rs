//! Per-stage timing of a frame: GPU timestamp queries where the device has them, wall-clock
//! time on the CPU (waiting for the GPU at each stage's end) otherwise. Either way the result
//! says which it was.

use std::time::Instant;

use crate::{GpuContext, GpuError, TimingSource};

/// Time spent in one stage of a frame.
#[derive(Clone, Debug, PartialEq)]
pub struct StageTime {
    pub stage: String,
    pub milliseconds: f64,
}

/// Most stage boundaries one frame may mark.
const MAX_MARKS: u32 = 64;

/// GPU timestamp resources, created once and reused by every frame.
struct Timestamps {
    set: wgpu::QuerySet,
    resolved: wgpu::Buffer,
    readback: wgpu::Buffer,
}

/// The one stage timer of every technique and of progressive steps. Make one per technique and
/// call [`StageTimer::start`] at the start of every frame: its GPU objects are made once, so
/// timing adds nothing to a frame's count. With a GPU whose adapter has timestamps, stages are
/// timed on the GPU; otherwise (no GPU, no timestamps, or a timer made by
/// [`StageTimer::wall_clock`] for stages that run on the CPU) on the CPU's clock, waiting for
/// the GPU at each stage's end where there is one.
#[derive(Default)]
pub struct StageTimer {
    names: Vec<String>,
    gpu: Option<Timestamps>,
    marks: u32,
    cpu_last: Option<Instant>,
    cpu_stages: Vec<StageTime>,
    /// Always the CPU's clock, even where the GPU has timestamps.
    wall_clock: bool,
    /// This frame is timed by GPU timestamps.
    timestamps: bool,
}

impl StageTimer {
    /// A timer on the CPU's clock whatever the GPU offers: for stages that run on the CPU, or
    /// mix CPU and GPU work.
    pub fn wall_clock() -> StageTimer {
        StageTimer {
            wall_clock: true,
            ..StageTimer::default()
        }
    }

    /// Starts a frame: marks the beginning of the first stage.
    pub fn start(&mut self, gpu: Option<&GpuContext>) {
        self.timestamps =
            !self.wall_clock && gpu.is_some_and(|g| g.timing == TimingSource::GpuTimestamps);
        if let (true, Some(ctx), None) = (self.timestamps, gpu, &self.gpu) {
            let size = MAX_MARKS as u64 * 8;
            let buffer = |label, usage| {
                ctx.create_buffer(&wgpu::BufferDescriptor {
                    label: Some(label),
                    size,
                    usage,
                    mapped_at_creation: false,
                })
            };
            self.gpu = Some(Timestamps {
                set: ctx.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("stage timestamps"),
                    ty: wgpu::QueryType::Timestamp,
                    count: MAX_MARKS,
                }),
                resolved: buffer(
                    "timestamps",
                    wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                ),
                readback: buffer(
                    "timestamps readback",
                    wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                ),
            });
        }
        self.names.clear();
        self.cpu_stages.clear();
        self.marks = 0;
        self.cpu_last = Some(Instant::now());
        if let (true, Some(ctx)) = (self.timestamps, gpu) {
            self.mark(ctx);
        }
    }

    fn mark(&mut self, ctx: &GpuContext) {
        if let Some(t) = &self.gpu {
            if self.marks < MAX_MARKS {
                let mut encoder = ctx.device.create_command_encoder(&Default::default());
                encoder.write_timestamp(&t.set, self.marks);
                ctx.queue.submit([encoder.finish()]);
                self.marks += 1;
            }
        }
    }

    /// Ends the current stage, named `stage`, and starts the next. All GPU work submitted so far
    /// belongs to the stages ended so far.
    pub fn lap(&mut self, gpu: Option<&GpuContext>, stage: &str) -> Result<(), GpuError> {
        match (self.timestamps, gpu) {
            (true, Some(ctx)) => {
                self.names.push(stage.to_string());
                self.mark(ctx);
            }
            _ => {
                if let Some(ctx) = gpu {
                    ctx.wait()?;
                }
                let now = Instant::now();
                let last = self.cpu_last.replace(now).unwrap_or(now);
                self.add(stage, (now - last).as_secs_f64() * 1e3);
            }
        }
        Ok(())
    }

    /// Records a stage its own code timed (a phase on the CPU), or adds to the stage of that
    /// name this frame already has; the next stage starts now. On the CPU's clock only: a frame
    /// timed by GPU timestamps has no place for it.
    pub fn measured(&mut self, stage: &str, milliseconds: f64) {
        debug_assert!(!self.timestamps, "a measured stage in a GPU-timed frame");
        self.add(stage, milliseconds);
        self.cpu_last = Some(Instant::now());
    }

    fn add(&mut self, stage: &str, milliseconds: f64) {
        match self.cpu_stages.iter_mut().find(|s| s.stage == stage) {
            Some(s) => s.milliseconds += milliseconds,
            None => self.cpu_stages.push(StageTime {
                stage: stage.to_string(),
                milliseconds,
            }),
        }
    }

    /// The frame's stage times and where they came from; the timer is empty after.
    pub fn finish(
        &mut self,
        gpu: Option<&GpuContext>,
    ) -> Result<(Vec<StageTime>, TimingSource), GpuError> {
        let (Some(t), true, Some(ctx)) = (&self.gpu, self.timestamps, gpu) else {
            return Ok((
                std::mem::take(&mut self.cpu_stages),
                TimingSource::CpuWallClock,
            ));
        };
        let size = self.marks as u64 * 8;
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        encoder.resolve_query_set(&t.set, 0..self.marks, &t.resolved, 0);
        encoder.copy_buffer_to_buffer(&t.resolved, 0, &t.readback, 0, size);
        ctx.queue.submit([encoder.finish()]);
        let slice = t.readback.slice(..size);
        let (sender, receiver) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = sender.send(r);
        });
        ctx.wait()?;
        receiver
            .recv()
            .map_err(|e| GpuError::Readback(e.to_string()))?
            .map_err(|e| GpuError::Readback(e.to_string()))?;
        let ticks: Vec<u64> = bytemuck::cast_slice(
            &slice
                .get_mapped_range()
                .map_err(|e| GpuError::Readback(e.to_string()))?,
        )
        .to_vec();
        t.readback.unmap();
        let period_ns = ctx.queue.get_timestamp_period() as f64;
        let stages = self
            .names
            .drain(..)
            .zip(ticks.windows(2))
            .map(|(stage, w)| StageTime {
                stage,
                milliseconds: w[1].saturating_sub(w[0]) as f64 * period_ns / 1e6,
            })
            .collect();
        Ok((stages, TimingSource::GpuTimestamps))
    }
}
