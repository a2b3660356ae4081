// Data shared by every kernel module: the scene buffers and the per-dispatch parameters.
// Each struct mirrors a #[repr(C)] struct in src/gpu/layout.rs; a test checks sizes and offsets.

struct Sphere {
    center: vec3f,
    radius: f32,      // negative: the normal faces inward
    material: u32,
    light: u32,       // 1 + index in lights, 0 if it does not emit
}

// The parallelogram q + a u + b v, a, b in [0, 1]; see src/scene/flat.rs for the axes.
struct Quad {
    q: vec3f,
    d: f32,           // plane: dot(normal, p) = d
    normal: vec3f,
    material: u32,
    alpha_axis: vec3f,
    light: u32,       // 1 + index in lights, 0 if it does not emit
    beta_axis: vec3f,
    edge_tolerance: f32, // counts as hit this far (a fraction of each edge) past its edges
}

// An emitter for next-event estimation: a quad (uniform on its area) or a sphere (radius > 0;
// uniform in the cone it subtends), picked in proportion to power (see src/scene/flat.rs).
struct Light {
    position: vec3f,  // quad corner, or sphere centre
    cdf: f32,         // chance of picking this light or one before it
    u: vec3f,         // quad edges
    pick: f32,        // chance of picking this light
    v: vec3f,
    radius: f32,      // sphere: |radius|; quad: 0
    normal: vec3f,    // quad unit normal
    inv_area: f32,    // quad: 1 / area
}

struct Material {
    albedo: vec3f,    // lambertian, metal
    kind: u32,        // MAT_* below
    emission: vec3f,  // lambertian emission, light radiance
    param: f32,       // metal: fuzz; dielectric: ior; light: 1 if two-sided
}

const MAT_LAMBERTIAN: u32 = 0u;
const MAT_METAL: u32 = 1u;
const MAT_DIELECTRIC: u32 = 2u;
const MAT_LIGHT: u32 = 3u;

struct Params {
    origin: vec3f,
    lens_radius: f32,
    to_upper_left: vec3f,
    width: u32,
    horizontal: vec3f,
    height: u32,
    vertical: vec3f,
    max_depth: u32,
    right: vec3f,
    seed: u32,
    up: vec3f,
    first_sample: u32,     // random-stream index of this dispatch's first sample
    background: vec3f,
    sample_count: u32,     // samples per pixel in this dispatch
    tile_origin: vec2u,
    tile_size: vec2u,
    sphere_count: u32,
    quad_count: u32,
    samples_before: u32,   // samples already in the accumulator
    sky: u32,              // 1: sky gradient background
    light_count: u32,
    roulette_depth: u32,   // Russian roulette from this many segments on; 0: off
}

struct Ray {
    origin: vec3f,
    dir: vec3f,
}

// Storage, not uniform: lavapipe compiles a shader variant for every distinct uniform value it
// can fold, and these change every dispatch (see GpuRenderer::render).
@group(0) @binding(0) var<storage, read> params: Params;
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
