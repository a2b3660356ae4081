//! Traversal of the scene's BVH (twin: `shaders/accel.wgsl`): depth-first; an interior node
//! tests both children's boxes, enters the nearer (by where the ray enters them) and pushes the
//! other with its entry distance; a popped child whose box now lies beyond the closest hit is
//! skipped without being read.

use crate::accel::{BOX_FAR_WIDENING, Bvh, MAX_DEPTH, box_entry, inverse_direction};
use crate::shared::ray::Ray;

/// Calls `test(packed primitive, closest)` for every primitive in a leaf, below node `root`,
/// whose box the ray meets before `closest` (and for a leaf root's, unconditionally); `test`
/// shortens `closest` when it finds a nearer hit. The scene's hierarchy starts at node 0, an
/// instanced mesh's at its instance's root.
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
    let entry = |index: u32, closest: f32| {
        let node = &bvh.nodes[index as usize];
        box_entry(node.min, node.max, ray.origin, inverse, closest)
    };
    let mut stack = [(0u32, 0f32); MAX_DEPTH];
    let mut top = 0;
    let mut index = root;
    loop {
        let node = &bvh.nodes[index as usize];
        if node.is_leaf() {
            let first = node.offset as usize;
            for &p in &bvh.primitives[first..first + node.count as usize] {
                test(p, closest);
            }
        } else {
            let (first, second) = (index + 1, node.offset);
            match (entry(first, *closest), entry(second, *closest)) {
                (Some(t_first), Some(t_second)) => {
                    let (near, far, t_far) = if t_second < t_first {
                        (second, first, t_first)
                    } else {
                        (first, second, t_second)
                    };
                    stack[top] = (far, t_far);
                    top += 1;
                    index = near;
                    continue;
                }
                (Some(_), None) => {
                    index = first;
                    continue;
                }
                (None, Some(_)) => {
                    index = second;
                    continue;
                }
                (None, None) => {}
            }
        }
        loop {
            if top == 0 {
                return;
            }
            top -= 1;
            let (pending, t_entry) = stack[top];
            // The box as box_entry would test it against the closest hit now.
            if t_entry <= *closest * BOX_FAR_WIDENING {
                index = pending;
                break;
            }
        }
    }
}
