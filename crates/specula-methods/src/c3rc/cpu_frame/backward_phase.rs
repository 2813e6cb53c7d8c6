//! c3rc's plan of a frame on the CPU (§5, §5.2): the visible mirror triangles and the pixels
//! each covers, their vertices traced, a camera per triangle large enough to pay for one (cut in
//! four where it covers many pixels), and the backward phase: each camera's view volume against
//! each point tree, with the level of detail its leaves are projected at.

use std::time::Instant;

use glam::{DVec3, Vec3};
use rayon::prelude::*;
use specula_scene::{Mesh, Scene};
use specula_trace::reference::Tracer;
use specula_trace::SceneAccel;

use super::super::camera::C3rc;
use super::super::points::Node;
use super::{
    ms, reflected_ray, FrameSettings, InCloud, PhaseReport, PixelSource, PixelSurfaces,
    PlacedCloud, Plan, ScreenView, Seen, TriangleCamera,
};

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
