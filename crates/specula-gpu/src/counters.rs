//! A few `u32` counters that shaders add to atomically (`array<atomic<u32>, N>`, read-write
//! storage), cleared before a pass and read back after it, through two buffers made once.

use crate::{GpuContext, GpuError};

pub struct Counters {
    /// The storage buffer the shaders bind.
    pub buffer: wgpu::Buffer,
    staging: wgpu::Buffer,
    count: usize,
}

impl Counters {
    pub fn new(ctx: &GpuContext, label: &str, count: usize) -> Self {
        let size = (4 * count.max(1)) as u64;
        let buffer = ctx.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let staging = ctx.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        Counters {
            buffer,
            staging,
            count,
        }
    }

    /// Sets every counter to 0 (queued before the passes that count).
    pub fn clear(&self, ctx: &GpuContext) {
        ctx.queue
            .write_buffer(&self.buffer, 0, &vec![0u8; 4 * self.count.max(1)]);
    }

    /// The counters after the work submitted so far (waits for it).
    pub fn read(&self, ctx: &GpuContext) -> Result<Vec<u32>, GpuError> {
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(&self.buffer, 0, &self.staging, 0, self.buffer.size());
        ctx.queue.submit([encoder.finish()]);
        let count = self.count;
        ctx.read_mapped(&self.staging, |bytes| {
            bytemuck::cast_slice::<u8, u32>(bytes)[..count].to_vec()
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counters_read_back_what_was_written_and_clear_to_zero() {
        let Some(ctx) = crate::test_context("counters") else {
            return;
        };
        let counters = Counters::new(&ctx, "test counters", 3);
        ctx.queue
            .write_buffer(&counters.buffer, 0, bytemuck::cast_slice(&[7u32, 0, 42]));
        assert_eq!(counters.read(&ctx).unwrap(), [7, 0, 42]);
        counters.clear(&ctx);
        assert_eq!(counters.read(&ctx).unwrap(), [0, 0, 0]);
    }
}
