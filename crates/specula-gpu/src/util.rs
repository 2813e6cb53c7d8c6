//! Small constructors for what every pass creates, so passes state only what differs.

/// A single-layer, single-mip 2D texture.
pub fn texture_2d(
    ctx: &crate::GpuContext,
    label: &str,
    width: u32,
    height: u32,
    format: wgpu::TextureFormat,
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    ctx.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage,
        view_formats: &[],
    })
}

/// A bind-group-layout entry (no array count).
pub fn layout_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
    ty: wgpu::BindingType,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty,
        count: None,
    }
}

/// A sampled, single-sample texture binding.
pub fn texture_binding(
    sample_type: wgpu::TextureSampleType,
    dimension: wgpu::TextureViewDimension,
) -> wgpu::BindingType {
    wgpu::BindingType::Texture {
        sample_type,
        view_dimension: dimension,
        multisampled: false,
    }
}

/// A colour attachment that loads with `load` and stores.
pub fn color_attachment(
    view: &wgpu::TextureView,
    load: wgpu::LoadOp<wgpu::Color>,
) -> Option<wgpu::RenderPassColorAttachment<'_>> {
    Some(wgpu::RenderPassColorAttachment {
        view,
        depth_slice: None,
        resolve_target: None,
        ops: wgpu::Operations {
            load,
            store: wgpu::StoreOp::Store,
        },
    })
}

/// A buffer binding without dynamic offset or minimum size.
pub fn buffer_binding(ty: wgpu::BufferBindingType) -> wgpu::BindingType {
    wgpu::BindingType::Buffer {
        ty,
        has_dynamic_offset: false,
        min_binding_size: None,
    }
}

/// What distinguishes one render pipeline from another here: entry points, vertex buffers,
/// depth state and colour targets (triangle lists, no multisampling).
pub struct PipelineSpec<'a> {
    pub label: &'a str,
    pub layout: &'a wgpu::PipelineLayout,
    pub module: &'a wgpu::ShaderModule,
    pub vertex_entry: &'a str,
    pub fragment_entry: &'a str,
    pub vertex_buffers: &'a [Option<wgpu::VertexBufferLayout<'a>>],
    pub depth: Option<wgpu::DepthStencilState>,
    pub targets: &'a [wgpu::TextureFormat],
    /// Channels written to every target.
    pub write_mask: wgpu::ColorWrites,
    /// Blending into every target; None: the fragment replaces what is there.
    pub blend: Option<wgpu::BlendState>,
    /// Triangles facing away (`Back`) or towards (`Front`) the view are skipped; None: both kept.
    pub cull_mode: Option<wgpu::Face>,
}

pub fn render_pipeline(device: &wgpu::Device, spec: &PipelineSpec) -> wgpu::RenderPipeline {
    let targets: Vec<Option<wgpu::ColorTargetState>> = spec
        .targets
        .iter()
        .map(|&format| {
            Some(wgpu::ColorTargetState {
                format,
                blend: spec.blend,
                write_mask: spec.write_mask,
            })
        })
        .collect();
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(spec.label),
        layout: Some(spec.layout),
        vertex: wgpu::VertexState {
            module: spec.module,
            entry_point: Some(spec.vertex_entry),
            compilation_options: Default::default(),
            buffers: spec.vertex_buffers,
        },
        primitive: wgpu::PrimitiveState {
            cull_mode: spec.cull_mode,
            ..Default::default()
        },
        depth_stencil: spec.depth.clone(),
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: spec.module,
            entry_point: Some(spec.fragment_entry),
            compilation_options: Default::default(),
            targets: &targets,
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// Parses and validates WGSL with naga (as wgpu will), returning the module or naga's message
/// pointing into the source.
pub fn validate_wgsl(name: &str, source: &str) -> Result<naga::Module, String> {
    let module = naga::front::wgsl::parse_str(source)
        .map_err(|e| format!("{name}: {}", e.emit_to_string(source)))?;
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&module)
    .map_err(|e| format!("{name}: {}", e.emit_to_string(source)))?;
    Ok(module)
}

/// A bind group whose entry `i` binds `resources[i]` at binding `i`.
pub fn bind_group(
    ctx: &crate::GpuContext,
    label: &str,
    layout: &wgpu::BindGroupLayout,
    resources: &[wgpu::BindingResource],
) -> wgpu::BindGroup {
    let entries: Vec<wgpu::BindGroupEntry> = resources
        .iter()
        .enumerate()
        .map(|(i, resource)| wgpu::BindGroupEntry {
            binding: i as u32,
            resource: resource.clone(),
        })
        .collect();
    ctx.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout,
        entries: &entries,
    })
}

/// A buffer of `size` bytes that is written in place (`COPY_DST` added to `usage`).
pub fn writable_buffer(
    ctx: &crate::GpuContext,
    label: &str,
    size: u64,
    usage: wgpu::BufferUsages,
) -> wgpu::Buffer {
    ctx.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(16),
        usage: usage | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })
}

/// Bytes per row of a texture-to-buffer copy: `unpadded` rounded up to wgpu's row alignment.
pub fn padded_row_bytes(unpadded: u32) -> u32 {
    unpadded.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT
}
