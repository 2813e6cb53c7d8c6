//! Depth-peeled layers of the solid refractors' surfaces from the eye (`layers` > 1): layer k
//! holds, per texel, the k-th surface along the eye ray (both facings), its world position,
//! view depth and normal, in two 2D-array textures the final pass reads.

use bytemuck::{Pod, Zeroable};
use specula_gpu::shaders::{self, CameraUniform};
use specula_gpu::util::{
    buffer_binding, layout_entry, render_pipeline, texture_binding, writable_buffer, PipelineSpec,
};
use specula_gpu::GpuContext;

use specula_core::gpu_scene::GpuScene;
use specula_core::raster;

const SHADER: &str = include_str!("peel.wgsl");

pub fn shader_source() -> String {
    shaders::compose(&["camera.wgsl", "scene.wgsl"], SHADER)
}

/// Host mirror of WGSL `Peel`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct PeelUniform {
    behind_previous: u32,
    pad: [u32; 3],
}

/// The peeled layers at one size and count, with what draws each.
struct Layers {
    width: u32,
    height: u32,
    count: u32,
    depth: wgpu::Texture,
    /// Per layer: its bind group (the previous layer's position) and its two target views.
    per_layer: Vec<(wgpu::BindGroup, wgpu::TextureView, wgpu::TextureView)>,
    position_view: wgpu::TextureView,
    normal_view: wgpu::TextureView,
}

pub struct Peel {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    camera: wgpu::Buffer,
    /// Uniforms for the first layer (nothing peeled) and the others.
    first: wgpu::Buffer,
    others: wgpu::Buffer,
    scene_bind_group: wgpu::BindGroup,
    layers: Option<Layers>,
    /// Counts the layer textures made, so that bind groups know when theirs are gone.
    generation: u64,
}

const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

impl Peel {
    pub fn new(ctx: &GpuContext, gpu_scene: &GpuScene) -> Peel {
        use wgpu::{BufferBindingType as B, ShaderStages as St, TextureViewDimension as D};
        let device = &ctx.device;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("image-space peel"),
            entries: &[
                layout_entry(0, St::VERTEX_FRAGMENT, buffer_binding(B::Uniform)),
                layout_entry(
                    1,
                    St::FRAGMENT,
                    texture_binding(wgpu::TextureSampleType::Float { filterable: false }, D::D2),
                ),
                layout_entry(2, St::FRAGMENT, buffer_binding(B::Uniform)),
            ],
        });
        let scene_layout = GpuScene::bind_group_layout(device);
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("image-space peel"),
            bind_group_layouts: &[Some(&layout), Some(&scene_layout)],
            ..Default::default()
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("image_space/peel.wgsl"),
            source: wgpu::ShaderSource::Wgsl(shader_source().into()),
        });
        let pipeline = render_pipeline(
            device,
            &PipelineSpec {
                label: "image-space peel",
                layout: &pipeline_layout,
                module: &module,
                vertex_entry: "vs_peel",
                fragment_entry: "fs_peel",
                vertex_buffers: &[Some(raster::vertex_layout())],
                depth: Some(wgpu::DepthStencilState {
                    format: raster::DEPTH_FORMAT,
                    depth_write_enabled: Some(true),
                    depth_compare: Some(wgpu::CompareFunction::Less),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                targets: &[FORMAT, FORMAT],
                write_mask: wgpu::ColorWrites::ALL,
                blend: None,
                cull_mode: None,
            },
        );
        let uniform = |label, value: u32| {
            let buffer = writable_buffer(ctx, label, 16, wgpu::BufferUsages::UNIFORM);
            ctx.queue.write_buffer(
                &buffer,
                0,
                bytemuck::bytes_of(&PeelUniform {
                    behind_previous: value,
                    pad: [0; 3],
                }),
            );
            buffer
        };
        Peel {
            pipeline,
            layout,
            camera: writable_buffer(
                ctx,
                "peel camera",
                size_of::<CameraUniform>() as u64,
                wgpu::BufferUsages::UNIFORM,
            ),
            first: uniform("peel first layer", 0),
            others: uniform("peel other layers", 1),
            scene_bind_group: gpu_scene.bind_group(ctx, &scene_layout),
            layers: None,
            generation: 0,
        }
    }

    fn make_layers(&self, ctx: &GpuContext, width: u32, height: u32, count: u32) -> Layers {
        let array = |label| {
            ctx.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d {
                    width,
                    height,
                    depth_or_array_layers: count,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: FORMAT,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            })
        };
        let position = array("peeled positions");
        let normal = array("peeled normals");
        let depth = specula_gpu::util::texture_2d(
            ctx,
            "peel depth",
            width,
            height,
            raster::DEPTH_FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT,
        );
        let layer_view = |texture: &wgpu::Texture, layer: u32| {
            texture.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2),
                base_array_layer: layer,
                array_layer_count: Some(1),
                ..Default::default()
            })
        };
        let array_view = |texture: &wgpu::Texture| {
            texture.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2Array),
                ..Default::default()
            })
        };
        let per_layer = (0..count)
            .map(|k| {
                // The first layer reads nothing (behind_previous = 0); it binds the last layer
                // only to fill the slot (never its own target).
                let (uniform, previous) = if k == 0 {
                    (&self.first, layer_view(&position, count - 1))
                } else {
                    (&self.others, layer_view(&position, k - 1))
                };
                let group = specula_gpu::util::bind_group(
                    ctx,
                    "image-space peel",
                    &self.layout,
                    &[
                        self.camera.as_entire_binding(),
                        wgpu::BindingResource::TextureView(&previous),
                        uniform.as_entire_binding(),
                    ],
                );
                (group, layer_view(&position, k), layer_view(&normal, k))
            })
            .collect();
        Layers {
            width,
            height,
            count,
            position_view: array_view(&position),
            normal_view: array_view(&normal),
            depth,
            per_layer,
        }
    }

    /// Draws `count` layers of the meshes in `ranges` for `camera`.
    pub fn draw(
        &mut self,
        ctx: &GpuContext,
        gpu_scene: &GpuScene,
        ranges: &[std::ops::Range<u32>],
        camera: &CameraUniform,
        count: u32,
    ) {
        let (width, height) = (camera.width as u32, camera.height as u32);
        let stale = self
            .layers
            .as_ref()
            .is_none_or(|l| (l.width, l.height, l.count) != (width, height, count));
        if stale {
            self.layers = Some(self.make_layers(ctx, width, height, count));
            self.generation += 1;
        }
        let layers = self.layers.as_ref().expect("made above");
        ctx.queue
            .write_buffer(&self.camera, 0, bytemuck::bytes_of(camera));
        let depth_view = layers.depth.create_view(&Default::default());
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        for (group, position, normal) in &layers.per_layer {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("image-space peel"),
                color_attachments: &[
                    specula_gpu::util::color_attachment(
                        position,
                        wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    ),
                    specula_gpu::util::color_attachment(
                        normal,
                        wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                    ),
                ],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &depth_view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                ..Default::default()
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, group, &[]);
            pass.set_bind_group(1, &self.scene_bind_group, &[]);
            pass.set_vertex_buffer(0, gpu_scene.vertices.slice(..));
            for range in ranges {
                pass.draw(range.clone(), 0..1);
            }
        }
        ctx.queue.submit([encoder.finish()]);
    }

    /// The layers' positions and normals as 2D arrays and their generation (after `draw`).
    pub fn views(&self) -> Option<(&wgpu::TextureView, &wgpu::TextureView, u64)> {
        self.layers
            .as_ref()
            .map(|l| (&l.position_view, &l.normal_view, self.generation))
    }
}
