//! c3rc's forward phase on the CPU (§5.1, §6): the points of the leaves each camera sees
//! projected with it into splats, and the splats resolved per pixel, nearest to the reflector
//! first (the paper), with the holes between them filled.

use std::time::Instant;

use glam::DVec3;
use rayon::prelude::*;
use specula_scene::Scene;
use specula_trace::SceneAccel;

use super::super::camera::{C3rc, Projector};
use super::super::points::OneRing;
use super::exact_hits::{albedo_at, fill_exact, mirror_rays, resolve_exact, Found};
use super::{
    fallback_pixels, ms, rows_per_thread, splat_pixels, FrameSettings, InCloud, PixelSurfaces,
    PlacedCloud, Plan, ScreenView, Seen, Splat, TAKEN_AS_IT_IS,
};

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
    resolve_splats(
        plan, scene, mirrors, clouds, view, surfaces, &settings, &per_node, out,
    );
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
        let (projections, count) = local.project_with(projector.cubic(q), q, *reach, first_only);
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
