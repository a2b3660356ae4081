//! Traversal of the scene's BVH: depth-first; an interior node tests its children's boxes,
//! enters the nearest (by where the ray enters them) and pushes the others with their entry
//! distances; a popped child whose box now lies beyond the closest hit is skipped without being
//! read. The CPU traverses the hierarchy collapsed to `WIDTH` children per node (`traverse_wide`);
//! a binary walk of the uncollapsed hierarchy is kept in the tests, as the reference the wide one
//! must agree with (the kernel's four-wide walk is modelled in `traversal_stats`).

use super::lanes::{Lanes, equal_bits};
use super::triangle_blocks::ShearedRay;
use crate::accel::wide::{EMPTY, LEAF, TRIANGLES, TriangleBlock, WIDTH, WideBvh, WideNode};
use crate::accel::{BOX_FAR_WIDENING, Bvh, MAX_DEPTH, inverse_direction};
use crate::shared::ray::Ray;
use std::mem::MaybeUninit;

/// Pending children of a wide traversal. Its slots are not cleared when it is made: a ray's
/// traversal is short beside clearing all of them, which had cost a few percent of a mesh
/// scene's render; only pushed slots are ever read.
struct Pending {
    slots: [MaybeUninit<(u32, f32)>; (WIDTH - 1) * MAX_DEPTH + 1],
    top: usize,
}

impl Pending {
    #[inline]
    fn new() -> Self {
        Pending {
            slots: [MaybeUninit::uninit(); (WIDTH - 1) * MAX_DEPTH + 1],
            top: 0,
        }
    }

    #[inline]
    fn push(&mut self, pending: (u32, f32)) {
        self.slots[self.top] = MaybeUninit::new(pending);
        self.top += 1;
    }

    /// The last pushed node whose box, entered at the distance pushed with it, the ray still
    /// meets before `closest` (as box_entry would test it now), popping those it passes over.
    #[inline]
    fn pop_within(&mut self, closest: f32) -> Option<u32> {
        while self.top > 0 {
            self.top -= 1;
            // SAFETY: slots below `top` were written by `push`.
            let (pending, t_entry) = unsafe { self.slots[self.top].assume_init() };
            if t_entry <= closest * BOX_FAR_WIDENING {
                return Some(pending);
            }
        }
        None
    }
}

/// What a traversal does at its leaves.
pub trait Leaves {
    /// Tests packed primitive `packed` (of a leaf kept as a list), shortening `closest` when it
    /// finds a nearer hit.
    fn primitive(&mut self, packed: u32, closest: &mut f32);
    /// Triangle `triangle` (its index in `FlatScene::triangles`) of a block is hit at distance
    /// `t` with weights `b1`, `b2` of its second and third corners, as `hit_triangle` gives
    /// them: within [`reach`] of `closest` as it was when the block was tested, which an
    /// earlier lane may since have shortened.
    fn triangle(&mut self, triangle: u32, hit: (f32, f32, f32), closest: &mut f32);
    /// Whether the traversal may end now (a search for any hit that has found one).
    #[inline]
    fn finished(&self) -> bool {
        false
    }
    /// Counting hooks (`traversal_stats`; nothing when rendering): a wide node read, a triangle
    /// block tested, a leaf's primitive list entered, a child pushed onto the stack, which is
    /// then `height` entries high.
    #[inline]
    fn read_node(&mut self) {}
    #[inline]
    fn read_block(&mut self, _block: &TriangleBlock) {}
    #[inline]
    fn enter_list(&mut self) {}
    #[inline]
    fn pushed(&mut self, _height: usize) {}
}

/// Up to and including `closest`: the `t_max` a closest-hit search tests primitives with, so
/// that a hit exactly as near can still win its tie-break.
#[inline]
pub fn reach(closest: f32) -> f32 {
    if closest.is_finite() {
        closest.next_up()
    } else {
        closest
    }
}

/// The binary walk (see the tests' `traverse`) over the hierarchy collapsed to `WIDTH` children
/// per node (`wide_bvh`), below child reference `root`: primitives met in another order (and
/// so others skipped), but the same closest hit, as each box test is `accel::box_entry`'s
/// arithmetic lane by lane, each triangle block's test `hit_triangle`'s, and ties between hits
/// resolve by primitive. A node's children are entered nearest first, the others pushed with
/// their entry distances.
#[inline]
pub fn traverse_wide(
    wide: &WideBvh,
    bvh: &Bvh,
    root: u32,
    ray: &Ray,
    closest: &mut f32,
    leaves: &mut impl Leaves,
) {
    if root == EMPTY {
        return;
    }
    let boxes = WideBoxes::new(ray);
    let sheared = ShearedRay::new(ray);
    // Each level pushes at most `WIDTH - 1` children.
    let mut stack = Pending::new();
    let mut reference = root;
    loop {
        if reference & LEAF != 0 {
            if reference & TRIANGLES != 0 {
                let block = &wide.blocks[(reference & !(LEAF | TRIANGLES)) as usize];
                leaves.read_block(block);
                let hits = sheared.hits(block, reach(*closest));
                let mut lanes = hits.hit;
                while lanes != 0 {
                    let lane = lanes.trailing_zeros() as usize;
                    lanes &= lanes - 1;
                    let hit = (hits.t[lane], hits.b1[lane], hits.b2[lane]);
                    leaves.triangle(block.triangles[lane], hit, closest);
                }
            } else {
                let leaf = &bvh.nodes[(reference & !LEAF) as usize];
                leaves.enter_list();
                let first = leaf.offset as usize;
                for &p in &bvh.primitives[first..first + leaf.count as usize] {
                    leaves.primitive(p, closest);
                }
            }
            if leaves.finished() {
                return;
            }
        } else {
            let node = &wide.nodes[reference as usize];
            leaves.read_node();
            let (entries, met) = boxes.entries(node, *closest);
            // The children met, nearest first (at most `WIDTH`: insertion sort).
            let mut order = [(0u32, 0f32); WIDTH];
            let mut count = 0;
            let children = node.children.iter().zip(entries);
            for (lane, (&child, entry)) in children.enumerate() {
                if met & (1 << lane) != 0 {
                    let mut at = count;
                    while at > 0 && order[at - 1].1 > entry {
                        order[at] = order[at - 1];
                        at -= 1;
                    }
                    order[at] = (child, entry);
                    count += 1;
                }
            }
            if count > 0 {
                for &pending in order[1..count].iter().rev() {
                    stack.push(pending);
                    leaves.pushed(stack.top);
                }
                reference = order[0].0;
                continue;
            }
        }
        match stack.pop_within(*closest) {
            Some(pending) => reference = pending,
            None => return,
        }
    }
}

/// A ray's origin and reciprocal direction, ready to test against a wide node's boxes.
struct WideBoxes {
    origin: [Lanes; 3],
    inverse: [Lanes; 3],
}

impl WideBoxes {
    fn new(ray: &Ray) -> Self {
        let inverse = inverse_direction(ray.dir);
        WideBoxes {
            origin: [0, 1, 2].map(|axis| Lanes::splat(ray.origin[axis])),
            inverse: [0, 1, 2].map(|axis| Lanes::splat(inverse[axis])),
        }
    }

    /// Where the ray enters each of `node`'s boxes, and as bits which it meets before
    /// `t_max`: `accel::box_entry` in each lane whose child is not `EMPTY`.
    #[inline]
    fn entries(&self, node: &WideNode, t_max: f32) -> ([f32; WIDTH], u32) {
        let mut near = Lanes::splat(0.0);
        let mut far = Lanes::splat(t_max);
        for axis in 0..3 {
            let t0 = (Lanes::load(&node.min[axis]) - self.origin[axis]) * self.inverse[axis];
            let t1 = (Lanes::load(&node.max[axis]) - self.origin[axis]) * self.inverse[axis];
            near = near.max(t0.min(t1));
            far = far.min(t0.max(t1));
        }
        far = far * Lanes::splat(BOX_FAR_WIDENING);
        let met = near.le(far).bits() & !equal_bits(&node.children, EMPTY);
        let mut entries = [0f32; WIDTH];
        near.store(&mut entries);
        (entries, met)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::box_entry;

    /// A binary walk of the uncollapsed hierarchy: the reference for `traverse_wide`.
    /// Calls `test(packed primitive, closest)` for every primitive in a leaf, below node `root`,
    /// whose box the ray meets before `closest` (and for a leaf root's, unconditionally); `test`
    /// shortens `closest` when it finds a nearer hit. The scene's hierarchy starts at node 0, an
    /// instanced mesh's at its instance's root.
    fn traverse(
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
        let mut stack = Pending::new();
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
                        stack.push((far, t_far));
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
            match stack.pop_within(*closest) {
                Some(pending) => index = pending,
                None => return,
            }
        }
    }

    use crate::accel::tests::{numbers, random_items};
    use crate::accel::wide::WideBvh;
    use glam::Vec3;

    /// Leaves of boxes, tested by a closure.
    struct Boxes<F>(F);

    impl<F: FnMut(u32, &mut f32)> Leaves for Boxes<F> {
        fn primitive(&mut self, packed: u32, closest: &mut f32) {
            (self.0)(packed, closest)
        }
        fn triangle(&mut self, _: u32, _: (f32, f32, f32), _: &mut f32) {
            unreachable!("no triangle blocks among boxes")
        }
    }

    /// Both traversals find the same nearest box among 3 000 (a stand-in for primitives, whose
    /// hits lie in their boxes; entry distance, then lower index), for 20 000 rays from inside
    /// and outside the scene in every direction, though they test them in different orders.
    #[test]
    fn the_wide_traversal_finds_what_the_binary_one_does() {
        let items = random_items(3000);
        let bvh = Bvh::build(&mut items.clone());
        let wide = WideBvh::new(&bvh, [], |_| None);
        let mut next = numbers(7);
        for _ in 0..20_000 {
            let origin = Vec3::new(next(), next(), next()) * 160.0 - 30.0;
            let dir = (Vec3::new(next(), next(), next()) * 2.0 - 1.0).normalize_or(Vec3::X);
            let ray = Ray { origin, dir };
            let inverse = inverse_direction(dir);
            let hit = |p: u32, closest: &mut f32, best: &mut (f32, u32)| {
                let item = &items[p as usize];
                if let Some(t) = box_entry(item.min, item.max, origin, inverse, *closest)
                    && t > 0.0
                    && (t < best.0 || (t == best.0 && p < best.1))
                {
                    *best = (t, p);
                    *closest = t;
                }
            };
            let (mut binary, mut wide_found) =
                ((f32::INFINITY, u32::MAX), (f32::INFINITY, u32::MAX));
            let mut closest = f32::INFINITY;
            traverse(&bvh, 0, &ray, &mut closest, |p, c| hit(p, c, &mut binary));
            let mut closest = f32::INFINITY;
            let mut boxes = Boxes(|p, c: &mut f32| hit(p, c, &mut wide_found));
            traverse_wide(&wide, &bvh, wide.root, &ray, &mut closest, &mut boxes);
            assert_eq!(binary, wide_found, "ray {ray:?}");
        }
    }
}
