// Ray-shape intersection (twin: src/cpu/intersect.rs). `Hit` is generated from src/shared/ray.rs.

fn primitive_kind(primitive: u32) -> u32 {
    return primitive >> PRIMITIVE_INDEX_BITS;
}

fn primitive_index(primitive: u32) -> u32 {
    return primitive & ((1u << PRIMITIVE_INDEX_BITS) - 1u);
}

// Closest, the closest hit found so far along a ray and what its shape needs to complete the
// hit, is generated from src/gpu/kernel_state.rs.

// Nothing found yet: every hit is nearer.
const NO_CLOSEST = Closest(vec3f(0.0, 1.0, 0.0), 3.4e38, vec4f(0.0), 0u, 0u, false, vec2f(0.0), vec2f(0.0), 0u);

// Whether a hit at t on primitive `packed` replaces the closest so far: nearer, or as near and
// earlier in the order of packed references (coincident surfaces resolve the same whatever
// order a BVH traversal meets them in; see consider in src/cpu/intersect.rs).
fn replaces(t: f32, packed: u32, c: ptr<function, Closest>) -> bool {
    return t > 0.0 && (t < (*c).t || (t == (*c).t && (!(*c).found || packed < (*c).primitive)));
}

// `replaces` where primitives are met in that order, as in kernels with the scene inlined: the
// closest so far is then never later than `packed`, so the same decision without comparing
// indices.
fn replaces_in_order(t: f32, c: ptr<function, Closest>) -> bool {
    return t > 0.0 && (t < (*c).t || (t == (*c).t && !(*c).found));
}

// Makes primitive `packed`, met at t, the closest so far (once `replaces` says it is): what a
// shape keeps to complete the hit, each sets beside it.
fn record_hit(t: f32, packed: u32, c: ptr<function, Closest>) {
    (*c).t = t;
    (*c).found = true;
    (*c).primitive = packed;
}

//#if INSTANCES
// `replaces` for triangle `triangle` of the instance packed as `packed`: as near and the same
// instance, the earlier triangle wins (see replaces in src/cpu/intersect.rs).
fn replaces_in_instance(t: f32, packed: u32, triangle: u32, c: ptr<function, Closest>) -> bool {
    let earlier = packed < (*c).primitive || (packed == (*c).primitive && triangle < (*c).triangle);
    return t > 0.0 && (t < (*c).t || (t == (*c).t && (!(*c).found || earlier)));
}

// Instance maps (twins of Instance's methods in src/scene/flat.rs).
fn instance_to_world(i: Instance, p: vec3f) -> vec3f {
    return vec3f(dot(i.to_world_x.xyz, p) + i.to_world_x.w, dot(i.to_world_y.xyz, p) + i.to_world_y.w,
        dot(i.to_world_z.xyz, p) + i.to_world_z.w);
}

fn instance_to_local(i: Instance, p: vec3f) -> vec3f {
    return vec3f(dot(i.to_local_x.xyz, p) + i.to_local_x.w, dot(i.to_local_y.xyz, p) + i.to_local_y.w,
        dot(i.to_local_z.xyz, p) + i.to_local_z.w);
}

// Not renormalised: distances along a ray stay the same in both coordinates.
fn instance_vector_to_local(i: Instance, v: vec3f) -> vec3f {
    return vec3f(dot(i.to_local_x.xyz, v), dot(i.to_local_y.xyz, v), dot(i.to_local_z.xyz, v));
}

// By the transpose of to_local (the inverse transpose of to_world), not normalised.
fn instance_normal_to_world(i: Instance, n: vec3f) -> vec3f {
    return i.to_local_x.xyz * n.x + i.to_local_y.xyz * n.y + i.to_local_z.xyz * n.z;
}

fn instance_magnitude_to_world(i: Instance, p: vec3f) -> vec3f {
    let a = abs(p);
    return vec3f(dot(abs(i.to_world_x.xyz), a) + abs(i.to_world_x.w),
        dot(abs(i.to_world_y.xyz), a) + abs(i.to_world_y.w), dot(abs(i.to_world_z.xyz), a) + abs(i.to_world_z.w));
}
//#endif

// Where a hit lies: the point put back onto the surface, and a bound on its error.
struct Surface {
    point: vec3f,
    error: f32,
}

// along_ray projected onto the plane dot(n, p) = d (unit n): a flat shape's hit point put back
// onto it (twin: shape::plane_surface).
fn plane_surface(along_ray: vec3f, n: vec3f, d: f32) -> Surface {
    let point = along_ray - (dot(n, along_ray) - d) * n;
    let p = abs(point);
    return Surface(point, POINT_ERROR * (max(p.x, max(p.y, p.z)) + abs(d)));
}

//#if INLINE_SCENE
// Where a ray first meets a box's surface: `t` (-1: nowhere ahead) and which of its six quads
// that is (`face`, in the order of box_faces in src/scene/flat.rs: +z, +x, -z, -x, +y, -y).
// Kernels with the scene inlined test a box's quads as one (see box_test in
// src/gpu/shader.rs): less work than six quad tests.
struct BoxHit {
    t: f32,
    face: u32,
}

// The box between the planes of its opposite faces, -x and +x, -y and +y, -z and +z: where the
// ray crosses them (`low`, `high`: each face's quad_distance before its edges are tested, so
// that a face coincident with another quad meets the ray at the same t), whether it crosses
// them at all (not where it runs parallel to them: |denominator| < PARALLEL_DENOMINATOR, as for quads) and, if
// not, whether its origin lies between them. The ray is inside the box where it is between
// all three pairs: it enters at the latest entry, if that lies ahead, or else leaves at the
// earliest exit.
fn slab_hit(low: vec3f, high: vec3f, crosses: vec3<bool>, between: vec3<bool>) -> BoxHit {
    let unbounded = select(vec3f(3.4e38), vec3f(-3.4e38), between);
    let enter = select(unbounded, min(low, high), crosses);
    let exit = select(-unbounded, max(low, high), crosses);
    let entry = max(max(enter.x, enter.y), enter.z);
    let leave = min(min(exit.x, exit.y), exit.z);
    let entering = entry > 0.0;
    let t = select(leave, entry, entering);
    // The face crossed at t; at an edge, the earlier quad, as among quads met at one distance.
    let at_low = (low == vec3f(t)) & crosses;
    let at_high = (high == vec3f(t)) & crosses;
    let face = select(select(select(select(select(5u, 4u, at_high.y), 3u, at_low.x), 2u, at_low.z), 1u, at_high.x), 0u, at_high.z);
    return BoxHit(select(-1.0, t, entry <= leave && t > 0.0), face);
}
//#endif

// A ray in the frame of the watertight triangle test: its dominant axis becomes z (`kz`: which
// axis that was) and it is sheared to run along +z; computed once per ray.
struct Shear {
    kz: u32,
    s: vec3f,
}

// v's components in the order (kx, ky, kz), kx = kz + 1 and ky = kz + 2 (mod 3).
fn permute(v: vec3f, kz: u32) -> vec3f {
    return select(select(v, v.zxy, kz == 1u), v.yzx, kz == 0u);
}

fn shear_of(dir: vec3f) -> Shear {
    let a = abs(dir);
    let kz = select(select(2u, 1u, a.y > a.z), 0u, a.x > a.y && a.x > a.z);
    let d = permute(dir, kz);
    return Shear(kz, vec3f(-d.x / d.z, -d.y / d.z, 1.0 / d.z));
}

//#if TRIANGLES
// a * b - c * d with its sign exact where fma is fused (Kahan's algorithm: within 2 ulps,
// Jeannerod, Louvet and Muller 2013), so that an edge shared by two triangles gets edge
// functions of exactly opposite signs. A plain a * b - c * d is antisymmetric only unfused:
// NVIDIA's compiler fuses one product into the subtraction, and rays aimed along the shared
// edge leaked between both triangles. Where fma is split into a product and a sum (lavapipe),
// this is the plain difference, antisymmetric there. WGSL cannot forbid a driver that splits
// fma and then fuses again: tests/stability.rs's closed boxes are the check on each device.
fn difference_of_products(a: f32, b: f32, c: f32, d: f32) -> f32 {
    let cd = c * d;
    return fma(a, b, -cd) + fma(-c, d, cd);
}

// Distance along the ray to triangle tri and the barycentric weights of its second and third
// corners there, or t = -1 for a miss: watertight (Woop, Benthin and Wald 2013; see
// hit_triangle in src/cpu/intersect.rs).
fn triangle_hit(tri: Triangle, ray: Ray, sh: Shear) -> vec3f {
    let q0 = permute(tri.p0 - ray.origin, sh.kz);
    let q1 = permute(tri.p1 - ray.origin, sh.kz);
    let q2 = permute(tri.p2 - ray.origin, sh.kz);
    let p0 = vec2f(q0.x + sh.s.x * q0.z, q0.y + sh.s.y * q0.z);
    let p1 = vec2f(q1.x + sh.s.x * q1.z, q1.y + sh.s.y * q1.z);
    let p2 = vec2f(q2.x + sh.s.x * q2.z, q2.y + sh.s.y * q2.z);
    let e0 = difference_of_products(p1.x, p2.y, p1.y, p2.x);
    let e1 = difference_of_products(p2.x, p0.y, p2.y, p0.x);
    let e2 = difference_of_products(p0.x, p1.y, p0.y, p1.x);
    let mixed = (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0);
    let det = e0 + e1 + e2;
    let scaled = e0 * (sh.s.z * q0.z) + e1 * (sh.s.z * q1.z) + e2 * (sh.s.z * q2.z);
    let safe = select(det, 1.0, det == 0.0);
    let t = scaled / safe;
    return select(vec3f(t, e1 / safe, e2 / safe), vec3f(-1.0), mixed || det == 0.0);
}

fn consider_triangle(tri: Triangle, index: u32, ray: Ray, sh: Shear, c: ptr<function, Closest>) {
    let h = triangle_hit(tri, ray, sh);
    if replaces(h.x, (KIND_TRIANGLE << PRIMITIVE_INDEX_BITS) | index, c) {
//#if ALPHA
        if passes_through(tri.material, index, h.yz, ray, (KIND_TRIANGLE << PRIMITIVE_INDEX_BITS) | index, 0u) {
            return;
        }
//#endif
        record_hit(h.x, (KIND_TRIANGLE << PRIMITIVE_INDEX_BITS) | index, c);
        (*c).material = tri.material;
        (*c).outward = cross(tri.p1 - tri.p0, tri.p2 - tri.p0);
        (*c).weights = h.yz;
    }
}

// The weighted corners and a bound on the point's error (see triangle_surface in
// src/cpu/intersect.rs).
fn triangle_surface(c: Closest) -> Surface {
    let tri = triangles[primitive_index(c.primitive)];
    let b0 = 1.0 - c.weights.x - c.weights.y;
    let point = b0 * tri.p0 + c.weights.x * tri.p1 + c.weights.y * tri.p2;
    let m = abs(b0) * abs(tri.p0) + abs(c.weights.x) * abs(tri.p1) + abs(c.weights.y) * abs(tri.p2);
    return Surface(point, POINT_ERROR * max(m.x, max(m.y, m.z)));
}
//#endif

//#if TRIANGLES
//#if INSTANCES
// triangle_surface for a triangle of an instance's mesh, placed (see instanced_triangle_surface
// in src/cpu/intersect.rs).
fn instanced_triangle_surface(c: Closest) -> Surface {
    let inst = instances[primitive_index(c.primitive)];
    let tri = triangles[c.triangle];
    let b0 = 1.0 - c.weights.x - c.weights.y;
    let point = b0 * instance_to_world(inst, tri.p0) + c.weights.x * instance_to_world(inst, tri.p1)
        + c.weights.y * instance_to_world(inst, tri.p2);
    let m = abs(b0) * instance_magnitude_to_world(inst, tri.p0)
        + abs(c.weights.x) * instance_magnitude_to_world(inst, tri.p1)
        + abs(c.weights.y) * instance_magnitude_to_world(inst, tri.p2);
    return Surface(point, 2.0 * POINT_ERROR * max(m.x, max(m.y, m.z)));
}
//#endif
//#endif

// The closest hit beyond the ray's origin, if any.
fn intersect(ray: Ray, hit: ptr<function, Hit>) -> bool {
    var c = NO_CLOSEST;
//#if INLINE_SCENE
    // The scene's primitives are constants in this kernel (see inline_scene below).
    inline_scene(ray, &c);
//#else
//#if BVH
    traverse(ray, &c);
//#endif
//#endif
    return hit_at_closest(ray, c, hit);
}

//#if NEE
//#if INLINE_SCENE
// `intersect` for a shadow ray, whose hit matters only where it is a light's: the closest
// primitive is found tracking its distance and index alone, and only if it emits is its hit
// worked out, from the emitting primitives alone (closest of all, it is closest of those, so
// the hit is intersect's): most shadow rays then never work out a hit.
fn intersect_emitter(ray: Ray, hit: ptr<function, Hit>) -> bool {
    var first = NO_CLOSEST;
    inline_scene_first(ray, &first);
    if !first.found || light_of(first.primitive) == 0u {
        return false;
    }
    var c = NO_CLOSEST;
    inline_emitters(ray, &c);
    return hit_at_closest(ray, c, hit);
}

// Only the distance and the index of primitive `packed` met at t, for `intersect_emitter`.
fn consider_first(t: f32, packed: u32, c: ptr<function, Closest>) {
    if replaces_in_order(t, c) {
        record_hit(t, packed, c);
    }
}
//#else
fn intersect_emitter(ray: Ray, hit: ptr<function, Hit>) -> bool {
    return intersect(ray, hit);
}
//#endif
//#endif

// The hit at closest primitive c, if any.
fn hit_at_closest(ray: Ray, closest: Closest, hit: ptr<function, Hit>) -> bool {
    var c = closest;
    if !c.found {
        return false;
    }
//#if TRIANGLES
//#if INSTANCES
    if primitive_kind(c.primitive) == KIND_INSTANCE {
        // By the inverse transpose: a mirroring placement turns the normal around with it.
        let tri = triangles[c.triangle];
        let inst = instances[primitive_index(c.primitive)];
        c.outward = instance_normal_to_world(inst, cross(tri.p1 - tri.p0, tri.p2 - tri.p0));
        c.material = inst.material;
    }
//#endif
//#endif
    let n = normalize(c.outward);
    let front = dot(ray.dir, n) < 0.0;
    let along_ray = ray.origin + c.t * ray.dir;
    // The shapes' (generated: shape_surface in src/gpu/shape_dispatch.rs), else a triangle's.
    var surface = shape_surface(c, along_ray, n);
//#if TRIANGLES
    if primitive_kind(c.primitive) == KIND_TRIANGLE {
        surface = triangle_surface(c);
    }
//#endif
//#if TRIANGLES
//#if INSTANCES
    if primitive_kind(c.primitive) == KIND_INSTANCE {
        surface = instanced_triangle_surface(c);
    }
//#endif
//#endif
    (*hit).t = c.t;
    (*hit).point = surface.point;
    (*hit).error = surface.error;
    (*hit).normal = select(-n, n, front);
    var shading = n;
//#if SHADING_NORMALS
    if primitive_kind(c.primitive) == KIND_TRIANGLE {
        shading = shading_normal(primitive_index(c.primitive), c.weights, n);
    }
//#if INSTANCES
    if primitive_kind(c.primitive) == KIND_INSTANCE {
        shading = instanced_shading_normal(instances[primitive_index(c.primitive)], c.triangle, c.weights, n);
    }
//#endif
//#endif
    (*hit).shading = select(-shading, shading, front);
    (*hit).coat = (*hit).shading;
    (*hit).front_face = front;
    (*hit).material = c.material;
    (*hit).primitive = c.primitive;
//#if VERTEX_COLORS
    (*hit).color = vertex_color(c);
//#endif
//#if READS_UVS
    (*hit).uv = shape_hit_uv(c, surface.point);
//#if TRIANGLES
    if primitive_kind(c.primitive) == KIND_TRIANGLE || primitive_kind(c.primitive) == KIND_INSTANCE {
        (*hit).uv = c.weights;
    }
//#endif
//#if TRIANGLE_UVS
    if primitive_kind(c.primitive) == KIND_TRIANGLE {
        (*hit).uv = interpolated_uv(primitive_index(c.primitive), c.weights);
    }
//#if INSTANCES
    if primitive_kind(c.primitive) == KIND_INSTANCE {
        (*hit).uv = interpolated_uv(c.triangle, c.weights);
    }
//#endif
//#endif
    (*hit).uv1 = second_uv(c, (*hit).uv);
//#endif
//#if NORMAL_MAPS
    let m = materials[c.material];
    let map = base_normal_map(m);
    if map.size.x > 0.0 {
        let bent = bent_normal(map, c, *hit, shading, n);
        (*hit).shading = select(-bent, bent, front);
    }
//#if CLEARCOAT
    // The coat's normal: the interpolated one, bent by the coat's own map only.
    let coat_map = coat_normal_map(m);
    if coat_map.size.x > 0.0 {
        let bent = bent_normal(coat_map, c, *hit, shading, n);
        // Bent where its mirror would send the view below the surface.
        (*hit).coat = valid_reflection((*hit).normal, -ray.dir, select(-bent, bent, front));
    }
//#endif
//#endif
    return true;
}

//#if NORMAL_MAPS
// The interpolated normal `shading` of hit (on candidate c) bent by normal map `map`, on
// outward's side; unbent on a shape.
fn bent_normal(map: NormalMap, c: Closest, hit: Hit, shading: vec3f, outward: vec3f) -> vec3f {
    if primitive_kind(c.primitive) == KIND_TRIANGLE {
        return normal_mapped(map, primitive_index(c.primitive), c.weights, uv_at(map.lookup, hit), shading, outward);
    }
//#if INSTANCES
    if primitive_kind(c.primitive) == KIND_INSTANCE {
        let inst = instances[primitive_index(c.primitive)];
        return instanced_normal_mapped(map, inst, c.triangle, c.weights, uv_at(map.lookup, hit), shading, outward);
    }
//#endif
    return shading;
}
//#endif

//#if TRIANGLE_UVS || TRIANGLE_UVS1
// Three corners' texture coordinates interpolated at weights (twin: interpolated_uv in
// src/cpu/intersect.rs).
fn corner_uvs_at(uv0: vec2f, uv1: vec2f, uv2: vec2f, weights: vec2f) -> vec2f {
    return (1.0 - weights.x - weights.y) * uv0 + weights.x * uv1 + weights.y * uv2;
}
//#endif

//#if TRIANGLE_UVS
// Triangle i's corner texture coordinates interpolated at weights.
fn interpolated_uv(i: u32, weights: vec2f) -> vec2f {
    let at = 6u * i;
    let uv0 = vec2f(triangle_uvs[at], triangle_uvs[at + 1u]);
    let uv1 = vec2f(triangle_uvs[at + 2u], triangle_uvs[at + 3u]);
    let uv2 = vec2f(triangle_uvs[at + 4u], triangle_uvs[at + 5u]);
    return corner_uvs_at(uv0, uv1, uv2, weights);
}
//#endif

//#if TRIANGLE_UVS1
// Triangle i's second corner texture coordinates (TEXCOORD_1) interpolated at weights.
fn interpolated_uv1(i: u32, weights: vec2f) -> vec2f {
    let at = 6u * i;
    let uv0 = vec2f(triangle_uvs1[at], triangle_uvs1[at + 1u]);
    let uv1 = vec2f(triangle_uvs1[at + 2u], triangle_uvs1[at + 3u]);
    let uv2 = vec2f(triangle_uvs1[at + 4u], triangle_uvs1[at + 5u]);
    return corner_uvs_at(uv0, uv1, uv2, weights);
}
//#endif

//#if READS_UVS
// The hit on c's second texture coordinates where the scene's materials read them, else uv,
// its first (twin: second_uv in src/cpu/intersect.rs).
fn second_uv(c: Closest, uv: vec2f) -> vec2f {
//#if TRIANGLE_UVS1
    if primitive_kind(c.primitive) == KIND_TRIANGLE {
        return interpolated_uv1(primitive_index(c.primitive), c.weights);
    }
//#if INSTANCES
    if primitive_kind(c.primitive) == KIND_INSTANCE {
        return interpolated_uv1(c.triangle, c.weights);
    }
//#endif
//#endif
    return uv;
}
//#endif

//#if VERTEX_COLORS
fn corner_color(at: u32) -> vec3f {
    return vec3f(triangle_colors[at], triangle_colors[at + 1u], triangle_colors[at + 2u]);
}

// The vertex colour at the hit on c: its triangle's corner colours interpolated, white on a
// shape (twin: vertex_color in src/cpu/intersect.rs).
fn vertex_color(c: Closest) -> vec3f {
    var i = 0u;
    if primitive_kind(c.primitive) == KIND_TRIANGLE {
        i = primitive_index(c.primitive);
    } else if primitive_kind(c.primitive) == KIND_INSTANCE {
        i = c.triangle;
    } else {
        return vec3f(1.0);
    }
    let at = 9u * i;
    return (1.0 - c.weights.x - c.weights.y) * corner_color(at) + c.weights.x * corner_color(at + 3u)
        + c.weights.y * corner_color(at + 6u);
}
//#endif

//#if SHADING_NORMALS
fn corner_normal(at: u32) -> vec3f {
    return vec3f(triangle_normals[at], triangle_normals[at + 1u], triangle_normals[at + 2u]);
}

// Triangle i's corner normals interpolated at weights, unit, turned into the hemisphere of the
// unit geometric normal `outward`; `outward` where they cancel (twin: shading_normal in
// src/cpu/intersect.rs).
fn shading_normal(i: u32, weights: vec2f, outward: vec3f) -> vec3f {
    return interpolated_normal(corner_normal(9u * i), corner_normal(9u * i + 3u), corner_normal(9u * i + 6u),
        weights, outward);
}

//#if INSTANCES
// A mesh corner's normal placed by instance `inst` as flattening places it (one the placement
// collapses takes the face's, `outward`).
fn placed_corner_normal(inst: Instance, n: vec3f, outward: vec3f) -> vec3f {
    let placed = instance_normal_to_world(inst, n);
    let len2 = dot(placed, placed);
    return select(outward, placed * (1.0 / sqrt(len2)), len2 > 0.0);
}

// shading_normal for triangle i of an instance's mesh, its corner normals placed first.
fn instanced_shading_normal(inst: Instance, i: u32, weights: vec2f, outward: vec3f) -> vec3f {
    return interpolated_normal(placed_corner_normal(inst, corner_normal(9u * i), outward),
        placed_corner_normal(inst, corner_normal(9u * i + 3u), outward),
        placed_corner_normal(inst, corner_normal(9u * i + 6u), outward), weights, outward);
}
//#endif

fn interpolated_normal(n0: vec3f, n1: vec3f, n2: vec3f, weights: vec2f, outward: vec3f) -> vec3f {
    let n = (1.0 - weights.x - weights.y) * n0 + weights.x * n1 + weights.y * n2;
    let len2 = dot(n, n);
    if !(len2 > 1e-12) {
        return outward;
    }
    let unit = n / sqrt(len2);
    return select(unit, -unit, dot(unit, outward) < 0.0);
}
//#endif

// Whether unit dir leaves hit below its geometric surface although the shading normal allowed
// it: such a scattered path ends (twin: below_surface in src/cpu/intersect.rs).
fn below_surface(hit: Hit, dir: vec3f) -> bool {
//#if SHADING_NORMALS
    return any(hit.shading != hit.normal) && dot(dir, hit.normal) <= 0.0;
//#else
    return false;
//#endif
}

// Moves a ray origin off a surface by a few units in the last place along n (Ray Tracing Gems,
// ch. 6); callers first move it by the point's error bound (see leave).
fn offset_component(p: f32, n: f32) -> f32 {
    if abs(p) < OFFSET_NEAR_ORIGIN {
        return p + OFFSET_FLOAT_SCALE * n;
    }
    var of_i = i32(OFFSET_INT_SCALE * n);
    if p < 0.0 {
        of_i = -of_i;
    }
    return bitcast<f32>(bitcast<i32>(p) + of_i);
}

fn offset_origin(p: vec3f, n: vec3f) -> vec3f {
    return vec3f(offset_component(p.x, n.x), offset_component(p.y, n.y), offset_component(p.z, n.z));
}

// The origin of a ray leaving `hit` on the side of unit `side`: past the point's error bound,
// then a few units in the last place further.
fn leave(hit: Hit, side: vec3f) -> vec3f {
    return offset_origin(hit.point + hit.error * side, side);
}

// A ray leaving `hit` along unit `dir`, started on the side `dir` points to.
fn spawn(hit: Hit, dir: vec3f) -> Ray {
    let side = select(-hit.normal, hit.normal, dot(dir, hit.normal) >= 0.0);
    return Ray(leave(hit, side), dir);
}
