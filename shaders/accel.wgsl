// BVH traversal (its model, step for step: `kernel_traverse` in src/cpu/traversal_stats.rs):
// depth-first over the four-wide hierarchy of src/accel/quantized.rs; an interior node tests
// its children's quantized boxes, enters the nearest by entry distance and pushes one entry
// for the others met (`group_entry` there: the node and their lanes, nearest first) with the
// nearest one's distance, on a stack in private memory. Nodes are read as
// `gpu_bvh` in src/gpu/layout.rs lays them out: an interior node holds its children's boxes
// and references, so entering a node is one read and a leaf's primitives are known from its
// reference.
//
// Lavapipe silently breaks every loop of an invocation once its SIMD group has run 65 535 loop
// iterations in all, and a traversal's length depends on the ray. So a kernel for a software
// adapter, and a debug kernel (LOOP_BUDGET, set by the renderer: a hardware GPU's render kernel
// carries none of this) counts: the
// host's bound on every other loop of a sample is added at the sample's start, and each
// traversal iteration (and pass of its popping loop, and primitive of a leaf) counts
// `traversal_weight` (lavapipe's SIMD lanes: a group runs each
// traversal as long as its slowest lane, so its count is at most the sum of its lanes'); a
// traversal that would pass `loop_budget` (half lavapipe's limit: the group's samples may be
// as many as its busiest lane's) stops and marks the sample spent, and the render loop leaves
// that sample to the next dispatch (see kernel.wgsl and GpuParams in src/shared/layout.rs).

//#if BVH
// The traversal's stack: each entry a word (an interior node's children left to enter, or an
// instance's index) and a distance (where the ray enters the nearest of those children's boxes,
// or ENTER_INSTANCE). At module scope: lavapipe keeps a function's array in registers, each
// dynamic index a chain of selects over every element, but a module's private array in memory,
// where its size costs nothing per index (docs/benchmarks.md).
var<private> stack: array<u32, BVH_STACK>;
var<private> stack_entry: array<f32, BVH_STACK>;
//#if LOOP_BUDGET
var<private> loop_iterations: u32;
var<private> budget_spent: bool;
//#endif

// Where the ray enters each of a node's children's boxes if it meets them within [0, t_max],
// else -1: box_entry (src/accel/mod.rs) four at once, of the boxes QuantizedNode::child_box decodes (a grid byte
// times its step is exact, so the decoding rounds alike fused or not).
fn children_entry(node: BvhNode, origin: vec3f, inverse: vec3f, t_max: f32) -> vec4f {
    let step = vec3f(
        bitcast<f32>((node.steps & 0xffu) << 23u),
        bitcast<f32>(((node.steps >> 8u) & 0xffu) << 23u),
        bitcast<f32>(((node.steps >> 16u) & 0xffu) << 23u),
    );
    let t0x = (node.origin.x + lane_bytes(node.low.x) * step.x - origin.x) * inverse.x;
    let t1x = (node.origin.x + lane_bytes(node.high.x) * step.x - origin.x) * inverse.x;
    let t0y = (node.origin.y + lane_bytes(node.low.y) * step.y - origin.y) * inverse.y;
    let t1y = (node.origin.y + lane_bytes(node.high.y) * step.y - origin.y) * inverse.y;
    let t0z = (node.origin.z + lane_bytes(node.low.z) * step.z - origin.z) * inverse.z;
    let t1z = (node.origin.z + lane_bytes(node.high.z) * step.z - origin.z) * inverse.z;
    let near = max(max(min(t0x, t1x), min(t0y, t1y)), max(min(t0z, t1z), vec4f(0.0)));
    let far = min(min(max(t0x, t1x), max(t0y, t1y)), min(max(t0z, t1z), vec4f(t_max))) * BOX_FAR_WIDENING;
    let used = vec4u(0u, 1u, 2u, 3u) < vec4u(node.lanes);
    return select(vec4f(-1.0), near, (near <= far) & used);
}

// The four bytes of w, lowest first, as floats.
fn lane_bytes(w: u32) -> vec4f {
    return vec4f((vec4u(w) >> vec4u(0u, 8u, 16u, 24u)) & vec4u(0xffu));
}

struct Ordered {
    key: vec4f,
    lane: vec4u,
}

// The lanes of the children met (key: entry distance, below BVH_NEAREST) before those missed
// (BVH_MISSED, BVH_EMPTY), nearest first: the sorting network of nearest_first in
// src/accel/quantized.rs.
fn nearest_first(near: vec4f) -> Ordered {
    let met = near >= vec4f(0.0);
    var k = select(vec4f(BVH_MISSED), min(near, vec4f(BVH_NEAREST)), met);
    var c = select(vec4u(BVH_EMPTY), vec4u(0u, 1u, 2u, 3u), met);
    var s = k.y < k.x;
    k = select(k, k.yxzw, s);
    c = select(c, c.yxzw, s);
    s = k.w < k.z;
    k = select(k, k.xywz, s);
    c = select(c, c.xywz, s);
    s = k.z < k.x;
    k = select(k, k.zyxw, s);
    c = select(c, c.zyxw, s);
    s = k.w < k.y;
    k = select(k, k.xwzy, s);
    c = select(c, c.xwzy, s);
    s = k.z < k.y;
    k = select(k, k.xzyw, s);
    c = select(c, c.xzyw, s);
    return Ordered(k, c);
}

// 1 / dir with components below 1e-20 in size taken as 1e-20 (no infinities in WGSL).
fn inverse_direction(d: vec3f) -> vec3f {
    let tiny = select(vec3f(1e-20), vec3f(-1e-20), d < vec3f(0.0));
    return 1.0 / select(d, tiny, abs(d) < vec3f(1e-20));
}

fn consider_primitive(packed: u32, ray: Ray, sh: ptr<function, Shear>, c: ptr<function, Closest>) {
    let kind = primitive_kind(packed);
    let index = primitive_index(packed);
//#if TRIANGLES
    if kind == KIND_TRIANGLE {
        consider_triangle(triangles[index], index, ray, *sh, c);
    }
//#endif
    // The shapes' (generated: src/gpu/shape_dispatch.rs).
    consider_shape(kind, index, ray, c);
}

//#if TRIANGLES
//#if INSTANCES
const NO_INSTANCE: u32 = 0xffffffffu;
// The entry distance of a stack entry that enters an instance (the entry its index), not a
// node's children.
const ENTER_INSTANCE: f32 = -1.0;

// Triangle `triangle` of instance `instance`'s mesh against the ray in mesh coordinates (the
// instance's material is read once the closest hit is known, in intersect).
fn consider_instanced_triangle(instance: u32, triangle: u32, ray: Ray, sh: Shear, c: ptr<function, Closest>) {
    let packed = (KIND_INSTANCE << PRIMITIVE_INDEX_BITS) | instance;
    let h = triangle_hit(triangles[triangle], ray, sh);
    if replaces_in_instance(h.x, packed, triangle, c) {
//#if ALPHA
        if passes_through(instances[instance].material, triangle, h.yz, ray, packed, triangle) {
            return;
        }
//#endif
        record_hit(h.x, packed, c);
        (*c).triangle = triangle;
        (*c).weights = h.yz;
    }
}
//#endif
//#endif

// Two levels in one loop (WGSL has no recursion, and SIMD lanes in different levels still step
// together): a top-level leaf's instances are pushed as stack entries marked ENTER_INSTANCE;
// popping one moves the ray into the instance's mesh coordinates (not renormalised: t stays
// the scene ray's) and descends its mesh's BVH from its root; once the stack is back at the
// height it had then, the scene's ray is restored (see consider_instance in src/cpu/intersect.rs,
// which re-enters the CPU's traversal instead).
//
// One iteration per interior node entered (`entering`: a node's or a leaf's reference), with
// the leaf it descends into if it does; one per leaf popped from the stack; none for a child
// whose box the ray misses; a popped entry whose nearest box now lies beyond the closest hit
// costs a pass of the popping loop, no read. (Testing the popped node's own box instead, as
// the binary walk once did, was slower on lavapipe: it reads the node.)
fn traverse(world: Ray, c: ptr<function, Closest>) {
    var ray = world;
    let world_inverse = inverse_direction(world.dir);
    var inverse = world_inverse;
//#if TRIANGLES
    let world_shear = shear_of(world.dir);
//#else
    let world_shear = Shear(0u, vec3f(0.0));
//#endif
    var sh = world_shear;
    var top = 0u;
    var entering = BVH_ROOT;
//#if TRIANGLES
//#if INSTANCES
    var instance = NO_INSTANCE;
    var floor = 0u;
//#endif
//#endif
    loop {
//#if LOOP_BUDGET
        if loop_iterations >= params.loop_budget {
            budget_spent = true;
            break;
        }
        loop_iterations += params.traversal_weight;
//#endif
        // An interior node first: when it sends the ray into a leaf, the leaf is tested in
        // the same iteration (lavapipe runs both halves every iteration anyway).
        var pop = false;
        if (entering & BVH_LEAF) == 0u {
            let node = bvh_node(entering);
            let o = nearest_first(children_entry(node, ray.origin, inverse, (*c).t));
            // The others met, in one entry (group_entry): the missed sort last.
            if o.lane.y != BVH_EMPTY {
                let left = select(select(3u, 2u, o.lane.w == BVH_EMPTY), 1u, o.lane.z == BVH_EMPTY);
                let lanes = (o.lane.y & 3u) | ((o.lane.z & 3u) << 2u) | ((o.lane.w & 3u) << 4u);
                stack[top] = entering | (lanes << BVH_GROUP_LANES_SHIFT) | (left << BVH_GROUP_COUNT_SHIFT);
                stack_entry[top] = o.key.y;
                top += 1u;
            }
            pop = o.lane.x == BVH_EMPTY;
            entering = node.children[o.lane.x & 3u];
        }
        if !pop && (entering & BVH_LEAF) != 0u {
            let first = entering & (BVH_LEAF_OFFSET_LIMIT - 1u);
            let count = (entering & ~BVH_LEAF) >> BVH_LEAF_COUNT_SHIFT;
//#if LOOP_BUDGET
            loop_iterations += params.traversal_weight * (count + 1u);
//#endif
            for (var i = first; i < first + count; i++) {
                let packed = bvh_primitive(i);
//#if TRIANGLES
//#if INSTANCES
                if instance != NO_INSTANCE {
                    consider_instanced_triangle(instance, primitive_index(packed), ray, sh, c);
                    continue;
                }
                if primitive_kind(packed) == KIND_INSTANCE {
                    stack[top] = primitive_index(packed);
                    stack_entry[top] = ENTER_INSTANCE;
                    top += 1u;
                    continue;
                }
//#endif
//#endif
                consider_primitive(packed, ray, &sh, c);
            }
            pop = true;
        }
        if pop {
            // Entries whose boxes now lie beyond the closest hit are dropped in an inner loop,
            // far cheaper per iteration than the traversal's.
            var finished = false;
            loop {
//#if LOOP_BUDGET
                // Every pass counts: lavapipe's limit counts this loop's every end.
                loop_iterations += params.traversal_weight;
//#endif
//#if TRIANGLES
//#if INSTANCES
                if instance != NO_INSTANCE && top == floor {
                    instance = NO_INSTANCE;
                    ray = world;
                    inverse = world_inverse;
                    sh = world_shear;
                }
//#endif
//#endif
                if top == 0u {
                    finished = true;
                    break;
                }
                top -= 1u;
                let word = stack[top];
                let key = stack_entry[top];
                // The nearest box left as box_entry would test it against the closest hit now:
                // beyond it, so are the others.
                var entered = key <= (*c).t * BOX_FAR_WIDENING;
                var group = true;
//#if TRIANGLES
//#if INSTANCES
                group = key != ENTER_INSTANCE;
//#endif
//#endif
                // The entry's next child (group_next; node 0 for an instance's entry, so that a
                // SIMD lane that reads under another's mask reads a node), the rest put back
                // under the same distance
                // (stack_entry[top], the distance, is still there for the rest).
                let node = select(0u, word & (BVH_GROUP_NODE_LIMIT - 1u), group);
                let lanes = (word >> BVH_GROUP_LANES_SHIFT) & 0x3fu;
                let left = word >> BVH_GROUP_COUNT_SHIFT;
                if group && entered {
                    entering = bvh_child(node, lanes & 3u);
                    if left > 1u {
                        stack[top] = node | ((lanes >> 2u) << BVH_GROUP_LANES_SHIFT) | ((left - 1u) << BVH_GROUP_COUNT_SHIFT);
                        top += 1u;
                    }
                }
//#if TRIANGLES
//#if INSTANCES
                if !group {
                    instance = word;
                    floor = top;
                    let inst = instances[instance];
                    ray = Ray(instance_to_local(inst, world.origin), instance_vector_to_local(inst, world.dir));
                    inverse = inverse_direction(ray.dir);
                    sh = shear_of(ray.dir);
                    entering = inst.root;
                    entered = true;
                }
//#endif
//#endif
                if entered {
                    break;
                }
            }
            if finished {
                break;
            }
        }
    }
}
//#endif
