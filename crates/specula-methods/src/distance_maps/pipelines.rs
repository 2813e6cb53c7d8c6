//! distance-maps' GPU pipelines: the layer pass that draws the maps, the min-max reduction of
//! their ranges and the tracing pass, each with its bind group layout; and the views of the
//! maps' array textures.

use specula_gpu::util::{
    buffer_binding, layout_entry, render_pipeline, texture_binding, PipelineSpec,
};

use specula_gpu::GpuContext;

use specula_core::raster;

use super::{layers_shader_source, ranges_shader_source, trace_shader_source, MAP_FORMAT};

// What most bindings here are.
const FLOAT: wgpu::TextureSampleType = wgpu::TextureSampleType::Float { filterable: false };
const UNIFORM: wgpu::BufferBindingType = wgpu::BufferBindingType::Uniform;
const READ_ONLY: wgpu::BufferBindingType = wgpu::BufferBindingType::Storage { read_only: true };

/// The layer pass: its bind group 0 layout (view, previous layer) and its pipeline.
pub(super) fn layer_pass(
    device: &wgpu::Device,
    scene_layout: &wgpu::BindGroupLayout,
    shadow_layout: &wgpu::BindGroupLayout,
) -> (wgpu::BindGroupLayout, wgpu::RenderPipeline) {
    use wgpu::{ShaderStages as St, TextureViewDimension as D};
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("distance-map layer"),
        entries: &[
            layout_entry(0, St::VERTEX_FRAGMENT, buffer_binding(UNIFORM)),
            layout_entry(1, St::FRAGMENT, texture_binding(FLOAT, D::D2Array)),
        ],
    });
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("distance_maps/layers.wgsl"),
        source: wgpu::ShaderSource::Wgsl(layers_shader_source().into()),
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("distance-map layer"),
        bind_group_layouts: &[Some(&layout), Some(scene_layout), Some(shadow_layout)],
        ..Default::default()
    });
    let pipeline = render_pipeline(
        device,
        &PipelineSpec {
            label: "distance-map layer",
            layout: &pipeline_layout,
            module: &module,
            vertex_entry: "vs_layer",
            fragment_entry: "fs_layer",
            vertex_buffers: &[Some(raster::vertex_layout())],
            depth: Some(wgpu::DepthStencilState {
                format: raster::DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            targets: &[MAP_FORMAT, MAP_FORMAT],
            write_mask: wgpu::ColorWrites::ALL,
            blend: None,
            cull_mode: None,
        },
    );
    (layout, pipeline)
}

/// The min-max reduction over `geometry_maps`: its pipeline, bind group and the range buffer
/// (two u32 per map).
pub(super) fn range_pass(
    ctx: &GpuContext,
    geometry_maps: &wgpu::Texture,
    map_count: u32,
) -> (wgpu::ComputePipeline, wgpu::BindGroup, wgpu::Buffer) {
    use wgpu::{ShaderStages as St, TextureViewDimension as D};
    let device = &ctx.device;
    let ranges = ctx.create_buffer(&wgpu::BufferDescriptor {
        label: Some("distance-map ranges"),
        size: 8 * map_count as u64,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("distance-map ranges"),
        entries: &[
            layout_entry(0, St::COMPUTE, texture_binding(FLOAT, D::D2Array)),
            layout_entry(
                1,
                St::COMPUTE,
                buffer_binding(wgpu::BufferBindingType::Storage { read_only: false }),
            ),
        ],
    });
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("distance_maps/ranges.wgsl"),
        source: wgpu::ShaderSource::Wgsl(ranges_shader_source().into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("distance-map ranges"),
        layout: Some(
            &device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("distance-map ranges"),
                bind_group_layouts: &[Some(&layout)],
                ..Default::default()
            }),
        ),
        module: &module,
        entry_point: Some("cs_range"),
        compilation_options: Default::default(),
        cache: None,
    });
    let bind_group = ctx.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("distance-map ranges"),
        layout: &layout,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(&array_view(geometry_maps)),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: ranges.as_entire_binding(),
            },
        ],
    });
    (pipeline, bind_group, ranges)
}

/// The tracing pass: its bind group 0 layout and its pipeline.
pub(super) fn trace_pass(
    device: &wgpu::Device,
    scene_layout: &wgpu::BindGroupLayout,
) -> (wgpu::BindGroupLayout, wgpu::RenderPipeline) {
    use wgpu::{ShaderStages as St, TextureSampleType as S, TextureViewDimension as D};
    let fragment = |binding, ty| layout_entry(binding, St::FRAGMENT, ty);
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("distance-map trace"),
        entries: &[
            fragment(0, buffer_binding(UNIFORM)),
            fragment(1, buffer_binding(UNIFORM)),
            fragment(2, texture_binding(FLOAT, D::D2)),
            fragment(3, texture_binding(FLOAT, D::D2)),
            fragment(4, texture_binding(FLOAT, D::D2)),
            fragment(5, texture_binding(S::Uint, D::D2)),
            fragment(6, texture_binding(FLOAT, D::D2Array)),
            fragment(7, texture_binding(FLOAT, D::D2Array)),
            fragment(8, buffer_binding(READ_ONLY)),
            fragment(9, buffer_binding(READ_ONLY)),
            fragment(10, buffer_binding(READ_ONLY)),
            fragment(11, buffer_binding(READ_ONLY)),
            fragment(
                12,
                buffer_binding(wgpu::BufferBindingType::Storage { read_only: false }),
            ),
        ],
    });
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("distance_maps/trace.wgsl"),
        source: wgpu::ShaderSource::Wgsl(trace_shader_source().into()),
    });
    let pipeline =
        raster::shading_pipeline(device, "distance-map trace", &module, &layout, scene_layout);
    (layout, pipeline)
}

/// A view of every layer of an array texture.
pub(super) fn array_view(texture: &wgpu::Texture) -> wgpu::TextureView {
    texture.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    })
}

/// A view of one layer of an array texture.
pub(super) fn layer_view(
    texture: &wgpu::Texture,
    layer: u32,
    dimension: wgpu::TextureViewDimension,
) -> wgpu::TextureView {
    texture.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(dimension),
        base_array_layer: layer,
        array_layer_count: Some(1),
        ..Default::default()
    })
}
