//! Composition on the raster: the refined faces drawn with Gouraud shading by the GPU, as the
//! paper composited them ("rendered with Gouraud shading" on graphics hardware, Ullmann et al.
//! 2001 §3), where the CPU otherwise locates each reflector pixel in its triangle's face tree.
//!
//! Each leaf face is one triangle of `compose.wgsl` with its corners' traced colours. A
//! fragment is kept only where the frame's ID buffer (uploaded once per frame) shows the face's
//! own triangle, so faces take exactly the pixels the CPU composition gives them, with the same
//! perspective-correct (or, `perspective_correct=false`, screen-linear) weights at the same
//! pixel centres. What the GPU does not shade as the CPU does is left to the CPU, marked by
//! alpha 0 in the readback: pixels of faces with deferred textures (texels read per pixel), a
//! corner behind the eye or no screen area, pixels no face covers (a centre just outside its
//! triangle's projection, which the ID buffer's rounding gave it), and filled pixels (traced).
//!
//! Costs: one upload of the ID buffer per frame (8 bytes a pixel), the faces' vertices
//! (36 bytes per corner), one draw, and the readback of the frame (16 bytes a pixel). A face
//! list larger than the device's largest buffer is composed on the CPU, with a warning.

use bytemuck::{Pod, Zeroable};
use specula_gpu::shaders::{self, CameraUniform};
use specula_gpu::util::{
    bind_group, buffer_binding, layout_entry, render_pipeline, texture_2d, texture_binding,
    writable_buffer, PipelineSpec,
};
use specula_gpu::{GpuContext, GpuError};

use specula_core::raster::{COLOR_FORMAT, IDS_FORMAT};

const SHADER: &str = include_str!("compose.wgsl");

/// The composition shader's full source (the camera prepended).
pub fn shader_source() -> String {
    shaders::compose(&["camera.wgsl"], SHADER)
}

/// One corner of a leaf face, as `compose.wgsl`'s `FaceVertex` reads it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct FaceVertex {
    pub p_world: [f32; 3],
    pub color: [f32; 3],
    /// (mesh + 1, triangle): the ID buffer's value where the face shows.
    pub triangle_id: [u32; 2],
    /// 1: the CPU shades this face's pixels (alpha 0 is written).
    pub cpu_shaded: u32,
}

/// Host mirror of WGSL `ComposeSettings`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct ComposeSettings {
    pub perspective_correct: u32,
    pub pad: [u32; 3],
}

/// Per view size: the uploaded ID buffer, the composition target and their bind group.
struct SizedTargets {
    ids: wgpu::Texture,
    target: wgpu::Texture,
    bind_group: wgpu::BindGroup,
}

/// The composition pass, kept across frames (its buffers grow, never shrink).
pub struct RasterComposition {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    camera: wgpu::Buffer,
    settings: wgpu::Buffer,
    sized: Option<SizedTargets>,
    vertices: Option<wgpu::Buffer>,
}

impl RasterComposition {
    pub fn new(gpu: &GpuContext) -> RasterComposition {
        let device = &gpu.device;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("vertex-tracing composition"),
            source: wgpu::ShaderSource::Wgsl(shader_source().into()),
        });
        let both = wgpu::ShaderStages::VERTEX | wgpu::ShaderStages::FRAGMENT;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("vertex-tracing composition"),
            entries: &[
                layout_entry(0, both, buffer_binding(wgpu::BufferBindingType::Uniform)),
                layout_entry(
                    1,
                    wgpu::ShaderStages::FRAGMENT,
                    buffer_binding(wgpu::BufferBindingType::Uniform),
                ),
                layout_entry(
                    2,
                    wgpu::ShaderStages::FRAGMENT,
                    texture_binding(
                        wgpu::TextureSampleType::Uint,
                        wgpu::TextureViewDimension::D2,
                    ),
                ),
            ],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("vertex-tracing composition"),
            bind_group_layouts: &[Some(&layout)],
            ..Default::default()
        });
        const ATTRIBUTES: [wgpu::VertexAttribute; 4] = wgpu::vertex_attr_array![
            0 => Float32x3, 1 => Float32x3, 2 => Uint32x2, 3 => Uint32
        ];
        let vertex_layout = wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<FaceVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &ATTRIBUTES,
        };
        let pipeline = render_pipeline(
            device,
            &PipelineSpec {
                label: "vertex-tracing composition",
                layout: &pipeline_layout,
                module: &module,
                vertex_entry: "vs_face",
                fragment_entry: "fs_face",
                vertex_buffers: &[Some(vertex_layout)],
                depth: None,
                targets: &[COLOR_FORMAT],
                write_mask: wgpu::ColorWrites::ALL,
                blend: None,
                cull_mode: None,
            },
        );
        let uniform = wgpu::BufferUsages::UNIFORM;
        RasterComposition {
            pipeline,
            layout,
            camera: writable_buffer(
                gpu,
                "composition camera",
                std::mem::size_of::<CameraUniform>() as u64,
                uniform,
            ),
            settings: writable_buffer(
                gpu,
                "composition settings",
                std::mem::size_of::<ComposeSettings>() as u64,
                uniform,
            ),
            sized: None,
            vertices: None,
        }
    }

    /// Uploads a frame's ID buffer: per pixel (mesh + 1, triangle), row by row.
    pub fn set_id_buffer(&mut self, gpu: &GpuContext, ids: &[[u32; 2]], width: u32, height: u32) {
        if self
            .sized
            .as_ref()
            .is_none_or(|s| (s.ids.width(), s.ids.height()) != (width, height))
        {
            let ids = texture_2d(
                gpu,
                "composition id buffer",
                width,
                height,
                IDS_FORMAT,
                wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            );
            let target = texture_2d(
                gpu,
                "composition target",
                width,
                height,
                COLOR_FORMAT,
                wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            );
            let bind_group = bind_group(
                gpu,
                "vertex-tracing composition",
                &self.layout,
                &[
                    self.camera.as_entire_binding(),
                    self.settings.as_entire_binding(),
                    wgpu::BindingResource::TextureView(&ids.create_view(&Default::default())),
                ],
            );
            self.sized = Some(SizedTargets {
                ids,
                target,
                bind_group,
            });
        }
        let sized = self.sized.as_ref().expect("made above");
        gpu.queue.write_texture(
            sized.ids.as_image_copy(),
            bytemuck::cast_slice(ids),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(width * 8),
                rows_per_image: None,
            },
            sized.ids.size(),
        );
    }

    /// The largest face list one draw takes, in corners (the device's buffer limit).
    pub fn max_corners(gpu: &GpuContext) -> usize {
        let corners =
            gpu.device.limits().max_buffer_size / std::mem::size_of::<FaceVertex>() as u64;
        corners.min(u32::MAX as u64) as usize
    }

    /// Draws `corners` (three a face) over the ID buffer last set and reads the result back:
    /// per pixel (colour, 1) where a face drawn on the GPU shows, zero elsewhere. `corners`
    /// must hold at most [`RasterComposition::max_corners`].
    pub fn compose(
        &mut self,
        gpu: &GpuContext,
        camera: &CameraUniform,
        perspective_correct: bool,
        corners: &[FaceVertex],
    ) -> Result<Vec<[f32; 4]>, GpuError> {
        let sized = self
            .sized
            .as_ref()
            .expect("set_id_buffer is called before compose");
        let bytes: &[u8] = bytemuck::cast_slice(corners);
        if self
            .vertices
            .as_ref()
            .is_none_or(|b| b.size() < bytes.len() as u64)
        {
            // Grown by half again, so that a frame a little larger than the last does not
            // reallocate.
            let size = (bytes.len() as u64 + bytes.len() as u64 / 2)
                .min(gpu.device.limits().max_buffer_size);
            self.vertices = Some(writable_buffer(
                gpu,
                "composition faces",
                size,
                wgpu::BufferUsages::VERTEX,
            ));
        }
        let vertices = self.vertices.as_ref().expect("made above");
        gpu.queue
            .write_buffer(&self.camera, 0, bytemuck::bytes_of(camera));
        let settings = ComposeSettings {
            perspective_correct: perspective_correct as u32,
            pad: [0; 3],
        };
        gpu.queue
            .write_buffer(&self.settings, 0, bytemuck::bytes_of(&settings));
        if !bytes.is_empty() {
            gpu.queue.write_buffer(vertices, 0, bytes);
        }
        let view = sized.target.create_view(&Default::default());
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("vertex-tracing composition"),
                color_attachments: &[specula_gpu::util::color_attachment(
                    &view,
                    wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                )],
                ..Default::default()
            });
            if !corners.is_empty() {
                pass.set_pipeline(&self.pipeline);
                pass.set_bind_group(0, &sized.bind_group, &[]);
                pass.set_vertex_buffer(0, vertices.slice(..bytes.len() as u64));
                pass.draw(0..corners.len() as u32, 0..1);
            }
        }
        gpu.queue.submit([encoder.finish()]);
        let texels = gpu.read_texture(&sized.target, 0)?;
        Ok(bytemuck::pod_collect_to_vec(&texels))
    }
}
