//! `c3rc`: hybrid backward–forward reflections with continuous 3-ray cameras.
//!
//! Paper: Mei, Popescu, Sacks, *A hybrid backward-forward method for interactive reflections*,
//! GRAPP 2007; the projection cubic and the multiple-projection quadratic derived below
//! (the paper's text states them without their coefficients).
//!
//! Steps, and where they are:
//! 1. Pre-processing (§3.1, §4; [`points`]): every non-specular object within `near` reflector
//!    radii of a mirror ([`cpu_frame::mesh_is_near`]) is sampled uniformly by area
//!    ([`points::PointCloud::sample`]), each point shaded as the reference shades that surface
//!    ([`points::PointCloud::shade`]) and given a splat radius (the disc it stands for); an
//!    eight-way kd-tree per object ([`points::PointCloud::build_tree`]: each node splits at its
//!    box's centre on all three axes at once), kept in the object's loaded pose so that a rigid
//!    move keeps it (colours are shaded again after a move: light and shadows change).
//! 2. Far field: the cube maps of `specula-core` ([`CubeMaps`]) drawn from each mirror with
//!    its nearby objects left out (the paper's environment-mapped background, §7).
//! 3. A C3RC per visible mirror triangle (§5; [`camera::C3rc::reflector`]): the view direction
//!    reflected about each vertex normal; the base is the triangle. The G-buffer says which
//!    triangles are visible and how many pixels each covers ([`cpu_frame::plan`]). The paper builds
//!    one per triangle and its depth test hides the splats of hidden ones; here a hidden
//!    triangle has no pixel for its splats.
//! 4. Backward phase (§5.2; [`cpu_frame::plan`]): each camera, mapped into each object's space,
//!    against that object's tree ([`camera::C3rc::corner_inside_or_face_meets_wall`]: the
//!    paper's two conditions, a face meeting a side wall read as the paper defines it, not only
//!    where the wall crosses the face's frame, which would cull every box a narrow volume passes
//!    through; by default the conservative [`camera::C3rc::may_see_box`], below), collecting
//!    leaves.
//! 5. Forward phase (§5.1, §6; [`cpu_frame::forward`] on the CPU, [`gpu::GpuProjection`] as GPU
//!    compute passes): each leaf's points projected with the camera (the cubic; a point may
//!    show several times, in one camera or in several), each splatted as a square at the pixel
//!    of its base point, with push-back depth (its distance from the reflector) so that the
//!    point nearest the reflector wins (ties: the splat whose centre is nearest the pixel's).
//!    A splat lands only on pixels of the mirror it was projected from whose surface point lies
//!    within the splat's reach of its base point (the paper does not say how splats are kept
//!    on the reflector; this keeps them off other objects and off other parts of the mirror in
//!    front, as a depth test would).
//! 6. Shading: envmap's shading pass, taking a mirror pixel's reflected radiance from the
//!    splats where they cover it and from the far-field cube map where they do not.
//!
//! With `exact_hits` (the default) steps 5 and 6 go further ([`cpu_frame`]'s `resolve_exact`):
//! a splat only nominates its point's triangle for the pixels it covers; each mirror pixel's
//! exact reflected ray is met with the nominated triangles, the nearest meeting inside one
//! wins, its colour is the albedo where the ray meets it (texture at the exact UV) times the
//! light its points carry; and the shading pass searches the ray's segment up to that hit in
//! the far field's world positions (16 steps, as distance maps search), showing a far surface
//! it finds in front.
//!
//! Beyond the paper (each switched off by the `paper` preset; `specula methods` lists it):
//! - Conservative box test: boxes are also kept where the base triangle's inside meets them
//!   with the tested corner behind the base (objects touching the mirror), and where a
//!   self-intersecting camera folds over (the fold's surface bounds the volume there and is
//!   neither a wall nor the base); the paper's two conditions cull those and their points go
//!   missing (paper: `conservative_culling=false`).
//! - One-sided points: a point facing away from the reflector triangle is not splatted, and a
//!   tree node whose normal cone faces away from it is not visited (a closed object's back
//!   cannot show through holes in its front; an open mesh seen from its back is not reflected).
//!   The paper splats every point with its one colour (paper: `one_sided=false`).
//! - Every valid projection of a point is splatted (the paper's GPU issued one fragment per
//!   vertex and so did not support multiple projections, §6); switched off, the first is kept,
//!   at the smallest λ: nearest the reflector (paper: `multiple_projections=false`).
//! - Footprint-sized splats: each splat's square is sized to the point's disc against the
//!   sweeping triangle's cross-section there, mapped to the triangle's screen area, times
//!   `splat_scale`, at most `max_splat`; the paper's squares have a fixed side of 1 or 2 pixels,
//!   the preset takes 2 (fewer holes at the same density) (paper: `fixed_splat=2`).
//! - Exact hits (`exact_hits`, above): the paper's pixel takes the colour of the splat that wins
//!   the z-buffer; here splats nominate surfaces and each pixel's own reflected ray picks among
//!   them, so a magnified point leaves no block of one colour, a room's walls meet at sharp
//!   edges, and a splat too large costs time but does not blur. Each splat is at least as large
//!   as its point's disc edge projected with the same camera (the actual footprint). The far
//!   field has depth: a far object in front of a nearby one shows (paper: `exact_hits=false`,
//!   its z-buffer of colours with the far field behind every splat).
//! - Splats resolve in two steps: the nearest push-back depth finds the front surface, then
//!   within a depth band the splat whose centre is nearest the pixel's gives the colour; the
//!   paper's z-buffer keeps the nearest depth alone (paper: `depth_band=false`).
//! - Mirror pixels left uncovered with at least five of their eight neighbours covered take the
//!   front-most neighbour's colour; with exact hits instead, every mirror pixel is tried with
//!   the triangles its neighbours' rays met (5 × 5, up to 4 passes), filling the gaps no splat
//!   reached and mending pixels whose splats missed the nearer surface; the paper avoids holes
//!   by its sampling rate and splat size alone (§3.1) (paper: `fill_holes=false`).
//! - `trace_self`: a triangle whose vertex rays hit its own mirror (a teapot's body seeing its
//!   spout, lid and knob) gets no camera: its pixels are traced, one exact ray each. C3RC is
//!   first order (a reflector does not see itself); these are the pixels where that is wrong
//!   (paper: `trace_self=false`).
//! - `level_of_detail`: where a camera minifies a leaf so much that its points would crowd
//!   more than four into a pixel, every k-th point is projected with its splat grown to match;
//!   a node whose strided points number at most 128 is projected whole, not descended
//!   (paper: `level_of_detail=false`).
//! - `two_level_maps`: with two reflectors or more, the far field's cube maps shade the other
//!   specular objects they show from those objects' own maps, and their first level keeps the
//!   nearby objects, so that another mirror in the far field shows them; the paper's far field
//!   shows other specular objects black (paper: `two_level_maps=false`).
//!
//! Every switch but `exact_hits` acts on both projection paths (`projection=cpu` and `gpu`):
//! the culling, the cameras and the per-vertex and traced pixels are the CPU's on both; the
//! GPU's passes read the splat switches from each camera and skip the hole filling. docs/methods/c3rc.md has what
//! `trace_self` and `level_of_detail` bought.
//!
//! Implementation (changes no pixel): four planes bounding each camera's volume cull boxes and
//! points before the exact tests (only what lies outside the volume, which has no valid
//! projection); roots of the cubic beyond the largest λ at which the camera reaches the object
//! are not examined; a camera that cannot fold stops at its first valid root; the per-vertex
//! rays are traced only when `trace_self` or `min_pixels` may use them; the work is spread over
//! threads node by node and the resolve row band by row band. (Checked: with the planes, the λ
//! cut and the early stop removed, four scenes rendered byte-identical PNGs, with the defaults
//! and with the paper preset.)
//!
//! Approximations and artifacts:
//! - Point-based: the nearby objects are points, not surfaces. Too few points or too small
//!   splats leave holes (the far field shows through as speckles); with splatted colours too
//!   large splats blur and fatten edges (an object's silhouette grows by about a splat; with
//!   exact hits only by what a point's disc extrapolates). Where reflected rays converge
//!   (concave mirrors) a point's footprint grows past `max_splat` and holes appear: a small
//!   ball at a concave mirror's focal point, magnified many times, shows only in part. With the
//!   paper's fixed 2-pixel splats, holes appear wherever a mirror magnifies the points' spacing
//!   past 2 pixels.
//! - Exact hits: a surface whose triangles no splat nominates at a pixel is not there (a thin
//!   gap at a silhouette whose triangles are smaller than the points' spacing); lighting comes
//!   from the points, averaged over the splats (the point's disc times `splat_scale`) of the
//!   same object that hold the hit, so a shadow edge is that soft, and light bleeds across a
//!   room's corner within a splat's radius; a larger `splat_scale` also extrapolates a point's
//!   plane farther (silhouettes grow where a surface's true triangles are not nominated).
//! - Rays inside a camera are interpolated linearly between the vertices' reflected rays, not
//!   reflected about the interpolated normal: large curved triangles bend the reflection
//!   slightly (continuous across edges, exact at vertices).
//! - Other mirrors are not points: a mirror sees other mirrors only through the far field, as
//!   in envmap (and itself only where `trace_self` traces).
//! - The near/far split is per object: a far object is exactly as wrong as in envmap, a near one is
//!   right. On scenes whose objects are all far (door-mirror) c3rc is envmap but for the small
//!   triangles' per-vertex colour. With splatted colours (`exact_hits=false`) splats win over
//!   the far field wherever they cover a pixel, with no depth comparison: a far object in front
//!   of a near one is hidden by it (the suite's concave mirror, inside a room that is near: the
//!   yellow box 1.5 m away, beyond 3 mirror radii, does not show). With exact hits the far field
//!   is searched along the ray in 16 steps: a far surface thinner than a step may be missed,
//!   and a far surface between the reflector's centre and the ray, within two steps of a
//!   point the ray passes, may be taken for one in front of it (the parallax of a single
//!   cube map, as distance maps have without their refinement).
//! - Dielectric objects are shaded as envmap shades them, with the nearby objects in their
//!   cube maps.
//!
//! ## Parameters
//!
//! <!-- The parameter table: made from `Params::SPECS` by `specula_core::params::doc_table`;
//! `SPECULA_REGENERATE=1 cargo test -p specula-methods --lib doc` writes it again. -->
//! | parameter | takes | default | a change redoes | what it does |
//! |---|---|---|---|---|
//! | `points` | a whole number from 1 to 50000000 | `100000` | resources | points over all nearby objects (sets the density): fewer holes, linear projection cost |
//! | `density` | a number from 0 to 1000000000 | `0` | resources | points per square metre; 0 takes the density from `points` |
//! | `near` | a number from 0 to 1000000 | `3` | resources | objects within this many reflector radii become points; farther ones are the cube map's |
//! | `leaf_points` | a whole number from 1 to 1000000 | `256` | resources | kd-tree leaf size: smaller culls more precisely at more culling cost |
//! | `tree_depth` | a whole number from 0 to 30 | `12` | resources | kd-tree depth limit |
//! | `splat_scale` | a number from 0.01 to 100 | `2.5` | uniform | splat radius over the radius of the disc a point stands for: closes holes at more cost (with exact_hits it also widens the light kernel and plane extrapolation; else it blurs) |
//! | `max_splat` | a number from 0.5 to 64 | `16` | uniform | largest splat half-size in pixels (where reflected rays converge) |
//! | `min_pixels` | a whole number from 0 to 1000000 | `0` | uniform | triangles covering fewer visible pixels take the per-vertex reflected colour (0: every visible triangle gets a camera, as the paper; the default since exact hits) |
//! | `split_pixels` | a whole number from 0 to 1000000 | `0` | uniform | triangles covering more pixels are cut in four (up to 3 times) for more cameras; 0: never |
//! | `trace_self` | true or false | `true` | uniform | trace per pixel the triangles whose vertex rays hit their own mirror (false: first order, as the paper) |
//! | `level_of_detail` | true or false | `true` | uniform | project every k-th point of nodes the camera minifies to more than 4 points a pixel (false: every point, as the paper) |
//! | `conservative_culling` | true or false | `true` | uniform | keep the tree boxes the paper's two conditions miss: folds, the base's inside (false: the paper's test, §5.2) |
//! | `one_sided` | true or false | `true` | uniform | skip points (and tree nodes) facing away from the reflector triangle (false: every point splats, as the paper) |
//! | `multiple_projections` | true or false | `true` | uniform | splat every valid projection of a point (false: the first only, as the paper's GPU) |
//! | `fixed_splat` | a number from 0 to 64 | `0` | uniform | side in pixels of every splat square (the paper: 1 or 2); 0 sizes each to its footprint (splat_scale, max_splat) |
//! | `depth_band` | true or false | `true` | uniform | within a depth band behind the nearest splat, the nearest centre gives the colour (false: the nearest depth alone, as the paper) |
//! | `fill_holes` | true or false | `true` | uniform | fill uncovered mirror pixels with at least 5 covered neighbours (with exact_hits: try every mirror pixel with its neighbours' surfaces) (false: the far field shows, as the paper) |
//! | `exact_hits` | true or false | `true` | uniform | splats nominate surfaces: each mirror pixel's exact reflected ray meets their triangles, the albedo is looked up where it hits, lit by the points (false: each pixel takes a splat's colour, as the paper; runs on the CPU) |
//! | `resolution` | a whole number from 1 to 8192 | `256` | resources | texels per far-field cube-map face side |
//! | `dynamic` | true or false | `false` | uniform | redraw the far-field cube maps every frame (else only after a move) |
//! | `two_level_maps` | true or false | `true` | uniform | with two reflectors or more, shade the other specular objects a cube map shows from their own maps (two levels; else black) |
//! | `projection` | one of auto, cpu, gpu | `auto` | uniform | where the forward phase runs: rayon on the CPU, compute passes on the GPU, or auto (the CPU on a software GPU, else the GPU) |
//! | `shadow_resolution` | a whole number from 1 to 8192 | `1024` | scene preparation | texels per side of the scene raster's shadow maps |
//! <!-- end of the parameter table -->
//!
//! What they change:
//! - `points` (100000): how many points the nearby objects get in all (sets the density; the
//!   paper's Table 1 has 10,000 to 543,000, the 100,000-point dragon among them).
//!   More points: fewer holes and sharper reflections, linear cost in projection (less with
//!   the level of detail).
//! - `density` (0 = from `points`): points per square metre, overriding `points`.
//! - `near` (3): objects within this many reflector radii of a mirror become points; farther
//!   ones are the cube map's. Larger: more points, fewer objects in the wrong place.
//! - `leaf_points` (256), `tree_depth` (12): the tree's leaf size and depth. Smaller leaves
//!   cull more precisely (fewer wasted projections) at more culling cost. On the teapot and
//!   100k dragon points at 640×480, culling + projection + splatting took 23.3 ms at 128, 23.0
//!   at 256 and 21.9 at 384 (within run-to-run noise; 256 holds 76 points a leaf there). The
//!   paper states no limits, only the outcome (about 121 points a leaf, Table 1).
//! - `splat_scale` (2.5): splat radius over the radius of the disc a point stands for. Larger
//!   closes holes (random sampling leaves about e^(−scale²) of a surface uncovered: 10 % at
//!   1.5, 0.2 % at 2.5) at more cost; with splatted colours it also blurs (1.5 was the default
//!   before exact hits).
//! - `max_splat` (16): largest splat half-size in pixels (where reflected rays converge); the
//!   cost of a splat grows with its area (6 before exact hits).
//! - `exact_hits` (true): above; runs on the CPU (`projection=auto` keeps the forward phase
//!   there; `projection=gpu` splats colours, with a warning).
//! - `fixed_splat` (0 = footprint-sized): above; a fixed side overrides `splat_scale`,
//!   `max_splat` and the level of detail's growth.
//! - `min_pixels` (0): triangles covering fewer visible pixels do not pay for a camera (§8
//!   says it does not pay off; §7 would draw the teapot's knob with the environment map): their
//!   pixels take the per-vertex reflected colour, the radiance traced exactly along the
//!   reflected ray at each vertex, interpolated (counted: `small triangles`), with exact hits
//!   only where no splat or neighbour reached them; 0 or 1: every visible triangle gets a
//!   camera, as in the paper (paper: `min_pixels=0`). It was 2 before exact hits; an
//!   interpolated colour over a small triangle near a sphere's rim, which spans many reflected
//!   checker squares, is their blur (the closed room at 96 × 72 with exact hits: 0.1446 at 2
//!   when small triangles took the per-vertex colour everywhere, 0.0626 at 2 when only where
//!   nothing else was found, 0.0036 at 0).
//! - `split_pixels` (0 = never): an extension beyond the paper, off by default (so also in the
//!   paper preset): triangles covering more pixels are cut in four, up to three times: each
//!   part's camera interpolates over less (mean FLIP 0.0793 -> 0.0777 on mirror-teapot-bunny
//!   at 8), at more cameras.
//! - `trace_self` (true), `level_of_detail` (true), `conservative_culling` (true), `one_sided`
//!   (true), `multiple_projections` (true), `depth_band` (true, splatted colours only),
//!   `fill_holes` (true): above.
//! - `projection` (auto): where the forward phase runs: `cpu` (rayon), `gpu` (compute
//!   passes, f32), `auto` (the CPU with exact hits, and on a software GPU such as lavapipe,
//!   where it measured 2.3 to 3.9 times faster; the GPU otherwise).
//! - `resolution` (256), `dynamic` (false), `shadow_resolution` (1024): the far-field cube maps
//!   and the scene raster, as in envmap.

pub mod camera;
pub mod gpu;
pub mod cpu_frame;
pub mod points;

use glam::{DMat4, Vec3};
use specula_gpu::shaders::CameraUniform;
use specula_gpu::util::{
    bind_group, buffer_binding, layout_entry, texture_binding, writable_buffer,
};
use specula_gpu::{GpuContext, GpuError};
use specula_scene::{MaterialKind, Scene};

use cpu_frame::{FrameSettings, PhaseReport, PlacedCloud, ScreenView};
use points::{PointCloud, TreeLimits};
use specula_core::cube_maps::{self, CubeMaps, Exit};
use specula_core::gpu_scene::GpuScene;
use specula_core::lifecycle::{GpuFrame, GpuMethod, GpuTechnique};
use specula_core::live_scene::LiveScene;
use specula_core::raster::{self, BindGroupsBySlot, RasterPass};
use specula_core::screen::{PixelSurfaces, SurfaceReadback};
use specula_core::{Invalidates, MethodInfo, Param, ParamKind, TechniqueError};

const SHADER: &str = include_str!("c3rc.wgsl");

pub fn shader_source() -> String {
    cube_maps::shading_shader_source(SHADER)
}

specula_core::params! {
    /// c3rc's parameters (the table above).
    pub struct Params {
        points: u32 = Param {
            kind: ParamKind::Integer { min: 1, max: 50_000_000 },
            default: "100000",
            doc: "points over all nearby objects (sets the density): fewer holes, linear projection cost",
            invalidates: Invalidates::Resources,
        },
        density: f32 = Param {
            kind: ParamKind::Number { min: 0.0, max: 1e9 },
            default: "0",
            doc: "points per square metre; 0 takes the density from `points`",
            invalidates: Invalidates::Resources,
        },
        near: f32 = Param {
            kind: ParamKind::Number { min: 0.0, max: 1e6 },
            default: "3",
            doc: "objects within this many reflector radii become points; farther ones are the cube map's",
            invalidates: Invalidates::Resources,
        },
        leaf_points: usize = Param {
            kind: ParamKind::Integer { min: 1, max: 1_000_000 },
            default: "256",
            doc: "kd-tree leaf size: smaller culls more precisely at more culling cost",
            invalidates: Invalidates::Resources,
        },
        tree_depth: u32 = Param {
            kind: ParamKind::Integer { min: 0, max: 30 },
            default: "12",
            doc: "kd-tree depth limit",
            invalidates: Invalidates::Resources,
        },
        splat_scale: f32 = Param {
            kind: ParamKind::Number { min: 0.01, max: 100.0 },
            default: "2.5",
            doc: "splat radius over the radius of the disc a point stands for: closes holes at more cost (with exact_hits it also widens the light kernel and plane extrapolation; else it blurs)",
            invalidates: Invalidates::Uniform,
        },
        max_splat: f32 = Param {
            kind: ParamKind::Number { min: 0.5, max: 64.0 },
            default: "16",
            doc: "largest splat half-size in pixels (where reflected rays converge)",
            invalidates: Invalidates::Uniform,
        },
        min_pixels: u32 = Param {
            kind: ParamKind::Integer { min: 0, max: 1_000_000 },
            default: "0",
            doc: "triangles covering fewer visible pixels take the per-vertex reflected colour (0: every visible triangle gets a camera, as the paper; the default since exact hits)",
            invalidates: Invalidates::Uniform,
        },
        split_pixels: u32 = Param {
            kind: ParamKind::Integer { min: 0, max: 1_000_000 },
            default: "0",
            doc: "triangles covering more pixels are cut in four (up to 3 times) for more cameras; 0: never",
            invalidates: Invalidates::Uniform,
        },
        trace_self: bool = Param {
            kind: ParamKind::Flag,
            default: "true",
            doc: "trace per pixel the triangles whose vertex rays hit their own mirror (false: first order, as the paper)",
            invalidates: Invalidates::Uniform,
        },
        level_of_detail: bool = Param {
            kind: ParamKind::Flag,
            default: "true",
            doc: "project every k-th point of nodes the camera minifies to more than 4 points a pixel (false: every point, as the paper)",
            invalidates: Invalidates::Uniform,
        },
        conservative_culling: bool = Param {
            kind: ParamKind::Flag,
            default: "true",
            doc: "keep the tree boxes the paper's two conditions miss: folds, the base's inside (false: the paper's test, §5.2)",
            invalidates: Invalidates::Uniform,
        },
        one_sided: bool = Param {
            kind: ParamKind::Flag,
            default: "true",
            doc: "skip points (and tree nodes) facing away from the reflector triangle (false: every point splats, as the paper)",
            invalidates: Invalidates::Uniform,
        },
        multiple_projections: bool = Param {
            kind: ParamKind::Flag,
            default: "true",
            doc: "splat every valid projection of a point (false: the first only, as the paper's GPU)",
            invalidates: Invalidates::Uniform,
        },
        fixed_splat: f32 = Param {
            kind: ParamKind::Number { min: 0.0, max: 64.0 },
            default: "0",
            doc: "side in pixels of every splat square (the paper: 1 or 2); 0 sizes each to its footprint (splat_scale, max_splat)",
            invalidates: Invalidates::Uniform,
        },
        depth_band: bool = Param {
            kind: ParamKind::Flag,
            default: "true",
            doc: "within a depth band behind the nearest splat, the nearest centre gives the colour (false: the nearest depth alone, as the paper)",
            invalidates: Invalidates::Uniform,
        },
        fill_holes: bool = Param {
            kind: ParamKind::Flag,
            default: "true",
            doc: "fill uncovered mirror pixels with at least 5 covered neighbours (with exact_hits: try every mirror pixel with its neighbours' surfaces) (false: the far field shows, as the paper)",
            invalidates: Invalidates::Uniform,
        },
        exact_hits: bool = Param {
            kind: ParamKind::Flag,
            default: "true",
            doc: "splats nominate surfaces: each mirror pixel's exact reflected ray meets their triangles, the albedo is looked up where it hits, lit by the points (false: each pixel takes a splat's colour, as the paper; runs on the CPU)",
            invalidates: Invalidates::Uniform,
        },
        resolution: u32 = Param {
            kind: ParamKind::Integer { min: 1, max: 8192 },
            default: "256",
            doc: "texels per far-field cube-map face side",
            invalidates: Invalidates::Resources,
        },
        dynamic: bool = Param {
            kind: ParamKind::Flag,
            default: "false",
            doc: "redraw the far-field cube maps every frame (else only after a move)",
            invalidates: Invalidates::Uniform,
        },
        two_level_maps: bool = cube_maps::TWO_LEVEL_MAPS,
        projection: Projection = Param {
            kind: ParamKind::Choice(Projection::WORDS),
            default: "auto",
            doc: "where the forward phase runs: rayon on the CPU, compute passes on the GPU, or auto (the CPU on a software GPU, else the GPU)",
            invalidates: Invalidates::Uniform,
        },
        shadow_resolution: u32 = raster::SHADOW_RESOLUTION,
    }
}

pub const INFO: MethodInfo = MethodInfo {
    name: "c3rc",
    summary: "continuous 3-ray cameras: nearby objects as points projected per reflector triangle over an envmap far field",
    exact: false,
    needs_gpu: true,
    gpu_optional: false,
    progressive: false,
    // Refractors are shaded by envmap's shading pass from cube maps drawn as envmap draws
    // them (module doc: "Dielectric objects are shaded as envmap shades them"); only mirrors
    // get points and cameras.
    delegates: &[specula_core::Delegation {
        material: specula_core::SurfaceClass::Refractor,
        to: "envmap",
    }],
    params: Params::SPECS,
    presets: &[specula_core::Preset {
        name: "paper",
        summary: "the published algorithm (Mei, Popescu, Sacks 2007): a camera per visible triangle, the paper's box test, every point splatted once as a fixed 2-pixel square, nearest depth wins",
        settings: &[
            "conservative_culling=false",
            "one_sided=false",
            "multiple_projections=false",
            "fixed_splat=2",
            "depth_band=false",
            "fill_holes=false",
            "exact_hits=false",
            "trace_self=false",
            "min_pixels=0",
            "level_of_detail=false",
            "two_level_maps=false",
        ],
    }],
    create: || Box::new(GpuMethod::<C3rcMethod>::default()),
};

/// Source of `NearField::generation`: unique across techniques and scenes.
static NEXT_GENERATION: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);

/// Largest traced depth of the per-vertex fallback (as the reference's default).
const FALLBACK_MAX_DEPTH: u32 = 8;

/// Where the forward phase runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Projection {
    /// The CPU where the GPU is a software rasteriser (lavapipe: measured faster there), the
    /// GPU otherwise.
    Auto,
    Cpu,
    Gpu,
}

specula_core::choice!(Projection {
    Auto = "auto",
    Cpu = "cpu",
    Gpu = "gpu",
});

#[derive(Default)]
pub struct C3rcMethod {
    pub params: Params,
}

/// The nearby objects of the mirrors, as points.
struct NearField {
    /// (mirror mesh, its nearby meshes).
    near: Vec<(usize, Vec<usize>)>,
    clouds: Vec<PointCloud>,
    /// Scene version `near` was found at.
    found_at: u64,
    /// Milliseconds spent sampling and building trees when the clouds were made.
    build_ms: f64,
    /// Changes whenever points or colours change (what the GPU copy follows).
    generation: u64,
}

/// What depends on the scene.
pub struct Prepared {
    maps: CubeMaps,
    camera_buffer: wgpu::Buffer,
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    scene_bind_group: wgpu::BindGroup,
    bind_groups: BindGroupsBySlot,
    /// The faces' and near buffer's generations the bind groups were made for.
    bound: Option<(Option<u64>, u64)>,
    near_field: Option<NearField>,
    /// One vec4 per pixel: what the shading pass reads (the CPU writes it, or the GPU
    /// forward phase).
    near_buffer: gpu::Growing,
    gpu_projection: Option<gpu::GpuProjection>,
    readback: Option<SurfaceReadback>,
    near_pixels: Vec<[f32; 4]>,
}

/// The mirrors (specular meshes of mirror material) with their centres and radii.
fn mirrors(scene: &Scene) -> Vec<(usize, Vec3, f32)> {
    cube_maps::reflectors(scene)
        .into_iter()
        .filter(|&(m, ..)| {
            matches!(
                scene.materials[scene.meshes[m].material].kind,
                MaterialKind::Mirror { .. }
            )
        })
        .collect()
}

/// Each mirror's nearby objects: non-specular meshes within `near` × its radius.
fn near_objects(scene: &Scene, near: f32) -> Vec<(usize, Vec<usize>)> {
    mirrors(scene)
        .into_iter()
        .map(|(mirror, center, radius)| {
            let objects = (0..scene.meshes.len())
                .filter(|&m| !scene.materials[scene.meshes[m].material].is_specular())
                .filter(|&m| cpu_frame::mesh_is_near(scene, m, center, near * radius))
                .collect();
            (mirror, objects)
        })
        .collect()
}

impl C3rcMethod {
    fn build(&self, ctx: &GpuContext, live: &LiveScene) -> Result<Prepared, GpuError> {
        let device = &ctx.device;
        let gpu_scene = live.gpu(ctx);
        ctx.validated("c3rc set-up", || {
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some("c3rc.wgsl"),
                source: wgpu::ShaderSource::Wgsl(shader_source().into()),
            });
            let mut entries = cube_maps::shading_layout_entries();
            entries.push(layout_entry(
                9,
                wgpu::ShaderStages::FRAGMENT,
                buffer_binding(wgpu::BufferBindingType::Storage { read_only: true }),
            ));
            entries.push(layout_entry(
                10,
                wgpu::ShaderStages::FRAGMENT,
                texture_binding(
                    wgpu::TextureSampleType::Float { filterable: false },
                    wgpu::TextureViewDimension::D2Array,
                ),
            ));
            let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some("c3rc"),
                entries: &entries,
            });
            let scene_layout = GpuScene::bind_group_layout(device);
            let pipeline =
                raster::shading_pipeline(device, "c3rc shade", &module, &layout, &scene_layout);
            Prepared {
                scene_bind_group: gpu_scene.bind_group(ctx, &scene_layout),
                maps: {
                    let mut maps = CubeMaps::new(ctx, live.scene());
                    maps.keep_positions();
                    maps
                },
                camera_buffer: writable_buffer(
                    ctx,
                    "camera",
                    size_of::<CameraUniform>() as u64,
                    wgpu::BufferUsages::UNIFORM,
                ),
                pipeline,
                layout,
                bind_groups: BindGroupsBySlot::default(),
                bound: None,
                near_field: None,
                near_buffer: gpu::Growing::default(),
                gpu_projection: None,
                readback: None,
                near_pixels: Vec::new(),
            }
        })
    }

    /// The nearby objects' point clouds for `live`, made when missing or when the set of
    /// nearby objects changed; colours shaded again after a move. True when the clouds were
    /// sampled and their trees built.
    fn update_near_field(&self, live: &LiveScene, field: &mut Option<NearField>) -> bool {
        let scene = live.scene();
        let stale = field.as_ref().map(|f| f.found_at) != Some(live.version());
        if !stale {
            return false;
        }
        let near = near_objects(scene, self.params.near);
        let mut meshes: Vec<usize> = near.iter().flat_map(|(_, m)| m.iter().copied()).collect();
        meshes.sort_unstable();
        meshes.dedup();
        let same_set = field
            .as_ref()
            .is_some_and(|f| f.clouds.iter().map(|c| c.mesh).eq(meshes.iter().copied()));
        if !same_set {
            let start = std::time::Instant::now();
            let area: f32 = meshes.iter().map(|&m| points::area(&scene.meshes[m])).sum();
            let density = if self.params.density > 0.0 {
                self.params.density
            } else {
                self.params.points as f32 / area.max(1e-12)
            };
            let clouds = meshes
                .iter()
                .map(|&m| {
                    PointCloud::sample(
                        m,
                        &scene.meshes[m],
                        live.world_from_loaded(m).inverse(),
                        density,
                        1.0,
                        TreeLimits {
                            leaf_points: self.params.leaf_points,
                            max_depth: self.params.tree_depth,
                        },
                    )
                })
                .collect();
            *field = Some(NearField {
                near: Vec::new(),
                clouds,
                found_at: u64::MAX,
                build_ms: start.elapsed().as_secs_f64() * 1e3,
                generation: 0,
            });
        }
        let f = field.as_mut().expect("made above");
        for cloud in &mut f.clouds {
            cloud.shade(scene, live.accel(), live.world_from_loaded(cloud.mesh));
        }
        f.near = near;
        f.found_at = live.version();
        f.generation = NEXT_GENERATION.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        !same_set
    }
}

impl GpuTechnique for C3rcMethod {
    type Prepared = Prepared;
    type Params = Params;
    const INFO: &'static MethodInfo = &INFO;

    fn params(&self) -> &Params {
        &self.params
    }

    fn params_mut(&mut self) -> &mut Params {
        &mut self.params
    }

    /// Its forward phase runs on the CPU (on lavapipe): every stage on the CPU's clock.
    fn wall_clock(&self) -> bool {
        true
    }

    fn prepare(
        &mut self,
        gpu: &GpuContext,
        live: &LiveScene,
        _: Option<&RasterPass>,
    ) -> Result<Prepared, TechniqueError> {
        // The points are sampled by the first frame, which counts them.
        Ok(self.build(gpu, live)?)
    }

    fn invalidate(&mut self, prepared: Option<&mut Prepared>, what: Invalidates) -> bool {
        if let (Some(p), true) = (prepared, what >= Invalidates::Resources) {
            p.maps.drop_faces();
            p.near_field = None;
        }
        true
    }

    /// The paper's steps after the G-buffer: the nearby objects as points (§4), the far
    /// field's cube maps (§7), the backward phase culling the trees per mirror triangle's
    /// camera (§5), the forward phase projecting and splatting the points (§6), then the
    /// shading.
    fn shade(&mut self, p: &mut Prepared, frame: &mut GpuFrame<'_>) -> Result<(), TechniqueError> {
        let mut field = p.near_field.take();
        let rebuilt = self.update_near_field(frame.live, &mut field);
        let field = field.expect("made by update_near_field");
        frame.lap("points (sample, trees, shading)")?;
        let faces_drawn = self.far_field(p, frame, &field)?;
        let surfaces = read_g_buffer(p, frame)?;
        let report = self.phases(p, frame, &field, &surfaces)?;
        shade_pixels(p, frame)?;
        frame.lap("upload and shading")?;
        for (name, value) in counters(&field, &report, rebuilt, faces_drawn) {
            frame.count(&name, value);
        }
        let visible = report.cameras + report.small_triangles + report.self_seeing_triangles;
        if visible == 0 && !field.near.is_empty() {
            frame.warn("c3rc: no mirror triangle is visible; only the far field shows".into());
        }
        p.near_field = Some(field);
        Ok(())
    }
}

impl C3rcMethod {
    /// The far field: the mirrors' cube maps with their nearby objects left out. Returns the
    /// faces drawn.
    fn far_field(
        &self,
        p: &mut Prepared,
        frame: &mut GpuFrame<'_>,
        field: &NearField,
    ) -> Result<u64, TechniqueError> {
        p.maps.set_hidden(field.near.clone());
        p.maps.set_two_levels(self.params.two_level_maps);
        let faces_drawn = p.maps.update(
            frame.gpu,
            frame.raster(),
            frame.live,
            self.params.resolution,
            Exit::Slab,
            self.params.dynamic,
        )?;
        frame.lap("far-field cube maps")?;
        Ok(faces_drawn)
    }

    /// The backward and forward phases, on the GPU or the CPU, leaving each mirror pixel's
    /// reflection of the nearby objects in the near buffer. Returns what they counted.
    fn phases(
        &self,
        p: &mut Prepared,
        frame: &mut GpuFrame<'_>,
        field: &NearField,
        surfaces: &PixelSurfaces,
    ) -> Result<PhaseReport, TechniqueError> {
        let (gpu, live, camera) = (frame.gpu, frame.live, frame.camera);
        let scene = live.scene();
        let placed = placed_clouds(field, live);
        let mirror_meshes: Vec<usize> = field.near.iter().map(|(m, _)| *m).collect();
        let view = ScreenView::new(camera, frame.width, frame.height);
        let settings = self.frame_settings();
        let mut plan = cpu_frame::plan(
            scene,
            live.accel(),
            &mirror_meshes,
            &placed,
            &view,
            surfaces,
            settings,
        );
        frame.measured("c3rc set-up", plan.report.setup_ms);
        frame.measured("culling (backward phase)", plan.report.culling_ms);
        p.near_buffer.fit(
            gpu,
            "c3rc near reflection",
            (frame.width * frame.height) as usize,
            16,
            wgpu::BufferUsages::STORAGE,
        );
        let points: usize = field.clouds.iter().map(|c| c.len()).sum();
        // The exact hits' resolve runs on the CPU only: `auto` keeps it there.
        let on_gpu = points <= gpu::MAX_POINTS
            && match self.params.projection {
                Projection::Gpu => true,
                Projection::Cpu => false,
                Projection::Auto => !gpu.is_software() && !self.params.exact_hits,
            };
        if on_gpu && self.params.exact_hits {
            frame.warn(
                "c3rc: projection=gpu splats colours (exact_hits runs on the CPU only)".into(),
            );
        }
        if on_gpu {
            plan.fallback(
                scene,
                live.accel(),
                &view,
                surfaces,
                FALLBACK_MAX_DEPTH,
                &mut p.near_pixels,
            );
            gpu.queue
                .write_buffer(p.near_buffer.get(), 0, bytemuck::cast_slice(&p.near_pixels));
            if p.gpu_projection.is_none() {
                p.gpu_projection = Some(gpu::GpuProjection::new(gpu)?);
            }
            let counts = p.gpu_projection.as_mut().expect("made above").forward(
                gpu,
                &plan,
                &placed,
                field.generation,
                &mirror_meshes,
                scene.meshes.len(),
                &view,
                camera,
                &settings,
                frame.g(),
                &p.near_buffer,
            )?;
            let report = &mut plan.report;
            report.points_in_leaves = counts[0] as u64;
            report.points_projected = counts[1] as u64;
            report.valid_projections = counts[2] as u64;
            report.splats = counts[3] as u64;
            frame.lap("projection and splatting (GPU)")?;
        } else {
            cpu_frame::forward(
                &mut plan,
                scene,
                live.accel(),
                &mirror_meshes,
                &placed,
                &view,
                surfaces,
                settings,
                &mut p.near_pixels,
            );
            frame.measured("projection (forward phase)", plan.report.projection_ms);
            frame.measured("splatting (resolve, holes)", plan.report.splatting_ms);
            frame.measured(
                "pixels without a camera (per-vertex, traced)",
                plan.report.fallback_ms,
            );
            gpu.queue
                .write_buffer(p.near_buffer.get(), 0, bytemuck::cast_slice(&p.near_pixels));
        }
        Ok(plan.report)
    }

    /// What the phases follow, from the parameters.
    fn frame_settings(&self) -> FrameSettings {
        let params = &self.params;
        FrameSettings {
            min_pixels: params.min_pixels,
            split_pixels: params.split_pixels,
            trace_self: params.trace_self,
            level_of_detail: params.level_of_detail,
            conservative_culling: params.conservative_culling,
            one_sided: params.one_sided,
            multiple_projections: params.multiple_projections,
            fixed_splat: params.fixed_splat,
            depth_band: params.depth_band,
            fill_holes: params.fill_holes,
            exact_hits: params.exact_hits,
            splat_scale: params.splat_scale,
            max_splat: params.max_splat,
            max_depth: FALLBACK_MAX_DEPTH,
        }
    }
}

/// The nearby objects' clouds where their objects are now.
fn placed_clouds<'a>(field: &'a NearField, live: &LiveScene) -> Vec<PlacedCloud<'a>> {
    field
        .clouds
        .iter()
        .map(|cloud| {
            let object_from_world = live.world_from_loaded(cloud.mesh).inverse();
            let matrix = DMat4::from_cols_array(&object_from_world.to_cols_array().map(f64::from));
            PlacedCloud::new(cloud, matrix)
        })
        .collect()
}

/// The G-buffer's surfaces on the CPU, for the phases.
fn read_g_buffer(
    p: &mut Prepared,
    frame: &mut GpuFrame<'_>,
) -> Result<PixelSurfaces, TechniqueError> {
    let (gpu, width, height) = (frame.gpu, frame.width, frame.height);
    if p.readback.as_ref().map(|r| (r.width, r.height)) != Some((width, height)) {
        p.readback = Some(SurfaceReadback::new(gpu, width, height));
    }
    let surfaces = p
        .readback
        .as_ref()
        .expect("made above")
        .read(gpu, frame.g())?;
    frame.lap("g-buffer readback")?;
    Ok(surfaces)
}

/// The shading: envmap's over the far field, with each mirror pixel's near reflection.
fn shade_pixels(p: &mut Prepared, frame: &GpuFrame<'_>) -> Result<(), TechniqueError> {
    let (gpu, g) = (frame.gpu, frame.g());
    let bound = Some((p.maps.faces_generation(), p.near_buffer.generation()));
    if p.bound != bound {
        p.bind_groups.clear();
        p.bound = bound;
    }
    Ok(gpu.validated("c3rc shade", || {
        gpu.queue.write_buffer(
            &p.camera_buffer,
            0,
            bytemuck::bytes_of(&frame.camera_uniform),
        );
        let group = p.bind_groups.get_or_make(frame.raster(), g, || {
            let views = g.views();
            let mut entries = cube_maps::shading_bindings(&p.camera_buffer, &views, &p.maps);
            entries.push(p.near_buffer.get().as_entire_binding());
            entries.push(wgpu::BindingResource::TextureView(
                p.maps.positions_view().expect("kept since build"),
            ));
            bind_group(gpu, "c3rc", &p.layout, &entries)
        });
        raster::fullscreen_pass(
            gpu,
            "c3rc shade",
            &p.pipeline,
            &[group, &p.scene_bind_group],
            frame.output(),
        )
    })?)
}

/// The frame's counters: the paper's Tables 1 and 2 and what the fallbacks took.
fn counters(
    field: &NearField,
    report: &PhaseReport,
    rebuilt: bool,
    faces_drawn: u64,
) -> Vec<(String, u64)> {
    let points: usize = field.clouds.iter().map(|c| c.len()).sum();
    let leaves: usize = field.clouds.iter().map(|c| c.stats.leaves).sum();
    let depth_sum: f64 = field
        .clouds
        .iter()
        .map(|c| c.stats.average_depth * c.stats.leaves as f64)
        .sum();
    let tree_us: f64 = field.clouds.iter().map(|c| c.stats.build_ms * 1e3).sum();
    vec![
        ("nearby objects".into(), field.clouds.len() as u64),
        ("points".into(), points as u64),
        ("kd-tree leaves".into(), leaves as u64),
        (
            "kd-tree points per leaf".into(),
            (points as f64 / leaves.max(1) as f64).round() as u64,
        ),
        (
            "kd-tree mean leaf depth (hundredths)".into(),
            (100.0 * depth_sum / leaves.max(1) as f64).round() as u64,
        ),
        ("kd-tree build us".into(), tree_us.round() as u64),
        (
            "points sampled and trees built this frame".into(),
            if rebuilt { points as u64 } else { 0 },
        ),
        (
            "sampling and trees ms (when built)".into(),
            field.build_ms.round() as u64,
        ),
        ("cameras (C3RCs)".into(), report.cameras),
        (
            "triangles split into several cameras".into(),
            report.split_triangles,
        ),
        (
            "cameras that can project a point twice".into(),
            report.cameras_that_can_project_twice,
        ),
        ("leaves seen by cameras".into(), report.leaves_visited),
        ("points in leaves seen".into(), report.points_in_leaves),
        (
            "points skipped by level of detail".into(),
            report.points_skipped_by_level_of_detail,
        ),
        (
            "points projected (cubic solved)".into(),
            report.points_projected,
        ),
        ("valid projections".into(), report.valid_projections),
        (
            "valid projections per thousand points considered".into(),
            (1000 * report.valid_projections)
                / (report.points_in_leaves - report.points_skipped_by_level_of_detail).max(1),
        ),
        ("splats".into(), report.splats),
        (
            "points with several projections in one camera".into(),
            report.points_projected_more_than_once,
        ),
        (
            "culling us".into(),
            (report.culling_ms * 1e3).round() as u64,
        ),
        (
            "projection us".into(),
            (report.projection_ms * 1e3).round() as u64,
        ),
        ("pixels covered by splats".into(), report.covered_pixels),
        ("pixels filled from neighbours".into(), report.holes_filled),
        (
            "small triangles (per-vertex colour)".into(),
            report.small_triangles,
        ),
        (
            "pixels of small triangles".into(),
            report.small_triangle_pixels,
        ),
        (
            "triangles that see their own mirror (traced per pixel)".into(),
            report.self_seeing_triangles,
        ),
        (
            "pixels of triangles that see their own mirror".into(),
            report.self_seeing_pixels,
        ),
        ("cube map faces rendered".into(), faces_drawn),
    ]
}
