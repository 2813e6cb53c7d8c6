//! One frame of c3rc on the CPU (Mei, Popescu and Sacks 2007, §3.2, §5.2, §6): a camera per
//! visible reflector triangle, the backward phase (each camera's view volume against the point
//! trees), the forward phase (the points of the leaves it sees projected with it), and the
//! splats resolved per pixel: nearest to the reflector first (the paper), or, with exact hits,
//! each pixel's own reflected ray met with the triangles the splats covering it nominate
//! (`resolve_exact`, `fill_exact`). Triangles too small to pay for a camera take the
//! per-vertex reflected colour instead.

use std::time::Instant;

use glam::{DMat4, DVec3, Vec3};
use rayon::prelude::*;
use specula_scene::Scene;
use specula_trace::optics::reflect;
use specula_trace::reference::{offset_origin, Tracer};
use specula_trace::{Ray, SceneAccel};

use super::camera::{C3rc, PlaneBound, Projector};
use super::points::PointCloud;

mod backward_phase;
mod exact_hits;
mod forward_phase;

pub use backward_phase::plan;
use exact_hits::pixel_reflected_ray;
pub use forward_phase::forward;
pub use specula_core::screen::{PixelSurfaces, ScreenView};

/// Per-frame knobs (see the module parameters in `c3rc/mod.rs`).
#[derive(Clone, Copy, Debug)]
pub struct FrameSettings {
    pub min_pixels: u32,
    /// Triangles covering more pixels are cut in four (up to three times); 0: never.
    pub split_pixels: u32,
    /// Trace the pixels of triangles whose vertex rays hit their own mirror (else they get a
    /// camera like the others, first order as in the paper).
    pub trace_self: bool,
    /// Project every k-th point of a leaf whose points would crowd into pixels.
    pub level_of_detail: bool,
    /// Keep the boxes the paper's two conditions miss ([`C3rc::may_see_box`]; else
    /// [`C3rc::corner_inside_or_face_meets_wall`]).
    pub conservative_culling: bool,
    /// Points facing away from the reflector triangle are not splatted, and nodes whose
    /// normal cones face away from it not visited.
    pub one_sided: bool,
    /// Splat every valid projection of a point (else only the first, at the smallest λ).
    pub multiple_projections: bool,
    /// Side in pixels of every splat square; 0: each sized to its footprint (`splat_scale`,
    /// `max_splat`).
    pub fixed_splat: f32,
    /// Resolve in two steps (nearest depth, then the nearest centre within a depth band); else
    /// the nearest push-back depth alone.
    pub depth_band: bool,
    /// Fill one-pixel holes between splats (with exact hits,
    /// [`fill_exact`](exact_hits::fill_exact)'s neighbours' surfaces instead).
    pub fill_holes: bool,
    /// Splats only nominate surfaces: each pixel's exact reflected ray is met with the
    /// triangles of the points whose splats cover it, the nearest hit wins, and its colour is
    /// the albedo there times the light its points carry (`resolve_exact`); else each pixel
    /// takes a splat's colour.
    pub exact_hits: bool,
    pub splat_scale: f32,
    pub max_splat: f32,
    pub max_depth: u32,
}

/// A point cloud placed in the world for this frame.
pub struct PlacedCloud<'a> {
    pub cloud: &'a PointCloud,
    pub object_from_world: DMat4,
    pub world_from_object: DMat4,
}

impl<'a> PlacedCloud<'a> {
    pub fn new(cloud: &'a PointCloud, object_from_world: DMat4) -> PlacedCloud<'a> {
        PlacedCloud {
            cloud,
            object_from_world,
            world_from_object: object_from_world.inverse(),
        }
    }
}

/// One reflector triangle's camera.
pub(super) struct TriangleCamera {
    pub(super) mesh: usize,
    pub(super) world: C3rc,
    /// Pixels² the triangle covers on screen (not occlusion-aware): the image-side area the
    /// camera's cross-sections map to, for splat sizes.
    pub(super) screen_area: f64,
    /// The λ intervals where the camera's sweeping triangle can fold over itself
    /// ([`C3rc::multiple_projection_intervals`]; empty: every point projects at most once).
    pub(super) folding: Vec<(f64, f64)>,
    /// 1 / |cos| of the angle between the view ray and the triangle (capped): how much farther
    /// apart on the surface than on the screen neighbouring pixels' points are.
    pub(super) obliquity: f32,
}

impl TriangleCamera {
    pub(super) fn may_project_twice(&self) -> bool {
        !self.folding.is_empty()
    }
}

/// A camera mapped into one cloud's (loaded) space, with what culling and projection there
/// need: its plane bound, its cubic's affine coefficients, and the largest λ at which it can
/// reach the cloud.
pub(super) struct InCloud {
    camera: C3rc,
    bound: PlaneBound,
    projector: Projector,
    reach: f64,
}

/// A tree node a camera's view volume meets: a leaf, or an inner node the level of detail
/// projects whole; every `stride`-th of its points is projected.
#[derive(Clone, Copy, Debug)]
pub(super) struct Seen {
    pub(super) cloud: usize,
    pub(super) node: usize,
    pub(super) stride: usize,
}

/// Where a visible mirror triangle's pixels get their reflected radiance.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum PixelSource {
    /// Its camera's splats (and the far field where they leave a gap).
    Camera,
    /// Too small for a camera: the per-vertex colour.
    PerVertex,
    /// It sees its own mirror: one exact ray per pixel.
    Traced,
}

/// A projected point.
#[derive(Clone, Copy)]
struct Splat {
    x: f32,
    y: f32,
    radius: f32,
    /// Push-back depth: the point's distance from the reflector.
    depth: f32,
    /// Depth range behind the front-most splat that still counts as the same surface (0: only
    /// the front-most splats).
    band: f32,
    /// How far (metres) from `p_world` a pixel's surface point may lie and still be the
    /// surface the splat came from.
    reach: f32,
    p_world: Vec3,
    color: Vec3,
    mesh: u32,
    /// The point's object (scene mesh), the triangle it lies on, where it lies in the world,
    /// the splat's radius in metres (the point's disc times `splat_scale`, and √stride: how far
    /// its plane is extrapolated and its light reaches), and the light it carries (for
    /// `exact_hits`).
    object: u32,
    triangle: u32,
    q_world: Vec3,
    disc: f32,
    light: Vec3,
}

/// What a frame found and how long its phases took (the paper's Table 2).
#[derive(Clone, Debug, Default)]
pub struct PhaseReport {
    pub cameras: u64,
    pub cameras_that_can_project_twice: u64,
    pub small_triangles: u64,
    pub small_triangle_pixels: u64,
    pub self_seeing_triangles: u64,
    /// Triangles cut into several cameras.
    pub split_triangles: u64,
    pub self_seeing_pixels: u64,
    pub leaves_visited: u64,
    /// Points in the leaves the cameras saw.
    pub points_in_leaves: u64,
    /// Those inside the camera's plane bound and facing it: projected by solving the cubic.
    pub points_projected: u64,
    pub valid_projections: u64,
    pub points_projected_more_than_once: u64,
    /// Valid projections of front-facing points in front of the eye.
    pub splats: u64,
    /// Points left out where a leaf's points would crowd more than a few into a pixel.
    pub points_skipped_by_level_of_detail: u64,
    pub covered_pixels: u64,
    pub holes_filled: u64,
    pub setup_ms: f64,
    pub culling_ms: f64,
    pub projection_ms: f64,
    /// Resolving the splats per pixel and filling holes.
    pub splatting_ms: f64,
    /// The pixels of triangles without a camera (per-vertex colour, traced pixels).
    pub fallback_ms: f64,
}

/// Radiance arriving along each mirror pixel's reflected ray from the nearby objects
/// (alpha non-zero where something was found: [`TAKEN_AS_IT_IS`] or the distance to it; 0 where
/// the far field shows), for the pixels of the
/// reflectors `mirrors`: [`plan`] then [`forward`] on the CPU.
#[allow(clippy::too_many_arguments)]
pub fn reflect_near(
    scene: &Scene,
    accel: &SceneAccel,
    mirrors: &[usize],
    clouds: &[PlacedCloud],
    view: &ScreenView,
    surfaces: &PixelSurfaces,
    settings: FrameSettings,
    out: &mut Vec<[f32; 4]>,
) -> PhaseReport {
    let mut plan = plan(scene, accel, mirrors, clouds, view, surfaces, settings);
    forward(
        &mut plan, scene, accel, mirrors, clouds, view, surfaces, settings, out,
    );
    plan.report
}

/// A frame's cameras and what each sees, before the forward phase.
pub struct Plan {
    pub(super) cameras: Vec<TriangleCamera>,
    /// First and past-last rows with a mirror pixel.
    mirror_rows: (usize, usize),
    /// The nodes each camera's view volume meets.
    pub(super) seen: Vec<Vec<Seen>>,
    /// Each camera in each cloud's space: index camera × clouds + cloud.
    in_cloud: Vec<InCloud>,
    /// Where each visible triangle's (per mirror mesh) pixels come from.
    sources: Vec<Vec<PixelSource>>,
    vertices: Vec<(usize, u32)>,
    traced: Vec<(Vec3, bool)>,
    pub report: PhaseReport,
}

impl Plan {
    /// Clears `out` to the frame's size and writes the pixels of the triangles without a
    /// camera (alpha [`TAKEN_AS_IT_IS`]): the per-vertex colour of small ones, traced colour of
    /// self-seeing ones.
    pub fn fallback(
        &self,
        scene: &Scene,
        accel: &SceneAccel,
        view: &ScreenView,
        surfaces: &PixelSurfaces,
        max_depth: u32,
        out: &mut Vec<[f32; 4]>,
    ) {
        out.clear();
        out.resize((view.width * view.height) as usize, [0.0; 4]);
        fallback_pixels(
            scene,
            accel,
            view,
            surfaces,
            &self.sources,
            &self.vertices,
            &self.traced,
            max_depth,
            false,
            out,
        );
    }
}

/// The alpha of a pixel's colour that the shading pass takes as it is (a traced, per-vertex or
/// splatted colour); a positive alpha is the distance along the pixel's reflected ray to the
/// nearby surface, which the shading pass tests against the far field (`c3rc.wgsl`); 0: none.
pub const TAKEN_AS_IT_IS: f32 = -1.0;

fn ms(start: Instant) -> f64 {
    start.elapsed().as_secs_f64() * 1e3
}

/// Calls `f(pixel, squared distance to the splat's centre)` for each pixel the square splat
/// covers that shows the surface the splat came from.
fn splat_pixels(
    s: &Splat,
    view: &ScreenView,
    surfaces: &PixelSurfaces,
    rows: (i64, i64),
    mut f: impl FnMut(usize, f32),
) {
    let w = view.width as i64;
    let x0 = ((s.x - s.radius).floor() as i64).max(0);
    let x1 = ((s.x + s.radius).ceil() as i64).min(w);
    let y0 = ((s.y - s.radius).floor() as i64).max(rows.0);
    let y1 = ((s.y + s.radius).ceil() as i64).min(rows.1);
    for py in y0..y1 {
        let dy = py as f32 + 0.5 - s.y;
        if dy.abs() > s.radius {
            continue;
        }
        for px in x0..x1 {
            let dx = px as f32 + 0.5 - s.x;
            if dx.abs() > s.radius {
                continue;
            }
            let k = (py * w + px) as usize;
            if surfaces.ids[k][0] != s.mesh + 1 {
                continue;
            }
            // A pixel whose surface is farther from the splat's reflector point than the
            // splat reaches shows another part of the reflector (or something in front of it).
            let p = surfaces.position[k];
            if (Vec3::new(p[0], p[1], p[2]) - s.p_world).length_squared() > s.reach * s.reach {
                continue;
            }
            f(k, dx * dx + dy * dy);
        }
    }
}

/// Rows of each band when `rows` (first, past-last) are split among the threads: every thread
/// reads all splats and writes its own rows.
fn rows_per_thread((first, last): (usize, usize)) -> usize {
    (last - first)
        .div_ceil(rayon::current_num_threads().max(1))
        .max(1)
}

/// The exact mirror reflection at `p` of the ray from the eye: the normal `n` turned to face
/// the eye (as the reference turns it), the origin pushed off the surface whose geometric
/// normal is `ng` (either side).
fn reflected_ray(p: Vec3, n: Vec3, ng: Vec3, eye: Vec3) -> Ray {
    let d = (p - eye).normalize_or_zero();
    let n = if n.dot(d) > 0.0 { -n } else { n };
    let dir = reflect(d, n);
    Ray {
        origin: offset_origin(p, ng, dir),
        dir,
    }
}

/// The pixels of the triangles that have no camera: small ones take their vertices' traced
/// colours, interpolated (with `keep_found`, only where the exact hits found nothing: their
/// neighbours' splats and surfaces usually reach them, and interpolating across a triangle that
/// spans many reflected checker squares would give their blur); those that see their own
/// mirror are traced, one exact reflected ray per pixel (with the normal interpolated as the
/// reference interpolates it).
#[allow(clippy::too_many_arguments)]
fn fallback_pixels(
    scene: &Scene,
    accel: &SceneAccel,
    view: &ScreenView,
    surfaces: &PixelSurfaces,
    sources: &[Vec<PixelSource>],
    vertices: &[(usize, u32)],
    traced: &[(Vec3, bool)],
    max_depth: u32,
    keep_found: bool,
    out: &mut [[f32; 4]],
) {
    let tracer = Tracer {
        scene,
        accel,
        max_depth,
    };
    let color_of = |mesh: usize, i: u32| {
        let k = vertices.binary_search(&(mesh, i)).expect("traced above");
        traced[k].0
    };
    out.par_iter_mut()
        .zip(&surfaces.ids)
        .zip(&surfaces.position)
        .enumerate()
        .for_each(|(k, ((out, [mesh1, t]), position))| {
            if *mesh1 == 0 {
                return;
            }
            let mesh = (mesh1 - 1) as usize;
            let source = sources.get(mesh).and_then(|f| f.get(*t as usize)).copied();
            if !matches!(source, Some(PixelSource::PerVertex | PixelSource::Traced)) {
                return;
            }
            if keep_found && source == Some(PixelSource::PerVertex) && out[3] != 0.0 {
                return;
            }
            let m = &scene.meshes[mesh];
            let tri = m.triangles[*t as usize];
            let [a, b, c] = tri.map(|i| m.positions[i as usize]);
            let p = Vec3::from_slice(&position[..3]);
            let bary = barycentric(p, a, b, c);
            let color = if source == Some(PixelSource::PerVertex) {
                color_of(mesh, tri[0]) * bary[0]
                    + color_of(mesh, tri[1]) * bary[1]
                    + color_of(mesh, tri[2]) * bary[2]
            } else {
                tracer.radiance(&pixel_reflected_ray(scene, view, surfaces, k), 1, None)
            };
            *out = [color.x, color.y, color.z, TAKEN_AS_IT_IS];
        });
}

/// Barycentric coordinates of `p` projected onto triangle abc, clamped to it.
fn barycentric(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> [f32; 3] {
    let n = (b - a).cross(c - a);
    let nn = n.length_squared();
    if nn <= 0.0 {
        return [1.0 / 3.0; 3];
    }
    let w0 = ((b - p).cross(c - p).dot(n) / nn).max(0.0);
    let w1 = ((c - p).cross(a - p).dot(n) / nn).max(0.0);
    let w2 = (1.0 - w0 - w1).max(0.0);
    let sum = w0 + w1 + w2;
    [w0 / sum, w1 / sum, w2 / sum]
}

/// Whether mesh `mesh` (not specular) comes within `distance` of `center`: its box first,
/// then its triangles (a room around the reflector is near only where a wall is).
pub fn mesh_is_near(scene: &Scene, mesh: usize, center: Vec3, distance: f32) -> bool {
    let m = &scene.meshes[mesh];
    let b = m.bounds();
    let outside = (b.min - center).max(center - b.max).max(Vec3::ZERO);
    if outside.length() > distance {
        return false;
    }
    m.triangles.iter().any(|tri| {
        let [a, b, c] = tri.map(|i| m.positions[i as usize].as_dvec3());
        (closest_point_on_triangle(center.as_dvec3(), a, b, c) - center.as_dvec3()).length()
            <= distance as f64
    })
}

/// The point of triangle abc closest to `p` (Ericson, Real-Time Collision Detection, 5.1.5).
fn closest_point_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}
