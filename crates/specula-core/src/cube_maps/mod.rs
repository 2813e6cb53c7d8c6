//! Each specular mesh's ("reflector's") environment cube map, and the shading of a G-buffer
//! from those maps: the classic dynamic environment mapping that `envmap` is, and that `c3rc`
//! (its far field) and `image-space` (its fallback) draw on too.
//!
//! A map is drawn from the centre of its reflector's bounding box with the reflector left out:
//! six 90° faces per reflector in one 2D array (`lookup.wgsl` looks them up). Every lookup
//! pretends the environment is infinitely far, so nearby objects appear in the wrong place and
//! at the wrong size (exact only for a distant environment, or at the centre of the map).
//!
//! Two levels (`two_level_maps`, beyond the classic technique): with two reflectors or more,
//! each face is drawn twice, first with specular objects black, then with them shaded from
//! those first faces (`shade.wgsl`), so a mirror in another's map is not black.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use specula_gpu::shaders::{self, CameraUniform};
use specula_gpu::util::{
    bind_group, buffer_binding, layout_entry, texture_binding, writable_buffer,
};
use specula_gpu::{GpuContext, GpuError};
use specula_scene::Scene;

use crate::gpu_scene::GpuScene;
use crate::live_scene::LiveScene;
use crate::params::{Invalidates, Param, ParamKind};
use crate::raster::{self, RasterPass};
/// The shading pass that shades every specular pixel from the cube maps alone.
const SHADE_ONLY_SHADER: &str = include_str!("shade_only.wgsl");
/// The G-buffer shading from the cube maps, as a function `shade(pixel, near)` (c3rc calls it
/// with its own reflections of nearby objects).
pub const SHADE_SHADER: &str = include_str!("shade.wgsl");
/// The cube-map lookup shared with the techniques that fall back on envmap's maps.
pub const LOOKUP_SHADER: &str = include_str!("lookup.wgsl");

/// The shading pass's full source: every specular pixel from the cube maps alone.
pub fn shader_source() -> String {
    shading_shader_source(SHADE_ONLY_SHADER)
}

/// `entry` (which defines `fs_shade`, calling `shade`) after the cube-map shading it calls.
pub fn shading_shader_source(entry: &str) -> String {
    shaders::compose(
        &[
            "optics.wgsl",
            "camera.wgsl",
            "scene.wgsl",
            "cubemap.wgsl",
            "specular_pixel.wgsl",
        ],
        &format!("{LOOKUP_SHADER}\n{SHADE_SHADER}\n{entry}"),
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

/// `two_level_maps`, declared once for every technique that draws [`CubeMaps`]: whether
/// [`CubeMaps::set_two_levels`] is on.
pub const TWO_LEVEL_MAPS: Param = Param {
    kind: ParamKind::Flag,
    default: "true",
    doc: "with two reflectors or more, shade the other specular objects a cube map shows from their own maps (two levels; else black)",
    invalidates: Invalidates::Uniform,
};

/// Each specular mesh's ("reflector's") environment cube map, drawn from the centre of its
/// bounding box with the reflector left out: six 90° faces per reflector in one 2D array,
/// looked up by `lookup.wgsl`. The faces depend on the scene only: they are drawn again after a
/// move, or on every frame when asked (`dynamic`). envmap shades with them; image-space falls
/// back on them where its image-space lookups find nothing.
pub struct CubeMaps {
    /// (mesh index, centre, radius) of each reflector.
    pub reflectors: Vec<(usize, Vec3, f32)>,
    /// The scene version and exit model the reflector buffers were written for.
    placed: Option<(u64, Exit)>,
    env_views: wgpu::Buffer,
    reflector_buffer: wgpu::Buffer,
    mesh_reflector: wgpu::Buffer,
    faces: Option<Faces>,
    /// The pass shading specular objects in the faces from their own first faces, made when a
    /// scene with two reflectors or more first draws its faces.
    second_level: Option<SecondLevel>,
    generation: u64,
    /// (reflector mesh, meshes its final faces leave out besides itself): what a technique
    /// draws by other means (c3rc's near objects). The first level of two keeps them, so that
    /// a specular object in the final faces shows them.
    hidden: Vec<(usize, Vec<usize>)>,
    /// Keep each face's world positions too (`positions_view`): c3rc depth-tests its splats
    /// against the far field with them.
    keep_positions: bool,
    /// Two levels where the scene has two reflectors or more (the technique's `two_level_maps`;
    /// a step beyond every paper that uses cube maps).
    two_levels: bool,
}

/// The cube-map faces at one resolution.
struct Faces {
    texture: wgpu::Texture,
    view: wgpu::TextureView,
    /// With two reflectors or more: the faces with specular objects black, which the final
    /// ones (`texture`) shade them from, and a view of each final face to draw it into.
    first: Option<(wgpu::Texture, wgpu::TextureView)>,
    layer_views: Vec<wgpu::TextureView>,
    /// Each face's world positions (w = 1 on geometry, 0 where nothing was drawn), when kept.
    positions: Option<(wgpu::Texture, wgpu::TextureView)>,
    resolution: u32,
    /// Counts the textures made, so that bind groups know when theirs is gone.
    generation: u64,
    /// Scene version the faces were drawn at (None: never drawn).
    drawn_at: Option<u64>,
}

impl CubeMaps {
    pub fn new(ctx: &GpuContext, scene: &Scene) -> CubeMaps {
        let reflectors = reflectors(scene);
        let mut mesh_reflector = vec![-1i32; scene.meshes.len().max(1)];
        for (k, &(mesh, ..)) in reflectors.iter().enumerate() {
            mesh_reflector[mesh] = k as i32;
        }
        let storage = |label, size: usize| {
            writable_buffer(ctx, label, size as u64, wgpu::BufferUsages::STORAGE)
        };
        let count = reflectors.len().max(1);
        let mesh_reflector_buffer = storage("mesh reflectors", 4 * mesh_reflector.len());
        ctx.queue.write_buffer(
            &mesh_reflector_buffer,
            0,
            bytemuck::cast_slice(&mesh_reflector),
        );
        CubeMaps {
            reflectors,
            placed: None,
            env_views: storage("environment views", 6 * count * 64),
            reflector_buffer: storage("reflectors", count * size_of::<GpuReflector>()),
            mesh_reflector: mesh_reflector_buffer,
            faces: None,
            second_level: None,
            generation: 0,
            hidden: Vec::new(),
            keep_positions: false,
            two_levels: true,
        }
    }

    /// Whether specular objects in the faces are shaded from their own first faces (two
    /// levels, where the scene has two reflectors or more) or left black (one level, as the
    /// papers' maps). A change makes the faces again at the next update.
    pub fn set_two_levels(&mut self, two_levels: bool) {
        self.two_levels = two_levels;
    }

    /// Keeps each face's world positions from now on (made with the next faces).
    pub fn keep_positions(&mut self) {
        if !self.keep_positions {
            self.keep_positions = true;
            self.faces = None;
        }
    }

    /// The faces' world positions, kept since [`CubeMaps::keep_positions`] (after `update`).
    pub fn positions_view(&self) -> Option<&wgpu::TextureView> {
        let faces = self.faces.as_ref()?;
        faces.positions.as_ref().map(|(_, view)| view)
    }

    /// Leaves `hidden` meshes out of the final faces of the reflectors they are given for
    /// ((reflector mesh, meshes) pairs; with two levels the first keeps them); a change marks
    /// the faces stale.
    pub fn set_hidden(&mut self, hidden: Vec<(usize, Vec<usize>)>) {
        if hidden != self.hidden {
            self.hidden = hidden;
            if let Some(faces) = &mut self.faces {
                faces.drawn_at = None;
            }
        }
    }

    /// Forgets the faces (a new resolution makes them again).
    pub fn drop_faces(&mut self) {
        self.faces = None;
    }

    /// Brings the maps up to date for `live` at `resolution`: the reflectors' centres and face
    /// views after a move, and the faces when they are stale or `redraw_always`. Returns the
    /// number of faces drawn.
    pub fn update(
        &mut self,
        gpu: &GpuContext,
        raster: &RasterPass,
        live: &LiveScene,
        resolution: u32,
        exit: Exit,
        redraw_always: bool,
    ) -> Result<u64, GpuError> {
        let scene = live.scene();
        let gpu_scene = live.gpu(gpu);
        if self.placed != Some((live.version(), exit)) {
            self.reflectors = reflectors(scene);
            let mut views = Vec::with_capacity(6 * self.reflectors.len());
            let mut gpu_reflectors = Vec::with_capacity(self.reflectors.len());
            for (k, &(_, center, radius)) in self.reflectors.iter().enumerate() {
                views.extend(
                    face_cameras(scene, center, resolution)
                        .iter()
                        .map(|c| c.clip_from_world),
                );
                gpu_reflectors.push(GpuReflector {
                    center: center.to_array(),
                    radius,
                    first_layer: 6 * k as u32,
                    exit_model: exit as u32,
                    pad: [0; 2],
                });
            }
            if !gpu_reflectors.is_empty() {
                gpu.queue
                    .write_buffer(&self.env_views, 0, bytemuck::cast_slice(&views));
                gpu.queue.write_buffer(
                    &self.reflector_buffer,
                    0,
                    bytemuck::cast_slice(&gpu_reflectors),
                );
            }
            self.placed = Some((live.version(), exit));
        }
        let two_levels = self.two_levels && self.reflectors.len() >= 2;
        if self
            .faces
            .as_ref()
            .map(|f| (f.resolution, f.first.is_some()))
            != Some((resolution, two_levels))
        {
            self.generation += 1;
            let layers = (6 * self.reflectors.len() as u32).max(1);
            let (texture, view) = faces_texture(gpu, "environment faces", resolution, layers);
            let layer_views = (0..layers)
                .filter(|_| two_levels)
                .map(|layer| {
                    texture.create_view(&wgpu::TextureViewDescriptor {
                        dimension: Some(wgpu::TextureViewDimension::D2),
                        base_array_layer: layer,
                        array_layer_count: Some(1),
                        ..Default::default()
                    })
                })
                .collect();
            self.faces = Some(Faces {
                texture,
                view,
                layer_views,
                first: two_levels.then(|| {
                    faces_texture(gpu, "environment faces, first level", resolution, layers)
                }),
                positions: self.keep_positions.then(|| {
                    faces_texture(gpu, "environment faces, positions", resolution, layers)
                }),
                resolution,
                generation: self.generation,
                drawn_at: None,
            });
        }
        let faces = self.faces.as_ref().expect("made above");
        if !redraw_always && faces.drawn_at == Some(live.version()) {
            return Ok(0);
        }
        let face_g = raster.acquire(gpu, resolution, resolution);
        let first_level = faces.first.as_ref().map_or(&faces.texture, |(t, _)| t);
        let draws = self.face_draws(scene, resolution);
        let positions = faces.positions.as_ref().map(|(t, _)| t);
        for (k, face, face_camera, hidden) in &draws {
            // The first level of two shades the specular objects the final faces show: it
            // leaves out only its own reflector, so that a specular object shows what a
            // technique hides from the final faces (c3rc's nearby objects) instead of black.
            let first_hidden = if two_levels {
                &hidden[..1]
            } else {
                &hidden[..]
            };
            raster.draw_into(gpu, gpu_scene, face_camera, first_hidden, None, &face_g)?;
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            copy_to_layer(
                &mut encoder,
                &face_g.color,
                first_level,
                6 * k + face,
                resolution,
            );
            if let (Some(positions), false) = (positions, two_levels) {
                copy_to_layer(
                    &mut encoder,
                    &face_g.position,
                    positions,
                    6 * k + face,
                    resolution,
                );
            }
            gpu.queue.submit([encoder.finish()]);
        }
        if two_levels {
            self.shade_second_level(gpu, raster, live, &draws, &face_g)?;
        }
        raster.release(&face_g);
        self.faces.as_mut().expect("made above").drawn_at = Some(live.version());
        Ok(6 * self.reflectors.len() as u64 * (1 + two_levels as u64))
    }

    /// Every face to draw: (reflector, face, camera, the meshes it leaves out).
    fn face_draws(&self, scene: &Scene, resolution: u32) -> Vec<FaceDraw> {
        let mut draws = Vec::new();
        for (k, &(mesh, center, _)) in self.reflectors.iter().enumerate() {
            let mut hidden = vec![mesh];
            if let Some((_, more)) = self.hidden.iter().find(|(m, _)| *m == mesh) {
                hidden.extend(more);
            }
            for (face, camera) in face_cameras(scene, center, resolution)
                .into_iter()
                .enumerate()
            {
                draws.push((k, face, camera, hidden.clone()));
            }
        }
        draws
    }

    /// The final faces: each face drawn again, its specular pixels shaded as envmap shades
    /// them (`shade.wgsl`) from the first-level faces, so that a specular object in a
    /// reflector's map shows what its own map holds instead of black.
    fn shade_second_level(
        &mut self,
        gpu: &GpuContext,
        raster: &RasterPass,
        live: &LiveScene,
        draws: &[FaceDraw],
        face_g: &raster::GBuffer,
    ) -> Result<(), GpuError> {
        if self.second_level.is_none() {
            self.second_level = Some(SecondLevel::new(gpu, live)?);
        }
        let faces = self.faces.as_ref().expect("made by update");
        let (_, first_view) = faces.first.as_ref().expect("two levels have a first");
        let level = self.second_level.as_mut().expect("made above");
        // Made again only for another face G-buffer or another faces texture.
        let key = (face_g.slot, faces.generation);
        if level.bind_group.as_ref().map(|(k, _)| *k) != Some(key) {
            let views = face_g.views();
            let mut entries = vec![level.camera.as_entire_binding()];
            entries.extend(views.iter().map(wgpu::BindingResource::TextureView));
            entries.extend([
                wgpu::BindingResource::TextureView(first_view),
                self.env_views.as_entire_binding(),
                self.reflector_buffer.as_entire_binding(),
                self.mesh_reflector.as_entire_binding(),
            ]);
            let group = bind_group(gpu, "cube maps, second level", &level.layout, &entries);
            level.bind_group = Some((key, group));
        }
        let level = &*level;
        let (_, group) = level.bind_group.as_ref().expect("made above");
        gpu.validated("cube maps, second level", || -> Result<(), GpuError> {
            for (k, face, face_camera, hidden) in draws {
                raster.draw_into(gpu, live.gpu(gpu), face_camera, hidden, None, face_g)?;
                gpu.queue
                    .write_buffer(&level.camera, 0, bytemuck::bytes_of(face_camera));
                let layer = &faces.layer_views[6 * k + face];
                let mut encoder = gpu.device.create_command_encoder(&Default::default());
                if let Some((positions, _)) = &faces.positions {
                    let resolution = faces.resolution;
                    copy_to_layer(
                        &mut encoder,
                        &face_g.position,
                        positions,
                        6 * k + face,
                        resolution,
                    );
                }
                {
                    let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                        label: Some("cube maps, second level"),
                        color_attachments: &[specula_gpu::util::color_attachment(
                            layer,
                            wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        )],
                        ..Default::default()
                    });
                    pass.set_pipeline(&level.pipeline);
                    pass.set_bind_group(0, group, &[]);
                    pass.set_bind_group(1, &level.scene_bind_group, &[]);
                    pass.draw(0..3, 0..1);
                }
                gpu.queue.submit([encoder.finish()]);
            }
            Ok(())
        })?
    }

    /// The bind group layout entries `lookup.wgsl` reads, from `first` on: the faces, their
    /// views, the reflectors and each mesh's reflector index.
    pub fn layout_entries(first: u32) -> [wgpu::BindGroupLayoutEntry; 4] {
        use wgpu::{BufferBindingType as B, ShaderStages as St, TextureViewDimension as D};
        let float = wgpu::TextureSampleType::Float { filterable: false };
        let read_only = || buffer_binding(B::Storage { read_only: true });
        [
            layout_entry(first, St::FRAGMENT, texture_binding(float, D::D2Array)),
            layout_entry(first + 1, St::FRAGMENT, read_only()),
            layout_entry(first + 2, St::FRAGMENT, read_only()),
            layout_entry(first + 3, St::FRAGMENT, read_only()),
        ]
    }

    /// The resources for [`CubeMaps::layout_entries`], in the same order (after `update`).
    pub fn bindings(&self) -> [wgpu::BindingResource<'_>; 4] {
        let faces = self
            .faces
            .as_ref()
            .expect("CubeMaps::update makes the faces");
        [
            wgpu::BindingResource::TextureView(&faces.view),
            self.env_views.as_entire_binding(),
            self.reflector_buffer.as_entire_binding(),
            self.mesh_reflector.as_entire_binding(),
        ]
    }

    /// Which texture holds the faces now (changes when they are made again), for bind groups
    /// that must follow them.
    pub fn faces_generation(&self) -> Option<u64> {
        self.faces.as_ref().map(|f| f.generation)
    }
}

/// Copies a face's `resolution`² texture into `layer` of `to`.
fn copy_to_layer(
    encoder: &mut wgpu::CommandEncoder,
    from: &wgpu::Texture,
    to: &wgpu::Texture,
    layer: usize,
    resolution: u32,
) {
    encoder.copy_texture_to_texture(
        from.as_image_copy(),
        wgpu::TexelCopyTextureInfo {
            texture: to,
            mip_level: 0,
            origin: wgpu::Origin3d {
                x: 0,
                y: 0,
                z: layer as u32,
            },
            aspect: wgpu::TextureAspect::All,
        },
        wgpu::Extent3d {
            width: resolution,
            height: resolution,
            depth_or_array_layers: 1,
        },
    );
}

/// One cube-map face to draw: (reflector, face, camera, the meshes it leaves out; its own
/// reflector first).
type FaceDraw = (usize, usize, CameraUniform, Vec<usize>);

/// A 2D array of `layers` cube-map faces, `resolution` texels a side, that can be copied and
/// drawn into and read, and its array view.
fn faces_texture(
    gpu: &GpuContext,
    label: &str,
    resolution: u32,
    layers: u32,
) -> (wgpu::Texture, wgpu::TextureView) {
    let texture = gpu.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: resolution,
            height: resolution,
            depth_or_array_layers: layers,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: raster::COLOR_FORMAT,
        usage: wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_DST
            | wgpu::TextureUsages::RENDER_ATTACHMENT,
        view_formats: &[],
    });
    let view = texture.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(wgpu::TextureViewDimension::D2Array),
        ..Default::default()
    });
    (texture, view)
}

/// The pipeline, bindings and camera of [`CubeMaps`]' second level: envmap's own shading pass
/// run on each face's G-buffer from the face's camera.
struct SecondLevel {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    scene_bind_group: wgpu::BindGroup,
    camera: wgpu::Buffer,
    /// For the face G-buffer (pool slot) and faces texture (generation) it binds.
    bind_group: Option<((usize, u64), wgpu::BindGroup)>,
}

impl SecondLevel {
    fn new(gpu: &GpuContext, live: &LiveScene) -> Result<SecondLevel, GpuError> {
        let device = &gpu.device;
        gpu.validated("cube maps, second level set-up", || {
            let (layout, scene_layout, pipeline) = shading_pass(device, "cube maps, second level");
            SecondLevel {
                pipeline,
                scene_bind_group: live.gpu(gpu).bind_group(gpu, &scene_layout),
                layout,
                camera: writable_buffer(
                    gpu,
                    "face camera",
                    size_of::<CameraUniform>() as u64,
                    wgpu::BufferUsages::UNIFORM,
                ),
                bind_group: None,
            }
        })
    }
}

/// The cube-map shading pass (`shade.wgsl` over a G-buffer): its bind group layout, the scene's,
/// and its pipeline; envmap's own and its cube maps' second level.
pub fn shading_pass(
    device: &wgpu::Device,
    label: &str,
) -> (
    wgpu::BindGroupLayout,
    wgpu::BindGroupLayout,
    wgpu::RenderPipeline,
) {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("cube-map shading"),
        source: wgpu::ShaderSource::Wgsl(shader_source().into()),
    });
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries: &shading_layout_entries(),
    });
    let scene_layout = GpuScene::bind_group_layout(device);
    let pipeline = raster::shading_pipeline(device, label, &module, &layout, &scene_layout);
    (layout, scene_layout, pipeline)
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

crate::choice!(Exit {
    None = "none",
    Sphere = "sphere",
    Slab = "slab",
});

/// (mesh index, centre, radius) of every specular mesh: the tightest sphere around the box
/// centre (farthest vertex, not the box's half-diagonal).
pub fn reflectors(scene: &Scene) -> Vec<(usize, Vec3, f32)> {
    scene
        .meshes
        .iter()
        .enumerate()
        .filter(|(_, m)| scene.materials[m.material].is_specular())
        .map(|(i, m)| {
            let center = m.bounds().center();
            let radius = m
                .positions
                .iter()
                .map(|p| (*p - center).length())
                .fold(0.0, f32::max);
            (i, center, radius)
        })
        .collect()
}

/// The six face cameras of a cube map around `center` that holds the whole scene.
fn face_cameras(scene: &Scene, center: Vec3, resolution: u32) -> Vec<CameraUniform> {
    let (near, far) = raster::depth_range(&scene.bounds(), center);
    raster::cube_views(center, near, far, resolution)
        .iter()
        .map(|view| {
            let forward = Vec3::from_array(view.direction);
            let up = match view.direction {
                d if d[1].abs() > 0.5 => Vec3::Z * d[1].signum(),
                _ => -Vec3::Y,
            };
            CameraUniform::new(
                center,
                forward.cross(up),
                up,
                forward,
                90.0,
                resolution,
                resolution,
                near,
                far,
            )
        })
        .collect()
}

/// The bindings `shade.wgsl` reads (group 0, bindings 0..=8): camera, the G-buffer's colour,
/// position, normal and ids, and the cube maps.
pub fn shading_layout_entries() -> Vec<wgpu::BindGroupLayoutEntry> {
    use wgpu::{
        BufferBindingType as B, ShaderStages as St, TextureSampleType as S,
        TextureViewDimension as D,
    };
    let float = S::Float { filterable: false };
    let mut entries = vec![
        layout_entry(0, St::FRAGMENT, buffer_binding(B::Uniform)),
        layout_entry(1, St::FRAGMENT, texture_binding(float, D::D2)),
        layout_entry(2, St::FRAGMENT, texture_binding(float, D::D2)),
        layout_entry(3, St::FRAGMENT, texture_binding(float, D::D2)),
        layout_entry(4, St::FRAGMENT, texture_binding(S::Uint, D::D2)),
    ];
    entries.extend(CubeMaps::layout_entries(5));
    entries
}

/// The resources for [`shading_layout_entries`], in order: the camera, the G-buffer's views
/// (`GBuffer::views`) and the cube maps.
pub fn shading_bindings<'a>(
    camera: &'a wgpu::Buffer,
    views: &'a [wgpu::TextureView; 4],
    maps: &'a CubeMaps,
) -> Vec<wgpu::BindingResource<'a>> {
    let mut entries = vec![camera.as_entire_binding()];
    entries.extend(views.iter().map(wgpu::BindingResource::TextureView));
    entries.extend(maps.bindings());
    entries
}
