//! Pre-processing of c3rc (Mei, Popescu and Sacks 2007, §3.1 and §4): the diffuse geometry
//! near a reflector sampled uniformly by area into points, each with its shaded colour, and an
//! eight-way kd-tree over each object's points.
//!
//! Points and trees are kept in the object's loaded pose ("object space" here: the mesh as the
//! scene was loaded, before any move), so a rigid move keeps them; culling maps each camera
//! into that space. Colours depend on where the object and the lights are, so they are shaded
//! again after a move (the tree is not rebuilt).

use std::time::Instant;

use glam::{Mat4, Vec2, Vec3};
use rayon::prelude::*;
use specula_scene::{MaterialKind, Mesh, Scene};
use specula_trace::reference::{SurfacePoint, Tracer};
use specula_trace::SceneAccel;

/// Limits of the tree's recursion.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TreeLimits {
    /// A node with at most this many points is a leaf.
    pub leaf_points: usize,
    /// Nodes at this depth are leaves whatever they hold.
    pub max_depth: u32,
}

/// A node of the eight-way tree: its points' tight box, and either its children (a run of
/// `child_count` nodes from `first`) or, for a leaf, its points (a run from `first`).
#[derive(Clone, Copy, Debug)]
pub struct Node {
    pub lo: Vec3,
    pub hi: Vec3,
    /// Every point's normal n has n · normal_axis ≥ normal_cos (−1: any direction).
    pub normal_axis: Vec3,
    pub normal_cos: f32,
    pub first: u32,
    pub count: u32,
    pub leaf: bool,
    /// The run of points under this node (every node's are contiguous), leaf or not.
    pub point_first: u32,
    pub point_count: u32,
}

/// The points of one object, in its loaded pose, ordered so that each leaf's are contiguous.
pub struct PointCloud {
    pub mesh: usize,
    pub p_object: Vec<Vec3>,
    pub n_object: Vec<Vec3>,
    uv: Vec<Vec2>,
    /// The mesh triangle each point lies on.
    pub triangle: Vec<u32>,
    /// Radiance each point leaves towards the side its normal faces.
    pub color: Vec<Vec3>,
    /// What the surface's albedo is multiplied by there (`color` = albedo × `light`): the
    /// light a point carries to a pixel whose albedo is looked up where its ray meets the
    /// surface (`exact_hits`).
    pub light: Vec<Vec3>,
    /// Splat radius in metres: the disc one point stands for, times the splat scale.
    pub radius: f32,
    pub nodes: Vec<Node>,
    pub stats: TreeStats,
    /// The triangles around each vertex of the mesh (for `exact_hits`: a ray that misses a
    /// point's triangle is tried on its neighbours).
    pub one_ring: OneRing,
}

/// The triangles sharing each vertex of a mesh, packed: vertex v's are
/// `triangles[offsets[v]..offsets[v + 1]]`.
#[derive(Clone, Debug, Default)]
pub struct OneRing {
    offsets: Vec<u32>,
    triangles: Vec<u32>,
}

impl OneRing {
    pub fn new(mesh: &Mesh) -> OneRing {
        let mut offsets = vec![0u32; mesh.positions.len() + 1];
        for tri in &mesh.triangles {
            for &v in tri {
                offsets[v as usize + 1] += 1;
            }
        }
        for v in 0..mesh.positions.len() {
            offsets[v + 1] += offsets[v];
        }
        let mut filled = offsets.clone();
        let mut triangles = vec![0u32; mesh.triangles.len() * 3];
        for (t, tri) in mesh.triangles.iter().enumerate() {
            for &v in tri {
                triangles[filled[v as usize] as usize] = t as u32;
                filled[v as usize] += 1;
            }
        }
        OneRing { offsets, triangles }
    }

    /// The triangles sharing vertex `v`.
    pub fn around(&self, v: u32) -> &[u32] {
        let v = v as usize;
        &self.triangles[self.offsets[v] as usize..self.offsets[v + 1] as usize]
    }
}

/// Table 1 of the paper, for one tree.
#[derive(Clone, Copy, Debug, Default)]
pub struct TreeStats {
    pub build_ms: f64,
    pub leaves: usize,
    /// Mean depth of the leaves (the root is depth 0).
    pub average_depth: f64,
    pub points_per_leaf: f64,
}

/// A small, fast, deterministic hash for sampling (the same scene gives the same points).
fn hash(mut x: u64) -> u64 {
    x ^= x >> 33;
    x = x.wrapping_mul(0xff51afd7ed558ccd);
    x ^= x >> 33;
    x = x.wrapping_mul(0xc4ceb9fe1a85ec53);
    x ^ (x >> 33)
}

fn unit(x: u64) -> f32 {
    (hash(x) >> 40) as f32 / (1u64 << 24) as f32
}

/// Total surface area of a mesh.
pub fn area(mesh: &Mesh) -> f32 {
    (0..mesh.triangles.len())
        .map(|t| mesh.face_normal_scaled(t).length() * 0.5)
        .sum()
}

impl Node {
    /// Indices of the points under this node.
    pub fn points(&self) -> std::ops::Range<usize> {
        self.point_first as usize..(self.point_first + self.point_count) as usize
    }

    /// False only when every point of the node faces away from every point of the sphere
    /// (`center`, `radius`): all normals n and directions u from a point to the sphere have
    /// n · u ≤ 0 when the angle between the normal axis and the direction from the node to
    /// the sphere exceeds 90° plus the normal cone's and the direction cone's half-angles.
    pub fn may_face(&self, center: Vec3, radius: f32) -> bool {
        if self.normal_cos <= 0.0 {
            return true;
        }
        let box_center = (self.lo + self.hi) * 0.5;
        let to = center - box_center;
        let distance = to.length();
        let spread = radius + (self.hi - self.lo).length() * 0.5;
        if distance <= spread {
            return true;
        }
        // Angles: β of the normal cone, α of the directions, θ between axis and `to`; the
        // node may face the sphere when θ ≤ 90° + α + β, i.e. cos θ ≥ −sin(α + β) (always
        // when α + β ≥ 90°). Without trigonometric calls.
        let (cos_beta, sin_alpha) = (self.normal_cos, spread / distance);
        let sin_beta = (1.0 - cos_beta * cos_beta).max(0.0).sqrt();
        let cos_alpha = (1.0 - sin_alpha * sin_alpha).max(0.0).sqrt();
        if cos_alpha * cos_beta - sin_alpha * sin_beta <= 0.0 {
            return true;
        }
        let cos_theta = self.normal_axis.dot(to) / distance;
        cos_theta >= -(sin_alpha * cos_beta + cos_alpha * sin_beta) - 1e-4
    }
}

impl PointCloud {
    /// Samples `mesh` (in its pose now, taken as its loaded pose after
    /// `world_from_loaded⁻¹`) at `density` points per square metre: each triangle gets
    /// `area × density` points, the fraction rounded by a random draw, placed uniformly.
    pub fn sample(
        mesh_index: usize,
        mesh: &Mesh,
        loaded_from_world: Mat4,
        density: f32,
        splat_scale: f32,
        limits: TreeLimits,
    ) -> PointCloud {
        let mut p_object = Vec::new();
        let mut n_object = Vec::new();
        let mut uv = Vec::new();
        let mut triangle = Vec::new();
        for (t, tri) in mesh.triangles.iter().enumerate() {
            let [i0, i1, i2] = tri.map(|i| i as usize);
            let (a, b, c) = (mesh.positions[i0], mesh.positions[i1], mesh.positions[i2]);
            let face = (b - a).cross(c - a);
            let expected = face.length() * 0.5 * density;
            let seed = (mesh_index as u64) << 40 ^ (t as u64) << 8;
            let count = expected.floor() as u64 + u64::from(unit(seed) < expected.fract());
            for k in 0..count {
                let (r1, r2) = (unit(seed + 2 * k + 1).sqrt(), unit(seed + 2 * k + 2));
                let (w0, w1, w2) = (1.0 - r1, r1 * (1.0 - r2), r1 * r2);
                let p = a * w0 + b * w1 + c * w2;
                let n = (mesh.normals[i0] * w0 + mesh.normals[i1] * w1 + mesh.normals[i2] * w2)
                    .try_normalize()
                    .or_else(|| face.try_normalize())
                    .unwrap_or(Vec3::Y);
                triangle.push(t as u32);
                p_object.push(loaded_from_world.transform_point3(p));
                n_object.push(loaded_from_world.transform_vector3(n));
                uv.push(if mesh.uvs.is_empty() {
                    Vec2::ZERO
                } else {
                    mesh.uvs[i0] * w0 + mesh.uvs[i1] * w1 + mesh.uvs[i2] * w2
                });
            }
        }
        let radius = splat_scale / (std::f32::consts::PI * density.max(1e-12)).sqrt();
        let mut cloud = PointCloud {
            mesh: mesh_index,
            color: vec![Vec3::ZERO; p_object.len()],
            light: vec![Vec3::ZERO; p_object.len()],
            triangle,
            p_object,
            n_object,
            uv,
            radius,
            nodes: Vec::new(),
            stats: TreeStats::default(),
            one_ring: OneRing::new(mesh),
        };
        cloud.build_tree(limits);
        cloud
    }

    pub fn len(&self) -> usize {
        self.p_object.len()
    }

    pub fn is_empty(&self) -> bool {
        self.p_object.is_empty()
    }

    /// Builds the eight-way tree (§4): a node splits at the centre of its points' box on all
    /// three axes at once into up to eight children (empty ones dropped) until it holds at most
    /// `leaf_points` points or reaches `max_depth`. Reorders the points leaf by leaf.
    pub fn build_tree(&mut self, limits: TreeLimits) {
        let start = Instant::now();
        let mut order: Vec<u32> = (0..self.len() as u32).collect();
        let mut nodes = vec![Node {
            lo: Vec3::ZERO,
            hi: Vec3::ZERO,
            normal_axis: Vec3::ZERO,
            normal_cos: -1.0,
            first: 0,
            count: 0,
            leaf: true,
            point_first: 0,
            point_count: 0,
        }];
        let mut depth_sum = 0u64;
        let mut leaves = 0usize;
        // (node index, range start, range end, depth)
        let mut stack = vec![(0usize, 0usize, order.len(), 0u32)];
        while let Some((node, begin, end, depth)) = stack.pop() {
            let points = &self.p_object;
            let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
            for &i in &order[begin..end] {
                lo = lo.min(points[i as usize]);
                hi = hi.max(points[i as usize]);
            }
            nodes[node].lo = lo;
            nodes[node].hi = hi;
            nodes[node].point_first = begin as u32;
            nodes[node].point_count = (end - begin) as u32;
            // The cone of the normals: their mean direction and the widest angle from it.
            let normals = &self.n_object;
            let axis = order[begin..end]
                .iter()
                .map(|&i| normals[i as usize])
                .sum::<Vec3>()
                .normalize_or_zero();
            nodes[node].normal_axis = axis;
            nodes[node].normal_cos = if axis == Vec3::ZERO {
                -1.0
            } else {
                order[begin..end]
                    .iter()
                    .map(|&i| normals[i as usize].dot(axis))
                    .fold(1.0, f32::min)
            };
            let n = end - begin;
            let mid = (lo + hi) * 0.5;
            let split = n > limits.leaf_points && depth < limits.max_depth && lo != hi;
            if !split {
                nodes[node].first = begin as u32;
                nodes[node].count = n as u32;
                nodes[node].leaf = true;
                leaves += 1;
                depth_sum += depth as u64;
                continue;
            }
            let octant = |i: u32| {
                let p = points[i as usize];
                (p.x > mid.x) as usize
                    | ((p.y > mid.y) as usize) << 1
                    | ((p.z > mid.z) as usize) << 2
            };
            let slice = &mut order[begin..end];
            slice.sort_unstable_by_key(|&i| octant(i));
            let mut counts = [0usize; 8];
            for &i in slice.iter() {
                counts[octant(i)] += 1;
            }
            let first_child = nodes.len();
            let mut at = begin;
            for count in counts.into_iter().filter(|&c| c > 0) {
                stack.push((nodes.len(), at, at + count, depth + 1));
                nodes.push(Node {
                    lo,
                    hi,
                    normal_axis: Vec3::ZERO,
                    normal_cos: -1.0,
                    first: 0,
                    count: 0,
                    leaf: true,
                    point_first: 0,
                    point_count: 0,
                });
                at += count;
            }
            nodes[node].first = first_child as u32;
            nodes[node].count = (nodes.len() - first_child) as u32;
            nodes[node].leaf = false;
        }
        let permute = |v: &mut Vec<Vec3>| *v = order.iter().map(|&i| v[i as usize]).collect();
        permute(&mut self.p_object);
        permute(&mut self.n_object);
        permute(&mut self.color);
        permute(&mut self.light);
        self.triangle = order.iter().map(|&i| self.triangle[i as usize]).collect();
        self.uv = order.iter().map(|&i| self.uv[i as usize]).collect();
        self.nodes = nodes;
        self.stats = TreeStats {
            build_ms: start.elapsed().as_secs_f64() * 1e3,
            leaves,
            average_depth: depth_sum as f64 / leaves.max(1) as f64,
            points_per_leaf: self.len() as f64 / leaves.max(1) as f64,
        };
    }

    /// Shades every point as the reference shades a hit on its material (unlit: its colour;
    /// Lambertian: lights with shadow rays, ambient), with the object at `world_from_loaded`;
    /// in parallel.
    pub fn shade(&mut self, scene: &Scene, accel: &SceneAccel, world_from_loaded: Mat4) {
        let material = &scene.materials[scene.meshes[self.mesh].material];
        let tracer = Tracer {
            scene,
            accel,
            max_depth: 1,
        };
        let (p, n, uv) = (&self.p_object, &self.n_object, &self.uv);
        self.color
            .par_iter_mut()
            .zip(&mut self.light)
            .enumerate()
            .for_each(|(i, (color, light))| {
                let ns = world_from_loaded.transform_vector3(n[i]).normalize();
                let sp = SurfacePoint {
                    p: world_from_loaded.transform_point3(p[i]),
                    ng: ns,
                    ns,
                    uv: uv[i],
                    backface: false,
                    material: scene.meshes[self.mesh].material,
                };
                let texture = material
                    .texture
                    .map(|t| scene.textures[t].sample(uv[i]))
                    .unwrap_or(Vec3::ONE);
                // The reference's Lambertian shading is albedo × a light term: shaded with a
                // unit albedo it gives that term.
                *light = match material.kind {
                    MaterialKind::Unlit => Vec3::ONE,
                    _ => tracer.diffuse(&sp, Vec3::ONE),
                };
                *color = material.color * texture * *light;
            });
    }

    /// Checks the tree's invariants: every point lies in its leaf's box, children lie in
    /// their parent's box, and every point is in exactly one leaf.
    pub fn validate(&self) -> Result<(), String> {
        let mut seen = vec![false; self.len()];
        for (k, node) in self.nodes.iter().enumerate() {
            let range = node.first as usize..(node.first + node.count) as usize;
            if node.leaf {
                for i in range {
                    let p = self.p_object[i];
                    if p.cmplt(node.lo).any() || p.cmpgt(node.hi).any() {
                        return Err(format!("point {i} outside leaf {k}'s box"));
                    }
                    if std::mem::replace(&mut seen[i], true) {
                        return Err(format!("point {i} in two leaves"));
                    }
                }
            } else {
                for c in range {
                    let child = &self.nodes[c];
                    if child.lo.cmplt(node.lo).any() || child.hi.cmpgt(node.hi).any() {
                        return Err(format!("node {c} outside its parent {k}"));
                    }
                }
            }
        }
        match seen.iter().position(|s| !s) {
            Some(i) => Err(format!("point {i} in no leaf")),
            None => Ok(()),
        }
    }
}
