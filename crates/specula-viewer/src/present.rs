//! Draws the viewer's images onto the window surface (`present.wgsl`): one image, or two side
//! by side at a split. The images live in two kept `Rgba32Float` textures: a technique's GPU
//! frame is copied in on the GPU, a CPU image (reference, error map, a CPU technique) is
//! written in place; a texture is made again only when its size changes.

use bytemuck::{Pod, Zeroable};
use specula_gpu::util::{self, layout_entry, texture_binding};
use specula_gpu::GpuContext;
use specula_trace::Image;

const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct Params {
    size: [f32; 2],
    split: f32,
    mode: u32,
    encode_srgb: u32,
    offset_x: f32,
    pad: [u32; 2],
}

/// Where on the window the images go: `width` × `height` pixels from `x` (the panel is left
/// of it), the whole height.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Viewport {
    pub x: u32,
    pub width: u32,
    pub height: u32,
}

/// Which of the two images a source goes to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    Left,
    Right,
}

pub struct Presenter {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    params: wgpu::Buffer,
    images: [wgpu::Texture; 2],
    bind_group: wgpu::BindGroup,
    encode_srgb: bool,
}

impl Presenter {
    pub fn new(gpu: &GpuContext, surface_format: wgpu::TextureFormat) -> Presenter {
        let module = gpu
            .device
            .create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("present"),
                source: wgpu::ShaderSource::Wgsl(include_str!("present.wgsl").into()),
            });
        let fragment = wgpu::ShaderStages::FRAGMENT;
        let image = texture_binding(
            wgpu::TextureSampleType::Float { filterable: false },
            wgpu::TextureViewDimension::D2,
        );
        let layout = gpu
            .device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("present"),
                entries: &[
                    layout_entry(0, fragment, image),
                    layout_entry(1, fragment, image),
                    layout_entry(
                        2,
                        fragment,
                        util::buffer_binding(wgpu::BufferBindingType::Uniform),
                    ),
                ],
            });
        let pipeline_layout = gpu
            .device
            .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("present"),
                bind_group_layouts: &[Some(&layout)],
                ..Default::default()
            });
        let pipeline = util::render_pipeline(
            &gpu.device,
            &util::PipelineSpec {
                label: "present",
                layout: &pipeline_layout,
                module: &module,
                vertex_entry: "vs_main",
                fragment_entry: "fs_main",
                vertex_buffers: &[],
                depth: None,
                targets: &[surface_format],
                write_mask: wgpu::ColorWrites::ALL,
                blend: None,
                cull_mode: None,
            },
        );
        let params = util::writable_buffer(
            gpu,
            "present params",
            std::mem::size_of::<Params>() as u64,
            wgpu::BufferUsages::UNIFORM,
        );
        let images = [image_texture(gpu, 1, 1), image_texture(gpu, 1, 1)];
        let bind_group = make_bind_group(gpu, &layout, &images, &params);
        Presenter {
            pipeline,
            layout,
            params,
            images,
            bind_group,
            encode_srgb: !surface_format.is_srgb(),
        }
    }

    /// The texture for `side`, made again (with the bind group) where its size differs.
    fn target(&mut self, gpu: &GpuContext, side: Side, width: u32, height: u32) -> &wgpu::Texture {
        let i = side as usize;
        let size = self.images[i].size();
        if (size.width, size.height) != (width, height) {
            self.images[i] = image_texture(gpu, width, height);
            self.bind_group = make_bind_group(gpu, &self.layout, &self.images, &self.params);
        }
        &self.images[i]
    }

    /// Copies a technique's frame texture (`Rgba32Float`) to `side`.
    pub fn show_texture(
        &mut self,
        gpu: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        side: Side,
        frame: &wgpu::Texture,
    ) {
        let size = frame.size();
        let target = self.target(gpu, side, size.width, size.height);
        encoder.copy_texture_to_texture(
            frame.as_image_copy(),
            target.as_image_copy(),
            wgpu::Extent3d {
                depth_or_array_layers: 1,
                ..size
            },
        );
    }

    /// Writes a CPU image to `side`.
    pub fn show_image(&mut self, gpu: &GpuContext, side: Side, image: &Image) {
        let target = self.target(gpu, side, image.width, image.height).clone();
        let texels: Vec<[f32; 4]> = image.pixels.iter().map(|c| [c.x, c.y, c.z, 1.0]).collect();
        gpu.queue.write_texture(
            target.as_image_copy(),
            bytemuck::cast_slice(&texels),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(image.width * 16),
                rows_per_image: None,
            },
            target.size(),
        );
    }

    /// Draws the left image (or, with `split`, both, cut at that fraction of the width) over
    /// the whole of `target`.
    pub fn draw(
        &self,
        gpu: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        target: &wgpu::TextureView,
        viewport: Viewport,
        split: Option<f32>,
    ) {
        let params = Params {
            size: [viewport.width as f32, viewport.height as f32],
            split: split.unwrap_or(1.0),
            mode: split.is_some() as u32,
            encode_srgb: self.encode_srgb as u32,
            offset_x: viewport.x as f32,
            pad: [0; 2],
        };
        gpu.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(&params));
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("present"),
            color_attachments: &[specula_gpu::util::color_attachment(
                target,
                wgpu::LoadOp::Clear(wgpu::Color::BLACK),
            )],
            ..Default::default()
        });
        pass.set_viewport(
            viewport.x as f32,
            0.0,
            viewport.width as f32,
            viewport.height as f32,
            0.0,
            1.0,
        );
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &self.bind_group, &[]);
        pass.draw(0..3, 0..1);
    }
}

fn image_texture(gpu: &GpuContext, width: u32, height: u32) -> wgpu::Texture {
    util::texture_2d(
        gpu,
        "viewer image",
        width.max(1),
        height.max(1),
        FORMAT,
        wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
    )
}

fn make_bind_group(
    gpu: &GpuContext,
    layout: &wgpu::BindGroupLayout,
    images: &[wgpu::Texture; 2],
    params: &wgpu::Buffer,
) -> wgpu::BindGroup {
    let views = images
        .each_ref()
        .map(|t| t.create_view(&Default::default()));
    util::bind_group(
        gpu,
        "present",
        layout,
        &[
            wgpu::BindingResource::TextureView(&views[0]),
            wgpu::BindingResource::TextureView(&views[1]),
            params.as_entire_binding(),
        ],
    )
}

#[cfg(test)]
mod tests {
    #[test]
    fn present_shader_is_valid_wgsl() {
        specula_gpu::util::validate_wgsl("present.wgsl", include_str!("present.wgsl")).unwrap();
    }
}
