//! c3rc's exact hits: each mirror pixel's own reflected ray met with the triangles the splats
//! covering it nominate (`resolve_exact`), and the pixels no splat nominated a triangle for
//! filled from their neighbours' (`fill_exact`).

use glam::Vec3;
use rayon::prelude::*;
use specula_scene::Scene;
use specula_trace::Ray;

use super::super::points::OneRing;
use super::{
    barycentric, reflected_ray, rows_per_thread, splat_pixels, PixelSurfaces, ScreenView, Splat,
};

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
pub(super) struct NominatedHit {
    meeting: Meeting,
    pub(super) t: f32,
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
pub(super) fn resolve_exact(
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
pub(super) struct Found {
    pub(super) hit: NominatedHit,
    pub(super) light: Vec3,
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
pub(super) fn fill_exact(
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

/// The exact reflected ray of every pixel of `mirrors` in `rows` (others: None), for
/// `resolve_exact` and `fill_exact`.
pub(super) fn mirror_rays(
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
pub(super) fn albedo_at(scene: &Scene, hit: &NominatedHit) -> Vec3 {
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
pub(super) fn pixel_reflected_ray(
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
