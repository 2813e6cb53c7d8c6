//! Ray queries against a scene's triangles: closest hit and any hit (shadows), over a [`Bvh`],
//! with the watertight ray–triangle test of Woop, Benthin and Wald (JCGT 2013, "Watertight
//! Ray/Triangle Intersection"): no ray slips through a shared edge or vertex.
//!
//! Queries walk the tree collapsed to 8-wide nodes ([`WideBvh`]), nearest child first, with
//! Ize's robust slab test (one AVX pass over the eight boxes where the CPU has AVX, detected
//! at run time; two SSE passes otherwise), and test a leaf's (up to four) triangles at once
//! from a structure-of-arrays block (Embree's `Triangle4` layout). Each SIMD lane performs the
//! scalar test's operations in its order, and the hit lanes are taken in leaf order against
//! the nearest hit so far, so the hits are those of a scalar loop bit for bit: the tests hold
//! the kernel to a scalar watertight test kept for them alone (`tests::scalar_hit`), on random
//! rays over real meshes, with the AVX and the SSE traversal each.

use std::mem::MaybeUninit;

use glam::{Vec3, Vec3A, Vec4};
use specula_scene::{Aabb, Scene};

use crate::bvh::Bvh;
use crate::wide_bvh::{WideBvh, WideNode, WIDTH};

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
    /// Origin and inverse direction splatted across four lanes, one per child box.
    origin_x: Vec4,
    origin_y: Vec4,
    origin_z: Vec4,
    inv_x: Vec4,
    inv_y: Vec4,
    inv_z: Vec4,
    /// Which direction components are negative: the slab test then enters through the max
    /// planes. Choosing planes by sign (not by min/max) keeps empty, inverted boxes missed.
    negative: [bool; 3],
    /// The watertight test's axis permutation and shear (Woop et al. 2013, section 3): `kz`
    /// is the dominant axis of the direction, kx = (kz + 1) mod 3, ky = (kx + 1) mod 3, and
    /// (Sx, Sy, Sz) = (d[kx]/d[kz], d[ky]/d[kz], 1/d[kz]). The paper swaps kx and ky when
    /// d[kz] < 0 to keep the triangle's winding; specula accepts hits from both sides, and the
    /// swap only negates U, V, W and det together, so it is left out.
    kz: usize,
    shear: [f32; 3],
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
        let (kx, ky) = ((kz + 1) % 3, (kz + 2) % 3);
        // Replace zero components by a tiny signed value so the slab test sees ±inf-free data.
        let safe = d.to_array().map(|c| {
            if c.abs() < 1e-30 {
                1e-30f32.copysign(c)
            } else {
                c
            }
        });
        let inv_dir = Vec3A::ONE / Vec3A::from_array(safe);
        RayData {
            origin_x: Vec4::splat(ray.origin.x),
            origin_y: Vec4::splat(ray.origin.y),
            origin_z: Vec4::splat(ray.origin.z),
            inv_x: Vec4::splat(inv_dir.x),
            inv_y: Vec4::splat(inv_dir.y),
            inv_z: Vec4::splat(inv_dir.z),
            negative: safe.map(|c| c < 0.0),
            kz,
            shear: [d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]],
        }
    }

    /// Slab test of a wide node's eight child boxes, four at a time: a bit mask of the
    /// children the ray enters before `t_max`, and the entry distances.
    #[inline(always)]
    fn hit_children(&self, node: &WideNode, t_max: f32) -> (u32, [f32; 8]) {
        let (low, t_low) = self.hit_group(node, 0, t_max);
        let (high, t_high) = self.hit_group(node, 1, t_max);
        let mut t_near = [0.0; 8];
        t_near[..4].copy_from_slice(&t_low.to_array());
        t_near[4..].copy_from_slice(&t_high.to_array());
        (low | high << 4, t_near)
    }

    /// [`RayData::hit_children`] with 8-wide AVX instructions: the same operations in the same
    /// order on all eight boxes at once, so the same mask and distances bit for bit.
    ///
    /// # Safety
    /// The CPU must support AVX.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    #[inline]
    unsafe fn hit_children_avx(&self, node: &WideNode, t_max: f32) -> (u32, [f32; 8]) {
        use std::arch::x86_64::*;
        // Each coordinate's eight bounds are 32 contiguous, 32-byte-aligned bytes (`WideNode`
        // is aligned to 64 and each field is 32 bytes).
        let (lo, hi) = (
            [&node.min_x, &node.min_y, &node.min_z],
            [&node.max_x, &node.max_y, &node.max_z],
        );
        let origin = [self.origin_x.x, self.origin_y.x, self.origin_z.x];
        let inv = [self.inv_x.x, self.inv_y.x, self.inv_z.x];
        let mut t_near = [_mm256_setzero_ps(); 3];
        let mut t_far = [_mm256_setzero_ps(); 3];
        for axis in 0..3 {
            let (near, far) = if self.negative[axis] {
                (hi[axis], lo[axis])
            } else {
                (lo[axis], hi[axis])
            };
            let o = _mm256_set1_ps(origin[axis]);
            let i = _mm256_set1_ps(inv[axis]);
            t_near[axis] = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(near.as_ptr().cast()), o), i);
            t_far[axis] = _mm256_mul_ps(_mm256_sub_ps(_mm256_load_ps(far.as_ptr().cast()), o), i);
        }
        let entry = _mm256_max_ps(
            _mm256_max_ps(_mm256_max_ps(t_near[0], t_near[1]), t_near[2]),
            _mm256_setzero_ps(),
        );
        let exit = _mm256_mul_ps(
            _mm256_min_ps(
                _mm256_min_ps(_mm256_min_ps(t_far[0], t_far[1]), t_far[2]),
                _mm256_set1_ps(t_max),
            ),
            _mm256_set1_ps(ROBUST_WIDENING),
        );
        let mask = _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OS>(entry, exit)) as u32;
        let mut distances = [0.0f32; 8];
        _mm256_storeu_ps(distances.as_mut_ptr(), entry);
        (mask, distances)
    }

    /// Slab test of one group of four child boxes of a node.
    #[inline(always)]
    fn hit_group(&self, node: &WideNode, group: usize, t_max: f32) -> (u32, Vec4) {
        let pick = |negative: bool, lo: Vec4, hi: Vec4| if negative { (hi, lo) } else { (lo, hi) };
        let (near_x, far_x) = pick(self.negative[0], node.min_x[group], node.max_x[group]);
        let (near_y, far_y) = pick(self.negative[1], node.min_y[group], node.max_y[group]);
        let (near_z, far_z) = pick(self.negative[2], node.min_z[group], node.max_z[group]);
        let t_near = ((near_x - self.origin_x) * self.inv_x)
            .max((near_y - self.origin_y) * self.inv_y)
            .max((near_z - self.origin_z) * self.inv_z)
            .max(Vec4::ZERO);
        // Robust traversal (Ize 2013): widen the far distance by 2γ(3) so rounding never makes
        // a box the ray touches look missed.
        let t_far = ((far_x - self.origin_x) * self.inv_x)
            .min((far_y - self.origin_y) * self.inv_y)
            .min((far_z - self.origin_z) * self.inv_z)
            .min(Vec4::splat(t_max))
            * ROBUST_WIDENING;
        (t_near.cmple(t_far).bitmask(), t_near)
    }

    /// The watertight ray–triangle test on the (up to) four triangles of `block` at once, each
    /// lane with the scalar test's operations in its order, so each lane's result is the one
    /// that test gives bit for bit. Returns, where a lane hits with 0 < t < `t_max`, the lanes
    /// that do (a bit mask) and per lane the scaled distance, the determinant, t, b1 and b2.
    #[inline(always)]
    /// `KZ` is the ray's `kz` as a constant, so that the permutation compiles to fixed lanes.
    fn hit_block<const KZ: usize>(&self, block: &TriangleBlock, t_max: f32) -> Option<BlockHits> {
        // The axes (kx, ky, kz) for kx = (kz + 1) mod 3, ky = (kz + 2) mod 3.
        let (ix, iy, iz) = match KZ {
            0 => (1, 2, 0),
            1 => (2, 0, 1),
            _ => (0, 1, 2),
        };
        let origin = [self.origin_x, self.origin_y, self.origin_z];
        let relative = |vertex: usize, axis: usize| block.v[vertex][axis] - origin[axis];
        let (a_x, a_y, a_z) = (relative(0, ix), relative(0, iy), relative(0, iz));
        let (b_x, b_y, b_z) = (relative(1, ix), relative(1, iy), relative(1, iz));
        let (c_x, c_y, c_z) = (relative(2, ix), relative(2, iy), relative(2, iz));
        let [sx, sy, sz] = self.shear.map(Vec4::splat);
        let (ax, ay) = (a_x - sx * a_z, a_y - sy * a_z);
        let (bx, by) = (b_x - sx * b_z, b_y - sy * b_z);
        let (cx, cy) = (c_x - sx * c_z, c_y - sy * c_z);
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        let lanes = (1u32 << block.count) - 1;
        let on_edge =
            (u.cmpeq(Vec4::ZERO) | v.cmpeq(Vec4::ZERO) | w.cmpeq(Vec4::ZERO)).bitmask() & lanes;
        if on_edge != 0 {
            // On an edge in single precision: decide in double, as the paper prescribes.
            let [ax, ay, bx, by, cx, cy] = [ax, ay, bx, by, cx, cy].map(|x| x.to_array());
            let [mut us, mut vs, mut ws] = [u, v, w].map(|x| x.to_array());
            for lane in (0..4).filter(|lane| on_edge & (1 << lane) != 0) {
                let f = |x: [f32; 4]| x[lane] as f64;
                us[lane] = (f(cx) * f(by) - f(cy) * f(bx)) as f32;
                vs[lane] = (f(ax) * f(cy) - f(ay) * f(cx)) as f32;
                ws[lane] = (f(bx) * f(ay) - f(by) * f(ax)) as f32;
            }
            [u, v, w] = [us, vs, ws].map(Vec4::from_array);
        }
        let zero = Vec4::ZERO;
        let outside = (u.cmplt(zero) | v.cmplt(zero) | w.cmplt(zero))
            & (u.cmpgt(zero) | v.cmpgt(zero) | w.cmpgt(zero));
        let det = u + v + w;
        let (az, bz, cz) = (sz * a_z, sz * b_z, sz * c_z);
        let t_scaled = u * az + v * bz + w * cz;
        // t = t_scaled / det must lie in (0, t_max): compare without dividing, sign-aware.
        let limit = Vec4::splat(t_max) * det;
        let ahead = (det.cmpgt(zero) & t_scaled.cmpgt(zero) & t_scaled.cmplt(limit))
            | (det.cmplt(zero) & t_scaled.cmplt(zero) & t_scaled.cmpgt(limit));
        let mask = (ahead & !outside).bitmask() & lanes;
        if mask == 0 {
            // Most blocks a ray reaches it misses: no division for them.
            return None;
        }
        let inv_det = Vec4::ONE / det;
        Some(BlockHits {
            mask,
            t_scaled: t_scaled.to_array(),
            det: det.to_array(),
            t: (t_scaled * inv_det).to_array(),
            b1: (v * inv_det).to_array(),
            b2: (w * inv_det).to_array(),
        })
    }
}

/// What [`RayData::hit_block`] finds in a block, per lane.
struct BlockHits {
    mask: u32,
    t_scaled: [f32; 4],
    det: [f32; 4],
    t: [f32; 4],
    b1: [f32; 4],
    b2: [f32; 4],
}

/// The (up to four) triangles of one leaf in structure-of-arrays form, so one SIMD test checks
/// them all (the layout of Embree's `Triangle4`): `v[vertex][axis]` holds that coordinate of
/// each lane's triangle. Lanes past `count` repeat the last triangle and are masked off.
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug)]
pub struct TriangleBlock {
    v: [[Vec4; 3]; 3],
    /// The leaf's first triangle (in leaf order) and how many it has (1 to 4).
    first: u32,
    count: u32,
}

impl TriangleBlock {
    fn new(triangles: &[[Vec3A; 3]], first: u32, count: u32) -> TriangleBlock {
        assert!(
            (1..=4).contains(&count),
            "a leaf holds 1 to 4 triangles, not {count}"
        );
        let lane = |l: usize| &triangles[first as usize + l.min(count as usize - 1)];
        let v = std::array::from_fn(|vertex| {
            std::array::from_fn(|axis| {
                Vec4::from_array(std::array::from_fn(|l| lane(l)[vertex][axis]))
            })
        });
        TriangleBlock { v, first, count }
    }
}

/// One block per leaf of `wide`, in its leaves' order.
fn blocks(wide: &WideBvh, triangles: &[[Vec3A; 3]]) -> Vec<TriangleBlock> {
    wide.leaves
        .iter()
        .map(|&(first, count)| TriangleBlock::new(triangles, first, count))
        .collect()
}

/// A scene's triangles (world space) in BVH leaf order, with the BVH over them.
pub struct SceneAccel {
    /// The binary tree (the form a GPU gets).
    pub bvh: Bvh,
    /// The same tree collapsed to 8-wide nodes, which CPU queries traverse.
    pub wide: WideBvh,
    /// Triangle vertices in leaf order.
    pub triangles: Vec<[Vec3A; 3]>,
    /// The same triangles a block per leaf of `wide` (its [`WideBvh::leaves`] order): what
    /// queries test.
    blocks: Vec<TriangleBlock>,
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
        let triangles_ordered: Vec<[Vec3A; 3]> = bvh
            .primitives
            .iter()
            .map(|&p| triangles[p as usize].map(Vec3A::from))
            .collect();
        let ids_ordered = bvh.primitives.iter().map(|&p| ids[p as usize]).collect();
        let wide = WideBvh::from_binary(&bvh);
        let blocks = blocks(&wide, &triangles_ordered);
        SceneAccel {
            bvh,
            wide,
            triangles: triangles_ordered,
            blocks,
            ids: ids_ordered,
        }
    }

    /// Takes the new positions of moved meshes (same triangles, `scene` after the move) by
    /// refitting the tree's boxes; returns the refitted tree's SAH cost. The caller rebuilds
    /// (with [`SceneAccel::new`]) when that cost has grown too far past a fresh build's.
    pub fn refit(&mut self, scene: &Scene) -> f32 {
        for (triangle, &(mesh, index)) in self.triangles.iter_mut().zip(&self.ids) {
            let mesh = &scene.meshes[mesh as usize];
            *triangle =
                mesh.triangles[index as usize].map(|i| Vec3A::from(mesh.positions[i as usize]));
        }
        // `primitives` index the build's input order; the triangles are stored in leaf order,
        // so the box of input primitive `p` is that of the triangle in `p`'s leaf slot.
        let bounds = self.primitive_bounds();
        self.bvh.refit(&bounds);
        self.wide = WideBvh::from_binary(&self.bvh);
        self.blocks = blocks(&self.wide, &self.triangles);
        self.bvh.sah_cost(&bounds)
    }

    /// Each triangle's box, in the BVH build's input order (`Bvh::primitives` indexes it).
    pub fn primitive_bounds(&self) -> Vec<Aabb> {
        let mut bounds = vec![Aabb::EMPTY; self.triangles.len()];
        for (slot, &p) in self.bvh.primitives.iter().enumerate() {
            let mut b = Aabb::EMPTY;
            self.triangles[slot].iter().for_each(|&v| b.grow(v.into()));
            bounds[p as usize] = b;
        }
        bounds
    }

    /// The tree's SAH cost ([`Bvh::sah_cost`]).
    pub fn sah_cost(&self) -> f32 {
        self.bvh.sah_cost(&self.primitive_bounds())
    }

    /// Closest hit with 0 < t < `t_max`. Where the CPU has AVX the traversal is compiled for
    /// it (detected at run time; the same hits bit for bit).
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        let data = RayData::new(ray);
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx") {
            // SAFETY: the CPU supports AVX.
            return unsafe { self.intersect_avx(&data, t_max) };
        }
        self.intersect_with::<false>(&data, t_max)
    }

    /// # Safety
    /// The CPU must support AVX.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    unsafe fn intersect_avx(&self, data: &RayData, t_max: f32) -> Option<Hit> {
        self.intersect_with::<true>(data, t_max)
    }

    #[inline(always)]
    fn intersect_with<const AVX: bool>(&self, data: &RayData, t_max: f32) -> Option<Hit> {
        match data.kz {
            0 => self.intersect_kz::<0, AVX>(data, t_max),
            1 => self.intersect_kz::<1, AVX>(data, t_max),
            _ => self.intersect_kz::<2, AVX>(data, t_max),
        }
    }

    #[inline(always)]
    fn intersect_kz<const KZ: usize, const AVX: bool>(
        &self,
        data: &RayData,
        t_max: f32,
    ) -> Option<Hit> {
        let mut best: Option<(f32, f32, f32, usize)> = None;
        let mut t_best = t_max;
        self.traverse::<AVX>(data, &mut t_best, |leaf, t_best| {
            let block = &self.blocks[leaf];
            let Some(hits) = data.hit_block::<KZ>(block, *t_best) else {
                return false;
            };
            let mut mask = hits.mask;
            while mask != 0 {
                let lane = mask.trailing_zeros() as usize;
                mask &= mask - 1;
                // The triangles one by one in leaf order, each against the nearest hit so far,
                // as a scalar loop over them decides.
                let (t_scaled, det) = (hits.t_scaled[lane], hits.det[lane]);
                let closer = if det > 0.0 {
                    t_scaled < *t_best * det
                } else {
                    t_scaled > *t_best * det
                };
                if closer {
                    *t_best = hits.t[lane];
                    let i = block.first as usize + lane;
                    best = Some((hits.t[lane], hits.b1[lane], hits.b2[lane], i));
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

    /// Whether anything lies on the ray with 0 < t < `t_max` (with AVX where the CPU has it,
    /// as [`SceneAccel::intersect`]).
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        let data = RayData::new(ray);
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx") {
            // SAFETY: the CPU supports AVX.
            return unsafe { self.occluded_avx(&data, t_max) };
        }
        self.occluded_with::<false>(&data, t_max)
    }

    /// # Safety
    /// The CPU must support AVX.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx")]
    unsafe fn occluded_avx(&self, data: &RayData, t_max: f32) -> bool {
        self.occluded_with::<true>(data, t_max)
    }

    #[inline(always)]
    fn occluded_with<const AVX: bool>(&self, data: &RayData, t_max: f32) -> bool {
        match data.kz {
            0 => self.occluded_kz::<0, AVX>(data, t_max),
            1 => self.occluded_kz::<1, AVX>(data, t_max),
            _ => self.occluded_kz::<2, AVX>(data, t_max),
        }
    }

    #[inline(always)]
    fn occluded_kz<const KZ: usize, const AVX: bool>(&self, data: &RayData, t_max: f32) -> bool {
        let mut t = t_max;
        let mut found = false;
        self.traverse::<AVX>(data, &mut t, |leaf, t_max| {
            found = data.hit_block::<KZ>(&self.blocks[leaf], *t_max).is_some();
            found
        });
        found
    }

    /// Front-to-back traversal of the wide tree; `leaf` tests a leaf's triangles (its block,
    /// by number; it may shrink `t_max`) and returns true to stop.
    #[inline(always)]
    fn traverse<const AVX: bool>(
        &self,
        data: &RayData,
        t_max: &mut f32,
        mut leaf: impl FnMut(usize, &mut f32) -> bool,
    ) {
        if self.triangles.is_empty() {
            return;
        }
        // Entries are (index, count, entry distance): count 0 is a node, > 0 a leaf. Each level
        // adds at most seven entries and the tree is at most MAX_DEPTH deep.
        const STACK: usize = WIDTH * crate::bvh::MAX_DEPTH + WIDTH;
        // Left uninitialised: zeroing 3 KiB per ray costs more than a primary ray's traversal.
        let mut stack = [const { MaybeUninit::<(u32, u32, f32)>::uninit() }; STACK];
        let mut top = 0;
        let mut current = (0u32, 0u32);
        loop {
            let (index, count) = current;
            if count > 0 {
                if leaf(index as usize, t_max) {
                    return;
                }
            } else {
                let node = &self.wide.nodes[index as usize];
                #[cfg(target_arch = "x86_64")]
                let (mut mask, t_near) = if AVX {
                    // SAFETY: `AVX` is set only in functions compiled for (and entered on) AVX.
                    unsafe { data.hit_children_avx(node, *t_max) }
                } else {
                    data.hit_children(node, *t_max)
                };
                #[cfg(not(target_arch = "x86_64"))]
                let (mut mask, t_near) = data.hit_children(node, *t_max);
                if mask != 0 {
                    let first = mask.trailing_zeros() as usize;
                    mask &= mask - 1;
                    if mask == 0 {
                        // One child hit, the common case: descend without touching the stack.
                        current = (node.index[first], node.count[first]);
                        continue;
                    }
                    // Several: keep them sorted by entry distance, farthest first, then
                    // descend into the nearest and push the rest.
                    let t = t_near;
                    let mut hits = [(0u32, 0u32, 0.0f32); WIDTH];
                    hits[0] = (node.index[first], node.count[first], t[first]);
                    let mut n = 1;
                    while mask != 0 {
                        let slot = mask.trailing_zeros() as usize;
                        mask &= mask - 1;
                        let entry = (node.index[slot], node.count[slot], t[slot]);
                        let mut i = n;
                        while i > 0 && hits[i - 1].2 < entry.2 {
                            hits[i] = hits[i - 1];
                            i -= 1;
                        }
                        hits[i] = entry;
                        n += 1;
                    }
                    for &hit in &hits[..n - 1] {
                        stack[top].write(hit);
                        top += 1;
                    }
                    current = (hits[n - 1].0, hits[n - 1].1);
                    continue;
                }
            }
            // Pop the nearest pending entry that can still hold a closer hit.
            loop {
                if top == 0 {
                    return;
                }
                top -= 1;
                // SAFETY: every entry below `top` was written before `top` moved past it.
                let (index, count, t_entry) = unsafe { stack[top].assume_init() };
                if t_entry <= *t_max {
                    current = (index, count);
                    break;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The oracle: the watertight ray–triangle test of Woop, Benthin and Wald (JCGT 2013,
    /// "Watertight Ray/Triangle Intersection", section 3 and its double-precision fallback on
    /// edges) on one triangle, written as a plain scalar function. Returns (t_scaled, det, t,
    /// b1, b2) where the ray meets the triangle with 0 < t < `t_max`.
    fn scalar_hit(data: &RayData, triangle: &[Vec3A; 3], t_max: f32) -> Option<[f32; 5]> {
        let kz = data.kz;
        let (kx, ky) = ((kz + 1) % 3, (kz + 2) % 3);
        let origin = [data.origin_x.x, data.origin_y.x, data.origin_z.x];
        let [sx, sy, sz] = data.shear;
        // Vertices relative to the origin, permuted and sheared.
        let relative = |p: Vec3A| [p[kx] - origin[kx], p[ky] - origin[ky], p[kz] - origin[kz]];
        let [a, b, c] = triangle.map(relative);
        let (ax, ay) = (a[0] - sx * a[2], a[1] - sy * a[2]);
        let (bx, by) = (b[0] - sx * b[2], b[1] - sy * b[2]);
        let (cx, cy) = (c[0] - sx * c[2], c[1] - sy * c[2]);
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        if u == 0.0 || v == 0.0 || w == 0.0 {
            let f = |x: f32| x as f64;
            u = (f(cx) * f(by) - f(cy) * f(bx)) as f32;
            v = (f(ax) * f(cy) - f(ay) * f(cx)) as f32;
            w = (f(bx) * f(ay) - f(by) * f(ax)) as f32;
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        let t_scaled = u * (sz * a[2]) + v * (sz * b[2]) + w * (sz * c[2]);
        let limit = t_max * det;
        let ahead = (det > 0.0 && t_scaled > 0.0 && t_scaled < limit)
            || (det < 0.0 && t_scaled < 0.0 && t_scaled > limit);
        if !ahead {
            return None;
        }
        let inv_det = 1.0 / det;
        Some([t_scaled, det, t_scaled * inv_det, v * inv_det, w * inv_det])
    }

    /// Closest hit by the oracle, each leaf's triangles one by one in leaf order against the
    /// nearest hit so far, over the traversal the kernel uses.
    fn scalar_closest(accel: &SceneAccel, data: &RayData, t_max: f32) -> Option<Hit> {
        let mut best = None;
        let mut t_best = t_max;
        accel.traverse::<false>(data, &mut t_best, |leaf, t_best| {
            let (first, count) = accel.wide.leaves[leaf];
            for i in first as usize..(first + count) as usize {
                if let Some([_, _, t, b1, b2]) = scalar_hit(data, &accel.triangles[i], *t_best) {
                    *t_best = t;
                    best = Some(Hit {
                        t,
                        b1,
                        b2,
                        mesh: accel.ids[i].0,
                        triangle: accel.ids[i].1,
                    });
                }
            }
            false
        });
        best
    }

    /// Closest hit by the oracle over every triangle, no tree: t only (equal distances on a
    /// shared edge may be taken from either triangle, in another order).
    fn brute_force_t(accel: &SceneAccel, data: &RayData) -> Option<f32> {
        let mut t_best = f32::INFINITY;
        let mut found = None;
        for triangle in &accel.triangles {
            if let Some([_, _, t, _, _]) = scalar_hit(data, triangle, t_best) {
                t_best = t;
                found = Some(t);
            }
        }
        found
    }

    fn bits(h: Option<Hit>) -> Option<(u32, u32, u32, u32, u32)> {
        h.map(|h| {
            (
                h.t.to_bits(),
                h.b1.to_bits(),
                h.b2.to_bits(),
                h.mesh,
                h.triangle,
            )
        })
    }

    /// A small xorshift generator: the same rays on every machine.
    struct Rng(u64);

    impl Rng {
        fn unit(&mut self) -> f32 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            (self.0 >> 40) as f32 / (1u64 << 24) as f32
        }

        fn in_box(&mut self, lo: Vec3, hi: Vec3) -> Vec3 {
            lo + (hi - lo) * Vec3::new(self.unit(), self.unit(), self.unit())
        }
    }

    /// `n` random rays at a mesh: three in four from a box around it twice its size, aimed at
    /// random points of its bounding box (most hit it, many graze it); one in four from inside
    /// its box in a random direction (rays that start among the triangles).
    fn random_rays(accel: &SceneAccel, n: usize, seed: u64) -> Vec<Ray> {
        let mut bounds = Aabb::EMPTY;
        accel
            .triangles
            .iter()
            .flatten()
            .for_each(|p| bounds.grow(Vec3::from(*p)));
        let (lo, hi) = (bounds.min, bounds.max);
        let (center, half) = ((lo + hi) * 0.5, (hi - lo) * 0.5);
        let mut rng = Rng(seed);
        (0..n)
            .map(|k| {
                let (origin, target) = if k % 4 == 3 {
                    let origin = rng.in_box(lo, hi);
                    (origin, origin + rng.in_box(-Vec3::ONE, Vec3::ONE))
                } else {
                    (
                        rng.in_box(center - 2.0 * half, center + 2.0 * half),
                        rng.in_box(lo, hi),
                    )
                };
                Ray {
                    origin,
                    dir: (target - origin).normalize_or(Vec3::Z),
                }
            })
            .collect()
    }

    fn mesh_accel(file: &str) -> SceneAccel {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../scenes/meshes")
            .join(file);
        let scene = specula_scene::load(path.to_str().unwrap()).unwrap();
        SceneAccel::new(&scene)
    }

    /// The meshes the kernel is held to the oracle on (scenes/meshes: copies of the shared
    /// Stanford bunny, dragon, Utah teapot and Suzanne, with their provenance there).
    const MESHES: [&str; 4] = [
        "bunny.obj",
        "dragon_res4.obj",
        "teapot.obj",
        "suzanne_assimp.obj",
    ];
    const RAYS_PER_MESH: usize = 100_000;

    /// The SIMD kernel (the SSE traversal, and the AVX one where this CPU has it) finds the
    /// oracle's hits bit for bit, closest and any, on 10^5 random rays per mesh; and the
    /// closest distance is the one a loop over every triangle finds, on a tenth of them.
    #[test]
    fn the_simd_kernel_finds_the_scalar_oracles_hits_bit_for_bit() {
        #[cfg(target_arch = "x86_64")]
        let avx = std::arch::is_x86_feature_detected!("avx");
        #[cfg(not(target_arch = "x86_64"))]
        let avx = false;
        if !avx {
            specula_testkit::missing(
                specula_testkit::Requirement::Avx,
                "SIMD kernel against the scalar oracle, AVX traversal",
                "this CPU has no AVX: only the SSE traversal is compared",
            );
        }
        for (m, file) in MESHES.iter().enumerate() {
            let accel = mesh_accel(file);
            let rays = random_rays(&accel, RAYS_PER_MESH, 0x9e37_79b9_7f4a_7c15 + m as u64);
            let (mut hits, mut brute_checked) = (0, 0);
            for (k, ray) in rays.iter().enumerate() {
                let data = RayData::new(ray);
                let oracle = scalar_closest(&accel, &data, f32::INFINITY);
                hits += oracle.is_some() as usize;
                let sse = accel.intersect_with::<false>(&data, f32::INFINITY);
                assert_eq!(bits(sse), bits(oracle), "{file}, SSE: {ray:?}");
                // Any hit before the oracle's closest one, a little past it and a little short.
                let t_any = oracle.map_or(10.0, |h| h.t * 1.001);
                let t_short = oracle.map_or(10.0, |h| h.t * 0.999);
                for t_max in [t_any, t_short] {
                    let expected = scalar_closest(&accel, &data, t_max).is_some();
                    assert_eq!(
                        accel.occluded_with::<false>(&data, t_max),
                        expected,
                        "{file}: {ray:?}"
                    );
                    #[cfg(target_arch = "x86_64")]
                    if avx {
                        // SAFETY: the CPU supports AVX.
                        assert_eq!(unsafe { accel.occluded_avx(&data, t_max) }, expected);
                    }
                }
                #[cfg(target_arch = "x86_64")]
                if avx {
                    // SAFETY: the CPU supports AVX.
                    let avx_hit = unsafe { accel.intersect_avx(&data, f32::INFINITY) };
                    assert_eq!(bits(avx_hit), bits(oracle), "{file}, AVX: {ray:?}");
                }
                assert_eq!(bits(accel.intersect(ray, f32::INFINITY)), bits(oracle));
                if k % 10 == 0 {
                    brute_checked += 1;
                    let brute = brute_force_t(&accel, &data);
                    assert_eq!(
                        brute.map(f32::to_bits),
                        oracle.map(|h| h.t.to_bits()),
                        "{file}, every triangle: {ray:?}"
                    );
                }
            }
            eprintln!(
                "{file}: {} triangles, {RAYS_PER_MESH} rays, {hits} hits, bit for bit with the oracle (SSE{}); {brute_checked} against every triangle",
                accel.triangles.len(),
                if avx { " and AVX" } else { "" }
            );
            assert!(
                hits > RAYS_PER_MESH / 4,
                "{file}: the rays must hit the mesh ({hits})"
            );
        }
    }

    /// The oracle is the watertight test: a ray through a shared edge or vertex of a fan of
    /// triangles hits one of them (none slips through), and a ray beside the fan misses.
    #[test]
    fn the_oracle_is_watertight_on_shared_edges_and_vertices() {
        let centre = Vec3A::new(0.0, 0.0, 0.0);
        let fan: Vec<[Vec3A; 3]> = (0..6)
            .map(|k| {
                let corner = |k: i32| {
                    let a = k as f32 * std::f32::consts::TAU / 6.0;
                    Vec3A::new(a.cos(), a.sin(), 0.0)
                };
                [centre, corner(k), corner(k + 1)]
            })
            .collect();
        let through = |p: Vec3| {
            let ray = Ray {
                origin: p + Vec3::new(0.3, -0.2, 2.0),
                dir: (-Vec3::new(0.3, -0.2, 2.0)).normalize(),
            };
            let data = RayData::new(&ray);
            fan.iter()
                .filter(|t| scalar_hit(&data, t, f32::INFINITY).is_some())
                .count()
        };
        // The centre vertex and the points along each shared edge.
        assert!(through(Vec3::ZERO) >= 1);
        for k in 0..6 {
            let a = k as f32 * std::f32::consts::TAU / 6.0;
            for s in [0.1, 0.37, 0.5, 0.93] {
                assert!(
                    through(Vec3::new(a.cos(), a.sin(), 0.0) * s) >= 1,
                    "edge {k} at {s}"
                );
            }
        }
        assert_eq!(through(Vec3::new(2.0, 0.0, 0.0)), 0);
    }
}
