//! What a ray's BVH traversal reads, counted per ray, for `rt-gpu bench --stats`: the proxy for
//! a GPU's traversal cost where no GPU is at hand (issue 67). Two traversals are counted over
//! the same rays:
//!
//! - the kernel's ([`kernel_traverse`]): a model of the four-wide walk of `shaders/accel.wgsl`,
//!   step for step (a node's four quantized boxes read, the nearest child met entered, the
//!   others met pushed as one entry with the nearest one's entry distance; a top-level leaf's
//!   instances pushed and entered when popped);
//! - the CPU's: [`traverse_wide`] itself, its reads counted through the [`Leaves`] hooks.
//!
//! The rays are a render's two kinds: camera rays through every pixel (coherent) and rays
//! bounced off their hits in a cosine-distributed direction (incoherent, as a path tracer's
//! are after the first hit). Each ray's closest hit from both traversals is checked against
//! [`intersect`]'s, so the counts are of traversals that find what a render finds.

use super::accel::{Leaves, reach, traverse_wide};
use super::intersect::{hit_triangle, intersect, local_ray};
use crate::accel::quantized::{self, KERNEL_WIDTH, MISSED, NEAREST, nearest_first};
use crate::accel::wide::{EMPTY, TriangleBlock, WideNode};
use crate::accel::{BOX_FAR_WIDENING, box_entry, inverse_direction};
use crate::options::{RenderOptions, SamplerKind};
use crate::scene::flat::FlatScene;
use crate::shared::primitive::{PRIMITIVE_INDEX_BITS, PrimitiveRef};
use crate::shared::ray::{Ray, spawn};
use crate::shared::sampler::Sampler;
use crate::shared::warp::cosine_direction;
use rayon::prelude::*;

/// Bytes of one node of the kernel's hierarchy (`GpuBvhNode`: four children's quantized boxes
/// and references), read on entering an interior node.
pub const KERNEL_NODE_BYTES: u64 = std::mem::size_of::<crate::shared::layout::GpuBvhNode>() as u64;
/// What the kernel reads of a node to take a child from a stack entry: the texel of its
/// children's references (`bvh_child` in shaders/common.wgsl).
pub const KERNEL_CHILD_BYTES: u64 = 16;

/// Whether the CPU backend walks `scene`'s BVH (a scene of a few shapes is tested in turn).
pub fn cpu_traverses(scene: &FlatScene) -> bool {
    !scene.bvh.nodes.is_empty() && super::intersect::traverses_bvh(scene)
}

/// One traversal's reads, summed over rays.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Counts {
    pub rays: u64,
    /// The kernel's: its traversal loop's count (`loop_iterations` in shaders/accel.wgsl, at a
    /// weight of 1), the unit of lavapipe's loop budget: an iteration per interior node
    /// entered, a leaf's primitives and one more, a pass of the popping loop.
    pub iterations: u64,
    /// Interior nodes read (the kernel's: four wide, quantized; the CPU's: eight or four wide).
    pub nodes: u64,
    /// Bytes of those nodes (interior nodes only, on both sides: what leaves read is the
    /// primitives', counted in `primitives`), and the kernel's: a texel of its node for each
    /// child it takes from a stack entry.
    pub node_bytes: u64,
    /// Leaves whose primitives were tested (the CPU's triangle blocks among them: one block,
    /// its corners beside each other, for a subtree of few triangles).
    pub leaves: u64,
    /// Primitives tested (a triangle block's lanes in use each count).
    pub primitives: u64,
    /// Instances entered (the ray moved into a mesh's coordinates).
    pub instances: u64,
    /// The kernel's: `iterations` with each [`SIMD_LANES`] consecutive rays charged their
    /// slowest's (lavapipe runs every lane through every iteration of its group: a lower bound
    /// of what divergence costs there, whose lanes also wait on each other's leaf and popping
    /// loops).
    pub group_iterations: u64,
    /// Stack entries written (the kernel's: an entry put back with a child taken from it
    /// counts again).
    pub pushes: u64,
    /// The sum over rays of the deepest the stack got, and the deepest of all.
    pub stack_depth_sum: u64,
    pub stack_depth_max: u64,
}

impl Counts {
    fn add(mut self, o: Counts) -> Counts {
        self.rays += o.rays;
        self.iterations += o.iterations;
        self.group_iterations += o.group_iterations;
        self.nodes += o.nodes;
        self.node_bytes += o.node_bytes;
        self.leaves += o.leaves;
        self.primitives += o.primitives;
        self.instances += o.instances;
        self.pushes += o.pushes;
        self.stack_depth_sum += o.stack_depth_sum;
        self.stack_depth_max = self.stack_depth_max.max(o.stack_depth_max);
        self
    }

    /// A per-ray mean of a count.
    pub fn per_ray(&self, count: u64) -> f64 {
        count as f64 / self.rays.max(1) as f64
    }

    /// One ray's deepest stack, counted in.
    fn end_ray(&mut self, deepest: u64) {
        self.rays += 1;
        self.stack_depth_sum += deepest;
        self.stack_depth_max = self.stack_depth_max.max(deepest);
    }
}

/// Both traversals' counts over one kind of ray.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RayKindStats {
    pub kernel: Counts,
    pub wide: Counts,
    /// Rays whose closest hit a traversal found at another distance than `intersect` did (0
    /// unless the model has drifted from the kernel, or a scene's alpha-tested surfaces, which
    /// the count does not model, let a ray through).
    pub disagreements: u64,
}

impl RayKindStats {
    fn add(self, o: RayKindStats) -> RayKindStats {
        RayKindStats {
            kernel: self.kernel.add(o.kernel),
            wide: self.wide.add(o.wide),
            disagreements: self.disagreements + o.disagreements,
        }
    }
}

/// The counts of a scene's camera rays and their bounces.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TraversalStats {
    pub camera: RayKindStats,
    pub bounce: RayKindStats,
}

/// The rays counted: one camera ray through every pixel of an `opts.width` x `opts.height`
/// image, and a bounce in a cosine-distributed direction from each one's hit. The same scene
/// and size give the same rays.
pub fn stats_rays(scene: &FlatScene, opts: &RenderOptions) -> [Vec<Ray>; 2] {
    let width = opts.width;
    let rows: Vec<(Vec<Ray>, Vec<Ray>)> = (0..opts.height)
        .into_par_iter()
        .map(|y| {
            let (mut cameras, mut bounces) = (Vec::new(), Vec::new());
            for x in 0..width {
                let pixel = y * width + x;
                let mut sampler = Sampler::for_sample(SamplerKind::Independent, pixel, 0, 1);
                let camera = super::camera::generate_ray(&scene.camera, opts, x, y, &mut sampler);
                cameras.push(camera);
                if let Some(hit) = intersect(scene, &camera) {
                    let (u1, u2) = (sampler.next_f32(), sampler.next_f32());
                    bounces.push(spawn(&hit, cosine_direction(hit.normal, u1, u2)));
                }
            }
            (cameras, bounces)
        })
        .collect();
    let (cameras, bounces) = rows.into_iter().unzip::<_, _, Vec<_>, Vec<_>>();
    [cameras.concat(), bounces.concat()]
}

/// The rays of one SIMD group in `Counts::group_iterations`: lavapipe's 8 lanes of 32 bits at
/// 256 bits (4 at 128), a row of 8 pixels of a workgroup (camera rays, at a width that is a
/// multiple of 8; bounces are 8 successive hits).
pub const SIMD_LANES: usize = 8;

/// Both traversals' counts over [`stats_rays`]; `None` when the scene has no BVH.
pub fn traversal_stats(scene: &FlatScene, opts: &RenderOptions) -> Option<TraversalStats> {
    if scene.bvh.nodes.is_empty() {
        return None;
    }
    let [cameras, bounces] = stats_rays(scene, opts);
    Some(TraversalStats {
        camera: group_stats(scene, &cameras),
        bounce: group_stats(scene, &bounces),
    })
}

/// Both traversals' counts over `rays`, taken as SIMD groups of [`SIMD_LANES`] adjacent rays
/// (a row's pixels; a bounce's, those whose camera ray hit) for `Counts::group_iterations`.
pub fn group_stats(scene: &FlatScene, rays: &[Ray]) -> RayKindStats {
    rays.par_chunks(SIMD_LANES)
        .map(|group| {
            let each: Vec<RayKindStats> = group.iter().map(|r| count_ray(scene, r)).collect();
            let slowest = each.iter().map(|s| s.kernel.iterations).max().unwrap_or(0);
            let mut sum = (each.into_iter()).fold(RayKindStats::default(), RayKindStats::add);
            sum.kernel.group_iterations = slowest * group.len() as u64;
            sum
        })
        .reduce(RayKindStats::default, RayKindStats::add)
}

/// One ray through both traversals, checked against `intersect`.
pub fn count_ray(scene: &FlatScene, ray: &Ray) -> RayKindStats {
    let expected = intersect(scene, ray).map_or(f32::INFINITY, |hit| hit.t);
    let mut out = RayKindStats::default();
    let mut closest = f32::INFINITY;
    kernel_traverse(scene, ray, &mut closest, &mut out.kernel);
    let kernel_agrees = closest == expected;
    let mut closest = f32::INFINITY;
    let mut counting = Counting {
        scene,
        ray,
        counts: &mut out.wide,
        deepest: 0,
        in_instance: false,
    };
    let wide = &scene.wide_bvh;
    traverse_wide(
        wide,
        &scene.bvh,
        wide.root,
        ray,
        &mut closest,
        &mut counting,
    );
    let deepest = counting.deepest;
    out.wide.end_ray(deepest);
    out.disagreements = (!kernel_agrees || closest != expected) as u64;
    out
}

/// Where the ray meets primitive `packed` (a top-level one: a shape or a placed triangle)
/// before `t_max`. Alpha-tested surfaces count as opaque.
fn hit_primitive(scene: &FlatScene, packed: u32, ray: &Ray, t_max: f32) -> Option<f32> {
    match PrimitiveRef::unpacked(packed) {
        PrimitiveRef::Shape { kind, index } => {
            scene.shapes.hit(kind, index, ray, t_max).map(|h| h.0)
        }
        PrimitiveRef::Triangle(i) => {
            hit_triangle(&scene.triangles[i as usize], ray, 0.0, t_max).map(|h| h.0)
        }
        PrimitiveRef::Instance(_) => unreachable!("instances are entered, not hit"),
    }
}

/// An instanced mesh's triangle `packed` (as its leaves hold it) along the ray in the mesh's
/// coordinates.
fn hit_mesh_triangle(scene: &FlatScene, packed: u32, local: &Ray, t_max: f32) -> Option<f32> {
    let triangle = packed & ((1 << PRIMITIVE_INDEX_BITS) - 1);
    hit_triangle(&scene.triangles[triangle as usize], local, 0.0, t_max).map(|h| h.0)
}

/// A stack entry of the kernel's walk: an interior node's children left to enter
/// (`quantized::group_entry`) and the distance at which the ray enters the nearest one's box,
/// or an instance to enter.
#[derive(Clone, Copy)]
enum Entry {
    Group(u32, f32),
    Instance(u32),
}

/// The kernel's traversal (`traverse` in shaders/accel.wgsl), counting what it reads: the
/// closest hit's distance in `closest`. An interior node's read tests its children's quantized
/// boxes; the ray enters the nearest child met and pushes one entry for the others met, nearest
/// first, with the nearest one's entry distance; a leaf (entered, never read: its reference
/// holds its range) tests its primitives and pushes its instances; popping drops entries whose
/// nearest box now lies beyond the closest hit, enters an entry's next child (putting the rest
/// back), and an instance's entry moves the ray into its mesh and descends from the mesh's root
/// until the stack is back at the height it had then.
pub fn kernel_traverse(scene: &FlatScene, world: &Ray, closest: &mut f32, counts: &mut Counts) {
    use crate::shared::layout::{BVH_LEAF, BVH_LEAF_COUNT_SHIFT, BVH_LEAF_OFFSET_LIMIT};
    let kernel = scene.kernel_bvh();
    let primitives = &scene.bvh.primitives;
    let mut ray = *world;
    let mut inverse = inverse_direction(ray.dir);
    let mut stack: Vec<Entry> = Vec::with_capacity(64);
    let mut deepest = 0;
    // The stack's height when the ray entered the instance it is in.
    let mut instance: Option<usize> = None;
    let mut entering = kernel.root;
    loop {
        counts.iterations += 1;
        let mut pop = false;
        if entering & BVH_LEAF == 0 {
            counts.nodes += 1;
            counts.node_bytes += KERNEL_NODE_BYTES;
            let node = &kernel.nodes[entering as usize];
            let keys: [f32; KERNEL_WIDTH] = std::array::from_fn(|lane| {
                let (min, max) = node.child_box(lane);
                let entry = (lane < node.count as usize)
                    .then(|| box_entry(min, max, ray.origin, inverse, *closest))
                    .flatten();
                entry.map_or(MISSED, |t| t.min(NEAREST))
            });
            let lanes = std::array::from_fn(|lane| {
                if keys[lane] == MISSED {
                    quantized::EMPTY
                } else {
                    lane as u32
                }
            });
            let ordered = nearest_first(keys, lanes);
            let others: Vec<u32> = (ordered[1..].iter())
                .map(|o| o.1)
                .take_while(|&lane| lane != quantized::EMPTY)
                .collect();
            if !others.is_empty() {
                stack.push(Entry::Group(
                    quantized::group_entry(entering, &others),
                    ordered[1].0,
                ));
                counts.pushes += 1;
                deepest = deepest.max(stack.len() as u64);
            }
            pop = ordered[0].1 == quantized::EMPTY;
            if !pop {
                entering = node.children[ordered[0].1 as usize];
            }
        }
        if !pop && entering & BVH_LEAF != 0 {
            let first = (entering & (BVH_LEAF_OFFSET_LIMIT - 1)) as usize;
            let count = ((entering & !BVH_LEAF) >> BVH_LEAF_COUNT_SHIFT) as usize;
            counts.leaves += 1;
            counts.iterations += count as u64 + 1;
            for &packed in &primitives[first..first + count] {
                counts.primitives += 1;
                if instance.is_some() {
                    if let Some(t) = hit_mesh_triangle(scene, packed, &ray, reach(*closest)) {
                        *closest = closest.min(t);
                    }
                    continue;
                }
                if let PrimitiveRef::Instance(i) = PrimitiveRef::unpacked(packed) {
                    stack.push(Entry::Instance(i));
                    counts.pushes += 1;
                    deepest = deepest.max(stack.len() as u64);
                    continue;
                }
                if let Some(t) = hit_primitive(scene, packed, &ray, reach(*closest)) {
                    *closest = closest.min(t);
                }
            }
            pop = true;
        }
        if pop {
            loop {
                counts.iterations += 1;
                if let Some(floor) = instance
                    && stack.len() == floor
                {
                    instance = None;
                    ray = *world;
                    inverse = inverse_direction(ray.dir);
                }
                let Some(top) = stack.pop() else {
                    let bound = kernel.stack_bound(scene.largest_instance_leaf());
                    debug_assert!(deepest <= bound as u64, "{deepest} entries, {bound} held");
                    counts.end_ray(deepest);
                    return;
                };
                match top {
                    Entry::Group(word, t_entry) => {
                        if t_entry <= *closest * BOX_FAR_WIDENING {
                            let (lane, rest) = quantized::group_next(word);
                            let node = word & (quantized::GROUP_NODE_LIMIT - 1);
                            entering = kernel.nodes[node as usize].children[lane as usize];
                            counts.node_bytes += KERNEL_CHILD_BYTES;
                            if let Some(rest) = rest {
                                stack.push(Entry::Group(rest, t_entry));
                                counts.pushes += 1;
                            }
                            break;
                        }
                    }
                    Entry::Instance(i) => {
                        counts.instances += 1;
                        let inst = &scene.instances[i as usize];
                        instance = Some(stack.len());
                        ray = local_ray(inst, world);
                        inverse = inverse_direction(ray.dir);
                        entering = kernel.instance_roots[i as usize];
                        break;
                    }
                }
            }
        }
    }
}

/// The CPU's wide traversal's leaves, counting: the closest hit's distance only, an instance
/// descended into through the same traversal (on a stack of its own: the deepest stack is
/// either level's).
struct Counting<'a> {
    scene: &'a FlatScene,
    ray: &'a Ray,
    counts: &'a mut Counts,
    deepest: u64,
    /// Whether `ray` is in an instance's mesh, whose leaves hold its triangles.
    in_instance: bool,
}

impl Leaves for Counting<'_> {
    fn primitive(&mut self, packed: u32, closest: &mut f32) {
        self.counts.primitives += 1;
        let scene = self.scene;
        if self.in_instance {
            if let Some(t) = hit_mesh_triangle(scene, packed, self.ray, reach(*closest)) {
                *closest = closest.min(t);
            }
            return;
        }
        if let PrimitiveRef::Instance(i) = PrimitiveRef::unpacked(packed) {
            self.counts.instances += 1;
            let inst = &scene.instances[i as usize];
            let local = local_ray(inst, self.ray);
            let mut inside = Counting {
                scene,
                ray: &local,
                counts: self.counts,
                deepest: 0,
                in_instance: true,
            };
            let wide = &scene.wide_bvh;
            let root = wide.instance_roots[i as usize];
            traverse_wide(wide, &scene.bvh, root, &local, closest, &mut inside);
            self.deepest = self.deepest.max(inside.deepest);
            return;
        }
        if let Some(t) = hit_primitive(scene, packed, self.ray, reach(*closest)) {
            *closest = closest.min(t);
        }
    }

    fn triangle(&mut self, _: u32, hit: (f32, f32, f32), closest: &mut f32) {
        if hit.0 < reach(*closest) {
            *closest = closest.min(hit.0);
        }
    }

    fn read_node(&mut self) {
        self.counts.nodes += 1;
        self.counts.node_bytes += std::mem::size_of::<WideNode>() as u64;
    }

    fn read_block(&mut self, block: &TriangleBlock) {
        self.counts.leaves += 1;
        self.counts.primitives += block.triangles.iter().filter(|&&t| t != EMPTY).count() as u64;
    }

    fn enter_list(&mut self) {
        self.counts.leaves += 1;
    }

    fn pushed(&mut self, height: usize) {
        self.counts.pushes += 1;
        self.deepest = self.deepest.max(height as u64);
    }
}
