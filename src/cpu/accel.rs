//! Traversal of the scene's BVH (twin: `shaders/accel.wgsl`): nodes depth-first, the nearer
//! child (by the ray's direction along the node's split axis) first, a stack of pending second
//! children.

use super::shapes::Ray;
use crate::accel::{Bvh, MAX_DEPTH, hits_box, inverse_direction};

/// Calls `test(packed primitive, closest)` for every primitive in a leaf, below node `root`,
/// whose box the ray meets before `closest`; `test` shortens `closest` when it finds a nearer
/// hit. The scene's hierarchy starts at node 0, an instanced mesh's at its instance's root.
#[inline]
pub fn traverse(
    bvh: &Bvh,
    root: u32,
    ray: &Ray,
    closest: &mut f32,
    mut test: impl FnMut(u32, &mut f32),
) {
    if bvh.nodes.is_empty() {
        return;
    }
    let inverse = inverse_direction(ray.dir);
    let negative = [ray.dir.x < 0.0, ray.dir.y < 0.0, ray.dir.z < 0.0];
    let mut stack = [0u32; MAX_DEPTH];
    let mut top = 0;
    let mut index = root;
    loop {
        let node = &bvh.nodes[index as usize];
        if hits_box(node.min, node.max, ray.origin, inverse, *closest) {
            if node.is_leaf() {
                let first = node.offset as usize;
                for &p in &bvh.primitives[first..first + node.count as usize] {
                    test(p, closest);
                }
            } else {
                let (near, far) = if negative[(node.count & 3) as usize] {
                    (node.offset, index + 1)
                } else {
                    (index + 1, node.offset)
                };
                stack[top] = far;
                top += 1;
                index = near;
                continue;
            }
        }
        if top == 0 {
            return;
        }
        top -= 1;
        index = stack[top];
    }
}
