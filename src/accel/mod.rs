//! The bounding volume hierarchy both backends traverse (CPU: `cpu/accel.rs`, collapsed by
//! `wide`; GPU: `shaders/accel.wgsl`, collapsed by `quantized`): built once on the host over every primitive of a flat scene (spheres,
//! quads, triangles) by binned SAH, in parallel, and flattened depth-first into a compact node
//! array: an interior node's first child follows it, its second is at `offset`; a leaf's
//! primitives are `primitives[offset .. offset + count]`.

pub mod quantized;
pub mod wide;

use glam::{Vec3, Vec3A};

/// Most primitives a leaf holds, except at the depth limit.
pub const MAX_LEAF: usize = 4;
/// Most levels: the CPU's traversal stack is sized for this many (the kernel's is sized to the
/// scene's hierarchy: `BVH_STACK` in src/gpu/shader.rs).
pub const MAX_DEPTH: usize = 48;
/// `count` of an interior node: this bit, and the split axis in the low two bits.
pub const INTERIOR: u32 = 1 << 31;
/// SAH bins per split.
const BINS: usize = 16;
/// Below this many primitives a subtree is built on the current thread.
const PARALLEL_BELOW: usize = 4096;
/// Up to this many primitives a node's split is chosen exactly, by sorting them (cheaper there
/// than binning, and never worse).
const SORTED_UP_TO: usize = 16;

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

/// A primitive to place: its bounds and packed reference. 16-byte aligned, hence 32 bytes, so
/// that the partition's swaps move two whole vectors (28 bytes stalled on store forwarding).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(16))]
pub struct Item {
    pub min: Vec3,
    pub max: Vec3,
    pub primitive: u32,
    /// The build's scratch, in what would be padding: the item's SAH bin along each axis at
    /// the node being split, kept by the binning for the partition that follows it.
    bins: [u8; 4],
}

impl Item {
    pub fn new(min: Vec3, max: Vec3, primitive: u32) -> Self {
        Item {
            min,
            max,
            primitive,
            bins: [0; 4],
        }
    }

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

/// A subtree as built: below `PARALLEL_BELOW` primitives straight into a node array of its own
/// (offsets relative to its start); above, the levels split across threads, joined once at the
/// end so that every node is copied once.
enum Part {
    Nodes {
        nodes: Vec<Node>,
        depth: usize,
    },
    Split {
        node: Node,
        children: Box<[Part; 2]>,
    },
}

impl Bvh {
    /// Builds the hierarchy over `items` (reordered in place into leaf order).
    pub fn build(items: &mut [Item]) -> Bvh {
        if items.is_empty() {
            return Bvh::default();
        }
        let (bounds, centroids) = bounds_of(items);
        let part = build(items, 0, 0, bounds, centroids);
        let mut bvh = Bvh {
            nodes: Vec::with_capacity(2 * items.len() / 3 + 1),
            primitives: items.iter().map(|i| i.primitive).collect(),
            depth: 0,
        };
        bvh.depth = bvh.append(part) as u32;
        bvh
    }

    /// Appends `other`'s nodes and primitives after this hierarchy's (a second level, reached
    /// from an instance); returns the index of its root.
    pub fn append_hierarchy(&mut self, other: Bvh) -> u32 {
        let node_base = self.nodes.len() as u32;
        let primitive_base = self.primitives.len() as u32;
        self.nodes.extend(other.nodes.into_iter().map(|mut node| {
            node.offset += if node.is_leaf() {
                primitive_base
            } else {
                node_base
            };
            node
        }));
        self.primitives.extend(other.primitives);
        self.depth = self.depth.max(other.depth);
        node_base
    }

    /// Appends a built part's nodes; returns its depth.
    fn append(&mut self, part: Part) -> usize {
        match part {
            Part::Nodes { nodes, depth } => {
                let base = self.nodes.len() as u32;
                self.nodes.extend(nodes.into_iter().map(|mut node| {
                    if !node.is_leaf() {
                        node.offset += base;
                    }
                    node
                }));
                depth
            }
            Part::Split { node, children } => {
                let at = self.nodes.len();
                self.nodes.push(node);
                let [first, second] = *children;
                let depth = self.append(first);
                self.nodes[at].offset = self.nodes.len() as u32;
                depth.max(self.append(second))
            }
        }
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

/// The items binned along each axis by `bins_of`, in parallel for large sets; each item keeps
/// its bins.
fn binned(
    items: &mut [Item],
    bins_of: &(impl Fn(&Item) -> glam::IVec3 + Sync),
) -> [[Bin; BINS]; 3] {
    let serial = |chunk: &mut [Item]| {
        let mut bins = [[Bin::EMPTY; BINS]; 3];
        for item in chunk {
            let at = bins_of(item);
            item.bins = [at.x as u8, at.y as u8, at.z as u8, 0];
            let c = item.centroid();
            for (axis, axis_bins) in bins.iter_mut().enumerate() {
                let b = &mut axis_bins[at[axis] as usize];
                b.count += 1;
                b.bounds = b.bounds.grow(item.min(), item.max());
                b.centroids = b.centroids.grow(c, c);
            }
        }
        bins
    };
    if items.len() >= PARALLEL_BELOW * 4 {
        use rayon::prelude::*;
        let merge = |a: [[Bin; BINS]; 3], b: [[Bin; BINS]; 3]| {
            std::array::from_fn(|axis| std::array::from_fn(|k| a[axis][k].merge(b[axis][k])))
        };
        items
            .par_chunks_mut(PARALLEL_BELOW * 4)
            .map(serial)
            .reduce(|| [[Bin::EMPTY; BINS]; 3], merge)
    } else {
        serial(items)
    }
}

/// How a node's items are divided: at `at` (after `partition`), each side with its bounds and
/// centroid bounds.
struct Split {
    at: usize,
    axis: usize,
    children: [(Bounds, Bounds); 2],
}

/// The subtree over `items`, which start at `first` in the whole array, whose bounds and
/// centroid bounds are `bounds` and `centroids`; large ones split across threads.
fn build(
    items: &mut [Item],
    first: usize,
    depth: usize,
    bounds: Bounds,
    centroids: Bounds,
) -> Part {
    if items.len() <= PARALLEL_BELOW {
        let mut nodes = Vec::with_capacity(items.len());
        let depth = build_into(items, first, depth, bounds, centroids, &mut nodes);
        return Part::Nodes { nodes, depth };
    }
    let Some(Split { at, axis, children }) = split(items, depth, bounds, centroids) else {
        return Part::Nodes {
            nodes: vec![leaf(bounds, first, items.len())],
            depth,
        };
    };
    let (left, right) = items.split_at_mut(at);
    let [(lb, lc), (rb, rc)] = children;
    let (a, b) = rayon::join(
        || build(left, first, depth + 1, lb, lc),
        || build(right, first + at, depth + 1, rb, rc),
    );
    Part::Split {
        node: interior(bounds, axis),
        children: Box::new([a, b]),
    }
}

/// Builds the subtree over `items` depth-first into `nodes`; returns its deepest level.
fn build_into(
    items: &mut [Item],
    first: usize,
    depth: usize,
    bounds: Bounds,
    centroids: Bounds,
    nodes: &mut Vec<Node>,
) -> usize {
    let Some(Split { at, axis, children }) = split(items, depth, bounds, centroids) else {
        nodes.push(leaf(bounds, first, items.len()));
        return depth;
    };
    let node = nodes.len();
    nodes.push(interior(bounds, axis));
    let (left, right) = items.split_at_mut(at);
    let [(lb, lc), (rb, rc)] = children;
    let left_depth = build_into(left, first, depth + 1, lb, lc, nodes);
    let second = nodes.len();
    nodes[node].offset = second as u32;
    left_depth.max(build_into(right, first + at, depth + 1, rb, rc, nodes))
}

fn leaf(bounds: Bounds, first: usize, count: usize) -> Node {
    Node {
        min: bounds.min.into(),
        max: bounds.max.into(),
        offset: first as u32,
        count: count as u32,
    }
}

/// An interior node; its second child's index is filled in once known.
fn interior(bounds: Bounds, axis: usize) -> Node {
    Node {
        min: bounds.min.into(),
        max: bounds.max.into(),
        offset: 0,
        count: INTERIOR | axis as u32,
    }
}

/// Chooses where to divide `items` (and partitions them), or `None` for a leaf: a leaf costs one
/// test per primitive, a split one box test plus its children's, weighed by surface area.
fn split(items: &mut [Item], depth: usize, bounds: Bounds, centroids: Bounds) -> Option<Split> {
    let n = items.len();
    if n == 1 || depth + 1 >= MAX_DEPTH {
        return None;
    }
    let extent = centroids.max - centroids.min;
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    if extent[axis] <= 0.0 {
        if n <= MAX_LEAF {
            return None;
        }
        // Every centroid in one place.
        return Some(halves(items, axis));
    }
    let leaf_cost = n as f32;
    let area = bounds.half_area().max(f32::MIN_POSITIVE);
    if n <= SORTED_UP_TO {
        // Few items: every split between their sorted centroids along each axis, costed exactly.
        // Each axis's order is sorted as indices by the centroids worked out once (stably, as
        // `sort_by` would order the items); the items move once, into the chosen order.
        let centroids: [Vec3A; SORTED_UP_TO] =
            std::array::from_fn(|k| items.get(k).map_or(Vec3A::ZERO, Item::centroid));
        let mut orders = [[0u8; SORTED_UP_TO]; 3];
        let (mut best_axis, mut best, mut best_cost) = (axis, 1, f32::INFINITY);
        for a in (0..3).filter(|&a| extent[a] > 0.0) {
            let order = &mut orders[a][..n];
            stable_order(order, |k| centroids[k][a]);
            let item = |k: usize| &items[order[k] as usize];
            let mut right = [Bounds::EMPTY; SORTED_UP_TO];
            let mut running = Bounds::EMPTY;
            for k in (1..n).rev() {
                running = running.grow(item(k).min(), item(k).max());
                right[k] = running;
            }
            let mut left = Bounds::EMPTY;
            for (k, right) in right.iter().enumerate().take(n).skip(1) {
                left = left.grow(item(k - 1).min(), item(k - 1).max());
                let cost = left.half_area() * k as f32 + right.half_area() * (n - k) as f32;
                if cost < best_cost {
                    (best_axis, best, best_cost) = (a, k, cost);
                }
            }
        }
        if n <= MAX_LEAF && leaf_cost <= 0.5 + best_cost / area {
            return None;
        }
        let before: [Item; SORTED_UP_TO] = std::array::from_fn(|k| items[k.min(n - 1)]);
        for (item, &k) in items.iter_mut().zip(&orders[best_axis][..n]) {
            *item = before[k as usize];
        }
        let (left, right) = items.split_at(best);
        return Some(Split {
            at: best,
            axis: best_axis,
            children: [bounds_of(left), bounds_of(right)],
        });
    }
    // Binned SAH along each axis the centroids spread over (Wald 2007).
    // The bin of a centroid, ((min + max) / 2 - lo) * BINS / extent, per axis at once. An
    // extent too small for its reciprocal to be finite counts as none.
    let scale = 0.5 * BINS as f32 / extent;
    let spread = extent.cmpgt(Vec3A::ZERO) & scale.is_finite_mask();
    let scale = Vec3A::select(spread, scale, Vec3A::ZERO);
    let offset = centroids.min * scale * 2.0;
    let bins_of = move |i: &Item| {
        let at = (i.min() + i.max()) * scale - offset;
        // Clamped as floats first, where it is cheaper; `as` then saturates and maps NaN to 0.
        at.clamp(Vec3A::ZERO, Vec3A::splat(BINS as f32 - 1.0))
            .as_ivec3()
    };
    let bins = binned(items, &bins_of);
    let (mut best_axis, mut best, mut best_cost) = (axis, 0, f32::INFINITY);
    let (mut best_left, mut best_right) = (Bin::EMPTY, Bin::EMPTY);
    for a in (0..3).filter(|&a| spread.test(a)) {
        // Cost of splitting after bin k: area x count on each side.
        let mut left = [Bin::EMPTY; BINS];
        let mut running = Bin::EMPTY;
        for k in 0..BINS - 1 {
            running = running.merge(bins[a][k]);
            left[k] = running;
        }
        let mut right = Bin::EMPTY;
        for k in (0..BINS - 1).rev() {
            right = right.merge(bins[a][k + 1]);
            if left[k].count == 0 || right.count == 0 {
                continue;
            }
            let cost = left[k].bounds.half_area() * left[k].count as f32
                + right.bounds.half_area() * right.count as f32;
            if cost < best_cost {
                (best_axis, best, best_cost) = (a, k, cost);
                (best_left, best_right) = (left[k], right);
            }
        }
    }
    if n <= MAX_LEAF && leaf_cost <= 0.5 + best_cost / area {
        return None;
    }
    if best_cost == f32::INFINITY {
        // Every item in one bin on every axis (centroids too close together, or not finite).
        return Some(halves(items, axis));
    }
    let at = partition(items, |i| i.bins[best_axis] as usize <= best);
    Some(Split {
        at,
        axis: best_axis,
        children: [best_left, best_right].map(|b| (b.bounds, b.centroids)),
    })
}

/// `order` set to the indices 0.. sorted by `key` (ties in index order): an insertion sort, as
/// `sort_by` does so few, on indices rather than the items.
fn stable_order(order: &mut [u8], key: impl Fn(usize) -> f32) {
    for i in 0..order.len() {
        let k = key(i);
        let mut j = i;
        while j > 0 && key(order[j - 1] as usize).total_cmp(&k).is_gt() {
            order[j] = order[j - 1];
            j -= 1;
        }
        order[j] = i as u8;
    }
}

/// `items` split in halves by position in the array: where their centroids tell nothing apart.
fn halves(items: &[Item], axis: usize) -> Split {
    let (left, right) = items.split_at(items.len() / 2);
    Split {
        at: left.len(),
        axis,
        children: [bounds_of(left), bounds_of(right)],
    }
}

/// Moves the items for which `left` holds to the front; returns how many there are. Hoare's
/// scheme from both ends: only misplaced items move, each once (the build's largest cost is
/// this memory traffic).
fn partition(items: &mut [Item], left: impl Fn(&Item) -> bool) -> usize {
    let (mut i, mut j) = (0, items.len());
    loop {
        while i < j && left(&items[i]) {
            i += 1;
        }
        while i < j && !left(&items[j - 1]) {
            j -= 1;
        }
        if i + 1 >= j {
            return i;
        }
        items.swap(i, j - 1);
        i += 1;
        j -= 1;
    }
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

/// Where the ray from `origin` with reciprocal direction `inverse` enters the box, if it meets
/// it within [0, t_max]; the far distance is widened by 3 ulps' worth (pbrt-v4's 1 + 2 gamma(3))
/// so that rounding cannot miss a box the ray grazes.
#[inline]
pub fn box_entry(min: Vec3, max: Vec3, origin: Vec3, inverse: Vec3, t_max: f32) -> Option<f32> {
    let t0 = (min - origin) * inverse;
    let t1 = (max - origin) * inverse;
    let near = t0.min(t1).max_element().max(0.0);
    let far = t0.max(t1).min_element().min(t_max) * BOX_FAR_WIDENING;
    (near <= far).then_some(near)
}

/// 1 + 2 gamma(3), gamma(n) = n eps / (1 - n eps), eps = 2^-24.
pub const BOX_FAR_WIDENING: f32 = 1.0 + 2.0 * (3.0 * 5.960_464_5e-8 / (1.0 - 3.0 * 5.960_464_5e-8));

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Numbers in [0, 1), the same sequence for the same `seed`.
    pub(crate) fn numbers(seed: u64) -> impl FnMut() -> f32 {
        let mut state = seed;
        move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 40) as f32 / (1u64 << 24) as f32
        }
    }

    /// `n` boxes scattered in a 100-unit cube, the same every call.
    pub(crate) fn random_items(n: usize) -> Vec<Item> {
        let mut next = numbers(12345);
        (0..n as u32)
            .map(|primitive| {
                let c = Vec3::new(next(), next(), next()) * 100.0;
                let h = Vec3::new(next(), next(), next());
                Item::new(c - h, c + h, primitive)
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

    /// The sorted path's index order is `sort_by`'s order of the items, ties (many, from
    /// keys on a coarse grid, and -0 against +0) in their first order.
    #[test]
    fn index_order_is_a_stable_sort() {
        let mut next = numbers(7);
        for n in 1..=SORTED_UP_TO {
            for _ in 0..200 {
                let keys: Vec<f32> = (0..n).map(|_| (next() * 4.0).floor() - 2.0).collect();
                let keys: Vec<f32> = keys
                    .iter()
                    .map(|&k| if k == 0.0 && next() < 0.5 { -0.0 } else { k })
                    .collect();
                let mut order = [0u8; SORTED_UP_TO];
                stable_order(&mut order[..n], |k| keys[k]);
                let mut expected: Vec<usize> = (0..n).collect();
                expected.sort_by(|&a, &b| keys[a].total_cmp(&keys[b]));
                let order: Vec<usize> = order[..n].iter().map(|&k| k as usize).collect();
                assert_eq!(order, expected, "{keys:?}");
            }
        }
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
    fn appended_hierarchies_keep_their_structure() {
        let mut top_items = random_items(100);
        let mut top = Bvh::build(&mut top_items);
        let mut mesh_items = random_items(1000);
        let original = mesh_items.clone();
        let mesh = Bvh::build(&mut mesh_items);
        let (nodes, primitives) = (top.nodes.len(), top.primitives.len());
        let root = top.append_hierarchy(mesh.clone());
        assert_eq!(root as usize, nodes);
        assert_eq!(top.primitives[primitives..], mesh.primitives[..]);
        // Every node of the appended hierarchy points where it did, moved by the offsets.
        for (i, node) in mesh.nodes.iter().enumerate() {
            let moved = top.nodes[nodes + i];
            let base = if node.is_leaf() { primitives } else { nodes };
            assert_eq!(moved.offset as usize, node.offset as usize + base);
            assert_eq!(
                (moved.min, moved.max, moved.count),
                (node.min, node.max, node.count)
            );
        }
        // Checked from its own root, it is the hierarchy it was.
        let from_root = Bvh {
            nodes: top.nodes[nodes..]
                .iter()
                .map(|n| Node {
                    offset: n.offset - if n.is_leaf() { primitives } else { nodes } as u32,
                    ..*n
                })
                .collect(),
            primitives: top.primitives[primitives..].to_vec(),
            depth: mesh.depth,
        };
        check(&from_root, &original);
        assert!(top.depth >= mesh.depth);
    }

    #[test]
    fn coincident_primitives_split_by_count() {
        let item = Item::new(Vec3::ZERO, Vec3::ONE, 0);
        let mut items: Vec<Item> = (0..1000)
            .map(|primitive| Item { primitive, ..item })
            .collect();
        let original = items.clone();
        let bvh = Bvh::build(&mut items);
        check(&bvh, &original);
    }

    /// Two thin layers, 100 apart in y, each spread 400 wide in x: the centroids spread widest
    /// in x, but only a split in y separates the layers. The best split is sought on every
    /// axis, both where it is binned (many items) and where it is sorted (few).
    #[test]
    fn the_split_is_sought_on_every_axis() {
        for n in [16, 1000] {
            let mut next = numbers(7);
            let mut items: Vec<Item> = (0..n as u32)
                .map(|primitive| {
                    let y = if primitive % 2 == 0 { 0.0 } else { 100.0 };
                    let c = Vec3::new(400.0 * next(), y, 10.0 * next());
                    Item::new(c - 1.0, c + 1.0, primitive)
                })
                .collect();
            let original = items.clone();
            let bvh = Bvh::build(&mut items);
            check(&bvh, &original);
            let root = &bvh.nodes[0];
            assert_eq!(
                root.count,
                INTERIOR | 1,
                "{n} items: the root splits on axis y"
            );
            let (first, second) = (&bvh.nodes[1], &bvh.nodes[root.offset as usize]);
            assert!(
                first.max.y < second.min.y || second.max.y < first.min.y,
                "{n} items: the root's children overlap in y"
            );
        }
    }

    /// Centroids apart by less than f32's reciprocal resolves (the bins' scale would be
    /// infinite): the builder still gives a valid tree, each item within its leaf's bounds.
    #[test]
    fn centroids_closer_than_a_bin_resolves_still_split() {
        for n in [20, 1000] {
            let mut items: Vec<Item> = (0..n as u32)
                .map(|primitive| {
                    let z = if primitive % 2 == 0 { 0.0 } else { 1e-40 };
                    Item::new(Vec3::new(0.0, 0.0, z), Vec3::new(1.0, 1.0, z), primitive)
                })
                .collect();
            let original = items.clone();
            let bvh = Bvh::build(&mut items);
            check(&bvh, &original);
        }
    }

    fn hits_box(min: Vec3, max: Vec3, origin: Vec3, inverse: Vec3, t_max: f32) -> bool {
        box_entry(min, max, origin, inverse, t_max).is_some()
    }

    #[test]
    fn boxes_are_hit_conservatively() {
        let (min, max) = (Vec3::splat(-1.0), Vec3::splat(1.0));
        let o = Vec3::new(0.0, 0.0, -5.0);
        assert_eq!(
            box_entry(min, max, o, inverse_direction(Vec3::Z), 10.0),
            Some(4.0)
        );
        assert_eq!(
            box_entry(min, max, Vec3::ZERO, inverse_direction(Vec3::Z), 10.0),
            Some(0.0)
        );
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
