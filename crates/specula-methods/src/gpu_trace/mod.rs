//! `gpu-trace`: the exact reference (specula_trace::reference) on the GPU, as WGSL compute
//! passes over the BVH the CPU builds. Its images agree with the CPU reference's (≥ 79 dB PSNR
//! over whole 80×60 images, see tests/gpu_trace.rs); it is the exact method every technique's
//! speed is compared with on the same device.
//!
//! Paper: none (Whitted 1980, as the CPU reference). Triangle test: Woop, Benthin and Wald,
//! "Watertight Ray/Triangle Intersection" (JCGT 2013); traversal: ordered, stack-based, with
//! Ize's robust box test (2013). Wavefront form: Laine, Karras and Aila, "Megakernels
//! Considered Harmful: Wavefront Path Tracing on GPUs" (HPG 2013).
//!
//! Steps:
//! 1. upload the scene's binary SAH BVH as built on the CPU ([`LiveScene::accel`], nodes as
//!    they are) and its triangles in leaf order; a rigid move refits (or rebuilds) the CPU tree
//!    and the next frame writes the nodes and corners again into the same buffers (new ones
//!    only when a rebuild changed the node count). A camera change uploads nothing but the
//!    camera;
//! 2. trace, in one of two forms (`mode`):
//!    - `megakernel`: one thread per pixel traces its pixel's whole Whitted ray tree depth
//!      first from a private stack of pending rays (origin, direction, weight, depth, colour
//!      channel);
//!    - `wavefront`: rays wait in queues in GPU memory; one dispatch intersects and shades
//!      every ray of a generation (each pending ray of depth k) and appends the rays it spawns
//!      to the next generation's queue, max_depth + 1 generations in all; contributions are
//!      added to their pixel atomically.
//!
//! Shading is the CPU reference's, ray for ray: unlit, Lambert with hard shadows (an any-hit
//! ray per light) and ambient, mirrors (Schlick or F0), dielectrics with exact Fresnel and both
//! branches, total internal reflection, thin sheets, dispersion (one path per colour channel
//! from the first dispersive interface), the background, `max_depth`.
//!
//! Bounds: the megakernel's stack holds 16 pending rays; depth first, that is every tree up to
//! max_depth 11 exactly (each level leaves at most one waiting sibling, a dispersive split
//! five). The wavefront's queues hold `queue_factor` × pixels rays each. Past either bound a
//! spawned ray is dropped, counted (`rays dropped`) and warned about; nothing is dropped at the
//! default max_depth 8 with the megakernel.
//!
//! Approximations: none beyond float rounding. The CPU decides a ray that falls exactly on a
//! triangle edge in single precision again in double precision; WGSL has no double, so such a
//! ray counts as on the triangle. Shader compilers may fuse multiply-adds, so hits agree to the
//! last bits only: where a path's outcome hinges on those bits (a grazing silhouette seen
//! through several refractions) a pixel may differ.
//!
//! Hardware ray queries (`wgpu::Features::EXPERIMENTAL_RAY_QUERY`) are detected and reported
//! (`specula methods`, `bench`); neither lavapipe nor the H200 machine sometimes lent here has
//! them, so the compute traversal is the method and no second path is compiled.
//!
//! ## Parameters
//!
//! <!-- The parameter table: made from `Params::SPECS` by `specula_core::params::doc_table`;
//! `SPECULA_REGENERATE=1 cargo test -p specula-methods --lib doc` writes it again. -->
//! | parameter | takes | default | a change redoes | what it does |
//! |---|---|---|---|---|
//! | `max_depth` | a whole number from 0 to 64 | `8` | uniform | most specular bounces on a path (the megakernel is exact up to 11) |
//! | `mode` | one of megakernel, wavefront | `megakernel` | resources | one thread per pixel with a private ray stack, or ray queues in GPU memory |
//! | `queue_factor` | a whole number from 1 to 16 | `4` | resources | wavefront: rays per pixel each queue holds |
//! <!-- end of the parameter table -->
//!
//! What they change:
//! - `max_depth`: the most specular bounces on a path, as the CPU reference's.
//!   Cost grows with the paths that need it.
//! - `mode` (docs/methods/gpu-trace.md): the form of
//!   the tracing, above.
//! - `queue_factor`: wavefront queue capacity in rays per pixel. More memory, fewer
//!   drops on deep glass.

use bytemuck::{Pod, Zeroable};
use specula_gpu::counters::Counters;
use specula_gpu::shaders::{self, CameraUniform};
use specula_gpu::util::{buffer_binding, layout_entry, writable_buffer};
use specula_gpu::{GpuContext, GpuError};
use specula_trace::SceneAccel;

use specula_core::gpu_scene::GpuScene;
use specula_core::lifecycle::{GpuFrame, GpuMethod, GpuTechnique};
use specula_core::live_scene::LiveScene;
use specula_core::raster::{self, RasterPass};
use specula_core::{
    Invalidates, MethodInfo, Param, ParamKind, TechniqueError, COUNTER_RAYS_TRACED,
    COUNTER_SHADOW_RAYS,
};

const BVH: &str = include_str!("bvh.wgsl");
const SHADE: &str = include_str!("shade.wgsl");
const MEGAKERNEL: &str = include_str!("megakernel.wgsl");
const WAVEFRONT: &str = include_str!("wavefront.wgsl");

/// The megakernel's shader: the common files, shading, traversal, its entry point.
pub fn megakernel_source() -> String {
    shaders::compose(
        &["optics.wgsl", "camera.wgsl", "scene.wgsl"],
        &[SHADE, BVH, MEGAKERNEL].join("\n"),
    )
}

/// The wavefront's shader.
pub fn wavefront_source() -> String {
    shaders::compose(
        &["optics.wgsl", "camera.wgsl", "scene.wgsl"],
        &[SHADE, BVH, WAVEFRONT].join("\n"),
    )
}

/// Side of the wavefront's square tiles, in pixels: its queues hold `queue_factor` rays per
/// pixel of one tile, whatever the image size.
const WAVEFRONT_TILE: u32 = 256;
/// Generations the wavefront's count slots cover (max_depth + 1 of them, plus the next's count).
const GENERATIONS: u32 = 65;

/// Names of the shader's counter slots (shade.wgsl's COUNT_*), as reports list them.
pub const COUNTER_NAMES: [&str; 4] = [
    COUNTER_RAYS_TRACED,
    COUNTER_SHADOW_RAYS,
    "paths cut at max_depth",
    "rays dropped (queue or stack full)",
];
const DROPPED: usize = 3;

specula_core::params! {
    /// gpu-trace's parameters (the table above).
    pub struct Params {
        max_depth: u32 = Param {
            kind: ParamKind::Integer { min: 0, max: 64 },
            default: "8",
            doc: "most specular bounces on a path (the megakernel is exact up to 11)",
            invalidates: Invalidates::Uniform,
        },
        mode: Mode = Param {
            kind: ParamKind::Choice(Mode::WORDS),
            default: "megakernel",
            doc: "one thread per pixel with a private ray stack, or ray queues in GPU memory",
            invalidates: Invalidates::Resources,
        },
        queue_factor: u32 = Param {
            kind: ParamKind::Integer { min: 1, max: 16 },
            default: "4",
            doc: "wavefront: rays per pixel each queue holds",
            invalidates: Invalidates::Resources,
        },
    }
}

pub const INFO: MethodInfo = MethodInfo {
    name: "gpu-trace",
    summary: "exact Whitted ray tracing in WGSL compute over the CPU's SAH BVH (the reference on the GPU)",
    exact: true,
    needs_gpu: true,
    gpu_optional: false,
    progressive: false,
    delegates: &[],
    params: Params::SPECS,
    presets: &[],
    create: || Box::new(GpuMethod::<GpuTrace>::default()),
};

/// Host mirror of WGSL `Settings` (shade.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct GpuSettings {
    max_depth: u32,
    triangle_count: u32,
    queue_capacity: u32,
    pad: u32,
}

/// Host mirror of WGSL `Triangle` (bvh.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct GpuTriangle {
    p0: [f32; 3],
    vertex: u32,
    p1: [f32; 3],
    pad0: u32,
    p2: [f32; 3],
    pad1: u32,
}

/// Whether the adapter offers hardware ray queries (reported; see the module doc).
pub fn ray_queries_supported(ctx: &GpuContext) -> bool {
    ctx.adapter
        .features()
        .contains(wgpu::Features::EXPERIMENTAL_RAY_QUERY)
}

/// The triangles of `accel` in leaf order, each with its first vertex in `gpu_scene`'s buffer.
fn leaf_triangles(accel: &SceneAccel, gpu_scene: &GpuScene) -> Vec<GpuTriangle> {
    accel
        .triangles
        .iter()
        .zip(&accel.ids)
        .map(|(t, &(mesh, triangle))| GpuTriangle {
            p0: t[0].to_array(),
            vertex: gpu_scene.mesh_vertex_ranges[mesh as usize].start + 3 * triangle,
            p1: t[1].to_array(),
            pad0: 0,
            p2: t[2].to_array(),
            pad1: 0,
        })
        .collect()
}

/// What depends on the scene: the BVH on the GPU and the pipeline.
pub struct Prepared {
    /// Scene version the nodes and triangles were written at.
    uploaded_at: u64,
    nodes: wgpu::Buffer,
    triangles: wgpu::Buffer,
    triangle_count: u32,
    camera: wgpu::Buffer,
    settings: wgpu::Buffer,
    counters: Counters,
    layout: wgpu::BindGroupLayout,
    scene_layout: wgpu::BindGroupLayout,
    scene_bind_group: wgpu::BindGroup,
    megakernel: wgpu::ComputePipeline,
    /// The bind group for the current output texture and buffers (remade when either changes).
    bind_group: Option<(wgpu::Texture, wgpu::BindGroup)>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    Megakernel,
    Wavefront,
}

specula_core::choice!(Mode {
    Megakernel = "megakernel",
    Wavefront = "wavefront",
});

/// The wavefront's pipelines and buffers, for one queue capacity.
struct Wavefront {
    generate: wgpu::ComputePipeline,
    extend: wgpu::ComputePipeline,
    resolve: wgpu::ComputePipeline,
    queue_factor: u32,
    bind_group: wgpu::BindGroup,
    tile: wgpu::Buffer,
    queue_counts: wgpu::Buffer,
    accumulator: wgpu::Buffer,
    /// Bytes between the generation numbers in the dynamic-offset uniform.
    generation_stride: u32,
}

/// Host mirror of WGSL `Tile` (wavefront.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct GpuTile {
    origin: [u32; 2],
    size: [u32; 2],
    capacity: u32,
    pad: [u32; 3],
}

impl Wavefront {
    fn new(ctx: &GpuContext, p: &Prepared, queue_factor: u32) -> Result<Wavefront, GpuError> {
        let device = &ctx.device;
        ctx.validated("gpu-trace wavefront set-up", || {
            use wgpu::{BufferBindingType as B, ShaderStages as St};
            let read_write = || buffer_binding(B::Storage { read_only: false });
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("gpu-trace wavefront"),
                entries: &[
                    layout_entry(0, St::COMPUTE, read_write()),
                    layout_entry(1, St::COMPUTE, read_write()),
                    layout_entry(2, St::COMPUTE, read_write()),
                    layout_entry(3, St::COMPUTE, buffer_binding(B::Uniform)),
                    layout_entry(
                        4,
                        St::COMPUTE,
                        wgpu::BindingType::Buffer {
                            ty: B::Uniform,
                            has_dynamic_offset: true,
                            min_binding_size: wgpu::BufferSize::new(4),
                        },
                    ),
                ],
            });
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("gpu-trace wavefront"),
                bind_group_layouts: &[Some(&p.layout), Some(&p.scene_layout), Some(&layout)],
                ..Default::default()
            });
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("gpu_trace/wavefront.wgsl"),
                source: wgpu::ShaderSource::Wgsl(wavefront_source().into()),
            });
            let pipeline = |entry: &str| {
                device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                    label: Some(entry),
                    layout: Some(&pipeline_layout),
                    module: &module,
                    entry_point: Some(entry),
                    compilation_options: Default::default(),
                    cache: None,
                })
            };
            let tile_pixels = WAVEFRONT_TILE * WAVEFRONT_TILE;
            let capacity = queue_factor * tile_pixels;
            // WGSL `PendingRay`: three vec3 + u32 rows of 16 bytes.
            const PENDING_RAY_BYTES: u64 = 48;
            let storage =
                |label, size: u64| writable_buffer(ctx, label, size, wgpu::BufferUsages::STORAGE);
            let queues = storage("ray queues", 2 * capacity as u64 * PENDING_RAY_BYTES);
            let queue_counts = storage("ray queue counts", 4 * (GENERATIONS as u64 + 1));
            let accumulator = storage("radiance accumulator", 12 * tile_pixels as u64);
            let tile = writable_buffer(
                ctx,
                "wavefront tile",
                size_of::<GpuTile>() as u64,
                wgpu::BufferUsages::UNIFORM,
            );
            let generation_stride = device.limits().min_uniform_buffer_offset_alignment.max(4);
            let generations = writable_buffer(
                ctx,
                "wavefront generations",
                (generation_stride * GENERATIONS) as u64,
                wgpu::BufferUsages::UNIFORM,
            );
            let numbers: Vec<u8> = (0..GENERATIONS)
                .flat_map(|g| {
                    let mut entry = vec![0u8; generation_stride as usize];
                    entry[..4].copy_from_slice(&g.to_le_bytes());
                    entry
                })
                .collect();
            ctx.queue.write_buffer(&generations, 0, &numbers);
            let bind_group = specula_gpu::util::bind_group(
                ctx,
                "gpu-trace wavefront",
                &layout,
                &[
                    queues.as_entire_binding(),
                    queue_counts.as_entire_binding(),
                    accumulator.as_entire_binding(),
                    tile.as_entire_binding(),
                    wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer: &generations,
                        offset: 0,
                        size: wgpu::BufferSize::new(4),
                    }),
                ],
            );
            Wavefront {
                generate: pipeline("cs_generate"),
                extend: pipeline("cs_extend"),
                resolve: pipeline("cs_resolve"),
                queue_factor,
                bind_group,
                tile,
                queue_counts,
                accumulator,
                generation_stride,
            }
        })
    }

    /// Rays each queue holds: `queue_factor` × the pixels of a whole tile.
    fn capacity(&self) -> u32 {
        self.queue_factor * WAVEFRONT_TILE * WAVEFRONT_TILE
    }

    /// Traces the image tile by tile (group 0 bound to `group`).
    fn trace(
        &self,
        ctx: &GpuContext,
        p: &Prepared,
        group: &wgpu::BindGroup,
        width: u32,
        height: u32,
        max_depth: u32,
    ) {
        for y0 in (0..height).step_by(WAVEFRONT_TILE as usize) {
            for x0 in (0..width).step_by(WAVEFRONT_TILE as usize) {
                let size = [
                    WAVEFRONT_TILE.min(width - x0),
                    WAVEFRONT_TILE.min(height - y0),
                ];
                let tile = GpuTile {
                    origin: [x0, y0],
                    size,
                    capacity: self.queue_factor * size[0] * size[1],
                    pad: [0; 3],
                };
                ctx.queue
                    .write_buffer(&self.tile, 0, bytemuck::bytes_of(&tile));
                let pixels = size[0] * size[1];
                let mut encoder = ctx.device.create_command_encoder(&Default::default());
                encoder.clear_buffer(&self.queue_counts, 0, None);
                encoder.clear_buffer(&self.accumulator, 0, None);
                {
                    let mut pass = encoder.begin_compute_pass(&Default::default());
                    pass.set_bind_group(0, group, &[]);
                    pass.set_bind_group(1, &p.scene_bind_group, &[]);
                    pass.set_bind_group(2, &self.bind_group, &[0]);
                    pass.set_pipeline(&self.generate);
                    pass.dispatch_workgroups(pixels.div_ceil(64), 1, 1);
                    pass.set_pipeline(&self.extend);
                    // Generation g holds at most MAX_CHILDREN^g rays per pixel, and never more
                    // than a queue holds.
                    let mut bound = pixels as u64;
                    for g in 0..=max_depth.min(GENERATIONS - 1) {
                        pass.set_bind_group(2, &self.bind_group, &[g * self.generation_stride]);
                        pass.dispatch_workgroups(
                            (bound.min(tile.capacity as u64) as u32).div_ceil(64),
                            1,
                            1,
                        );
                        bound *= 6;
                    }
                    pass.set_pipeline(&self.resolve);
                    pass.dispatch_workgroups(pixels.div_ceil(64), 1, 1);
                }
                ctx.queue.submit([encoder.finish()]);
            }
        }
    }
}

#[derive(Default)]
pub struct GpuTrace {
    pub params: Params,
    /// The wavefront's queues, made for the current preparation at the first wavefront frame.
    wavefront: Option<Wavefront>,
}

impl GpuTrace {
    pub fn new(mode: Mode, max_depth: u32) -> GpuMethod<GpuTrace> {
        let mut trace = GpuMethod::<GpuTrace>::default();
        trace.params.mode = mode;
        trace.params.max_depth = max_depth;
        trace
    }
}

fn storage_buffer(ctx: &GpuContext, label: &str, bytes: &[u8]) -> wgpu::Buffer {
    // Storage bindings may not be empty, and hold at least one element of any of the structs.
    let size = bytes.len().max(64) as u64;
    let buffer = writable_buffer(ctx, label, size, wgpu::BufferUsages::STORAGE);
    ctx.queue.write_buffer(&buffer, 0, bytes);
    buffer
}

/// Writes `bytes` into `buffer`, or into a new buffer when they no longer fit.
fn rewrite(ctx: &GpuContext, buffer: &mut wgpu::Buffer, label: &str, bytes: &[u8]) {
    if bytes.len() as u64 > buffer.size() {
        *buffer = storage_buffer(ctx, label, bytes);
    } else {
        ctx.queue.write_buffer(buffer, 0, bytes);
    }
}

impl GpuTrace {
    fn build(ctx: &GpuContext, live: &LiveScene) -> Result<Prepared, GpuError> {
        let device = &ctx.device;
        let gpu_scene = live.gpu(ctx);
        let accel = live.accel();
        ctx.validated("gpu-trace set-up", || {
            use wgpu::{BufferBindingType as B, ShaderStages as St};
            let read_only = || buffer_binding(B::Storage { read_only: true });
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("gpu-trace"),
                entries: &[
                    layout_entry(0, St::COMPUTE, buffer_binding(B::Uniform)),
                    layout_entry(1, St::COMPUTE, read_only()),
                    layout_entry(2, St::COMPUTE, read_only()),
                    layout_entry(3, St::COMPUTE, read_only()),
                    layout_entry(
                        4,
                        St::COMPUTE,
                        wgpu::BindingType::StorageTexture {
                            access: wgpu::StorageTextureAccess::WriteOnly,
                            format: raster::COLOR_FORMAT,
                            view_dimension: wgpu::TextureViewDimension::D2,
                        },
                    ),
                    layout_entry(
                        5,
                        St::COMPUTE,
                        buffer_binding(B::Storage { read_only: false }),
                    ),
                    layout_entry(6, St::COMPUTE, buffer_binding(B::Uniform)),
                ],
            });
            let scene_layout = GpuScene::bind_group_layout(device);
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("gpu-trace"),
                bind_group_layouts: &[Some(&layout), Some(&scene_layout)],
                ..Default::default()
            });
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("gpu_trace/megakernel.wgsl"),
                source: wgpu::ShaderSource::Wgsl(megakernel_source().into()),
            });
            let megakernel = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some("gpu-trace megakernel"),
                layout: Some(&pipeline_layout),
                module: &module,
                entry_point: Some("cs_trace"),
                compilation_options: Default::default(),
                cache: None,
            });
            let uniform = |label, size: usize| {
                writable_buffer(ctx, label, size as u64, wgpu::BufferUsages::UNIFORM)
            };
            Prepared {
                uploaded_at: live.version(),
                nodes: storage_buffer(ctx, "bvh nodes", bytemuck::cast_slice(&accel.bvh.nodes)),
                triangles: storage_buffer(
                    ctx,
                    "bvh triangles",
                    bytemuck::cast_slice(&leaf_triangles(accel, gpu_scene)),
                ),
                triangle_count: accel.triangles.len() as u32,
                camera: uniform("gpu-trace camera", size_of::<CameraUniform>()),
                settings: uniform("gpu-trace settings", size_of::<GpuSettings>()),
                counters: Counters::new(ctx, "gpu-trace counters", COUNTER_NAMES.len()),
                scene_bind_group: gpu_scene.bind_group(ctx, &scene_layout),
                layout,
                scene_layout,
                megakernel,
                bind_group: None,
            }
        })
    }
}

impl Prepared {
    /// Writes the moved scene's BVH and triangles (after [`LiveScene`] refitted or rebuilt it).
    fn upload_moves(&mut self, ctx: &GpuContext, live: &LiveScene) {
        if self.uploaded_at == live.version() {
            return;
        }
        let accel = live.accel();
        let nodes = bytemuck::cast_slice(&accel.bvh.nodes);
        let before = (self.nodes.size(), self.triangles.size());
        rewrite(ctx, &mut self.nodes, "bvh nodes", nodes);
        let triangles = leaf_triangles(accel, live.gpu(ctx));
        rewrite(
            ctx,
            &mut self.triangles,
            "bvh triangles",
            bytemuck::cast_slice(&triangles),
        );
        if (self.nodes.size(), self.triangles.size()) != before {
            self.bind_group = None;
        }
        self.uploaded_at = live.version();
    }

    fn bind_group(
        &mut self,
        ctx: &GpuContext,
        live: &LiveScene,
        output: &wgpu::Texture,
    ) -> &wgpu::BindGroup {
        if self.bind_group.as_ref().is_none_or(|(t, _)| t != output) {
            let view = output.create_view(&Default::default());
            let group = specula_gpu::util::bind_group(
                ctx,
                "gpu-trace",
                &self.layout,
                &[
                    self.camera.as_entire_binding(),
                    self.nodes.as_entire_binding(),
                    self.triangles.as_entire_binding(),
                    live.gpu(ctx).vertices.as_entire_binding(),
                    wgpu::BindingResource::TextureView(&view),
                    self.counters.buffer.as_entire_binding(),
                    self.settings.as_entire_binding(),
                ],
            );
            self.bind_group = Some((output.clone(), group));
        }
        &self.bind_group.as_ref().expect("made above").1
    }
}

impl GpuTechnique for GpuTrace {
    type Prepared = Prepared;
    type Params = Params;
    const INFO: &'static MethodInfo = &INFO;
    /// It traces from the camera: no G-buffer.
    const SCENE_RASTER: bool = false;

    fn params(&self) -> &Params {
        &self.params
    }

    fn params_mut(&mut self) -> &mut Params {
        &mut self.params
    }

    fn prepare(
        &mut self,
        gpu: &GpuContext,
        live: &LiveScene,
        _: Option<&RasterPass>,
    ) -> Result<Prepared, TechniqueError> {
        self.wavefront = None;
        Ok(Self::build(gpu, live)?)
    }

    fn invalidate(&mut self, _: Option<&mut Prepared>, what: Invalidates) -> bool {
        if what >= Invalidates::Resources {
            self.wavefront = None;
        }
        true
    }

    /// The moved scene's BVH uploaded, then every pixel's path traced in one dispatch (the
    /// megakernel) or generation by generation through queues (the wavefront).
    fn shade(&mut self, p: &mut Prepared, frame: &mut GpuFrame<'_>) -> Result<(), TechniqueError> {
        p.upload_moves(frame.gpu, frame.live);
        frame.lap("bvh upload")?;
        self.trace(p, frame)?;
        frame.lap("ray tracing")?;
        let counts = p.counters.read(frame.gpu)?;
        if counts[DROPPED] > 0 {
            frame.warn(format!(
                "gpu-trace dropped {} rays (its ray stack or queues were full; max_depth {} is past what they hold): the image is darker where they went",
                counts[DROPPED], self.params.max_depth
            ));
        }
        for (name, count) in COUNTER_NAMES.iter().zip(counts) {
            frame.count(name, count as u64);
        }
        Ok(())
    }
}

impl GpuTrace {
    /// Every pixel's path, into `frame.output`.
    fn trace(&mut self, p: &mut Prepared, frame: &GpuFrame<'_>) -> Result<(), TechniqueError> {
        let (gpu, live, output) = (frame.gpu, frame.live, frame.output());
        let (width, height) = (frame.width, frame.height);
        if self.params.mode == Mode::Wavefront && self.wavefront.is_none() {
            self.wavefront = Some(Wavefront::new(gpu, p, self.params.queue_factor)?);
        }
        let wavefront = self
            .wavefront
            .as_ref()
            .filter(|_| self.params.mode == Mode::Wavefront);
        let settings = GpuSettings {
            max_depth: self.params.max_depth,
            triangle_count: p.triangle_count,
            queue_capacity: wavefront.map(Wavefront::capacity).unwrap_or(0),
            pad: 0,
        };
        let max_depth = self.params.max_depth;
        Ok(gpu.validated("gpu-trace", || {
            gpu.queue
                .write_buffer(&p.camera, 0, bytemuck::bytes_of(&frame.camera_uniform));
            gpu.queue
                .write_buffer(&p.settings, 0, bytemuck::bytes_of(&settings));
            p.counters.clear(gpu);
            let group = p.bind_group(gpu, live, output).clone();
            if let Some(wavefront) = wavefront {
                wavefront.trace(gpu, p, &group, width, height, max_depth);
                return;
            }
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            {
                let mut pass = encoder.begin_compute_pass(&Default::default());
                pass.set_pipeline(&p.megakernel);
                pass.set_bind_group(0, &group, &[]);
                pass.set_bind_group(1, &p.scene_bind_group, &[]);
                pass.dispatch_workgroups(width.div_ceil(8), height.div_ceil(8), 1);
            }
            gpu.queue.submit([encoder.finish()]);
        })?)
    }
}
