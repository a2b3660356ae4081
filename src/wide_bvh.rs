//! The scene's BVH collapsed to four children per node, which the CPU traverses (`cpu/accel.rs`)
//! testing a node's four boxes at once with SIMD, as Embree does: a binary node's two children
//! are replaced by its largest interior child's two until four are reached. Leaves stay the
//! binary hierarchy's, so the primitives and their order are the same; the GPU keeps the binary
//! hierarchy.

use crate::accel::{Bvh, Node};
use std::collections::HashMap;

/// A child: `EMPTY`, a leaf (`LEAF` | the index of the binary hierarchy's leaf node) or the
/// index of another wide node.
pub const EMPTY: u32 = u32::MAX;
pub const LEAF: u32 = 1 << 31;

/// Four children's boxes, one array per bound and axis so that SIMD lanes load them at once.
/// An empty child's box is +inf on every bound; traversal skips it by its `EMPTY` reference.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(16))]
pub struct WideNode {
    pub min: [[f32; 4]; 3],
    pub max: [[f32; 4]; 3],
    pub children: [u32; 4],
}

#[derive(Clone, Debug, PartialEq, Default)]
pub struct WideBvh {
    pub nodes: Vec<WideNode>,
    /// The scene's root as a child reference (`EMPTY` without primitives).
    pub root: u32,
    /// Each instance's root, by instance index.
    pub instance_roots: Vec<u32>,
}

impl WideBvh {
    /// Collapses `bvh`, whose scene root is node 0, and the roots of its instanced meshes'
    /// hierarchies (binary node indices, one per instance; shared roots collapse once).
    pub fn new(bvh: &Bvh, instance_roots: impl IntoIterator<Item = u32>) -> Self {
        let mut wide = WideBvh {
            nodes: Vec::with_capacity(bvh.nodes.len() / 2 + 1),
            root: EMPTY,
            instance_roots: Vec::new(),
        };
        if bvh.nodes.is_empty() {
            return wide;
        }
        wide.root = wide.collapse(bvh, 0);
        let mut collapsed: HashMap<u32, u32> = HashMap::new();
        for root in instance_roots {
            let reference = match collapsed.get(&root) {
                Some(&reference) => reference,
                None => {
                    let reference = wide.collapse(bvh, root);
                    collapsed.insert(root, reference);
                    reference
                }
            };
            wide.instance_roots.push(reference);
        }
        wide
    }

    /// The child reference of binary node `index`, its subtree collapsed (depth first).
    fn collapse(&mut self, bvh: &Bvh, index: u32) -> u32 {
        let node = &bvh.nodes[index as usize];
        if node.is_leaf() {
            return LEAF | index;
        }
        let mut children = [index + 1, node.offset, EMPTY, EMPTY];
        let mut count = 2;
        while count < 4 {
            // Open the interior child of largest surface area: the likeliest to be entered.
            let widest = (0..count)
                .filter(|&i| !bvh.nodes[children[i] as usize].is_leaf())
                .max_by(|&a, &b| {
                    let area_of = |i: usize| area(&bvh.nodes[children[i] as usize]);
                    area_of(a).total_cmp(&area_of(b))
                });
            let Some(i) = widest else { break };
            let opened = children[i];
            children[i] = opened + 1;
            children[count] = bvh.nodes[opened as usize].offset;
            count += 1;
        }
        let at = self.nodes.len();
        self.nodes.push(WideNode {
            min: [[f32::INFINITY; 4]; 3],
            max: [[f32::INFINITY; 4]; 3],
            children: [EMPTY; 4],
        });
        for (lane, &child) in children[..count].iter().enumerate() {
            let box_of = &bvh.nodes[child as usize];
            let reference = self.collapse(bvh, child);
            let node = &mut self.nodes[at];
            for axis in 0..3 {
                node.min[axis][lane] = box_of.min[axis];
                node.max[axis][lane] = box_of.max[axis];
            }
            node.children[lane] = reference;
        }
        at as u32
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
        let wide = WideBvh::new(&bvh, []);
        let mut leaves = Vec::new();
        let mut stack = vec![wide.root];
        while let Some(reference) = stack.pop() {
            if reference & LEAF != 0 {
                leaves.push(reference & !LEAF);
                continue;
            }
            let node = &wide.nodes[reference as usize];
            for lane in 0..4 {
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
