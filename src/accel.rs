//! The bounding volume hierarchy both backends traverse (CPU: `cpu/accel.rs`, GPU:
//! `shaders/accel.wgsl`): built once on the host over every primitive of a flat scene (spheres,
//! quads, triangles) by binned SAH, in parallel, and flattened depth-first into a compact node
//! array: an interior node's first child follows it, its second is at `offset`; a leaf's
//! primitives are `primitives[offset .. offset + count]`.

use glam::{Vec3, Vec3A};

/// Most primitives a leaf holds, except at the depth limit.
pub const MAX_LEAF: usize = 4;
/// Most levels: the traversal stacks (on the GPU a private array) hold this many entries.
pub const MAX_DEPTH: usize = 48;
/// `count` of an interior node: this bit, and the split axis in the low two bits.
pub const INTERIOR: u32 = 1 << 31;
/// SAH bins per split.
const BINS: usize = 16;
/// Below this many primitives a subtree is built on the current thread.
const PARALLEL_BELOW: usize = 4096;

#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Node {
    pub min: Vec3,
    pub max: Vec3,
    /// Interior: the index of the second child; leaf: the first of its primitives.
    pub offset: u32,
    /// Leaf: how many primitives; interior: `INTERIOR | axis`.
    pub count: u32,
}

impl Node {
    pub fn is_leaf(&self) -> bool {
        self.count & INTERIOR == 0
    }
}

#[derive(Clone, Debug, PartialEq, Default)]
pub struct Bvh {
    pub nodes: Vec<Node>,
    /// Packed primitive references (`scene::flat::PrimitiveRef::packed`), in leaf order.
    pub primitives: Vec<u32>,
    /// Levels below the root (a lone leaf: 0).
    pub depth: u32,
}

/// A primitive to place: its bounds and packed reference.
#[derive(Clone, Copy, Debug)]
pub struct Item {
    pub min: Vec3,
    pub max: Vec3,
    pub primitive: u32,
}

impl Item {
    #[inline]
    fn min(&self) -> Vec3A {
        Vec3A::from(self.min)
    }
    #[inline]
    fn max(&self) -> Vec3A {
        Vec3A::from(self.max)
    }
    #[inline]
    fn centroid(&self) -> Vec3A {
        0.5 * (self.min() + self.max())
    }
}

/// A box as SIMD vectors (the build's inner loops grow thousands of them).
#[derive(Clone, Copy)]
struct Bounds {
    min: Vec3A,
    max: Vec3A,
}

impl Bounds {
    const EMPTY: Bounds = Bounds {
        min: Vec3A::splat(f32::MAX),
        max: Vec3A::splat(f32::MIN),
    };
    #[inline]
    fn grow(self, min: Vec3A, max: Vec3A) -> Bounds {
        Bounds {
            min: self.min.min(min),
            max: self.max.max(max),
        }
    }
    fn half_area(&self) -> f32 {
        let d = (self.max - self.min).max(Vec3A::ZERO);
        d.x * d.y + d.y * d.z + d.z * d.x
    }
}

enum Tree {
    Leaf {
        bounds: Bounds,
        first: usize,
        count: usize,
    },
    Interior {
        bounds: Bounds,
        axis: usize,
        children: Box<[Tree; 2]>,
    },
}

impl Bvh {
    /// Builds the hierarchy over `items` (reordered in place into leaf order).
    pub fn build(items: &mut [Item]) -> Bvh {
        if items.is_empty() {
            return Bvh::default();
        }
        let (bounds, centroids) = bounds_of(items);
        let tree = build(items, 0, 0, bounds, centroids);
        let mut bvh = Bvh {
            nodes: Vec::with_capacity(2 * items.len() / MAX_LEAF + 1),
            primitives: items.iter().map(|i| i.primitive).collect(),
            depth: 0,
        };
        bvh.flatten(&tree, 0);
        bvh
    }

    fn flatten(&mut self, tree: &Tree, depth: u32) -> usize {
        self.depth = self.depth.max(depth);
        let at = self.nodes.len();
        match tree {
            Tree::Leaf {
                bounds,
                first,
                count,
            } => self.nodes.push(Node {
                min: bounds.min.into(),
                max: bounds.max.into(),
                offset: *first as u32,
                count: *count as u32,
            }),
            Tree::Interior {
                bounds,
                axis,
                children,
            } => {
                self.nodes.push(Node {
                    min: bounds.min.into(),
                    max: bounds.max.into(),
                    offset: 0,
                    count: INTERIOR | *axis as u32,
                });
                self.flatten(&children[0], depth + 1);
                let second = self.flatten(&children[1], depth + 1);
                self.nodes[at].offset = second as u32;
            }
        }
        at
    }
}

/// The bounds of `items` and of their centroids.
fn bounds_of(items: &[Item]) -> (Bounds, Bounds) {
    let fold = |(b, c): (Bounds, Bounds), i: &Item| {
        let centroid = i.centroid();
        (b.grow(i.min(), i.max()), c.grow(centroid, centroid))
    };
    if items.len() >= PARALLEL_BELOW * 4 {
        use rayon::prelude::*;
        items
            .par_chunks(PARALLEL_BELOW)
            .map(|chunk| chunk.iter().fold((Bounds::EMPTY, Bounds::EMPTY), fold))
            .reduce(
                || (Bounds::EMPTY, Bounds::EMPTY),
                |(a, b), (c, d)| (a.grow(c.min, c.max), b.grow(d.min, d.max)),
            )
    } else {
        items.iter().fold((Bounds::EMPTY, Bounds::EMPTY), fold)
    }
}

/// What a SAH bin gathers: its items' count, bounds and centroid bounds.
#[derive(Clone, Copy)]
struct Bin {
    count: usize,
    bounds: Bounds,
    centroids: Bounds,
}

impl Bin {
    const EMPTY: Bin = Bin {
        count: 0,
        bounds: Bounds::EMPTY,
        centroids: Bounds::EMPTY,
    };
    fn merge(self, o: Bin) -> Bin {
        Bin {
            count: self.count + o.count,
            bounds: self.bounds.grow(o.bounds.min, o.bounds.max),
            centroids: self.centroids.grow(o.centroids.min, o.centroids.max),
        }
    }
}

/// The items binned by `bin`, in parallel for large sets.
fn binned(items: &[Item], bin: &(impl Fn(&Item) -> usize + Sync)) -> [Bin; BINS] {
    let serial = |chunk: &[Item]| {
        let mut bins = [Bin::EMPTY; BINS];
        for item in chunk {
            let b = &mut bins[bin(item)];
            let c = item.centroid();
            b.count += 1;
            b.bounds = b.bounds.grow(item.min(), item.max());
            b.centroids = b.centroids.grow(c, c);
        }
        bins
    };
    if items.len() >= PARALLEL_BELOW * 4 {
        use rayon::prelude::*;
        let merge = |a: [Bin; BINS], b: [Bin; BINS]| std::array::from_fn(|k| a[k].merge(b[k]));
        items
            .par_chunks(PARALLEL_BELOW * 4)
            .map(serial)
            .reduce(|| [Bin::EMPTY; BINS], merge)
    } else {
        serial(items)
    }
}

/// The subtree over `items`, which start at `first` in the whole array, whose bounds and
/// centroid bounds are `bounds` and `centroids`.
fn build(
    items: &mut [Item],
    first: usize,
    depth: usize,
    bounds: Bounds,
    centroids: Bounds,
) -> Tree {
    let leaf = Tree::Leaf {
        bounds,
        first,
        count: items.len(),
    };
    if items.len() == 1 || depth + 1 >= MAX_DEPTH {
        return leaf;
    }
    let extent = centroids.max - centroids.min;
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let (split, children_bounds) = if extent[axis] > 0.0 {
        // Binned SAH along the widest centroid axis (Wald 2007).
        let (lo, scale) = (centroids.min[axis], BINS as f32 / extent[axis]);
        let bin = move |i: &Item| (((i.centroid()[axis] - lo) * scale) as usize).min(BINS - 1);
        let bins = binned(items, &bin);
        // Cost of splitting after bin k: area x count on each side.
        let mut left = [Bin::EMPTY; BINS];
        let mut running = Bin::EMPTY;
        for k in 0..BINS - 1 {
            running = running.merge(bins[k]);
            left[k] = running;
        }
        let (mut best, mut best_cost, mut best_right) = (0, f32::INFINITY, Bin::EMPTY);
        let mut right = Bin::EMPTY;
        for k in (0..BINS - 1).rev() {
            right = right.merge(bins[k + 1]);
            let cost = left[k].bounds.half_area() * left[k].count as f32
                + right.bounds.half_area() * right.count as f32;
            if cost < best_cost {
                (best, best_cost, best_right) = (k, cost, right);
            }
        }
        // A leaf costs one test per primitive; a split one box test plus the children's.
        let leaf_cost = items.len() as f32;
        let split_cost = 0.5 + best_cost / bounds.half_area().max(f32::MIN_POSITIVE);
        if items.len() <= MAX_LEAF && leaf_cost <= split_cost {
            return leaf;
        }
        let split = partition(items, |i| bin(i) <= best);
        (split, Some([left[best], best_right]))
    } else if items.len() <= MAX_LEAF {
        return leaf;
    } else {
        // Every centroid in one place: halves by position in the array.
        (items.len() / 2, None)
    };
    let (left, right) = items.split_at_mut(split);
    let [(lb, lc), (rb, rc)] = match children_bounds {
        Some(bins) => bins.map(|b| (b.bounds, b.centroids)),
        None => [bounds_of(left), bounds_of(right)],
    };
    let children = if left.len() + right.len() > PARALLEL_BELOW {
        let (a, b) = rayon::join(
            || build(left, first, depth + 1, lb, lc),
            || build(right, first + split, depth + 1, rb, rc),
        );
        [a, b]
    } else {
        [
            build(left, first, depth + 1, lb, lc),
            build(right, first + split, depth + 1, rb, rc),
        ]
    };
    Tree::Interior {
        bounds,
        axis,
        children: Box::new(children),
    }
}

/// Moves the items for which `left` holds to the front; returns how many there are.
fn partition(items: &mut [Item], left: impl Fn(&Item) -> bool) -> usize {
    let mut i = 0;
    for j in 0..items.len() {
        if left(&items[j]) {
            items.swap(i, j);
            i += 1;
        }
    }
    i
}

/// A safe reciprocal of a ray direction for slab tests: components below 1e-20 in size are
/// taken as 1e-20 (WGSL may not produce infinities), which only makes the test more generous.
#[inline]
pub fn inverse_direction(dir: Vec3) -> Vec3 {
    let safe = |d: f32| {
        if d.abs() < 1e-20 {
            if d < 0.0 { -1e-20 } else { 1e-20 }
        } else {
            d
        }
    };
    Vec3::new(1.0 / safe(dir.x), 1.0 / safe(dir.y), 1.0 / safe(dir.z))
}

/// Whether the ray from `origin` with reciprocal direction `inverse` meets the box within
/// [0, t_max]; the far distance is widened by 3 ulps' worth (pbrt-v4's 1 + 2 gamma(3)) so that
/// rounding cannot miss a box the ray grazes.
#[inline]
pub fn hits_box(min: Vec3, max: Vec3, origin: Vec3, inverse: Vec3, t_max: f32) -> bool {
    let t0 = (min - origin) * inverse;
    let t1 = (max - origin) * inverse;
    let near = t0.min(t1).max_element().max(0.0);
    let far = t0.max(t1).min_element().min(t_max) * BOX_FAR_WIDENING;
    near <= far
}

/// 1 + 2 gamma(3), gamma(n) = n eps / (1 - n eps), eps = 2^-24.
pub const BOX_FAR_WIDENING: f32 = 1.0 + 2.0 * (3.0 * 5.960_464_5e-8 / (1.0 - 3.0 * 5.960_464_5e-8));

#[cfg(test)]
mod tests {
    use super::*;

    fn random_items(n: usize) -> Vec<Item> {
        let mut state = 12345u64;
        let mut next = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        (0..n as u32)
            .map(|primitive| {
                let c = Vec3::new(next(), next(), next()) * 100.0;
                let h = Vec3::new(next(), next(), next());
                Item {
                    min: c - h,
                    max: c + h,
                    primitive,
                }
            })
            .collect()
    }

    /// Every primitive in exactly one leaf, bounds containing children and primitives, depth
    /// within the limit, leaves within MAX_LEAF.
    fn check(bvh: &Bvh, items: &[Item]) {
        let mut seen = vec![0u32; items.len()];
        let by_ref: std::collections::HashMap<u32, &Item> =
            items.iter().map(|i| (i.primitive, i)).collect();
        let contains = |outer: &Node, min: Vec3, max: Vec3| {
            outer.min.cmple(min).all() && outer.max.cmpge(max).all()
        };
        let mut stack = vec![(0usize, 0u32)];
        while let Some((i, depth)) = stack.pop() {
            let node = &bvh.nodes[i];
            assert!(depth <= bvh.depth && (depth as usize) < MAX_DEPTH);
            if node.is_leaf() {
                assert!(node.count >= 1 && node.count as usize <= MAX_LEAF);
                for &p in &bvh.primitives[node.offset as usize..][..node.count as usize] {
                    seen[p as usize] += 1;
                    let item = by_ref[&p];
                    assert!(contains(node, item.min, item.max));
                }
            } else {
                let (a, b) = (i + 1, node.offset as usize);
                assert!(b > a && b < bvh.nodes.len());
                for c in [a, b] {
                    assert!(contains(node, bvh.nodes[c].min, bvh.nodes[c].max));
                    stack.push((c, depth + 1));
                }
            }
        }
        assert!(
            seen.iter().all(|&n| n == 1),
            "a primitive is not in exactly one leaf"
        );
    }

    #[test]
    fn every_primitive_is_in_one_leaf_and_bounds_nest() {
        for n in [1, 2, 5, 100, 10_000, 50_000] {
            let mut items = random_items(n);
            let original = items.clone();
            let bvh = Bvh::build(&mut items);
            check(&bvh, &original);
        }
    }

    #[test]
    fn coincident_primitives_split_by_count() {
        let item = Item {
            min: Vec3::ZERO,
            max: Vec3::ONE,
            primitive: 0,
        };
        let mut items: Vec<Item> = (0..1000)
            .map(|primitive| Item { primitive, ..item })
            .collect();
        let original = items.clone();
        let bvh = Bvh::build(&mut items);
        check(&bvh, &original);
    }

    #[test]
    fn boxes_are_hit_conservatively() {
        let (min, max) = (Vec3::splat(-1.0), Vec3::splat(1.0));
        let o = Vec3::new(0.0, 0.0, -5.0);
        assert!(hits_box(min, max, o, inverse_direction(Vec3::Z), f32::MAX));
        assert!(!hits_box(min, max, o, inverse_direction(Vec3::Z), 3.9));
        assert!(!hits_box(
            min,
            max,
            o,
            inverse_direction(-Vec3::Z),
            f32::MAX
        ));
        // Along an axis, just inside a face's plane, and through a flat box.
        let grazing = Vec3::new(1.0 - 1e-7, 0.0, -5.0);
        assert!(hits_box(
            min,
            max,
            grazing,
            inverse_direction(Vec3::Z),
            f32::MAX
        ));
        let flat = (Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 0.0, 1.0));
        let down = Vec3::new(0.3, -1.0, 0.2).normalize();
        assert!(hits_box(
            flat.0,
            flat.1,
            Vec3::new(0.0, 2.0, 0.0),
            inverse_direction(down),
            f32::MAX
        ));
        // Parallel to the slab, outside it.
        let outside = Vec3::new(2.0, 0.0, -5.0);
        assert!(!hits_box(
            min,
            max,
            outside,
            inverse_direction(Vec3::Z),
            100.0
        ));
    }
}
