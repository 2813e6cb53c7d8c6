//! `vertex-tracing`: adaptive progressive vertex tracing.
//!
//! Paper: Ullmann, Schmidt, Beier, Bruderlin, *Adaptive progressive vertex tracing for
//! interactive reflections*, Eurographics 2001 short paper.
//!
//! Steps, and where they are:
//! 1. Visibility (§3): the ID buffer — the scene raster pass's G-buffer ids where the run has a
//!    GPU, the CPU tracer's primary hits where it has none ([`specula_core::screen::PixelSurfaces`]).
//!    A reflector vertex is seen when the ID buffer at its pixel shows its surface at its depth
//!    ([`refine::FrameInputs::is_visible`]; the paper's ID buffer "is essentially a Z-buffer").
//!    The rest of the scene comes from the same pass (the raster colour, or the reference's
//!    shading of each primary hit without a GPU).
//! 2. Vertex rays (§3; [`refine::Package`]): for each vertex of a reflector triangle with a seen
//!    vertex (the paper's rule: an edge is traced when one of its ends is seen), the primary
//!    ray from the eye aimed at it — its intersection is the vertex, so it is not searched for
//!    ("these primary ray intersections are completely avoided"): a hidden end of a seen edge
//!    is shaded as its own surface, not as the occluder, and an occluder's edge does not leak
//!    into the reflector's interpolation — then reflected, refracted and shadow rays through
//!    the reference tracer, keeping each vertex's colour and ray tree
//!    ([`specula_trace::reference::RayTree`]).
//! 3. Refinement (§3.1–3.2, Figure 6): the edges with a seen end in a queue, longest on the
//!    screen first; an edge whose ends differ in display colour by more than `epsilon` or in
//!    ray tree is split at its midpoint (one new vertex, one new ray), both faces beside it cut
//!    in two (Figure 4); the new edges join the queue. A refined face flatter than `flatness`
//!    (height over longest edge) has its longest edge split (§3.2, the convergence fix), unless
//!    its height is under two pixels; colour splits stop at `min_edge_px`, all splits at
//!    `max_level`. An edge with an end behind the eye has no projected length and is kept.
//! 4. Triangle filling (§3): each pixel of a face left with an unresolved edge (its ends differ
//!    but it may not be split) is traced exactly.
//! 5. Display: each reflector pixel belongs to the triangle the ID buffer shows there; it takes
//!    the leaf face of that triangle's refinement it falls in, Gouraud-interpolated from the
//!    face's corners, or its traced colour once filled. With `composition=gpu` (the paper's way:
//!    "rendered with Gouraud shading" on graphics hardware) the leaf faces are drawn by the GPU
//!    raster, each kept only where the ID buffer shows its own triangle ([`compose`]); the CPU
//!    shades what the raster does not (faces with deferred textures or a corner behind the
//!    eye, pixels no face covers) and the filled pixels. Without a GPU the CPU locates each
//!    pixel in its triangle's face tree: the same image (a test holds them equal).
//!
//! Progressive display (`budget_ms` > 0, what the viewer sets): the first call returns the
//! Gouraud preview (original vertices only); each later call refines for about `budget_ms`
//! (the paper's `TimeToBreak`) and shows the faces refined so far over the previous image; once
//! the queue is empty, filling runs, also in budgeted steps; the frame says `converged` at the
//! end. Any change of camera, size, parameters or scene starts over from the preview. A
//! reflector chosen to be traced per pixel (below) is drawn whole in the first call, with the
//! rest of the scene: it is chosen where its pixels cost about what its vertices would. `specula
//! render --sequence DIR` writes each step as a numbered image with its time and rays.
//!
//! Work is cut into task packages of reflector triangles (`refine::Package`), refined in
//! parallel (rayon) here and by MPI workers in `specula render --distributed` (§4; the
//! `distributed` module, feature `mpi`, with the load balancer of `balance`; the workers get
//! the same settings, the paper preset's included, and run the same package code).
//!
//! Beyond the paper (each switched off by the `paper` preset; `specula methods` lists it):
//! - Each reflector is traced by its vertices or per pixel, chosen per frame from measured
//!   counts; the paper traces vertices always (paper: `tracing=vertices`). Per pixel where the
//!   vertices of its triangles the ID buffer shows outnumber `vertex_ratio` × its pixels (a
//!   dense mesh, a small or distant reflector, a low resolution: refinement would trace about
//!   as many samples as there are pixels), or where up to 256 of its pixels, traced, take
//!   fewer than `min_path_rays` closest-hit and shadow rays beyond the primary (a plain mirror:
//!   owning, locating and interpolating a pixel on the CPU costs about what its one reflected
//!   ray does). A reflector traced per pixel is shaded from the ID buffer's hit where it was
//!   traced (no second primary ray): the reference's value bit for bit. The frame's counters
//!   say, per reflector, its seen vertices, pixels, sampled rays per path and the choice.
//! - Deferred textures: where a face's corners read the same textures along alike paths (a
//!   dial seen through the cover), their texture coordinates and coefficients are
//!   interpolated — perspective-correct for the textured surface's virtual image — and the
//!   texels read per pixel, so texture detail needs no refinement; a crease of the textured
//!   surface splits the edge. Switched off, a texture test splits an edge whose texture between
//!   its ends departs from their blend by more than ε, and texels are interpolated as colours
//!   like the rest (paper: `deferred_textures=false`).
//! - Ray trees leave out rays of little weight, which change objects often in glass and the
//!   picture hardly (paper: `tree_weight=0`): the paper compares whole trees.
//! - Perspective-correct Gouraud interpolation (each corner's weight divided by its depth).
//!   The paper interpolates "linearly by means of Gouraud shading", on the screen
//!   (paper: `perspective_correct=false`), which bends a large face's gradient.
//! - The flatness rule is kept off triangle borders: a border edge is split or kept by its ends
//!   alone, alike in the two triangles beside it wherever their packages are. The paper's rule
//!   cuts any longest edge, a border edge too — Figure 7's third edge can be one
//!   (paper: `flatness_inside_triangles=false`); a package then splits a border edge by its own
//!   side's faces, which the neighbour's package does not see, so along package borders the
//!   image depends on how the frame was cut (the thread count, `package_triangles`; a few dozen
//!   pixels by a level or two at 640×480 with one-triangle packages on truck-cover and
//!   glass-sphere).
//! - Faces none of whose corners is seen are traced: a triangle seen only between its corners
//!   (behind an occluder with a gap) is made active and filled, and so is such a leaf face of an
//!   active triangle. The paper's footnote leaves the first case "not considered" and renders
//!   every face of its seen triangles (paper: `trace_unseen=false`): such a triangle is not
//!   drawn, its pixels keep the rest of the scene's colour there (the raster pass draws
//!   reflectors black), and such a leaf face is Gouraud-interpolated like any other.
//! - Faces with a corner behind the eye are traced. The paper is silent; switched off
//!   (paper: `trace_behind_eye=false`) each pixel takes the corners' colours weighted by where
//!   its ray meets the face — what rasterizing the face clipped at the near plane gives (no
//!   screen triangle exists to interpolate linearly on).
//! - Stray pixels are traced: a pixel the ID buffer gives to a triangle that cannot be seen
//!   there (its centre outside the triangle's projection by half a pixel, a raster depth
//!   buffer's rounding; or a closed glass's back face between the two walls of a thin shell).
//!   The paper's display gives every pixel of a triangle that triangle's interpolated colour
//!   (paper: `trace_stray=false`): a stray pixel takes the leaf face the face tree's separating
//!   lines put it in, its weights clamped to the face and summing to one (near the face's
//!   nearest side's colour).
//!
//! Implementation (changes no pixel): the original vertices are traced once per process for all
//! its packages (a vertex's sample is a function of its position and host triangle alone), and
//! the active triangles are ordered along a Morton curve, so that a package is a compact patch
//! with a short border (the paper's future work: "spatial sectors"). With the CPU's ID buffer
//! a filled pixel is shaded from the buffer's hit of its primary ray (the same ray: no second
//! intersection), and a package's filled pixels are traced in parallel (a pane of a few large
//! triangles is a few packages). The CPU's ID buffer is traced in the reference's 32 × 32
//! tiles, and the same pass shades, from each fresh hit, the pixels of the rest of the scene
//! and of the reflectors the last frame traced per pixel (its choice is most often this
//! frame's): one pass over the image, as the reference makes. A reflector so shaded but chosen
//! by its vertices in this frame is composed over (its rays spent and counted, no pixel
//! changed; `a_wrong_guess_of_the_per_pixel_reflectors_changes_no_pixel`). A package's pixels do not
//! depend on how the frame was cut (`refine`'s doc says why; the test
//! `the_image_does_not_depend_on_how_the_frame_is_cut_into_packages` holds it bit for bit), so
//! the cut, the order, rayon's scheduling and MPI give the same image — with
//! `flatness_inside_triangles` on, the default; the paper's flatness rule (above) makes the cut
//! matter along package borders.
//!
//! Approximations and artifacts: between vertices the radiance is interpolated linearly, so a
//! reflected feature smaller than the refined faces and seen by neither end of any edge is
//! missed (the sampling's Nyquist limit); ε on display colours lets faint gradients band
//! slightly; without filling, discontinuities are staircased to the last faces' size
//! (`min_edge_px`). The paper states no values for ε, v, l, the deepest split or the ray
//! depth, so the `paper` preset keeps specula's defaults for them.
//!
//! ## Parameters
//!
//! <!-- The parameter table: made from `Params::SPECS` by `specula_core::params::doc_table`;
//! `SPECULA_REGENERATE=1 cargo test -p specula-methods --lib doc` writes it again. -->
//! | parameter | takes | default | a change redoes | what it does |
//! |---|---|---|---|---|
//! | `epsilon` | a number from 0 to 1 | `0.03` | uniform | ε: display-colour difference (largest channel, 0-1) that splits an edge |
//! | `flatness` | a number from 0 to 1 | `0.2` | uniform | v: a refined face with height/longest edge below this has that edge split |
//! | `min_edge_px` | a number from 0.5 to 1000 | `3` | uniform | l: shortest edge (pixels) split for a colour difference; shorter ones are filled |
//! | `max_level` | a whole number from 0 to 40 | `20` | uniform | deepest split of an original edge |
//! | `tree_weight` | a number from 0 to 1 | `0.02` | uniform | rays reaching the eye with less weight than this are left out of the ray trees compared |
//! | `refine` | true or false | `true` | uniform | adaptive refinement (false: the Gouraud preview of the original vertices only) |
//! | `fill` | true or false | `true` | uniform | triangle filling: trace each pixel of the faces refinement left unresolved |
//! | `deferred_textures` | true or false | `true` | uniform | interpolate texture coordinates between alike paths and read texels per pixel (false: split edges across texture detail) |
//! | `perspective_correct` | true or false | `true` | uniform | Gouraud interpolation perspective-correct (false: linear on the screen, the paper's) |
//! | `flatness_inside_triangles` | true or false | `true` | uniform | the flatness rule leaves triangle borders alone, so packages never disagree (false: any longest edge, the paper's) |
//! | `trace_unseen` | true or false | `true` | uniform | trace faces seen only between their corners (false: the paper: a triangle with no seen corner is not drawn) |
//! | `trace_behind_eye` | true or false | `true` | uniform | trace faces with a corner behind the eye (false: interpolate them where each pixel's ray meets them) |
//! | `trace_stray` | true or false | `true` | uniform | trace pixels the ID buffer gives to a triangle that cannot be seen there (false: interpolate them from that triangle, the paper's display) |
//! | `tracing` | one of auto, vertices, pixels | `auto` | uniform | per reflector: auto traces its pixels where its seen vertices or its paths make vertices no cheaper (vertex_ratio, min_path_rays); vertices (the paper) or pixels for all |
//! | `vertex_ratio` | a number from 0 to 1000 | `0.05` | uniform | tracing=auto: seen vertices per pixel above which a reflector is traced per pixel |
//! | `min_path_rays` | a number from 0 to 1000 | `6` | uniform | tracing=auto: rays per pixel path (beyond the primary, on a sample) below which a reflector is traced per pixel |
//! | `budget_ms` | a whole number from 0 to 60000 | `0` | uniform | progressive mode: milliseconds per call, preview first (0: everything in one call) |
//! | `package_triangles` | a whole number from 0 to 1048576 | `0` | uniform | reflector triangles per task package (0: sixteen packages per thread) |
//! | `visibility` | one of auto, cpu, gpu | `auto` | uniform | ID buffer from the GPU raster pass, from CPU primary rays, or the GPU where present |
//! | `composition` | one of auto, cpu, gpu | `auto` | uniform | refined faces Gouraud-shaded by the GPU raster (the paper's display) or each pixel located and interpolated on the CPU; auto: the GPU where the run has one that is not a software rasterizer |
//! | `max_depth` | a whole number from 0 to 64 | `8` | uniform | most specular bounces on a vertex's or a filled pixel's path |
//! | `show_faces` | true or false | `false` | uniform | draw the edges of the refined faces over the image (the paper's Figure 13) |
//! | `shadow_resolution` | a whole number from 1 to 8192 | `1024` | scene preparation | texels per side of the scene raster's shadow maps |
//! <!-- end of the parameter table -->
//!
//! What they change (quality / cost):
//! - `epsilon` (0.03): colour difference that splits an edge. Lower follows fainter changes,
//!   with more vertex rays.
//! - `flatness` (0.2): the factor of flatness v; higher cuts more slivers (more rays, better
//!   convergence at discontinuities).
//! - `min_edge_px` (3): the shortest edge split for a colour difference, in pixels; lower
//!   refines further before filling takes over.
//! - `max_level` (20): the deepest split.
//! - `tree_weight` (0.02): rays whose radiance reaches the eye scaled by less than this are
//!   left out of the ray trees compared (Fresnel-weak internal bounces in glass change their
//!   objects often and the picture hardly); 0 compares whole trees (the paper), with many more
//!   splits in glass.
//! - `refine` (true) / `fill` (true): switch off refinement (the preview alone) or filling.
//! - `deferred_textures` (true): see above; off, textured reflections refine (and fill) along
//!   texture detail: more rays.
//! - `perspective_correct` (true): off, faces are interpolated linearly on the screen (the
//!   paper); the same cost, a bent gradient across large faces (the preview's most).
//! - `flatness_inside_triangles` (true): off, the flatness rule cuts border edges too (the
//!   paper): a few more splits along discontinuities near triangle borders, and an image that
//!   depends on the package cut there.
//! - `trace_unseen` (true) / `trace_behind_eye` (true) / `trace_stray` (true): off, those
//!   pixels are interpolated (or not drawn) instead of traced: fewer rays, the paper's holes and
//!   smears where a reflector is seen between occluders, reaches behind the eye, or meets the
//!   ID buffer's rounding.
//! - `budget_ms` (0): progressive mode, milliseconds per call; 0 does everything in one call.
//! - `package_triangles` (0): reflector triangles per task package, the parallel grain (0: the
//!   active triangles in sixteen packages per thread). The original vertices are traced once
//!   for all packages; a vertex refinement adds on a package border is traced once per
//!   package: smaller packages balance better and trace a little more.
//! - `tracing` (auto): per reflector as above; `vertices` for all (the paper); `pixels` for all
//!   (the reference's image, at the reference's cost).
//! - `vertex_ratio` (0.05): seen vertices per pixel above which `auto` traces a reflector per
//!   pixel. Measured on the scene suite (docs/methods/vertex-tracing.md): at 320 × 240 its reflectors above
//!   0.05 show 0.11–0.42 and took 0.96–1.72× the reference's frame by their vertices; at
//!   1024 × 768 they show 0.01–0.04.
//! - `min_path_rays` (6): rays per sampled pixel path below which `auto` traces per pixel
//!   (measured on the suite at 1024 × 768: mirrors 1.9–3.6 with their shadow rays, glass
//!   16–24); the sample is 256 of a candidate reflector's pixel paths.
//! - `composition` (auto): `gpu` draws the refined faces with the GPU raster, `cpu` locates and
//!   interpolates each pixel on the CPU, `auto` uses a GPU where the run has one that is not a
//!   software rasterizer. On lavapipe the raster took 16.8 ms where the CPU took 6.6 ms
//!   (truck-cover, 1024 × 768, docs/methods/vertex-tracing.md): uploading the ID buffer and reading the
//!   frame back cost more than locating on two cores.
//! - `visibility` (auto): `gpu` draws the ID buffer with the scene raster pass, `cpu` traces it,
//!   `auto` uses a GPU where the run has one that is not a software rasterizer (on lavapipe
//!   the raster pass took 16 ms where tracing the same buffer took 8, and the traced buffer's
//!   hits shade the rest of the scene with no second primary ray).
//! - `max_depth` (8): the reference's bound on specular bounces, for every vertex and pixel.
//! - `shadow_resolution`: the raster pass's shadow maps (GPU visibility only).
//! - `show_faces` (false): draws the refined faces' edges over the image (Figure 13).

pub(crate) mod balance;
mod choice;
pub mod compose;
#[cfg(feature = "mpi")]
pub mod distributed;
mod phases;
mod progress;
pub(crate) mod refine;
mod setup;
pub mod simulate;
pub(crate) mod wire;

use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::Vec3;
use rayon::prelude::*;
use specula_gpu::GpuContext;
use specula_scene::Camera;
use specula_trace::Image;

use compose::{FaceVertex, RasterComposition};
pub use phases::FramePhases;
use progress::{stage_timer, Progress, COMPOSITION_STAGE, STAGES, VERTICES_STAGE};
use refine::{FrameInputs, OriginalSamples, Package, Topology};
pub use refine::{PackageCounters, ReflectorTracing};
pub(crate) use setup::FrameSetup;
use specula_core::live_scene::LiveScene;
use specula_core::raster::{self, RasterPass, RasterSpec};
use specula_core::screen::SurfaceReadback;
use specula_core::{
    Context, Drawn, Invalidates, MethodInfo, Param, ParamKind, ParamSet, Pixels, Technique,
    TechniqueError,
};

/// Packages per rayon thread when `package_triangles` is 0: enough that a package holding a
/// reflection's outline does not leave the other threads idle.
const PACKAGES_PER_THREAD: usize = 16;

specula_core::params! {
    /// vertex-tracing's parameters (the table above): what a frame and the refinement of
    /// every package follow.
    #[derive(Copy)]
    pub struct Params {
        epsilon: f32 = Param {
            kind: ParamKind::Number { min: 0.0, max: 1.0 },
            default: "0.03",
            doc: "ε: display-colour difference (largest channel, 0-1) that splits an edge",
            invalidates: Invalidates::Uniform,
        },
        flatness: f32 = Param {
            kind: ParamKind::Number { min: 0.0, max: 1.0 },
            default: "0.2",
            doc: "v: a refined face with height/longest edge below this has that edge split",
            invalidates: Invalidates::Uniform,
        },
        min_edge_px: f32 = Param {
            kind: ParamKind::Number {
                min: 0.5,
                max: 1000.0,
            },
            default: "3",
            doc: "l: shortest edge (pixels) split for a colour difference; shorter ones are filled",
            invalidates: Invalidates::Uniform,
        },
        max_level: u32 = Param {
            kind: ParamKind::Integer { min: 0, max: 40 },
            default: "20",
            doc: "deepest split of an original edge",
            invalidates: Invalidates::Uniform,
        },
        tree_weight: f32 = Param {
            kind: ParamKind::Number { min: 0.0, max: 1.0 },
            default: "0.02",
            doc: "rays reaching the eye with less weight than this are left out of the ray trees compared",
            invalidates: Invalidates::Uniform,
        },
        refine: bool = Param {
            kind: ParamKind::Flag,
            default: "true",
            doc: "adaptive refinement (false: the Gouraud preview of the original vertices only)",
            invalidates: Invalidates::Uniform,
        },
        fill: bool = Param {
            kind: ParamKind::Flag,
            default: "true",
            doc: "triangle filling: trace each pixel of the faces refinement left unresolved",
            invalidates: Invalidates::Uniform,
        },
        deferred_textures: bool = Param {
            kind: ParamKind::Flag,
            default: "true",
            doc: "interpolate texture coordinates between alike paths and read texels per pixel (false: split edges across texture detail)",
            invalidates: Invalidates::Uniform,
        },
        perspective_correct: bool = Param {
            kind: ParamKind::Flag,
            default: "true",
            doc: "Gouraud interpolation perspective-correct (false: linear on the screen, the paper's)",
            invalidates: Invalidates::Uniform,
        },
        flatness_inside_triangles: bool = Param {
            kind: ParamKind::Flag,
            default: "true",
            doc: "the flatness rule leaves triangle borders alone, so packages never disagree (false: any longest edge, the paper's)",
            invalidates: Invalidates::Uniform,
        },
        trace_unseen: bool = Param {
            kind: ParamKind::Flag,
            default: "true",
            doc: "trace faces seen only between their corners (false: the paper: a triangle with no seen corner is not drawn)",
            invalidates: Invalidates::Uniform,
        },
        trace_behind_eye: bool = Param {
            kind: ParamKind::Flag,
            default: "true",
            doc: "trace faces with a corner behind the eye (false: interpolate them where each pixel's ray meets them)",
            invalidates: Invalidates::Uniform,
        },
        trace_stray: bool = Param {
            kind: ParamKind::Flag,
            default: "true",
            doc: "trace pixels the ID buffer gives to a triangle that cannot be seen there (false: interpolate them from that triangle, the paper's display)",
            invalidates: Invalidates::Uniform,
        },
        tracing: ReflectorTracing = Param {
            kind: ParamKind::Choice(ReflectorTracing::WORDS),
            default: "auto",
            doc: "per reflector: auto traces its pixels where its seen vertices or its paths make vertices no cheaper (vertex_ratio, min_path_rays); vertices (the paper) or pixels for all",
            invalidates: Invalidates::Uniform,
        },
        vertex_ratio: f32 = Param {
            kind: ParamKind::Number {
                min: 0.0,
                max: 1000.0,
            },
            default: "0.05",
            doc: "tracing=auto: seen vertices per pixel above which a reflector is traced per pixel",
            invalidates: Invalidates::Uniform,
        },
        min_path_rays: f32 = Param {
            kind: ParamKind::Number {
                min: 0.0,
                max: 1000.0,
            },
            default: "6",
            doc: "tracing=auto: rays per pixel path (beyond the primary, on a sample) below which a reflector is traced per pixel",
            invalidates: Invalidates::Uniform,
        },
        budget_ms: u32 = Param {
            kind: ParamKind::Integer { min: 0, max: 60000 },
            default: "0",
            doc: "progressive mode: milliseconds per call, preview first (0: everything in one call)",
            invalidates: Invalidates::Uniform,
        },
        package_triangles: usize = Param {
            kind: ParamKind::Integer { min: 0, max: 1 << 20 },
            default: "0",
            doc: "reflector triangles per task package (0: sixteen packages per thread)",
            invalidates: Invalidates::Uniform,
        },
        visibility: GpuChoice = Param {
            kind: ParamKind::Choice(GpuChoice::WORDS),
            default: "auto",
            doc: "ID buffer from the GPU raster pass, from CPU primary rays, or the GPU where present",
            invalidates: Invalidates::Uniform,
        },
        composition: GpuChoice = Param {
            kind: ParamKind::Choice(GpuChoice::WORDS),
            default: "auto",
            doc: "refined faces Gouraud-shaded by the GPU raster (the paper's display) or each pixel located and interpolated on the CPU; auto: the GPU where the run has one that is not a software rasterizer",
            invalidates: Invalidates::Uniform,
        },
        max_depth: u32 = Param {
            kind: ParamKind::Integer { min: 0, max: 64 },
            default: "8",
            doc: "most specular bounces on a vertex's or a filled pixel's path",
            invalidates: Invalidates::Uniform,
        },
        show_faces: bool = Param {
            kind: ParamKind::Flag,
            default: "false",
            doc: "draw the edges of the refined faces over the image (the paper's Figure 13)",
            invalidates: Invalidates::Uniform,
        },
        shadow_resolution: u32 = raster::SHADOW_RESOLUTION,
    }
}

pub const INFO: MethodInfo = MethodInfo {
    name: "vertex-tracing",
    summary: "adaptive progressive vertex tracing: rays from reflector vertices, edge refinement, triangle filling, MPI (Ullmann et al. 2001)",
    exact: false,
    needs_gpu: false,
    gpu_optional: true,
    progressive: true,
    delegates: &[],
    params: Params::SPECS,
    presets: &[specula_core::Preset {
        name: "paper",
        summary: "the published algorithm (Ullmann et al. 2001): whole ray trees, texels interpolated as colours, Gouraud linear on the screen, the flatness rule on any edge, faces with no seen corner not drawn, nothing traced but vertices and unresolved faces",
        settings: &[
            "tree_weight=0",
            "deferred_textures=false",
            "perspective_correct=false",
            "flatness_inside_triangles=false",
            "trace_unseen=false",
            "trace_behind_eye=false",
            "trace_stray=false",
            "tracing=vertices",
        ],
    }],
    create: || Box::new(VertexTracing::default()),
};

/// Where the ID buffer comes from, and where the refined faces are composed: the CPU, the GPU,
/// or (auto) the GPU where the run has one that is not a software rasterizer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GpuChoice {
    Auto,
    Cpu,
    Gpu,
}

specula_core::choice!(GpuChoice {
    Auto = "auto",
    Cpu = "cpu",
    Gpu = "gpu",
});

impl GpuChoice {
    /// The GPU this choice uses in a run whose context is `ctx`.
    fn gpu(self, ctx: &Context) -> Result<Option<&GpuContext>, TechniqueError> {
        match self {
            GpuChoice::Cpu => Ok(None),
            // A software rasterizer draws slower than the CPU does the same work beside it: on
            // lavapipe the raster pass drew the ID buffer in 16 ms where tracing it took 8 (and
            // the traced buffer's hits shade the rest of the scene with no second primary ray),
            // and composition took 16.8 ms against the CPU's 6.6.
            GpuChoice::Auto => Ok(ctx.gpu.as_ref().filter(|gpu| !gpu.is_software())),
            GpuChoice::Gpu => ctx.gpu(INFO.name).map(Some),
        }
    }
}

#[derive(Default)]
pub struct VertexTracing {
    pub params: Params,
    gpu: Option<GpuPass>,
    raster_composition: Option<RasterComposition>,
    /// The scene id it was built for, and the topology.
    topology: Option<(u64, Arc<Topology>)>,
    /// The scene id and, per mesh, the reflectors the last CPU frame traced per pixel: the
    /// next frame shades them in its ID buffer's pass (see `FrameSetup::traced_shading_the_rest`).
    per_pixel_guess: Option<(u64, Vec<bool>)>,
    progress: Option<Progress>,
}

/// The scene raster pass and its readback, for the GPU ID buffer.
struct GpuPass {
    scene_id: u64,
    shadow_resolution: u32,
    raster: RasterPass,
    readback: Option<SurfaceReadback>,
}

/// What a progressive image was started for: a change of any part starts over.
#[derive(Clone, Debug, PartialEq)]
struct ViewKey {
    camera: Camera,
    width: u32,
    height: u32,
    scene: (u64, u64),
    /// Every parameter (the package size and depth among them).
    settings: Params,
    gpu_visibility: bool,
}

impl Technique for VertexTracing {
    fn info(&self) -> &'static MethodInfo {
        &INFO
    }

    fn params(&self) -> &dyn ParamSet {
        &self.params
    }

    fn params_mut(&mut self) -> &mut dyn ParamSet {
        &mut self.params
    }

    fn invalidate(&mut self, what: Invalidates) {
        self.progress = None;
        if what >= Invalidates::Resources {
            self.gpu = None;
            self.raster_composition = None;
        }
    }

    fn prepare(&mut self, ctx: &Context, live: &LiveScene) -> Result<(), TechniqueError> {
        self.topology(live);
        if let Some(gpu) = self.params.visibility.gpu(ctx)? {
            self.ensure_raster(gpu, live)?;
        }
        Ok(())
    }

    /// A progressive step, or a whole frame without a budget: the ID buffer and the reflectors'
    /// packages (a fresh frame), then the vertex rays, refinement and filling within the
    /// budget, then the composition of the refined faces into the image.
    fn draw(
        &mut self,
        ctx: &Context,
        live: &LiveScene,
        camera: &Camera,
        width: u32,
        height: u32,
    ) -> Result<Drawn, TechniqueError> {
        let start = Instant::now();
        let composition_gpu = self.params.composition.gpu(ctx)?;
        let fresh = self.keep_or_start_frame(ctx, live, camera, width, height)?;
        let (params, budget_ms) = (self.params, self.params.budget_ms);
        let progress = self.progress.as_mut().expect("set above");
        let deadline = (budget_ms > 0).then(|| start + Duration::from_millis(budget_ms as u64));

        let clock = Instant::now();
        if fresh && !progress.setup.active.is_empty() {
            let inputs = progress.setup.inputs(live, camera, params, params.max_depth);
            progress.originals = OriginalSamples::trace(&inputs, &progress.setup.active);
        }
        let mut inputs = progress.setup.inputs(live, camera, params, params.max_depth);
        inputs.originals = Some(&progress.originals);
        refine_packages(&mut progress.packages, &inputs, fresh && budget_ms > 0, deadline);
        progress
            .stages
            .measured(STAGES[VERTICES_STAGE], clock.elapsed().as_secs_f64() * 1e3);

        let clock = Instant::now();
        let mut warnings = Vec::new();
        let composed = match composition_gpu {
            Some(gpu) if !progress.packages.is_empty() => {
                let composer = self
                    .raster_composition
                    .get_or_insert_with(|| RasterComposition::new(gpu));
                let uniform = raster::camera_uniform(camera, &live.scene().bounds(), width, height);
                let frame = RasterFrame {
                    ids: &progress.setup.surfaces.ids,
                    width,
                    height,
                    ids_uploaded: &mut progress.ids_uploaded,
                };
                let packages = &progress.packages;
                compose_on_raster(gpu, composer, frame, packages, &inputs, &uniform, &mut warnings)?
            }
            _ => None,
        };
        let results: Vec<Vec<(u32, Vec3)>> = progress
            .packages
            .par_iter_mut()
            .map(|package| package.take_pixels(&inputs, composed.as_deref()))
            .collect();
        for (k, color) in results.into_iter().flatten() {
            progress.image.pixels[k as usize] = color;
        }
        progress.stages.measured(
            STAGES[COMPOSITION_STAGE],
            clock.elapsed().as_secs_f64() * 1e3,
        );
        self.finish_step(live, warnings)
    }
}

/// Runs every package not yet done until `deadline` (a fresh progressive frame: only as far as
/// its Gouraud preview, which it shows before any refinement).
fn refine_packages(
    packages: &mut [Package],
    inputs: &FrameInputs,
    preview_only: bool,
    deadline: Option<Instant>,
) {
    packages.par_iter_mut().for_each(|package| {
        if package.is_done() || (preview_only && package.has_preview()) {
            return;
        }
        let until = if preview_only {
            Some(Instant::now())
        } else {
            deadline
        };
        package.run(inputs, until);
    });
}

impl VertexTracing {
    /// Keeps the progressive frame in hand where the view, the scene and the settings are
    /// those it was started for (and there is a budget), else starts one. Returns whether it
    /// is fresh.
    fn keep_or_start_frame(
        &mut self,
        ctx: &Context,
        live: &LiveScene,
        camera: &Camera,
        width: u32,
        height: u32,
    ) -> Result<bool, TechniqueError> {
        let gpu = self.params.visibility.gpu(ctx)?;
        let key = ViewKey {
            camera: camera.clone(),
            width,
            height,
            scene: (live.id(), live.version()),
            settings: self.params,
            gpu_visibility: gpu.is_some(),
        };
        // Without a budget every call is a whole fresh frame (as bench times it).
        let keep =
            self.params.budget_ms > 0 && self.progress.as_ref().is_some_and(|p| p.key == key);
        if !keep {
            self.progress = Some(self.start_frame(gpu, live, camera, width, height, key)?);
        }
        Ok(!keep)
    }

    /// The step's image (with the leaf faces drawn where asked), stages and counters.
    fn finish_step(
        &mut self,
        live: &LiveScene,
        mut warnings: Vec<String>,
    ) -> Result<Drawn, TechniqueError> {
        let budget_ms = self.params.budget_ms;
        let progress = self.progress.as_mut().expect("a frame in hand");
        let converged = progress.packages.iter().all(Package::is_done);
        let (stages, timing) = progress.stages.finish(None)?;
        let counters = progress.counters(live.scene());
        // Later calls of a progressive frame report their own time only.
        progress.stages = stage_timer([0.0; STAGES.len()]);
        if progress.setup.choices.is_empty() {
            warnings.push("no reflector pixel is visible: nothing to vertex-trace".into());
        }
        // Without a budget the next call starts afresh: the image is not kept.
        let mut image = if budget_ms > 0 {
            progress.image.clone()
        } else {
            std::mem::replace(&mut progress.image, Image::new(0, 0))
        };
        if self.params.show_faces {
            for package in &progress.packages {
                for (a, b) in package.leaf_edges() {
                    draw_line(&mut image, a, b, Vec3::new(1.0, 0.1, 0.1));
                }
            }
        }
        Ok(Drawn {
            pixels: Pixels::Image(image),
            stages,
            counters,
            timing,
            warnings,
            converged,
        })
    }
}

impl VertexTracing {
    /// The scene's topology, built at its first frame.
    fn topology(&mut self, live: &LiveScene) -> Arc<Topology> {
        match &self.topology {
            Some((id, topology)) if *id == live.id() => topology.clone(),
            _ => {
                let topology = Arc::new(Topology::new(live.scene()));
                self.topology = Some((live.id(), topology.clone()));
                topology
            }
        }
    }

    fn ensure_raster(&mut self, gpu: &GpuContext, live: &LiveScene) -> Result<(), TechniqueError> {
        let stale = self.gpu.as_ref().is_none_or(|p| {
            p.scene_id != live.id() || p.shadow_resolution != self.params.shadow_resolution
        });
        if stale {
            self.gpu = Some(GpuPass {
                scene_id: live.id(),
                shadow_resolution: self.params.shadow_resolution,
                raster: RasterPass::new(
                    gpu,
                    live,
                    RasterSpec::scene(self.params.shadow_resolution),
                )?,
                readback: None,
            });
        }
        Ok(())
    }

    /// A fresh frame: the ID buffer and the rest of the scene, then the packages (nothing
    /// traced yet).
    fn start_frame(
        &mut self,
        gpu: Option<&GpuContext>,
        live: &LiveScene,
        camera: &Camera,
        width: u32,
        height: u32,
        key: ViewKey,
    ) -> Result<Progress, TechniqueError> {
        let clock = Instant::now();
        let (settings, max_depth) = (self.params, self.params.max_depth);
        let topology = self.topology(live);
        let (setup, rest, rest_rays, visibility_ms) = match gpu {
            Some(gpu) => {
                self.ensure_raster(gpu, live)?;
                let pass = self.gpu.as_mut().expect("made above");
                pass.raster.begin_frame(gpu, live)?;
                let uniform = raster::camera_uniform(camera, &live.scene().bounds(), width, height);
                let g = pass.raster.render(gpu, live.gpu(gpu), &uniform, None)?;
                if pass.readback.as_ref().map(|r| (r.width, r.height)) != Some((width, height)) {
                    pass.readback = Some(SurfaceReadback::new(gpu, width, height));
                }
                let surfaces = pass.readback.as_ref().expect("made above").read(gpu, &g)?;
                // The raster colour is the rest of the scene; specular pixels are black in it.
                let mut rest = g.read_color(gpu)?;
                let visibility_ms = clock.elapsed().as_secs_f64() * 1e3;
                let setup = FrameSetup::new(
                    live, camera, width, height, surfaces, topology, settings, max_depth,
                );
                let rays = setup.trace_reflectors_per_pixel(live, camera, max_depth, &mut rest);
                (setup, rest, rays, visibility_ms)
            }
            None => {
                // The last frame's buffers: a steady view allocates (and faults in) no pages.
                let recycled = self
                    .progress
                    .take()
                    .map(|progress| progress.setup.surfaces)
                    .filter(|surfaces| !surfaces.hits.is_empty());
                // The scene's other surfaces (and the reflectors the last frame traced per
                // pixel) are shaded in the ID buffer's pass: the first stage's time holds them;
                // the fourth, the other reflectors traced per pixel.
                let guess = match &self.per_pixel_guess {
                    Some((scene, guess)) if *scene == live.id() => guess.clone(),
                    _ => Vec::new(),
                };
                let (setup, mut rest, early) = FrameSetup::traced_shading_the_rest(
                    live, camera, width, height, topology, settings, max_depth, recycled, &guess,
                );
                // The choice and the owners were made inside: their stages hold them.
                let visibility_ms =
                    clock.elapsed().as_secs_f64() * 1e3 - setup.choice_ms - setup.owners_ms;
                let late = setup
                    .trace_reflectors_per_pixel_but(live, camera, max_depth, &mut rest, &guess);
                self.per_pixel_guess = Some((live.id(), setup.per_pixel_meshes()));
                let rays = (early.0 + late.0, early.1 + late.1);
                (setup, rest, rays, visibility_ms)
            }
        };
        let per_pixel_ms =
            clock.elapsed().as_secs_f64() * 1e3 - visibility_ms - setup.choice_ms - setup.owners_ms;
        let stages = stage_timer([
            visibility_ms,
            setup.choice_ms,
            setup.owners_ms,
            per_pixel_ms,
            0.0,
            0.0,
        ]);
        let packages = setup.packages(self.params.package_triangles);
        Ok(Progress {
            key,
            setup,
            packages,
            originals: OriginalSamples::default(),
            image: rest,
            stages,
            rest_rays,
            ids_uploaded: false,
        })
    }
}

/// The frame's ID buffer, for [`compose_on_raster`].
struct RasterFrame<'a> {
    ids: &'a [[u32; 2]],
    width: u32,
    height: u32,
    /// Whether the composer holds this frame's ID buffer (set once it does).
    ids_uploaded: &'a mut bool,
}

/// Composes the faces of `packages` changed since the last call on the raster
/// ([`compose`]): per pixel (colour, 1) where a face drawn on the GPU showed. None, with a
/// warning, where the faces exceed the device's largest buffer (the CPU composes them).
fn compose_on_raster(
    gpu: &GpuContext,
    composer: &mut RasterComposition,
    frame: RasterFrame,
    packages: &[Package],
    inputs: &FrameInputs,
    camera: &specula_gpu::shaders::CameraUniform,
    warnings: &mut Vec<String>,
) -> Result<Option<Vec<[f32; 4]>>, TechniqueError> {
    let corners: Vec<FaceVertex> = packages
        .par_iter()
        .fold(Vec::new, |mut corners, package| {
            package.raster_faces(inputs, &mut corners);
            corners
        })
        .reduce(Vec::new, |mut a, mut b| {
            a.append(&mut b);
            a
        });
    if corners.len() > RasterComposition::max_corners(gpu) {
        warnings.push(format!(
            "{} refined faces exceed the GPU's largest buffer ({} bytes): composed on the CPU",
            corners.len() / 3,
            gpu.device.limits().max_buffer_size
        ));
        return Ok(None);
    }
    if !*frame.ids_uploaded {
        composer.set_id_buffer(gpu, frame.ids, frame.width, frame.height);
        *frame.ids_uploaded = true;
    }
    let composed = gpu.validated("vertex-tracing composition", || {
        composer.compose(gpu, camera, inputs.settings.perspective_correct, &corners)
    })??;
    Ok(Some(composed))
}

/// Draws the segment from `a` to `b` (pixel coordinates) in `color`, clipped to the image.
fn draw_line(image: &mut Image, a: glam::Vec2, b: glam::Vec2, color: Vec3) {
    let steps = (b - a).abs().max_element().ceil().clamp(1.0, 1e5) as u32;
    for i in 0..=steps {
        let p = a.lerp(b, i as f32 / steps as f32);
        if p.x >= 0.0 && p.y >= 0.0 && p.x < image.width as f32 && p.y < image.height as f32 {
            let k = p.y as usize * image.width as usize + p.x as usize;
            image.pixels[k] = color;
        }
    }
}
