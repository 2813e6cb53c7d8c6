//! The scene raster pass every technique starts from: it draws the background and all
//! geometry with depth, shades the non-specular surfaces (unlit; Lambert with the scene's
//! lights, distance shadow maps and ambient) and leaves specular ones black, and writes a
//! G-buffer: world position, normal, and mesh + triangle IDs (the ID buffer vertex tracing
//! needs).
//!
//! Approximations against the reference: shadows come from distance shadow maps (six 90° faces
//! per point or spot light, one orthographic map per directional light) instead of shadow rays,
//! so shadow edges are accurate to a shadow-map texel and a normal offset of 1.5 texels plus a
//! bias of 2 texels avoid self-shadowing; everything else is the reference's shading, evaluated
//! at the same pixel centres.
//!
//! What a pass draws comes from its [`RasterSpec`]: which meshes (all, specular only, or
//! non-specular only), which targets (all, shaded; or the geometry only, unlit), which faces
//! are culled, and whether the background is drawn, so that a
//! technique needing, say, the back faces of its refractors uses this pass, not a copy of it.
//!
//! Nothing is created per frame: G-buffers come from a pool kept across frames
//! ([`RasterPass::begin_frame`] hands them all back, and drops those the last frame did not
//! use, so a resized view does not leave its old sizes behind), and the camera uniform is rewritten in
//! place before each draw (every draw is its own submission, and wgpu orders a buffer write
//! before the next submission). Shadow maps are drawn at creation and again, by
//! [`RasterPass::begin_frame`], only when the scene's geometry has changed.
//!
//! Parameters: `shadow_resolution` (default 1024) — texels per side of each shadow map; higher
//! sharpens shadow edges at a cost of resolution² per layer in memory and in the prepare pass.

use std::cell::{Cell, RefCell};

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec3};
use specula_gpu::shaders::{self, CameraUniform};
use specula_gpu::util::{
    buffer_binding, layout_entry, render_pipeline, texture_2d, texture_binding, PipelineSpec,
};
use specula_gpu::{GpuContext, GpuError};
use specula_scene::{Camera, Scene};
use specula_trace::Image;

use crate::gpu_scene::{GpuScene, GpuVertex, LIGHT_DIRECTIONAL};
use crate::live_scene::LiveScene;
use crate::params::{Invalidates, Param, ParamKind, ParamSet};

const SHADER: &str = include_str!("raster.wgsl");

/// The raster shader's full source (common files prepended).
pub fn shader_source() -> String {
    shaders::compose(
        &["camera.wgsl", "scene.wgsl", "cubemap.wgsl", "lighting.wgsl"],
        SHADER,
    )
}

/// The raster pass's parameter, `shadow_resolution` in the list of every technique that draws
/// it.
pub const SHADOW_RESOLUTION: Param = Param {
    kind: ParamKind::Integer { min: 1, max: 8192 },
    default: "1024",
    doc: "texels per side of the scene raster's shadow maps",
    invalidates: Invalidates::Scene,
};

/// The value of `params`' `shadow_resolution` ([`SHADOW_RESOLUTION`]): the scene raster pass's
/// shadow maps of a technique that draws it.
///
/// # Panics
/// Where `params` has no such parameter (a technique that draws the raster pass declares it).
pub fn shadow_resolution(params: &dyn ParamSet) -> u32 {
    let value = params
        .get("shadow_resolution")
        .expect("a technique that draws the scene raster declares shadow_resolution");
    value
        .parse()
        .unwrap_or_else(|_| panic!("shadow_resolution is a whole number, not {value}"))
}

pub const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;
pub const IDS_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rg32Uint;
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
const SHADOW_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;
/// Colour, position, normal, IDs.
const G_BUFFER_FORMATS: [wgpu::TextureFormat; 4] =
    [COLOR_FORMAT, COLOR_FORMAT, COLOR_FORMAT, IDS_FORMAT];

/// Host mirror of WGSL `ShadowView`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct ShadowView {
    pub clip_from_world: [[f32; 4]; 4],
    pub origin: [f32; 3],
    pub directional: u32,
    pub direction: [f32; 3],
    pub texel_size: f32,
}

/// Render targets of one frame. `ids` holds (mesh + 1, triangle); 0 marks the background.
/// Textures are shared handles: a `GBuffer` from [`RasterPass`] is a view of a pooled set.
#[derive(Clone)]
pub struct GBuffer {
    pub width: u32,
    pub height: u32,
    pub color: wgpu::Texture,
    pub position: wgpu::Texture,
    pub normal: wgpu::Texture,
    pub ids: wgpu::Texture,
    pub depth: wgpu::Texture,
    /// Its slot in the pool: an id never reused, stable while the G-buffer stays pooled, so a
    /// technique can keep bind groups per slot.
    pub slot: usize,
}

impl GBuffer {
    fn new(ctx: &GpuContext, width: u32, height: u32, slot: usize) -> GBuffer {
        let texture = |label, format, usage| texture_2d(ctx, label, width, height, format, usage);
        let usage = wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC;
        GBuffer {
            width,
            height,
            color: texture(
                "color",
                COLOR_FORMAT,
                usage | wgpu::TextureUsages::STORAGE_BINDING,
            ),
            position: texture("position", COLOR_FORMAT, usage),
            normal: texture("normal", COLOR_FORMAT, usage),
            ids: texture("ids", IDS_FORMAT, usage),
            depth: texture("depth", DEPTH_FORMAT, usage),
            slot,
        }
    }

    /// Views of colour, position, normal and IDs, in the order the shading passes bind them.
    pub fn views(&self) -> [wgpu::TextureView; 4] {
        [&self.color, &self.position, &self.normal, &self.ids]
            .map(|t| t.create_view(&Default::default()))
    }

    /// The shaded colour as an image.
    pub fn read_color(&self, ctx: &GpuContext) -> Result<Image, GpuError> {
        read_rgba32f(ctx, &self.color)
    }

    /// Per pixel: (mesh index + 1, triangle index); mesh 0 is the background.
    pub fn read_ids(&self, ctx: &GpuContext) -> Result<Vec<[u32; 2]>, GpuError> {
        Ok(bytemuck::cast_slice(&ctx.read_texture(&self.ids, 0)?).to_vec())
    }
}

pub fn read_rgba32f(ctx: &GpuContext, texture: &wgpu::Texture) -> Result<Image, GpuError> {
    let bytes = ctx.read_texture(texture, 0)?;
    let texels: &[[f32; 4]] = bytemuck::cast_slice(&bytes);
    Ok(Image {
        width: texture.width(),
        height: texture.height(),
        pixels: texels.iter().map(|t| Vec3::new(t[0], t[1], t[2])).collect(),
    })
}

/// Bind groups that read a pooled G-buffer, kept per pool slot ([`GBuffer::slot`]) so that a
/// steady-state frame makes none.
#[derive(Default)]
pub struct BindGroupsBySlot {
    groups: Vec<(usize, wgpu::BindGroup)>,
    /// The pool's [`RasterPass::drops`] when these were last pruned.
    pruned_at: u64,
}

impl BindGroupsBySlot {
    /// The bind group of `g`'s slot, made by `make` the first time. Those of G-buffers `pass`
    /// no longer pools are dropped first, so they do not keep the textures alive.
    pub fn get_or_make(
        &mut self,
        pass: &RasterPass,
        g: &GBuffer,
        make: impl FnOnce() -> wgpu::BindGroup,
    ) -> &wgpu::BindGroup {
        if self.pruned_at != pass.drops.get() {
            self.keep_pooled(pass);
            self.pruned_at = pass.drops.get();
        }
        let index = match self.groups.iter().position(|(s, _)| *s == g.slot) {
            Some(index) => index,
            None => {
                self.groups.push((g.slot, make()));
                self.groups.len() - 1
            }
        };
        &self.groups[index].1
    }

    /// The bind group made for `slot`, if any.
    pub fn get(&self, slot: usize) -> Option<&wgpu::BindGroup> {
        self.groups.iter().find(|(s, _)| *s == slot).map(|(_, g)| g)
    }

    /// Forgets every bind group (what they bind was replaced).
    pub fn clear(&mut self) {
        self.groups.clear();
    }

    /// Forgets the bind groups of G-buffers `pass` no longer pools.
    fn keep_pooled(&mut self, pass: &RasterPass) {
        let pool = pass.pool.borrow();
        self.groups
            .retain(|(slot, _)| pool.iter().any(|entry| entry.g.slot == *slot));
    }
}

/// A technique's output image, kept across frames and replaced only when the size changes.
#[derive(Default)]
pub struct OutputTexture {
    texture: Option<wgpu::Texture>,
}

impl OutputTexture {
    /// The `width` × `height` colour target (readable, sampleable, storable).
    pub fn get(&mut self, ctx: &GpuContext, width: u32, height: u32) -> wgpu::Texture {
        match &self.texture {
            Some(t) if t.width() == width && t.height() == height => t.clone(),
            _ => {
                let texture = texture_2d(
                    ctx,
                    "output",
                    width,
                    height,
                    COLOR_FORMAT,
                    wgpu::TextureUsages::RENDER_ATTACHMENT
                        | wgpu::TextureUsages::COPY_SRC
                        | wgpu::TextureUsages::COPY_DST
                        | wgpu::TextureUsages::TEXTURE_BINDING
                        | wgpu::TextureUsages::STORAGE_BINDING,
                );
                self.texture = Some(texture.clone());
                texture
            }
        }
    }
}

/// Which surface a scene draw keeps at each pixel.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Keep {
    Nearest,
    Farthest,
}

/// A depth attachment cleared to the far plane and kept.
fn cleared_depth(view: &wgpu::TextureView) -> wgpu::RenderPassDepthStencilAttachment<'_> {
    wgpu::RenderPassDepthStencilAttachment {
        view,
        depth_ops: Some(wgpu::Operations {
            load: wgpu::LoadOp::Clear(1.0),
            store: wgpu::StoreOp::Store,
        }),
        stencil_ops: None,
    }
}

/// The last pass of techniques that shade the G-buffer: a full-screen triangle (`vs_fullscreen`)
/// running `fs_shade` of `module` into one colour target, with `layout` as bind group 0 and the
/// scene's (`GpuScene::bind_group_layout`) as group 1.
pub fn shading_pipeline(
    device: &wgpu::Device,
    label: &str,
    module: &wgpu::ShaderModule,
    layout: &wgpu::BindGroupLayout,
    scene_layout: &wgpu::BindGroupLayout,
) -> wgpu::RenderPipeline {
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: &[Some(layout), Some(scene_layout)],
        ..Default::default()
    });
    render_pipeline(
        device,
        &PipelineSpec {
            label,
            layout: &pipeline_layout,
            module,
            vertex_entry: "vs_fullscreen",
            fragment_entry: "fs_shade",
            vertex_buffers: &[],
            depth: None,
            targets: &[COLOR_FORMAT],
            write_mask: wgpu::ColorWrites::ALL,
            blend: None,
            cull_mode: None,
        },
    )
}

/// Draws the full-screen triangle of `pipeline` (vertex entry without buffers) into `output`,
/// with `bind_groups` bound as groups 0, 1, ... : the last pass of techniques that shade the
/// G-buffer's pixels.
pub fn fullscreen_pass(
    ctx: &GpuContext,
    label: &str,
    pipeline: &wgpu::RenderPipeline,
    bind_groups: &[&wgpu::BindGroup],
    output: &wgpu::Texture,
) {
    let output_view = output.create_view(&Default::default());
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(label),
            color_attachments: &[specula_gpu::util::color_attachment(
                &output_view,
                wgpu::LoadOp::Clear(wgpu::Color::BLACK),
            )],
            ..Default::default()
        });
        pass.set_pipeline(pipeline);
        for (group, bind_group) in bind_groups.iter().enumerate() {
            pass.set_bind_group(group as u32, *bind_group, &[]);
        }
        pass.draw(0..3, 0..1);
    }
    ctx.queue.submit([encoder.finish()]);
}

/// Near and far planes that hold the whole scene as seen from `eye`. The near plane is
/// 10⁻⁴ of the far one: a 32-bit depth buffer then separates surfaces 0.2 mm apart at 0.7 m
/// in a 1.5 m scene (the truck cover's two walls, 3 mm apart, are told apart), where 10⁻⁵
/// separated only about 2 mm and let the back wall win depth ties; geometry nearer the eye
/// than the near plane (1.5 mm there) is clipped.
pub fn depth_range(scene_bounds: &specula_scene::Aabb, eye: Vec3) -> (f32, f32) {
    let radius = scene_bounds.radius().max(1e-3);
    let far = (scene_bounds.center() - eye).length() + radius * 1.01;
    (far * 1e-4, far)
}

pub fn camera_uniform(
    camera: &Camera,
    scene_bounds: &specula_scene::Aabb,
    width: u32,
    height: u32,
) -> CameraUniform {
    let frame = camera.frame();
    let (near, far) = depth_range(scene_bounds, camera.eye);
    CameraUniform::new(
        camera.eye,
        frame.right,
        frame.up,
        frame.forward,
        camera.fov_y_deg,
        width,
        height,
        near,
        far,
    )
}

/// Which meshes a raster pass draws.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshSelection {
    All,
    /// Mirrors and dielectrics only.
    Specular,
    /// Everything but mirrors and dielectrics.
    NonSpecular,
}

/// Which G-buffer targets a raster pass fills.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Targets {
    /// Every target, the colour lit (shadow maps drawn and read).
    Shaded,
    /// Position, normal, IDs and depth only: the colour stays black and no light is computed or
    /// shadow map drawn (a refractor's back faces, a depth or normal map).
    Geometry,
}

/// What a [`RasterPass`] draws.
#[derive(Clone, Copy, Debug)]
pub struct RasterSpec {
    pub meshes: MeshSelection,
    pub targets: Targets,
    /// `Some(Face::Front)` keeps only back faces (a refractor's far side).
    pub cull_mode: Option<wgpu::Face>,
    /// Draw the background behind the geometry (else IDs stay 0 and colour black there).
    pub background: bool,
    /// Texels per side of each shadow map.
    pub shadow_resolution: u32,
}

impl RasterSpec {
    /// Everything, both faces, with the background: the view every technique starts from.
    pub fn scene(shadow_resolution: u32) -> RasterSpec {
        RasterSpec {
            meshes: MeshSelection::All,
            targets: Targets::Shaded,
            cull_mode: None,
            background: true,
            shadow_resolution,
        }
    }
}

/// Light views and the bind groups that render each shadow-map layer, made once.
struct Shadows {
    pipeline: wgpu::RenderPipeline,
    maps: wgpu::Texture,
    depth: wgpu::Texture,
    /// One uniform buffer and bind group per layer.
    layer_views: Vec<(wgpu::Buffer, wgpu::BindGroup)>,
    /// Every layer's view, read by lighting.wgsl.
    views: wgpu::Buffer,
    resolution: u32,
}

/// A pooled G-buffer: handed out now (`in_use`), and used at all this frame (`used`).
struct PoolEntry {
    g: GBuffer,
    in_use: bool,
    used: bool,
}

pub struct RasterPass {
    spec: RasterSpec,
    scene_pipeline: wgpu::RenderPipeline,
    /// The scene pipeline keeping the farthest surface ([`RasterPass::draw_farthest_into`]),
    /// made on first use, from the module and layout kept for it.
    farthest_pipeline: std::cell::OnceCell<wgpu::RenderPipeline>,
    module: wgpu::ShaderModule,
    scene_pipeline_layout: wgpu::PipelineLayout,
    background_pipeline: wgpu::RenderPipeline,
    scene_bind_group: wgpu::BindGroup,
    shadow_layout: wgpu::BindGroupLayout,
    shadow_bind_group: wgpu::BindGroup,
    shadows: Shadows,
    camera_buffer: wgpu::Buffer,
    camera_bind_group: wgpu::BindGroup,
    /// Per mesh: whether the spec selects it.
    selected: Vec<bool>,
    /// G-buffers kept across frames, and whether each is handed out this frame.
    pool: RefCell<Vec<PoolEntry>>,
    next_slot: Cell<usize>,
    /// How many times `begin_frame` dropped G-buffers from the pool: bind groups kept per slot
    /// prune theirs only when it changes.
    drops: Cell<u64>,
    /// The scene version the shadow maps were drawn at.
    shadows_at: Cell<u64>,
}

fn uniform_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Uniform,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// How [`GpuVertex`] buffers are laid out for a vertex shader (locations 0 to 4).
pub fn vertex_layout() -> wgpu::VertexBufferLayout<'static> {
    const ATTRIBUTES: [wgpu::VertexAttribute; 5] = wgpu::vertex_attr_array![
        0 => Float32x3, 1 => Uint32, 2 => Float32x3, 3 => Uint32, 4 => Float32x2
    ];
    wgpu::VertexBufferLayout {
        array_stride: std::mem::size_of::<GpuVertex>() as u64,
        step_mode: wgpu::VertexStepMode::Vertex,
        attributes: &ATTRIBUTES,
    }
}

/// (forward, up) of the six cube faces, in the order +X, -X, +Y, -Y, +Z, -Z (cubemap.wgsl).
pub const CUBE_FACES: [(Vec3, Vec3); 6] = [
    (Vec3::X, Vec3::NEG_Y),
    (Vec3::NEG_X, Vec3::NEG_Y),
    (Vec3::Y, Vec3::Z),
    (Vec3::NEG_Y, Vec3::NEG_Z),
    (Vec3::Z, Vec3::NEG_Y),
    (Vec3::NEG_Z, Vec3::NEG_Y),
];

/// The six 90° views of a cube around `position`, in the order of [`CUBE_FACES`].
pub fn cube_views(position: Vec3, near: f32, far: f32, resolution: u32) -> [ShadowView; 6] {
    let projection = Mat4::perspective_rh(std::f32::consts::FRAC_PI_2, 1.0, near, far);
    CUBE_FACES.map(|(forward, up)| ShadowView {
        clip_from_world: (projection * Mat4::look_to_rh(position, forward, up)).to_cols_array_2d(),
        origin: position.to_array(),
        directional: 0,
        direction: forward.to_array(),
        texel_size: 2.0 / resolution as f32,
    })
}

/// The bind group layouts of the raster shader: the camera (group 0), the scene (group 1),
/// the shadow maps with their views (group 2), and the light view a shadow-map layer is drawn
/// from.
struct Layouts {
    camera: wgpu::BindGroupLayout,
    shadow_view: wgpu::BindGroupLayout,
    scene: wgpu::BindGroupLayout,
    shadows: wgpu::BindGroupLayout,
}

impl Layouts {
    fn new(device: &wgpu::Device) -> Layouts {
        let camera = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("camera"),
            entries: &[uniform_entry(0)],
        });
        let shadow_view = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("shadow view"),
            entries: &[uniform_entry(1)],
        });
        let scene = GpuScene::bind_group_layout(device);
        let shadows = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("shadows"),
            entries: &[
                layout_entry(
                    0,
                    wgpu::ShaderStages::FRAGMENT,
                    buffer_binding(wgpu::BufferBindingType::Storage { read_only: true }),
                ),
                layout_entry(
                    1,
                    wgpu::ShaderStages::FRAGMENT,
                    texture_binding(
                        wgpu::TextureSampleType::Float { filterable: false },
                        wgpu::TextureViewDimension::D2Array,
                    ),
                ),
            ],
        });
        Layouts {
            camera,
            shadow_view,
            scene,
            shadows,
        }
    }
}

fn depth_state(write: bool, compare: wgpu::CompareFunction) -> Option<wgpu::DepthStencilState> {
    Some(wgpu::DepthStencilState {
        format: DEPTH_FORMAT,
        depth_write_enabled: Some(write),
        depth_compare: Some(compare),
        stencil: Default::default(),
        bias: Default::default(),
    })
}

/// The scene pipeline: the fragment stage `spec` targets, its faces culled as `spec` asks,
/// each fragment kept by `compare` against the depth there; with `Greater` (the farthest kept:
/// a view looking back along the rays) lit from the far side.
fn scene_pipeline(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    layout: &wgpu::PipelineLayout,
    spec: &RasterSpec,
    compare: wgpu::CompareFunction,
) -> wgpu::RenderPipeline {
    render_pipeline(
        device,
        &PipelineSpec {
            label: "scene raster",
            layout,
            module,
            vertex_entry: "vs_scene",
            fragment_entry: match (spec.targets, compare == wgpu::CompareFunction::Greater) {
                (Targets::Shaded, false) => "fs_scene",
                (Targets::Geometry, false) => "fs_geometry",
                (Targets::Shaded, true) => "fs_scene_from_behind",
                (Targets::Geometry, true) => "fs_geometry_from_behind",
            },
            vertex_buffers: &[Some(vertex_layout())],
            depth: depth_state(true, compare),
            targets: &G_BUFFER_FORMATS,
            write_mask: wgpu::ColorWrites::ALL,
            blend: None,
            cull_mode: spec.cull_mode,
        },
    )
}

/// The pass's pipelines from `module`: the scene (nearest surface kept), the background, and
/// the shadow map; and the scene pipeline's layout.
fn pipelines(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    layouts: &Layouts,
    spec: &RasterSpec,
) -> ([wgpu::RenderPipeline; 3], wgpu::PipelineLayout) {
    let layout = |layouts: &[Option<&wgpu::BindGroupLayout>]| {
        device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: None,
            bind_group_layouts: layouts,
            ..Default::default()
        })
    };
    let scene_pipeline_layout = layout(&[
        Some(&layouts.camera),
        Some(&layouts.scene),
        Some(&layouts.shadows),
    ]);
    let depth = depth_state;
    let scene_pipeline = scene_pipeline(
        device,
        module,
        &scene_pipeline_layout,
        spec,
        wgpu::CompareFunction::Less,
    );
    let background_pipeline_layout = layout(&[Some(&layouts.camera), Some(&layouts.scene)]);
    let background_pipeline = render_pipeline(
        device,
        &PipelineSpec {
            label: "background",
            layout: &background_pipeline_layout,
            module,
            vertex_entry: "vs_fullscreen",
            fragment_entry: "fs_background",
            vertex_buffers: &[],
            depth: depth(false, wgpu::CompareFunction::Always),
            targets: &G_BUFFER_FORMATS,
            write_mask: wgpu::ColorWrites::ALL,
            blend: None,
            cull_mode: None,
        },
    );
    let shadow_pipeline_layout = layout(&[Some(&layouts.shadow_view)]);
    let shadow_pipeline = render_pipeline(
        device,
        &PipelineSpec {
            label: "shadow map",
            layout: &shadow_pipeline_layout,
            module,
            vertex_entry: "vs_shadow",
            fragment_entry: "fs_shadow",
            vertex_buffers: &[Some(vertex_layout())],
            depth: depth(true, wgpu::CompareFunction::Less),
            targets: &[SHADOW_FORMAT],
            write_mask: wgpu::ColorWrites::ALL,
            blend: None,
            cull_mode: None,
        },
    );
    (
        [scene_pipeline, background_pipeline, shadow_pipeline],
        scene_pipeline_layout,
    )
}

impl Shadows {
    /// The shadow maps of `gpu_scene`'s lights (`resolution` texels a side, one layer per
    /// light view), drawn with `pipeline`; with the bind group lighting.wgsl reads them by.
    fn new(
        ctx: &GpuContext,
        gpu_scene: &GpuScene,
        layouts: &Layouts,
        pipeline: wgpu::RenderPipeline,
        resolution: u32,
    ) -> (Shadows, wgpu::BindGroup) {
        let layers = gpu_scene.shadow_layers().max(1);
        let maps = ctx.create_texture(&wgpu::TextureDescriptor {
            label: Some("shadow maps"),
            size: wgpu::Extent3d {
                width: resolution,
                height: resolution,
                depth_or_array_layers: layers,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: SHADOW_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let depth = texture_2d(
            ctx,
            "shadow depth",
            resolution,
            resolution,
            DEPTH_FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT,
        );
        let layer_views = (0..gpu_scene.shadow_layers())
            .map(|_| {
                let buffer = specula_gpu::util::writable_buffer(
                    ctx,
                    "shadow view",
                    size_of::<ShadowView>() as u64,
                    wgpu::BufferUsages::UNIFORM,
                );
                let bind_group = ctx.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: None,
                    layout: &layouts.shadow_view,
                    entries: &[wgpu::BindGroupEntry {
                        binding: 1,
                        resource: buffer.as_entire_binding(),
                    }],
                });
                (buffer, bind_group)
            })
            .collect();
        let views = specula_gpu::util::writable_buffer(
            ctx,
            "shadow views",
            layers as u64 * size_of::<ShadowView>() as u64,
            wgpu::BufferUsages::STORAGE,
        );
        let bind_group = ctx.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("shadows"),
            layout: &layouts.shadows,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: views.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&maps.create_view(
                        &wgpu::TextureViewDescriptor {
                            dimension: Some(wgpu::TextureViewDimension::D2Array),
                            ..Default::default()
                        },
                    )),
                },
            ],
        });
        let shadows = Shadows {
            pipeline,
            maps,
            depth,
            layer_views,
            views,
            resolution,
        };
        (shadows, bind_group)
    }
}

/// The camera uniform, rewritten before each draw, and its bind group (group 0).
fn camera_binding(
    ctx: &GpuContext,
    layout: &wgpu::BindGroupLayout,
) -> (wgpu::Buffer, wgpu::BindGroup) {
    let buffer = specula_gpu::util::writable_buffer(
        ctx,
        "camera",
        size_of::<CameraUniform>() as u64,
        wgpu::BufferUsages::UNIFORM,
    );
    let bind_group = ctx.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("camera"),
        layout,
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: buffer.as_entire_binding(),
        }],
    });
    (buffer, bind_group)
}

/// Per mesh of `scene`: whether `selection` draws it.
fn selected_meshes(scene: &Scene, selection: MeshSelection) -> Vec<bool> {
    scene
        .meshes
        .iter()
        .map(|mesh| {
            let specular = scene.materials[mesh.material].is_specular();
            match selection {
                MeshSelection::All => true,
                MeshSelection::Specular => specular,
                MeshSelection::NonSpecular => !specular,
            }
        })
        .collect()
}

impl RasterPass {
    /// Builds the pipelines and renders the shadow maps (they depend on the scene only).
    pub fn new(
        ctx: &GpuContext,
        live: &LiveScene,
        spec: RasterSpec,
    ) -> Result<RasterPass, GpuError> {
        let (scene, gpu_scene) = (live.scene(), live.gpu(ctx));
        let pass = ctx.validated("raster pass set-up", || {
            Self::build(ctx, scene, gpu_scene, spec)
        })?;
        pass.draw_shadows(ctx, scene, gpu_scene)?;
        pass.shadows_at.set(live.version());
        Ok(pass)
    }

    fn build(
        ctx: &GpuContext,
        scene: &Scene,
        gpu_scene: &GpuScene,
        spec: RasterSpec,
    ) -> RasterPass {
        let device = &ctx.device;
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("raster.wgsl"),
            source: wgpu::ShaderSource::Wgsl(shader_source().into()),
        });
        let layouts = Layouts::new(device);
        let ([scene_pipeline, background_pipeline, shadow_pipeline], scene_pipeline_layout) =
            pipelines(device, &module, &layouts, &spec);
        let (shadows, shadow_bind_group) = Shadows::new(
            ctx,
            gpu_scene,
            &layouts,
            shadow_pipeline,
            spec.shadow_resolution,
        );
        let (camera_buffer, camera_bind_group) = camera_binding(ctx, &layouts.camera);
        RasterPass {
            spec,
            scene_bind_group: gpu_scene.bind_group(ctx, &layouts.scene),
            scene_pipeline,
            farthest_pipeline: Default::default(),
            module,
            scene_pipeline_layout,
            background_pipeline,
            shadow_layout: layouts.shadows,
            shadow_bind_group,
            shadows,
            camera_buffer,
            camera_bind_group,
            selected: selected_meshes(scene, spec.meshes),
            pool: RefCell::new(Vec::new()),
            next_slot: Cell::new(0),
            drops: Cell::new(0),
            shadows_at: Cell::new(0),
        }
    }

    /// The light views of the scene's shadow maps: six per point or spot light, one per
    /// directional light.
    fn shadow_views(&self, scene: &Scene, gpu_scene: &GpuScene) -> Vec<ShadowView> {
        let resolution = self.shadows.resolution;
        let bounds = scene.bounds();
        let (center, radius) = (bounds.center(), bounds.radius().max(1e-3));
        let mut views = Vec::new();
        for light in &gpu_scene.gpu_lights {
            if light.kind == LIGHT_DIRECTIONAL {
                let direction = Vec3::from_array(light.direction).normalize();
                let eye = center - direction * 2.0 * radius;
                let up = direction.any_orthonormal_vector();
                let projection =
                    Mat4::orthographic_rh(-radius, radius, -radius, radius, 0.0, 4.0 * radius);
                views.push(ShadowView {
                    clip_from_world: (projection * Mat4::look_to_rh(eye, direction, up))
                        .to_cols_array_2d(),
                    origin: eye.to_array(),
                    directional: 1,
                    direction: direction.to_array(),
                    texel_size: 2.0 * radius / resolution as f32,
                });
            } else {
                let position = Vec3::from_array(light.position);
                let far = (center - position).length() + radius * 1.01;
                views.extend(cube_views(position, far * 1e-5, far, resolution));
            }
        }
        views
    }

    /// Draws the shadow maps of the scene as it is now: at creation, and after the geometry
    /// changed. Creates nothing.
    fn draw_shadows(
        &self,
        ctx: &GpuContext,
        scene: &Scene,
        gpu_scene: &GpuScene,
    ) -> Result<(), GpuError> {
        ctx.validated("shadow maps", || {
            let views = self.shadow_views(scene, gpu_scene);
            if !views.is_empty() {
                ctx.queue
                    .write_buffer(&self.shadows.views, 0, bytemuck::cast_slice(&views));
            }
            let depth_view = self.shadows.depth.create_view(&Default::default());
            for (layer, (view, (buffer, bind_group))) in
                views.iter().zip(&self.shadows.layer_views).enumerate()
            {
                ctx.queue.write_buffer(buffer, 0, bytemuck::bytes_of(view));
                let layer_view = self.shadows.maps.create_view(&wgpu::TextureViewDescriptor {
                    dimension: Some(wgpu::TextureViewDimension::D2),
                    base_array_layer: layer as u32,
                    array_layer_count: Some(1),
                    ..Default::default()
                });
                let mut encoder = ctx.device.create_command_encoder(&Default::default());
                {
                    let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                        label: Some("shadow map"),
                        color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                            view: &layer_view,
                            depth_slice: None,
                            resolve_target: None,
                            ops: wgpu::Operations {
                                load: wgpu::LoadOp::Clear(wgpu::Color {
                                    r: 3.0e38,
                                    g: 0.0,
                                    b: 0.0,
                                    a: 0.0,
                                }),
                                store: wgpu::StoreOp::Store,
                            },
                        })],
                        depth_stencil_attachment: Some(cleared_depth(&depth_view)),
                        ..Default::default()
                    });
                    pass.set_pipeline(&self.shadows.pipeline);
                    pass.set_bind_group(0, bind_group, &[]);
                    pass.set_vertex_buffer(0, gpu_scene.vertices.slice(..));
                    pass.draw(0..gpu_scene.vertex_count, 0..1);
                }
                // One submission per layer: the next layer's view is written before it.
                ctx.queue.submit([encoder.finish()]);
            }
        })
    }

    /// Layout of bind group 2 of lighting.wgsl (the lights' shadow maps).
    pub fn shadow_layout(&self) -> &wgpu::BindGroupLayout {
        &self.shadow_layout
    }

    /// Bind group 2 of lighting.wgsl, for passes that shade surfaces as this one does.
    pub fn shadow_bind_group(&self) -> &wgpu::BindGroup {
        &self.shadow_bind_group
    }

    /// Starts a frame: hands every pooled G-buffer back, and redraws the shadow maps when an
    /// object moved since they were drawn.
    pub fn begin_frame(&self, ctx: &GpuContext, live: &LiveScene) -> Result<(), GpuError> {
        // G-buffers the last frame did not use (another size: a resized window, a view that
        // moved at reduced resolution) are dropped, so the pool holds one frame's worth.
        let mut pool = self.pool.borrow_mut();
        let pooled = pool.len();
        pool.retain(|entry| entry.used);
        if pool.len() != pooled {
            self.drops.set(self.drops.get() + 1);
        }
        for entry in pool.iter_mut() {
            entry.in_use = false;
            entry.used = false;
        }
        drop(pool);
        if self.spec.targets == Targets::Shaded && self.shadows_at.get() != live.version() {
            self.draw_shadows(ctx, live.scene(), live.gpu(ctx))?;
            self.shadows_at.set(live.version());
        }
        Ok(())
    }

    /// How many G-buffers the pool holds.
    pub fn pooled(&self) -> usize {
        self.pool.borrow().len()
    }

    /// Hands `g` back before the frame ends, once what was drawn from it has been submitted:
    /// passes that draw many short-lived maps (nested reflections) reuse it instead of holding
    /// them all.
    pub fn release(&self, g: &GBuffer) {
        if let Some(entry) = self
            .pool
            .borrow_mut()
            .iter_mut()
            .find(|entry| entry.g.slot == g.slot)
        {
            entry.in_use = false;
        }
    }

    /// A `width` × `height` G-buffer not yet handed out this frame, made only when the pool
    /// has none.
    pub fn acquire(&self, ctx: &GpuContext, width: u32, height: u32) -> GBuffer {
        let mut pool = self.pool.borrow_mut();
        if let Some(entry) = pool
            .iter_mut()
            .find(|e| !e.in_use && e.g.width == width && e.g.height == height)
        {
            entry.in_use = true;
            entry.used = true;
            return entry.g.clone();
        }
        let slot = self.next_slot.get();
        self.next_slot.set(slot + 1);
        let g = GBuffer::new(ctx, width, height, slot);
        pool.push(PoolEntry {
            g: g.clone(),
            in_use: true,
            used: true,
        });
        g
    }

    /// Rasterises the scene for `camera` into a pooled G-buffer; `hidden_mesh`, if given, is
    /// left out (a reflector rendering its own environment).
    pub fn render(
        &self,
        ctx: &GpuContext,
        gpu_scene: &GpuScene,
        camera: &CameraUniform,
        hidden_mesh: Option<usize>,
    ) -> Result<GBuffer, GpuError> {
        self.render_with(ctx, gpu_scene, camera, hidden_mesh, None)
    }

    /// As [`RasterPass::render`], also drawing `extra` (a vertex buffer laid out as
    /// `GpuVertex`, the byte offset and the count of its vertices) after the scene: per-frame
    /// geometry such as markers.
    pub fn render_with(
        &self,
        ctx: &GpuContext,
        gpu_scene: &GpuScene,
        camera: &CameraUniform,
        hidden_mesh: Option<usize>,
        extra: Option<(&wgpu::Buffer, u64, u32)>,
    ) -> Result<GBuffer, GpuError> {
        let g = self.acquire(ctx, camera.width as u32, camera.height as u32);
        self.draw_into(ctx, gpu_scene, camera, hidden_mesh.as_slice(), extra, &g)?;
        Ok(g)
    }

    /// Rasterises into `g` (of the camera's size), leaving out the meshes in `hidden`.
    pub fn draw_into(
        &self,
        ctx: &GpuContext,
        gpu_scene: &GpuScene,
        camera: &CameraUniform,
        hidden: &[usize],
        extra: Option<(&wgpu::Buffer, u64, u32)>,
        g: &GBuffer,
    ) -> Result<(), GpuError> {
        ctx.validated("scene raster", || {
            self.draw(ctx, gpu_scene, camera, hidden, extra, g, Keep::Nearest)
        })
    }

    /// Draws over `g` (of the camera's size), leaving out the meshes in `hidden`, keeping at
    /// each pixel the surface farthest from the camera between its near and far planes (what
    /// was in `g` stays where none lies there), without the background, each surface lit on
    /// its side away from the camera: the reversed depth test of pvrr's zooming region (seed
    /// 000 §7), whose rays come from the mirror beyond.
    pub fn draw_farthest_into(
        &self,
        ctx: &GpuContext,
        gpu_scene: &GpuScene,
        camera: &CameraUniform,
        hidden: &[usize],
        extra: Option<(&wgpu::Buffer, u64, u32)>,
        g: &GBuffer,
    ) -> Result<(), GpuError> {
        ctx.validated("scene raster, farthest surface", || {
            self.farthest_pipeline.get_or_init(|| {
                scene_pipeline(
                    &ctx.device,
                    &self.module,
                    &self.scene_pipeline_layout,
                    &self.spec,
                    wgpu::CompareFunction::Greater,
                )
            });
            self.draw(ctx, gpu_scene, camera, hidden, extra, g, Keep::Farthest)
        })
    }

    #[allow(clippy::too_many_arguments)]
    fn draw(
        &self,
        ctx: &GpuContext,
        gpu_scene: &GpuScene,
        camera: &CameraUniform,
        hidden: &[usize],
        extra: Option<(&wgpu::Buffer, u64, u32)>,
        g: &GBuffer,
        keep: Keep,
    ) {
        ctx.queue
            .write_buffer(&self.camera_buffer, 0, bytemuck::bytes_of(camera));
        let views = g.views();
        let depth_view = g.depth.create_view(&Default::default());
        let (load, clear_depth, pipeline) = match keep {
            Keep::Nearest => (
                wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT),
                1.0,
                &self.scene_pipeline,
            ),
            Keep::Farthest => (
                wgpu::LoadOp::Load,
                0.0,
                self.farthest_pipeline
                    .get()
                    .expect("made by draw_farthest_into"),
            ),
        };
        let attachments: Vec<Option<wgpu::RenderPassColorAttachment>> = views
            .iter()
            .map(|view| specula_gpu::util::color_attachment(view, load))
            .collect();
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("scene raster"),
                color_attachments: &attachments,
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &depth_view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(clear_depth),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                ..Default::default()
            });
            pass.set_bind_group(0, &self.camera_bind_group, &[]);
            pass.set_bind_group(1, &self.scene_bind_group, &[]);
            if self.spec.background && keep == Keep::Nearest {
                pass.set_pipeline(&self.background_pipeline);
                pass.draw(0..3, 0..1);
            }
            pass.set_pipeline(pipeline);
            pass.set_bind_group(2, &self.shadow_bind_group, &[]);
            pass.set_vertex_buffer(0, gpu_scene.vertices.slice(..));
            for range in
                gpu_scene.vertex_ranges(|mesh| self.selected[mesh] && !hidden.contains(&mesh))
            {
                pass.draw(range, 0..1);
            }
            if let Some((buffer, offset, count)) = extra {
                pass.set_vertex_buffer(0, buffer.slice(offset..));
                pass.draw(0..count, 0..1);
            }
        }
        ctx.queue.submit([encoder.finish()]);
    }
}
