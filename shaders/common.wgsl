// Data shared by every kernel module: the scene buffers and the per-dispatch parameters. Their
// structs (Sphere, Quad, Light, Material, Params, FirstBounce) and the constants both sides share
// are generated from src/gpu/layout.rs ahead of this file.

struct Ray {
    origin: vec3f,
    dir: vec3f,
}

// Per render: uniform, which lavapipe folds into the kernel (constant loop bounds).
@group(0) @binding(0) var<uniform> params: Params;
// Per dispatch: storage, since lavapipe compiles (and keeps) a kernel variant for every new
// uniform value it folds (see GpuDispatch in src/gpu/layout.rs).
@group(0) @binding(7) var<storage, read> dispatch: Dispatch;
// Every image the scene reads (a texel per vec4f), and the environment's alias table
// (ImageArray in src/gpu/layout.rs).
//#if IMAGE_TEXTURE || ENVIRONMENT
@group(0) @binding(8) var<storage, read> images: array<vec4f>;
//#endif
// Scenes small enough live in uniform buffers, which drivers such as lavapipe read far faster
// than storage buffers in these loops; SCENE_CAPACITY is set by the host for each scene.
//#if UNIFORM_SCENE
//#if SPHERES
@group(0) @binding(1) var<uniform> spheres: array<Sphere, SCENE_CAPACITY>;
//#endif
//#if QUADS
@group(0) @binding(2) var<uniform> quads: array<Quad, SCENE_CAPACITY>;
//#endif
@group(0) @binding(3) var<uniform> materials: array<Material, SCENE_CAPACITY>;
//#if NEE
@group(0) @binding(6) var<uniform> lights: array<Light, SCENE_CAPACITY>;
//#endif
//#else
//#if SPHERES
@group(0) @binding(1) var<storage, read> spheres: array<Sphere>;
//#endif
//#if QUADS
@group(0) @binding(2) var<storage, read> quads: array<Quad>;
//#endif
@group(0) @binding(3) var<storage, read> materials: array<Material>;
//#if NEE
@group(0) @binding(6) var<storage, read> lights: array<Light>;
//#endif
//#endif
// Meshes and the BVH: never uniform (they may be large).
//#if TRIANGLES
@group(0) @binding(9) var<storage, read> triangles: array<Triangle>;
//#endif
//#if SHADING_NORMALS
// Per triangle its three corner normals, nine floats (SceneBuffers::triangle_normals).
@group(0) @binding(12) var<storage, read> triangle_normals: array<f32>;
//#endif
//#if INSTANCES
@group(0) @binding(13) var<storage, read> instances: array<Instance>;
//#endif
//#if BVH
// The nodes are texels (two per node, BVH_NODE_ROW per row: see BvhNodeTexture in
// src/gpu/layout.rs): lavapipe fetches a texel for all its SIMD lanes at once, where it reads a
// storage buffer at lane-dependent addresses one lane and one word at a time.
@group(0) @binding(10) var bvh_node_texels: texture_2d<u32>;
@group(0) @binding(11) var<storage, read> bvh_primitives: array<u32>;

fn bvh_node(i: u32) -> BvhNode {
    let first = 2u * i;
    let a = textureLoad(bvh_node_texels, vec2u(first % BVH_NODE_ROW, first / BVH_NODE_ROW), 0);
    let b = textureLoad(bvh_node_texels, vec2u((first + 1u) % BVH_NODE_ROW, (first + 1u) / BVH_NODE_ROW), 0);
    return BvhNode(bitcast<vec3f>(a.xyz), a.w, bitcast<vec3f>(b.xyz), b.w);
}
//#endif
