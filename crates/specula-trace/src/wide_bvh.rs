//! A 4-wide BVH collapsed from the binary [`Bvh`], for CPU traversal: each node stores its four
//! children's boxes in structure-of-arrays form so one SIMD slab test checks all four (the
//! layout of Wald et al. 2008, "Getting rid of packets", and of Embree's BVH4). The binary tree
//! stays the canonical one (it is what a GPU gets); this one is derived from it.

use glam::{Vec3A, Vec4};
use specula_scene::Aabb;

use crate::bvh::Bvh;

/// A child slot: an interior node (`count` = 0, `index` = node), a leaf (`count` > 0
/// primitives; `index` = its entry in [`WideBvh::leaves`]), or empty (`count` = 0, `index` =
/// `EMPTY`; its box is inverted so no ray ever enters it).
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug)]
pub struct WideNode {
    pub min_x: Vec4,
    pub min_y: Vec4,
    pub min_z: Vec4,
    pub max_x: Vec4,
    pub max_y: Vec4,
    pub max_z: Vec4,
    pub index: [u32; 4],
    pub count: [u32; 4],
}

pub const EMPTY: u32 = u32::MAX;

impl WideNode {
    fn empty() -> Self {
        WideNode {
            min_x: Vec4::INFINITY,
            min_y: Vec4::INFINITY,
            min_z: Vec4::INFINITY,
            max_x: Vec4::NEG_INFINITY,
            max_y: Vec4::NEG_INFINITY,
            max_z: Vec4::NEG_INFINITY,
            index: [EMPTY; 4],
            count: [0; 4],
        }
    }

    fn set_box(&mut self, slot: usize, b: &Aabb) {
        self.min_x[slot] = b.min.x;
        self.min_y[slot] = b.min.y;
        self.min_z[slot] = b.min.z;
        self.max_x[slot] = b.max.x;
        self.max_y[slot] = b.max.y;
        self.max_z[slot] = b.max.z;
    }

    pub fn child_box(&self, slot: usize) -> Aabb {
        Aabb {
            min: Vec3A::new(self.min_x[slot], self.min_y[slot], self.min_z[slot]).into(),
            max: Vec3A::new(self.max_x[slot], self.max_y[slot], self.max_z[slot]).into(),
        }
    }
}

#[derive(Clone, Debug, Default)]
pub struct WideBvh {
    /// Node 0 is the root.
    pub nodes: Vec<WideNode>,
    /// Each leaf's primitives: (first, count) in leaf order, numbered in depth-first order so
    /// that per-leaf data kept beside it (the accelerator's triangle blocks) lies in the order
    /// traversal meets it.
    pub leaves: Vec<(u32, u32)>,
}

impl WideBvh {
    pub fn from_binary(bvh: &Bvh) -> WideBvh {
        let mut wide = WideBvh {
            nodes: vec![WideNode::empty()],
            leaves: Vec::new(),
        };
        let root = &bvh.nodes[0];
        if bvh.primitives.is_empty() {
            return wide;
        }
        if root.is_leaf() {
            wide.nodes[0].set_box(0, &root.bounds());
            wide.nodes[0].index[0] = 0;
            wide.nodes[0].count[0] = root.count;
            wide.leaves.push((root.first, root.count));
        } else {
            wide.fill(bvh, 0, 0);
        }
        wide
    }

    /// Fills wide node `target` with the (up to four) descendants of binary node `source`
    /// obtained by repeatedly opening the interior child with the largest surface area.
    fn fill(&mut self, bvh: &Bvh, source: usize, target: usize) {
        let first = bvh.nodes[source].first as usize;
        let mut children = vec![first, first + 1];
        while children.len() < 4 {
            let widest = children
                .iter()
                .enumerate()
                .filter(|(_, &c)| !bvh.nodes[c].is_leaf())
                .max_by(|a, b| {
                    bvh.nodes[*a.1]
                        .bounds()
                        .surface_area()
                        .total_cmp(&bvh.nodes[*b.1].bounds().surface_area())
                });
            let Some((slot, &node)) = widest else { break };
            let grandchild = bvh.nodes[node].first as usize;
            children[slot] = grandchild;
            children.push(grandchild + 1);
        }
        for (slot, &child) in children.iter().enumerate() {
            let node = bvh.nodes[child];
            self.nodes[target].set_box(slot, &node.bounds());
            if node.is_leaf() {
                self.nodes[target].index[slot] = self.leaves.len() as u32;
                self.nodes[target].count[slot] = node.count;
                self.leaves.push((node.first, node.count));
            } else {
                let index = self.nodes.len();
                self.nodes.push(WideNode::empty());
                self.nodes[target].index[slot] = index as u32;
                self.fill(bvh, child, index);
            }
        }
    }

    /// Checks that every primitive slot in `0..primitive_count` is covered by exactly one leaf,
    /// that every node and every leaf entry is reached exactly once, and that each child box
    /// contains the boxes below it and (via `bounds`, indexed in leaf order) its primitives.
    pub fn validate(&self, bounds_in_leaf_order: &[Aabb]) -> Result<(), String> {
        let mut covered = vec![false; bounds_in_leaf_order.len()];
        let mut reached = vec![false; self.nodes.len()];
        let mut leaves_reached = vec![false; self.leaves.len()];
        let contains = |outer: &Aabb, inner: &Aabb| {
            inner.is_empty()
                || (outer.min.cmple(inner.min).all() && outer.max.cmpge(inner.max).all())
        };
        let mut stack = vec![0usize];
        while let Some(n) = stack.pop() {
            if std::mem::replace(
                reached.get_mut(n).ok_or(format!("node {n} out of range"))?,
                true,
            ) {
                return Err(format!("node {n} reached twice"));
            }
            let node = &self.nodes[n];
            for slot in 0..4 {
                let (index, count) = (node.index[slot], node.count[slot] as usize);
                let b = node.child_box(slot);
                if index == EMPTY {
                    if !b.is_empty() {
                        return Err(format!("node {n} slot {slot} is empty but has a box"));
                    }
                } else if count > 0 {
                    let Some(&(first, leaf_count)) = self.leaves.get(index as usize) else {
                        return Err(format!("node {n} slot {slot} points to missing leaf {index}"));
                    };
                    if leaf_count as usize != count {
                        return Err(format!(
                            "node {n} slot {slot} counts {count} primitives, its leaf {leaf_count}"
                        ));
                    }
                    if std::mem::replace(&mut leaves_reached[index as usize], true) {
                        return Err(format!("leaf {index} reached twice"));
                    }
                    let first = first as usize;
                    if first + count > covered.len() {
                        return Err(format!(
                            "node {n} slot {slot} covers primitives past the end"
                        ));
                    }
                    for p in first..first + count {
                        if std::mem::replace(&mut covered[p], true) {
                            return Err(format!("primitive slot {p} in two leaves"));
                        }
                        if !contains(&b, &bounds_in_leaf_order[p]) {
                            return Err(format!(
                                "node {n} slot {slot} does not contain primitive slot {p}"
                            ));
                        }
                    }
                } else {
                    let child = index as usize;
                    let Some(child_node) = self.nodes.get(child) else {
                        return Err(format!(
                            "node {n} slot {slot} points to missing node {child}"
                        ));
                    };
                    for s in 0..4 {
                        if !contains(&b, &child_node.child_box(s)) {
                            return Err(format!(
                                "node {n} slot {slot} does not contain node {child}'s slot {s}"
                            ));
                        }
                    }
                    stack.push(child);
                }
            }
        }
        if let Some(p) = covered.iter().position(|c| !c) {
            return Err(format!("primitive slot {p} is in no leaf"));
        }
        if let Some(n) = reached.iter().position(|r| !r) {
            return Err(format!("node {n} is unreachable"));
        }
        if let Some(l) = leaves_reached.iter().position(|r| !r) {
            return Err(format!("leaf {l} is unreachable"));
        }
        Ok(())
    }
}
