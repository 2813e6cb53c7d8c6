//! `distance-maps`: multiple specular reflections and refractions traced in layered distance cube
//! maps.
//!
//! Paper: Umenhoffer, Patow, Szirmay-Kalos, *Robust multiple specular reflections and refractions*,
//! GPU Gems 3, ch. 17, 2007.
//!
//! Steps, per frame (the paper's; by default the steps beyond the paper, below, replace parts of
//! step 4):
//! 1. the scene raster pass (G-buffer) for the camera;
//! 2. for each specular mesh (a "reflector"), a layered distance map about its reference point (the
//!    centre of its bounding box): per layer six 90° faces, each texel holding the material
//!    (diffuse radiance, or F0 with the sign-coded index of refraction, see `codes.wgsl`), the
//!    surface normal, the mesh, and the distance from the reference point; texels that see nothing
//!    hold distance -1. Layers come from depth peeling (`layers=N`: the N nearest surfaces in each
//!    direction; what lies beyond the N-th is lost) or from the paper's simplified layers
//!    (`layers=simple`: the front faces of all specular meshes as seen from the reference point,
//!    their back faces, then the non-specular surfaces, depth-peeled into `diffuse_layers`). The
//!    paper redraws the maps every frame (`dynamic=true`);
//! 3. with min-max acceleration, the smallest and largest distance of each layer (a compute
//!    reduction);
//! 4. a full-screen pass over the reflector pixels traces each reflected or refracted ray in the
//!    reflector's map (the paper's `Hit()`): per layer, a linear search marching uniformly in
//!    texture space (`d = a·t/(1 − t)`, the step count following the texels the ray spans, at most
//!    `linear_steps`), from the listing's t = 0.0001 up to the map's far sphere, or between the
//!    layer's min and max spheres (each widened by 0.01 % against rounding), restarting where
//!    nothing is visible; then the secant search in the layer with the nearest overshooting sample.
//!    The far sphere stands in for the listing's t → 1: the ray's end at infinity cannot be
//!    sampled, and a sample on the sphere that holds the whole scene lies behind every surface as
//!    the paper's last samples do. At a specular hit the path reflects (a mirror; Schlick's
//!    Fresnel, or exactly F0 for a mirror whose material has no Fresnel term, as the reference) or
//!    refracts (a dielectric, weighted by 1 − F of Schlick's formula at the incident angle on
//!    either side, as Listing 17-5; reflected under total internal reflection) with the normal
//!    stored in the map, up to `max_depth` rays; at a diffuse hit it takes the stored radiance. A
//!    thin-walled sheet (a material the paper does not have) passes the ray straight on, weighted
//!    by 1 − its two-interface reflectance 2F/(1 + F).
//!
//! Where the listings are silent, this implementation chooses (for every setting unless a step
//! beyond the paper below replaces the choice): the maps are read bilinearly (the paper
//! interpolates between directions) over the texels that see something, the nearest texel deciding
//! whether anything is visible and giving the material code (blending in the clear value -1 would
//! sink every edge of a layer towards the reference point, and blending codes would invent
//! materials); a lookup beside a cube face's edge reuses that face's edge texels, as non-seamless
//! cube maps of the paper's hardware did; the secant search stops at a sample where the map shows
//! nothing (Listing 17-2 would divide by the clear value); a ray whose search finds no bracket in
//! any layer meets the background (with plain interpolation that happens only where the map shows
//! nothing along the ray's end: it left the scene); a dispersive material is traced with its green
//! index (the paper stores one index per texel).
//!
//! The figures below are mean FLIP on the suite at 160 × 120, default → the step alone switched
//! off (`specula compare scenes/suite --methods distance-maps -p NAME=VALUE -W 160 -H 120`); the
//! `paper` preset, everything off at depth 2, measures 0.012 (mirror-sphere) to 0.77 (glass-block).
//!
//! Beyond the paper (each switched off by the `paper` preset; `specula methods` lists it):
//! - every layer's bracket is refined and the nearest refined hit wins
//!   (paper: `refine_every_layer=false`); the paper refines only the layer with the nearest
//!   overshooting sample, which can lie past another layer's hit where steps are long (lit-room
//!   0.047 → 0.048, mirrors-merged 0.0210 → 0.0213, the rest unchanged);
//! - distances, radiance and normals are interpolated only between texels of one mesh, and a
//!   bracket whose two samples show different meshes counts only where the ray passes the second
//!   mesh's distance (from in front of it to behind it), taking the overshooting sample as the hit;
//!   otherwise the search starts over (paper: `interpolation=plain`): a ray that goes round an
//!   object's silhouette, behind it as seen from the reference point, no longer hits the surface
//!   the paper's interpolation spans between the two objects. It pays on concave-mirror (0.053 →
//!   0.078) and costs on most other scenes of the suite (mirror-bunny 0.052 → 0.045,
//!   mirror-sphere-nearby 0.042 → 0.034, glass-sphere 0.019 → 0.017);
//! - the search along each secondary ray starts 2 / `resolution` of |x| away from its start
//!   (paper: `skip_start=false`, the listing's t = 0.0001), so that the interpolated copy of the
//!   surface a ray leaves is not taken for its hit (without it: mirror-bunny 0.052 → 0.065,
//!   thin-sheet 0.105 → 0.156; worse with coarser maps: a mirror sphere in a box at 128², RMSE 0.02
//!   → 0.19);
//! - at every dielectric surface both branches are traced, reflected and refracted
//!   (paper: `dielectric_branches=refracted`); Listing 17-5 follows only the refracted one, so the
//!   first surface's reflection and the light reflected inside a glass object are missing
//!   (glass-sphere 0.019 → 0.235, glass-lens 0.025 → 0.158, glass-block 0.066 → 0.218). A per-pixel
//!   stack of 8 branches holds the paths still to trace; branches carrying under 0.4 % of the pixel
//!   are dropped; a thin-walled sheet also reflects;
//! - the Fresnel terms at dielectrics are exact (paper: `dielectric_fresnel=schlick`), where the
//!   paper applies Schlick's approximation, at the incident angle also inside the glass (Schlick:
//!   glass-sphere 0.019 → 0.064, glass-merged 0.025 → 0.056);
//! - dispersive materials are traced once per colour channel (paper: `dispersion=false`);
//! - a ray the search does not resolve, where the map holds a diffuse surface towards the point
//!   where the ray leaves the map's far sphere, takes the farthest diffuse surface the map holds
//!   towards that exit point (an environment-map estimate, off by parallax for near surfaces), and
//!   a branch at `max_depth` or with no room on the stack takes the same estimate in the direction
//!   it would leave in (paper: `estimate=false`). Without it the missed ray meets the background,
//!   and a path cut at the depth limit ends with its product of Fresnel factors, as if the surface
//!   it stops at sent radiance 1: what Listing 17-5 returns when its depth runs out (a cut path
//!   then shows white where the reference shows the further bounces: glass-block 0.066 → 0.280,
//!   glass-lens 0.025 → 0.126, concave-mirror 0.053 → 0.095). Each is counted in the frame's
//!   counters (`rays not resolved`, `branches cut at max_depth`, `branches over the stack`) and
//!   named in a warning. The estimate helps in closed scenes (the suite's lens 0.069 → 0.030 mean
//!   FLIP, against a missed ray meeting the background) and hurts in open ones where the missed ray
//!   did leave the scene (mirror-teapot-bunny 0.046 → 0.060, truck-cover 0.148 → 0.183): a ray that
//!   passes behind an object as seen from the reference point looks, in the map, like one that
//!   stepped over it (docs/methods/distance-maps.md).
//!
//! Implementation (changes no pixel): with `dynamic=false` the maps and their min-max ranges are
//! kept until an object moves instead of being redrawn every frame (they would come out the same);
//! the counters and warnings only report.
//!
//! Approximations and artifacts:
//! - sampling: each layer is a height field about the reference point, sampled at `resolution`; the
//!   distance is interpolated bilinearly, so a hit is exact on planes (the secant step; the tests
//!   measure 4e-5 m on a 2 m box at 128²) and off by the interpolation error elsewhere; radiance
//!   and normals are interpolated too, so textures blur at the map's resolution; with per-mesh
//!   interpolation a hit found between two meshes is accurate to one linear step;
//! - limited layers: surfaces beyond the last layer in a direction are missing; reflections that
//!   should see them see the layer in front, or nothing (then the background);
//! - thin objects: the linear search can step over a surface thinner than its step (the paper's
//!   Figure 17-6); fewer `linear_steps` miss more;
//! - diffuse radiance is stored as seen from the reference point: exact for Lambertian and unlit
//!   surfaces (their radiance does not depend on direction), with the raster pass's shadow maps;
//! - paths longer than `max_depth` end as `estimate` says; the reference follows them to its own
//!   depth (8 in `compare`).
//!
//! ## Parameters
//!
//! <!-- The parameter table: made from `Params::SPECS` by `specula_core::params::doc_table`;
//! `SPECULA_REGENERATE=1 cargo test -p specula-methods --lib doc` writes it again. -->
//! | parameter | takes | default | a change redoes | what it does |
//! |---|---|---|---|---|
//! | `resolution` | a whole number from 1 to 8192 | `512` | resources | texels per face side: finer geometry and more exact hits; 6 x resolution^2 texels per layer |
//! | `layers` | one of simple, 1, 2, 3, 4, 5, 6, 7, 8 | `simple` | resources | the paper's three layers (simple) or that many depth-peeled layers |
//! | `diffuse_layers` | a whole number from 1 to 6 | `1` | resources | with layers=simple, depth-peeled layers of the non-specular surfaces |
//! | `linear_steps` | a whole number from 1 to 1000 | `80` | uniform | most linear-search steps per layer; fewer miss thin objects |
//! | `secant_steps` | a whole number from 0 to 100 | `10` | uniform | secant iterations after the linear search (0: its overshooting sample is the hit) |
//! | `max_depth` | a whole number from 1 to 16 | `4` | uniform | most specular bounces on a path (deeper branches take the map's estimate) |
//! | `min_max` | true or false | `true` | uniform | min-max acceleration: march only between each layer's nearest and farthest distance |
//! | `skip_start` | true or false | `true` | uniform | start each secondary ray's search 2/resolution of \|x\| away (false: the paper's t = 0.0001) |
//! | `refine_every_layer` | true or false | `true` | uniform | refine every layer's bracket, nearest refined hit wins (false: the paper's layer with the nearest overshoot only) |
//! | `interpolation` | one of mesh, plain | `mesh` | uniform | mesh: interpolate within one mesh, brackets across meshes only where the ray passes the second; plain: the paper's |
//! | `dielectric_branches` | one of both, refracted | `both` | uniform | trace reflected and refracted branches at glass (refracted: the paper's single path) |
//! | `dielectric_fresnel` | one of exact, schlick | `exact` | uniform | Fresnel terms at glass: exact, or the paper's Schlick approximation |
//! | `dispersion` | true or false | `true` | uniform | trace dispersive glass once per colour channel (false: the green index, as the paper's one index) |
//! | `estimate` | true or false | `true` | uniform | unresolved rays and cut branches take the map's estimate (false: background, and the paper's path weight) |
//! | `output` | one of radiance, first-hit | `radiance` | uniform | first-hit writes each reflector pixel's first secondary hit position instead |
//! | `dynamic` | true or false | `false` | uniform | redraw the maps every frame (else only after a move) |
//! | `shadow_resolution` | a whole number from 1 to 8192 | `1024` | scene preparation | texels per side of the scene raster's shadow maps |
//! <!-- end of the parameter table -->
//!
//! What they change:
//! - `resolution` ((paper: `resolution=512`), its cube maps): texels per face side.
//!   Higher resolves finer geometry and texture and makes hits more exact; cost 6 × resolution²
//!   texels per layer per reflector per frame, and longer linear searches (steps follow the texels
//!   a ray spans).
//! - `layers` ((paper: `layers=simple`), its implementation): `simple`, or a
//!   number 1 to 8 of depth-peeled layers. More layers capture surfaces hidden from the reference
//!   point; each costs a rasterisation of the scene into six faces and a linear search per ray.
//! - `diffuse_layers` ((paper: `diffuse_layers=1`), all diffuse surfaces in one layer):
//!   with `layers=simple`, the non-specular surfaces in this many depth-peeled layers (1 to 6); the
//!   same trade-off.
//! - `linear_steps` ((paper: `linear_steps=80`), the finest of its Figure 17-6): the
//!   most steps of a linear search per layer (fewer where a ray spans fewer texels). Fewer miss
//!   thin objects and leave stair steps the secant search cannot always recover; cost is linear.
//! - `secant_steps` ((paper: `secant_steps=10`), the finest of its Figure 17-6): secant
//!   iterations after the linear search (0: the linear search's overshooting sample is the hit).
//!   Removes stair-stepping; exact on planes in one.
//! - `max_depth` ((paper: `max_depth=2`), the paper's video): the most specular bounces
//!   on a path, the surface the camera sees being the first (the paper's MAXDEPTH). Each costs one
//!   more trace, only on paths that need it; a glass object needs 3 or more (in, reflected inside,
//!   out): on the suite's glass sphere mean FLIP 0.098 at 2, 0.027 at 3, 0.020 at 4, 0.020 at 8
//!   (320 × 240); at 2 on the suite at 160 × 120, glass-block 0.066 → 0.229, glass-sphere 0.019 →
//!   0.061.
//! - `min_max` ((paper: `min_max=true`), its 50 fps video): min-max acceleration;
//!   marches only between each layer's smallest and largest distance (fewer steps wasted and finer
//!   steps where surfaces are; the paper: 25 → 50 fps); costs a reduction over the maps.
//! - `dynamic` ((paper: `dynamic=true`), its maps "were updated in every frame"):
//!   redraw the maps (and their min-max ranges) every frame even when nothing moved; otherwise only
//!   after a move. Changes the cost, not the image.
//! - `refine_every_layer`: see Beyond the paper; costs a secant search per layer
//!   with a bracket instead of one.
//! - `interpolation`: `mesh` or `plain`, see Beyond the paper; `plain` draws
//!   surfaces spanned between objects at silhouettes.
//! - `skip_start`: see Beyond the paper; without it rays can hit the interpolated
//!   copy of the surface they leave.
//! - `dielectric_branches`: `both` or `refracted`, see Beyond the paper; both cost
//!   a second trace per dielectric surface on the path (up to the stack).
//! - `dielectric_fresnel`: `exact` or `schlick`; no cost difference.
//! - `dispersion`: a dispersive scene costs three traces per glass pixel.
//! - `estimate`: see Beyond the paper; costs a lookup per layer for each unresolved
//!   ray and cut branch.
//! - `output`: `first-hit` writes, instead of radiance, the world position
//!   where each reflector pixel's first secondary ray hits (-1e30 where it finds nothing), to check
//!   the search.
//! - `shadow_resolution`: the raster pass's shadow maps.

use bytemuck::{Pod, Zeroable};
use specula_gpu::counters::Counters;
use specula_gpu::shaders;
use specula_gpu::util::bind_group;
use specula_gpu::GpuContext;

use specula_core::lifecycle::{GpuFrame, GpuMethod, GpuTechnique};
use specula_core::live_scene::LiveScene;
use specula_core::raster::{self, BindGroupsBySlot, RasterPass, CUBE_FACES};
use specula_core::{
    Invalidates, MethodInfo, Param, ParamKind, ParamType, ParamValue, TechniqueError,
};

mod maps;
mod pipelines;

use pipelines::array_view;

/// The tracing pass's fallback counters, in trace.wgsl's order: counter name, and what the
/// rays are in a warning.
const FALLBACK_KINDS: [(&str, &str); 3] = [
    (
        "rays not resolved",
        "rays found no surface where the map holds one",
    ),
    (
        "branches cut at max_depth",
        "path branches reached max_depth at a mirror or glass surface",
    ),
    (
        "branches over the stack",
        "path branches found no room on the per-pixel stack",
    ),
];

specula_core::params! {
    /// distance-maps' parameters (the table above).
    pub struct Params {
        resolution: u32 = Param {
            kind: ParamKind::Integer { min: 1, max: 8192 },
            default: "512",
            doc: "texels per face side: finer geometry and more exact hits; 6 x resolution^2 texels per layer",
            invalidates: Invalidates::Resources,
        },
        layers: Layers = Param {
            kind: ParamKind::Choice(&["simple", "1", "2", "3", "4", "5", "6", "7", "8"]),
            default: "simple",
            doc: "the paper's three layers (simple) or that many depth-peeled layers",
            invalidates: Invalidates::Resources,
        },
        diffuse_layers: u32 = Param {
            kind: ParamKind::Integer { min: 1, max: 6 },
            default: "1",
            doc: "with layers=simple, depth-peeled layers of the non-specular surfaces",
            invalidates: Invalidates::Resources,
        },
        linear_steps: u32 = Param {
            kind: ParamKind::Integer { min: 1, max: 1000 },
            default: "80",
            doc: "most linear-search steps per layer; fewer miss thin objects",
            invalidates: Invalidates::Uniform,
        },
        secant_steps: u32 = Param {
            kind: ParamKind::Integer { min: 0, max: 100 },
            default: "10",
            doc: "secant iterations after the linear search (0: its overshooting sample is the hit)",
            invalidates: Invalidates::Uniform,
        },
        max_depth: u32 = Param {
            kind: ParamKind::Integer { min: 1, max: 16 },
            default: "4",
            doc: "most specular bounces on a path (deeper branches take the map's estimate)",
            invalidates: Invalidates::Uniform,
        },
        min_max: bool = Param {
            kind: ParamKind::Flag,
            default: "true",
            doc: "min-max acceleration: march only between each layer's nearest and farthest distance",
            invalidates: Invalidates::Uniform,
        },
        skip_start: bool = Param {
            kind: ParamKind::Flag,
            default: "true",
            doc: "start each secondary ray's search 2/resolution of |x| away (false: the paper's t = 0.0001)",
            invalidates: Invalidates::Uniform,
        },
        refine_every_layer: bool = Param {
            kind: ParamKind::Flag,
            default: "true",
            doc: "refine every layer's bracket, nearest refined hit wins (false: the paper's layer with the nearest overshoot only)",
            invalidates: Invalidates::Uniform,
        },
        interpolation: Interpolation = Param {
            kind: ParamKind::Choice(Interpolation::WORDS),
            default: "mesh",
            doc: "mesh: interpolate within one mesh, brackets across meshes only where the ray passes the second; plain: the paper's",
            invalidates: Invalidates::Uniform,
        },
        dielectric_branches: Branches = Param {
            kind: ParamKind::Choice(Branches::WORDS),
            default: "both",
            doc: "trace reflected and refracted branches at glass (refracted: the paper's single path)",
            invalidates: Invalidates::Uniform,
        },
        dielectric_fresnel: DielectricFresnel = Param {
            kind: ParamKind::Choice(DielectricFresnel::WORDS),
            default: "exact",
            doc: "Fresnel terms at glass: exact, or the paper's Schlick approximation",
            invalidates: Invalidates::Uniform,
        },
        dispersion: bool = Param {
            kind: ParamKind::Flag,
            default: "true",
            doc: "trace dispersive glass once per colour channel (false: the green index, as the paper's one index)",
            invalidates: Invalidates::Uniform,
        },
        estimate: bool = Param {
            kind: ParamKind::Flag,
            default: "true",
            doc: "unresolved rays and cut branches take the map's estimate (false: background, and the paper's path weight)",
            invalidates: Invalidates::Uniform,
        },
        output: Output = Param {
            kind: ParamKind::Choice(Output::WORDS),
            default: "radiance",
            doc: "first-hit writes each reflector pixel's first secondary hit position instead",
            invalidates: Invalidates::Uniform,
        },
        dynamic: bool = Param {
            kind: ParamKind::Flag,
            default: "false",
            doc: "redraw the maps every frame (else only after a move)",
            invalidates: Invalidates::Uniform,
        },
        shadow_resolution: u32 = raster::SHADOW_RESOLUTION,
    }
}

pub const INFO: MethodInfo = MethodInfo {
    name: "distance-maps",
    summary: "layered distance cube maps with linear + secant search (Umenhoffer et al.): multiple reflections and refractions",
    exact: false,
    needs_gpu: true,
    gpu_optional: false,
    progressive: false,
    delegates: &[],
    params: Params::SPECS,
    presets: &[specula_core::Preset {
        name: "paper",
        summary: "the published algorithm (Umenhoffer, Patow, Szirmay-Kalos 2007) at its published settings (the video's depth 2, maps redrawn every frame): every step beyond the paper off",
        settings: &[
            "resolution=512",
            "layers=simple",
            "diffuse_layers=1",
            "linear_steps=80",
            "secant_steps=10",
            "max_depth=2",
            "min_max=true",
            "dynamic=true",
            "skip_start=false",
            "refine_every_layer=false",
            "interpolation=plain",
            "dielectric_branches=refracted",
            "dielectric_fresnel=schlick",
            "dispersion=false",
            "estimate=false",
        ],
    }],
    create: || Box::new(GpuMethod::<DistanceMaps>::default()),
};

const CODES: &str = include_str!("codes.wgsl");
const LAYERS_SHADER: &str = include_str!("layers.wgsl");
const RANGES_SHADER: &str = include_str!("ranges.wgsl");
const TRACE_SHADER: &str = include_str!("trace.wgsl");

/// The layer pass's full source.
pub fn layers_shader_source() -> String {
    shaders::compose(
        &["camera.wgsl", "scene.wgsl", "cubemap.wgsl", "lighting.wgsl"],
        &format!("{CODES}\n{LAYERS_SHADER}"),
    )
}

/// The min-max reduction's source.
pub fn ranges_shader_source() -> String {
    RANGES_SHADER.to_string()
}

/// The tracing pass's full source.
pub fn trace_shader_source() -> String {
    shaders::compose(
        &[
            "optics.wgsl",
            "camera.wgsl",
            "scene.wgsl",
            "cubemap.wgsl",
            "specular_pixel.wgsl",
        ],
        &format!("{CODES}\n{TRACE_SHADER}"),
    )
}

const MAP_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba32Float;

/// How a reflector's map is split into layers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layers {
    /// The paper's simplified layers: specular front faces, specular back faces, then the
    /// non-specular surfaces (the paper: one layer; more are depth-peeled).
    Simple,
    /// Depth peeling: the given number of nearest surfaces per direction.
    Peeled(u32),
}

impl ParamType for Layers {
    fn from_param(value: &ParamValue) -> Result<Self, String> {
        match value.word() {
            "simple" => Ok(Layers::Simple),
            n => n
                .parse()
                .map(Layers::Peeled)
                .map_err(|_| format!("expected simple or a layer count, not {n}")),
        }
    }
    fn to_param(&self) -> String {
        match self {
            Layers::Simple => "simple".to_string(),
            Layers::Peeled(n) => n.to_string(),
        }
    }
}

impl DistanceMaps {
    /// Layers per reflector map.
    pub fn layer_count(&self) -> u32 {
        match self.params.layers {
            Layers::Simple => 2 + self.params.diffuse_layers,
            Layers::Peeled(n) => n,
        }
    }
}

/// How the map's texels are interpolated, and which brackets a linear search accepts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    /// Only between texels of one mesh; a bracket across two meshes only where the ray passes
    /// the second one's distance (see the module doc).
    Mesh,
    /// The paper's: between all visible texels, every bracket.
    Plain,
}

specula_core::choice!(Interpolation {
    Mesh = "mesh",
    Plain = "plain",
});

/// Which branches a path follows at a dielectric.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Branches {
    /// Reflected and refracted.
    Both,
    /// The refracted one only, as the paper.
    Refracted,
}

specula_core::choice!(Branches {
    Both = "both",
    Refracted = "refracted",
});

/// The Fresnel terms at a dielectric.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DielectricFresnel {
    Exact,
    /// Schlick's approximation, as the paper.
    Schlick,
}

specula_core::choice!(DielectricFresnel {
    Exact = "exact",
    Schlick = "schlick",
});

/// What the tracing pass writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Output {
    Radiance = 0,
    /// World position of the first secondary hit (see the module doc).
    FirstHit = 1,
}

specula_core::choice!(Output {
    Radiance = "radiance",
    FirstHit = "first-hit",
});

/// Host mirror of WGSL `LayerView` (layers.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuLayerView {
    pub clip_from_world: [[f32; 4]; 4],
    pub origin: [f32; 3],
    pub select: u32,
    pub peel: u32,
    pub pad: [u32; 3],
}

const KEEP_ALL: u32 = 0;
const KEEP_SPECULAR_FACING: u32 = 1;
const KEEP_SPECULAR_AWAY: u32 = 2;
const KEEP_NON_SPECULAR: u32 = 3;

/// Host mirror of WGSL `TraceSettings` (trace.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuTraceSettings {
    pub layers: u32,
    pub linear_steps: u32,
    pub secant_steps: u32,
    pub max_depth: u32,
    pub min_max: u32,
    pub dispersive: u32,
    pub output: u32,
    pub resolution: f32,
    pub skip_start: u32,
    pub refine_every_layer: u32,
    pub per_mesh: u32,
    pub both_branches: u32,
    pub exact_fresnel: u32,
    pub estimate: u32,
    pub pad: [u32; 2],
}

/// Host mirror of WGSL `MapReflector`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuMapReflector {
    pub origin: [f32; 3],
    pub first_map: u32,
    pub far: f32,
    pub pad: [u32; 3],
}

/// Host mirror of WGSL `Face`: a cube face's right, up and forward (w unused).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuFace {
    pub right: [f32; 4],
    pub up: [f32; 4],
    pub forward: [f32; 4],
}

/// The bases the faces are rendered with (`Mat4::look_to_rh` of [`CUBE_FACES`]).
pub fn face_bases() -> [GpuFace; 6] {
    CUBE_FACES.map(|(forward, up)| {
        let right = forward.cross(up).normalize();
        let up = right.cross(forward);
        GpuFace {
            right: right.extend(0.0).to_array(),
            up: up.extend(0.0).to_array(),
            forward: forward.extend(0.0).to_array(),
        }
    })
}

/// One face of one layer of one reflector's map.
struct LayerDraw {
    /// Its `GpuLayerView`, rewritten when the reflector moves.
    view_buffer: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    material_target: wgpu::TextureView,
    geometry_target: wgpu::TextureView,
    /// Vertex ranges of the meshes the layer can hold.
    vertex_ranges: Vec<std::ops::Range<u32>>,
}

pub struct Prepared {
    /// The scene version the layer views and reflector origins were made for.
    version: u64,
    /// The scene version the maps were drawn at (None: not yet).
    maps_drawn_at: Option<u64>,
    /// The scene version of the maps the min-max ranges were reduced from.
    ranges_at: Option<u64>,
    reflectors: Vec<usize>,
    material_maps: wgpu::Texture,
    geometry_maps: wgpu::Texture,
    depth: wgpu::TextureView,
    draws: Vec<LayerDraw>,
    layer_pipeline: wgpu::RenderPipeline,
    /// Bind group 1 of both the layer and the tracing pass.
    scene_bind_group: wgpu::BindGroup,
    range_pipeline: wgpu::ComputePipeline,
    range_bind_group: wgpu::BindGroup,
    ranges: wgpu::Buffer,
    map_count: u32,
    trace_pipeline: wgpu::RenderPipeline,
    trace_layout: wgpu::BindGroupLayout,
    settings: wgpu::Buffer,
    reflector_buffer: wgpu::Buffer,
    mesh_reflector: wgpu::Buffer,
    faces: wgpu::Buffer,
    camera_buffer: wgpu::Buffer,
    /// Tracing bind group per G-buffer pool slot.
    trace_bind_groups: BindGroupsBySlot,
    /// Fallbacks the tracing pass took (trace.wgsl's FALLBACK_*).
    fallbacks: Counters,
}

#[derive(Default)]
pub struct DistanceMaps {
    pub params: Params,
}

impl GpuTechnique for DistanceMaps {
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
        raster: Option<&RasterPass>,
    ) -> Result<Prepared, TechniqueError> {
        self.build(gpu, live, raster.expect("declared by scene_raster"))
    }

    // The maps and most passes follow the resolution and layer count: the default rebuilds
    // the whole preparation on a change of resources.

    /// The paper's steps after the G-buffer: the layered distance maps (drawn again after a
    /// move), their min-max ranges, then each pixel's paths traced through them.
    fn shade(&mut self, p: &mut Prepared, frame: &mut GpuFrame<'_>) -> Result<(), TechniqueError> {
        let (gpu, live) = (frame.gpu, frame.live);
        self.place_for(p, gpu, live);
        gpu.queue.write_buffer(
            &p.settings,
            0,
            bytemuck::bytes_of(&self.trace_settings(live)),
        );
        let faces = self.distance_maps(p, frame)?;
        p.fallbacks.clear(gpu);
        gpu.validated("distance-map trace", || trace(gpu, p, frame))?;
        frame.lap("tracing")?;
        self.report(p, frame, faces)
    }
}

impl DistanceMaps {
    /// The tracing pass's settings for this frame.
    fn trace_settings(&self, live: &LiveScene) -> GpuTraceSettings {
        let params = &self.params;
        let dispersive = live.scene().materials.iter().any(|m| m.is_dispersive());
        GpuTraceSettings {
            layers: self.layer_count(),
            linear_steps: params.linear_steps,
            secant_steps: params.secant_steps,
            max_depth: params.max_depth,
            min_max: u32::from(params.min_max),
            dispersive: u32::from(params.dispersion && dispersive),
            output: params.output as u32,
            resolution: params.resolution as f32,
            skip_start: u32::from(params.skip_start),
            refine_every_layer: u32::from(params.refine_every_layer),
            per_mesh: u32::from(params.interpolation == Interpolation::Mesh),
            both_branches: u32::from(params.dielectric_branches == Branches::Both),
            exact_fresnel: u32::from(params.dielectric_fresnel == DielectricFresnel::Exact),
            estimate: u32::from(params.estimate),
            pad: [0; 2],
        }
    }

    /// The layered maps, drawn again after a move (or every frame with `dynamic`), and their
    /// min-max ranges reduced again after them. Returns the faces drawn.
    fn distance_maps(
        &self,
        p: &mut Prepared,
        frame: &mut GpuFrame<'_>,
    ) -> Result<u64, TechniqueError> {
        let (gpu, live) = (frame.gpu, frame.live);
        let redraw = self.params.dynamic || p.maps_drawn_at != Some(live.version());
        let faces = if redraw { p.draws.len() as u64 } else { 0 };
        if redraw {
            let raster = frame.raster();
            gpu.validated("distance-map layers", || {
                p.draw_maps(gpu, live.gpu(gpu), raster)
            })?;
            frame.lap("distance maps")?;
            p.maps_drawn_at = Some(live.version());
        }
        if self.params.min_max && (redraw || p.ranges_at != p.maps_drawn_at) {
            gpu.validated("distance-map ranges", || p.reduce_ranges(gpu))?;
            frame.lap("min-max")?;
            p.ranges_at = p.maps_drawn_at;
        }
        Ok(faces)
    }

    /// The frame's counters, and a warning for each kind of fallback the tracing took.
    fn report(
        &self,
        p: &Prepared,
        frame: &mut GpuFrame<'_>,
        faces: u64,
    ) -> Result<(), TechniqueError> {
        let fallbacks = p.fallbacks.read(frame.gpu)?;
        frame.count("reflectors", p.reflectors.len() as u64);
        frame.count("layers per map", self.layer_count() as u64);
        frame.count("cube map faces rendered", faces);
        frame.count(
            "distance map texels",
            faces * (self.params.resolution as u64).pow(2),
        );
        frame.count("raster passes", 1 + faces);
        for (kind, ((name, what), &count)) in FALLBACK_KINDS.iter().zip(&fallbacks).enumerate() {
            frame.count(name, count as u64);
            if count > 0 {
                let taken = match (self.params.estimate, kind) {
                    (true, _) => {
                        "they take the farthest diffuse surface the map holds in their direction (an estimate)"
                    }
                    (false, 0) => "they meet the background (estimate=false)",
                    (false, _) => {
                        "they end with their weight so far, as if the surface they stop at sent radiance 1 (estimate=false, the paper's Listing 17-5)"
                    }
                };
                frame.warn(format!("distance-maps: {count} {what}; {taken}"));
            }
        }
        Ok(())
    }
}

/// The tracing pass over the G-buffer, into `output`.
fn trace(ctx: &GpuContext, p: &mut Prepared, frame: &GpuFrame<'_>) {
    let g = frame.g();
    ctx.queue.write_buffer(
        &p.camera_buffer,
        0,
        bytemuck::bytes_of(&frame.camera_uniform),
    );
    let group = p.trace_bind_groups.get_or_make(frame.raster(), g, || {
        let [color, position, normal, ids] = g.views();
        let views = [
            color,
            position,
            normal,
            ids,
            array_view(&p.material_maps),
            array_view(&p.geometry_maps),
        ];
        let mut resources = vec![
            p.camera_buffer.as_entire_binding(),
            p.settings.as_entire_binding(),
        ];
        resources.extend(views.iter().map(wgpu::BindingResource::TextureView));
        resources.extend(
            [
                &p.reflector_buffer,
                &p.mesh_reflector,
                &p.ranges,
                &p.faces,
                &p.fallbacks.buffer,
            ]
            .map(|b| b.as_entire_binding()),
        );
        bind_group(ctx, "distance-map trace", &p.trace_layout, &resources)
    });
    raster::fullscreen_pass(
        ctx,
        "distance-map trace",
        &p.trace_pipeline,
        &[group, &p.scene_bind_group],
        frame.output(),
    )
}

#[cfg(test)]
mod tests;
