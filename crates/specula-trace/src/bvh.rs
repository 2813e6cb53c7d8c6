//! Bounding volume hierarchy over primitives given by their boxes: a binary tree built with the
//! surface area heuristic (binned, Wald 2007, "On fast construction of SAH-based bounding volume
//! hierarchies"), stored flat in depth-first order so it can be uploaded to a GPU as is.

use bytemuck::{Pod, Zeroable};
use glam::{BVec4A, Vec3, Vec3A, Vec4};
use specula_scene::Aabb;

/// One node, 32 bytes, 16-byte aligned so each corner loads as one SIMD register. An interior
/// node (`count` = 0) has its children at `first` and `first + 1`; a leaf holds `count`
/// primitives starting at `first` in `Bvh::primitives`.
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct BvhNode {
    pub min: [f32; 3],
    pub first: u32,
    pub max: [f32; 3],
    pub count: u32,
}

impl BvhNode {
    pub fn bounds(&self) -> Aabb {
        Aabb {
            min: Vec3::from_array(self.min),
            max: Vec3::from_array(self.max),
        }
    }

    /// The box's corners as SIMD vectors, each loaded whole with its fourth lane (`first` or
    /// `count`) cleared: those integer bits would read as denormal floats, which are slow.
    #[inline(always)]
    pub fn corners(&self) -> (Vec3A, Vec3A) {
        let lanes: &[f32; 8] = bytemuck::cast_ref(self);
        let xyz = BVec4A::new(true, true, true, false);
        let corner = |i: usize| {
            Vec3A::from_vec4(Vec4::select(
                xyz,
                Vec4::from_slice(&lanes[i..i + 4]),
                Vec4::ZERO,
            ))
        };
        (corner(0), corner(4))
    }

    pub fn is_leaf(&self) -> bool {
        self.count > 0
    }
}

#[derive(Clone, Debug, Default)]
pub struct Bvh {
    pub nodes: Vec<BvhNode>,
    /// Primitive indices in leaf order.
    pub primitives: Vec<u32>,
}

const BINS: usize = 32;
const MAX_LEAF: usize = 4;
/// Deepest level a node may have (the root is level 1).
pub const MAX_DEPTH: usize = 60;
/// SAH cost of a traversal step relative to one primitive test.
const TRAVERSAL_COST: f32 = 1.0;

fn node_from(bounds: Aabb, first: u32, count: u32) -> BvhNode {
    BvhNode {
        min: bounds.min.to_array(),
        first,
        max: bounds.max.to_array(),
        count,
    }
}

impl Bvh {
    /// Builds over primitives with boxes `bounds`. Boxes must be finite (empty boxes are fine:
    /// they are never hit).
    pub fn build(bounds: &[Aabb]) -> Bvh {
        let n = bounds.len();
        let mut primitives: Vec<u32> = (0..n as u32).collect();
        if n == 0 {
            return Bvh {
                nodes: vec![node_from(Aabb::EMPTY, 0, 0)],
                primitives,
            };
        }
        let centroids: Vec<Vec3> = bounds
            .iter()
            .map(|b| if b.is_empty() { Vec3::ZERO } else { b.center() })
            .collect();
        let nodes = build_range(&mut primitives, 0, bounds, &centroids, 1);
        Bvh { nodes, primitives }
    }

    /// Recomputes every node's box bottom-up for primitives that moved (same primitives, new
    /// `bounds`); the topology is kept. Children always follow their parent in `nodes`, so one
    /// pass from the back visits every child before its parent.
    pub fn refit(&mut self, bounds: &[Aabb]) {
        for i in (0..self.nodes.len()).rev() {
            let node = self.nodes[i];
            let first = node.first as usize;
            let node_bounds = if node.is_leaf() {
                self.primitives[first..first + node.count as usize]
                    .iter()
                    .fold(Aabb::EMPTY, |b, &p| b.union(&bounds[p as usize]))
            } else if self.nodes.len() == 1 {
                Aabb::EMPTY
            } else {
                self.nodes[first]
                    .bounds()
                    .union(&self.nodes[first + 1].bounds())
            };
            self.nodes[i].min = node_bounds.min.to_array();
            self.nodes[i].max = node_bounds.max.to_array();
        }
    }

    /// The tree's surface-area-heuristic cost: the summed area of every node's box weighted by
    /// its work (a traversal step, or its primitive tests), over the summed area of the
    /// primitives' own boxes (`bounds`). That denominator does not change when primitives move
    /// rigidly, so a refitted tree's cost compares with the cost it had when it was built: it
    /// grows as boxes stretch over moved objects.
    pub fn sah_cost(&self, bounds: &[Aabb]) -> f32 {
        let area = |b: &Aabb| if b.is_empty() { 0.0 } else { b.surface_area() };
        let primitives: f32 = bounds.iter().map(area).sum();
        if primitives <= 0.0 {
            return 0.0;
        }
        self.nodes
            .iter()
            .map(|n| {
                let work = if n.is_leaf() {
                    n.count as f32
                } else {
                    TRAVERSAL_COST
                };
                area(&n.bounds()) * work
            })
            .sum::<f32>()
            / primitives
    }

    pub fn depth(&self) -> usize {
        fn depth(nodes: &[BvhNode], i: usize) -> usize {
            let n = &nodes[i];
            if n.is_leaf() || nodes.len() == 1 {
                1
            } else {
                1 + depth(nodes, n.first as usize).max(depth(nodes, n.first as usize + 1))
            }
        }
        depth(&self.nodes, 0)
    }

    /// Checks the tree's invariants: every primitive appears in exactly one leaf; children
    /// indices are in range and each node is reached once; every node's box contains its
    /// children's boxes and its primitives' boxes. Returns the first violation found.
    pub fn validate(&self, bounds: &[Aabb]) -> Result<(), String> {
        if self.nodes.is_empty() {
            return Err("no root node".into());
        }
        if self.primitives.len() != bounds.len() {
            return Err(format!(
                "{} primitive slots for {} primitives",
                self.primitives.len(),
                bounds.len()
            ));
        }
        let mut seen_prim = vec![false; bounds.len()];
        let mut seen_node = vec![false; self.nodes.len()];
        let mut stack = vec![0usize];
        let contains = |outer: &Aabb, inner: &Aabb| {
            inner.is_empty()
                || (outer.min.cmple(inner.min).all() && outer.max.cmpge(inner.max).all())
        };
        while let Some(i) = stack.pop() {
            if std::mem::replace(&mut seen_node[i], true) {
                return Err(format!("node {i} is reached twice"));
            }
            let node = &self.nodes[i];
            let node_bounds = node.bounds();
            if node.is_leaf() || (i == 0 && bounds.is_empty()) {
                let (first, count) = (node.first as usize, node.count as usize);
                if first + count > self.primitives.len() {
                    return Err(format!(
                        "leaf {i} covers primitives {first}..{} of {}",
                        first + count,
                        self.primitives.len()
                    ));
                }
                for &p in &self.primitives[first..first + count] {
                    let p = p as usize;
                    if p >= bounds.len() {
                        return Err(format!("leaf {i} holds primitive {p} of {}", bounds.len()));
                    }
                    if std::mem::replace(&mut seen_prim[p], true) {
                        return Err(format!("primitive {p} is in two leaves"));
                    }
                    if !contains(&node_bounds, &bounds[p]) {
                        return Err(format!("leaf {i}'s box does not contain primitive {p}"));
                    }
                }
            } else {
                let left = node.first as usize;
                if left == 0 || left + 1 >= self.nodes.len() {
                    return Err(format!(
                        "node {i} has children at {left} of {}",
                        self.nodes.len()
                    ));
                }
                for child in [left, left + 1] {
                    if !contains(&node_bounds, &self.nodes[child].bounds()) {
                        return Err(format!("node {i}'s box does not contain child {child}"));
                    }
                    stack.push(child);
                }
            }
        }
        if let Some(p) = seen_prim.iter().position(|s| !s) {
            return Err(format!("primitive {p} is in no leaf"));
        }
        if let Some(n) = seen_node.iter().position(|s| !s) {
            return Err(format!("node {n} is unreachable"));
        }
        Ok(())
    }
}

/// Below this many primitives a subtree is built on the calling thread; above, its two halves
/// are built in parallel.
const PARALLEL_PRIMITIVES: usize = 16_384;

/// The subtree over `prims` (the primitives `offset..` of the whole list, reordered in place),
/// its root first and every node's children after it, child and leaf indices its own (leaves'
/// primitive ranges global). Large subtrees split their root here and build the two halves in
/// parallel; the tree is the one the sequential build makes, nodes laid out differently.
fn build_range(
    prims: &mut [u32],
    offset: usize,
    bounds: &[Aabb],
    centroids: &[Vec3],
    depth: usize,
) -> Vec<BvhNode> {
    if prims.len() < PARALLEL_PRIMITIVES || depth >= MAX_DEPTH {
        return build_sequential(prims, offset, bounds, centroids, depth);
    }
    let node_bounds = prims
        .iter()
        .fold(Aabb::EMPTY, |b, &p| b.union(&bounds[p as usize]));
    let Some(mid) = split(prims, bounds, centroids, &node_bounds) else {
        return vec![node_from(node_bounds, offset as u32, prims.len() as u32)];
    };
    let (left_prims, right_prims) = prims.split_at_mut(mid);
    let (left, right) = rayon::join(
        || build_range(left_prims, offset, bounds, centroids, depth + 1),
        || build_range(right_prims, offset + mid, bounds, centroids, depth + 1),
    );
    // [root, left's root, right's root, the rest of left, the rest of right]: a subtree node
    // k ≥ 1 moves to `base + k - 1`.
    let (left_base, right_base) = (3, 3 + left.len() - 1);
    let relocate = |k: u32, base: usize, root: usize| {
        if k == 0 {
            root as u32
        } else {
            (base + k as usize - 1) as u32
        }
    };
    let mut nodes = Vec::with_capacity(1 + left.len() + right.len());
    nodes.push(BvhNode {
        first: 1,
        count: 0,
        ..node_from(node_bounds, 0, 0)
    });
    let moved = |node: &BvhNode, base: usize, root: usize| {
        if node.is_leaf() {
            *node
        } else {
            BvhNode {
                first: relocate(node.first, base, root),
                ..*node
            }
        }
    };
    nodes.push(moved(&left[0], left_base, 1));
    nodes.push(moved(&right[0], right_base, 2));
    nodes.extend(left[1..].iter().map(|n| moved(n, left_base, 1)));
    nodes.extend(right[1..].iter().map(|n| moved(n, right_base, 2)));
    nodes
}

/// [`build_range`] on the calling thread: a stack of nodes to split, each node's two children
/// appended together.
fn build_sequential(
    prims: &mut [u32],
    offset: usize,
    bounds: &[Aabb],
    centroids: &[Vec3],
    depth: usize,
) -> Vec<BvhNode> {
    let n = prims.len();
    let mut nodes = Vec::with_capacity(2 * n.max(1));
    nodes.push(node_from(Aabb::EMPTY, 0, n as u32));
    let mut stack = vec![(0usize, 0usize, n, depth)];
    while let Some((node, start, end, depth)) = stack.pop() {
        let range = &mut prims[start..end];
        let node_bounds = range
            .iter()
            .fold(Aabb::EMPTY, |b, &p| b.union(&bounds[p as usize]));
        nodes[node] = node_from(node_bounds, (offset + start) as u32, (end - start) as u32);
        // Traversal keeps a fixed 64-entry stack: past that depth, nodes stay leaves.
        if end - start <= 1 || depth >= MAX_DEPTH {
            continue;
        }
        if let Some(mid) = split(range, bounds, centroids, &node_bounds) {
            let left = nodes.len();
            nodes.push(node_from(Aabb::EMPTY, 0, 0));
            nodes.push(node_from(Aabb::EMPTY, 0, 0));
            nodes[node].first = left as u32;
            nodes[node].count = 0;
            stack.push((left + 1, start + mid, end, depth + 1));
            stack.push((left, start, start + mid, depth + 1));
        }
    }
    nodes
}

/// Binned SAH split of `prims` (reordered in place); returns the size of the left part, or
/// None when a leaf is cheaper.
fn split(
    prims: &mut [u32],
    bounds: &[Aabb],
    centroids: &[Vec3],
    node_bounds: &Aabb,
) -> Option<usize> {
    let mut centroid_bounds = Aabb::EMPTY;
    for &p in prims.iter() {
        centroid_bounds.grow(centroids[p as usize]);
    }
    let extent = centroid_bounds.extent();
    let leaf_cost = prims.len() as f32;
    let mut best: Option<(f32, usize, usize)> = None; // (cost, axis, bins on the left)
    for axis in 0..3 {
        if extent[axis] <= 0.0 {
            continue;
        }
        let scale = BINS as f32 / extent[axis];
        let bin_of = |p: u32| {
            (((centroids[p as usize][axis] - centroid_bounds.min[axis]) * scale) as usize)
                .min(BINS - 1)
        };
        let mut bin_bounds = [Aabb::EMPTY; BINS];
        let mut bin_count = [0usize; BINS];
        for &p in prims.iter() {
            let b = bin_of(p);
            bin_bounds[b] = bin_bounds[b].union(&bounds[p as usize]);
            bin_count[b] += 1;
        }
        let mut right_area = [0.0f32; BINS];
        let mut right_count = [0usize; BINS];
        let (mut acc, mut count) = (Aabb::EMPTY, 0);
        for b in (1..BINS).rev() {
            acc = acc.union(&bin_bounds[b]);
            count += bin_count[b];
            right_area[b] = if acc.is_empty() {
                0.0
            } else {
                acc.surface_area()
            };
            right_count[b] = count;
        }
        let (mut acc, mut count) = (Aabb::EMPTY, 0);
        for b in 0..BINS - 1 {
            acc = acc.union(&bin_bounds[b]);
            count += bin_count[b];
            if count == 0 || right_count[b + 1] == 0 {
                continue;
            }
            let left_area = if acc.is_empty() {
                0.0
            } else {
                acc.surface_area()
            };
            let cost = left_area * count as f32 + right_area[b + 1] * right_count[b + 1] as f32;
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, b + 1));
            }
        }
    }
    let area = node_bounds.surface_area().max(f32::MIN_POSITIVE);
    match best {
        Some((cost, axis, left_bins)) => {
            let split_cost = TRAVERSAL_COST + cost / area;
            if split_cost >= leaf_cost && prims.len() <= MAX_LEAF {
                return None;
            }
            let scale = BINS as f32 / extent[axis];
            let mut mid = 0;
            for i in 0..prims.len() {
                let c = centroids[prims[i] as usize][axis];
                let bin = (((c - centroid_bounds.min[axis]) * scale) as usize).min(BINS - 1);
                if bin < left_bins {
                    prims.swap(i, mid);
                    mid += 1;
                }
            }
            Some(mid)
        }
        // All centroids coincide: split in the middle of the list if too many for one leaf.
        None if prims.len() > MAX_LEAF => Some(prims.len() / 2),
        None => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_parallel_build_makes_the_sequential_build_s_tree() {
        // A wavy sheet of 4 × 150 × 150 boxes: large enough to split in parallel.
        let bounds: Vec<Aabb> = (0..150 * 150 * 4)
            .map(|k| {
                let (i, j) = ((k / 4) % 150, (k / 4) / 150);
                let p = Vec3::new(
                    i as f32,
                    (i as f32 * 0.3).sin() * 4.0 + (k % 4) as f32,
                    j as f32,
                );
                let mut b = Aabb::EMPTY;
                b.grow(p);
                b.grow(p + Vec3::new(0.9, 0.2, 0.7));
                b
            })
            .collect();
        assert!(bounds.len() > 2 * PARALLEL_PRIMITIVES);
        let parallel = Bvh::build(&bounds);
        parallel.validate(&bounds).unwrap();
        let mut primitives: Vec<u32> = (0..bounds.len() as u32).collect();
        let centroids: Vec<Vec3> = bounds.iter().map(|b| b.center()).collect();
        let sequential = Bvh {
            nodes: build_sequential(&mut primitives, 0, &bounds, &centroids, 1),
            primitives,
        };
        sequential.validate(&bounds).unwrap();
        // The same tree: as many nodes, the same primitive order, the same cost and depth.
        assert_eq!(parallel.nodes.len(), sequential.nodes.len());
        assert_eq!(parallel.primitives, sequential.primitives);
        assert_eq!(parallel.depth(), sequential.depth());
        let (a, b) = (parallel.sah_cost(&bounds), sequential.sah_cost(&bounds));
        assert!((a - b).abs() <= 1e-5 * b, "{a} against {b}");
    }
}
