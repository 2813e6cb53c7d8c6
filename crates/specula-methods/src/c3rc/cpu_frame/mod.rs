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
use specula_scene::{Mesh, Scene};
use specula_trace::optics::reflect;
use specula_trace::reference::{offset_origin, Tracer};
use specula_trace::{Ray, SceneAccel};

use super::camera::{C3rc, PlaneBound, Projector};
use super::points::{Node, OneRing, PointCloud};

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
    /// Fill one-pixel holes between splats (with exact hits, [`fill_exact`]'s neighbours'
    /// surfaces instead).
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

/// The cameras of the visible mirror triangles and the backward phase (§5.2): which leaves
/// each camera's view volume meets.
pub fn plan(
    scene: &Scene,
    accel: &SceneAccel,
    mirrors: &[usize],
    clouds: &[PlacedCloud],
    view: &ScreenView,
    surfaces: &PixelSurfaces,
    settings: FrameSettings,
) -> Plan {
    let mut report = PhaseReport::default();
    // Cameras for the triangles that cover enough pixels; the rest are small.
    let start = Instant::now();
    let (visible, mirror_rows) = visible_triangles(scene, mirrors, view, surfaces);
    // The exact reflected ray at every vertex of a visible triangle: its radiance (the
    // per-vertex colour) and whether it hits its own mirror; needed only when a triangle may
    // take the per-vertex colour (one covering fewer than `min_pixels`, at least one pixel)
    // or be traced.
    let vertices = if settings.trace_self || settings.min_pixels > 1 {
        visible_vertices(scene, mirrors, &visible)
    } else {
        Vec::new()
    };
    let traced = trace_vertices(scene, accel, view, &vertices, settings.max_depth);
    let sees_itself = |mesh: usize, i: u32| {
        let k = vertices.binary_search(&(mesh, i)).expect("traced above");
        traced[k].1
    };
    let (cameras, sources) = triangle_cameras(
        scene,
        mirrors,
        view,
        &visible,
        &sees_itself,
        settings,
        &mut report,
    );
    report.cameras = cameras.len() as u64;
    report.setup_ms = ms(start);

    // Backward phase: each camera's view volume against every tree.
    let start = Instant::now();
    let culled: Vec<(Vec<Seen>, Vec<InCloud>)> = cameras
        .par_iter()
        .map(|camera| {
            let mut seen = Vec::new();
            let mut stack = Vec::new();
            let in_clouds = clouds
                .iter()
                .enumerate()
                .map(|(c, placed)| cull_cloud(camera, c, placed, settings, &mut seen, &mut stack))
                .collect();
            (seen, in_clouds)
        })
        .collect();
    let (seen, in_cloud): (Vec<Vec<Seen>>, Vec<Vec<InCloud>>) = culled.into_iter().unzip();
    report.leaves_visited = seen.iter().map(|l| l.len() as u64).sum();
    report.culling_ms = ms(start);
    Plan {
        cameras,
        mirror_rows,
        seen,
        in_cloud: in_cloud.into_iter().flatten().collect(),
        sources,
        vertices,
        traced,
        report,
    }
}

/// Per mesh, the pixels the ID buffer gives each triangle of a mirror (other meshes: none);
/// and the first and past-last rows with a mirror pixel (the later per-pixel passes look only
/// there).
fn visible_triangles(
    scene: &Scene,
    mirrors: &[usize],
    view: &ScreenView,
    surfaces: &PixelSurfaces,
) -> (Vec<Vec<u32>>, (usize, usize)) {
    let mut visible: Vec<Vec<u32>> = scene
        .meshes
        .iter()
        .enumerate()
        .map(|(k, m)| {
            vec![
                0;
                if mirrors.contains(&k) {
                    m.triangles.len()
                } else {
                    0
                }
            ]
        })
        .collect();
    let mut mirror_rows = (view.height as usize, 0usize);
    for (k, [mesh1, triangle]) in surfaces.ids.iter().enumerate() {
        if *mesh1 > 0 && mirrors.contains(&((mesh1 - 1) as usize)) {
            visible[(mesh1 - 1) as usize][*triangle as usize] += 1;
            let y = k / view.width as usize;
            mirror_rows = (mirror_rows.0.min(y), mirror_rows.1.max(y + 1));
        }
    }
    (visible, mirror_rows)
}

/// The (mesh, vertex) of every vertex of a visible mirror triangle, sorted, each once.
fn visible_vertices(scene: &Scene, mirrors: &[usize], visible: &[Vec<u32>]) -> Vec<(usize, u32)> {
    let mut vertices: Vec<(usize, u32)> = Vec::new();
    for &mesh in mirrors {
        for (t, _) in visible[mesh].iter().enumerate().filter(|(_, &c)| c > 0) {
            vertices.extend(scene.meshes[mesh].triangles[t].iter().map(|&i| (mesh, i)));
        }
    }
    vertices.sort_unstable();
    vertices.dedup();
    vertices
}

/// Where each visible mirror triangle's pixels come from, and the cameras of those that get
/// cameras: a triangle under `min_pixels` takes the per-vertex colour, one with a vertex that
/// `sees_itself` (when `trace_self`) is traced, every other gets its cameras
/// ([`push_triangle_cameras`]).
fn triangle_cameras(
    scene: &Scene,
    mirrors: &[usize],
    view: &ScreenView,
    visible: &[Vec<u32>],
    sees_itself: &dyn Fn(usize, u32) -> bool,
    settings: FrameSettings,
    report: &mut PhaseReport,
) -> (Vec<TriangleCamera>, Vec<Vec<PixelSource>>) {
    let mut cameras = Vec::new();
    let mut sources: Vec<Vec<PixelSource>> = visible
        .iter()
        .map(|v| vec![PixelSource::Camera; v.len()])
        .collect();
    for &mesh in mirrors {
        let m = &scene.meshes[mesh];
        for (t, &count) in visible[mesh].iter().enumerate() {
            if count == 0 {
                continue;
            }
            if count < settings.min_pixels {
                sources[mesh][t] = PixelSource::PerVertex;
                report.small_triangles += 1;
                report.small_triangle_pixels += count as u64;
                continue;
            }
            if settings.trace_self && m.triangles[t].iter().any(|&i| sees_itself(mesh, i)) {
                sources[mesh][t] = PixelSource::Traced;
                report.self_seeing_triangles += 1;
                report.self_seeing_pixels += count as u64;
                continue;
            }
            push_triangle_cameras(
                &mut cameras,
                m,
                (mesh, t),
                count,
                view,
                settings.split_pixels,
                report,
            );
        }
    }
    (cameras, sources)
}

/// The cameras of triangle `t` of `m` (mesh `mesh`), which covers `count` pixels: one, or
/// one per part when it is cut.
fn push_triangle_cameras(
    cameras: &mut Vec<TriangleCamera>,
    m: &Mesh,
    (mesh, t): (usize, usize),
    count: u32,
    view: &ScreenView,
    split_pixels: u32,
    report: &mut PhaseReport,
) {
    let eye = view.eye.as_dvec3();
    let idx = m.triangles[t].map(|i| i as usize);
    let v = idx.map(|i| m.positions[i].as_dvec3());
    let mut n = idx.map(|i| m.normals[i].as_dvec3());
    // The side the eye sees reflects (the reference flips normals the same way).
    let mut face = (v[1] - v[0]).cross(v[2] - v[0]);
    if face.dot(n[0] + n[1] + n[2]) < 0.0 {
        face = -face;
    }
    if face.dot(eye - v[0]) < 0.0 {
        n = n.map(|x| -x);
    }
    let screen = v.map(|p| view.project(p.as_vec3()));
    let screen_area = match screen {
        [Some(a), Some(b), Some(c)] => {
            let (ab, ac) = ((b.0 - a.0, b.1 - a.1), (c.0 - a.0, c.1 - a.1));
            0.5 * (ab.0 * ac.1 - ab.1 * ac.0).abs() as f64
        }
        _ => count as f64,
    }
    .max(count as f64);
    let centroid = (v[0] + v[1] + v[2]) / 3.0;
    let cos = face
        .normalize_or_zero()
        .dot((centroid - eye).normalize_or_zero())
        .abs();
    // Large triangles are cut in four (normals interpolated as the reference does) until each
    // part covers at most `split_pixels`: linear interpolation of the rays then follows the
    // reflection of the interpolated normal more closely.
    let mut levels = 0;
    while split_pixels > 0
        && levels < MAX_SPLIT_LEVELS
        && screen_area / 4f64.powi(levels as i32) > split_pixels as f64
    {
        levels += 1;
    }
    report.split_triangles += (levels > 0) as u64;
    for (v, n) in subdivide(v, n, levels) {
        let world = C3rc::reflector(v, n, eye);
        let folding = world.multiple_projection_intervals();
        report.cameras_that_can_project_twice += !folding.is_empty() as u64;
        cameras.push(TriangleCamera {
            mesh,
            world,
            screen_area: screen_area / 4f64.powi(levels as i32),
            folding,
            obliquity: (1.0 / cos.max(0.1)) as f32,
        });
    }
}

/// The backward phase of `camera` in cloud `c` (`placed`): the camera mapped into the cloud's
/// space, returned; the nodes its view volume meets pushed to `seen` (`stack` is scratch).
fn cull_cloud(
    camera: &TriangleCamera,
    c: usize,
    placed: &PlacedCloud,
    settings: FrameSettings,
    seen: &mut Vec<Seen>,
    stack: &mut Vec<usize>,
) -> InCloud {
    let cloud = placed.cloud;
    let local = camera.world.transformed(&placed.object_from_world);
    let root = &cloud.nodes[0];
    let in_cloud = InCloud {
        camera: local,
        bound: local.plane_bound(),
        projector: local.projector(),
        reach: local.lambda_bound(root.lo.as_dvec3(), root.hi.as_dvec3()),
    };
    if cloud.is_empty() {
        return in_cloud;
    }
    let folds = if settings.conservative_culling {
        local.fold_boxes(&camera.folding, in_cloud.reach)
    } else {
        Vec::new()
    };
    // The base's bounding sphere, for the normal-cone test.
    let base_center = (local.v[0] + local.v[1] + local.v[2]) / 3.0;
    let base_radius = local
        .v
        .iter()
        .map(|v| (*v - base_center).length())
        .fold(0.0, f64::max);
    let sees = |lo: DVec3, hi: DVec3| {
        if settings.conservative_culling {
            local.may_see_box(lo, hi, &folds)
        } else {
            local.corner_inside_or_face_meets_wall(lo, hi)
        }
    };
    stack.clear();
    stack.push(0usize);
    while let Some(k) = stack.pop() {
        let node = &cloud.nodes[k];
        let (lo, hi) = (node.lo.as_dvec3(), node.hi.as_dvec3());
        // The cheap planes first (they cull only boxes outside the volume), and the normal
        // cone (a node whose points all face away from the mirror triangle shows nothing when
        // points are one-sided), then the box test.
        if !in_cloud.bound.may_meet_box(lo, hi)
            || (settings.one_sided && !node.may_face(base_center.as_vec3(), base_radius as f32))
            || !sees(lo, hi)
        {
            continue;
        }
        let stride = if settings.level_of_detail {
            lod_stride(camera, &local, node, cloud.radius)
        } else {
            1
        };
        // A node the camera minifies so much that the level of detail keeps few of its points
        // is projected whole, strided: descending would cost more tests than the projections
        // it saves.
        let whole =
            settings.level_of_detail && node.point_count as usize / stride <= LOD_WHOLE_NODE_POINTS;
        if node.leaf || whole {
            seen.push(Seen {
                cloud: c,
                node: k,
                stride,
            });
        } else {
            stack.extend(node.first as usize..(node.first + node.count) as usize);
        }
    }
    in_cloud
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

/// The forward phase on the CPU (§5.1, §6): every leaf's points projected with the camera
/// that sees it, splatted and resolved per pixel; one-pixel holes filled (`fill_holes`; with
/// exact hits, pixels filled and mended from their neighbours' surfaces); then the pixels of
/// the triangles without a camera.
#[allow(clippy::too_many_arguments)]
pub fn forward(
    plan: &mut Plan,
    scene: &Scene,
    accel: &SceneAccel,
    mirrors: &[usize],
    clouds: &[PlacedCloud],
    view: &ScreenView,
    surfaces: &PixelSurfaces,
    settings: FrameSettings,
    out: &mut Vec<[f32; 4]>,
) {
    let pixel_count = (view.width * view.height) as usize;
    out.clear();
    out.resize(pixel_count, [0.0; 4]);
    // Forward phase: the leaves' points projected with the camera, every valid projection.
    let start = Instant::now();
    // The work spread node by node (a few wide cameras see most of the points: per-camera
    // work would leave a core idle).
    let items: Vec<(usize, Seen)> = plan
        .seen
        .iter()
        .enumerate()
        .flat_map(|(i, seen)| seen.iter().map(move |&s| (i, s)))
        .collect();
    let per_node: Vec<(Vec<Splat>, [u64; 5])> = items
        .par_iter()
        .map(|&(i, seen)| project_node(plan, clouds, view, &settings, i, seen))
        .collect();
    plan.report.projection_ms = ms(start);

    let start = Instant::now();
    resolve_splats(plan, scene, mirrors, clouds, view, surfaces, &settings, &per_node, out);
    plan.report.splatting_ms = ms(start);

    // Small triangles (per-vertex colour) and those that see their own mirror (traced).
    let start = Instant::now();
    fallback_pixels(
        scene,
        accel,
        view,
        surfaces,
        &plan.sources,
        &plan.vertices,
        &plan.traced,
        settings.max_depth,
        settings.exact_hits,
        out,
    );
    plan.report.fallback_ms = ms(start);
}

/// The points of one tree node seen by camera `i`, projected with it: their splats, and
/// (points tried, solved, valid projections, points projected twice, points skipped by the
/// level of detail).
fn project_node(
    plan: &Plan,
    clouds: &[PlacedCloud],
    view: &ScreenView,
    settings: &FrameSettings,
    i: usize,
    seen: Seen,
) -> (Vec<Splat>, [u64; 5]) {
    let camera = &plan.cameras[i];
    let cloud = clouds[seen.cloud].cloud;
    let world_from_object = clouds[seen.cloud].world_from_object;
    let InCloud {
        camera: local,
        bound,
        projector,
        reach,
    } = &plan.in_cloud[i * clouds.len() + seen.cloud];
    let range = cloud.nodes[seen.node].points();
    let stride = seen.stride;
    let (tried, skipped) = (range.len(), range.len() - range.len().div_ceil(stride));
    let (mut solved, mut valid, mut twice) = (0u64, 0u64, 0u64);
    let mut splats = Vec::new();
    // Kept points stand for the skipped ones: larger splats.
    let radius = (cloud.radius * settings.splat_scale) as f64 * (stride as f64).sqrt();
    for i in range.step_by(stride) {
        let q = cloud.p_object[i].as_dvec3();
        if !bound.may_contain(q) {
            continue;
        }
        // Points seen from behind belong to a surface whose front is nearer: a point
        // facing away from all three base vertices faces away from every base point.
        let n = cloud.n_object[i].as_dvec3();
        if settings.one_sided && local.v.iter().all(|v| n.dot(*v - q) <= 0.0) {
            continue;
        }
        solved += 1;
        let first_only = !settings.multiple_projections || !camera.may_project_twice();
        let (projections, count) =
            local.project_with(projector.cubic(q), q, *reach, first_only);
        twice += (count > 1) as u64;
        valid += count as u64;
        for projection in &projections[..count] {
            let base_local = projection.base_point(local);
            if settings.one_sided && n.dot(base_local - q) <= 0.0 {
                continue;
            }
            let p_world = projection.base_point(&camera.world).as_vec3();
            let Some((x, y, z_view)) = view.project(p_world) else {
                continue;
            };
            let area = camera.world.sweep_area(projection.lambda).max(1e-30);
            let r = (radius * (camera.screen_area / area).sqrt()) as f32;
            let radius_px = if settings.fixed_splat > 0.0 {
                0.5 * settings.fixed_splat
            } else if settings.exact_hits && r < settings.max_splat {
                // The disc's edge projected with the same camera: its actual
                // footprint, which the cross-section's area underestimates where the
                // surface is oblique to it or the rays converge.
                let footprint = disc_footprint(
                    local,
                    projector,
                    q,
                    n,
                    radius,
                    projection.lambda,
                    &camera.world,
                    view,
                    (x, y),
                );
                r.max(footprint).clamp(0.5, settings.max_splat)
            } else if settings.exact_hits {
                settings.max_splat
            } else {
                r.clamp(0.5, settings.max_splat)
            };
            let depth = (q - base_local).length() as f32;
            splats.push(Splat {
                x,
                y,
                radius: radius_px,
                depth,
                band: if settings.depth_band {
                    2.0 * radius as f32 + 0.01 * depth
                } else {
                    0.0
                },
                reach: (radius_px + 1.5) * view.footprint(z_view) * camera.obliquity,
                p_world,
                color: cloud.color[i],
                mesh: camera.mesh as u32,
                object: cloud.mesh as u32,
                triangle: cloud.triangle[i],
                q_world: world_from_object.transform_point3(q).as_vec3(),
                disc: radius as f32,
                light: cloud.light[i],
            });
        }
    }
    (splats, [tried as u64, solved, valid, twice, skipped as u64])
}

/// Splats resolved per pixel: with exact hits, each mirror pixel's own reflected ray met with
/// the triangles its splats nominate; else on the reflector surface the splat came from,
/// nearest first. Then the one-pixel holes filled (`fill_holes`).
#[allow(clippy::too_many_arguments)]
fn resolve_splats(
    plan: &mut Plan,
    scene: &Scene,
    mirrors: &[usize],
    clouds: &[PlacedCloud],
    view: &ScreenView,
    surfaces: &PixelSurfaces,
    settings: &FrameSettings,
    per_node: &[(Vec<Splat>, [u64; 5])],
    out: &mut [[f32; 4]],
) {
    let pixel_count = (view.width * view.height) as usize;
    let report = &mut plan.report;
    let mut depth = vec![f32::INFINITY; pixel_count];
    for (splats, [tried, solved, valid, twice, skipped]) in per_node {
        report.points_skipped_by_level_of_detail += skipped;
        report.points_in_leaves += tried;
        report.points_projected += solved;
        report.splats += splats.len() as u64;
        report.points_projected_more_than_once += twice;
        report.valid_projections += valid;
    }
    if settings.exact_hits {
        let splats: Vec<&Splat> = per_node.iter().flat_map(|(s, _)| s).collect();
        let mut rings: Vec<Option<&OneRing>> = vec![None; scene.meshes.len()];
        for placed in clouds {
            rings[placed.cloud.mesh] = Some(&placed.cloud.one_ring);
        }
        let rays = mirror_rays(scene, view, surfaces, mirrors, plan.mirror_rows);
        let mut found = vec![None; pixel_count];
        resolve_exact(
            scene,
            &rings,
            &splats,
            view,
            surfaces,
            plan.mirror_rows,
            &rays,
            &mut found,
        );
        report.covered_pixels = found.iter().filter(|f| f.is_some()).count() as u64;
        if settings.fill_holes {
            report.holes_filled = fill_exact(scene, view, plan.mirror_rows, &rays, &mut found);
        }
        for (k, f) in found.iter().enumerate() {
            if let Some(Found { hit, light }) = f {
                let c = albedo_at(scene, hit) * *light;
                // The distance, for the shading pass's test against the far field.
                out[k] = [c.x, c.y, c.z, hit.t];
            }
        }
    } else {
        resolve(per_node, view, surfaces, plan.mirror_rows, &mut depth, out);
        let w = view.width as usize;
        let (first, last) = plan.mirror_rows;
        if first < last {
            let rows = first * w..last * w;
            report.covered_pixels = depth[rows].iter().filter(|d| d.is_finite()).count() as u64;
            if settings.fill_holes {
                report.holes_filled =
                    fill_holes(view, surfaces, mirrors, (first, last), &depth, out);
            }
        }
    }
}

/// Pixels from `centre` (the screen position of point `q`'s projection at `lambda`) to where
/// the edge of its disc (radius `radius` about `q`, normal `n`, in the cloud's space) projects
/// with the same camera (`local` there, `world` in the world), the largest of two tangent
/// directions; 0 where neither projects.
#[allow(clippy::too_many_arguments)]
fn disc_footprint(
    local: &C3rc,
    projector: &Projector,
    q: DVec3,
    n: DVec3,
    radius: f64,
    lambda: f64,
    world: &C3rc,
    view: &ScreenView,
    centre: (f32, f32),
) -> f32 {
    let (t1, t2) = n.normalize_or_zero().any_orthonormal_pair();
    [t1, t2]
        .into_iter()
        .filter_map(|t| {
            let edge = q + t * radius;
            let bary = local.bary_near(projector.cubic(edge), edge, lambda)?;
            let p_world = world.v[0] * bary[0] + world.v[1] * bary[1] + world.v[2] * bary[2];
            let (x, y, _) = view.project(p_world.as_vec3())?;
            Some(((x - centre.0).powi(2) + (y - centre.1).powi(2)).sqrt())
        })
        .fold(0.0, f32::max)
}

/// The alpha of a pixel's colour that the shading pass takes as it is (a traced, per-vertex or
/// splatted colour); a positive alpha is the distance along the pixel's reflected ray to the
/// nearby surface, which the shading pass tests against the far field (`c3rc.wgsl`); 0: none.
pub const TAKEN_AS_IT_IS: f32 = -1.0;

/// A node whose strided points number at most this is projected whole (not descended).
const LOD_WHOLE_NODE_POINTS: usize = 128;

/// Points per pixel the level of detail keeps (about).
const LOD_POINTS_PER_PIXEL: f64 = 4.0;

/// How many of a leaf's points one projected point stands for: where the camera minifies the
/// leaf so much that its points would crowd more than [`LOD_POINTS_PER_PIXEL`] into a pixel,
/// every k-th point is enough. Estimated at the leaf's nearest sweep distance (its
/// cross-section there is the smallest, so the stride the smallest).
fn lod_stride(camera: &TriangleCamera, local: &C3rc, node: &Node, radius: f32) -> usize {
    let center = (local.v[0] + local.v[1] + local.v[2]) / 3.0;
    let (lo, hi) = (node.lo.as_dvec3(), node.hi.as_dvec3());
    let nearest = center.clamp(lo, hi);
    let lambda = (nearest - center).length();
    let section = local.sweep_area(lambda).max(1e-30);
    let pixels_per_point =
        std::f64::consts::PI * (radius as f64).powi(2) * (camera.screen_area / section);
    let points_per_pixel = 1.0 / pixels_per_point.max(1e-30);
    ((points_per_pixel / LOD_POINTS_PER_PIXEL).floor() as usize).clamp(1, 1 << 16)
}

/// Most times a large triangle is cut in four.
const MAX_SPLIT_LEVELS: u32 = 3;

/// The triangle (vertices, unit normals) cut into 4^levels by its edges' midpoints; midpoint
/// normals are the normalised means.
fn subdivide(v: [DVec3; 3], n: [DVec3; 3], levels: u32) -> Vec<([DVec3; 3], [DVec3; 3])> {
    let mut parts = vec![(v, n.map(|x| x.normalize_or_zero()))];
    for _ in 0..levels {
        parts = parts
            .into_iter()
            .flat_map(|(v, n)| {
                let mid =
                    |a: usize, b: usize| ((v[a] + v[b]) * 0.5, (n[a] + n[b]).normalize_or_zero());
                let ((v01, n01), (v12, n12), (v20, n20)) = (mid(0, 1), mid(1, 2), mid(2, 0));
                [
                    ([v[0], v01, v20], [n[0], n01, n20]),
                    ([v01, v[1], v12], [n01, n[1], n12]),
                    ([v20, v12, v[2]], [n20, n12, n[2]]),
                    ([v01, v12, v20], [n01, n12, n20]),
                ]
            })
            .collect();
    }
    parts
}

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

/// Resolves the splats per pixel: the nearest push-back depth finds the front surface; among
/// the splats within `band` of it (points of that same surface) the one whose centre is
/// nearest the pixel's gives the colour (a point-sampled reconstruction, not the colour of
/// whichever point happened to lie nearest the reflector).
fn resolve(
    per_node: &[(Vec<Splat>, [u64; 5])],
    view: &ScreenView,
    surfaces: &PixelSurfaces,
    rows: (usize, usize),
    depth: &mut [f32],
    out: &mut [[f32; 4]],
) {
    let w = view.width as usize;
    let (first, last) = rows;
    if first >= last {
        return;
    }
    let band = rows_per_thread(rows);
    depth[first * w..last * w]
        .par_chunks_mut(band * w)
        .zip(out[first * w..last * w].par_chunks_mut(band * w))
        .enumerate()
        .for_each(|(b, (depth, out))| {
            let top = first + b * band;
            let range = (top as i64, (top + depth.len() / w) as i64);
            let offset = top * w;
            let splats = || per_node.iter().flat_map(|(splats, _)| splats);
            for s in splats() {
                splat_pixels(s, view, surfaces, range, |k, _| {
                    depth[k - offset] = depth[k - offset].min(s.depth)
                });
            }
            let mut nearest = vec![f32::INFINITY; depth.len()];
            for s in splats() {
                splat_pixels(s, view, surfaces, range, |k, d2| {
                    let k = k - offset;
                    if s.depth <= depth[k] + s.band && d2 < nearest[k] {
                        nearest[k] = d2;
                        out[k] = [s.color.x, s.color.y, s.color.z, TAKEN_AS_IT_IS];
                    }
                });
            }
        });
}

/// How a pixel's exact reflected ray meets the triangle of a point whose splat covers it.
#[derive(Clone, Copy, PartialEq, PartialOrd)]
enum Meeting {
    /// Within the triangle: the surface the ray hits, if nothing nearer is nominated.
    Inside,
    /// On the triangle's plane, outside it but within the point's disc: the surface
    /// extrapolated (its true triangle nominated by no splat here).
    OnDisc,
}

/// The best hit per pixel so far: how it met, its distance along the ray, the object, the
/// triangle and the barycentrics there.
#[derive(Clone, Copy)]
struct NominatedHit {
    meeting: Meeting,
    t: f32,
    object: u32,
    triangle: u32,
    b1: f32,
    b2: f32,
}

/// Where `ray` meets the plane of `object`'s `triangle` (t > 0): distance and barycentrics
/// (b1, b2), with b0 = 1 − b1 − b2; any of them may be negative (outside the triangle).
fn meet_plane(scene: &Scene, ray: &Ray, object: u32, triangle: u32) -> Option<(f32, f32, f32)> {
    let m = &scene.meshes[object as usize];
    let [a, b, c] = m.triangles[triangle as usize].map(|i| m.positions[i as usize]);
    let (e1, e2) = (b - a, c - a);
    let pvec = ray.dir.cross(e2);
    let det = e1.dot(pvec);
    if det.abs() < 1e-12 {
        return None;
    }
    let inv = 1.0 / det;
    let tvec = ray.origin - a;
    let b1 = tvec.dot(pvec) * inv;
    let qvec = tvec.cross(e1);
    let b2 = ray.dir.dot(qvec) * inv;
    let t = e2.dot(qvec) * inv;
    (t > 0.0 && t.is_finite()).then_some((t, b1, b2))
}

/// Resolves the splats with the pixels' exact rays (`exact_hits`): every splat covering a
/// mirror pixel nominates its point's triangle; the pixel's reflected ray (the reference's,
/// about the interpolated normal) is met with it, and the nearest meeting inside a triangle
/// wins (else the nearest within a point's disc on its plane). The colour is the surface's
/// albedo where the ray meets it (its texture at the exact UV) times the light of the points
/// whose discs hold that spot, weighted by a kernel falling to 0 at the disc's edge. A splat
/// thus only has to reach a pixel, not to stand for its colour: magnified points leave no
/// blocks, and the edges of large triangles (a room's walls) are exact.
#[allow(clippy::too_many_arguments)]
fn resolve_exact(
    scene: &Scene,
    rings: &[Option<&OneRing>],
    splats: &[&Splat],
    view: &ScreenView,
    surfaces: &PixelSurfaces,
    rows: (usize, usize),
    rays: &[Option<Ray>],
    found: &mut [Option<Found>],
) {
    let w = view.width as usize;
    let (first, last) = rows;
    if first >= last {
        return;
    }
    let band = rows_per_thread(rows);
    found[first * w..last * w]
        .par_chunks_mut(band * w)
        .enumerate()
        .for_each(|(b, found)| {
            let top = first + b * band;
            let range = (top as i64, (top + found.len() / w) as i64);
            let offset = top * w;
            let rays = &rays[offset..offset + found.len()];
            let mut best: Vec<Option<NominatedHit>> = vec![None; found.len()];
            for s in splats {
                splat_pixels(s, view, surfaces, range, |k, _| {
                    let k = k - offset;
                    // Another point of the winning triangle meets it where the winner did
                    // (the many points of a room's wall over one pixel).
                    if best[k].is_some_and(|h| (h.object, h.triangle) == (s.object, s.triangle)) {
                        return;
                    }
                    let ray = rays[k].expect("a splat lands on mirror pixels only");
                    let Some((t, b1, b2)) = meet_plane(scene, &ray, s.object, s.triangle) else {
                        return;
                    };
                    let on_disc = |t: f32| {
                        (ray.origin + ray.dir * t - s.q_world).length_squared() <= s.disc * s.disc
                    };
                    let hit = if inside(b1, b2) {
                        NominatedHit {
                            meeting: Meeting::Inside,
                            t,
                            object: s.object,
                            triangle: s.triangle,
                            b1,
                            b2,
                        }
                    } else if best[k]
                        .is_some_and(|h| h.meeting == Meeting::Inside && h.t < t - s.disc)
                    {
                        // Clearly behind a surface the ray meets: neither this point's plane
                        // nor its neighbours' (within its disc) can win.
                        return;
                    } else if on_disc(t) {
                        // The ray misses the point's triangle near the point: its true
                        // triangle is likely a neighbour (triangles smaller than the points'
                        // spacing, a curved surface whose plane here is another).
                        let ring = rings[s.object as usize].expect("a nominating point's cloud");
                        meet_one_ring(scene, ring, &ray, s.object, s.triangle).unwrap_or(
                            NominatedHit {
                                meeting: Meeting::OnDisc,
                                t,
                                object: s.object,
                                triangle: s.triangle,
                                b1,
                                b2,
                            },
                        )
                    } else {
                        return;
                    };
                    if best[k].is_none_or(|h| (hit.meeting, hit.t) < (h.meeting, h.t)) {
                        best[k] = Some(hit);
                    }
                });
            }
            // The light at each winning hit: the points of its object whose discs hold it.
            let mut light = vec![(Vec3::ZERO, f32::NEG_INFINITY); found.len()];
            for s in splats {
                splat_pixels(s, view, surfaces, range, |k, _| {
                    let k = k - offset;
                    let (Some(hit), Some(ray)) = (best[k], rays[k]) else {
                        return;
                    };
                    if hit.object != s.object {
                        return;
                    }
                    // (sum of weighted lights, sum of weights) once a disc holds the hit;
                    // before that, (the nearest point's light, minus its squared distance).
                    // The winner's own splat covers the pixel, so one of the two is found.
                    let d2 = (ray.origin + ray.dir * hit.t - s.q_world).length_squared();
                    let weight = 1.0 - d2 / (s.disc * s.disc);
                    let (sum, weights) = &mut light[k];
                    if weight > 0.0 {
                        if *weights <= 0.0 {
                            (*sum, *weights) = (Vec3::ZERO, 0.0);
                        }
                        *sum += s.light * weight;
                        *weights += weight;
                    } else if *weights <= 0.0 && -d2 > *weights {
                        (*sum, *weights) = (s.light, -d2);
                    }
                });
            }
            for (k, hit) in best.iter().enumerate() {
                let Some(hit) = *hit else { continue };
                let (sum, weight) = light[k];
                let light = if weight > 0.0 { sum / weight } else { sum };
                found[k] = Some(Found { hit, light });
            }
        });
}

/// What a mirror pixel's exact ray met: the hit and the light the points carry there.
#[derive(Clone, Copy)]
struct Found {
    hit: NominatedHit,
    light: Vec3,
}

/// Passes of [`fill_exact`], and how far (pixels) each looks for neighbours.
const FILL_PASSES: usize = 4;
const FILL_RADIUS: i64 = 2;

/// Fills mirror pixels no splat reached, and mends those whose splats missed the surface in
/// front (exact hits): each is tried with the triangles its neighbours' rays met (within
/// [`FILL_RADIUS`]); its own ray's nearest meeting inside one wins, with that neighbour's
/// light, where it is nearer than what the pixel has (or the pixel has nothing, or only a
/// point's disc); [`FILL_PASSES`] times, so a hole fills inwards from its edge. Where a surface
/// lies behind a gap between splats (random sampling leaves some, most where a mirror
/// magnifies), or a small object's triangles were nominated only around a pixel, its triangles
/// are the neighbours'. Returns the pixels changed.
fn fill_exact(
    scene: &Scene,
    view: &ScreenView,
    rows: (usize, usize),
    rays: &[Option<Ray>],
    found: &mut [Option<Found>],
) -> u64 {
    let (w, h) = (view.width as i64, view.height as i64);
    let mut filled_total = 0u64;
    for _ in 0..FILL_PASSES {
        let now: &[Option<Found>] = found;
        let filled: Vec<(usize, Found)> = (rows.0 as i64..rows.1 as i64)
            .into_par_iter()
            .flat_map_iter(|y| {
                (0..w).filter_map(move |x| {
                    let k = (y * w + x) as usize;
                    // Mirror pixels only.
                    let ray = rays[k]?;
                    let mut tried: Vec<(u32, u32)> = Vec::new();
                    if let Some(own) = now[k] {
                        tried.push((own.hit.object, own.hit.triangle));
                    }
                    let mut best: Option<Found> = None;
                    for dy in -FILL_RADIUS..=FILL_RADIUS {
                        for dx in -FILL_RADIUS..=FILL_RADIUS {
                            let (nx, ny) = (x + dx, y + dy);
                            if nx < 0 || ny < 0 || nx >= w || ny >= h {
                                continue;
                            }
                            let Some(neighbour) = now[(ny * w + nx) as usize] else {
                                continue;
                            };
                            let key = (neighbour.hit.object, neighbour.hit.triangle);
                            if tried.contains(&key) {
                                continue;
                            }
                            tried.push(key);
                            let Some((t, b1, b2)) = meet_plane(scene, &ray, key.0, key.1) else {
                                continue;
                            };
                            let nearer = |b: Option<Found>| {
                                b.is_none_or(|b| (Meeting::Inside, t) < (b.hit.meeting, b.hit.t))
                            };
                            if inside(b1, b2) && nearer(best) && nearer(now[k]) {
                                let hit = NominatedHit {
                                    meeting: Meeting::Inside,
                                    t,
                                    b1,
                                    b2,
                                    ..neighbour.hit
                                };
                                best = Some(Found {
                                    hit,
                                    light: neighbour.light,
                                });
                            }
                        }
                    }
                    best.map(|f| (k, f))
                })
            })
            .collect();
        if filled.is_empty() {
            break;
        }
        filled_total += filled.len() as u64;
        for (k, f) in filled {
            found[k] = Some(f);
        }
    }
    filled_total
}

/// Rows of each band when `rows` (first, past-last) are split among the threads: every thread
/// reads all splats and writes its own rows.
fn rows_per_thread((first, last): (usize, usize)) -> usize {
    (last - first)
        .div_ceil(rayon::current_num_threads().max(1))
        .max(1)
}

/// The exact reflected ray of every pixel of `mirrors` in `rows` (others: None), for
/// `resolve_exact` and `fill_exact`.
fn mirror_rays(
    scene: &Scene,
    view: &ScreenView,
    surfaces: &PixelSurfaces,
    mirrors: &[usize],
    rows: (usize, usize),
) -> Vec<Option<Ray>> {
    let w = view.width as usize;
    let mut rays = vec![None; (view.width * view.height) as usize];
    rays[rows.0 * w..rows.1.max(rows.0) * w]
        .par_iter_mut()
        .enumerate()
        .for_each(|(i, ray)| {
            let k = rows.0 * w + i;
            let mesh1 = surfaces.ids[k][0];
            if mesh1 > 0 && mirrors.contains(&((mesh1 - 1) as usize)) {
                *ray = Some(pixel_reflected_ray(scene, view, surfaces, k));
            }
        });
    rays
}

/// Barycentric slack within which a ray meets a triangle (its edges shared with neighbours).
const BARY_SLACK: f32 = 1e-4;

/// Whether barycentrics (b1, b2) lie within a triangle (with [`BARY_SLACK`]).
fn inside(b1: f32, b2: f32) -> bool {
    b1 >= -BARY_SLACK && b2 >= -BARY_SLACK && b1 + b2 <= 1.0 + BARY_SLACK
}

/// The nearest meeting of `ray` inside a triangle sharing a vertex with `object`'s `triangle`
/// (not itself).
fn meet_one_ring(
    scene: &Scene,
    ring: &OneRing,
    ray: &Ray,
    object: u32,
    triangle: u32,
) -> Option<NominatedHit> {
    let m = &scene.meshes[object as usize];
    let mut best: Option<NominatedHit> = None;
    for &v in &m.triangles[triangle as usize] {
        for &other in ring.around(v) {
            if other == triangle {
                continue;
            }
            let Some((t, b1, b2)) = meet_plane(scene, ray, object, other) else {
                continue;
            };
            if inside(b1, b2) && best.is_none_or(|h| t < h.t) {
                best = Some(NominatedHit {
                    meeting: Meeting::Inside,
                    t,
                    object,
                    triangle: other,
                    b1,
                    b2,
                });
            }
        }
    }
    best
}

/// The surface's albedo (colour × texture) where `hit` meets it; outside its triangle (within a
/// point's disc), with its UVs extrapolated: on the neighbouring triangle of the same plane
/// and mapping, exact.
fn albedo_at(scene: &Scene, hit: &NominatedHit) -> Vec3 {
    let m = &scene.meshes[hit.object as usize];
    let material = &scene.materials[m.material];
    let Some(texture) = material.texture else {
        return material.color;
    };
    let [w0, w1, w2] = [1.0 - hit.b1 - hit.b2, hit.b1, hit.b2];
    let [i0, i1, i2] = m.triangles[hit.triangle as usize].map(|i| i as usize);
    let uv = if m.uvs.is_empty() {
        glam::Vec2::ZERO
    } else {
        m.uvs[i0] * w0 + m.uvs[i1] * w1 + m.uvs[i2] * w2
    };
    material.color * scene.textures[texture].sample(uv)
}

/// The exact reflected ray of mirror pixel `k` (as the reference reflects it: about the
/// normal interpolated at the pixel's surface point).
fn pixel_reflected_ray(
    scene: &Scene,
    view: &ScreenView,
    surfaces: &PixelSurfaces,
    k: usize,
) -> Ray {
    let [mesh1, t] = surfaces.ids[k];
    let m = &scene.meshes[(mesh1 - 1) as usize];
    let tri = m.triangles[t as usize];
    let [a, b, c] = tri.map(|i| m.positions[i as usize]);
    let p = Vec3::from_slice(&surfaces.position[k][..3]);
    let bary = barycentric(p, a, b, c);
    let [na, nb, nc] = tri.map(|i| m.normals[i as usize]);
    let n = (na * bary[0] + nb * bary[1] + nc * bary[2]).normalize_or_zero();
    let face = (b - a).cross(c - a).normalize_or_zero();
    reflected_ray(p, n, face, view.eye)
}

/// Fills one-pixel holes between splats: an uncovered mirror pixel with at least five of its
/// eight neighbours covered (on the same mesh) takes the front-most neighbour's colour.
/// Returns the pixels filled.
fn fill_holes(
    view: &ScreenView,
    surfaces: &PixelSurfaces,
    mirrors: &[usize],
    rows: (usize, usize),
    depth: &[f32],
    out: &mut [[f32; 4]],
) -> u64 {
    let (w, h) = (view.width as i64, view.height as i64);
    let covered_out: &[[f32; 4]] = out;
    let filled: Vec<(usize, [f32; 4])> = (rows.0 as i64..rows.1 as i64)
        .into_par_iter()
        .flat_map_iter(|y| {
            (0..w).filter_map(move |x| {
                let k = (y * w + x) as usize;
                let mesh1 = surfaces.ids[k][0];
                if covered_out[k][3] != 0.0
                    || mesh1 == 0
                    || !mirrors.contains(&((mesh1 - 1) as usize))
                {
                    return None;
                }
                let mut covered = 0;
                let mut best: Option<usize> = None;
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        let (nx, ny) = (x + dx, y + dy);
                        if (dx, dy) == (0, 0) || nx < 0 || ny < 0 || nx >= w || ny >= h {
                            continue;
                        }
                        let n = (ny * w + nx) as usize;
                        if surfaces.ids[n][0] == mesh1 && depth[n].is_finite() {
                            covered += 1;
                            if best.is_none_or(|b| depth[n] < depth[b]) {
                                best = Some(n);
                            }
                        }
                    }
                }
                best.filter(|_| covered >= 5).map(|b| (k, covered_out[b]))
            })
        })
        .collect();
    for &(k, color) in &filled {
        out[k] = color;
    }
    filled.len() as u64
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

/// Radiance along the exact reflected ray at each (mesh, vertex) (traced through the BVH
/// with the reference's shading), and whether that ray hits the same mesh first.
fn trace_vertices(
    scene: &Scene,
    accel: &SceneAccel,
    view: &ScreenView,
    vertices: &[(usize, u32)],
    max_depth: u32,
) -> Vec<(Vec3, bool)> {
    let tracer = Tracer {
        scene,
        accel,
        max_depth,
    };
    vertices
        .par_iter()
        .map(|&(mesh, i)| {
            let m = &scene.meshes[mesh];
            let n = m.normals[i as usize].normalize_or_zero();
            let ray = reflected_ray(m.positions[i as usize], n, n, view.eye);
            let sees_itself = accel
                .intersect(&ray, f32::INFINITY)
                .is_some_and(|hit| hit.mesh as usize == mesh);
            (tracer.radiance(&ray, 1, None), sees_itself)
        })
        .collect()
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
