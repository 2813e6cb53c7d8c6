//! `pvrr`: per-vertex reflection and refraction.
//!
//! Paper: Kakimoto, Tatsukawa, Chun, Nishita, *Real-time reflection and refraction on a
//! per-vertex basis*, Journal of the Institute of Image Electronics Engineers of Japan
//! 37(3), 2008.
//!
//! Every mesh with a mirror or dielectric material is a reflector. Steps, per frame:
//! 1. for every reflector vertex V the eye's ray is followed exactly, in parallel through the
//!    scene's BVH: reflected about V's normal at a mirror; at a lens (§4.5) refracted into the
//!    solid at V, traced to where it leaves, refracted out — once per colour channel when the
//!    material's three indices differ (chromatic aberration). The segment leaving the
//!    reflector is traced to its nearest hit P (`rays`);
//! 2. the reflector's visible triangles form one patch (§3), or several (step 3): a patch's
//!    virtual viewpoint is the point nearest, in the least-squares sense, to its vertices'
//!    exit lines (§3.2), (Σ (I − r rᵀ)) c = Σ (I − r rᵀ) o; its view volume (§3.3, `view`)
//!    looks along the mean exit direction, near plane just in front of the reflector, far
//!    plane past every P and the whole scene, sides containing every P (with a 2 % margin;
//!    the paper's contain every exit segment between the two planes, below). Of the up vectors — the world's, and the patch's two principal
//!    curvature directions (§4.3) — the one giving the smallest cross-section wins, which fits
//!    the volume to cylinders and saddles;
//! 3. adaptive subdivision, beyond the paper (below);
//! 4. 1st pass: per patch, the scene without the reflector is rasterised from the virtual
//!    viewpoint into a reflection map. With `depth` ≥ 2 the other reflectors in that map are
//!    themselves drawn by pvrr from the virtual viewpoint, recursively (§4.4, multiple
//!    reflection);
//! 5. each vertex's texture coordinate is where the line from its patch's viewpoint through
//!    its P meets the patch's map (§3.1, steps 3.2–3.4);
//! 6. 2nd pass: the reflector's patches are drawn over the scene raster with those coordinates,
//!    so every vertex shows exactly its ray-traced P: a mirror times its Fresnel term (Schlick
//!    or F0), a lens times the exact Fresnel transmittance along the path; for three indices,
//!    three draws with red, green and blue colour masks share one 1st pass (§4.5, Figure 15).
//!
//! Beyond the paper (each switched off by the `paper` preset; `specula methods` lists it):
//! - adaptive subdivision (step 3; §4.1 leaves it to future work): a patch whose field of view
//!   exceeds `max_fov`, or with a P at or behind its near plane, is split in two at its median
//!   triangle centroid, until every patch is acceptable, is one triangle, or `max_patches` is
//!   reached. Neighbouring patches share their boundary vertices, which show the same P in
//!   both patches, so the images meet there (§4.1's continuity). Patches share the reflector's
//!   map height by solid angle, and a level below the top shares `max_patches` across the
//!   patches of the level above. The paper renders one view per reflector
//!   ("only once for a reflector object on the 1st pass", §3.2); its divided mirror of
//!   Figure 7 is two meshes, which here are two reflectors too (paper: `max_patches=1`);
//! - view volumes fitted to the hits: a volume's sides contain every P, the only points the
//!   2nd pass looks up (a triangle's texture coordinates interpolate its corners'). §3.3's
//!   volume contains the whole reflection lines between its near and far planes; where the
//!   lines spread from near the viewpoint (a glass sphere's patches, a ball lens) their parts
//!   near the mirror span many times the hits' angle, and the hits got a small part of the
//!   map's texels: on the suite's glass sphere at 320 × 240 the mean FLIP went from 0.242 to
//!   0.029, on the lens from 0.154 to 0.100, on the concave mirror from 0.071 to 0.010
//!   (paper: `fit_hits=false`);
//! - the zooming region drawn as §7 proposes (`zooming=view`). A P behind its patch's
//!   viewpoint lies between a concave mirror and its rays' convergence (or between a magnifier
//!   and the point its rays converge on), where no forward view shows it. A patch with at least
//!   8 such hits, a quarter of its hits or more, on surfaces the raster draws, gets a zooming
//!   view instead (no wider than `max_fov`): from its viewpoint back toward the mirror, its far
//!   plane just before the mirror, keeping the farthest surface (the reversed depth test §7
//!   names), lit on its side away from the viewpoint, so each texel holds what the line from
//!   the mirror through the viewpoint meets first before the viewpoint. It is drawn over the
//!   forward view from the same viewpoint turned upside down (the same texels, the opposite
//!   directions), so where nothing lies before the viewpoint the texel holds what the line
//!   meets beyond it. Every vertex of the patch then reads this one map: a P before the
//!   viewpoint where it projects, a P beyond it through the viewpoint, so a triangle that
//!   straddles the caustic (one corner before the convergence, one beyond) interpolates
//!   within one picture. The rest, counted as `unresolved vertices`, named in a warning and
//!   striped magenta with `markers=true`, take the radiance ray traced along their exit
//!   segment (up to 8 bounces, as the reference), blended across their triangles by the share
//!   of such corners (`zooming=traced` does this for every P behind its viewpoint): a patch
//!   with fewer hits behind its viewpoint (near a ball's caustic, where the patches that split
//!   off hold one or two, a zooming view each doubled the suite's glass sphere's frame for the
//!   same mean FLIP), a P too near the zooming view's viewpoint plane to project, and a P on a
//!   mirror or lens, which the zooming view leaves black (it draws no nested level). The
//!   paper "simply ignore[s]" the region: such a vertex keeps the texture coordinate of step
//!   5, where its line through the viewpoint meets the forward map on the far side of the
//!   map's centre, and shows what the map holds there (paper: `zooming=map`). On the concave
//!   magnifier of `scenes/zooming` at 320 × 240 the mean FLIP is 0.017 (traced: 0.204), on the
//!   suite's lens, a magnifier, 0.078 (0.100);
//! - a dielectric's surface reflection: a mirror drawn over its transmitted light (float
//!   blending; on a device without it, left out) whose per-vertex weight is the exact Fresnel
//!   reflectance (a thin sheet's, ½ Σ 2R_σ / (1 + R_σ)), with patches and 1st passes of its own. The
//!   paper's lens shows its transmitted light only (§4.5) (paper: `surface_reflection=false`);
//! - the light reflected once inside a solid dielectric: refracted in, reflected with weight R
//!   where it first meets the surface again, refracted out where it meets it next; drawn as
//!   the surface reflection is (on the suite's glass sphere the two took pvrr's mean FLIP from
//!   0.343 to 0.252). Inside another reflector's map (depth ≥ 2) a dielectric shows its
//!   transmitted light only (paper: `internal_reflection=false`).
//! - a bounded frame: the levels of a frame are planned in full before anything is drawn, within
//!   a budget across all reflectors and levels — the top level within `frame_patches` 1st passes
//!   and `frame_texels` map texels (each reflector its share: fewer patches, a coarser map),
//!   the levels below within `nested_share` times the top level's passes and texels and a
//!   quarter of that times its per-vertex rays, given to the outer patches largest map first
//!   (only those with a vertex whose P lies on another reflector: the others' maps show none
//!   at their vertices), each nested map no finer than its outer map. An outer patch the
//!   budget does not cover (counted, with a warning), like every patch of the deepest level
//!   and of `depth=1`, shows the other reflectors as the scene raster draws them, black,
//!   except at its corners whose P lies on one: those take the radiance ray traced along
//!   their exit segment, blended across their triangles as the unresolved vertices' (not
//!   black: issue 29; with `zooming=map`, the paper's, they stay black). The
//!   2nd pass's vertices are sized from the plan and checked against the device's largest
//!   buffer before any is written: a view that cannot fit is a clear error, not a device
//!   validation error. The paper renders every level in full (§4.4), whatever it costs: three
//!   mirrors seeing each other took 264 s at 96 × 72, and a glass sphere and lens merged into
//!   one mesh asked for a 2.9 GB buffer (paper: `nested_share=1000`, `frame_patches=1048576`,
//!   `frame_texels=4294967296`).
//!
//! Where the paper is silent, this implementation chooses (the `paper` preset keeps these):
//! the vertices that shape a view are those the eye sees (the paper's lens rays start at its
//! front face, §4.5); a reflector is hidden from its own maps (the paper's near plane excludes
//! its open mirror, §3.3; a solid's far side can reach past that plane); an exit segment that
//! leaves the scene puts its P 4 scene radii along it; inside a solid a path follows total
//! internal reflection until it leaves (the paper refracts twice and says nothing of it;
//! following it keeps each vertex's path exact, the paper's premise); when a patch's exit
//! lines are (nearly) parallel no least-squares viewpoint exists, and the view looks along
//! their mean direction from 10 patch radii behind it, with a warning; a view volume is at
//! most 2 atan 50 ≈ 177.7° wide (a P beyond shows the map's edge); the up vector is the
//! candidate with the smallest cross-section, §4.3's aim (the aspect ratio "optimized for the
//! reflection ray distribution") made a rule, as §3.3 names no up vector; the 2nd pass's
//! weights are the scene material's (the paper names none; every specula method shades the
//! scene's materials so, which the reference does too).
//!
//! Approximations and artifacts: between vertices the map is warped linearly, so error grows
//! with triangle size and curvature and falls as the mesh is refined (a reflector with fewer
//! than 9 visible vertices raises a warning); objects hidden from the virtual viewpoint but
//! seen along some exit ray, or the reverse, show the wrong surface (the occlusion
//! inconsistency of §6); a reflector does not appear in its own map (no self-reflection); a
//! lens follows up to three paths (above; one in the paper), and light reflected twice or more
//! inside it is missing. Every path is sampled at the vertices: a solid meshed only at its rim
//! (a box-shaped pane, whose every vertex is a corner) sends each vertex's path through the
//! rim's edge faces, and the interior of its faces shows those wrong paths. In multiple
//! reflection, the inner reflector's rays start at the outer one's virtual viewpoint, not at
//! the exact bounce points. A reflector whose exit directions spread widely (a whole sphere, a
//! teapot) gets a wide, distorted map from one view (§4.1's reason for subdividing): with
//! `max_patches=1` its image degrades, more of its P fall behind the viewpoint, and where a
//! P lies before the near plane far off the view's axis the map shows what lies beyond that
//! plane there (on the suite's mirror sphere, a ring of the black background: the viewpoint
//! lies inside the sphere, and at wide angles the room lies wholly before the near plane).
//!
//! Concave mirrors (§4.2) go through the same construction: the viewpoint lands near the
//! convergence point with the mirror behind it and the map comes out reversed (Figure 8).
//! The "zooming region" — P between the mirror and the convergence point, so behind the
//! viewpoint — cannot be shown by any forward view: a zooming view shows it (above), or
//! subdivision tries smaller patches and the rest is ray traced. A converging lens before a
//! near wall (a magnifier) is the same case: its rays converge behind the wall. A zooming view
//! is one map through its viewpoint, the forward picture's approximation: lines that miss the
//! viewpoint (spherical aberration) meet the scene elsewhere than their texel shows, exactly
//! at the vertices only; an object nearer the mirror than the patch's nearest vertex (inside
//! a deep cap, within its sagitta) lies beyond the far plane and is missing from it.
//!
//! Cached mode (§5): with `cached=true` a reflector's exit segments, patches and viewpoints are
//! kept in the eye's frame and reused while the reflector's vertices do not move relative to
//! the eye (a spectacle lens worn, a door mirror seen by the driver), also across `prepare`
//! of a moved scene; only the exit segments' hits P, the view volumes and the two passes are
//! redone. Changing `max_fov`, `max_patches`, `fit_hits` or `zooming` empties the cache.
//!
//! Implementation (changes no pixel): the per-vertex rays run in parallel; nothing is allocated
//! per frame once the frame's shape is known: maps come from the raster pass's G-buffer pool,
//! 2nd-pass vertices and uniforms from arenas written in place ([`specula_gpu::arena`]), bind
//! groups are kept per map slot.
//!
//! ## Parameters
//!
//! <!-- The parameter table: made from `Params::SPECS` by `specula_core::params::doc_table`;
//! `SPECULA_REGENERATE=1 cargo test -p specula-methods --lib doc` writes it again. -->
//! | parameter | takes | default | a change redoes | what it does |
//! |---|---|---|---|---|
//! | `resolution` | a whole number from 1 to 8192 | `512` | uniform | reflection-map height in texels of an undivided reflector (patches share it by solid angle) |
//! | `shadow_resolution` | a whole number from 1 to 8192 | `1024` | scene preparation | texels per side of the scene raster's shadow maps |
//! | `max_fov` | a number from 1 to 170 | `90` | resources | widest view volume a patch may keep, degrees; lower: more, less distorted maps |
//! | `max_patches` | a whole number from 1 to 4096 | `256` | resources | most patches per reflector (1: the paper's one view per reflector); each costs a 1st pass |
//! | `fit_hits` | true or false | `true` | resources | fit each view volume's sides to its hits, the only points the 2nd pass looks up (false: contain the whole reflection lines, as the paper's §3.3) |
//! | `zooming` | one of view, traced, map | `view` | resources | the vertices whose hit lies between the mirror and their rays' convergence (zooming region): view = the zooming view of §7 (from the viewpoint back toward the mirror, farthest surface kept); traced = their ray-traced radiance blended across their triangles; map = the map where their line through the viewpoint meets it, as the paper's algorithm |
//! | `surface_reflection` | true or false | `true` | uniform | add a dielectric's surface reflection (the paper's lens shows transmitted light only) |
//! | `internal_reflection` | true or false | `true` | uniform | add the light reflected once inside a solid dielectric (the paper's lens shows transmitted light only) |
//! | `depth` | a whole number from 1 to 4 | `2` | uniform | reflectors seen in reflectors, levels deep |
//! | `nested_share` | a number from 0 to 1000 | `8` | uniform | the levels below the top may draw up to this many times the top level's 1st passes and map texels, and trace a quarter of that times its per-vertex rays (0: none) |
//! | `frame_patches` | a whole number from 1 to 1048576 | `2048` | uniform | the most 1st passes a frame draws, all levels together (nested levels are left out first) |
//! | `frame_texels` | a whole number from 1 to 4294967296 | `16777216` | uniform | the most reflection-map texels a frame draws, all levels together (nested levels are left out first) |
//! | `ior` | `material`, one index of refraction or three (red,green,blue), each above 1 and at most 4 | `material` | scene preparation | the lenses' indices of refraction (three: chromatic aberration) |
//! | `cached` | true or false | `false` | uniform | keep exit rays and patches in the eye's frame while the lens does not move relative to it |
//! | `markers` | true or false | `false` | uniform | verification overlay: a red ball at every vertex's exact ray-traced hit |
//! | `marker_size` | a number from 0.000001 to 0.1 | `0.012` | uniform | marker radius as a fraction of its distance from the reflector |
//! <!-- end of the parameter table -->
//!
//! What they change:
//! - `resolution` (the paper states none): reflection-map height in texels of an
//!   undivided reflector (the width follows the view volume's aspect ratio); patches share it
//!   in proportion to the solid angle each covers (height × √share, at least 16). Higher
//!   sharpens the reflection between vertices; costs rasterising about that many texels per
//!   frame.
//! - `shadow_resolution`: shadow maps of the scene raster (see `raster`).
//! - `max_fov`: the widest view volume a patch may keep (subdivision
//!   only). Lower gives more, less distorted maps (more 1st passes).
//! - `max_patches` (1 is the paper's one view per reflector): the most patches
//!   per reflector; each costs a 1st pass (a zooming view two). A level below the top shares this budget across all
//!   the patches of the level above (each of N outer patches plans at most
//!   max(1, `max_patches` / N) per inner reflector), so the 1st passes of a frame stay within
//!   `max_patches` × reflectors per level.
//! - `depth`: reflectors seen in reflectors,
//!   levels deep (1: other reflectors appear in maps as the scene raster draws them, their
//!   vertices' ray-traced radiance blended in, above). Each
//!   level adds at most `max_patches` 1st passes per reflector it shows; inner reflections get
//!   coarser patches as outer ones get finer; the frame budget bounds them all (below).
//! - `nested_share`: the levels below the top may draw this many times the top
//!   level's 1st passes and map texels and trace a quarter of that times its per-vertex rays
//!   (0: depth 1's frame). Higher shows reflections in reflectors in more of the picture; on
//!   the scene suite at 160 × 120 a depth-2 frame took 0.67–1.13 times depth 1's with 8
//!   (docs/methods/pvrr.md), where unbounded it took up to 24 times (the lit room).
//! - `frame_patches`, `frame_texels`: the most 1st passes
//!   and map texels of a frame, all levels together; the top level's reflectors share them
//!   first (each at most `frame_patches` / (2 × reflectors) patches and a map of
//!   `frame_texels` / (8 × reflectors) texels: a zooming view draws two maps), the nested
//!   levels take what is left. They bound a frame's
//!   passes and its maps' memory (60 bytes a texel).
//! - `fit_hits`: view volumes fitted to the hits (above); false: to the whole
//!   reflection lines, as §3.3, with coarser maps where the lines spread.
//! - `zooming`: the zooming region (above). `view` costs two 1st passes per
//!   zooming patch and a traced path per unresolved vertex; `traced` a traced path per vertex
//!   whose P lies behind its viewpoint (and more patches, split for them); `map` nothing.
//! - `surface_reflection`, `internal_reflection`: a dielectric's reflections
//!   (above); each costs its own per-vertex rays, patches and 1st passes.
//! - `ior`: the dielectric's indices; one value, or three (red, green,
//!   blue; the paper's Figure 15 uses 1.60,1.61,1.62), overrides the material's.
//! - `cached`: the cached mode above.
//! - `markers`: the paper's verification overlay (Figures 1 and 14): a small
//!   red ball at every visible vertex's exact hit P, drawn in every pass, so each ball should
//!   sit on its vertex in the picture. A dispersive lens gets a red, a green and a blue ball
//!   per vertex, at its three channels' P, each seen through its own channel (so white where
//!   all three sit on the vertex). Balls are 1.2 % of their distance from the
//!   reflector (`marker_size`, default 0.012), at most 0.3 × the distance to the nearest
//!   neighbouring vertex's P.

mod passes;
mod plan;
mod rays;
mod view;

pub use rays::{EyeFrame, Interaction, MeshPaths, Segment};
pub use view::{least_squares_viewpoint, principal_directions, Extents, Patch, ViewBasis};

use std::cell::RefCell;

use bytemuck::{Pod, Zeroable};
use glam::{Vec3, Vec4};
use rayon::prelude::*;
use specula_gpu::arena::Arena;
use specula_gpu::shaders::{self, CameraUniform};
use specula_gpu::util::{bind_group, layout_entry, render_pipeline, texture_binding, PipelineSpec};
use specula_gpu::{GpuContext, GpuError};
use specula_scene::{Camera, MaterialKind, Scene};
use specula_trace::SceneAccel;

use rays::{trace_hits, trace_paths, ChannelPaths};
use specula_core::gpu_scene::GpuScene;
use specula_core::lifecycle::{GpuFrame, GpuMethod, GpuTechnique};
use specula_core::live_scene::LiveScene;
use specula_core::raster::{self, BindGroupsBySlot, GBuffer, RasterPass};
use specula_core::{
    Invalidates, MethodInfo, Param, ParamKind, ParamType, ParamValue, TechniqueError,
};
pub use passes::shader_source;
use passes::*;
use plan::*;
use view::{PatchInput, PatchLimits};

const SHADER: &str = include_str!("pvrr.wgsl");

/// Specular bounces the ray tracing of an unresolved vertex's exit segment follows (the
/// reference's default).
const TRACED_DEPTH: u32 = 8;

/// How a patch shows the vertices whose P lies behind its viewpoint: between a concave mirror
/// (or a magnifier) and the point where their rays converge, the zooming region (§4.2, §7).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Zooming {
    /// The zooming view §7 proposes: the patch's map is drawn from its viewpoint back toward
    /// the mirror, keeping the farthest surface, over the forward view turned through the
    /// viewpoint.
    View,
    /// Each such vertex's radiance ray traced along its exit segment, blended across its
    /// triangles.
    Traced,
    /// The paper's algorithm: the map where the vertex's line through the viewpoint meets it.
    Map,
}

specula_core::choice!(Zooming {
    View = "view",
    Traced = "traced",
    Map = "map",
});

/// The lenses' indices of refraction where `ior` overrides their materials': `material`
/// (None), one index, or three (red, green, blue).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Ior(pub Option<Vec3>);

impl ParamType for Ior {
    fn from_param(value: &ParamValue) -> Result<Self, String> {
        parse_ior(value.word()).map(Ior).map_err(str::to_string)
    }
    fn to_param(&self) -> String {
        match self.0 {
            None => "material".to_string(),
            Some(i) => format!("{},{},{}", i.x, i.y, i.z),
        }
    }
}

pub use specula_core::gpu_scene::MARKER_RADIANCE;

specula_core::params! {
    /// pvrr's parameters (the table above).
    pub struct Params {
        resolution: u32 = Param {
            kind: ParamKind::Integer { min: 1, max: 8192 },
            default: "512",
            doc: "reflection-map height in texels of an undivided reflector (patches share it by solid angle)",
            invalidates: Invalidates::Uniform,
        },
        shadow_resolution: u32 = raster::SHADOW_RESOLUTION,
        // Both shape the patches, which the cached mode keeps: changing them clears the cache.
        max_fov: f32 = Param {
            kind: ParamKind::Number { min: 1.0, max: 170.0 },
            default: "90",
            doc: "widest view volume a patch may keep, degrees; lower: more, less distorted maps",
            invalidates: Invalidates::Resources,
        },
        max_patches: usize = Param {
            kind: ParamKind::Integer { min: 1, max: 4096 },
            default: "256",
            doc: "most patches per reflector (1: the paper's one view per reflector); each costs a 1st pass",
            invalidates: Invalidates::Resources,
        },
        fit_hits: bool = Param {
            kind: ParamKind::Flag,
            default: "true",
            doc: "fit each view volume's sides to its hits, the only points the 2nd pass looks up (false: contain the whole reflection lines, as the paper's §3.3)",
            invalidates: Invalidates::Resources,
        },
        zooming: Zooming = Param {
            kind: ParamKind::Choice(Zooming::WORDS),
            default: "view",
            doc: "the vertices whose hit lies between the mirror and their rays' convergence (zooming region): view = the zooming view of §7 (from the viewpoint back toward the mirror, farthest surface kept); traced = their ray-traced radiance blended across their triangles; map = the map where their line through the viewpoint meets it, as the paper's algorithm",
            invalidates: Invalidates::Resources,
        },
        surface_reflection: bool = Param {
            kind: ParamKind::Flag,
            default: "true",
            doc: "add a dielectric's surface reflection (the paper's lens shows transmitted light only)",
            invalidates: Invalidates::Uniform,
        },
        internal_reflection: bool = Param {
            kind: ParamKind::Flag,
            default: "true",
            doc: "add the light reflected once inside a solid dielectric (the paper's lens shows transmitted light only)",
            invalidates: Invalidates::Uniform,
        },
        depth: u32 = Param {
            kind: ParamKind::Integer { min: 1, max: 4 },
            default: "2",
            doc: "reflectors seen in reflectors, levels deep",
            invalidates: Invalidates::Uniform,
        },
        nested_share: f32 = Param {
            kind: ParamKind::Number {
                min: 0.0,
                max: 1000.0,
            },
            default: "8",
            doc: "the levels below the top may draw up to this many times the top level's 1st passes and map texels, and trace a quarter of that times its per-vertex rays (0: none)",
            invalidates: Invalidates::Uniform,
        },
        frame_patches: u64 = Param {
            kind: ParamKind::Integer {
                min: 1,
                max: 1 << 20,
            },
            default: "2048",
            doc: "the most 1st passes a frame draws, all levels together (nested levels are left out first)",
            invalidates: Invalidates::Uniform,
        },
        frame_texels: u64 = Param {
            kind: ParamKind::Integer {
                min: 1,
                max: 1 << 32,
            },
            default: "16777216",
            doc: "the most reflection-map texels a frame draws, all levels together (nested levels are left out first)",
            invalidates: Invalidates::Uniform,
        },
        ior: Ior = Param {
            kind: ParamKind::Text {
                expected: "`material`, one index of refraction or three (red,green,blue), each above 1 and at most 4",
            },
            default: "material",
            doc: "the lenses' indices of refraction (three: chromatic aberration)",
            invalidates: Invalidates::Scene,
        },
        cached: bool = Param {
            kind: ParamKind::Flag,
            default: "false",
            doc: "keep exit rays and patches in the eye's frame while the lens does not move relative to it",
            invalidates: Invalidates::Uniform,
        },
        markers: bool = Param {
            kind: ParamKind::Flag,
            default: "false",
            doc: "verification overlay: a red ball at every vertex's exact ray-traced hit",
            invalidates: Invalidates::Uniform,
        },
        marker_size: f32 = Param {
            kind: ParamKind::Number { min: 1e-6, max: 0.1 },
            default: "0.012",
            doc: "marker radius as a fraction of its distance from the reflector",
            invalidates: Invalidates::Uniform,
        },
    }
}

pub const INFO: MethodInfo = MethodInfo {
    name: "pvrr",
    summary: "per-vertex reflection and refraction (Kakimoto et al.): exact at every vertex",
    exact: false,
    needs_gpu: true,
    gpu_optional: false,
    progressive: false,
    delegates: &[],
    params: Params::SPECS,
    presets: &[specula_core::Preset {
        name: "paper",
        summary: "the published algorithm (Kakimoto, Tatsukawa, Chun, Nishita): one view per reflector, the zooming region as projected, a lens's transmitted light only",
        settings: &[
            "max_patches=1",
            "fit_hits=false",
            "zooming=map",
            "surface_reflection=false",
            "internal_reflection=false",
            "nested_share=1000",
            "frame_patches=1048576",
            "frame_texels=4294967296",
        ],
    }],
    create: || Box::new(GpuMethod::<Pvrr>::default()),
};

/// The smallest map height a patch gets, however little of the view it covers.
const MIN_MAP_TEXELS: u32 = 16;

/// Fewer visible vertices than this, and the linear warp between them is too coarse to trust.
const MIN_VISIBLE_VERTICES: usize = 9;

/// Host mirror of WGSL `MirrorMaterial`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuMirrorMaterial {
    pub f0: [f32; 3],
    pub fresnel: u32,
    pub stripes: u32,
    /// 1: blend in the ray-traced radiance of the unresolved vertices (not `zooming=map`).
    pub blend_traced: u32,
    pub pad: [u32; 2],
}

/// One corner of a reflector triangle for the 2nd pass.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct MirrorVertex {
    position: [f32; 3],
    normal: [f32; 3],
    uv: [f32; 2],
    /// Fresnel transmittance along a lens path; 1 on mirrors.
    weight: f32,
    /// 1 where the vertex's P could not be placed in its patch's map (zooming region).
    unresolved: f32,
    /// An unresolved vertex's radiance, ray traced along its exit segment (0 elsewhere, and
    /// everywhere with `zooming=map`).
    traced: [f32; 3],
}

/// Texture coordinate ((0, 0) = top-left) of `p` in the map rendered with `view`: where the
/// line from the map's viewpoint through `p` meets the map's plane (§3.1, step 3.3). A `p`
/// behind the viewpoint (the zooming region) meets it beyond the viewpoint, on the far side of
/// the map's centre; with `mirror_behind` such a `p` is first mirrored to the front of the
/// viewpoint's plane instead, which is where a traced vertex looks the map up for its blend
/// between a resolved and an unresolved corner.
pub fn map_uv(view: &CameraUniform, p: Vec3, mirror_behind: bool) -> [f32; 2] {
    let clip = glam::Mat4::from_cols_array_2d(&view.clip_from_world) * Vec4::from((p, 1.0));
    let w = if mirror_behind || clip.w >= 0.0 {
        clip.w.abs().max(1e-20)
    } else {
        clip.w.min(-1e-20)
    };
    let ndc = clip.truncate() / w;
    [ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5]
}

/// One patch ready to draw: its 1st pass camera and, per colour channel, its triangles'
/// corners with texture coordinates into that map.
struct PatchDraw {
    camera: CameraUniform,
    /// A zooming view's (`camera` looks back toward the mirror): the forward view from the
    /// same viewpoint, drawn upside down first, so that each texel of the map holds what lies
    /// beyond the viewpoint on its line where nothing lies between the mirror and the
    /// viewpoint.
    fill: Option<CameraUniform>,
    channels: Vec<Vec<MirrorVertex>>,
    /// Per corner (the channels share their order), whether its P lies on another mirror or
    /// lens: a nested level (`depth` ≥ 2) shows it in the map, else its traced radiance does.
    reflector_corners: Vec<bool>,
}

impl PatchDraw {
    /// Whether some vertex's P lies on another mirror or lens: only then does a nested level
    /// show anything in its map.
    fn sees_reflectors(&self) -> bool {
        self.reflector_corners.contains(&true)
    }

    /// Its corners whose P lies on another reflector take their traced radiance (a patch
    /// without a nested level, whose map shows that reflector black). Returns how many.
    fn trace_reflector_corners(&mut self) -> u64 {
        for channel in &mut self.channels {
            for (corner, &on) in channel.iter_mut().zip(&self.reflector_corners) {
                if on {
                    corner.unresolved = 1.0;
                }
            }
        }
        self.reflector_corners.iter().filter(|&&on| on).count() as u64
    }

    /// Its 1st passes.
    fn passes(&self) -> u64 {
        1 + self.fill.is_some() as u64
    }

    /// The texels its 1st passes draw.
    fn texels(&self) -> u64 {
        (self.camera.width * self.camera.height) as u64 * self.passes()
    }
}

/// A patch's 1st pass camera, `height` texels high, and with a zooming view the camera of the
/// forward view drawn first into the same map ([`PatchDraw::fill`]).
fn patch_cameras(patch: &Patch, height: u32) -> (CameraUniform, Option<CameraUniform>) {
    match &patch.zooming {
        None => (patch.extents.camera(&patch.basis, height), None),
        Some(zooming) => {
            // The forward view through the same texels: the zooming view's field.
            let forward = Extents {
                tan_x: zooming.tan_x,
                tan_y: zooming.tan_y,
                ..patch.extents.clone()
            };
            (
                zooming.camera(&patch.basis.reversed(), height),
                Some(upside_down(forward.camera(&patch.basis, height))),
            )
        }
    }
}

/// `camera` drawing its image upside down, with the directions its pixels stand for turned
/// with it: texel (x, y) of it shows the scene in the direction opposite to texel
/// (x, y) of the view from the same viewpoint looking back with `right` reversed
/// ([`view::ViewBasis::reversed`]), the same line through the viewpoint.
fn upside_down(mut camera: CameraUniform) -> CameraUniform {
    let flip = glam::Mat4::from_scale(Vec3::new(1.0, -1.0, 1.0));
    camera.clip_from_world =
        (flip * glam::Mat4::from_cols_array_2d(&camera.clip_from_world)).to_cols_array_2d();
    camera.up_world = (-Vec3::from_array(camera.up_world)).to_array();
    camera
}

/// One reflector seen from one eye, ready for both passes.
struct ReflectorDraw {
    mesh: usize,
    material: GpuMirrorMaterial,
    /// Added to what the reflector's earlier draw left (a dielectric's reflections).
    additive: bool,
    patches: Vec<PatchDraw>,
}

/// A reflector's eye-relative state kept by the cached mode.
struct CachedReflector {
    /// The mesh's vertices in the eye's frame when the state was computed, and its
    /// interaction: the state is valid while both are unchanged.
    key: Vec<Vec3>,
    interaction: Interaction,
    paths: MeshPaths,
    patches: Vec<Patch>,
}

/// A mirror or dielectric mesh: how it bends rays and how its 2nd pass shades. A solid
/// dielectric is three: its transmitted light, then its surface reflection and the light
/// reflected once inside it, added over it (a thin sheet has no third).
struct Reflector {
    mesh: usize,
    interaction: Interaction,
    material: GpuMirrorMaterial,
    additive: bool,
}

impl Reflector {
    fn of(scene: &Scene, mesh: usize, ior_override: Option<Vec3>) -> Vec<Reflector> {
        let material = &scene.materials[scene.meshes[mesh].material];
        let Some(interaction) = Interaction::of(&material.kind, ior_override) else {
            return Vec::new();
        };
        // A lens's 2nd pass is weighted by the path's exact Fresnel terms instead.
        let weighted = GpuMirrorMaterial {
            f0: [1.0; 3],
            ..Zeroable::zeroed()
        };
        let first = Reflector {
            mesh,
            interaction,
            material: match material.kind {
                MaterialKind::Mirror { fresnel } => GpuMirrorMaterial {
                    f0: material.color.to_array(),
                    fresnel: fresnel as u32,
                    ..Zeroable::zeroed()
                },
                _ => weighted,
            },
            additive: false,
        };
        let added = [
            Interaction::surface_reflection(&material.kind, ior_override),
            Interaction::internal_reflection(&material.kind, ior_override),
        ];
        std::iter::once(first)
            .chain(added.into_iter().flatten().map(|interaction| Reflector {
                mesh,
                interaction,
                material: weighted,
                additive: true,
            }))
            .collect()
    }
}

/// Per-frame tallies for the frame's counters and warnings.
#[derive(Default)]
struct Tally {
    rays: u64,
    /// 1st passes: one per patch, two per zooming view.
    passes: u64,
    map_texels: u64,
    /// Of those, in levels below the top.
    nested_passes: u64,
    nested_texels: u64,
    /// Outer patches whose nested level the frame budget left out.
    budget_cuts: u64,
    /// Patches drawn from a zooming view.
    zooming_views: u64,
    unresolved: u64,
    cache_hits: u64,
    principal_up: u64,
    warnings: Vec<String>,
}

pub struct Prepared {
    /// The scene version the corners and far distance were made for.
    version: u64,
    /// Every mirror and dielectric mesh.
    reflectors: Vec<Reflector>,
    /// Corners of the scene's bounds, which every map's far plane must hold.
    scene_corners: Vec<Vec3>,
    /// How far along an exit ray that leaves the scene its P is put.
    far_distance: f32,
    /// 2nd pass pipelines writing all channels, then red, green, blue only.
    pipelines: [wgpu::RenderPipeline; 4],
    /// The 2nd pass pipeline adding to what is there (a dielectric's reflections), where the
    /// device can blend float targets.
    additive: Option<wgpu::RenderPipeline>,
    layout: wgpu::BindGroupLayout,
    /// Per-frame data written in place: 2nd-pass and marker vertices, and uniforms (cameras,
    /// materials) bound at dynamic offsets.
    arenas: RefCell<Arenas>,
}

struct Arenas {
    vertices: Arena,
    uniforms: Arena,
    /// 2nd-pass bind group per map (G-buffer pool slot), for the arenas' current buffers.
    bind_groups: BindGroupsBySlot,
}

/// What the frame's steps read: the prepared state and the live scene's BVH and GPU upload.
struct Shared<'a> {
    prepared: &'a Prepared,
    raster: &'a RasterPass,
    accel: &'a SceneAccel,
    gpu_scene: &'a GpuScene,
}

impl std::ops::Deref for Shared<'_> {
    type Target = Prepared;
    fn deref(&self) -> &Prepared {
        self.prepared
    }
}

#[derive(Default)]
pub struct Pvrr {
    pub params: Params,
    /// Per reflector, its exit rays and patches in the eye's frame (`cached`).
    cache: Vec<Option<CachedReflector>>,
}

/// A marker ball: centre, radius, colour channel (0 red, 1 green, 2 blue).
type Ball = (Vec3, f32, u32);

/// Marker balls for one channel's hits: `size` × the distance from the exit point, capped at
/// 0.3 × the distance to the nearest neighbouring vertex's P so that balls stay apart.
fn marker_balls(
    size: f32,
    channel: u32,
    mesh: &specula_scene::Mesh,
    visible: &[bool],
    exits: &[Segment],
    hits: &[Vec3],
) -> Vec<Ball> {
    let mut nearest = vec![f32::INFINITY; hits.len()];
    for tri in &mesh.triangles {
        for k in 0..3 {
            let (i, j) = (tri[k] as usize, tri[(k + 1) % 3] as usize);
            let d = (hits[i] - hits[j]).length();
            if d > 0.0 {
                nearest[i] = nearest[i].min(d);
                nearest[j] = nearest[j].min(d);
            }
        }
    }
    (0..hits.len())
        .filter(|&i| visible[i])
        .map(|i| {
            let radius = ((hits[i] - exits[i].origin).length() * size).min(0.3 * nearest[i]);
            (hits[i], radius, channel)
        })
        .collect()
}

/// `paths` and `patches` with every point and direction carried by `point` and `vector` (to or
/// from the eye's frame).
fn map_state(
    paths: &MeshPaths,
    patches: &[Patch],
    point: impl Fn(Vec3) -> Vec3,
    vector: impl Fn(Vec3) -> Vec3,
) -> (MeshPaths, Vec<Patch>) {
    let channels = paths
        .channels
        .iter()
        .map(|c| ChannelPaths {
            exits: c
                .exits
                .iter()
                .map(|s| Segment {
                    origin: point(s.origin),
                    dir: vector(s.dir),
                })
                .collect(),
            weights: c.weights.clone(),
        })
        .collect();
    let patches = patches
        .iter()
        .map(|patch| Patch {
            basis: ViewBasis {
                viewpoint: point(patch.basis.viewpoint),
                right: vector(patch.basis.right),
                up: vector(patch.basis.up),
                forward: vector(patch.basis.forward),
            },
            ..patch.clone()
        })
        .collect();
    let paths = MeshPaths {
        visible: paths.visible.clone(),
        channels,
        rays: paths.rays,
    };
    (paths, patches)
}

impl CachedReflector {
    fn matches(&self, key: &[Vec3], interaction: &Interaction) -> bool {
        self.interaction == *interaction
            && self.key.len() == key.len()
            && self
                .key
                .iter()
                .zip(key)
                .all(|(a, b)| (*a - *b).abs().max_element() <= 1e-6 * (1.0 + a.abs().max_element()))
    }
}

/// The corners of the scene's bounds (which every map's far plane must hold), and how far along
/// an exit ray that leaves the scene its P is put.
fn scene_extent(scene: &Scene) -> (Vec<Vec3>, f32) {
    let bounds = scene.bounds();
    let corners = (0..8)
        .map(|k| {
            Vec3::select(
                glam::BVec3::new(k & 1 != 0, k & 2 != 0, k & 4 != 0),
                bounds.max,
                bounds.min,
            )
        })
        .collect();
    (corners, (bounds.radius() * 4.0).max(1.0))
}

impl GpuTechnique for Pvrr {
    type Prepared = Prepared;
    type Params = Params;
    const INFO: &'static MethodInfo = &INFO;

    fn params(&self) -> &Params {
        &self.params
    }

    fn params_mut(&mut self) -> &mut Params {
        &mut self.params
    }

    /// Its G-buffer holds the markers too, drawn after the reflection maps.
    fn draws_own_g_buffer(&self) -> bool {
        true
    }

    fn prepare(
        &mut self,
        gpu: &GpuContext,
        live: &LiveScene,
        _: Option<&RasterPass>,
    ) -> Result<Prepared, TechniqueError> {
        // The cache survives: its entries are checked against the new scene's geometry.
        Ok(self.build(gpu, live)?)
    }

    fn invalidate(&mut self, _: Option<&mut Prepared>, what: Invalidates) -> bool {
        if what >= Invalidates::Resources {
            self.cache.clear();
        }
        true
    }

    /// The paper's steps: per-vertex rays and the patches' views planned (steps 1–5), the
    /// reflection maps (1st pass), the scene's G-buffer, then the reflectors drawn with their
    /// vertices' texture coordinates (2nd pass).
    fn shade(
        &mut self,
        prepared: &mut Prepared,
        frame: &mut GpuFrame<'_>,
    ) -> Result<(), TechniqueError> {
        let (gpu, live) = (frame.gpu, frame.live);
        if prepared.version != live.version() {
            (prepared.scene_corners, prepared.far_distance) = scene_extent(live.scene());
            prepared.version = live.version();
        }
        let p = Shared {
            prepared,
            raster: frame.raster(),
            accel: live.accel(),
            gpu_scene: live.gpu(gpu),
        };
        {
            let mut arenas = p.arenas.borrow_mut();
            arenas.vertices.begin_frame();
            arenas.uniforms.begin_frame();
        }
        let (tree, mut tally, traced_corners) = self.plan(&p, live.scene(), frame.camera);
        frame.lap("per-vertex rays")?;
        let markers = self.markers(&p, gpu, &tree, &tally)?;
        // Marker vertices sit at `offset` in the vertex arena; the raster pass draws them from a
        // buffer of their own, so the arena's buffer is passed with a slice there.
        let arena_buffer = markers.map(|_| p.arenas.borrow().vertices.buffer().clone());
        let marker_slice = arena_buffer
            .as_ref()
            .zip(markers)
            .map(|(buffer, (offset, count))| (buffer, offset, count));
        let maps = render_maps(gpu, &p, &tree, marker_slice)?;
        frame.lap("reflection maps (1st pass)")?;
        let g =
            p.raster
                .render_with(gpu, p.gpu_scene, &frame.camera_uniform, None, marker_slice)?;
        frame.lap("g-buffer")?;
        second_pass(gpu, &p, &frame.camera_uniform, &g, &tree.level, &maps)?;
        let vertex_peak = p.arenas.borrow().vertices.peak();
        frame.lap("mirror (2nd pass)")?;
        // The 2nd pass drew over the G-buffer's colour: that is the frame.
        frame.show(g.color.clone());
        for warning in std::mem::take(&mut tally.warnings) {
            frame.warn(warning);
        }
        count(frame, &tree, &tally, vertex_peak, traced_corners);
        Ok(())
    }
}

impl Pvrr {
    /// Steps 1–5 for every level of reflectors seen in reflectors, within the frame budget:
    /// the plan, what it counted, and the corners traced for want of a nested level.
    fn plan(&mut self, p: &Shared, scene: &Scene, camera: &Camera) -> (PlanTree, Tally, u64) {
        // The top level fits the frame budget by itself: each reflector's patches and map
        // (at most 4 times as wide as high) within its share of it, each patch perhaps a
        // zooming view (two 1st passes, twice the texels).
        let reflectors = p.reflectors.len().max(1) as u64;
        let top_patches = (self.params.frame_patches / reflectors / 2).max(1) as usize;
        let top_resolution = ((self.params.frame_texels / reflectors / 8) as f64).sqrt() as u32;
        let settings = PlanSettings {
            resolution: self
                .params
                .resolution
                .min(top_resolution.max(MIN_MAP_TEXELS)),
            limits: PatchLimits {
                max_fov_deg: self.params.max_fov,
                max_patches: self.params.max_patches.min(top_patches),
                zooming_view: self.params.zooming == Zooming::View,
            },
            markers: self.params.markers.then_some(self.params.marker_size),
            fit_hits: self.params.fit_hits,
            zooming: self.params.zooming,
            surface_reflection: self.params.surface_reflection,
            internal_reflection: self.params.internal_reflection,
        };
        let frame = camera.frame();
        let eye_frame = EyeFrame {
            origin: camera.eye,
            right: frame.right,
            up: frame.up,
            forward: frame.forward,
        };
        let mut tally = Tally::default();
        let cache = self.params.cached.then_some((&mut self.cache, &eye_frame));
        let top = plan_level(
            p, &settings, scene, camera.eye, None, cache, &mut tally, true,
        );
        let limits = FrameLimits {
            nested_share: self.params.nested_share,
            frame_patches: self.params.frame_patches,
            frame_texels: self.params.frame_texels,
        };
        let mut budget = FrameBudget::after_top(&top, tally.rays, &limits);
        let mut tree = plan_tree(
            p,
            &settings,
            scene,
            top,
            self.params.depth,
            &mut budget,
            &mut tally,
        );
        let traced_corners = trace_where_no_nested_level(&mut tree);
        if tally.budget_cuts > 0 {
            tally.warnings.push(format!(
                "pvrr: the frame budget (nested_share = {}, frame_patches = {}, frame_texels = {}) left out the reflections seen in reflectors of {} map(s): other reflectors show there as the scene raster draws them, their vertices' ray-traced radiance blended in",
                self.params.nested_share, self.params.frame_patches, self.params.frame_texels, tally.budget_cuts
            ));
        }
        (tree, tally, traced_corners)
    }

    /// The verification markers' vertices, in the vertex arena: (offset, count). Every buffer
    /// the frame writes is sized from the plan and checked before any is.
    fn markers(
        &self,
        p: &Shared,
        gpu: &GpuContext,
        tree: &PlanTree,
        tally: &Tally,
    ) -> Result<Option<(u64, u32)>, TechniqueError> {
        let markers = self
            .params
            .markers
            .then(|| marker_vertices(p.gpu_scene.marker_mesh(0), &tree.level.balls));
        let marker_bytes = markers
            .as_ref()
            .map_or(0, |m| std::mem::size_of_val(m.as_slice()) as u64);
        let peak = tree.peak_vertex_bytes() + marker_bytes;
        let limit = gpu.device.limits().max_buffer_size;
        if peak > limit {
            return Err(GpuError::TooLarge {
                what: format!(
                    "pvrr's 2nd-pass vertices for this view ({} 1st passes, {} reflectors)",
                    tally.passes,
                    tree.level.reflectors.len()
                ),
                bytes: peak,
                limit,
            }
            .into());
        }
        Ok(match markers {
            Some(vertices) => {
                let mut arenas = p.arenas.borrow_mut();
                let bytes: &[u8] = bytemuck::cast_slice(&vertices);
                arenas.vertices.reserve(gpu, [bytes.len() as u64])?;
                let offset = arenas.vertices.push(gpu, bytes);
                Some((offset, vertices.len() as u32))
            }
            None => None,
        })
    }
}

/// The frame's counters, as reports list them.
fn count(
    frame: &mut GpuFrame<'_>,
    tree: &PlanTree,
    tally: &Tally,
    vertex_peak: u64,
    traced_corners: u64,
) {
    frame.count("mirrors", tree.level.reflectors.len() as u64);
    frame.count("per-vertex rays", tally.rays);
    frame.count("1st passes", tally.passes);
    frame.count("patches with a principal up vector", tally.principal_up);
    frame.count("reflection map texels", tally.map_texels);
    frame.count("1st passes in levels below the top", tally.nested_passes);
    frame.count("map texels in levels below the top", tally.nested_texels);
    frame.count(
        "maps whose nested level the frame budget left out",
        tally.budget_cuts,
    );
    frame.count("largest 2nd-pass vertex buffer (bytes)", vertex_peak);
    frame.count("patches drawn from a zooming view", tally.zooming_views);
    frame.count(
        "corners on another reflector traced for want of a nested level",
        traced_corners,
    );
    frame.count("unresolved vertices", tally.unresolved);
    frame.count("reflectors from the cache", tally.cache_hits);
}

/// `material`, one index, or three (red, green, blue), each in (1, 4].
fn parse_ior(value: &str) -> Result<Option<Vec3>, &'static str> {
    if value == "material" {
        return Ok(None);
    }
    let values: Vec<f32> = value
        .split(',')
        .map(|v| v.trim().parse::<f32>().ok().filter(|i| *i > 1.0 && *i <= 4.0))
        .collect::<Option<_>>()
        .ok_or("expected `material`, one index of refraction or three (red,green,blue), each above 1 and at most 4")?;
    match values[..] {
        [i] => Ok(Some(Vec3::splat(i))),
        [r, g, b] => Ok(Some(Vec3::new(r, g, b))),
        _ => Err("expected one index of refraction or three (red,green,blue)"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A zooming view and the forward view drawn upside down into the same map agree on every
    /// line through the viewpoint: a point before the viewpoint (the zooming side) and a point
    /// beyond it land on the same texel in both, the one projected, the other through the
    /// viewpoint (w < 0), so the map's forward content sits where the 2nd pass looks it up.
    #[test]
    fn a_zooming_view_and_its_upside_down_forward_view_share_their_texels() {
        let basis = ViewBasis {
            viewpoint: Vec3::new(0.3, 1.2, 2.0),
            right: Vec3::new(0.0, 0.0, -1.0),
            up: Vec3::Y,
            forward: Vec3::X,
        };
        // Hits on both sides of the viewpoint, spread over a 40 × 30° field.
        let segments: Vec<(Vec3, Vec3)> = (0..12)
            .map(|k| {
                let (a, b) = ((k % 4) as f32 / 3.0 - 0.5, (k / 4) as f32 / 2.0 - 0.5);
                let direction = basis.forward + basis.right * 0.7 * a + basis.up * 0.5 * b;
                let side = if k % 2 == 0 { 1.5 } else { -0.8 };
                (
                    basis.viewpoint - direction * 2.0,
                    basis.viewpoint + direction * side,
                )
            })
            .collect();
        let patch = Patch {
            triangles: vec![0],
            basis,
            extents: Extents::new(
                &basis,
                &segments,
                &[basis.viewpoint + basis.forward * 9.0],
                false,
            ),
            zooming: Some(Extents::zooming(&basis.reversed(), &segments)),
            principal_up: false,
            fallback: None,
        };
        let (zooming, fill) = patch_cameras(&patch, 64);
        let fill = fill.expect("a zooming patch has a forward view to draw first");
        assert_eq!((zooming.width, zooming.height), (fill.width, fill.height));
        for &(_, p) in &segments {
            let (z, f) = (map_uv(&zooming, p, false), map_uv(&fill, p, false));
            assert!(
                (z[0] - f[0]).abs() < 1e-4 && (z[1] - f[1]).abs() < 1e-4,
                "{z:?} {f:?}"
            );
            assert!(
                z.iter().all(|c| (0.0..=1.0).contains(c)),
                "{z:?} outside the map"
            );
        }
        // And the direction each texel of the upside-down view shows is the opposite of the
        // zooming view's, as its background is drawn (camera_ray_direction).
        let direction = |c: &CameraUniform, u: f32, v: f32| {
            let x = (2.0 * u - 1.0) * c.tan_half_fov_y * c.aspect;
            let y = (1.0 - 2.0 * v) * c.tan_half_fov_y;
            (Vec3::from(c.forward_world)
                + x * Vec3::from(c.right_world)
                + y * Vec3::from(c.up_world))
            .normalize()
        };
        for (u, v) in [(0.1, 0.2), (0.5, 0.5), (0.9, 0.7)] {
            let sum = direction(&zooming, u, v) + direction(&fill, u, v);
            assert!(sum.length() < 1e-5, "{sum}");
        }
    }
}
