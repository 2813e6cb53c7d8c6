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

/// A technique's stage timer. Make one per technique and call [`StageTimer::start`] at the start
/// of every frame: its GPU objects are made once, so timing adds nothing to a frame's count.
#[derive(Default)]
pub struct StageTimer {
    names: Vec<String>,
    gpu: Option<Timestamps>,
    marks: u32,
    cpu_last: Option<Instant>,
    cpu_stages: Vec<StageTime>,
}

impl StageTimer {
    /// Starts a frame: marks the beginning of the first stage.
    pub fn start(&mut self, ctx: &GpuContext) {
        if ctx.timing == TimingSource::GpuTimestamps && self.gpu.is_none() {
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
        self.mark(ctx);
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
    pub fn lap(&mut self, ctx: &GpuContext, stage: &str) -> Result<(), GpuError> {
        self.names.push(stage.to_string());
        if self.gpu.is_some() {
            self.mark(ctx);
        } else {
            ctx.wait()?;
            let now = Instant::now();
            let last = self.cpu_last.replace(now).unwrap_or(now);
            self.cpu_stages.push(StageTime {
                stage: stage.to_string(),
                milliseconds: (now - last).as_secs_f64() * 1e3,
            });
        }
        Ok(())
    }

    /// The frame's stage times and where they came from.
    pub fn finish(&mut self, ctx: &GpuContext) -> Result<(Vec<StageTime>, TimingSource), GpuError> {
        let Some(t) = &self.gpu else {
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
