//! The scene uploaded to the GPU once per scene: un-indexed world-space vertices (three per
//! triangle, so each carries its mesh and triangle ID for the ID buffer), materials, textures
//! (all texels in one storage buffer, sampled in WGSL exactly as the CPU samples them) and
//! lights. A moved mesh rewrites its vertex range in place ([`GpuScene::write_mesh`]).
//!
//! Three mesh slots past the scene's own meshes, [`GpuScene::marker_mesh`], are unlit red,
//! green and blue with no triangles: verification overlays (pvrr's markers) draw extra
//! geometry under those mesh IDs.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use specula_gpu::GpuContext;
use specula_scene::{Background, Light, MaterialKind, Mesh, Scene};

/// One vertex: world position, mesh index, world normal, triangle index, texture coordinate.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuVertex {
    pub position: [f32; 3],
    pub mesh: u32,
    pub normal: [f32; 3],
    pub triangle: u32,
    pub uv: [f32; 2],
}

pub const MATERIAL_UNLIT: u32 = 0;
pub const MATERIAL_DIFFUSE: u32 = 1;
pub const MATERIAL_MIRROR: u32 = 2;
pub const MATERIAL_DIELECTRIC: u32 = 3;
pub const FLAG_FRESNEL: u32 = 1;
pub const FLAG_THIN: u32 = 2;

/// Host mirror of WGSL `Material` (raster.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuMaterial {
    pub color: [f32; 3],
    pub kind: u32,
    pub ior: [f32; 3],
    /// Index into the texture table, or -1.
    pub texture: i32,
    pub flags: u32,
    pub pad: [u32; 3],
}

/// Host mirror of WGSL `TextureInfo`: where a texture's texels start in the texel buffer.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuTextureInfo {
    pub offset: u32,
    pub width: u32,
    pub height: u32,
    pub pad: u32,
}

pub const LIGHT_POINT: u32 = 0;
pub const LIGHT_DIRECTIONAL: u32 = 1;
pub const LIGHT_SPOT: u32 = 2;

/// Host mirror of WGSL `Light`. `shadow_layer` is the first shadow-map layer of the light (six
/// for point and spot lights, one for a directional light).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuLight {
    pub position: [f32; 3],
    pub kind: u32,
    pub direction: [f32; 3],
    pub cos_inner: f32,
    pub intensity: [f32; 3],
    pub cos_outer: f32,
    pub shadow_layer: u32,
    pub pad: [u32; 3],
}

/// Host mirror of WGSL `SceneInfo`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuSceneInfo {
    pub ambient: [f32; 3],
    pub light_count: u32,
    pub background: [f32; 3],
    /// Texture index of an equirectangular background, or -1 for a constant colour.
    pub background_texture: i32,
    pub background_intensity: f32,
    pub pad: [u32; 3],
}

pub struct GpuScene {
    pub vertices: wgpu::Buffer,
    pub vertex_count: u32,
    pub materials: wgpu::Buffer,
    pub mesh_materials: wgpu::Buffer,
    pub texture_infos: wgpu::Buffer,
    pub texels: wgpu::Buffer,
    pub lights: wgpu::Buffer,
    pub info: wgpu::Buffer,
    pub gpu_lights: Vec<GpuLight>,
    /// Index of the first marker mesh (the scene's mesh count).
    pub first_marker_mesh: u32,
    /// Each mesh's range in `vertices` (meshes are uploaded in order, three vertices per
    /// triangle), so that a pass can leave one out.
    pub mesh_vertex_ranges: Vec<std::ops::Range<u32>>,
}

/// Radiance of the marker meshes' unlit materials: beyond any lit surface, so that a test can
/// find them in a float image.
pub const MARKER_RADIANCE: f32 = 4.0;

fn storage<T: Pod>(ctx: &GpuContext, label: &str, items: &[T], placeholder: T) -> wgpu::Buffer {
    // Storage bindings may not be empty.
    let contents: Vec<T> = if items.is_empty() {
        vec![placeholder]
    } else {
        items.to_vec()
    };
    ctx.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some(label),
        contents: bytemuck::cast_slice(&contents),
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
    })
}

impl GpuScene {
    /// The vertices of mesh `index`, three per triangle.
    fn mesh_vertices(index: usize, mesh: &Mesh) -> impl Iterator<Item = GpuVertex> + '_ {
        mesh.triangles.iter().enumerate().flat_map(move |(t, tri)| {
            tri.map(|i| {
                let i = i as usize;
                GpuVertex {
                    position: mesh.positions[i].to_array(),
                    mesh: index as u32,
                    normal: mesh.normals[i].to_array(),
                    triangle: t as u32,
                    uv: mesh
                        .uvs
                        .get(i)
                        .map(|uv| uv.to_array())
                        .unwrap_or([0.0, 0.0]),
                }
            })
        })
    }

    /// The mesh ID the marker geometry of colour channel `channel` (0 red, 1 green, 2 blue)
    /// is drawn under.
    pub fn marker_mesh(&self, channel: u32) -> u32 {
        self.first_marker_mesh + channel
    }

    /// Rewrites mesh `index`'s vertices in place (after a rigid move: same triangles).
    pub fn write_mesh(&self, ctx: &GpuContext, index: usize, mesh: &Mesh) {
        let vertices: Vec<GpuVertex> = Self::mesh_vertices(index, mesh).collect();
        let offset = self.mesh_vertex_ranges[index].start as u64 * size_of::<GpuVertex>() as u64;
        ctx.queue
            .write_buffer(&self.vertices, offset, bytemuck::cast_slice(&vertices));
    }

    pub fn upload(ctx: &GpuContext, scene: &Scene) -> GpuScene {
        let mut vertices = Vec::with_capacity(scene.triangle_count() * 3);
        let mut mesh_vertex_ranges = Vec::with_capacity(scene.meshes.len());
        for (m, mesh) in scene.meshes.iter().enumerate() {
            let start = vertices.len() as u32;
            vertices.extend(Self::mesh_vertices(m, mesh));
            mesh_vertex_ranges.push(start..vertices.len() as u32);
        }
        let materials = gpu_materials(scene);
        let first_marker_material = scene.materials.len() as u32;
        let mesh_materials: Vec<u32> = scene
            .meshes
            .iter()
            .map(|m| m.material as u32)
            .chain((0..3).map(|c| first_marker_material + c))
            .collect();
        let (texture_infos, texels) = gpu_textures(scene);
        let gpu_lights = gpu_lights(scene);
        let (background, background_texture, background_intensity) = match scene.background {
            Background::Color(c) => (c, -1, 1.0),
            Background::Equirect { texture, intensity } => (Vec3::ZERO, texture as i32, intensity),
        };
        let info = GpuSceneInfo {
            ambient: scene.ambient.to_array(),
            light_count: gpu_lights.len() as u32,
            background: background.to_array(),
            background_texture,
            background_intensity,
            pad: [0; 3],
        };
        let vertex_count = vertices.len() as u32;
        if vertices.is_empty() {
            vertices.push(GpuVertex::zeroed());
        }
        GpuScene {
            vertices: ctx.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("scene vertices"),
                contents: bytemuck::cast_slice(&vertices),
                usage: wgpu::BufferUsages::VERTEX
                    | wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_DST,
            }),
            vertex_count,
            materials: storage(ctx, "materials", &materials, GpuMaterial::zeroed()),
            mesh_materials: storage(ctx, "mesh materials", &mesh_materials, 0),
            texture_infos: storage(
                ctx,
                "texture infos",
                &texture_infos,
                GpuTextureInfo::zeroed(),
            ),
            texels: storage(ctx, "texels", &texels, [0.0; 4]),
            lights: storage(ctx, "lights", &gpu_lights, GpuLight::zeroed()),
            info: ctx.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("scene info"),
                contents: bytemuck::bytes_of(&info),
                usage: wgpu::BufferUsages::UNIFORM,
            }),
            gpu_lights,
            first_marker_mesh: scene.meshes.len() as u32,
            mesh_vertex_ranges,
        }
    }

    /// The vertex ranges of the meshes for which `keep` holds, consecutive meshes merged into
    /// one range (one draw call each).
    pub fn vertex_ranges(&self, keep: impl Fn(usize) -> bool) -> Vec<std::ops::Range<u32>> {
        let mut ranges: Vec<std::ops::Range<u32>> = Vec::new();
        for (mesh, range) in self.mesh_vertex_ranges.iter().enumerate() {
            if !keep(mesh) || range.is_empty() {
                continue;
            }
            match ranges.last_mut() {
                Some(last) if last.end == range.start => last.end = range.end,
                _ => ranges.push(range.clone()),
            }
        }
        ranges
    }

    /// Number of shadow-map layers the lights need.
    pub fn shadow_layers(&self) -> u32 {
        self.gpu_lights
            .iter()
            .map(|l| if l.kind == LIGHT_DIRECTIONAL { 1 } else { 6 })
            .sum()
    }
}

/// The scene's materials and, after them, the three marker materials.
fn gpu_materials(scene: &Scene) -> Vec<GpuMaterial> {
    let markers = [Vec3::X, Vec3::Y, Vec3::Z]
        .map(|c| specula_scene::Material::unlit("marker", c * MARKER_RADIANCE));
    scene
        .materials
        .iter()
        .chain(&markers)
        .map(|m| {
            let (kind, ior, flags) = match m.kind {
                MaterialKind::Unlit => (MATERIAL_UNLIT, Vec3::ONE, 0),
                MaterialKind::Diffuse => (MATERIAL_DIFFUSE, Vec3::ONE, 0),
                MaterialKind::Mirror { fresnel } => (
                    MATERIAL_MIRROR,
                    Vec3::ONE,
                    if fresnel { FLAG_FRESNEL } else { 0 },
                ),
                MaterialKind::Dielectric { ior, thin_walled } => (
                    MATERIAL_DIELECTRIC,
                    ior,
                    if thin_walled { FLAG_THIN } else { 0 },
                ),
            };
            GpuMaterial {
                color: m.color.to_array(),
                kind,
                ior: ior.to_array(),
                texture: m.texture.map(|t| t as i32).unwrap_or(-1),
                flags,
                pad: [0; 3],
            }
        })
        .collect()
}

/// Every texture's place in one texel buffer, and the texels.
fn gpu_textures(scene: &Scene) -> (Vec<GpuTextureInfo>, Vec<[f32; 4]>) {
    let mut texels: Vec<[f32; 4]> = Vec::new();
    let texture_infos: Vec<GpuTextureInfo> = scene
        .textures
        .iter()
        .map(|t| {
            let offset = texels.len() as u32;
            texels.extend(t.texels.iter().map(|c| [c.x, c.y, c.z, 1.0]));
            GpuTextureInfo {
                offset,
                width: t.width,
                height: t.height,
                pad: 0,
            }
        })
        .collect();
    (texture_infos, texels)
}

/// The lights, each with the first layer of its shadow maps (six for a point or spot light,
/// one for a directional light).
fn gpu_lights(scene: &Scene) -> Vec<GpuLight> {
    let mut gpu_lights = Vec::new();
    let mut layer = 0;
    for light in &scene.lights {
        let (kind, position, direction, intensity, cos_inner, cos_outer, layers) = match *light {
            Light::Point {
                position,
                intensity,
            } => (LIGHT_POINT, position, Vec3::Z, intensity, 1.0, 1.0, 6),
            Light::Directional {
                direction,
                irradiance,
            } => (
                LIGHT_DIRECTIONAL,
                Vec3::ZERO,
                direction,
                irradiance,
                1.0,
                1.0,
                1,
            ),
            Light::Spot {
                position,
                direction,
                intensity,
                inner_cone,
                outer_cone,
            } => (
                LIGHT_SPOT,
                position,
                direction,
                intensity,
                inner_cone.cos(),
                outer_cone.cos(),
                6,
            ),
        };
        gpu_lights.push(GpuLight {
            position: position.to_array(),
            kind,
            direction: direction.to_array(),
            cos_inner,
            intensity: intensity.to_array(),
            cos_outer,
            shadow_layer: layer,
            pad: [0; 3],
        });
        layer += layers;
    }
    gpu_lights
}

impl GpuScene {
    /// Layout of bind group 1, shared by every technique's shaders (shaders/common/scene.wgsl).
    pub fn bind_group_layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
        let storage = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::VERTEX_FRAGMENT | wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: true },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("scene"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::VERTEX_FRAGMENT | wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
                storage(1),
                storage(2),
                storage(3),
                storage(4),
                storage(5),
            ],
        })
    }

    pub fn bind_group(&self, ctx: &GpuContext, layout: &wgpu::BindGroupLayout) -> wgpu::BindGroup {
        let buffers = [
            &self.info,
            &self.materials,
            &self.mesh_materials,
            &self.texture_infos,
            &self.texels,
            &self.lights,
        ];
        specula_gpu::util::bind_group(
            ctx,
            "scene",
            layout,
            &buffers.map(|b| b.as_entire_binding()),
        )
    }
}
