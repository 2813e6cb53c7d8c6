//! `envmap`: classic dynamic environment mapping, the baseline the papers argue against.
//!
//! Paper: none (the standard technique; Umenhoffer et al., `001_7674acf89cfed11c.txt`, and
//! Kakimoto et al., `000_00fe11db0f879bd7.txt`, both compare against it).
//!
//! Steps, per frame:
//! 1. the scene raster pass (G-buffer) for the camera;
//! 2. for each specular mesh (a "reflector"), a cube map of the scene rendered from the centre
//!    of its bounding box, with the reflector itself left out;
//! 3. a full-screen pass that shades each specular pixel: mirrors look up the reflected
//!    direction (Schlick Fresnel or F0); dielectrics mix the reflected lookup with the
//!    transmitted one by exact Fresnel, per colour channel (so dispersion shows); thin sheets
//!    look straight through.
//!
//! Approximations and artifacts: every lookup pretends the environment is infinitely far, so
//! nearby objects appear in the wrong place and at the wrong size (exact only for a distant
//! environment, or at the centre of the cube map); other specular objects appear black in a
//! reflector's cube map (no inter-reflection); the two-interface variants leave the refractor
//! through a bounding sphere or a parallel face instead of its real back surface, and ignore
//! internal reflection.
//!
//! Parameters:
//! - `resolution` (default 256): texels per cube-map face side. Higher sharpens reflections;
//!   cost is 6 × resolution² rasterised texels per reflector per frame.
//! - `exit` (default `slab`): the naive second interface of solid refractors. `none` looks the
//!   environment up right after the first refraction (single interface); `sphere` refracts
//!   again where the ray leaves the bounding sphere (exact for a sphere); `slab` refracts again
//!   at a face parallel to the entry face (exact for thin shells with parallel faces). The
//!   default is the one with the lowest RMSE on the built-in refraction scenes (glass-dragon
//!   0.092 vs 0.097 none / 0.102 sphere; spectacle-lens 0.176 vs 0.191 / 0.205, at 320×240);
//!   costs are equal.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use specula_gpu::shaders::{self, CameraUniform};
use specula_gpu::util::{
    buffer_binding, layout_entry, render_pipeline, texture_binding, PipelineSpec,
};
use specula_gpu::{GpuContext, GpuError, StageTimer};
use specula_scene::{Camera, Scene};
use wgpu::util::DeviceExt;

use crate::gpu_scene::GpuScene;
use crate::raster::{self, RasterPass};
use crate::technique::{Frame, Setting, Technique, TechniqueError};

const SHADER: &str = include_str!("envmap.wgsl");

pub fn shader_source() -> String {
    shaders::compose(
        &["optics.wgsl", "camera.wgsl", "scene.wgsl", "cubemap.wgsl"],
        SHADER,
    )
}

/// Host mirror of WGSL `Reflector`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuReflector {
    pub center: [f32; 3],
    pub radius: f32,
    pub first_layer: u32,
    pub exit_model: u32,
    pub pad: [u32; 2],
}

struct Prepared {
    gpu_scene: GpuScene,
    raster: RasterPass,
    /// (mesh index, centre, radius) of each reflector.
    reflectors: Vec<(usize, Vec3, f32)>,
    env_faces: wgpu::Texture,
    env_views: wgpu::Buffer,
    reflector_buffer: wgpu::Buffer,
    mesh_reflector: wgpu::Buffer,
    face_cameras: Vec<CameraUniform>,
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    scene_bind_group: wgpu::BindGroup,
}

/// Where a ray that refracted into a solid leaves it (`envmap`'s second interface).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Exit {
    /// No second interface: the environment is looked up along the first refracted ray.
    None = 0,
    /// Through the refractor's bounding sphere, refracting at the sphere's normal.
    Sphere = 1,
    /// Through a face parallel to the entry face (a thin slab), refracting at its normal.
    Slab = 2,
}

pub struct EnvMap {
    pub resolution: u32,
    pub exit: Exit,
    pub shadow_resolution: u32,
    prepared: Option<Prepared>,
}

impl EnvMap {
    pub fn new(resolution: u32, exit: Exit) -> Self {
        EnvMap {
            resolution,
            exit,
            ..Default::default()
        }
    }
}

impl Default for EnvMap {
    fn default() -> Self {
        EnvMap {
            resolution: 256,
            exit: Exit::Slab,
            shadow_resolution: 1024,
            prepared: None,
        }
    }
}

impl EnvMap {
    fn build(&self, ctx: &GpuContext, scene: &Scene) -> Result<Prepared, GpuError> {
        let device = &ctx.device;
        let gpu_scene = GpuScene::upload(device, scene);
        let raster = RasterPass::new(ctx, &gpu_scene, self.shadow_resolution)?;
        ctx.validated("envmap set-up", || {
            let reflectors: Vec<(usize, Vec3, f32)> = scene
                .meshes
                .iter()
                .enumerate()
                .filter(|(_, m)| scene.materials[m.material].is_specular())
                .map(|(i, m)| {
                    // The tightest sphere around the box centre: farthest vertex, not the
                    // box's half-diagonal.
                    let center = m.bounds().center();
                    let radius = m
                        .positions
                        .iter()
                        .map(|p| (*p - center).length())
                        .fold(0.0, f32::max);
                    (i, center, radius)
                })
                .collect();
            let bounds = scene.bounds();
            let mut face_cameras = Vec::new();
            let mut views: Vec<[[f32; 4]; 4]> = Vec::new();
            let mut gpu_reflectors = Vec::new();
            for (k, &(_, center, radius)) in reflectors.iter().enumerate() {
                let (near, far) = raster::depth_range(&bounds, center);
                for view in raster::cube_views(center, near, far, self.resolution) {
                    let forward = Vec3::from_array(view.direction);
                    let up = match view.direction {
                        d if d[1].abs() > 0.5 => Vec3::Z * d[1].signum(),
                        _ => -Vec3::Y,
                    };
                    let camera = CameraUniform::new(
                        center,
                        forward.cross(up),
                        up,
                        forward,
                        90.0,
                        self.resolution,
                        self.resolution,
                        near,
                        far,
                    );
                    views.push(camera.clip_from_world);
                    face_cameras.push(camera);
                }
                gpu_reflectors.push(GpuReflector {
                    center: center.to_array(),
                    radius,
                    first_layer: 6 * k as u32,
                    exit_model: self.exit as u32,
                    pad: [0; 2],
                });
            }
            let mut mesh_reflector = vec![-1i32; scene.meshes.len().max(1)];
            for (k, &(mesh, ..)) in reflectors.iter().enumerate() {
                mesh_reflector[mesh] = k as i32;
            }
            let layers = (6 * reflectors.len() as u32).max(1);
            let env_faces = device.create_texture(&wgpu::TextureDescriptor {
                label: Some("environment faces"),
                size: wgpu::Extent3d {
                    width: self.resolution,
                    height: self.resolution,
                    depth_or_array_layers: layers,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: raster::COLOR_FORMAT,
                usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
                view_formats: &[],
            });
            let storage = |label, contents: &[u8]| {
                device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some(label),
                    contents,
                    usage: wgpu::BufferUsages::STORAGE,
                })
            };
            if views.is_empty() {
                views.push([[0.0; 4]; 4]);
                gpu_reflectors.push(GpuReflector::zeroed());
            }
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("envmap.wgsl"),
                source: wgpu::ShaderSource::Wgsl(shader_source().into()),
            });
            use wgpu::{
                BufferBindingType as B, ShaderStages as St, TextureSampleType as S,
                TextureViewDimension as D,
            };
            let float = S::Float { filterable: false };
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("envmap"),
                entries: &[
                    layout_entry(0, St::FRAGMENT, buffer_binding(B::Uniform)),
                    layout_entry(1, St::FRAGMENT, texture_binding(float, D::D2)),
                    layout_entry(2, St::FRAGMENT, texture_binding(float, D::D2)),
                    layout_entry(3, St::FRAGMENT, texture_binding(float, D::D2)),
                    layout_entry(4, St::FRAGMENT, texture_binding(S::Uint, D::D2)),
                    layout_entry(5, St::FRAGMENT, texture_binding(float, D::D2Array)),
                    layout_entry(
                        6,
                        St::FRAGMENT,
                        buffer_binding(B::Storage { read_only: true }),
                    ),
                    layout_entry(
                        7,
                        St::FRAGMENT,
                        buffer_binding(B::Storage { read_only: true }),
                    ),
                    layout_entry(
                        8,
                        St::FRAGMENT,
                        buffer_binding(B::Storage { read_only: true }),
                    ),
                ],
            });
            let scene_layout = GpuScene::bind_group_layout(device);
            let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some("envmap"),
                bind_group_layouts: &[Some(&layout), Some(&scene_layout)],
                ..Default::default()
            });
            let pipeline = render_pipeline(
                device,
                &PipelineSpec {
                    label: "envmap shade",
                    layout: &pipeline_layout,
                    module: &module,
                    vertex_entry: "vs_fullscreen",
                    fragment_entry: "fs_shade",
                    vertex_buffers: &[],
                    depth: None,
                    targets: &[raster::COLOR_FORMAT],
                    write_mask: wgpu::ColorWrites::ALL,
                },
            );
            Prepared {
                scene_bind_group: gpu_scene.bind_group(device, &scene_layout),
                env_views: storage("environment views", bytemuck::cast_slice(&views)),
                reflector_buffer: storage("reflectors", bytemuck::cast_slice(&gpu_reflectors)),
                mesh_reflector: storage("mesh reflectors", bytemuck::cast_slice(&mesh_reflector)),
                gpu_scene,
                raster,
                reflectors,
                env_faces,
                face_cameras,
                pipeline,
                layout,
            }
        })
    }
}

impl Technique for EnvMap {
    fn name(&self) -> &'static str {
        "envmap"
    }

    fn parameters(&self) -> Vec<(String, String)> {
        vec![
            ("resolution".into(), self.resolution.to_string()),
            ("exit".into(), format!("{:?}", self.exit).to_lowercase()),
            (
                "shadow_resolution".into(),
                self.shadow_resolution.to_string(),
            ),
        ]
    }

    fn set_parameter(&mut self, name: &str, value: &str) -> Result<(), TechniqueError> {
        let setting = Setting {
            technique: "envmap",
            name,
            value,
        };
        match name {
            "resolution" => self.resolution = setting.texels()?,
            "shadow_resolution" => self.shadow_resolution = setting.texels()?,
            "exit" => {
                self.exit = match value {
                    "none" => Exit::None,
                    "sphere" => Exit::Sphere,
                    "slab" => Exit::Slab,
                    _ => return Err(setting.bad("expected none, sphere or slab")),
                }
            }
            _ => {
                return Err(
                    setting.bad("envmap's parameters are resolution, exit and shadow_resolution")
                )
            }
        }
        self.prepared = None;
        Ok(())
    }

    fn prepare(&mut self, ctx: &GpuContext, scene: &Scene) -> Result<(), TechniqueError> {
        self.prepared = Some(self.build(ctx, scene)?);
        Ok(())
    }

    fn render(
        &mut self,
        ctx: &GpuContext,
        scene: &Scene,
        camera: &Camera,
        width: u32,
        height: u32,
    ) -> Result<Frame, TechniqueError> {
        let p = self.prepared.as_ref().ok_or(TechniqueError::NotPrepared {
            technique: "envmap",
        })?;
        let device = &ctx.device;
        let mut clock = StageTimer::start(ctx);
        let camera_uniform = raster::camera_uniform(camera, &scene.bounds(), width, height);
        let g = p.raster.render(ctx, &p.gpu_scene, &camera_uniform, None)?;
        clock.lap(ctx, "g-buffer")?;
        for (k, &(mesh, ..)) in p.reflectors.iter().enumerate() {
            for face in 0..6 {
                let layer = 6 * k + face;
                let face_g =
                    p.raster
                        .render(ctx, &p.gpu_scene, &p.face_cameras[layer], Some(mesh))?;
                let mut encoder = device.create_command_encoder(&Default::default());
                encoder.copy_texture_to_texture(
                    face_g.color.as_image_copy(),
                    wgpu::TexelCopyTextureInfo {
                        texture: &p.env_faces,
                        mip_level: 0,
                        origin: wgpu::Origin3d {
                            x: 0,
                            y: 0,
                            z: layer as u32,
                        },
                        aspect: wgpu::TextureAspect::All,
                    },
                    wgpu::Extent3d {
                        width: self.resolution,
                        height: self.resolution,
                        depth_or_array_layers: 1,
                    },
                );
                ctx.queue.submit([encoder.finish()]);
            }
        }
        clock.lap(ctx, "environment cube maps")?;
        let output = ctx.validated("envmap shade", || {
            let camera_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("camera"),
                contents: bytemuck::bytes_of(&camera_uniform),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            let view = |t: &wgpu::Texture| t.create_view(&Default::default());
            let faces_view = p.env_faces.create_view(&wgpu::TextureViewDescriptor {
                dimension: Some(wgpu::TextureViewDimension::D2Array),
                ..Default::default()
            });
            let (color, position, normal, ids) = (
                view(&g.color),
                view(&g.position),
                view(&g.normal),
                view(&g.ids),
            );
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("envmap"),
                layout: &p.layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: camera_buffer.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::TextureView(&color),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: wgpu::BindingResource::TextureView(&position),
                    },
                    wgpu::BindGroupEntry {
                        binding: 3,
                        resource: wgpu::BindingResource::TextureView(&normal),
                    },
                    wgpu::BindGroupEntry {
                        binding: 4,
                        resource: wgpu::BindingResource::TextureView(&ids),
                    },
                    wgpu::BindGroupEntry {
                        binding: 5,
                        resource: wgpu::BindingResource::TextureView(&faces_view),
                    },
                    wgpu::BindGroupEntry {
                        binding: 6,
                        resource: p.env_views.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 7,
                        resource: p.reflector_buffer.as_entire_binding(),
                    },
                    wgpu::BindGroupEntry {
                        binding: 8,
                        resource: p.mesh_reflector.as_entire_binding(),
                    },
                ],
            });
            raster::fullscreen_pass(
                ctx,
                "envmap shade",
                &p.pipeline,
                &[&bind_group, &p.scene_bind_group],
                width,
                height,
            )
        })?;
        clock.lap(ctx, "shading")?;
        let image = raster::read_rgba32f(ctx, &output)?;
        clock.lap(ctx, "readback")?;
        let faces = 6 * p.reflectors.len() as u64;
        let (stages, timing) = clock.finish(ctx)?;
        Ok(Frame {
            image,
            stages,
            counters: vec![
                ("reflectors".into(), p.reflectors.len() as u64),
                ("cube map faces rendered".into(), faces),
                (
                    "cube map texels".into(),
                    faces * (self.resolution as u64).pow(2),
                ),
                ("raster passes".into(), 1 + faces),
            ],
            timing,
            warnings: Vec::new(),
        })
    }
}
