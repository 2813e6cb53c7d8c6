//! `envmap`: classic dynamic environment mapping, the baseline the papers argue against.
//!
//! Paper: none (the standard technique; Umenhoffer, Patow, Szirmay-Kalos, *Robust multiple
//! specular reflections and refractions*, 2007, and Kakimoto, Tatsukawa, Chun, Nishita,
//! *Real-time reflection and refraction on a per-vertex basis*, 2008, both compare against it).
//!
//! Steps, per frame:
//! 1. the scene raster pass (G-buffer) for the camera;
//! 2. for each specular mesh (a "reflector"), a cube map of the scene rendered from the centre
//!    of its bounding box, with the reflector itself left out. The maps depend on the scene
//!    only: they are drawn again when an object moves (or every frame with `dynamic=true`, as
//!    a game redraws them for a moving scene);
//! 3. a full-screen pass that shades each specular pixel: mirrors look up the reflected
//!    direction (Schlick Fresnel or F0); dielectrics mix the reflected lookup with the
//!    transmitted one by exact Fresnel, per colour channel (so dispersion shows); thin sheets
//!    look straight through.
//!
//! Beyond the classic technique (`two_level_maps`, default true; false leaves them black, as the
//! classic maps do): other specular objects in a reflector's cube map are shaded from their own
//! cube maps (one level of envmap shading: each face is drawn twice, first with specular
//! objects black, then with them shaded from those first faces), not left black.
//!
//! Approximations and artifacts: every lookup pretends the environment is infinitely far, so
//! nearby objects appear in the wrong place and at the wrong size (exact only for a distant
//! environment, or at the centre of the cube map); specular objects in a reflector's cube map
//! show one bounce of envmap shading, and in theirs the others are black (two levels deep
//! they are); the two-interface variants leave the refractor
//! through a bounding sphere or a parallel face instead of its real back surface, and ignore
//! internal reflection.
//!
//! ## Parameters
//!
//! <!-- The parameter table: made from `Params::SPECS` by `specula_core::params::doc_table`;
//! `SPECULA_REGENERATE=1 cargo test -p specula-methods --lib doc` writes it again. -->
//! | parameter | takes | default | a change redoes | what it does |
//! |---|---|---|---|---|
//! | `resolution` | a whole number from 1 to 8192 | `256` | resources | texels per cube-map face side: sharper reflections, 6 x resolution^2 texels per reflector |
//! | `exit` | one of none, sphere, slab | `slab` | uniform | second interface of solid refractors: none, the bounding sphere, or a parallel face |
//! | `dynamic` | true or false | `false` | uniform | redraw the cube maps every frame (else only after a move) |
//! | `two_level_maps` | true or false | `true` | uniform | with two reflectors or more, shade the other specular objects a cube map shows from their own maps (two levels; else black) |
//! | `shadow_resolution` | a whole number from 1 to 8192 | `1024` | scene preparation | texels per side of the scene raster's shadow maps |
//! <!-- end of the parameter table -->
//!
//! What they change:
//! - `resolution`: texels per cube-map face side. Higher sharpens reflections;
//!   cost is 6 × resolution² rasterised texels per reflector per redraw, twice (and a shading
//!   pass per face) when the scene has two specular meshes or more and `two_level_maps` is on.
//! - `two_level_maps`: with two reflectors or more, shade the specular objects a
//!   cube map shows from their own maps (see above); false draws them black, at half the cost.
//! - `exit`: the naive second interface of solid refractors. `none` looks the
//!   environment up right after the first refraction (single interface); `sphere` refracts
//!   again where the ray leaves the bounding sphere (exact for a sphere); `slab` refracts again
//!   at a face parallel to the entry face (exact for thin shells with parallel faces). The
//!   default is the one with the lowest RMSE on the built-in refraction scenes (glass-dragon
//!   0.092 vs 0.097 none / 0.102 sphere; spectacle-lens 0.176 vs 0.191 / 0.205, at 320×240);
//!   costs are equal.
//! - `dynamic`: redraw the cube maps every frame even when nothing moved (the
//!   cost of a fully dynamic scene); otherwise they are redrawn only after a move.
//! - `shadow_resolution`: shadow maps of the scene raster (see `raster`).

use specula_core::cube_maps::{shading_bindings, shading_pass, CubeMaps, Exit, TWO_LEVEL_MAPS};
use specula_core::lifecycle::{GpuFrame, GpuMethod, GpuTechnique};
use specula_core::raster::{self, BindGroupsBySlot, RasterPass};
use specula_core::{
    Invalidates, LiveScene, MethodInfo, Param, ParamKind, TechniqueError,
};
use specula_gpu::shaders::CameraUniform;
use specula_gpu::util::{bind_group, writable_buffer};
use specula_gpu::GpuContext;

specula_core::params! {
    /// envmap's parameters (the table above).
    pub struct Params {
        resolution: u32 = Param {
            kind: ParamKind::Integer { min: 1, max: 8192 },
            default: "256",
            doc: "texels per cube-map face side: sharper reflections, 6 x resolution^2 texels per reflector",
            invalidates: Invalidates::Resources,
        },
        exit: Exit = Param {
            kind: ParamKind::Choice(Exit::WORDS),
            default: "slab",
            doc: "second interface of solid refractors: none, the bounding sphere, or a parallel face",
            invalidates: Invalidates::Uniform,
        },
        dynamic: bool = Param {
            kind: ParamKind::Flag,
            default: "false",
            doc: "redraw the cube maps every frame (else only after a move)",
            invalidates: Invalidates::Uniform,
        },
        two_level_maps: bool = TWO_LEVEL_MAPS,
        shadow_resolution: u32 = raster::SHADOW_RESOLUTION,
    }
}

pub const INFO: MethodInfo = MethodInfo {
    name: "envmap",
    summary: "classic dynamic cube-map reflection and refraction from each reflector's centre (the baseline)",
    exact: false,
    needs_gpu: true,
    gpu_optional: false,
    progressive: false,
    delegates: &[],
    params: Params::SPECS,
    presets: &[],
    create: || Box::new(GpuMethod::<EnvMap>::default()),
};

/// What depends on the scene (not on `resolution`).
pub struct Prepared {
    maps: CubeMaps,
    camera_buffer: wgpu::Buffer,
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    scene_bind_group: wgpu::BindGroup,
    /// Shading bind group per G-buffer pool slot, for the faces texture `bound_faces`.
    bind_groups: BindGroupsBySlot,
    bound_faces: Option<u64>,
}

#[derive(Default)]
pub struct EnvMap {
    pub params: Params,
}

impl EnvMap {
    pub fn new(resolution: u32, exit: Exit) -> GpuMethod<EnvMap> {
        let mut envmap = GpuMethod::<EnvMap>::default();
        envmap.params.resolution = resolution;
        envmap.params.exit = exit;
        envmap
    }
}

impl GpuTechnique for EnvMap {
    type Prepared = Prepared;
    type Params = Params;
    const INFO: &'static MethodInfo = &INFO;

    fn params(&self) -> &Params {
        &self.params
    }

    fn params_mut(&mut self) -> &mut Params {
        &mut self.params
    }

    fn prepare(
        &mut self,
        gpu: &GpuContext,
        live: &LiveScene,
        _: Option<&RasterPass>,
    ) -> Result<Prepared, TechniqueError> {
        Ok(gpu.validated("envmap set-up", || {
            let (layout, scene_layout, pipeline) = shading_pass(&gpu.device, "envmap shade");
            Prepared {
                scene_bind_group: live.gpu(gpu).bind_group(gpu, &scene_layout),
                maps: CubeMaps::new(gpu, live.scene()),
                camera_buffer: writable_buffer(
                    gpu,
                    "camera",
                    size_of::<CameraUniform>() as u64,
                    wgpu::BufferUsages::UNIFORM,
                ),
                pipeline,
                layout,
                bind_groups: BindGroupsBySlot::default(),
                bound_faces: None,
            }
        })?)
    }

    fn invalidate(&mut self, prepared: Option<&mut Prepared>, what: Invalidates) -> bool {
        if let (Some(p), true) = (prepared, what >= Invalidates::Resources) {
            p.maps.drop_faces();
        }
        true
    }

    /// The classic technique's steps after the G-buffer: the cube maps, then the shading.
    fn shade(&mut self, p: &mut Prepared, frame: &mut GpuFrame<'_>) -> Result<(), TechniqueError> {
        let faces_drawn = self.environment_maps(p, frame)?;
        frame.lap("environment cube maps")?;
        shade_from_maps(p, frame)?;
        frame.lap("shading")?;
        let resolution = self.params.resolution as u64;
        frame.count("reflectors", p.maps.reflectors.len() as u64);
        frame.count("cube map faces rendered", faces_drawn);
        frame.count("cube map texels", faces_drawn * resolution.pow(2));
        frame.count("raster passes", 1 + faces_drawn);
        Ok(())
    }
}

impl EnvMap {
    /// Step 2: each reflector's cube map, drawn again where the scene moved (or every frame
    /// with `dynamic`). Returns the faces drawn.
    fn environment_maps(
        &self,
        p: &mut Prepared,
        frame: &GpuFrame<'_>,
    ) -> Result<u64, TechniqueError> {
        let params = &self.params;
        p.maps.set_two_levels(params.two_level_maps);
        let faces_drawn = p.maps.update(
            frame.gpu,
            frame.raster(),
            frame.live,
            params.resolution,
            params.exit,
            params.dynamic,
        )?;
        if p.bound_faces != p.maps.faces_generation() {
            p.bind_groups.clear();
            p.bound_faces = p.maps.faces_generation();
        }
        Ok(faces_drawn)
    }
}

/// Step 3: every specular pixel of the G-buffer shaded from the cube maps.
fn shade_from_maps(p: &mut Prepared, frame: &GpuFrame<'_>) -> Result<(), TechniqueError> {
    let (gpu, g) = (frame.gpu, frame.g());
    Ok(gpu.validated("envmap shade", || {
        gpu.queue.write_buffer(
            &p.camera_buffer,
            0,
            bytemuck::bytes_of(&frame.camera_uniform),
        );
        let group = p.bind_groups.get_or_make(frame.raster(), g, || {
            let views = g.views();
            let entries = shading_bindings(&p.camera_buffer, &views, &p.maps);
            bind_group(gpu, "envmap", &p.layout, &entries)
        });
        raster::fullscreen_pass(
            gpu,
            "envmap shade",
            &p.pipeline,
            &[group, &p.scene_bind_group],
            frame.output(),
        )
    })?)
}
