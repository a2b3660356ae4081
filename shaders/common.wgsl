// Data shared by every kernel module: the scene buffers and the per-dispatch parameters. Their
// structs (Ray, Hit, Light, Material, Params, FirstBounce) and the constants both sides share
// are generated from src/shared/layout.rs and src/gpu/layout.rs ahead of this file, the binding
// numbers (BINDING_*) from src/gpu/bindings.rs.

// Per render: uniform, which lavapipe folds into the kernel (constant loop bounds).
@group(0) @binding(BINDING_PARAMS) var<uniform> params: Params;
// Per dispatch: storage, since lavapipe compiles (and keeps) a kernel variant for every new
// uniform value it folds (see GpuDispatch in src/shared/layout.rs).
@group(0) @binding(BINDING_DISPATCH) var<storage, read> dispatch: Dispatch;
// Texel i of an array kept as a texture (TEXEL_ROW in src/shared/layout.rs says why and how).
fn texel_at(t: texture_2d<u32>, i: u32) -> vec4u {
    return textureLoad(t, vec2u(i % TEXEL_ROW, i / TEXEL_ROW), 0);
}

// Every image the scene reads (a texel per vec4f), and the environment's CDFs (ImageArray in
// src/gpu/layout.rs).
//#if IMAGE_TEXTURE || ENVIRONMENT || NORMAL_MAPS || METALLIC_ROUGHNESS || ALPHA || COAT_TABLE || SHEEN || LAYER_IMAGES
@group(0) @binding(BINDING_IMAGE_TEXELS) var image_texels: texture_2d<u32>;

fn image_value(i: u32) -> vec4f {
    return bitcast<vec4f>(texel_at(image_texels, i));
}
//#endif
// The shapes' arrays (spheres, quads, ...) are declared with their dispatch (generated:
// src/gpu/shape_dispatch.rs). Scenes small enough live in uniform buffers, which drivers such as lavapipe read far faster
// than storage buffers in these loops; SCENE_CAPACITY is set by the host for each scene.
//#if UNIFORM_SCENE
@group(0) @binding(BINDING_MATERIALS) var<uniform> materials: array<Material, SCENE_CAPACITY>;
//#if NEE
@group(0) @binding(BINDING_LIGHTS) var<uniform> lights: array<Light, SCENE_CAPACITY>;
//#endif
//#else
@group(0) @binding(BINDING_MATERIALS) var<storage, read> materials: array<Material>;
//#if NEE
@group(0) @binding(BINDING_LIGHTS) var<storage, read> lights: array<Light>;
//#endif
//#endif
// Meshes: never uniform (they may be large); the BVH where it fits (UNIFORM_BVH).
//#if TRIANGLES
@group(0) @binding(BINDING_TRIANGLES) var<storage, read> triangles: array<Triangle>;
//#endif
//#if SHADING_NORMALS
// Per triangle its three corner normals, nine floats (SceneBuffers::triangle_normals).
@group(0) @binding(BINDING_TRIANGLE_NORMALS) var<storage, read> triangle_normals: array<f32>;
//#endif
//#if TRIANGLE_UVS
// Per triangle its three corner texture coordinates, six floats (SceneBuffers::triangle_uvs).
@group(0) @binding(BINDING_TRIANGLE_UVS) var<storage, read> triangle_uvs: array<f32>;
//#endif
//#if TRIANGLE_UVS1
// Per triangle its three corner second texture coordinates (SceneBuffers::triangle_uvs1).
@group(0) @binding(BINDING_TRIANGLE_UVS1) var<storage, read> triangle_uvs1: array<f32>;
//#endif
//#if NORMAL_MAPS
// Per triangle its three corner tangents, twelve floats (SceneBuffers::triangle_tangents).
@group(0) @binding(BINDING_TRIANGLE_TANGENTS) var<storage, read> triangle_tangents: array<f32>;
//#endif
//#if VERTEX_COLORS
// Per triangle its three corner vertex colours, nine floats (SceneBuffers::triangle_colors).
@group(0) @binding(BINDING_TRIANGLE_COLORS) var<storage, read> triangle_colors: array<f32>;
//#endif
//#if INSTANCES
@group(0) @binding(BINDING_INSTANCES) var<storage, read> instances: array<Instance>;
//#endif
//#if BVH
//#if UNIFORM_BVH
// Small hierarchies: nodes and primitive references (four to a vec4u, the stride uniform
// arrays need) read from uniform arrays (see uniform_bvh in src/gpu/shader.rs).
@group(0) @binding(BINDING_BVH_NODES) var<uniform> bvh_nodes: array<BvhNode, BVH_CAPACITY>;
@group(0) @binding(BINDING_BVH_PRIMITIVES) var<uniform> bvh_primitive_words: array<vec4u, BVH_PRIMITIVE_CAPACITY>;

fn bvh_primitive(i: u32) -> u32 {
    return bvh_primitive_words[i / 4u][i % 4u];
}

fn bvh_node(i: u32) -> BvhNode {
    return bvh_nodes[i];
}

// Child `lane`'s reference of node i.
fn bvh_child(i: u32, lane: u32) -> u32 {
    return bvh_nodes[i].children[lane];
}
//#else
// Four texels per node (TEXEL_ROW and GpuBvhNode in src/shared/layout.rs).
@group(0) @binding(BINDING_BVH_NODES) var bvh_node_texels: texture_2d<u32>;
@group(0) @binding(BINDING_BVH_PRIMITIVES) var<storage, read> bvh_primitives: array<u32>;

fn bvh_primitive(i: u32) -> u32 {
    return bvh_primitives[i];
}

fn bvh_node(i: u32) -> BvhNode {
    let a = texel_at(bvh_node_texels, 4u * i);
    let b = texel_at(bvh_node_texels, 4u * i + 1u);
    let c = texel_at(bvh_node_texels, 4u * i + 2u);
    let d = texel_at(bvh_node_texels, 4u * i + 3u);
    return BvhNode(bitcast<vec3f>(a.xyz), a.w, b, c.xyz, c.w, d.xyz);
}

// Child `lane`'s reference of node i: one texel.
fn bvh_child(i: u32, lane: u32) -> u32 {
    return texel_at(bvh_node_texels, 4u * i + 1u)[lane];
}
//#endif
//#endif
