//! The scene's BVH as the kernel traverses it (`shaders/accel.wgsl`; packed for it by
//! `gpu::layout::gpu_bvh`): the binary hierarchy collapsed to [`KERNEL_WIDTH`] children per
//! node as `wide` collapses it for the CPU (the same opening of the largest child), each node's
//! children's boxes quantized to a byte per bound against the node's own box (Ylitie et al.
//! 2017, "Efficient Incoherent Ray Traversal on GPUs Through Compressed Wide BVHs"): a node is
//! 64 bytes, the size of the binary node it replaces, for two levels of the binary hierarchy.
//! Leaves stay the binary hierarchy's: a child reference is an interior node's index here, or
//! a leaf's `BVH_LEAF` reference (its primitive range), or [`EMPTY`].
//!
//! A quantized box is never smaller than the child's: it can only make a ray enter more
//! boxes, never miss a primitive, so both backends find the same closest hits. Four children,
//! not the CPU's eight: a GPU lane tests a node's boxes one after another and sorts them, and
//! four already halve what the binary walk read (docs/benchmarks.md). Where a bound would need
//! a step beyond f32's (coordinates near 1e38) it is decoded as infinite, by IEEE overflow.

use super::wide::open_children;
use super::{Bvh, Node};
use crate::shared::layout::{BVH_LEAF, BVH_LEAF_COUNT_SHIFT};
use glam::Vec3;
use std::collections::HashMap;

/// Children per node of the kernel's hierarchy.
pub const KERNEL_WIDTH: usize = 4;
/// An unused child's reference: never a node's index (below 2^31) nor a leaf's (a leaf's range
/// ends by `BVH_LEAF_OFFSET_LIMIT`, which this one's would pass).
pub const EMPTY: u32 = u32::MAX;

/// The sort key of a child the ray misses, and the largest of one it meets (its entry
/// distance, capped below it): the kernel orders a node's children by it, nearest first
/// ([`nearest_first`]).
pub const MISSED: f32 = f32::MAX;
pub const NEAREST: f32 = 3.0e38;

/// A node's children met, as their lanes (`EMPTY` where missed), ordered by `keys` (entry
/// distances, `MISSED` where missed), nearest first, by the sorting network the kernel runs
/// (`nearest_first` in shaders/accel.wgsl): compare-exchanges (0 1) (2 3) (0 2) (1 3) (1 2),
/// each exchanging only where the second is strictly nearer.
pub fn nearest_first(
    keys: [f32; KERNEL_WIDTH],
    lanes: [u32; KERNEL_WIDTH],
) -> [(f32, u32); KERNEL_WIDTH] {
    let mut sorted: [(f32, u32); KERNEL_WIDTH] = std::array::from_fn(|i| (keys[i], lanes[i]));
    for (a, b) in [(0, 1), (2, 3), (0, 2), (1, 3), (1, 2)] {
        if sorted[b].0 < sorted[a].0 {
            sorted.swap(a, b);
        }
    }
    sorted
}

/// The kernel's traversal stack holds, for each interior node on the ray's path, one entry for
/// the node's children met that it has yet to enter (its "siblings"), nearest first, with the
/// nearest one's entry distance: a word of the node's index (below [`GROUP_NODE_LIMIT`]), the
/// children's lanes, two bits each from [`GROUP_LANES_SHIFT`] (the next lowest), and how many
/// are left (1 to 3) from [`GROUP_COUNT_SHIFT`]. One entry where there were three: a third of
/// the stack, and one write instead of three for each node. A child popped while others are
/// left puts the entry back with the rest, under the same distance (the nearest's, so no
/// farther one is ever skipped: it costs a node read where the ray would have been seen to
/// miss its box; docs/benchmarks.md counts how rarely).
pub const GROUP_LANES_SHIFT: u32 = 24;
pub const GROUP_COUNT_SHIFT: u32 = 30;
pub const GROUP_NODE_LIMIT: u32 = 1 << GROUP_LANES_SHIFT;

/// The entry for interior node `node`'s children in `lanes` (1 to 3, nearest first) left to
/// enter.
pub fn group_entry(node: u32, lanes: &[u32]) -> u32 {
    debug_assert!(node < GROUP_NODE_LIMIT && (1..KERNEL_WIDTH).contains(&lanes.len()));
    let packed =
        (lanes.iter().enumerate()).fold(0, |w, (i, &lane)| w | (lane & 3) << (2 * i as u32));
    node | packed << GROUP_LANES_SHIFT | (lanes.len() as u32) << GROUP_COUNT_SHIFT
}

/// The next child's lane of group entry `word`, and the entry for those after it (`None` when it
/// was the last), as the kernel pops them.
pub fn group_next(word: u32) -> (u32, Option<u32>) {
    let node = word & (GROUP_NODE_LIMIT - 1);
    let lanes = (word >> GROUP_LANES_SHIFT) & 0x3f;
    let left = word >> GROUP_COUNT_SHIFT;
    let rest = (left > 1)
        .then(|| node | (lanes >> 2) << GROUP_LANES_SHIFT | (left - 1) << GROUP_COUNT_SHIFT);
    (lanes & 3, rest)
}

/// A node: the children's boxes as bytes on a grid of `2^exponent` steps per axis from `origin`
/// (the node's own minimum corner), rounded outward.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct QuantizedNode {
    pub origin: Vec3,
    /// Each axis's step as an f32's biased exponent (step = 2^(e - 127), e in 1..=254).
    pub exponents: [u8; 3],
    /// Children in use, the first `count` lanes.
    pub count: u8,
    pub children: [u32; KERNEL_WIDTH],
    /// `low[axis][lane]`, `high[axis][lane]`: the grid steps of each child's minimum and maximum.
    pub low: [[u8; KERNEL_WIDTH]; 3],
    pub high: [[u8; KERNEL_WIDTH]; 3],
}

/// The step `2^(e - 127)` of biased exponent `e`.
#[inline]
pub fn step_of(exponent: u8) -> f32 {
    f32::from_bits((exponent as u32) << 23)
}

/// A bound at `q` steps from `origin`: `origin + q x step` in f32, as the kernel decodes it
/// (`q x step` is exact, so a fused multiply-add rounds it alike).
#[inline]
pub fn decode(origin: f32, q: u8, step: f32) -> f32 {
    origin + q as f32 * step
}

impl QuantizedNode {
    /// Child `lane`'s box as the kernel decodes it.
    pub fn child_box(&self, lane: usize) -> (Vec3, Vec3) {
        let bound = |q: &[[u8; KERNEL_WIDTH]; 3]| {
            Vec3::from_array(std::array::from_fn(|axis| {
                decode(
                    self.origin[axis],
                    q[axis][lane],
                    step_of(self.exponents[axis]),
                )
            }))
        };
        (bound(&self.low), bound(&self.high))
    }

    /// The node over `children` (at most [`KERNEL_WIDTH`]: reference, minimum, maximum), each
    /// box quantized outward.
    pub fn new(children: &[(u32, Vec3, Vec3)]) -> Self {
        debug_assert!(!children.is_empty() && children.len() <= KERNEL_WIDTH);
        let origin = (children.iter()).fold(Vec3::INFINITY, |m, c| m.min(c.1));
        let top = (children.iter()).fold(Vec3::NEG_INFINITY, |m, c| m.max(c.2));
        let mut node = QuantizedNode {
            origin,
            count: children.len() as u8,
            children: [EMPTY; KERNEL_WIDTH],
            ..Default::default()
        };
        for (lane, c) in children.iter().enumerate() {
            node.children[lane] = c.0;
        }
        for axis in 0..3 {
            let (o, extent) = (origin[axis], top[axis] - origin[axis]);
            // The smallest step whose 255 span the extent, then larger until every bound
            // rounds outward within a byte (f32 rounding of origin + q x step may need one
            // more step).
            let mut exponent = smallest_exponent(extent / 255.0);
            loop {
                let step = step_of(exponent);
                let quantized: Option<Vec<(u8, u8)>> = (children.iter())
                    .map(|c| Some((below(c.1[axis], o, step)?, above(c.2[axis], o, step)?)))
                    .collect();
                match quantized {
                    Some(q) => {
                        for (lane, (low, high)) in q.into_iter().enumerate() {
                            node.low[axis][lane] = low;
                            node.high[axis][lane] = high;
                        }
                        node.exponents[axis] = exponent;
                        break;
                    }
                    None if exponent < 254 => exponent += 1,
                    None => {
                        // Beyond f32's steps (an infinite extent): every child spans the axis
                        // from the origin to infinity (255 x 2^127 overflows).
                        node.exponents[axis] = 254;
                        node.low[axis] = [0; KERNEL_WIDTH];
                        node.high[axis] = [255; KERNEL_WIDTH];
                        break;
                    }
                }
            }
        }
        node
    }
}

/// The biased exponent of the smallest power of two at least `step` (at least 1: 2^-126).
fn smallest_exponent(step: f32) -> u8 {
    if !(step > f32::MIN_POSITIVE) {
        return 1;
    }
    let bits = step.to_bits();
    let exponent = (bits >> 23) as u8;
    // A mantissa other than zero: the next power of two up.
    if bits & 0x7f_ffff != 0 {
        exponent.saturating_add(1)
    } else {
        exponent
    }
}

/// The most steps from `origin` at which the decoded bound is at most `bound`.
fn below(bound: f32, origin: f32, step: f32) -> Option<u8> {
    let mut q = (((bound - origin) / step).floor()).clamp(0.0, 255.0) as u8;
    while decode(origin, q, step) > bound {
        q = q.checked_sub(1)?;
    }
    Some(q)
}

/// The fewest steps from `origin` at which the decoded bound is at least `bound` (`None`
/// beyond 255).
fn above(bound: f32, origin: f32, step: f32) -> Option<u8> {
    let steps = ((bound - origin) / step).ceil();
    if !(steps <= 255.0) {
        return None;
    }
    let mut q = steps.max(0.0) as u8;
    while decode(origin, q, step) < bound {
        q = q.checked_add(1)?;
    }
    Some(q)
}

/// The kernel's hierarchy: its nodes (the scene root's first where it is interior), the
/// scene's root reference and each instance's, and the deepest interior levels a ray walks
/// (the kernel's stack is sized from them: `gpu::shader::compose`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct QuantizedBvh {
    pub nodes: Vec<QuantizedNode>,
    pub root: u32,
    pub instance_roots: Vec<u32>,
    /// Interior nodes on the longest path from the scene's root, and from any instance's.
    pub depth: u32,
    pub instance_depth: u32,
}

impl QuantizedBvh {
    /// The most entries the kernel's traversal stack holds (`BVH_STACK`), with top-level leaves
    /// of at most `instance_leaf` instances: one per interior level of the scene's hierarchy
    /// (a node's children met but the one entered: [`group_entry`]), the instances of one
    /// top-level leaf (entered one by one from the stack), and one per interior level of an
    /// instance's mesh below it.
    pub fn stack_bound(&self, instance_leaf: u32) -> u32 {
        self.depth.max(1) + instance_leaf + self.instance_depth
    }
}

/// A binary leaf's reference: `BVH_LEAF`, its count and its first primitive.
pub fn leaf_reference(leaf: &Node) -> u32 {
    BVH_LEAF | (leaf.count << BVH_LEAF_COUNT_SHIFT) | leaf.offset
}

impl QuantizedBvh {
    /// Collapses `bvh` (scene root at node 0) and its instanced meshes' roots (binary node
    /// indices, one per instance; shared roots collapse once).
    pub fn new(bvh: &Bvh, instance_roots: impl IntoIterator<Item = u32>) -> Self {
        let mut out = QuantizedBvh {
            nodes: Vec::with_capacity(bvh.nodes.len() / 3 + 1),
            root: BVH_LEAF,
            ..Default::default()
        };
        if bvh.nodes.is_empty() {
            return out;
        }
        let (root, depth) = out.collapse(bvh, 0);
        (out.root, out.depth) = (root, depth);
        let mut collapsed: HashMap<u32, (u32, u32)> = HashMap::new();
        for root in instance_roots {
            let (reference, depth) = match collapsed.get(&root) {
                Some(&done) => done,
                None => {
                    let done = out.collapse(bvh, root);
                    collapsed.insert(root, done);
                    done
                }
            };
            out.instance_roots.push(reference);
            out.instance_depth = out.instance_depth.max(depth);
        }
        out
    }

    /// The reference of binary node `index`, its subtree collapsed (depth first: a node before
    /// its children), and the interior levels below and at it.
    fn collapse(&mut self, bvh: &Bvh, index: u32) -> (u32, u32) {
        let node = &bvh.nodes[index as usize];
        if node.is_leaf() {
            return (leaf_reference(node), 0);
        }
        let (children, count) =
            open_children::<KERNEL_WIDTH>(bvh, index, |child| !bvh.nodes[child as usize].is_leaf());
        let at = self.nodes.len();
        self.nodes.push(QuantizedNode::default());
        let mut deepest = 0;
        let mut lanes = Vec::with_capacity(count);
        for &child in &children[..count] {
            let (reference, depth) = self.collapse(bvh, child);
            deepest = deepest.max(depth);
            let b = &bvh.nodes[child as usize];
            lanes.push((reference, b.min, b.max));
        }
        self.nodes[at] = QuantizedNode::new(&lanes);
        (at as u32, deepest + 1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::tests::{numbers, random_items};

    /// Every decoded box holds its child's box and lies within a step of it on each side, for
    /// random boxes at scales from 1e-30 to 1e30 and offsets far from the origin.
    #[test]
    fn quantized_boxes_hold_their_childrens() {
        let mut next = numbers(7);
        for i in 0..20_000 {
            let scale = 10f32.powf(next() * 60.0 - 30.0);
            let offset = Vec3::splat(if i % 3 == 0 { 1e6 * scale } else { 0.0 });
            let lanes: Vec<(u32, Vec3, Vec3)> = (0..1 + i % KERNEL_WIDTH)
                .map(|lane| {
                    let a = Vec3::new(next(), next(), next()) * scale + offset;
                    let b = a + Vec3::new(next(), next(), next()) * scale * next();
                    (lane as u32, a, b)
                })
                .collect();
            let node = QuantizedNode::new(&lanes);
            for (lane, &(reference, min, max)) in lanes.iter().enumerate() {
                assert_eq!(node.children[lane], reference);
                let (lo, hi) = node.child_box(lane);
                assert!(
                    lo.cmple(min).all() && hi.cmpge(max).all(),
                    "{lo} {hi} for {min} {max}"
                );
                let step = Vec3::from_array(node.exponents.map(step_of));
                assert!(
                    (min - lo).cmple(step * 2.0).all() && (hi - max).cmple(step * 2.0).all(),
                    "{lo} {hi} for {min} {max}, step {step}"
                );
            }
        }
    }

    /// A group entry gives back its lanes in order, then none, for every node index's extremes
    /// and every count; the kernel packs and unpacks the same bits (traverse in
    /// shaders/accel.wgsl; it leaves 3 where Rust leaves 0 in lanes past the count, never read).
    #[test]
    fn group_entries_give_back_their_lanes_in_order() {
        for node in [0, 1, 12_345, GROUP_NODE_LIMIT - 1] {
            for lanes in [&[3][..], &[2, 0], &[1, 3, 0], &[0, 1, 2], &[3, 2, 1]] {
                let mut word = Some(group_entry(node, lanes));
                let mut got = Vec::new();
                while let Some(w) = word {
                    assert_eq!(w & (GROUP_NODE_LIMIT - 1), node);
                    let (lane, rest) = group_next(w);
                    got.push(lane);
                    word = rest;
                }
                assert_eq!(got, lanes, "node {node}");
            }
        }
    }

    /// Every binary leaf is reached exactly once, and the nodes are a third of the binary
    /// hierarchy's at most.
    #[test]
    fn collapsing_keeps_every_leaf_once() {
        let bvh = Bvh::build(&mut random_items(5000));
        let q = QuantizedBvh::new(&bvh, []);
        let mut leaves = Vec::new();
        let mut stack = vec![q.root];
        while let Some(reference) = stack.pop() {
            if reference & BVH_LEAF != 0 {
                leaves.push(reference);
                continue;
            }
            let node = &q.nodes[reference as usize];
            stack.extend(&node.children[..node.count as usize]);
            assert!(
                node.children[node.count as usize..]
                    .iter()
                    .all(|&c| c == EMPTY)
            );
        }
        leaves.sort_unstable();
        let mut expected: Vec<u32> = (bvh.nodes.iter())
            .filter(|n| n.is_leaf())
            .map(leaf_reference)
            .collect();
        expected.sort_unstable();
        assert_eq!(leaves, expected);
        assert!(
            q.nodes.len() * 3 <= bvh.nodes.len(),
            "{} nodes",
            q.nodes.len()
        );
        assert!(q.depth > 0 && q.depth <= bvh.depth);
    }
}
