//! distance-maps' layered distance maps (steps 2 and 3): what is made per scene (the textures,
//! each layer face's view and draw, the buffers the tracing pass reads), placed again after a
//! move, drawn, and reduced to min-max ranges.

use specula_gpu::counters::Counters;
use specula_gpu::shaders::CameraUniform;
use specula_gpu::util::{bind_group, texture_2d, writable_buffer};
use specula_gpu::GpuContext;
use specula_scene::Scene;

use specula_core::gpu_scene::GpuScene;
use specula_core::live_scene::LiveScene;
use specula_core::raster::{self, BindGroupsBySlot, RasterPass};
use specula_core::TechniqueError;

use super::pipelines::{layer_pass, layer_view, range_pass, trace_pass};
use super::{
    face_bases, DistanceMaps, GpuLayerView, GpuMapReflector, GpuTraceSettings, LayerDraw, Layers,
    Prepared, FALLBACK_KINDS, KEEP_ALL, KEEP_NON_SPECULAR, KEEP_SPECULAR_AWAY,
    KEEP_SPECULAR_FACING, MAP_FORMAT,
};

/// The textures every map's layers are drawn into.
struct MapTextures {
    material: wgpu::Texture,
    geometry: wgpu::Texture,
    /// Bound as the "previous layer" where a layer does not peel.
    placeholder: wgpu::Texture,
}

impl DistanceMaps {
    /// Per face of every layer of every reflector's map (in draw order): its view, and which
    /// meshes it can hold; and the reflectors as the tracing pass sees them. Depends on where
    /// the reflectors are.
    #[allow(clippy::type_complexity)]
    fn layer_views(
        &self,
        scene: &Scene,
        gpu_scene: &GpuScene,
        reflectors: &[usize],
    ) -> (
        Vec<(GpuLayerView, Vec<std::ops::Range<u32>>)>,
        Vec<GpuMapReflector>,
    ) {
        let specular = |mesh: usize| scene.materials[scene.meshes[mesh].material].is_specular();
        let all = gpu_scene.vertex_ranges(|_| true);
        let specular_ranges = gpu_scene.vertex_ranges(specular);
        let diffuse_ranges = gpu_scene.vertex_ranges(|m| !specular(m));
        let bounds = scene.bounds();
        let layer_count = self.layer_count();
        let mut views_out = Vec::new();
        let mut gpu_reflectors = Vec::new();
        for (k, &mesh) in reflectors.iter().enumerate() {
            let origin = scene.meshes[mesh].bounds().center();
            let first_map = k as u32 * layer_count;
            let (near, far) = raster::depth_range(&bounds, origin);
            gpu_reflectors.push(GpuMapReflector {
                origin: origin.to_array(),
                first_map,
                far,
                pad: [0; 3],
            });
            let views = raster::cube_views(origin, near, far, self.params.resolution);
            for j in 0..layer_count {
                let (select, peel, ranges) = match self.params.layers {
                    Layers::Simple => match j {
                        0 => (KEEP_SPECULAR_FACING, 0, &specular_ranges),
                        1 => (KEEP_SPECULAR_AWAY, 0, &specular_ranges),
                        _ => (KEEP_NON_SPECULAR, u32::from(j > 2), &diffuse_ranges),
                    },
                    Layers::Peeled(_) => (KEEP_ALL, u32::from(j > 0), &all),
                };
                for view in &views {
                    let uniform = GpuLayerView {
                        clip_from_world: view.clip_from_world,
                        origin: origin.to_array(),
                        select,
                        peel,
                        pad: [0; 3],
                    };
                    views_out.push((uniform, ranges.clone()));
                }
            }
        }
        (views_out, gpu_reflectors)
    }

    /// What draws each layer's six faces, per reflector and layer (views written by
    /// [`Prepared::place`]).
    fn layer_draws(
        &self,
        ctx: &GpuContext,
        layer_count: u32,
        face_count: usize,
        layout: &wgpu::BindGroupLayout,
        maps: &MapTextures,
    ) -> Vec<LayerDraw> {
        use wgpu::TextureViewDimension as D;
        (0..face_count)
            .map(|i| {
                let array_layer = i as u32;
                let j = (array_layer / 6) % layer_count;
                let peel = match self.params.layers {
                    Layers::Simple => j > 2,
                    Layers::Peeled(_) => j > 0,
                };
                let view_buffer = writable_buffer(
                    ctx,
                    "distance-map layer view",
                    size_of::<GpuLayerView>() as u64,
                    wgpu::BufferUsages::UNIFORM,
                );
                let previous = if peel {
                    layer_view(&maps.geometry, array_layer - 6, D::D2Array)
                } else {
                    layer_view(&maps.placeholder, 0, D::D2Array)
                };
                let bind_group = bind_group(
                    ctx,
                    "distance-map layer",
                    layout,
                    &[
                        view_buffer.as_entire_binding(),
                        wgpu::BindingResource::TextureView(&previous),
                    ],
                );
                LayerDraw {
                    view_buffer,
                    bind_group,
                    material_target: layer_view(&maps.material, array_layer, D::D2),
                    geometry_target: layer_view(&maps.geometry, array_layer, D::D2),
                    vertex_ranges: Vec::new(),
                }
            })
            .collect()
    }

    pub(super) fn build(
        &self,
        ctx: &GpuContext,
        live: &LiveScene,
        raster: &RasterPass,
    ) -> Result<Prepared, TechniqueError> {
        let device = &ctx.device;
        let scene = live.scene();
        let gpu_scene = live.gpu(ctx);
        let reflectors: Vec<usize> = (0..scene.meshes.len())
            .filter(|&m| scene.materials[scene.meshes[m].material].is_specular())
            .collect();
        let layer_count = self.layer_count();
        let (map_count, array_layers) = self.map_layers(device, reflectors.len())?;
        let mut prepared = ctx.validated("distance-maps set-up", || {
            let (maps, depth) = self.map_textures(ctx, array_layers);
            let scene_layout = GpuScene::bind_group_layout(device);
            let (layer_layout, layer_pipeline) =
                layer_pass(device, &scene_layout, raster.shadow_layout());
            let draws = self.layer_draws(
                ctx,
                layer_count,
                6 * reflectors.len() * layer_count as usize,
                &layer_layout,
                &maps,
            );
            let (range_pipeline, range_bind_group, ranges) =
                range_pass(ctx, &maps.geometry, map_count);
            let (trace_layout, trace_pipeline) = trace_pass(device, &scene_layout);
            let mut mesh_reflector = vec![-1i32; scene.meshes.len().max(1)];
            for (k, &mesh) in reflectors.iter().enumerate() {
                mesh_reflector[mesh] = k as i32;
            }
            let storage = |label, contents: &[u8]| {
                let buffer = writable_buffer(
                    ctx,
                    label,
                    contents.len() as u64,
                    wgpu::BufferUsages::STORAGE,
                );
                ctx.queue.write_buffer(&buffer, 0, contents);
                buffer
            };
            let uniform = |label, size: usize| {
                writable_buffer(ctx, label, size as u64, wgpu::BufferUsages::UNIFORM)
            };
            Prepared {
                version: live.version(),
                maps_drawn_at: None,
                ranges_at: None,
                scene_bind_group: gpu_scene.bind_group(ctx, &scene_layout),
                settings: uniform("distance-map trace settings", size_of::<GpuTraceSettings>()),
                reflector_buffer: storage(
                    "distance-map reflectors",
                    &vec![0u8; reflectors.len().max(1) * size_of::<GpuMapReflector>()],
                ),
                mesh_reflector: storage(
                    "distance-map mesh reflectors",
                    bytemuck::cast_slice(&mesh_reflector),
                ),
                faces: storage("cube faces", bytemuck::cast_slice(&face_bases())),
                camera_buffer: uniform("camera", size_of::<CameraUniform>()),
                trace_bind_groups: BindGroupsBySlot::default(),
                fallbacks: Counters::new(ctx, "distance-map fallbacks", FALLBACK_KINDS.len()),
                reflectors,
                material_maps: maps.material,
                geometry_maps: maps.geometry,
                depth,
                draws,
                layer_pipeline,
                range_pipeline,
                range_bind_group,
                ranges,
                map_count,
                trace_pipeline,
                trace_layout,
            }
        })?;
        prepared.place(self, ctx, scene, gpu_scene);
        Ok(prepared)
    }

    /// The maps' count (reflectors × layers) and their cube faces' array layers, refused where
    /// the adapter holds fewer.
    fn map_layers(
        &self,
        device: &wgpu::Device,
        reflectors: usize,
    ) -> Result<(u32, u32), TechniqueError> {
        let layer_count = self.layer_count();
        let map_count = (reflectors as u32 * layer_count).max(1);
        let array_layers = 6 * map_count;
        let limit = device.limits().max_texture_array_layers;
        if array_layers > limit {
            return Err(TechniqueError::BadParameter {
                technique: "distance-maps",
                name: "layers".into(),
                value: layer_count.to_string(),
                reason: format!(
                    "{reflectors} reflectors × {layer_count} layers × 6 faces = {array_layers} cube faces; \
                     this adapter holds at most {limit}"
                ),
            });
        }
        Ok((map_count, array_layers))
    }

    /// Every map's material and geometry layers (`array_layers` faces each) and the depth
    /// buffer they are drawn with.
    fn map_textures(
        &self,
        ctx: &GpuContext,
        array_layers: u32,
    ) -> (MapTextures, wgpu::TextureView) {
        let map_texture = |label| {
            ctx.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d {
                    width: self.params.resolution,
                    height: self.params.resolution,
                    depth_or_array_layers: array_layers,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: MAP_FORMAT,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            })
        };
        let maps = MapTextures {
            material: map_texture("distance-map materials"),
            geometry: map_texture("distance-map geometry"),
            placeholder: texture_2d(
                ctx,
                "distance-map placeholder",
                1,
                1,
                MAP_FORMAT,
                wgpu::TextureUsages::TEXTURE_BINDING,
            ),
        };
        let depth = texture_2d(
            ctx,
            "distance-map depth",
            self.params.resolution,
            self.params.resolution,
            raster::DEPTH_FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT,
        )
        .create_view(&Default::default());
        (maps, depth)
    }

    /// The maps' views and origins, written again after a move.
    pub(super) fn place_for(&self, p: &mut Prepared, gpu: &GpuContext, live: &LiveScene) {
        if p.version != live.version() {
            p.place(self, gpu, live.scene(), live.gpu(gpu));
            p.version = live.version();
        }
    }
}

impl Prepared {
    /// Writes where every map's faces look from (the reflectors' current centres).
    fn place(
        &mut self,
        maps: &DistanceMaps,
        ctx: &GpuContext,
        scene: &Scene,
        gpu_scene: &GpuScene,
    ) {
        let (views, reflectors) = maps.layer_views(scene, gpu_scene, &self.reflectors);
        for (draw, (view, ranges)) in self.draws.iter_mut().zip(views) {
            ctx.queue
                .write_buffer(&draw.view_buffer, 0, bytemuck::bytes_of(&view));
            draw.vertex_ranges = ranges;
        }
        if !reflectors.is_empty() {
            ctx.queue
                .write_buffer(&self.reflector_buffer, 0, bytemuck::cast_slice(&reflectors));
        }
    }

    /// Draws every face of every layer of every map.
    pub(super) fn draw_maps(&self, ctx: &GpuContext, gpu_scene: &GpuScene, raster: &RasterPass) {
        let device = &ctx.device;
        let mut encoder = device.create_command_encoder(&Default::default());
        for draw in &self.draws {
            let attachment = |view| {
                Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color {
                            r: 0.0,
                            g: 0.0,
                            b: 0.0,
                            a: -1.0,
                        }),
                        store: wgpu::StoreOp::Store,
                    },
                })
            };
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("distance-map layer"),
                color_attachments: &[
                    attachment(&draw.material_target),
                    attachment(&draw.geometry_target),
                ],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &self.depth,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Discard,
                    }),
                    stencil_ops: None,
                }),
                ..Default::default()
            });
            pass.set_pipeline(&self.layer_pipeline);
            pass.set_bind_group(0, &draw.bind_group, &[]);
            pass.set_bind_group(1, &self.scene_bind_group, &[]);
            pass.set_bind_group(2, raster.shadow_bind_group(), &[]);
            pass.set_vertex_buffer(0, gpu_scene.vertices.slice(..));
            for range in &draw.vertex_ranges {
                pass.draw(range.clone(), 0..1);
            }
        }
        ctx.queue.submit([encoder.finish()]);
    }

    /// Min-max acceleration: each layer's smallest and largest distance.
    pub(super) fn reduce_ranges(&self, ctx: &GpuContext) {
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        let cleared: Vec<u32> = (0..self.map_count)
            .flat_map(|_| [f32::MAX.to_bits(), 0])
            .collect();
        ctx.queue
            .write_buffer(&self.ranges, 0, bytemuck::cast_slice(&cleared));
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.range_pipeline);
            pass.set_bind_group(0, &self.range_bind_group, &[]);
            let groups = self.material_maps.width().div_ceil(8);
            pass.dispatch_workgroups(groups, groups, self.map_count);
        }
        ctx.queue.submit([encoder.finish()]);
    }
}
