//! pvrr's GPU passes: the set-up (pipelines, arenas), the reflection maps (1st pass, step 4)
//! and the reflectors drawn with their vertices' coordinates (2nd pass, step 6).

use super::*;

pub fn shader_source() -> String {
    shaders::compose(&["optics.wgsl", "camera.wgsl"], SHADER)
}

/// Marker balls (centre, radius, colour channel) as `GpuVertex` triangles of the marker mesh
/// `first_marker_mesh` + channel.
pub(super) fn marker_vertices(
    first_marker_mesh: u32,
    balls: &[Ball],
) -> Vec<specula_core::gpu_scene::GpuVertex> {
    use specula_core::gpu_scene::GpuVertex;
    let ball = specula_scene::generators::sphere(1.0, 8, 4);
    let mut vertices = Vec::new();
    for &(p, radius, channel) in balls {
        let marker_mesh = first_marker_mesh + channel;
        for tri in &ball.triangles {
            for &i in tri {
                let n = ball.normals[i as usize];
                vertices.push(GpuVertex {
                    position: (p + ball.positions[i as usize] * radius).to_array(),
                    mesh: marker_mesh,
                    normal: n.to_array(),
                    triangle: 0,
                    uv: [0.0, 0.0],
                });
            }
        }
    }
    vertices
}

impl Pvrr {
    /// What depends on the scene: its reflectors and extent, the 2nd pass's pipelines and
    /// layout, and the per-frame arenas.
    pub(super) fn build(&self, ctx: &GpuContext, live: &LiveScene) -> Result<Prepared, GpuError> {
        let device = &ctx.device;
        let scene = live.scene();
        ctx.validated("pvrr set-up", || {
            let stages = wgpu::ShaderStages::VERTEX_FRAGMENT;
            // Cameras and materials live in the uniform arena, bound at dynamic offsets.
            let uniform = |size: usize| wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: true,
                min_binding_size: std::num::NonZeroU64::new(size as u64),
            };
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("pvrr mirror"),
                entries: &[
                    layout_entry(0, stages, uniform(size_of::<CameraUniform>())),
                    layout_entry(
                        1,
                        stages,
                        texture_binding(
                            wgpu::TextureSampleType::Float { filterable: false },
                            wgpu::TextureViewDimension::D2,
                        ),
                    ),
                    layout_entry(2, stages, uniform(size_of::<GpuMirrorMaterial>())),
                ],
            });
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("pvrr mirror"),
                bind_group_layouts: &[Some(&layout)],
                ..Default::default()
            });
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("pvrr.wgsl"),
                source: wgpu::ShaderSource::Wgsl(shader_source().into()),
            });
            const ATTRIBUTES: [wgpu::VertexAttribute; 6] = wgpu::vertex_attr_array![
                0 => Float32x3, 1 => Float32x3, 2 => Float32x2, 3 => Float32, 4 => Float32,
                5 => Float32x3
            ];
            let pipeline = |(write_mask, blend)| {
                render_pipeline(
                    device,
                    &PipelineSpec {
                        label: "pvrr mirror",
                        layout: &pipeline_layout,
                        module: &module,
                        vertex_entry: "vs_mirror",
                        fragment_entry: "fs_mirror",
                        vertex_buffers: &[Some(wgpu::VertexBufferLayout {
                            array_stride: std::mem::size_of::<MirrorVertex>() as u64,
                            step_mode: wgpu::VertexStepMode::Vertex,
                            attributes: &ATTRIBUTES,
                        })],
                        depth: Some(wgpu::DepthStencilState {
                            format: raster::DEPTH_FORMAT,
                            depth_write_enabled: Some(false),
                            depth_compare: Some(wgpu::CompareFunction::LessEqual),
                            stencil: Default::default(),
                            // Drawn again, a triangle does not always reproduce the G-buffer's
                            // depth bit for bit: on truck-cover black specks were left where it
                            // fell a hair behind (mean FLIP 0.078 -> 0.042 with this unit).
                            bias: wgpu::DepthBiasState {
                                constant: -1,
                                slope_scale: 0.0,
                                clamp: 0.0,
                            },
                        }),
                        targets: &[raster::COLOR_FORMAT],
                        write_mask,
                        blend,
                        cull_mode: None,
                    },
                )
            };
            let add = wgpu::BlendState {
                color: wgpu::BlendComponent {
                    src_factor: wgpu::BlendFactor::One,
                    dst_factor: wgpu::BlendFactor::One,
                    operation: wgpu::BlendOperation::Add,
                },
                alpha: wgpu::BlendComponent::REPLACE,
            };
            let pipelines = [
                (wgpu::ColorWrites::ALL, None),
                (wgpu::ColorWrites::RED, None),
                (wgpu::ColorWrites::GREEN, None),
                (wgpu::ColorWrites::BLUE, None),
            ]
            .map(&pipeline);
            // Without float blending a dielectric's surface reflection cannot be added.
            let additive = ctx
                .float32_blendable
                .then(|| pipeline((wgpu::ColorWrites::ALL, Some(add))));
            let reflectors = (0..scene.meshes.len())
                .flat_map(|mesh| Reflector::of(scene, mesh, self.params.ior.0))
                .filter(|r| !r.additive || additive.is_some())
                .collect();
            let (scene_corners, far_distance) = scene_extent(scene);
            let alignment = device.limits().min_uniform_buffer_offset_alignment as u64;
            Prepared {
                version: live.version(),
                reflectors,
                scene_corners,
                far_distance,
                pipelines,
                additive,
                layout,
                arenas: RefCell::new(Arenas {
                    vertices: Arena::new("pvrr vertices", wgpu::BufferUsages::VERTEX, 4),
                    uniforms: Arena::new("pvrr uniforms", wgpu::BufferUsages::UNIFORM, alignment),
                    bind_groups: BindGroupsBySlot::default(),
                }),
            }
        })
    }
}

/// Step 4: the reflection map of every patch of `tree`'s level: the scene raster without the
/// patch's reflector, with the other reflectors drawn over it by pvrr from the patch's virtual
/// viewpoint where the tree plans a level there (§4.4).
pub(super) fn render_maps(
    ctx: &GpuContext,
    p: &Shared,
    tree: &PlanTree,
    markers: Option<(&wgpu::Buffer, u64, u32)>,
) -> Result<Vec<Vec<GBuffer>>, GpuError> {
    tree.level
        .reflectors
        .iter()
        .enumerate()
        .map(|(r, reflector)| {
            reflector
                .patches
                .iter()
                .enumerate()
                .map(|(i, patch)| {
                    let hidden = Some(reflector.mesh);
                    let g = match &patch.fill {
                        None => p.raster.render_with(
                            ctx,
                            p.gpu_scene,
                            &patch.camera,
                            hidden,
                            markers,
                        )?,
                        Some(fill) => {
                            let g =
                                p.raster
                                    .render_with(ctx, p.gpu_scene, fill, hidden, markers)?;
                            p.raster.draw_farthest_into(
                                ctx,
                                p.gpu_scene,
                                &patch.camera,
                                hidden.as_slice(),
                                markers,
                                &g,
                            )?;
                            g
                        }
                    };
                    if let Some(inner) = tree.inner.get(r).and_then(|patches| patches[i].as_ref()) {
                        let maps = render_maps(ctx, p, inner, markers)?;
                        // The nested 2nd pass's vertices are spent once it is submitted.
                        let mark = p.arenas.borrow().vertices.used();
                        second_pass(ctx, p, &patch.camera, &g, &inner.level, &maps)?;
                        p.arenas.borrow_mut().vertices.rewind(mark);
                        maps.iter().flatten().for_each(|m| p.raster.release(m));
                    }
                    Ok(g)
                })
                .collect()
        })
        .collect()
}

/// Step 6: every reflector of `plan` drawn over `g` (rendered with `camera`) from its maps.
pub(super) fn second_pass(
    ctx: &GpuContext,
    p: &Shared,
    camera: &CameraUniform,
    g: &GBuffer,
    plan: &LevelPlan,
    maps: &[Vec<GBuffer>],
) -> Result<(), GpuError> {
    if plan.reflectors.is_empty() {
        return Ok(());
    }
    ctx.validated("pvrr 2nd pass", || -> Result<(), GpuError> {
        let mut arenas = p.arenas.borrow_mut();
        let arenas = &mut *arenas;
        // Room first (see Arena): one camera, one material per reflector, the vertices.
        let vertex_sizes: Vec<u64> = plan
            .reflectors
            .iter()
            .flat_map(|r| &r.patches)
            .flat_map(|patch| &patch.channels)
            .map(|v| std::mem::size_of_val(v.as_slice()) as u64)
            .collect();
        let uniform_sizes = std::iter::once(size_of::<CameraUniform>() as u64).chain(
            plan.reflectors
                .iter()
                .map(|_| size_of::<GpuMirrorMaterial>() as u64),
        );
        arenas.vertices.reserve(ctx, vertex_sizes)?;
        if arenas.uniforms.reserve(ctx, uniform_sizes)? {
            arenas.bind_groups.clear();
        }
        let camera_offset = arenas.uniforms.push(ctx, bytemuck::bytes_of(camera)) as u32;
        // (pipeline, map slot, material offset, vertex offset, count) per draw.
        let mut draws = Vec::new();
        for (reflector, maps) in plan.reflectors.iter().zip(maps) {
            let material_offset = arenas
                .uniforms
                .push(ctx, bytemuck::bytes_of(&reflector.material))
                as u32;
            for (patch, map) in reflector.patches.iter().zip(maps) {
                let uniforms = arenas.uniforms.buffer();
                arenas.bind_groups.get_or_make(p.raster, map, || {
                    let map_view = map.color.create_view(&Default::default());
                    let binding = |size: usize| {
                        wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                            buffer: uniforms,
                            offset: 0,
                            size: std::num::NonZeroU64::new(size as u64),
                        })
                    };
                    bind_group(
                        ctx,
                        "pvrr mirror",
                        &p.layout,
                        &[
                            binding(size_of::<CameraUniform>()),
                            wgpu::BindingResource::TextureView(&map_view),
                            binding(size_of::<GpuMirrorMaterial>()),
                        ],
                    )
                });
                let masked = patch.channels.len() == 3;
                for (c, vertices) in patch.channels.iter().enumerate() {
                    if vertices.is_empty() {
                        continue;
                    }
                    let offset = arenas.vertices.push(ctx, bytemuck::cast_slice(vertices));
                    let pipeline = match &p.additive {
                        Some(additive) if reflector.additive => additive,
                        _ => &p.pipelines[if masked { c + 1 } else { 0 }],
                    };
                    draws.push((
                        pipeline,
                        map.slot,
                        material_offset,
                        offset,
                        vertices.len() as u32,
                    ));
                }
            }
        }
        let color_view = g.color.create_view(&Default::default());
        let depth_view = g.depth.create_view(&Default::default());
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("pvrr 2nd pass"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &color_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Load,
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &depth_view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Load,
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                ..Default::default()
            });
            let vertices = arenas.vertices.buffer();
            for (pipeline, slot, material_offset, offset, count) in draws {
                let group = arenas.bind_groups.get(slot).expect("made above");
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, group, &[camera_offset, material_offset]);
                pass.set_vertex_buffer(0, vertices.slice(offset..));
                pass.draw(0..count, 0..1);
            }
        }
        ctx.queue.submit([encoder.finish()]);
        Ok(())
    })?
}
