//! The scene's BVH collapsed to `WIDTH` children per node, which the CPU traverses
//! (`cpu/accel.rs`) testing a node's boxes at once with SIMD (`cpu/lanes.rs`), as Embree does: a
//! binary node's two children are replaced by its largest interior child's two until `WIDTH`
//! are reached. Leaves stay the binary hierarchy's, so the primitives and their order are the
//! same; a subtree of triangles alone, at most `WIDTH` of them, becomes a [`TriangleBlock`], its
//! corners copied beside each other, so that it is one load and one test of all its lanes rather
//! than a chase through the primitive list into the scene's triangles. The kernel's hierarchy
//! is collapsed alike, four wide, with its boxes quantized (`quantized`).

use crate::accel::{Bvh, Node};
use crate::shared::primitive::PRIMITIVE_INDEX_BITS;
use glam::Vec3;
use std::collections::HashMap;

/// A child: `EMPTY`, a leaf (`LEAF` | the index of the binary hierarchy's leaf node, or `LEAF |
/// TRIANGLES` | the index of its [`TriangleBlock`]) or the index of another wide node.
pub const EMPTY: u32 = u32::MAX;
pub const LEAF: u32 = 1 << 31;
pub const TRIANGLES: u32 = 1 << 30;

/// Children per wide node and triangles per block: one SIMD register's floats, eight where the
/// build targets AVX2 (a level's eight boxes tested in the time of four, and half the levels),
/// else four (SSE).
pub const WIDTH: usize = if cfg!(all(target_arch = "x86_64", target_feature = "avx2")) {
    8
} else {
    4
};

/// `WIDTH` children's boxes, one array per bound and axis so that SIMD lanes load them at once.
/// An empty child's box is +inf on every bound; traversal skips it by its `EMPTY` reference.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(32))]
pub struct WideNode {
    pub min: [[f32; WIDTH]; 3],
    pub max: [[f32; WIDTH]; 3],
    pub children: [u32; WIDTH],
}

/// The triangles of a small subtree, in leaf order, one array per corner and axis
/// (`corners[corner][axis][lane]`) so that SIMD lanes load them at once. A lane past the
/// subtree's triangles holds `EMPTY` and a triangle of zeros.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(32))]
pub struct TriangleBlock {
    pub corners: [[[f32; WIDTH]; 3]; 3],
    /// Each lane's triangle: its index in `FlatScene::triangles`.
    pub triangles: [u32; WIDTH],
}

#[derive(Clone, Debug, PartialEq, Default)]
pub struct WideBvh {
    pub nodes: Vec<WideNode>,
    pub blocks: Vec<TriangleBlock>,
    /// The scene's root as a child reference (`EMPTY` without primitives).
    pub root: u32,
    /// Each instance's root, by instance index.
    pub instance_roots: Vec<u32>,
}

impl WideBvh {
    /// Collapses `bvh`, whose scene root is node 0, and the roots of its instanced meshes'
    /// hierarchies (binary node indices, one per instance; shared roots collapse once);
    /// `corners` gives a packed primitive reference's corners where it is a triangle.
    pub fn new(
        bvh: &Bvh,
        instance_roots: impl IntoIterator<Item = u32>,
        corners: impl Fn(u32) -> Option<[Vec3; 3]>,
    ) -> Self {
        let mut wide = WideBvh {
            nodes: Vec::with_capacity(bvh.nodes.len() / 2 + 1),
            blocks: Vec::new(),
            root: EMPTY,
            instance_roots: Vec::new(),
        };
        if bvh.nodes.is_empty() {
            return wide;
        }
        let small = SmallSubtrees::new(bvh, &corners);
        let instance_roots: Vec<u32> = instance_roots.into_iter().collect();
        // Grown block by block, a mesh's blocks (tens of megabytes) were copied at every
        // doubling of the vector.
        let mut roots: Vec<u32> = std::iter::once(0)
            .chain(instance_roots.iter().copied())
            .collect();
        roots.sort_unstable();
        roots.dedup();
        let fitting_roots = roots.iter().filter(|&&root| small.fits_block(root)).count();
        let blocks = small.blocks_below_others + fitting_roots;
        wide.blocks.reserve_exact(blocks);
        wide.root = wide.collapse(bvh, 0, &small, &corners);
        let mut collapsed: HashMap<u32, u32> = HashMap::new();
        for root in instance_roots {
            let reference = match collapsed.get(&root) {
                Some(&reference) => reference,
                None => {
                    let reference = wide.collapse(bvh, root, &small, &corners);
                    collapsed.insert(root, reference);
                    reference
                }
            };
            wide.instance_roots.push(reference);
        }
        debug_assert_eq!(wide.blocks.len(), blocks, "blocks reserved");
        wide
    }

    /// The child reference of binary node `index`, its subtree collapsed (depth first); a
    /// subtree of at most `WIDTH` triangles is one block.
    fn collapse(
        &mut self,
        bvh: &Bvh,
        index: u32,
        small: &SmallSubtrees,
        corners: &impl Fn(u32) -> Option<[Vec3; 3]>,
    ) -> u32 {
        let node = &bvh.nodes[index as usize];
        if small.fits_block(index) {
            return self.block(bvh, index, corners);
        }
        if node.is_leaf() {
            debug_assert!(index < TRIANGLES, "a leaf's index would read as a block's");
            return LEAF | index;
        }
        let (children, count) = open_children::<WIDTH>(bvh, index, |child| {
            !bvh.nodes[child as usize].is_leaf() && !small.fits_block(child)
        });
        let at = self.nodes.len();
        self.nodes.push(WideNode {
            min: [[f32::INFINITY; WIDTH]; 3],
            max: [[f32::INFINITY; WIDTH]; 3],
            children: [EMPTY; WIDTH],
        });
        for (lane, &child) in children[..count].iter().enumerate() {
            let box_of = &bvh.nodes[child as usize];
            let reference = self.collapse(bvh, child, small, corners);
            let node = &mut self.nodes[at];
            for axis in 0..3 {
                node.min[axis][lane] = box_of.min[axis];
                node.max[axis][lane] = box_of.max[axis];
            }
            node.children[lane] = reference;
        }
        at as u32
    }

    /// The block of the triangles below binary node `index` (at most `WIDTH`, in leaf order).
    fn block(&mut self, bvh: &Bvh, index: u32, corners: &impl Fn(u32) -> Option<[Vec3; 3]>) -> u32 {
        let mut block = TriangleBlock {
            corners: [[[0.0; WIDTH]; 3]; 3],
            triangles: [EMPTY; WIDTH],
        };
        let mut lane = 0;
        // A subtree of at most `WIDTH` primitives has at most `WIDTH` levels below it, so
        // that many nodes pending at once at most.
        let mut pending = [0u32; WIDTH + 1];
        pending[0] = index;
        let mut depth = 1;
        while depth > 0 {
            depth -= 1;
            let at = pending[depth];
            let node = &bvh.nodes[at as usize];
            if !node.is_leaf() {
                (pending[depth], pending[depth + 1]) = (node.offset, at + 1);
                depth += 2;
                continue;
            }
            let first = node.offset as usize;
            for &packed in &bvh.primitives[first..first + node.count as usize] {
                let points = corners(packed).expect("a block's primitives are triangles");
                for (corner, p) in points.iter().enumerate() {
                    for axis in 0..3 {
                        block.corners[corner][axis][lane] = p[axis];
                    }
                }
                block.triangles[lane] = packed & ((1 << PRIMITIVE_INDEX_BITS) - 1);
                lane += 1;
            }
        }
        self.blocks.push(block);
        LEAF | TRIANGLES | (self.blocks.len() - 1) as u32
    }
}

/// The children of interior binary node `index` opened up to `N`: its two, then, while fewer
/// than `N`, the child that `opens` allows of largest surface area (the likeliest to be
/// entered) replaced by its own two; and how many there are (the rest `EMPTY`). The CPU's
/// collapse and the kernel's (`quantized`) open alike.
pub fn open_children<const N: usize>(
    bvh: &Bvh,
    index: u32,
    opens: impl Fn(u32) -> bool,
) -> ([u32; N], usize) {
    let mut children = [EMPTY; N];
    (children[0], children[1]) = (index + 1, bvh.nodes[index as usize].offset);
    let mut count = 2;
    while count < N {
        let widest = (0..count).filter(|&i| opens(children[i])).max_by(|&a, &b| {
            let area_of = |i: usize| area(&bvh.nodes[children[i] as usize]);
            area_of(a).total_cmp(&area_of(b))
        });
        let Some(i) = widest else { break };
        let opened = children[i];
        children[i] = opened + 1;
        children[count] = bvh.nodes[opened as usize].offset;
        count += 1;
    }
    (children, count)
}

/// Which subtrees of a binary hierarchy hold at most `WIDTH` primitives, all triangles: those
/// become one block, whose test of all its lanes costs about what one triangle's does.
struct SmallSubtrees {
    /// Per node: its subtree's primitives, all triangles, capped at `TOO_MANY`.
    triangles: Vec<u8>,
    /// Subtrees that fit a block below a node that does not: the blocks of the collapse, but
    /// for roots that fit one.
    blocks_below_others: usize,
}

impl SmallSubtrees {
    const TOO_MANY: u8 = WIDTH as u8 + 1;

    fn new(bvh: &Bvh, corners: &impl Fn(u32) -> Option<[Vec3; 3]>) -> Self {
        let mut triangles = vec![0u8; bvh.nodes.len()];
        let mut blocks_below_others = 0;
        // Children follow their parent (depth-first order), so they are counted first.
        for (index, node) in bvh.nodes.iter().enumerate().rev() {
            triangles[index] = if node.is_leaf() {
                let first = node.offset as usize;
                let leaf = &bvh.primitives[first..first + node.count as usize];
                if leaf.len() < Self::TOO_MANY as usize
                    && leaf.iter().all(|&p| corners(p).is_some())
                {
                    leaf.len() as u8
                } else {
                    Self::TOO_MANY
                }
            } else {
                let (first, second) = (triangles[index + 1], triangles[node.offset as usize]);
                let both = first.saturating_add(second).min(Self::TOO_MANY);
                if !Self::fits(both) {
                    blocks_below_others += Self::fits(first) as usize + Self::fits(second) as usize;
                }
                both
            };
        }
        SmallSubtrees {
            triangles,
            blocks_below_others,
        }
    }

    fn fits_block(&self, index: u32) -> bool {
        Self::fits(self.triangles[index as usize])
    }

    /// Whether a subtree of `count` triangles (capped at `TOO_MANY`) is one block.
    fn fits(count: u8) -> bool {
        (1..Self::TOO_MANY).contains(&count)
    }
}

fn area(node: &Node) -> f32 {
    let d = node.max - node.min;
    d.x * d.y + d.y * d.z + d.z * d.x
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::tests::random_items;

    /// Every leaf of the binary hierarchy is reached exactly once, under boxes that are the
    /// binary nodes' own.
    #[test]
    fn collapsing_keeps_every_leaf_once() {
        let bvh = Bvh::build(&mut random_items(5000));
        let wide = WideBvh::new(&bvh, [], |_| None);
        let mut leaves = Vec::new();
        let mut stack = vec![wide.root];
        while let Some(reference) = stack.pop() {
            if reference & LEAF != 0 {
                leaves.push(reference & !LEAF);
                continue;
            }
            let node = &wide.nodes[reference as usize];
            for lane in 0..WIDTH {
                if node.children[lane] != EMPTY {
                    stack.push(node.children[lane]);
                }
            }
        }
        leaves.sort_unstable();
        let expected: Vec<u32> = (0..bvh.nodes.len() as u32)
            .filter(|&i| bvh.nodes[i as usize].is_leaf())
            .collect();
        assert_eq!(leaves, expected);
        assert!(
            wide.nodes.len() * 3 <= bvh.nodes.len(),
            "{} wide nodes",
            wide.nodes.len()
        );
    }
}
