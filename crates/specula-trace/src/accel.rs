//! Ray queries against a scene's triangles: closest hit and any hit (shadows), over a [`Bvh`],
//! with the watertight ray–triangle test of Woop, Benthin and Wald (JCGT 2013, "Watertight
//! Ray/Triangle Intersection"): no ray slips through a shared edge or vertex.

use glam::{Vec3, Vec3A};
use specula_scene::{Aabb, Scene};

use crate::bvh::{Bvh, BvhNode};

#[derive(Clone, Copy, Debug)]
pub struct Ray {
    pub origin: Vec3,
    /// Unit direction of travel.
    pub dir: Vec3,
}

/// A ray–triangle hit: distance along the ray, the barycentric weights of the triangle's second
/// and third vertices, and which triangle (mesh index, triangle index within the mesh).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    pub b1: f32,
    pub b2: f32,
    pub mesh: u32,
    pub triangle: u32,
}

/// 1 + 2γ(3), with γ(n) = nε/(1 − nε) and ε half the machine epsilon (Ize 2013).
const ROBUST_WIDENING: f32 =
    1.0 + 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5);

/// Per-ray constants of the watertight test and the slab test.
struct RayData {
    origin: Vec3A,
    inv_dir: Vec3A,
    /// Rows of the shear-and-permute transform of the watertight test: for a vertex `a`
    /// relative to the origin, `a·to_x = a[kx] − Sx·a[kz]`, `a·to_y = a[ky] − Sy·a[kz]`,
    /// `a·to_z = Sz·a[kz]`. Each row has one or two non-zero entries, so the dot products are
    /// bit-identical to the paper's scalar formulas (adding exact zeros changes nothing).
    to_x: Vec3A,
    to_y: Vec3A,
    to_z: Vec3A,
}

impl RayData {
    fn new(ray: &Ray) -> Self {
        let d = ray.dir;
        let abs = d.abs();
        let kz = if abs.x > abs.y {
            if abs.x > abs.z {
                0
            } else {
                2
            }
        } else if abs.y > abs.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        // Keep the triangle's winding: swap when the dominant component is negative.
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        // Replace zero components by a tiny signed value so the slab test sees ±inf-free data.
        let safe = d.to_array().map(|c| {
            if c.abs() < 1e-30 {
                1e-30f32.copysign(c)
            } else {
                c
            }
        });
        let (mut to_x, mut to_y, mut to_z) = ([0.0f32; 3], [0.0f32; 3], [0.0f32; 3]);
        let inv_dz = 1.0 / d[kz];
        to_x[kx] = 1.0;
        to_x[kz] = -d[kx] * inv_dz;
        to_y[ky] = 1.0;
        to_y[kz] = -d[ky] * inv_dz;
        to_z[kz] = inv_dz;
        RayData {
            origin: ray.origin.into(),
            inv_dir: Vec3A::ONE / Vec3A::from_array(safe),
            to_x: Vec3A::from_array(to_x),
            to_y: Vec3A::from_array(to_y),
            to_z: Vec3A::from_array(to_z),
        }
    }

    /// Entry distance into a node's box, if the ray meets it before `t_max`.
    #[inline(always)]
    fn hit_box(&self, node: &BvhNode, t_max: f32) -> Option<f32> {
        // Plain compare-and-select maxima (one SSE instruction each), not f32::max, whose NaN
        // handling costs more than the rest of the test: the direction has no zero components
        // (see `new`), so no NaN arises here.
        #[inline(always)]
        fn max(a: f32, b: f32) -> f32 {
            if a > b {
                a
            } else {
                b
            }
        }
        #[inline(always)]
        fn min(a: f32, b: f32) -> f32 {
            if a < b {
                a
            } else {
                b
            }
        }
        let (lo, hi) = node.corners();
        let t1 = (lo - self.origin) * self.inv_dir;
        let t2 = (hi - self.origin) * self.inv_dir;
        let (near, far) = (t1.min(t2), t1.max(t2));
        let t_near = max(max(near.x, near.y), max(near.z, 0.0));
        // Robust traversal (Ize 2013): widen the far distance by 2γ(3) so rounding never makes
        // a box the ray touches look missed.
        let t_far = min(min(far.x, far.y), min(far.z, t_max)) * ROBUST_WIDENING;
        (t_near <= t_far).then_some(t_near)
    }

    /// Watertight ray–triangle test; returns (t, b1, b2) for 0 < t < t_max.
    #[inline(always)]
    fn hit_triangle(&self, v: &[Vec3A; 3], t_max: f32) -> Option<(f32, f32, f32)> {
        let a = v[0] - self.origin;
        let b = v[1] - self.origin;
        let c = v[2] - self.origin;
        let (ax, ay) = (a.dot(self.to_x), a.dot(self.to_y));
        let (bx, by) = (b.dot(self.to_x), b.dot(self.to_y));
        let (cx, cy) = (c.dot(self.to_x), c.dot(self.to_y));
        let mut u = cx * by - cy * bx;
        let mut v_ = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        if u == 0.0 || v_ == 0.0 || w == 0.0 {
            // On an edge in single precision: decide in double, as the paper prescribes.
            u = (cx as f64 * by as f64 - cy as f64 * bx as f64) as f32;
            v_ = (ax as f64 * cy as f64 - ay as f64 * cx as f64) as f32;
            w = (bx as f64 * ay as f64 - by as f64 * ax as f64) as f32;
        }
        if (u < 0.0 || v_ < 0.0 || w < 0.0) && (u > 0.0 || v_ > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v_ + w;
        if det == 0.0 {
            return None;
        }
        let (az, bz, cz) = (a.dot(self.to_z), b.dot(self.to_z), c.dot(self.to_z));
        let t_scaled = u * az + v_ * bz + w * cz;
        // t = t_scaled / det must lie in (0, t_max): compare without dividing, sign-aware.
        if det > 0.0 {
            if t_scaled <= 0.0 || t_scaled >= t_max * det {
                return None;
            }
        } else if t_scaled >= 0.0 || t_scaled <= t_max * det {
            return None;
        }
        let inv_det = 1.0 / det;
        Some((t_scaled * inv_det, v_ * inv_det, w * inv_det))
    }
}

/// A scene's triangles (world space) in BVH leaf order, with the BVH over them.
pub struct SceneAccel {
    pub bvh: Bvh,
    /// Triangle vertices in leaf order.
    pub triangles: Vec<[Vec3A; 3]>,
    /// (mesh, triangle) of each entry of `triangles`.
    pub ids: Vec<(u32, u32)>,
}

impl SceneAccel {
    pub fn new(scene: &Scene) -> Self {
        let mut triangles = Vec::with_capacity(scene.triangle_count());
        let mut ids = Vec::with_capacity(scene.triangle_count());
        for (m, mesh) in scene.meshes.iter().enumerate() {
            for (t, tri) in mesh.triangles.iter().enumerate() {
                triangles.push(tri.map(|i| mesh.positions[i as usize]));
                ids.push((m as u32, t as u32));
            }
        }
        Self::from_triangles(triangles, ids)
    }

    pub fn from_triangles(triangles: Vec<[Vec3; 3]>, ids: Vec<(u32, u32)>) -> Self {
        let bounds: Vec<Aabb> = triangles
            .iter()
            .map(|t| {
                let mut b = Aabb::EMPTY;
                t.iter().for_each(|&p| b.grow(p));
                b
            })
            .collect();
        let bvh = Bvh::build(&bounds);
        let triangles_ordered = bvh
            .primitives
            .iter()
            .map(|&p| triangles[p as usize].map(Vec3A::from))
            .collect();
        let ids_ordered = bvh.primitives.iter().map(|&p| ids[p as usize]).collect();
        SceneAccel {
            bvh,
            triangles: triangles_ordered,
            ids: ids_ordered,
        }
    }

    /// Closest hit with 0 < t < `t_max`.
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        let data = RayData::new(ray);
        let mut best: Option<(f32, f32, f32, usize)> = None;
        let mut t_best = t_max;
        self.traverse(&data, &mut t_best, |leaf_first, leaf_count, t_best| {
            for i in leaf_first..leaf_first + leaf_count {
                if let Some((t, b1, b2)) = data.hit_triangle(&self.triangles[i], *t_best) {
                    *t_best = t;
                    best = Some((t, b1, b2, i));
                }
            }
            false
        });
        best.map(|(t, b1, b2, i)| Hit {
            t,
            b1,
            b2,
            mesh: self.ids[i].0,
            triangle: self.ids[i].1,
        })
    }

    /// Whether anything lies on the ray with 0 < t < `t_max`.
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        let data = RayData::new(ray);
        let mut t = t_max;
        let mut found = false;
        self.traverse(&data, &mut t, |first, count, t_max| {
            found = (first..first + count)
                .any(|i| data.hit_triangle(&self.triangles[i], *t_max).is_some());
            found
        });
        found
    }

    /// Front-to-back traversal; `leaf` tests a leaf's triangles (and may shrink `t_max`) and
    /// returns true to stop.
    #[inline(always)]
    fn traverse(
        &self,
        data: &RayData,
        t_max: &mut f32,
        mut leaf: impl FnMut(usize, usize, &mut f32) -> bool,
    ) {
        let nodes = &self.bvh.nodes;
        if self.triangles.is_empty() || data.hit_box(&nodes[0], *t_max).is_none() {
            return;
        }
        let mut stack = [(0u32, 0.0f32); 64];
        let mut top = 0;
        let mut current = 0usize;
        loop {
            let node = &nodes[current];
            if node.is_leaf() {
                if leaf(node.first as usize, node.count as usize, t_max) {
                    return;
                }
            } else {
                let left = node.first as usize;
                let hit_left = data.hit_box(&nodes[left], *t_max);
                let hit_right = data.hit_box(&nodes[left + 1], *t_max);
                match (hit_left, hit_right) {
                    (Some(tl), Some(tr)) => {
                        let (near, far, t_far) = if tl <= tr {
                            (left, left + 1, tr)
                        } else {
                            (left + 1, left, tl)
                        };
                        stack[top] = (far as u32, t_far);
                        top += 1;
                        current = near;
                        continue;
                    }
                    (Some(_), None) => {
                        current = left;
                        continue;
                    }
                    (None, Some(_)) => {
                        current = left + 1;
                        continue;
                    }
                    (None, None) => {}
                }
            }
            // Pop the nearest pending node that can still hold a closer hit.
            loop {
                if top == 0 {
                    return;
                }
                top -= 1;
                let (node, t_entry) = stack[top];
                if t_entry <= *t_max {
                    current = node as usize;
                    break;
                }
            }
        }
    }
}
