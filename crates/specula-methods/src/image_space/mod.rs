//! `image-space`: two-interface image-space refraction of nearby geometry.
//!
//! Paper: Wyman, *Interactive image-space refraction of nearby geometry*, 2005, building on
//! Wyman's two-interface image-space refraction of the same year.
//!
//! The paper's steps and where they are:
//! - **Precompute d_N** at each vertex (§3): [`normal_distances`], a ray cast along the
//!   inverted normal through the BVH against the refractor's own surface only (other objects
//!   inside or behind it are passed through).
//! - **First pass** (§3): the refractors' back faces, normals and positions (a [`RasterPass`]
//!   whose spec culls front faces).
//! - **Second pass** (§4.1–4.2): the nearby-geometry (NG) texture, the non-specular scene drawn
//!   from the eye without the refractors (colour, position, hence depth; a [`RasterPass`]).
//! - **Final pass** (`image_space.wgsl`, `fs_shade`, a full-screen pass over the scene's
//!   G-buffer; `refracted` is steps A–F): A. T1 from V and N1; B. d_V to the back face under
//!   the pixel; C. d̃ = (θt/θi)·d_V + (1 − θt/θi)·d_N (`interpolated_normal_distance` gives
//!   d_N at the pixel), the ratio taken as its limit 1/n at normal incidence; D. P̃2 = P1 +
//!   d̃·T1; E. N2 from the back-face texture where P̃2 projects (`back_face`); F. T2 (`leave`);
//!   then the nearby geometry (`nearby`) by one of the paper's three ways (`mode`):
//!   `kay-greenberg` (§4.1, `kay_greenberg`: P̃2 projected into the NG texture), `ray-plane`
//!   (§4.2, `ray_plane`: the nearest of a few planes fitted on the CPU, [`fit_planes`],
//!   projected into it), `iterative` (§4.3, G–J: `seeds` samples along T2, evenly spaced on
//!   the screen up to where the ray leaves the scene, the one whose depth best agrees with the
//!   NG depth under it starting `iterations` steps of t ← t − (z(P̃2 + t·T2) − z_NG) /
//!   (T2 · forward); `iterative_as_published`, or `iterative` with the steps below). A ray
//!   that finds nothing nearby takes the background (§4.1: "use T̃2 to index into the
//!   background environment map"; `nothing_nearby`). Mirrors take envmap's reflection; thin
//!   sheets look straight through to the nearby geometry.
//!
//! Beyond the paper (each switched off by the `paper` preset; figures: mean FLIP at 320 × 240):
//! - `exit_iterations` moves P̃2 along T1 to the depth of the back face under it,
//!   the §4.3 iteration applied to the back-face texture (0.240 → 0.118 with the cube maps
//!   looked up along the direction alone; the suite's glass sphere unless named, as in
//!   docs/methods/image-space.md) (paper: `exit_iterations=0`).
//! - `bracket`: the iterative mode skips seeds over empty NG texels, refines by secant where
//!   two consecutive seeds bracket the NG surface (the ray passes from in front of it to
//!   behind it) and keeps the best-agreeing point met, so that it cannot run off the screen
//!   where T2 is far from the view direction; a ray in front of the NG surface at every seed
//!   passes beside the nearby geometry and finds nothing (the glass sphere before the dragon,
//!   `scenes/table1`: 0.253 → 0.163, with the depth agreement below). The paper iterates from
//!   the best-agreeing seed (empty texels holding the far plane's depth, as a cleared
//!   z-buffer does) and takes the texel the last step lands on (paper: `bracket=false`).
//! - `depth_tolerance`: the iterative mode accepts the texel it ends on only
//!   where its depth agrees with the ray's within that fraction (else nothing nearby); the
//!   paper takes it whatever its depth (10 %, 5 %, 2 % measured: sphere before the dragon
//!   0.164 / 0.163 / 0.156, the bunny 0.240 / 0.217 / 0.206, the suite's glass sphere 0.072 /
//!   0.071 / 0.071; 5 % keeps a margin for coarse textures, where depth varies more across a
//!   texel) (paper: `depth_tolerance=0`).
//! - `discs`: ray-plane's planes are discs around what they were fitted to, and the plane
//!   standing for an object that no plane fits (facing the eye through its centre) a disc as
//!   large as its bounding sphere; the paper's planes are infinite, so such a plane catches
//!   rays that pass far from its object (paper: `discs=false`).
//! - `internal_reflection`: at the second interface light is split by Fresnel's equations
//!   and the reflected part (all of it under total internal reflection, §6's second
//!   limitation) is followed inside once more, marched in screen space (`march`) until it
//!   leaves the refractor (between the front faces of the G-buffer and the back faces of the
//!   first pass, or by the peeled layers), refined by bisection, and refracted out there to
//!   the nearby geometry. In the right-angle prism 94 % of the pixels the reference shows
//!   internally reflected show what TIR shows (0 % without). Still wrong: light trapped a
//!   second time takes the cube map along its reflected direction (counted as `internal
//!   reflections not resolved`). The paper's step F refracts all the light out, and under
//!   total internal reflection its Cg `refract` returns the zero vector (as WGSL's does):
//!   every point of that ray is P̃2, so the lookups read the NG texel behind P̃2, and where
//!   none is there the zero vector indexes the background, which selects no texel in any
//!   defined way: a one-colour background gives its colour whichever texel is read, and
//!   specula returns that; any other (a textured background, the cube map) gives black. Counted
//!   as `total internal reflections not followed` (paper: `internal_reflection=false`).
//! - `reflection`: the first surface's Fresnel reflection, from envmap's cube map as the
//!   reference has it, weighting the refraction by what is transmitted; the paper's steps
//!   (A–F, G–J) return the refracted colour alone (paper: `reflection=false`).
//! - `fallback`: a ray that leaves the NG texture's frustum or finds
//!   nothing nearby takes envmap's cube map of the refractor (drawn without it, [`CubeMaps`]),
//!   which also holds the nearby objects, instead of the paper's background environment map
//!   (paper: `fallback=background`).
//! - `parallax`: cube-map lookups go towards where the ray leaves the scene's
//!   bounding box, seen from the map's centre (0.118 → 0.072; lens 0.079 → 0.066); off, they
//!   go along the direction as envmap's do (mirrors included) (paper: `parallax=false`).
//! - `dispersion`: a dispersive material refracts once per colour channel; the paper's
//!   refractors have one index, and the preset refracts one path at the green (d-line) index
//!   (paper: `dispersion=false`).
//! - `two_level_maps`: with two reflectors or more, the cube maps shade the other specular
//!   objects they show from those objects' own maps (one level of envmap shading) instead of
//!   black (paper: `two_level_maps=false`).
//!
//! [`CubeMaps`]: specula_core::cube_maps::CubeMaps
//!
//! Where the paper is silent, what this implementation does (the preset keeps it):
//! - An exit point P̃2 that projects where the back-face texture holds nothing takes the
//!   normal of the back face under the pixel itself (counted as `exits off the back faces`);
//!   the paper would read the texture's cleared value. Where no back face is under the pixel
//!   either (an open surface), d_V is d_N and the ray leaves as through a face parallel to the
//!   entry face.
//! - The iterative seeds span the ray from P̃2 to where it leaves the scene's bounding sphere
//!   (the paper: up to the far plane, which specula places just past that sphere), evenly
//!   spaced on the screen as the paper's feature-size argument assumes, cut where the ray
//!   comes near the eye; seeds off the screen are skipped, and the iteration stops where its
//!   point leaves the screen (that ray takes the background) or where T2 is perpendicular to
//!   the view direction (the step's denominator is zero).
//! - §4.2's "few planes" are fitted by [`fit_planes`]: each set of coplanar triangles
//!   covering at least 2 % of its mesh's area, and for a mesh not mostly covered by such sets
//!   a plane facing the eye through its centre (the paper's plane standing for complex
//!   geometry, its Figure 6); the `MAX_PLANES` largest.
//! - The NG texture holds only non-specular surfaces (the paper's scenes have no mirrors), so
//!   a mirror seen through the refractor comes from the fallback. Mirrors and thin sheets,
//!   which the paper does not render, are shaded as above whatever the settings.
//!
//! The paper's four limitations (§6) and what this implementation does about them:
//! 1. *Two interfaces only.* Removed where depth-peeled layers allow it, off by default
//!    (`layers` > 1; the default 1 is the paper's two interfaces): the solid refractors'
//!    surfaces are peeled from the eye into 2 × `layers` layers (`peel.wgsl`), and light that
//!    has left the refractor is marched through them (a point is inside a refractor where an
//!    odd number of layers lie before it); where it enters a refractor again it is refracted
//!    in and out, up to `layers` − 1 more pairs of interfaces. Two glass balls one behind the
//!    other: mean FLIP 0.288 → 0.053 with `layers=2`; one more raster pass of the refractors
//!    per peeled layer (glass-dragon at 320 × 240: 97.7 → 114.6 ms a frame on lavapipe). On
//!    the built-in glass-dragon it changes 0.129 to 0.127. Light reflected at these extra
//!    interfaces takes the cube map.
//! 2. *Total internal reflection handled wrongly.* Removed in part by `internal_reflection`
//!    (above); with `layers=1` its march sees only two depth layers, so inside a concave
//!    refractor it can stop at the wrong one.
//! 3. *Aliasing* of d_V, N2 and the NG texture (nearest texels). Kept; `texture_scale` trades
//!    it for cost (glass sphere 0.095 / 0.071 / 0.058 at 0.5 / 1 / 2).
//! 4. *Visibility from one NG texture* (surfaces hidden from the eye cannot be refracted).
//!    Kept, measured by [`nearby_visibility`] with exact rays: 0 to 4.6 % of the refracted
//!    pixels on the scenes with nearby geometry reach a surface the eye cannot see; a second,
//!    depth-peeled NG layer would cost one more raster pass of the scene for at most those
//!    pixels, so it is not built.
//!
//! Implementation (changes no pixel): d_N is cast once per scene (a rigid move keeps it); the
//! planes are fitted again only after a move, the fallback cube maps redrawn only after a move
//! (unless `dynamic`); bind groups are kept per set of textures; each refracted path's lookups
//! are one call site in the shader, so that it compiles once.
//!
//! ## Parameters
//!
//! <!-- The parameter table: made from `Params::SPECS` by `specula_core::params::doc_table`;
//! `SPECULA_REGENERATE=1 cargo test -p specula-methods --lib doc` writes it again. -->
//! | parameter | takes | default | a change redoes | what it does |
//! |---|---|---|---|---|
//! | `mode` | one of kay-greenberg, ray-plane, iterative | `iterative` | uniform | how refracted rays find nearby geometry: the NG texture behind the exit point, the nearest fitted plane, or seeded iteration |
//! | `seeds` | a whole number from 1 to 64 | `7` | uniform | iterative mode: samples along the refracted ray choosing where iteration starts (more find smaller features) |
//! | `iterations` | a whole number from 0 to 32 | `4` | uniform | iterative mode: refinement steps from the best seed |
//! | `bracket` | true or false | `true` | uniform | iterative mode: refine by secant between seeds that bracket the nearby surface and keep the best-agreeing point (false: the paper's iteration from the best seed) |
//! | `depth_tolerance` | a number from 0 to 1 | `0.05` | uniform | iterative mode: the relative depth disagreement within which the texel found is accepted (0: any, as the paper) |
//! | `discs` | true or false | `true` | uniform | ray-plane mode: planes are discs around what they were fitted to (false: the paper's infinite planes) |
//! | `index` | a number from 0 to 4 | `0` | uniform | index of refraction of every refractor (0: each material's own) |
//! | `texture_scale` | a number from 0.125 to 2 | `1` | uniform | size of the back-face and nearby-geometry textures relative to the frame |
//! | `inside_steps` | a whole number from 1 to 256 | `24` | uniform | march steps following light reflected inside the refractor |
//! | `exit_iterations` | a whole number from 0 to 16 | `2` | uniform | steps moving the estimated exit point to the back face's depth (0: the paper's interpolated distance alone) |
//! | `internal_reflection` | true or false | `true` | uniform | split light by Fresnel at the exit and follow the reflected part inside once more (false: the paper's refraction of all of it, the zero vector under total internal reflection) |
//! | `reflection` | true or false | `true` | uniform | add the first surface's Fresnel reflection (false: the refracted colour alone, as the paper) |
//! | `fallback` | one of cube-map, background | `cube-map` | uniform | what a ray that finds no nearby geometry sees: the refractor's cube map, or the paper's background |
//! | `dispersion` | true or false | `true` | uniform | refract once per colour channel on dispersive materials (false: one path at the green index) |
//! | `resolution` | a whole number from 1 to 8192 | `256` | resources | texels per face side of the fallback cube maps (envmap's) |
//! | `dynamic` | true or false | `false` | uniform | redraw the fallback cube maps every frame (else only after a move) |
//! | `two_level_maps` | true or false | `true` | uniform | with two reflectors or more, shade the other specular objects a cube map shows from their own maps (two levels; else black) |
//! | `layers` | a whole number from 1 to 4 | `1` | uniform | pairs of interfaces a path may cross (1: the paper's two); more peel 2 x layers surface layers |
//! | `parallax` | true or false | `true` | uniform | correct cube-map lookups for parallax against the scene's bounding box (false: the direction alone, as envmap) |
//! | `shadow_resolution` | a whole number from 1 to 8192 | `1024` | scene preparation | texels per side of the scene raster's shadow maps |
//! <!-- end of the parameter table -->
//!
//! What they change:
//! - `mode`: `kay-greenberg`, `ray-plane` or
//!   `iterative` (above). Kay–Greenberg costs one texture read and barely bends what is seen;
//!   ray-plane adds a loop over at most 8 planes and is exact for planar surroundings;
//!   iterative costs `seeds + iterations` reads and follows any geometry.
//! - `seeds`: samples along T2 choosing the iteration's start. More
//!   find smaller features (the paper: seven find every feature larger than ten pixels at
//!   512²); cost linear.
//! - `iterations` (the paper: fewer than five are typically needed): refinement
//!   steps of the iterative mode; cost linear.
//! - `bracket` and `depth_tolerance` (0: none): the iterative
//!   mode's search and acceptance (above); neither costs a texture read more.
//! - `discs`: ray-plane's planes are discs (above); no cost.
//! - `index`: overrides the refractors' index of refraction
//!   (the paper's scenes: 1.2, spheres 1.5).
//! - `texture_scale`: the back-face and NG textures' size relative to the frame
//!   (the paper draws them at the frame's size). Lower is cheaper and more aliased.
//! - `exit_iterations` (0 is the paper's P̃2): see above; cost two texture reads
//!   per step.
//! - `internal_reflection`: see above; cost a march where Fresnel reflects.
//! - `reflection`, `dispersion`: see above; dispersion triples
//!   the refraction's cost on dispersive materials.
//! - `fallback` and `parallax`: see above. The cube maps
//!   are drawn whatever `fallback` says (mirrors and thin sheets read them).
//! - `layers`: see limitation 1; cost one raster pass
//!   of the refractors per peeled layer and a march per extra interface.
//! - `inside_steps`: march steps following light inside a refractor or between
//!   refractors; more find thinner parts; cost linear, only where the march runs.
//! - `resolution` and `dynamic`: the fallback cube maps' texels
//!   per face side, and whether they are redrawn every frame (as envmap's parameters).
//! - `shadow_resolution`: shadow maps of the raster passes (see `raster`).

use bytemuck::{Pod, Zeroable};
use specula_gpu::shaders;
use specula_gpu::GpuContext;

use specula_core::cube_maps::{self, Exit};
use specula_core::lifecycle::{GpuFrame, GpuMethod, GpuTechnique};
use specula_core::live_scene::LiveScene;
use specula_core::raster::{self, RasterPass};
use specula_core::{Invalidates, MethodInfo, Param, ParamKind, TechniqueError};

mod geometry;
mod passes;
pub mod peel;

pub use geometry::{fit_planes, nearby_visibility, normal_distances, GpuPlane, NearbyVisibility};
use passes::fit_planes_after_moves;
pub use passes::Prepared;

const SHADER: &str = include_str!("image_space.wgsl");

pub fn shader_source() -> String {
    shaders::compose(
        &[
            "optics.wgsl",
            "camera.wgsl",
            "scene.wgsl",
            "cubemap.wgsl",
            "specular_pixel.wgsl",
        ],
        &format!("{}\n{SHADER}", cube_maps::LOOKUP_SHADER),
    )
}

/// The most planes the ray-plane mode intersects (the paper: "a few").
pub const MAX_PLANES: usize = 8;

/// The final pass's counters, in image_space.wgsl's order: name, and what a warning says.
const COUNTERS: [(&str, &str); 7] = [
    (
        "rays that left the view",
        "refracted rays left the nearby-geometry texture's view and took the fallback",
    ),
    (
        "rays that found nothing nearby",
        "refracted rays found no nearby geometry and took the fallback",
    ),
    (
        "exits off the back faces",
        "estimated exit points fell outside the back-face texture (the pixel's own back face was used)",
    ),
    ("total internal reflections followed", ""),
    (
        "internal reflections not resolved",
        "internally reflected rays were not resolved in the textures and took the cube map",
    ),
    ("re-entries followed", ""),
    ("total internal reflections not followed", ""),
];

specula_core::params! {
    /// image-space's parameters (the table above).
    pub struct Params {
        mode: NearbyMode = Param {
            kind: ParamKind::Choice(NearbyMode::WORDS),
            default: "iterative",
            doc: "how refracted rays find nearby geometry: the NG texture behind the exit point, the nearest fitted plane, or seeded iteration",
            invalidates: Invalidates::Uniform,
        },
        seeds: u32 = Param {
            kind: ParamKind::Integer { min: 1, max: 64 },
            default: "7",
            doc: "iterative mode: samples along the refracted ray choosing where iteration starts (more find smaller features)",
            invalidates: Invalidates::Uniform,
        },
        iterations: u32 = Param {
            kind: ParamKind::Integer { min: 0, max: 32 },
            default: "4",
            doc: "iterative mode: refinement steps from the best seed",
            invalidates: Invalidates::Uniform,
        },
        bracket: bool = Param {
            kind: ParamKind::Flag,
            default: "true",
            doc: "iterative mode: refine by secant between seeds that bracket the nearby surface and keep the best-agreeing point (false: the paper's iteration from the best seed)",
            invalidates: Invalidates::Uniform,
        },
        depth_tolerance: f32 = Param {
            kind: ParamKind::Number { min: 0.0, max: 1.0 },
            default: "0.05",
            doc: "iterative mode: the relative depth disagreement within which the texel found is accepted (0: any, as the paper)",
            invalidates: Invalidates::Uniform,
        },
        discs: bool = Param {
            kind: ParamKind::Flag,
            default: "true",
            doc: "ray-plane mode: planes are discs around what they were fitted to (false: the paper's infinite planes)",
            invalidates: Invalidates::Uniform,
        },
        index: f32 = Param {
            kind: ParamKind::Number { min: 0.0, max: 4.0 },
            default: "0",
            doc: "index of refraction of every refractor (0: each material's own)",
            invalidates: Invalidates::Uniform,
        },
        texture_scale: f32 = Param {
            kind: ParamKind::Number {
                min: 0.125,
                max: 2.0,
            },
            default: "1",
            doc: "size of the back-face and nearby-geometry textures relative to the frame",
            invalidates: Invalidates::Uniform,
        },
        inside_steps: u32 = Param {
            kind: ParamKind::Integer { min: 1, max: 256 },
            default: "24",
            doc: "march steps following light reflected inside the refractor",
            invalidates: Invalidates::Uniform,
        },
        exit_iterations: u32 = Param {
            kind: ParamKind::Integer { min: 0, max: 16 },
            default: "2",
            doc: "steps moving the estimated exit point to the back face's depth (0: the paper's interpolated distance alone)",
            invalidates: Invalidates::Uniform,
        },
        internal_reflection: bool = Param {
            kind: ParamKind::Flag,
            default: "true",
            doc: "split light by Fresnel at the exit and follow the reflected part inside once more (false: the paper's refraction of all of it, the zero vector under total internal reflection)",
            invalidates: Invalidates::Uniform,
        },
        reflection: bool = Param {
            kind: ParamKind::Flag,
            default: "true",
            doc: "add the first surface's Fresnel reflection (false: the refracted colour alone, as the paper)",
            invalidates: Invalidates::Uniform,
        },
        fallback: Fallback = Param {
            kind: ParamKind::Choice(Fallback::WORDS),
            default: "cube-map",
            doc: "what a ray that finds no nearby geometry sees: the refractor's cube map, or the paper's background",
            invalidates: Invalidates::Uniform,
        },
        dispersion: bool = Param {
            kind: ParamKind::Flag,
            default: "true",
            doc: "refract once per colour channel on dispersive materials (false: one path at the green index)",
            invalidates: Invalidates::Uniform,
        },
        resolution: u32 = Param {
            kind: ParamKind::Integer { min: 1, max: 8192 },
            default: "256",
            doc: "texels per face side of the fallback cube maps (envmap's)",
            invalidates: Invalidates::Resources,
        },
        dynamic: bool = Param {
            kind: ParamKind::Flag,
            default: "false",
            doc: "redraw the fallback cube maps every frame (else only after a move)",
            invalidates: Invalidates::Uniform,
        },
        two_level_maps: bool = cube_maps::TWO_LEVEL_MAPS,
        layers: u32 = Param {
            kind: ParamKind::Integer { min: 1, max: 4 },
            default: "1",
            doc: "pairs of interfaces a path may cross (1: the paper's two); more peel 2 x layers surface layers",
            invalidates: Invalidates::Uniform,
        },
        parallax: bool = Param {
            kind: ParamKind::Flag,
            default: "true",
            doc: "correct cube-map lookups for parallax against the scene's bounding box (false: the direction alone, as envmap)",
            invalidates: Invalidates::Uniform,
        },
        shadow_resolution: u32 = raster::SHADOW_RESOLUTION,
    }
}

pub const INFO: MethodInfo = MethodInfo {
    name: "image-space",
    summary: "two-interface image-space refraction of nearby geometry (Wyman)",
    exact: false,
    needs_gpu: true,
    gpu_optional: false,
    progressive: false,
    // Mirrors are not handed to envmap: they look envmap's kind of cube map up with
    // image-space's own parallax correction (`env_along`; `parallax`, on by default), which
    // changes their figure (suite mirror sphere: envmap 0.20, image-space 0.017), so it is
    // image-space's own.
    delegates: &[],
    params: Params::SPECS,
    presets: &[specula_core::Preset {
        name: "paper",
        summary:
            "the published algorithm (Wyman 2005, nearby geometry): every step beyond the paper off",
        settings: &[
            "exit_iterations=0",
            "bracket=false",
            "depth_tolerance=0",
            "discs=false",
            "internal_reflection=false",
            "reflection=false",
            "fallback=background",
            "parallax=false",
            "dispersion=false",
            "two_level_maps=false",
        ],
    }],
    create: || Box::new(GpuMethod::<ImageSpace>::default()),
};

/// How refracted rays find the nearby geometry (§4).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NearbyMode {
    KayGreenberg = 0,
    RayPlane = 1,
    Iterative = 2,
}

specula_core::choice!(NearbyMode {
    KayGreenberg = "kay-greenberg",
    RayPlane = "ray-plane",
    Iterative = "iterative",
});

/// What a ray that finds no nearby geometry sees.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fallback {
    CubeMap = 0,
    Background = 1,
}

specula_core::choice!(Fallback {
    CubeMap = "cube-map",
    Background = "background",
});

/// Host mirror of WGSL `Settings`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuSettings {
    pub mode: u32,
    pub seeds: u32,
    pub iterations: u32,
    pub plane_count: u32,
    pub index_override: f32,
    pub depth_tolerance: f32,
    pub inside_steps: u32,
    pub exit_iterations: u32,
    pub scene_center: [f32; 3],
    pub scene_radius: f32,
    pub scene_min: [f32; 3],
    pub parallax: u32,
    pub scene_max: [f32; 3],
    pub layers: u32,
    pub peeled: u32,
    pub refractor_extent: f32,
    /// View depth of the far plane: what a cleared z-buffer holds.
    pub far_depth: f32,
    pub bracket: u32,
    pub discs: u32,
    pub internal_reflection: u32,
    pub reflection: u32,
    pub fallback: u32,
    pub dispersion: u32,
    pub pad: [u32; 3],
}

#[derive(Default)]
pub struct ImageSpace {
    pub params: Params,
}

impl ImageSpace {
    pub fn new(mode: NearbyMode) -> GpuMethod<ImageSpace> {
        let mut technique = GpuMethod::<ImageSpace>::default();
        technique.params.mode = mode;
        technique
    }
}

impl GpuTechnique for ImageSpace {
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
        self.build(gpu, live)
    }

    fn invalidate(&mut self, prepared: Option<&mut Prepared>, what: Invalidates) -> bool {
        if let (Some(p), true) = (prepared, what >= Invalidates::Resources) {
            p.maps.drop_faces();
        }
        true
    }

    /// The paper's steps after the G-buffer: the refractors' back faces and the nearby
    /// geometry from the eye, the fallback cube maps, the peeled layers, then each refractor
    /// pixel refracted through both interfaces.
    fn shade(&mut self, p: &mut Prepared, frame: &mut GpuFrame<'_>) -> Result<(), TechniqueError> {
        let (gpu, live) = (frame.gpu, frame.live);
        for pass in [&p.back_faces, &p.nearby] {
            pass.begin_frame(gpu, live)?;
        }
        fit_planes_after_moves(p, gpu, live);
        let textures = self.nearby_textures(p, frame)?;
        p.maps.set_two_levels(self.params.two_level_maps);
        let faces_drawn = p.maps.update(
            gpu,
            frame.raster(),
            live,
            self.params.resolution,
            Exit::None,
            self.params.dynamic,
        )?;
        frame.lap("fallback cube maps")?;
        let peeled = self.peel(p, frame, &textures.camera)?;
        self.refract(p, frame, &textures, peeled)?;
        frame.lap("refraction")?;
        let counts = p.counters.read(gpu)?;
        frame.count("refractors", p.maps.reflectors.len() as u64);
        frame.count("planes", p.plane_count as u64);
        frame.count("cube map faces rendered", faces_drawn);
        frame.count("raster passes", 3 + faces_drawn + peeled as u64);
        for ((name, what), &n) in COUNTERS.iter().zip(&counts) {
            frame.count(name, n as u64);
            if n > 0 && !what.is_empty() {
                frame.warn(format!("image-space: {n} {what}"));
            }
        }
        Ok(())
    }
}
