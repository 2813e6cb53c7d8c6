//! image-space's CPU side: d_N cast per vertex through the BVH (§3), §4.2's planes fitted to the
//! nearby geometry, and the measure of §6's fourth limitation (surfaces the eye cannot see).

use std::collections::HashMap;

use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use specula_scene::{MaterialKind, Scene};
use specula_trace::accel::{Ray, SceneAccel};

use super::MAX_PLANES;

/// Whether a material is refracted through as a solid (the paper's refractors).
pub(super) fn is_solid_refractor(kind: &MaterialKind) -> bool {
    matches!(
        kind,
        MaterialKind::Dielectric {
            thin_walled: false,
            ..
        }
    )
}

/// d_N for every vertex of `gpu_scene` (three per triangle, in its order): for vertices of
/// solid refractors, the distance along the inverted normal to the refractor's own surface on
/// the other side (other meshes are passed through); -1 where none is found (an open surface)
/// and for every other mesh.
pub fn normal_distances(scene: &Scene, accel: &SceneAccel) -> Vec<Vec<f32>> {
    scene
        .meshes
        .iter()
        .enumerate()
        .map(|(index, mesh)| {
            if !is_solid_refractor(&scene.materials[mesh.material].kind) {
                return Vec::new();
            }
            let offset = 1e-4 * mesh.bounds().extent().length().max(1e-6);
            let per_vertex: Vec<f32> = mesh
                .positions
                .par_iter()
                .zip(mesh.normals.par_iter())
                .map(|(&p, &n)| {
                    let Some(dir) = (-n).try_normalize() else {
                        return -1.0;
                    };
                    distance_to_own_surface(accel, index as u32, p + dir * offset, dir)
                        .map_or(-1.0, |t| t + offset)
                })
                .collect();
            mesh.triangles
                .iter()
                .flat_map(|tri| tri.map(|i| per_vertex[i as usize]))
                .collect()
        })
        .collect()
}

/// What the paper's fourth limitation costs on a scene: of the pixels that see a solid
/// refractor, how many send their (dominant) refracted path to a non-specular surface, and
/// how many of those surfaces are hidden from the eye behind other non-specular geometry —
/// points no single nearby-geometry texture drawn from the eye can hold.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct NearbyVisibility {
    pub refractor_pixels: usize,
    pub reaching_nearby_geometry: usize,
    pub hidden_from_eye: usize,
}

/// Measures [`NearbyVisibility`] with exact rays at `width` × `height`: each refractor pixel's
/// path is followed through solid refractors (refracted, or reflected under total internal
/// reflection) to the first other surface.
pub fn nearby_visibility(
    scene: &Scene,
    accel: &SceneAccel,
    width: u32,
    height: u32,
) -> NearbyVisibility {
    use specula_trace::optics::{reflect, refract};
    use specula_trace::reference::{offset_origin, surface_point};
    let eye = scene.camera.eye;
    let per_pixel: Vec<(bool, bool, bool)> = (0..width * height)
        .into_par_iter()
        .map(|i| {
            let (x, y) = ((i % width) as f32 + 0.5, (i / width) as f32 + 0.5);
            let mut ray = Ray {
                origin: eye,
                dir: scene.camera.ray_direction(x, y, width, height),
            };
            let mut through_refractor = false;
            for _ in 0..16 {
                let Some(hit) = accel.intersect(&ray, f32::INFINITY) else {
                    return (through_refractor, false, false);
                };
                let sp = surface_point(scene, &ray, &hit);
                let kind = &scene.materials[sp.material].kind;
                if !is_solid_refractor(kind) {
                    if !through_refractor || scene.materials[sp.material].is_specular() {
                        return (through_refractor, false, false);
                    }
                    return (true, true, hidden_behind_nearby(scene, accel, eye, sp.p));
                }
                through_refractor = true;
                let MaterialKind::Dielectric { ior, .. } = kind else {
                    unreachable!("a solid refractor is a dielectric");
                };
                let eta = if sp.backface { ior.y } else { 1.0 / ior.y };
                let dir = refract(ray.dir, sp.ns, eta).unwrap_or_else(|| reflect(ray.dir, sp.ns));
                ray = Ray {
                    origin: offset_origin(sp.p, sp.ng, dir),
                    dir,
                };
            }
            (through_refractor, false, false)
        })
        .collect();
    let mut visibility = NearbyVisibility::default();
    for (refractor, nearby, hidden) in per_pixel {
        visibility.refractor_pixels += refractor as usize;
        visibility.reaching_nearby_geometry += nearby as usize;
        visibility.hidden_from_eye += hidden as usize;
    }
    visibility
}

/// Whether a non-specular surface nearer than `point` lies on the line from the eye to it
/// (specular surfaces are passed through: the NG texture leaves them out).
fn hidden_behind_nearby(scene: &Scene, accel: &SceneAccel, eye: Vec3, point: Vec3) -> bool {
    let to_point = point - eye;
    let distance = to_point.length();
    let dir = to_point / distance;
    let mut origin = eye;
    let mut travelled = 0.0;
    for _ in 0..64 {
        let Some(hit) = accel.intersect(&Ray { origin, dir }, f32::INFINITY) else {
            return false;
        };
        if travelled + hit.t >= distance * (1.0 - 1e-3) {
            return false;
        }
        let mesh = &scene.meshes[hit.mesh as usize];
        if !scene.materials[mesh.material].is_specular() {
            return true;
        }
        let step = hit.t + 1e-4 * (1.0 + travelled + hit.t);
        origin += dir * step;
        travelled += step;
    }
    false
}

/// Distance from `origin` along `dir` to the first hit on mesh `mesh`, passing other meshes.
fn distance_to_own_surface(accel: &SceneAccel, mesh: u32, origin: Vec3, dir: Vec3) -> Option<f32> {
    let mut travelled = 0.0;
    let mut origin = origin;
    for _ in 0..64 {
        let hit = accel.intersect(&Ray { origin, dir }, f32::INFINITY)?;
        if hit.mesh == mesh {
            return Some(travelled + hit.t);
        }
        let step = hit.t + 1e-4 * (1.0 + travelled + hit.t);
        origin += dir * step;
        travelled += step;
    }
    None
}

/// One of §4.2's planes, as the shader reads it: a disc, so that a plane standing for one
/// object does not catch rays that pass far from it.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct GpuPlane {
    /// Unit normal; zero for a plane that faces the eye through `center` (an object that no
    /// plane of its own fits).
    pub normal: [f32; 3],
    /// dot(normal, p) on the plane.
    pub offset: f32,
    pub center: [f32; 3],
    /// Hits farther than this from `center` miss.
    pub radius: f32,
}

/// §4.2's planes, fitted on the CPU to the nearby (non-specular) geometry: each set of
/// coplanar triangles covering at least 2 % of its mesh's area is a disc around those
/// triangles (a floor, a wall, a box's side); a mesh not mostly covered by such sets gets a
/// disc through its centre facing the eye (the paper's plane standing for complex geometry,
/// its Figure 6), as large as its bounding sphere. The `MAX_PLANES` largest by area.
pub fn fit_planes(scene: &Scene) -> Vec<GpuPlane> {
    struct Group {
        area: f64,
        normal_sum: DVec3,
        offset_sum: f64,
        bounds: specula_scene::Aabb,
    }
    let diagonal = scene.bounds().extent().length().max(1e-6);
    let mut planes: Vec<(f64, GpuPlane)> = Vec::new();
    for mesh in &scene.meshes {
        if scene.materials[mesh.material].is_specular() {
            continue;
        }
        let mut groups: HashMap<[i64; 4], Group> = HashMap::new();
        let mut mesh_area = 0.0;
        for tri in &mesh.triangles {
            let corners = tri.map(|i| mesh.positions[i as usize]);
            let [a, b, c] = corners.map(|p| p.as_dvec3());
            let cross = (b - a).cross(c - a);
            let area = 0.5 * cross.length();
            if area <= 0.0 {
                continue;
            }
            mesh_area += area;
            let mut normal = cross.normalize();
            // One orientation per plane, so that both windings group together.
            let major = normal.abs().max_element();
            if [normal.x, normal.y, normal.z]
                .into_iter()
                .find(|v| v.abs() == major)
                .is_some_and(|v| v < 0.0)
            {
                normal = -normal;
            }
            let offset = normal.dot(a);
            let key = [
                (normal.x * 200.0).round() as i64,
                (normal.y * 200.0).round() as i64,
                (normal.z * 200.0).round() as i64,
                (offset / (1e-3 * diagonal as f64)).round() as i64,
            ];
            let group = groups.entry(key).or_insert(Group {
                area: 0.0,
                normal_sum: DVec3::ZERO,
                offset_sum: 0.0,
                bounds: specula_scene::Aabb::EMPTY,
            });
            group.area += area;
            group.normal_sum += normal * area;
            group.offset_sum += offset * area;
            for p in corners {
                group.bounds.grow(p);
            }
        }
        if mesh_area == 0.0 {
            continue;
        }
        let mut covered = 0.0;
        for group in groups.into_values() {
            if group.area >= 0.02 * mesh_area {
                covered += group.area;
                let normal = group.normal_sum.normalize();
                planes.push((
                    group.area,
                    GpuPlane {
                        normal: normal.as_vec3().to_array(),
                        offset: (group.offset_sum / group.area) as f32,
                        center: group.bounds.center().to_array(),
                        radius: group.bounds.radius() * 1.001,
                    },
                ));
            }
        }
        if covered < 0.5 * mesh_area {
            let bounds = mesh.bounds();
            planes.push((
                mesh_area,
                GpuPlane {
                    normal: [0.0; 3],
                    offset: 0.0,
                    center: bounds.center().to_array(),
                    radius: bounds.radius(),
                },
            ));
        }
    }
    planes.sort_by(|a, b| b.0.total_cmp(&a.0));
    planes.truncate(MAX_PLANES);
    planes.into_iter().map(|(_, p)| p).collect()
}

/// d_N per triangle corner, in scene order; -1 for the meshes that have none.
pub(super) fn triangle_normal_distances(scene: &Scene, accel: &SceneAccel) -> Vec<f32> {
    normal_distances(scene, accel)
        .into_iter()
        .zip(&scene.meshes)
        .flat_map(|(d, mesh)| {
            if d.is_empty() {
                vec![-1.0; 3 * mesh.triangles.len()]
            } else {
                d
            }
        })
        .collect()
}
