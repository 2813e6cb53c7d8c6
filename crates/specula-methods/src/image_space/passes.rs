//! image-space's GPU side: what it sets up per scene (the back-face and nearby-geometry raster
//! passes, the refraction pipeline and its bindings), and each frame's passes before and of the
//! final refraction pass.

use specula_gpu::counters::Counters;
use specula_gpu::shaders::CameraUniform;
use specula_gpu::util::{
    bind_group, buffer_binding, layout_entry, texture_binding, writable_buffer,
};
use specula_gpu::GpuContext;

use specula_core::cube_maps::CubeMaps;
use specula_core::gpu_scene::GpuScene;
use specula_core::lifecycle::GpuFrame;
use specula_core::live_scene::LiveScene;
use specula_core::raster::{self, MeshSelection, RasterPass, RasterSpec, Targets};
use specula_core::TechniqueError;

use super::geometry::{fit_planes, is_solid_refractor, triangle_normal_distances, GpuPlane};
use super::{peel, shader_source, GpuSettings, ImageSpace, COUNTERS, MAX_PLANES};

/// What a final-pass bind group was made for: the pool slots of the scene, back-face and NG
/// G-buffers, the cube-map faces' texture, and the peeled layers' (0: the placeholder).
type BindingKey = (usize, usize, usize, Option<u64>, u64);

/// What depends on the scene.
pub struct Prepared {
    pub(super) back_faces: RasterPass,
    pub(super) nearby: RasterPass,
    pub(super) maps: CubeMaps,
    planes: wgpu::Buffer,
    pub(super) plane_count: u32,
    /// The scene version the planes were fitted at.
    planes_at: Option<u64>,
    normal_distances: wgpu::Buffer,
    mesh_first_vertex: wgpu::Buffer,
    camera_buffer: wgpu::Buffer,
    settings_buffer: wgpu::Buffer,
    pub(super) counters: Counters,
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    scene_bind_group: wgpu::BindGroup,
    bind_groups: Vec<(BindingKey, wgpu::BindGroup)>,
    peel: peel::Peel,
    /// Bound in place of the peeled layers when there are none (layers = 1).
    no_layers: wgpu::TextureView,
    /// Vertex ranges of the solid refractors (what is peeled).
    solid_ranges: Vec<std::ops::Range<u32>>,
    /// The largest solid refractor's bounding-sphere diameter.
    refractor_extent: f32,
}

impl ImageSpace {
    pub(super) fn build(
        &self,
        ctx: &GpuContext,
        live: &LiveScene,
    ) -> Result<Prepared, TechniqueError> {
        let device = &ctx.device;
        let scene = live.scene();
        let gpu_scene = live.gpu(ctx);
        let (back_faces, nearby) = self.nearby_passes(ctx, live)?;
        let distances = triangle_normal_distances(scene, live.accel());
        Ok(ctx.validated("image-space set-up", || {
            let storage = |label, bytes: &[u8]| {
                let buffer = writable_buffer(
                    ctx,
                    label,
                    // At least one element of the largest struct read (a plane, 32 bytes): an empty
                    // scene list still binds.
                    bytes.len().max(64) as u64,
                    wgpu::BufferUsages::STORAGE,
                );
                ctx.queue.write_buffer(&buffer, 0, bytes);
                buffer
            };
            let first_vertex: Vec<u32> = gpu_scene
                .mesh_vertex_ranges
                .iter()
                .map(|r| r.start)
                .collect();
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("image_space.wgsl"),
                source: wgpu::ShaderSource::Wgsl(shader_source().into()),
            });
            let entries = refraction_layout_entries();
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("image-space"),
                entries: &entries,
            });
            let scene_layout = GpuScene::bind_group_layout(device);
            let pipeline = raster::shading_pipeline(
                device,
                "image-space refraction",
                &module,
                &layout,
                &scene_layout,
            );
            let uniform = |label, size: usize| {
                writable_buffer(ctx, label, size as u64, wgpu::BufferUsages::UNIFORM)
            };
            Prepared {
                back_faces,
                nearby,
                maps: CubeMaps::new(ctx, scene),
                // Fitted in render, at each scene version: the nearby objects move.
                plane_count: 0,
                planes_at: None,
                planes: writable_buffer(
                    ctx,
                    "ray-plane planes",
                    (MAX_PLANES * size_of::<GpuPlane>()) as u64,
                    wgpu::BufferUsages::STORAGE,
                ),
                normal_distances: storage("d_N", bytemuck::cast_slice(&distances)),
                mesh_first_vertex: storage(
                    "mesh first vertex",
                    bytemuck::cast_slice(&first_vertex),
                ),
                camera_buffer: uniform("camera", size_of::<CameraUniform>()),
                settings_buffer: uniform("image-space settings", size_of::<GpuSettings>()),
                counters: Counters::new(ctx, "image-space counters", COUNTERS.len()),
                pipeline,
                layout,
                scene_bind_group: gpu_scene.bind_group(ctx, &scene_layout),
                bind_groups: Vec::new(),
                peel: peel::Peel::new(ctx, gpu_scene),
                no_layers: specula_gpu::util::texture_2d(
                    ctx,
                    "no peeled layers",
                    1,
                    1,
                    wgpu::TextureFormat::Rgba32Float,
                    wgpu::TextureUsages::TEXTURE_BINDING,
                )
                .create_view(&wgpu::TextureViewDescriptor {
                    dimension: Some(wgpu::TextureViewDimension::D2Array),
                    ..Default::default()
                }),
                solid_ranges: gpu_scene.vertex_ranges(|mesh| {
                    is_solid_refractor(&scene.materials[scene.meshes[mesh].material].kind)
                }),
                refractor_extent: scene
                    .meshes
                    .iter()
                    .filter(|m| is_solid_refractor(&scene.materials[m.material].kind))
                    .map(|m| 2.0 * m.bounds().radius())
                    .fold(0.0, f32::max),
            }
        })?)
    }

    /// The back faces of the solid refractors and the nearby (non-specular) geometry, each a
    /// raster pass of its own.
    fn nearby_passes(
        &self,
        ctx: &GpuContext,
        live: &LiveScene,
    ) -> Result<(RasterPass, RasterPass), TechniqueError> {
        let back_faces = RasterPass::new(
            ctx,
            live,
            RasterSpec {
                meshes: MeshSelection::Specular,
                targets: Targets::Geometry,
                cull_mode: Some(wgpu::Face::Front),
                background: false,
                shadow_resolution: self.params.shadow_resolution,
            },
        )?;
        let nearby = RasterPass::new(
            ctx,
            live,
            RasterSpec {
                meshes: MeshSelection::NonSpecular,
                targets: Targets::Shaded,
                cull_mode: None,
                background: false,
                shadow_resolution: self.params.shadow_resolution,
            },
        )?;
        Ok((back_faces, nearby))
    }
}

/// The refraction pass's bindings: the camera, three G-buffers (the scene's, the back faces',
/// the nearby geometry's), d_N, the meshes' first vertices, the settings, the planes, the
/// counters, the cube maps and the peeled layers.
fn refraction_layout_entries() -> Vec<wgpu::BindGroupLayoutEntry> {
    use wgpu::{
        BufferBindingType as B, ShaderStages as St, TextureSampleType as S,
        TextureViewDimension as D,
    };
    let float = S::Float { filterable: false };
    let read_only = || buffer_binding(B::Storage { read_only: true });
    let mut entries = vec![layout_entry(0, St::FRAGMENT, buffer_binding(B::Uniform))];
    // Three G-buffers: the scene's, the back faces', the nearby geometry's.
    let mut binding = 1;
    for targets in [4, 3, 3] {
        for target in 0..targets {
            let kind = if target == targets - 1 {
                S::Uint
            } else {
                float
            };
            entries.push(layout_entry(
                binding,
                St::FRAGMENT,
                texture_binding(kind, D::D2),
            ));
            binding += 1;
        }
    }
    entries.extend([
        layout_entry(11, St::FRAGMENT, read_only()),
        layout_entry(12, St::FRAGMENT, read_only()),
        layout_entry(13, St::FRAGMENT, read_only()),
        layout_entry(14, St::FRAGMENT, buffer_binding(B::Uniform)),
        layout_entry(15, St::FRAGMENT, read_only()),
        layout_entry(
            16,
            St::FRAGMENT,
            buffer_binding(B::Storage { read_only: false }),
        ),
    ]);
    entries.extend(CubeMaps::layout_entries(17));
    entries.extend([
        layout_entry(21, St::FRAGMENT, texture_binding(float, D::D2Array)),
        layout_entry(22, St::FRAGMENT, texture_binding(float, D::D2Array)),
    ]);
    entries
}

/// The back faces and the nearby geometry, drawn from the eye at the texture scale.
pub(super) struct NearbyTextures {
    pub(super) camera: CameraUniform,
    back: raster::GBuffer,
    nearby: raster::GBuffer,
}

/// The planes of the ray-plane mode, fitted again after a move.
pub(super) fn fit_planes_after_moves(p: &mut Prepared, gpu: &GpuContext, live: &LiveScene) {
    if p.planes_at != Some(live.version()) {
        let planes = fit_planes(live.scene());
        gpu.queue
            .write_buffer(&p.planes, 0, bytemuck::cast_slice(&planes));
        p.plane_count = planes.len() as u32;
        p.planes_at = Some(live.version());
    }
}

impl ImageSpace {
    /// The refractors' back faces and the nearby geometry, from the eye.
    pub(super) fn nearby_textures(
        &self,
        p: &Prepared,
        frame: &mut GpuFrame<'_>,
    ) -> Result<NearbyTextures, TechniqueError> {
        let (gpu, gpu_scene) = (frame.gpu, frame.live.gpu(frame.gpu));
        let scale = self.params.texture_scale;
        let texture_width = ((frame.width as f32 * scale).round() as u32).max(1);
        let texture_height = ((frame.height as f32 * scale).round() as u32).max(1);
        let bounds = frame.live.scene().bounds();
        let camera = raster::camera_uniform(frame.camera, &bounds, texture_width, texture_height);
        let back = p.back_faces.render(gpu, gpu_scene, &camera, None)?;
        frame.lap("back faces")?;
        let nearby = p.nearby.render(gpu, gpu_scene, &camera, None)?;
        frame.lap("nearby geometry")?;
        Ok(NearbyTextures {
            camera,
            back,
            nearby,
        })
    }

    /// More interfaces: the solid refractors depth-peeled into layers. Returns the layers.
    pub(super) fn peel(
        &self,
        p: &mut Prepared,
        frame: &mut GpuFrame<'_>,
        texture_camera: &CameraUniform,
    ) -> Result<u32, TechniqueError> {
        let peeled = if self.params.layers > 1 {
            2 * self.params.layers
        } else {
            0
        };
        if peeled > 0 {
            let (gpu, gpu_scene) = (frame.gpu, frame.live.gpu(frame.gpu));
            gpu.validated("image-space peel", || {
                p.peel
                    .draw(gpu, gpu_scene, &p.solid_ranges, texture_camera, peeled)
            })?;
            frame.lap("peeled layers")?;
        }
        Ok(peeled)
    }

    /// The refraction pass's settings for this frame.
    fn settings(&self, p: &Prepared, frame: &GpuFrame<'_>, peeled: u32) -> GpuSettings {
        let params = &self.params;
        let bounds = frame.live.scene().bounds();
        GpuSettings {
            mode: params.mode as u32,
            seeds: params.seeds,
            iterations: params.iterations,
            plane_count: p.plane_count,
            index_override: params.index,
            depth_tolerance: params.depth_tolerance,
            inside_steps: params.inside_steps,
            exit_iterations: params.exit_iterations,
            scene_center: bounds.center().to_array(),
            scene_radius: bounds.radius(),
            scene_min: bounds.min.to_array(),
            parallax: params.parallax as u32,
            scene_max: bounds.max.to_array(),
            layers: params.layers,
            peeled,
            refractor_extent: p.refractor_extent,
            far_depth: raster::depth_range(&bounds, frame.camera.eye).1,
            bracket: params.bracket as u32,
            discs: params.discs as u32,
            internal_reflection: params.internal_reflection as u32,
            reflection: params.reflection as u32,
            fallback: params.fallback as u32,
            dispersion: params.dispersion as u32,
            pad: [0; 3],
        }
    }

    /// Each refractor pixel refracted through both interfaces, into `frame.output`.
    pub(super) fn refract(
        &self,
        p: &mut Prepared,
        frame: &GpuFrame<'_>,
        textures: &NearbyTextures,
        peeled: u32,
    ) -> Result<(), TechniqueError> {
        let settings = self.settings(p, frame, peeled);
        let (gpu, g) = (frame.gpu, frame.g());
        let gpu_scene = frame.live.gpu(gpu);
        let (back, nearby) = (&textures.back, &textures.nearby);
        p.counters.clear(gpu);
        Ok(gpu.validated("image-space refraction", || {
            gpu.queue.write_buffer(
                &p.camera_buffer,
                0,
                bytemuck::bytes_of(&frame.camera_uniform),
            );
            gpu.queue
                .write_buffer(&p.settings_buffer, 0, bytemuck::bytes_of(&settings));
            let layer_views = match p.peel.views() {
                Some(views) if peeled > 0 => views,
                _ => (&p.no_layers, &p.no_layers, 0),
            };
            let key = (
                g.slot,
                back.slot,
                nearby.slot,
                p.maps.faces_generation(),
                layer_views.2,
            );
            if !p.bind_groups.iter().any(|(k, _)| *k == key) {
                if p.bind_groups.len() >= 8 {
                    p.bind_groups.clear();
                }
                let [color, position, normal, ids] = g.views();
                let [_, back_position, back_normal, back_ids] = back.views();
                let [ng_color, ng_position, _, ng_ids] = nearby.views();
                let view = wgpu::BindingResource::TextureView;
                let mut resources = vec![
                    p.camera_buffer.as_entire_binding(),
                    view(&color),
                    view(&position),
                    view(&normal),
                    view(&ids),
                    view(&back_position),
                    view(&back_normal),
                    view(&back_ids),
                    view(&ng_color),
                    view(&ng_position),
                    view(&ng_ids),
                    gpu_scene.vertices.as_entire_binding(),
                    p.normal_distances.as_entire_binding(),
                    p.mesh_first_vertex.as_entire_binding(),
                    p.settings_buffer.as_entire_binding(),
                    p.planes.as_entire_binding(),
                    p.counters.buffer.as_entire_binding(),
                ];
                resources.extend(p.maps.bindings());
                resources.push(view(layer_views.0));
                resources.push(view(layer_views.1));
                let group = bind_group(gpu, "image-space", &p.layout, &resources);
                p.bind_groups.push((key, group));
            }
            let group = &p
                .bind_groups
                .iter()
                .find(|(k, _)| *k == key)
                .expect("made above")
                .1;
            raster::fullscreen_pass(
                gpu,
                "image-space refraction",
                &p.pipeline,
                &[group, &p.scene_bind_group],
                frame.output(),
            )
        })?)
    }
}
