use std::future::Future;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

use wgpu::util::DeviceExt;

/// Everything that can go wrong on the GPU side, as values: library code never panics on a
/// wgpu error.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    #[error("no Vulkan adapter found ({0}). On Debian/Ubuntu install Mesa's Vulkan driver: `apt-get install mesa-vulkan-drivers libvulkan1` (or run scripts/setup.sh)")]
    NoAdapter(String),
    #[error("cannot open the GPU device: {0}")]
    Device(String),
    #[error("wgpu validation error in {stage}: {message}")]
    Validation { stage: String, message: String },
    #[error("GPU readback failed: {0}")]
    Readback(String),
    #[error(
        "{what} needs {bytes} bytes in one buffer, more than this device's largest ({limit} bytes)"
    )]
    TooLarge {
        what: String,
        bytes: u64,
        limit: u64,
    },
}

/// Where a technique's per-stage timings come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TimingSource {
    /// GPU timestamp queries (the adapter supports them).
    GpuTimestamps,
    /// Wall-clock time on the CPU around each stage, waiting for the GPU to finish.
    CpuWallClock,
}

/// A headless wgpu device on the Vulkan backend.
pub struct GpuContext {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub adapter_info: wgpu::AdapterInfo,
    /// The adapter itself (a window asks it what its surface supports).
    pub adapter: wgpu::Adapter,
    pub timing: TimingSource,
    /// Whether 32-bit float targets can be blended into (wgpu's FLOAT32_BLENDABLE).
    pub float32_blendable: bool,
    /// wgpu errors raised outside any error scope. wgpu's default is to panic on them; here
    /// they are collected and returned as an error by the next [`GpuContext::wait`].
    uncaptured: Arc<Mutex<Vec<String>>>,
    created: [AtomicU64; KINDS],
    /// The staging buffer texture readbacks copy into, kept and grown to the largest readback
    /// so far: a warm readback creates nothing.
    readback: Mutex<Option<wgpu::Buffer>>,
}

/// How many GPU textures, buffers, bind groups, samplers and query sets were created (through
/// [`GpuContext`]'s `create_*` methods, the only way the project creates them: clippy.toml
/// forbids wgpu's own).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ResourceCounts {
    pub textures: u64,
    pub buffers: u64,
    pub bind_groups: u64,
    pub samplers: u64,
    pub query_sets: u64,
}

impl ResourceCounts {
    pub fn total(&self) -> u64 {
        self.textures + self.buffers + self.bind_groups + self.samplers + self.query_sets
    }
}

impl std::ops::Sub for ResourceCounts {
    type Output = ResourceCounts;
    fn sub(self, earlier: ResourceCounts) -> ResourceCounts {
        ResourceCounts {
            textures: self.textures - earlier.textures,
            buffers: self.buffers - earlier.buffers,
            bind_groups: self.bind_groups - earlier.bind_groups,
            samplers: self.samplers - earlier.samplers,
            query_sets: self.query_sets - earlier.query_sets,
        }
    }
}

const TEXTURES: usize = 0;
const BUFFERS: usize = 1;
const BIND_GROUPS: usize = 2;
const SAMPLERS: usize = 3;
const QUERY_SETS: usize = 4;
const KINDS: usize = 5;

/// The GPU objects alive on the device, as wgpu-hal counts them (its `counters` feature):
/// a second source beside [`ResourceCounts`], which sees only what went through
/// [`GpuContext`]'s wrappers. Objects wgpu creates and frees on its own (command encoders,
/// fences) are left out.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LiveObjects {
    pub buffers: isize,
    pub textures: isize,
    pub texture_views: isize,
    pub bind_groups: isize,
    pub samplers: isize,
    pub render_pipelines: isize,
    pub compute_pipelines: isize,
    pub query_sets: isize,
}

impl GpuContext {
    /// A Vulkan-only wgpu instance. The GL backend is never used (it lacks float render
    /// targets).
    pub fn vulkan_instance() -> wgpu::Instance {
        wgpu::Instance::new(wgpu::InstanceDescriptor {
            backends: wgpu::Backends::VULKAN,
            ..wgpu::InstanceDescriptor::new_without_display_handle()
        })
    }

    /// A headless context on the best Vulkan adapter.
    pub fn new() -> Result<GpuContext, GpuError> {
        Self::with_surface(&Self::vulkan_instance(), None)
    }

    /// Opens the best Vulkan adapter of `instance` (`HighPerformance`, so a real GPU wins over
    /// lavapipe where both exist) that can present to `surface` when one is given (the viewer's
    /// window; create it from the same instance).
    pub fn with_surface(
        instance: &wgpu::Instance,
        surface: Option<&wgpu::Surface<'_>>,
    ) -> Result<GpuContext, GpuError> {
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            compatible_surface: surface,
            force_fallback_adapter: false,
            ..Default::default()
        }))
        .map_err(|e| GpuError::NoAdapter(e.to_string()))?;
        // Stage timings write timestamps between submissions, which needs both features.
        let timestamp_features =
            wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS;
        let timestamps = adapter.features().contains(timestamp_features);
        // Adding into float targets (pvrr's surface reflection over a lens) needs blending.
        let float32_blendable = adapter
            .features()
            .contains(wgpu::Features::FLOAT32_BLENDABLE);
        let mut required_features = if timestamps {
            timestamp_features
        } else {
            wgpu::Features::empty()
        };
        if float32_blendable {
            required_features |= wgpu::Features::FLOAT32_BLENDABLE;
        }
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("specula"),
            required_features,
            required_limits: adapter.limits(),
            ..Default::default()
        }))
        .map_err(|e| GpuError::Device(e.to_string()))?;
        let uncaptured = Arc::new(Mutex::new(Vec::new()));
        let sink = uncaptured.clone();
        device.on_uncaptured_error(Arc::new(move |error: wgpu::Error| {
            sink.lock()
                .unwrap_or_else(|e| e.into_inner())
                .push(error.to_string());
        }));
        Ok(GpuContext {
            uncaptured,
            created: Default::default(),
            readback: Mutex::new(None),
            device,
            queue,
            adapter_info: adapter.get_info(),
            adapter,
            float32_blendable,
            timing: if timestamps {
                TimingSource::GpuTimestamps
            } else {
                TimingSource::CpuWallClock
            },
        })
    }

    /// Whether the adapter is a software rasterizer running on the CPU (lavapipe): a GPU path
    /// there shares the cores with the CPU's own.
    pub fn is_software(&self) -> bool {
        self.adapter_info.device_type == wgpu::DeviceType::Cpu
    }

    /// A one-line description of the adapter, e.g. "llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan, Cpu)".
    pub fn describe(&self) -> String {
        format!(
            "{} ({:?}, {:?})",
            self.adapter_info.name, self.adapter_info.backend, self.adapter_info.device_type
        )
    }

    /// Textures, buffers, bind groups, samplers and query sets created so far.
    pub fn resource_counts(&self) -> ResourceCounts {
        let count = |i: usize| self.created[i].load(Ordering::Relaxed);
        ResourceCounts {
            textures: count(TEXTURES),
            buffers: count(BUFFERS),
            bind_groups: count(BIND_GROUPS),
            samplers: count(SAMPLERS),
            query_sets: count(QUERY_SETS),
        }
    }

    /// The objects alive on the device once the work submitted so far is done (waits for it,
    /// so that objects dropped since are freed and not counted).
    pub fn live_objects(&self) -> Result<LiveObjects, GpuError> {
        self.wait()?;
        let hal = self.device.get_internal_counters().hal;
        Ok(LiveObjects {
            buffers: hal.buffers.read(),
            textures: hal.textures.read(),
            texture_views: hal.texture_views.read(),
            bind_groups: hal.bind_groups.read(),
            samplers: hal.samplers.read(),
            render_pipelines: hal.render_pipelines.read(),
            compute_pipelines: hal.compute_pipelines.read(),
            query_sets: hal.query_sets.read(),
        })
    }

    fn count(&self, kind: usize) {
        self.created[kind].fetch_add(1, Ordering::Relaxed);
    }

    #[allow(clippy::disallowed_methods)]
    pub fn create_texture(&self, descriptor: &wgpu::TextureDescriptor) -> wgpu::Texture {
        self.count(TEXTURES);
        self.device.create_texture(descriptor)
    }

    #[allow(clippy::disallowed_methods)]
    pub fn create_buffer(&self, descriptor: &wgpu::BufferDescriptor) -> wgpu::Buffer {
        self.count(BUFFERS);
        self.device.create_buffer(descriptor)
    }

    #[allow(clippy::disallowed_methods)]
    pub fn create_buffer_init(
        &self,
        descriptor: &wgpu::util::BufferInitDescriptor,
    ) -> wgpu::Buffer {
        self.count(BUFFERS);
        self.device.create_buffer_init(descriptor)
    }

    #[allow(clippy::disallowed_methods)]
    pub fn create_bind_group(&self, descriptor: &wgpu::BindGroupDescriptor) -> wgpu::BindGroup {
        self.count(BIND_GROUPS);
        self.device.create_bind_group(descriptor)
    }

    #[allow(clippy::disallowed_methods)]
    pub fn create_sampler(&self, descriptor: &wgpu::SamplerDescriptor) -> wgpu::Sampler {
        self.count(SAMPLERS);
        self.device.create_sampler(descriptor)
    }

    #[allow(clippy::disallowed_methods)]
    pub fn create_query_set(&self, descriptor: &wgpu::QuerySetDescriptor) -> wgpu::QuerySet {
        self.count(QUERY_SETS);
        self.device.create_query_set(descriptor)
    }

    /// Runs `work` inside a validation error scope: any wgpu validation error it causes comes
    /// back as `GpuError::Validation` naming `stage`, instead of wgpu's default panic.
    pub fn validated<T>(&self, stage: &str, work: impl FnOnce() -> T) -> Result<T, GpuError> {
        let scope = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let value = work();
        match block_on(scope.pop()) {
            Some(error) => Err(GpuError::Validation {
                stage: stage.to_string(),
                message: error.to_string(),
            }),
            None => Ok(value),
        }
    }

    /// Blocks until all submitted work is done; reports any wgpu error raised outside an error
    /// scope since the last wait.
    pub fn wait(&self) -> Result<(), GpuError> {
        self.device
            .poll(wgpu::PollType::Wait {
                submission_index: None,
                timeout: None,
            })
            .map_err(|e| GpuError::Readback(e.to_string()))?;
        let errors =
            std::mem::take(&mut *self.uncaptured.lock().unwrap_or_else(|e| e.into_inner()));
        if errors.is_empty() {
            Ok(())
        } else {
            Err(GpuError::Validation {
                stage: "outside any error scope".into(),
                message: errors.join("; "),
            })
        }
    }

    /// Reads a 2D texture (mip 0, layer `layer`) back to the CPU as tightly packed rows of
    /// `bytes_per_texel` bytes, undoing wgpu's 256-byte row alignment. The staging buffer is the
    /// context's own, made once per size increase.
    pub fn read_texture(&self, texture: &wgpu::Texture, layer: u32) -> Result<Vec<u8>, GpuError> {
        let bytes_per_texel = texture.format().block_copy_size(None).ok_or_else(|| {
            GpuError::Readback(format!("format {:?} cannot be copied", texture.format()))
        })?;
        let (width, height) = (texture.width(), texture.height());
        let unpadded = width * bytes_per_texel;
        let padded = crate::util::padded_row_bytes(unpadded);
        let size = (padded * height) as u64;
        let mut kept = self.readback.lock().unwrap_or_else(|e| e.into_inner());
        if kept.as_ref().is_none_or(|b| b.size() < size) {
            *kept = Some(self.create_buffer(&wgpu::BufferDescriptor {
                label: Some("readback"),
                size,
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                mapped_at_creation: false,
            }));
        }
        let buffer = kept.as_ref().expect("made above");
        let mut encoder = self.device.create_command_encoder(&Default::default());
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture,
                mip_level: 0,
                origin: wgpu::Origin3d {
                    x: 0,
                    y: 0,
                    z: layer,
                },
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded),
                    rows_per_image: Some(height),
                },
            },
            wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
        );
        self.queue.submit([encoder.finish()]);
        let read = self.read_mapped(buffer, |mapped| {
            let mut out = Vec::with_capacity((unpadded * height) as usize);
            for row in mapped[..size as usize].chunks_exact(padded as usize) {
                out.extend_from_slice(&row[..unpadded as usize]);
            }
            out
        });
        if read.is_err() {
            // A failed readback may leave the buffer mapped: the next one makes a fresh buffer
            // rather than failing on this one.
            *kept = None;
        }
        read
    }

    /// Waits for the work submitted so far, maps `buffer` (MAP_READ) and hands its bytes to
    /// `read`; the buffer is unmapped again after.
    pub fn read_mapped<R>(
        &self,
        buffer: &wgpu::Buffer,
        read: impl FnOnce(&[u8]) -> R,
    ) -> Result<R, GpuError> {
        let slice = buffer.slice(..);
        let (sender, receiver) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |result| {
            let _ = sender.send(result);
        });
        self.wait()?;
        receiver
            .recv()
            .map_err(|e| GpuError::Readback(e.to_string()))?
            .map_err(|e| GpuError::Readback(e.to_string()))?;
        let mapped = slice
            .get_mapped_range()
            .map_err(|e| GpuError::Readback(e.to_string()))?;
        let result = read(&mapped);
        drop(mapped);
        buffer.unmap();
        Ok(result)
    }
}

fn block_on<F: Future>(future: F) -> F::Output {
    pollster::block_on(future)
}
