//! c3rc's forward phase as GPU compute passes (`projection=gpu`, project.wgsl): the CPU's
//! plan (cameras and the leaves each sees) uploaded as work items, one workgroup per (camera,
//! leaf); the projection, the two splat passes (nearest depth, then nearest centre within the
//! depth band), the resolve and the hole filling run on the GPU into the buffer the shading
//! pass reads. The forward phase's switches (`FrameSettings`) travel in each camera. Buffers grow when a frame needs more and are otherwise reused, so a warm frame
//! creates no GPU objects.

use bytemuck::{Pod, Zeroable};
use specula_gpu::shaders::compose;
use specula_gpu::util::{
    bind_group, buffer_binding, layout_entry, texture_binding, writable_buffer,
};
use specula_gpu::{GpuContext, GpuError};

use super::cpu_frame::{FrameSettings, PlacedCloud, Plan, ScreenView};
use super::points::PointCloud;
use specula_core::raster::GBuffer;

const SHADER: &str = include_str!("project.wgsl");

pub fn shader_source() -> String {
    compose(&[], SHADER)
}

/// Largest point index the 24-bit keys hold.
pub const MAX_POINTS: usize = 1 << 24;

/// Host mirror of WGSL `Settings`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuSettings {
    pub eye: [f32; 4],
    pub right: [f32; 4],
    pub up: [f32; 4],
    pub forward: [f32; 4],
    pub lens: [f32; 4],
    pub width: u32,
    pub height: u32,
    pub work_items: u32,
    pub row: u32,
}

/// Host mirror of WGSL `Point`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuPoint {
    pub p: [f32; 4],
    pub n: [f32; 4],
    pub color: [f32; 4],
}

/// Host mirror of WGSL `Camera`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuCamera {
    pub v: [[f32; 4]; 3],
    pub d: [[f32; 4]; 3],
    pub frame: [f32; 4],
    pub planes: [[f32; 4]; 4],
    pub info: [f32; 4],
    pub ids: [u32; 4],
}

/// A buffer that grows to fit (to the next power of two, so that a warm frame makes none).
#[derive(Default)]
pub struct Growing {
    buffer: Option<wgpu::Buffer>,
    capacity: u64,
    /// How many buffers have been made: bind groups that hold this one follow it.
    generation: u64,
}

impl Growing {
    /// The buffer, made again (bigger) when `elements` of `element_size` bytes do not fit; true
    /// when it was made. It always holds one element at least: a binding may not be smaller
    /// than the shader's element, even where there is nothing to hold (a scene with no mirror).
    pub fn fit(
        &mut self,
        ctx: &GpuContext,
        label: &str,
        elements: usize,
        element_size: usize,
        usage: wgpu::BufferUsages,
    ) -> bool {
        let size = ((elements.max(1) * element_size) as u64).max(16);
        if self.buffer.is_some() && size <= self.capacity {
            return false;
        }
        let capacity = size.next_power_of_two();
        self.buffer = Some(writable_buffer(ctx, label, capacity, usage));
        self.capacity = capacity;
        self.generation += 1;
        true
    }

    pub fn get(&self) -> &wgpu::Buffer {
        self.buffer.as_ref().expect("fitted first")
    }

    pub fn generation(&self) -> u64 {
        self.generation
    }
}

pub struct GpuProjection {
    layout: wgpu::BindGroupLayout,
    clear: wgpu::ComputePipeline,
    splat_depth: wgpu::ComputePipeline,
    splat_nearest: wgpu::ComputePipeline,
    resolve: wgpu::ComputePipeline,
    fill_holes: wgpu::ComputePipeline,
    settings: wgpu::Buffer,
    counts: wgpu::Buffer,
    counts_readback: wgpu::Buffer,
    points: Growing,
    clouds: Growing,
    cameras: Growing,
    work: Growing,
    depth: Growing,
    nearest: Growing,
    mirror_meshes: Growing,
    /// The points uploaded: (near-field generation) they came from.
    uploaded: Option<u64>,
    /// The bind group, and the G-buffer slot and buffer generations (its own, the near
    /// buffer's) it was made for.
    bound: Option<((usize, u64, u64), wgpu::BindGroup)>,
    generation: u64,
}

/// What the GPU counted: (points in leaves, points projected, valid projections, splats).
pub type GpuCounts = [u32; 4];

impl GpuProjection {
    pub fn new(ctx: &GpuContext) -> Result<GpuProjection, GpuError> {
        let device = &ctx.device;
        ctx.validated("c3rc projection set-up", || {
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("c3rc project.wgsl"),
                source: wgpu::ShaderSource::Wgsl(shader_source().into()),
            });
            use wgpu::{BufferBindingType as B, ShaderStages as St, TextureSampleType as S};
            let read = || buffer_binding(B::Storage { read_only: true });
            let write = || buffer_binding(B::Storage { read_only: false });
            let d2 = wgpu::TextureViewDimension::D2;
            let entries = [
                layout_entry(0, St::COMPUTE, buffer_binding(B::Uniform)),
                layout_entry(1, St::COMPUTE, read()),
                layout_entry(2, St::COMPUTE, read()),
                layout_entry(3, St::COMPUTE, read()),
                layout_entry(4, St::COMPUTE, read()),
                layout_entry(5, St::COMPUTE, write()),
                layout_entry(6, St::COMPUTE, write()),
                layout_entry(7, St::COMPUTE, write()),
                layout_entry(
                    8,
                    St::COMPUTE,
                    texture_binding(S::Float { filterable: false }, d2),
                ),
                layout_entry(9, St::COMPUTE, texture_binding(S::Uint, d2)),
                layout_entry(10, St::COMPUTE, write()),
                layout_entry(11, St::COMPUTE, read()),
            ];
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("c3rc projection"),
                entries: &entries,
            });
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("c3rc projection"),
                bind_group_layouts: &[Some(&layout)],
                ..Default::default()
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
            let counts = writable_buffer(
                ctx,
                "c3rc gpu counts",
                16,
                wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            );
            let counts_readback = ctx.create_buffer(&wgpu::BufferDescriptor {
                label: Some("c3rc gpu counts readback"),
                size: 16,
                usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
                mapped_at_creation: false,
            });
            GpuProjection {
                clear: pipeline("clear"),
                splat_depth: pipeline("splat_depth"),
                splat_nearest: pipeline("splat_nearest"),
                resolve: pipeline("resolve"),
                fill_holes: pipeline("fill_holes"),
                layout,
                settings: writable_buffer(
                    ctx,
                    "c3rc projection settings",
                    size_of::<GpuSettings>() as u64,
                    wgpu::BufferUsages::UNIFORM,
                ),
                counts,
                counts_readback,
                points: Growing::default(),
                clouds: Growing::default(),
                cameras: Growing::default(),
                work: Growing::default(),
                depth: Growing::default(),
                nearest: Growing::default(),
                mirror_meshes: Growing::default(),
                uploaded: None,
                bound: None,
                generation: 0,
            }
        })
    }

    /// Runs the forward phase of `plan` into `near` (a storage buffer of one vec4 per pixel
    /// that already holds the per-vertex colour, alpha [`super::cpu_frame::TAKEN_AS_IT_IS`], where the
    /// plan gives it): the points and the frame's cameras and work uploaded, then the splats'
    /// depth, the nearest splat, the resolve and the holes filled, in compute passes.
    #[allow(clippy::too_many_arguments)]
    pub fn forward(
        &mut self,
        ctx: &GpuContext,
        plan: &Plan,
        placed: &[PlacedCloud],
        cloud_generation: u64,
        mirrors: &[usize],
        mesh_count: usize,
        view: &ScreenView,
        camera: &specula_scene::Camera,
        settings: &FrameSettings,
        g: &GBuffer,
        near: &Growing,
    ) -> Result<GpuCounts, GpuError> {
        let points_made = self.upload_points(ctx, placed, cloud_generation);
        let (frame_made, work_items, row) =
            self.upload_frame(ctx, plan, placed, mirrors, mesh_count, view, camera, settings);
        if points_made || frame_made {
            self.generation += 1;
        }
        self.bind(ctx, g, near);
        let pixels = (view.width * view.height) as u64;
        self.dispatch(ctx, pixels, work_items, row, settings)
    }

    /// Every cloud's points, one after another, uploaded when the clouds changed. Returns
    /// whether a buffer was made again.
    fn upload_points(&mut self, ctx: &GpuContext, placed: &[PlacedCloud], cloud_generation: u64) -> bool {
        let storage = wgpu::BufferUsages::STORAGE;
        let mut made = false;
        let clouds: Vec<&PointCloud> = placed.iter().map(|p| p.cloud).collect();
        let total: usize = clouds.iter().map(|c| c.len()).sum();
        made |= self
            .points
            .fit(ctx, "c3rc points", total, size_of::<GpuPoint>(), storage);
        if made || self.uploaded != Some(cloud_generation) {
            let mut data = Vec::with_capacity(total);
            for (k, cloud) in clouds.iter().enumerate() {
                for i in 0..cloud.len() {
                    let (p, n, c) = (cloud.p_object[i], cloud.n_object[i], cloud.color[i]);
                    data.push(GpuPoint {
                        p: [p.x, p.y, p.z, k as f32],
                        n: [n.x, n.y, n.z, cloud.radius],
                        color: [c.x, c.y, c.z, 1.0],
                    });
                }
            }
            ctx.queue
                .write_buffer(self.points.get(), 0, bytemuck::cast_slice(&data));
            self.uploaded = Some(cloud_generation);
        }
        made
    }

    /// The frame's cloud placements, cameras, work items (camera, first point, count, stride),
    /// depth and nearest buffers, mirror flags and settings. Returns whether a buffer was made
    /// again, the work items and the dispatch's row width.
    #[allow(clippy::too_many_arguments)]
    fn upload_frame(
        &mut self,
        ctx: &GpuContext,
        plan: &Plan,
        placed: &[PlacedCloud],
        mirrors: &[usize],
        mesh_count: usize,
        view: &ScreenView,
        camera: &specula_scene::Camera,
        settings: &FrameSettings,
    ) -> (bool, usize, u32) {
        let storage = wgpu::BufferUsages::STORAGE;
        let mut made = false;
        let clouds: Vec<&PointCloud> = placed.iter().map(|p| p.cloud).collect();
        let offsets: Vec<u32> = clouds
            .iter()
            .scan(0u32, |at, c| {
                let first = *at;
                *at += c.len() as u32;
                Some(first)
            })
            .collect();
        let matrices: Vec<[f32; 16]> = placed
            .iter()
            .map(|p| p.world_from_object.as_mat4().to_cols_array())
            .collect();
        made |= self
            .clouds
            .fit(ctx, "c3rc clouds", matrices.len(), 64, storage);
        ctx.queue
            .write_buffer(self.clouds.get(), 0, bytemuck::cast_slice(&matrices));
        let cameras: Vec<GpuCamera> = plan
            .cameras
            .iter()
            .map(|c| gpu_camera(c, settings))
            .collect();
        made |= self.cameras.fit(
            ctx,
            "c3rc cameras",
            cameras.len(),
            size_of::<GpuCamera>(),
            storage,
        );
        ctx.queue
            .write_buffer(self.cameras.get(), 0, bytemuck::cast_slice(&cameras));
        let (clouds, offsets) = (&clouds, &offsets);
        let work: Vec<[u32; 4]> = plan
            .seen
            .iter()
            .enumerate()
            .flat_map(|(i, seen)| {
                seen.iter().map(move |s| {
                    let node = &clouds[s.cloud].nodes[s.node];
                    [
                        i as u32,
                        offsets[s.cloud] + node.point_first,
                        node.point_count,
                        s.stride as u32,
                    ]
                })
            })
            .collect();
        made |= self.work.fit(ctx, "c3rc work", work.len(), 16, storage);
        ctx.queue
            .write_buffer(self.work.get(), 0, bytemuck::cast_slice(&work));
        let pixels = (view.width * view.height) as u64;
        made |= self
            .depth
            .fit(ctx, "c3rc depth", pixels as usize, 4, storage);
        made |= self
            .nearest
            .fit(ctx, "c3rc nearest", pixels as usize, 4, storage);
        let mut flags = vec![0u32; mesh_count.max(1)];
        for &m in mirrors {
            flags[m] = 1;
        }
        made |= self
            .mirror_meshes
            .fit(ctx, "c3rc mirror meshes", flags.len(), 4, storage);
        ctx.queue
            .write_buffer(self.mirror_meshes.get(), 0, bytemuck::cast_slice(&flags));
        let frame = camera.frame();
        let row = (work.len() as u32).clamp(1, 65535);
        let gpu_settings = GpuSettings {
            eye: view.eye.extend(0.0).to_array(),
            right: frame.right.extend(0.0).to_array(),
            up: frame.up.extend(0.0).to_array(),
            forward: frame.forward.extend(0.0).to_array(),
            lens: [
                (camera.fov_y_deg.to_radians() * 0.5).tan(),
                view.width as f32 / view.height as f32,
                settings.splat_scale,
                settings.max_splat,
            ],
            width: view.width,
            height: view.height,
            work_items: work.len() as u32,
            row,
        };
        ctx.queue
            .write_buffer(&self.settings, 0, bytemuck::bytes_of(&gpu_settings));
        (made, work.len(), row)
    }

    /// The projection's bind group, made again for another G-buffer, buffers or near buffer.
    fn bind(&mut self, ctx: &GpuContext, g: &GBuffer, near: &Growing) {
        let key = (g.slot, self.generation, near.generation());
        if self.bound.as_ref().map(|b| b.0) != Some(key) {
            let position = g.position.create_view(&Default::default());
            let ids = g.ids.create_view(&Default::default());
            let group = bind_group(
                ctx,
                "c3rc projection",
                &self.layout,
                &[
                    self.settings.as_entire_binding(),
                    self.points.get().as_entire_binding(),
                    self.clouds.get().as_entire_binding(),
                    self.cameras.get().as_entire_binding(),
                    self.work.get().as_entire_binding(),
                    self.depth.get().as_entire_binding(),
                    self.nearest.get().as_entire_binding(),
                    near.get().as_entire_binding(),
                    wgpu::BindingResource::TextureView(&position),
                    wgpu::BindingResource::TextureView(&ids),
                    self.counts.as_entire_binding(),
                    self.mirror_meshes.get().as_entire_binding(),
                ],
            );
            self.bound = Some((key, group));
        }
    }

    /// The compute passes over `work_items` items, and the counts they took.
    fn dispatch(
        &self,
        ctx: &GpuContext,
        pixels: u64,
        work_items: usize,
        row: u32,
        settings: &FrameSettings,
    ) -> Result<GpuCounts, GpuError> {
        let group = &self.bound.as_ref().expect("made above").1;
        ctx.validated("c3rc projection", || {
            let mut encoder = ctx.device.create_command_encoder(&Default::default());
            encoder.clear_buffer(&self.counts, 0, None);
            {
                let mut pass = encoder.begin_compute_pass(&Default::default());
                pass.set_bind_group(0, group, &[]);
                let pixel_groups = (pixels as u32).div_ceil(64);
                pass.set_pipeline(&self.clear);
                pass.dispatch_workgroups(pixel_groups, 1, 1);
                if work_items > 0 {
                    let rows = (work_items as u32).div_ceil(row);
                    pass.set_pipeline(&self.splat_depth);
                    pass.dispatch_workgroups(row, rows, 1);
                    pass.set_pipeline(&self.splat_nearest);
                    pass.dispatch_workgroups(row, rows, 1);
                }
                pass.set_pipeline(&self.resolve);
                pass.dispatch_workgroups(pixel_groups, 1, 1);
                if settings.fill_holes {
                    pass.set_pipeline(&self.fill_holes);
                    pass.dispatch_workgroups(pixel_groups, 1, 1);
                }
            }
            encoder.copy_buffer_to_buffer(&self.counts, 0, &self.counts_readback, 0, 16);
            ctx.queue.submit([encoder.finish()]);
        })?;
        ctx.read_mapped(&self.counts_readback, |bytes| {
            let counts: &[u32] = bytemuck::cast_slice(bytes);
            [counts[0], counts[1], counts[2], counts[3]]
        })
    }
}

/// A camera in its own frame (origin at its first vertex, scaled by its longest edge) with
/// its plane bound in world space, and the forward phase's switches.
fn gpu_camera(camera: &super::cpu_frame::TriangleCamera, settings: &FrameSettings) -> GpuCamera {
    let c = &camera.world;
    let scale = (0..3)
        .map(|i| (c.v[(i + 1) % 3] - c.v[i]).length())
        .fold(0.0f64, f64::max)
        .max(1e-12);
    let v =
        c.v.map(|p| ((p - c.v[0]) / scale).as_vec3().extend(0.0).to_array());
    let d = c.d.map(|x| x.as_vec3().extend(0.0).to_array());
    let mut planes = [[0.0, 0.0, 0.0, -1.0]; 4];
    for (slot, (n, offset)) in planes.iter_mut().zip(c.plane_bound().planes()) {
        // Normalised, with a little slack for f32.
        let length = n.length().max(1e-300);
        let unit = *n / length;
        *slot = [
            unit.x as f32,
            unit.y as f32,
            unit.z as f32,
            (offset / length - 1e-5 * scale) as f32,
        ];
    }
    let base = 0.5 * (c.v[1] - c.v[0]).cross(c.v[2] - c.v[0]).length();
    GpuCamera {
        v,
        d,
        frame: [
            c.v[0].x as f32,
            c.v[0].y as f32,
            c.v[0].z as f32,
            scale as f32,
        ],
        planes,
        info: [
            camera.screen_area as f32,
            camera.obliquity,
            base as f32,
            0.5 * settings.fixed_splat,
        ],
        ids: [
            camera.mesh as u32,
            (camera.may_project_twice() && settings.multiple_projections) as u32,
            settings.one_sided as u32,
            settings.depth_band as u32,
        ],
    }
}
