//! A buffer that per-frame data is written into at growing offsets and reused every frame, so
//! a steady-state frame creates no buffer: [`Arena::reserve`] says before a pass how many bytes
//! it will write (growing the buffer, which is the only creation, when they do not fit), then
//! [`Arena::push`] writes them. [`Arena::begin_frame`] starts again at offset 0.
//!
//! Reserve before pushing: growing replaces the buffer, so offsets handed out earlier in the
//! same pass would point into the old one. Passes already submitted keep the old buffer alive.
//! A pass whose data is spent once it is submitted can give its room back
//! ([`Arena::used`] before, [`Arena::rewind`] after): wgpu writes a buffer for the next
//! submission only after the earlier ones have read it.
//!
//! A buffer never grows past the device's largest (`max_buffer_size`): a reservation that does
//! not fit there is an error naming the arena and both sizes.

use crate::{GpuContext, GpuError};

pub struct Arena {
    label: &'static str,
    usage: wgpu::BufferUsages,
    /// Offsets are multiples of this.
    alignment: u64,
    buffer: Option<wgpu::Buffer>,
    used: u64,
    /// The most bytes in use at once since the frame began.
    peak: u64,
    /// Bumped whenever the buffer is replaced: bind groups made for it must be made again.
    generation: u64,
}

impl Arena {
    pub fn new(label: &'static str, usage: wgpu::BufferUsages, alignment: u64) -> Arena {
        Arena {
            label,
            usage: usage | wgpu::BufferUsages::COPY_DST,
            alignment: alignment.max(4),
            buffer: None,
            used: 0,
            peak: 0,
            generation: 0,
        }
    }

    pub fn begin_frame(&mut self) {
        self.used = 0;
        self.peak = 0;
    }

    fn aligned(&self, size: u64) -> u64 {
        size.div_ceil(self.alignment) * self.alignment
    }

    /// Makes room for `sizes` (each pushed at an aligned offset) after what is used; returns
    /// whether the buffer was replaced, or an error where the room exceeds the device's largest
    /// buffer.
    pub fn reserve(
        &mut self,
        ctx: &GpuContext,
        sizes: impl IntoIterator<Item = u64>,
    ) -> Result<bool, GpuError> {
        let needed = self.used + sizes.into_iter().map(|s| self.aligned(s)).sum::<u64>();
        let capacity = self.buffer.as_ref().map_or(0, |b| b.size());
        if needed <= capacity {
            return Ok(false);
        }
        let limit = ctx.device.limits().max_buffer_size;
        if needed > limit {
            return Err(GpuError::TooLarge {
                what: self.label.to_string(),
                bytes: needed,
                limit,
            });
        }
        let size = needed.max(2 * capacity).max(4096).min(limit);
        self.buffer = Some(ctx.create_buffer(&wgpu::BufferDescriptor {
            label: Some(self.label),
            size,
            usage: self.usage,
            mapped_at_creation: false,
        }));
        self.generation += 1;
        Ok(true)
    }

    /// The bytes pushed so far this frame: a mark to [`Arena::rewind`] to.
    pub fn used(&self) -> u64 {
        self.used
    }

    /// The most bytes in use at once since [`Arena::begin_frame`] (what the frame needed).
    pub fn peak(&self) -> u64 {
        self.peak
    }

    /// Gives back the room pushed after `mark` (from [`Arena::used`]), once the passes that
    /// read it are submitted.
    pub fn rewind(&mut self, mark: u64) {
        assert!(
            mark <= self.used,
            "{}: rewind past what is used",
            self.label
        );
        self.used = mark;
    }

    /// Writes `bytes` at the next aligned offset and returns that offset. Room must have been
    /// reserved.
    pub fn push(&mut self, ctx: &GpuContext, bytes: &[u8]) -> u64 {
        let offset = self.used;
        let buffer = self.buffer.as_ref().expect("reserve before push");
        assert!(
            offset + bytes.len() as u64 <= buffer.size(),
            "{}: push past the reserved room",
            self.label
        );
        if !bytes.is_empty() {
            ctx.queue.write_buffer(buffer, offset, bytes);
        }
        self.used = offset + self.aligned(bytes.len() as u64);
        self.peak = self.peak.max(self.used);
        offset
    }

    pub fn buffer(&self) -> &wgpu::Buffer {
        self.buffer.as_ref().expect("reserve before use")
    }

    pub fn generation(&self) -> u64 {
        self.generation
    }
}
