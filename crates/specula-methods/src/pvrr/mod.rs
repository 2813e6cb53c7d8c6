//! `pvrr`: per-vertex reflection (§3 and concave mirrors of §4.2; refraction and the rest of
//! §4 are not here yet).
//!
//! Paper: Kakimoto, Tatsukawa, Chun, Nishita, *Real-time reflection and refraction on a
//! per-vertex basis* (`../shared/seeds/000_00fe11db0f879bd7.txt`).
//!
//! Steps, per frame and per mirror mesh:
//! 1. for every vertex V, the ray from the eye is reflected about V's normal and traced through
//!    the scene's BVH (in parallel) to its nearest hit P (or a point far along it);
//! 2. the virtual viewpoint is the point nearest, in the least-squares sense, to all reflection
//!    lines: (Σ (I − r rᵀ)) c = Σ (I − r rᵀ) V;
//! 3. the view volume looks along the mean reflection direction, its near plane just in front
//!    of the mirror, its far plane past every P, its sides containing every V and P;
//! 4. 1st pass: the scene, without the mirror, is rasterised from the virtual viewpoint into a
//!    reflection map;
//! 5. each vertex's texture coordinate is the projection of its P into that map;
//! 6. 2nd pass: the mirror is drawn over the scene raster with those coordinates (Schlick
//!    Fresnel or F0), so every vertex shows exactly its ray-traced point P.
//!
//! Approximations and artifacts: between vertices the reflection is the 1st-pass image warped
//! linearly, so error grows with triangle size and curvature (it falls as the mesh is refined);
//! objects hidden from the virtual viewpoint but visible along some reflection ray (or the
//! reverse) show the wrong surface (the paper's occlusion inconsistency, §6).
//!
//! Concave mirrors (§4.2) go through the same construction: their reflection lines converge in
//! front of the mirror, the least-squares viewpoint lands near the convergence point with the
//! mirror behind it (the near plane then sits at 1/1000 of the far distance), and the map comes
//! out reversed, as in the paper's Figure 8. Not handled: the "zooming region" — objects between
//! the mirror and the convergence point lie behind the viewpoint and are missing from the map.
//!
//! When all reflection lines are (nearly) parallel no least-squares viewpoint exists: the view
//! then looks along their mean direction from 10 mirror radii behind the mirror, and the frame
//! carries a warning saying so.
//!
//! Not yet (issue 4): subdivision of large reflectors, the principal-curvature up vector,
//! multiple reflection, lens refraction and chromatic aberration. Dielectric surfaces are left
//! as the scene raster leaves them (black).
//!
//! Parameters:
//! - `resolution` (default 512): reflection-map height in texels (the width follows the view
//!   volume's aspect ratio). Higher sharpens the reflection between vertices; costs one
//!   rasterisation of that size per mirror per frame.
//! - `shadow_resolution` (default 1024): shadow maps of the scene raster (see `raster`).
//! - `markers` (default false): the paper's verification overlay (Figures 1 and 14): a small
//!   red ball at every vertex's exact hit point P, drawn in both passes, so each ball should sit
//!   on its vertex in the picture. Costs one small sphere per mirror vertex per pass.

use bytemuck::{Pod, Zeroable};
use glam::{Mat3, Vec3, Vec4};
use rayon::prelude::*;
use specula_gpu::shaders::{self, CameraUniform};
use specula_gpu::util::{render_pipeline, PipelineSpec};
use specula_gpu::{GpuContext, GpuError, StageTimer};
use specula_scene::{Camera, MaterialKind, Scene};
use specula_trace::reference::offset_origin;
use specula_trace::{optics, Ray, SceneAccel};
use wgpu::util::DeviceExt;

use crate::gpu_scene::GpuScene;
use crate::raster::{self, RasterPass};
use crate::technique::{Frame, Setting, Technique, TechniqueError};

const SHADER: &str = include_str!("pvrr.wgsl");

pub fn shader_source() -> String {
    shaders::compose(&["optics.wgsl", "camera.wgsl"], SHADER)
}

/// Host mirror of WGSL `MirrorMaterial`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuMirrorMaterial {
    pub f0: [f32; 3],
    pub fresnel: u32,
}

/// One corner of a mirror triangle for the 2nd pass.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct MirrorVertex {
    position: [f32; 3],
    normal: [f32; 3],
    uv: [f32; 2],
}

/// Where the 1st pass looks from, and each vertex's hit point P.
#[derive(Clone, Debug)]
pub struct VirtualView {
    pub camera: CameraUniform,
    /// Per mesh vertex: the reflection ray's hit point (or a far point along it).
    pub hits: Vec<Vec3>,
    /// Per mesh vertex: whether the reflection ray hit the scene.
    pub hit_scene: Vec<bool>,
    /// Set when the construction degenerated and a fallback was used (says which).
    pub fallback: Option<String>,
}

/// Steps 1–3 for one mirror mesh seen from `eye`: hit points, virtual viewpoint, view volume.
pub fn virtual_view(
    scene: &Scene,
    accel: &SceneAccel,
    mesh: usize,
    eye: Vec3,
    resolution: u32,
) -> VirtualView {
    let m = &scene.meshes[mesh];
    let bounds = scene.bounds();
    let far_distance = (bounds.radius() * 4.0).max(1.0);
    let traced: Vec<(Vec3, Vec3, bool)> = m
        .positions
        .par_iter()
        .zip(&m.normals)
        .map(|(&v, &n)| {
            let d = (v - eye).normalize();
            let n = if d.dot(n) > 0.0 { -n } else { n };
            let r = optics::reflect(d, n);
            let ray = Ray {
                origin: offset_origin(v, n, r),
                dir: r,
            };
            match accel.intersect(&ray, f32::INFINITY) {
                Some(hit) => (r, ray.origin + r * hit.t, true),
                None => (r, v + r * far_distance, false),
            }
        })
        .collect();
    // Least-squares point nearest to all reflection lines.
    let (mut a, mut b) = (Mat3::ZERO, Vec3::ZERO);
    for (&v, &(r, _, _)) in m.positions.iter().zip(&traced) {
        let projector = Mat3::IDENTITY - Mat3::from_cols(r * r.x, r * r.y, r * r.z);
        a += projector;
        b += projector * v;
    }
    let mean_dir = traced
        .iter()
        .map(|t| t.0)
        .sum::<Vec3>()
        .normalize_or(Vec3::Z);
    let center = m.bounds().center();
    let mut fallback = None;
    let solvable = a.determinant().abs() > 1e-6 * (m.positions.len() as f32).powi(3);
    let viewpoint = match solvable.then(|| a.inverse() * b).filter(|c| c.is_finite()) {
        Some(c) => c,
        None => {
            fallback = Some(format!(
                "pvrr: mirror '{}': its {} reflection lines are (nearly) parallel, so no least-squares viewpoint exists; looking along their mean direction from 10 mirror radii behind the mirror instead",
                m.name,
                m.positions.len()
            ));
            center - mean_dir * m.bounds().radius().max(1e-3) * 10.0
        }
    };
    let up_hint = if mean_dir.y.abs() > 0.99 {
        Vec3::Z
    } else {
        Vec3::Y
    };
    let right = mean_dir.cross(up_hint).normalize();
    let up = right.cross(mean_dir);
    let to_view = |p: Vec3| {
        let q = p - viewpoint;
        Vec3::new(q.dot(right), q.dot(up), q.dot(mean_dir))
    };
    let far = traced
        .iter()
        .map(|t| to_view(t.1).z)
        .fold(0.0f32, f32::max)
        .max(1e-3)
        * 1.05;
    let mirror_depth = m
        .positions
        .iter()
        .map(|&v| to_view(v).z)
        .fold(f32::NEG_INFINITY, f32::max);
    let near = if mirror_depth > 0.0 {
        (mirror_depth * 1.0001).min(far * 0.5)
    } else {
        far * 1e-3
    };
    let (mut tan_x, mut tan_y) = (1e-3f32, 1e-3f32);
    for p in m
        .positions
        .iter()
        .copied()
        .chain(traced.iter().map(|t| t.1))
    {
        let q = to_view(p);
        if q.z > 1e-6 {
            tan_x = tan_x.max(q.x.abs() / q.z);
            tan_y = tan_y.max(q.y.abs() / q.z);
        }
    }
    let (tan_x, tan_y) = (tan_x.min(50.0) * 1.02, tan_y.min(50.0) * 1.02);
    let height = resolution.max(1);
    let width =
        ((resolution as f32 * tan_x / tan_y).round() as u32).clamp(1, 4 * resolution.max(1));
    // The aspect CameraUniform derives from the texel size must still cover tan_x.
    let tan_y = tan_y.max(tan_x * height as f32 / width as f32);
    let camera = CameraUniform::new(
        viewpoint,
        right,
        up,
        mean_dir,
        2.0 * tan_y.atan().to_degrees(),
        width,
        height,
        near,
        far,
    );
    VirtualView {
        camera,
        hits: traced.iter().map(|t| t.1).collect(),
        hit_scene: traced.iter().map(|t| t.2).collect(),
        fallback,
    }
}

/// Texture coordinate ((0, 0) = top-left) of `p` in the reflection map of `view`.
pub fn map_uv(view: &CameraUniform, p: Vec3) -> [f32; 2] {
    let clip = glam::Mat4::from_cols_array_2d(&view.clip_from_world) * Vec4::from((p, 1.0));
    let ndc = clip.truncate() / clip.w;
    [ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5]
}

/// Small red balls at every hit point P, sized to a constant angle (1.2 %) as seen from their
/// virtual viewpoint; `marker_mesh` is the extra mesh index whose material is the marker's.
fn marker_vertices(
    device: &wgpu::Device,
    marker_mesh: u32,
    views: &[VirtualView],
) -> (wgpu::Buffer, u32) {
    use crate::gpu_scene::GpuVertex;
    let ball = specula_scene::generators::sphere(1.0, 8, 4);
    let mut vertices = Vec::new();
    for view in views {
        let eye = Vec3::from_array(view.camera.eye_world);
        for &p in &view.hits {
            let radius = (p - eye).length() * 0.012;
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
    }
    let count = vertices.len() as u32;
    if vertices.is_empty() {
        vertices.push(GpuVertex::zeroed());
    }
    let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("pvrr markers"),
        contents: bytemuck::cast_slice(&vertices),
        usage: wgpu::BufferUsages::VERTEX,
    });
    (buffer, count)
}

struct Prepared {
    gpu_scene: GpuScene,
    raster: RasterPass,
    accel: SceneAccel,
    mirrors: Vec<usize>,
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
}

pub struct Pvrr {
    pub resolution: u32,
    pub shadow_resolution: u32,
    pub markers: bool,
    prepared: Option<Prepared>,
}

impl Default for Pvrr {
    fn default() -> Self {
        Pvrr {
            resolution: 512,
            shadow_resolution: 1024,
            markers: false,
            prepared: None,
        }
    }
}

fn entry(binding: u32, ty: wgpu::BindingType) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
        ty,
        count: None,
    }
}

impl Pvrr {
    fn build(&self, ctx: &GpuContext, scene: &Scene) -> Result<Prepared, GpuError> {
        let device = &ctx.device;
        // Markers are drawn as one extra, empty mesh (index `scene.meshes.len()`) whose
        // material is unlit red.
        let mut uploaded = scene.clone();
        if self.markers {
            uploaded
                .materials
                .push(specula_scene::Material::unlit("pvrr marker", Vec3::X));
            uploaded.meshes.push(specula_scene::Mesh {
                material: uploaded.materials.len() - 1,
                ..Default::default()
            });
        }
        let gpu_scene = GpuScene::upload(device, &uploaded);
        let raster = RasterPass::new(ctx, &gpu_scene, self.shadow_resolution)?;
        ctx.validated("pvrr set-up", || {
            let uniform = wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            };
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("pvrr mirror"),
                entries: &[
                    entry(0, uniform),
                    entry(
                        1,
                        wgpu::BindingType::Texture {
                            sample_type: wgpu::TextureSampleType::Float { filterable: false },
                            view_dimension: wgpu::TextureViewDimension::D2,
                            multisampled: false,
                        },
                    ),
                    entry(2, uniform),
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
            const ATTRIBUTES: [wgpu::VertexAttribute; 3] =
                wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x2];
            let pipeline = render_pipeline(
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
                        bias: Default::default(),
                    }),
                    targets: &[raster::COLOR_FORMAT],
                },
            );
            let mirrors = scene
                .meshes
                .iter()
                .enumerate()
                .filter(|(_, m)| {
                    matches!(
                        scene.materials[m.material].kind,
                        MaterialKind::Mirror { .. }
                    )
                })
                .map(|(i, _)| i)
                .collect();
            Prepared {
                gpu_scene,
                raster,
                accel: SceneAccel::new(scene),
                mirrors,
                pipeline,
                layout,
            }
        })
    }
}

impl Technique for Pvrr {
    fn name(&self) -> &'static str {
        "pvrr"
    }

    fn parameters(&self) -> Vec<(String, String)> {
        vec![
            ("resolution".into(), self.resolution.to_string()),
            (
                "shadow_resolution".into(),
                self.shadow_resolution.to_string(),
            ),
        ]
    }

    fn set_parameter(&mut self, name: &str, value: &str) -> Result<(), TechniqueError> {
        let setting = Setting {
            technique: "pvrr",
            name,
            value,
        };
        match name {
            "resolution" => self.resolution = setting.texels()?,
            "shadow_resolution" => self.shadow_resolution = setting.texels()?,
            "markers" => self.markers = setting.flag()?,
            _ => {
                return Err(
                    setting.bad("pvrr's parameters are resolution, shadow_resolution and markers")
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
        let p = self
            .prepared
            .as_ref()
            .ok_or(TechniqueError::NotPrepared { technique: "pvrr" })?;
        let device = &ctx.device;
        let mut timer = StageTimer::start(ctx);
        let camera_uniform = raster::camera_uniform(camera, &scene.bounds(), width, height);
        let views: Vec<VirtualView> = p
            .mirrors
            .iter()
            .map(|&m| virtual_view(scene, &p.accel, m, camera.eye, self.resolution))
            .collect();
        timer.lap(ctx, "per-vertex rays")?;
        let markers = self
            .markers
            .then(|| marker_vertices(device, scene.meshes.len() as u32, &views));
        let extra = markers.as_ref().map(|(buffer, count)| (buffer, *count));
        let g = p
            .raster
            .render_with(ctx, &p.gpu_scene, &camera_uniform, None, extra)?;
        timer.lap(ctx, "g-buffer")?;
        let maps = p
            .mirrors
            .iter()
            .zip(&views)
            .map(|(&m, view)| {
                p.raster
                    .render_with(ctx, &p.gpu_scene, &view.camera, Some(m), extra)
            })
            .collect::<Result<Vec<_>, _>>()?;
        timer.lap(ctx, "reflection maps (1st pass)")?;
        ctx.validated("pvrr 2nd pass", || {
            let camera_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("camera"),
                contents: bytemuck::bytes_of(&camera_uniform),
                usage: wgpu::BufferUsages::UNIFORM,
            });
            let color_view = g.color.create_view(&Default::default());
            let depth_view = g.depth.create_view(&Default::default());
            let mut encoder = device.create_command_encoder(&Default::default());
            let mut resources = Vec::new();
            for ((&m, view), map) in p.mirrors.iter().zip(&views).zip(&maps) {
                let mesh = &scene.meshes[m];
                let material = &scene.materials[mesh.material];
                let vertices: Vec<MirrorVertex> = mesh
                    .triangles
                    .iter()
                    .flatten()
                    .map(|&i| {
                        let i = i as usize;
                        MirrorVertex {
                            position: mesh.positions[i].to_array(),
                            normal: mesh.normals[i].to_array(),
                            uv: map_uv(&view.camera, view.hits[i]),
                        }
                    })
                    .collect();
                let vertex_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                    label: Some("mirror vertices"),
                    contents: bytemuck::cast_slice(&vertices),
                    usage: wgpu::BufferUsages::VERTEX,
                });
                let fresnel = matches!(material.kind, MaterialKind::Mirror { fresnel: true });
                let material_buffer =
                    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                        label: Some("mirror material"),
                        contents: bytemuck::bytes_of(&GpuMirrorMaterial {
                            f0: material.color.to_array(),
                            fresnel: fresnel as u32,
                        }),
                        usage: wgpu::BufferUsages::UNIFORM,
                    });
                let map_view = map.color.create_view(&Default::default());
                let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("pvrr mirror"),
                    layout: &p.layout,
                    entries: &[
                        wgpu::BindGroupEntry {
                            binding: 0,
                            resource: camera_buffer.as_entire_binding(),
                        },
                        wgpu::BindGroupEntry {
                            binding: 1,
                            resource: wgpu::BindingResource::TextureView(&map_view),
                        },
                        wgpu::BindGroupEntry {
                            binding: 2,
                            resource: material_buffer.as_entire_binding(),
                        },
                    ],
                });
                resources.push((vertex_buffer, bind_group, vertices.len() as u32));
            }
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
                pass.set_pipeline(&p.pipeline);
                for (vertex_buffer, bind_group, count) in &resources {
                    pass.set_bind_group(0, bind_group, &[]);
                    pass.set_vertex_buffer(0, vertex_buffer.slice(..));
                    pass.draw(0..*count, 0..1);
                }
            }
            ctx.queue.submit([encoder.finish()]);
        })?;
        timer.lap(ctx, "mirror (2nd pass)")?;
        let image = raster::read_rgba32f(ctx, &g.color)?;
        timer.lap(ctx, "readback")?;
        let (stages, timing) = timer.finish(ctx)?;
        let vertex_rays: u64 = p
            .mirrors
            .iter()
            .map(|&m| scene.meshes[m].positions.len() as u64)
            .sum();
        Ok(Frame {
            image,
            stages,
            counters: vec![
                ("mirrors".into(), p.mirrors.len() as u64),
                ("per-vertex rays".into(), vertex_rays),
                (
                    "reflection map texels".into(),
                    views
                        .iter()
                        .map(|v| (v.camera.width * v.camera.height) as u64)
                        .sum(),
                ),
            ],
            timing,
            warnings: views.iter().filter_map(|v| v.fallback.clone()).collect(),
        })
    }
}
