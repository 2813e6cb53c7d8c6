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

pub struct StageTimer {
    names: Vec<String>,
    gpu: Option<(wgpu::QuerySet, u32)>,
    cpu_last: Instant,
    cpu_stages: Vec<StageTime>,
}

impl StageTimer {
    /// Starts timing: marks the beginning of the first stage.
    pub fn start(ctx: &GpuContext) -> StageTimer {
        let gpu = (ctx.timing == TimingSource::GpuTimestamps).then(|| {
            let set = ctx.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("stage timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: MAX_MARKS,
            });
            (set, 0)
        });
        let mut timer = StageTimer {
            names: Vec::new(),
            gpu,
            cpu_last: Instant::now(),
            cpu_stages: Vec::new(),
        };
        timer.mark(ctx);
        timer
    }

    fn mark(&mut self, ctx: &GpuContext) {
        if let Some((set, next)) = &mut self.gpu {
            if *next < MAX_MARKS {
                let mut encoder = ctx.device.create_command_encoder(&Default::default());
                encoder.write_timestamp(set, *next);
                ctx.queue.submit([encoder.finish()]);
                *next += 1;
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
            self.cpu_stages.push(StageTime {
                stage: stage.to_string(),
                milliseconds: (now - self.cpu_last).as_secs_f64() * 1e3,
            });
            self.cpu_last = now;
        }
        Ok(())
    }

    /// The stages' times and where they came from.
    pub fn finish(self, ctx: &GpuContext) -> Result<(Vec<StageTime>, TimingSource), GpuError> {
        let Some((set, marks)) = self.gpu else {
            return Ok((self.cpu_stages, TimingSource::CpuWallClock));
        };
        let size = marks as u64 * 8;
        let resolved = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("timestamps"),
            size,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let readback = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("timestamps readback"),
            size,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        encoder.resolve_query_set(&set, 0..marks, &resolved, 0);
        encoder.copy_buffer_to_buffer(&resolved, 0, &readback, 0, size);
        ctx.queue.submit([encoder.finish()]);
        let slice = readback.slice(..);
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
        let period_ns = ctx.queue.get_timestamp_period() as f64;
        let stages = self
            .names
            .into_iter()
            .zip(ticks.windows(2))
            .map(|(stage, w)| StageTime {
                stage,
                milliseconds: w[1].saturating_sub(w[0]) as f64 * period_ns / 1e6,
            })
            .collect();
        Ok((stages, TimingSource::GpuTimestamps))
    }
}
