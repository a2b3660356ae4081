//! Building the kernel for a scene. The WGSL modules in `shaders/` are joined in order, and
//! blocks between `//#if FEATURE` (or `//#if A || B`), optional `//#else`, and `//#endif` are kept
//! only when the scene needs that feature: a scene without spheres gets no sphere code, one
//! without glass no dielectric branch.

use crate::gpu::layout::SceneBuffers;
use crate::material::{KINDS, MaterialFeature, MaterialKind};
use crate::options::{Integrator, RenderOptions, SamplerKind};
use crate::scene::Background;
use crate::scene::flat::FlatScene;
use crate::shape::quad::GpuQuad;
use crate::shape::{self, Quad, ShapeKind, ShapeVisitor, SurfaceShape};
use crate::shared::layout::{WgslStruct, WgslType, float_literal};

/// The kernel's modules, in dependency order.
const MODULES: &[(&str, &str)] = &[
    ("common.wgsl", include_str!("../../shaders/common.wgsl")),
    ("rng.wgsl", include_str!("../../shaders/rng.wgsl")),
    ("sampler.wgsl", include_str!("../../shaders/sampler.wgsl")),
    ("sampling.wgsl", include_str!("../../shaders/sampling.wgsl")),
    ("angles.wgsl", include_str!("../../shaders/angles.wgsl")),
    (
        "microfacet.wgsl",
        include_str!("../../shaders/microfacet.wgsl"),
    ),
    ("fresnel.wgsl", include_str!("../../shaders/fresnel.wgsl")),
    ("medium.wgsl", include_str!("../../shaders/medium.wgsl")),
    ("camera.wgsl", include_str!("../../shaders/camera.wgsl")),
    (
        "intersect.wgsl",
        include_str!("../../shaders/intersect.wgsl"),
    ),
    ("accel.wgsl", include_str!("../../shaders/accel.wgsl")),
    ("texture.wgsl", include_str!("../../shaders/texture.wgsl")),
    ("alpha.wgsl", include_str!("../../shaders/alpha.wgsl")),
    (
        "normal_map.wgsl",
        include_str!("../../shaders/normal_map.wgsl"),
    ),
    ("coat.wgsl", include_str!("../../shaders/coat.wgsl")),
    ("specular.wgsl", include_str!("../../shaders/specular.wgsl")),
    (
        "environment.wgsl",
        include_str!("../../shaders/environment.wgsl"),
    ),
    (
        "materials.wgsl",
        include_str!("../../shaders/materials.wgsl"),
    ),
    (
        "clearcoat.wgsl",
        include_str!("../../shaders/clearcoat.wgsl"),
    ),
    ("sheen.wgsl", include_str!("../../shaders/sheen.wgsl")),
    (
        "microsurface.wgsl",
        include_str!("../../shaders/microsurface.wgsl"),
    ),
    // Here: each material the scene uses (shaders/materials/), then their dispatch.
    (
        "background.wgsl",
        include_str!("../../shaders/background.wgsl"),
    ),
    ("lights.wgsl", include_str!("../../shaders/lights.wgsl")),
    (
        "integrator.wgsl",
        include_str!("../../shaders/integrator.wgsl"),
    ),
    ("aov.wgsl", include_str!("../../shaders/aov.wgsl")),
    ("film.wgsl", include_str!("../../shaders/film.wgsl")),
    ("kernel.wgsl", include_str!("../../shaders/kernel.wgsl")),
];

/// What a scene needs from the kernel.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Features {
    /// The shape kinds the kernel holds, as bits in the order of `shape::KINDS`.
    pub shapes: u32,
    pub triangles: bool,
    /// Triangles shaded with interpolated vertex normals.
    pub shading_normals: bool,
    /// Triangles with corner texture coordinates, which a material's texture reads.
    pub triangle_uvs: bool,
    /// Triangles with second corner texture coordinates (glTF TEXCOORD_1), which a material's
    /// image reads.
    pub triangle_uvs1: bool,
    /// Triangles with corner tangents, for their materials' normal maps.
    pub normal_maps: bool,
    /// Triangles with corner colours (glTF COLOR_0), which multiply their materials' colour.
    pub vertex_colors: bool,
    /// Meshes placed as instances (the BVH's second level; see `scene::flat::Instance`).
    pub instances: bool,
    /// Primitives found through the scene's BVH (off only where `inline_scene` is on).
    pub bvh: bool,
    /// BVH traversals count their loop iterations against a budget and end a sample that
    /// would pass it (see shaders/accel.wgsl): lavapipe silently breaks an invocation's loops
    /// after 65 535 iterations in all. Set by the renderer for software adapters (and debug
    /// kernels, whose `trace_rays` reports the count); a hardware GPU's kernel carries none of
    /// it.
    pub loop_budget: bool,
    /// The material features on, as [`MaterialFeature::bit`]s: each material
    /// kind the scene uses, and the extra features its instances need.
    pub materials: u32,
    /// A camera with an aperture.
    pub lens: bool,
    /// The Sobol sampler (else independent numbers).
    pub sobol: bool,
    pub sky: bool,
    /// An environment image as the background (and, with nee, a light).
    pub environment: bool,
    /// The `first_bounce` entry point, for tests.
    pub debug: bool,
    /// Next-event estimation: light sampling with MIS (the nee integrator, in a scene with
    /// lights and diffuse surfaces to light).
    pub nee: bool,
    /// The albedo feature buffer in place of light transport (the albedo integrator,
    /// `shaders/aov.wgsl`).
    pub aov_albedo: bool,
    /// The normal feature buffer in place of light transport (the normal integrator).
    pub aov_normal: bool,
    /// Lights of no area (points, spots, the sun) among the lights.
    pub punctual: bool,
    /// Scene arrays in uniform buffers of `scene_capacity` elements (faster where they fit).
    pub uniform_scene: bool,
    pub scene_capacity: u32,
    /// The BVH's nodes in a uniform buffer of `bvh_capacity` nodes (where they fit) rather
    /// than a texture.
    pub uniform_bvh: bool,
    pub bvh_capacity: u32,
    /// With `uniform_bvh`, the primitive references' array length in vec4u (four each).
    pub bvh_primitive_capacity: u32,
    /// The shapes written into the kernel as constants, tested in straight-line code:
    /// no loads, no loops, and the compiler folds the zeros of axis-aligned quads.
    pub inline_scene: bool,
}

/// A boolean switch of [`Features`]: its name (what `//#if` blocks test) and its field.
type Switch = (&'static str, fn(&mut Features) -> &mut bool);

/// Every boolean switch of [`Features`], once: the one list `flags` and `set` read.
const SWITCHES: [Switch; 21] = [
    ("TRIANGLES", |f| &mut f.triangles),
    ("SHADING_NORMALS", |f| &mut f.shading_normals),
    ("TRIANGLE_UVS", |f| &mut f.triangle_uvs),
    ("TRIANGLE_UVS1", |f| &mut f.triangle_uvs1),
    ("NORMAL_MAPS", |f| &mut f.normal_maps),
    ("VERTEX_COLORS", |f| &mut f.vertex_colors),
    ("INSTANCES", |f| &mut f.instances),
    ("BVH", |f| &mut f.bvh),
    ("LOOP_BUDGET", |f| &mut f.loop_budget),
    ("LENS", |f| &mut f.lens),
    ("SOBOL", |f| &mut f.sobol),
    ("SKY", |f| &mut f.sky),
    ("ENVIRONMENT", |f| &mut f.environment),
    ("DEBUG", |f| &mut f.debug),
    ("NEE", |f| &mut f.nee),
    ("AOV_ALBEDO", |f| &mut f.aov_albedo),
    ("AOV_NORMAL", |f| &mut f.aov_normal),
    ("PUNCTUAL", |f| &mut f.punctual),
    ("UNIFORM_SCENE", |f| &mut f.uniform_scene),
    ("UNIFORM_BVH", |f| &mut f.uniform_bvh),
    ("INLINE_SCENE", |f| &mut f.inline_scene),
];
/// How many of [`SWITCHES`] come before the material features in [`Features::flags`] (after
/// the shapes').
const GEOMETRY_SWITCHES: usize = 6;

/// Most shapes a kernel takes as constants.
pub const MAX_INLINE_PRIMITIVES: usize = 64;

/// The largest uniform binding every WebGPU device offers.
pub const MAX_UNIFORM_BYTES: u64 = 64 * 1024;
/// The largest element of the scene arrays that go into uniform buffers together.
pub const LARGEST_ELEMENT_BYTES: u64 = {
    use crate::shared::layout::{GpuLight, GpuMaterial};
    use std::mem::size_of;
    let sizes = [
        shape::LARGEST_GPU_RECORD,
        size_of::<GpuMaterial>(),
        size_of::<GpuLight>(),
    ];
    let mut largest = 0;
    let mut i = 0;
    while i < sizes.len() {
        if sizes[i] > largest {
            largest = sizes[i];
        }
        i += 1;
    }
    largest as u64
};
/// A BVH node as the kernel reads it (`layout::GpuBvhNode`).
const NODE_BYTES: u64 = std::mem::size_of::<crate::shared::layout::GpuBvhNode>() as u64;

impl Features {
    pub fn of(scene: &FlatScene) -> Self {
        // Only materials some primitive uses: a scene may define more than it places. Each
        // used material once (its features are worked out, not looked up).
        let mut used = vec![false; scene.materials.len()];
        for m in
            (scene.shapes.materials().into_iter()).chain(scene.triangles.iter().map(|t| t.material))
        {
            used[m as usize] = true;
        }
        let mut materials = 0;
        for (m, _) in scene.materials.iter().zip(&used).filter(|(_, used)| **used) {
            for feature in std::iter::once(m.kind().feature).chain(m.extra_features()) {
                materials |= feature.bit();
            }
        }
        // Uniform arrays have a fixed size: the next power of two (fewer distinct kernels).
        let longest = (shape::KINDS.iter())
            .map(|k| scene.shapes.count(k))
            .fold(0, usize::max)
            .max(scene.materials.len())
            .max(scene.lights.len());
        let capacity = (longest.max(1) as u64).next_power_of_two();
        let reference_words = scene.bvh.primitives.len().div_ceil(4);
        let bvh_primitive_capacity = (reference_words.max(1) as u64).next_power_of_two();
        // Bounded in size: a flat scene holds only the materials and lights its primitives
        // use, so neither outnumbers them. Not under an environment: lavapipe then compiles and
        // keeps a variant of the inlined kernel at every dispatch (see docs/benchmarks.md).
        let inline_scene = scene.triangles.is_empty()
            && !matches!(scene.background, Background::Environment(_))
            && scene.shapes.len() <= MAX_INLINE_PRIMITIVES
            && scene.materials.len() <= MAX_INLINE_PRIMITIVES
            && scene.lights.len() <= MAX_INLINE_PRIMITIVES;
        // Any other scene goes through its BVH, faster even on lavapipe than a loop over a few
        // hundred primitives.
        let bvh = !inline_scene;
        // The kernel's hierarchy only where it traverses one (made on first use).
        let interior_nodes = if bvh {
            scene.kernel_bvh().nodes.len()
        } else {
            0
        };
        let bvh_capacity = (interior_nodes.max(1) as u64).next_power_of_two();
        Features {
            shapes: (shape::KINDS.iter().enumerate())
                .filter(|(_, k)| scene.shapes.count(k) > 0)
                .fold(0, |bits, (position, _)| bits | 1 << position),
            triangles: !scene.triangles.is_empty(),
            shading_normals: !scene.triangle_normals.is_empty(),
            triangle_uvs: !scene.triangle_uvs.is_empty(),
            triangle_uvs1: !scene.triangle_uvs1.is_empty(),
            normal_maps: !scene.triangle_tangents.is_empty(),
            vertex_colors: !scene.triangle_colors.is_empty(),
            instances: !scene.instances.is_empty(),
            bvh,
            loop_budget: false,
            materials,
            lens: scene.camera.lens_radius > 0.0,
            sobol: false,
            sky: scene.background == Background::Sky,
            environment: matches!(scene.background, Background::Environment(_)),
            debug: false,
            nee: false,
            aov_albedo: false,
            aov_normal: false,
            punctual: scene.lights.iter().any(|l| l.shape.is_delta()),
            // BVH kernels too: lavapipe reads uniform arrays in straight-line code.
            uniform_scene: capacity * LARGEST_ELEMENT_BYTES <= MAX_UNIFORM_BYTES,
            scene_capacity: capacity as u32,
            // Lavapipe gathers a uniform array's words lane by lane in straight-line code, where
            // a texel fetch is a function call (and storage is read one lane at a time).
            uniform_bvh: bvh
                && bvh_capacity * NODE_BYTES <= MAX_UNIFORM_BYTES
                && bvh_primitive_capacity * 16 <= MAX_UNIFORM_BYTES,
            bvh_capacity: bvh_capacity as u32,
            bvh_primitive_capacity: bvh_primitive_capacity as u32,
            inline_scene,
        }
    }

    /// Everything on, scene arrays in storage buffers: the general kernel any scene can run
    /// (except `sky` and `environment`, which replace the constant background, `lens`, which
    /// changes the random-number sequence, and `shading_normals`, `triangle_uvs` and
    /// `normal_maps`, whose buffers only scenes with vertex normals, texture coordinates or
    /// normal maps fill).
    pub fn everything(scene: &FlatScene) -> Self {
        let own = Features::of(scene);
        Features {
            shapes: (1 << shape::KINDS.len()) - 1,
            triangles: true,
            bvh: true,
            materials: MaterialFeature::ALL
                .iter()
                .fold(0, |bits, f| bits | f.bit()),
            uniform_scene: false,
            uniform_bvh: false,
            inline_scene: false,
            punctual: true,
            ..own
        }
    }

    /// These features for rendering `scene` with `integrator`. Without lights, or without
    /// surfaces or media to take light samples at, nee computes exactly what naive does, so
    /// the kernel leaves it out.
    pub fn with_integrator(self, scene: &FlatScene, integrator: Integrator) -> Self {
        let samples_lights = scene.materials.iter().any(|m| m.samples_lights())
            || self.has_material(MaterialFeature::Media);
        Features {
            nee: integrator == Integrator::Nee && !scene.lights.is_empty() && samples_lights,
            aov_albedo: integrator == Integrator::Albedo,
            aov_normal: integrator == Integrator::Normal,
            ..self
        }
    }

    /// These features for a render with `opts`: its integrator and its sampler.
    pub fn for_render(self, scene: &FlatScene, opts: &RenderOptions) -> Self {
        Features {
            sobol: opts.sampler == SamplerKind::Sobol,
            ..self.with_integrator(scene, opts.integrator)
        }
    }

    /// The material kinds whose code the kernel holds.
    pub fn kinds(&self) -> impl Iterator<Item = &'static MaterialKind> + '_ {
        KINDS.iter().filter(|k| self.has_material(k.feature))
    }

    /// Every switch by name, in a fixed order: what `//#if` blocks test. The material
    /// features come after the geometry's switches (the first `GEOMETRY_SWITCHES` of
    /// [`SWITCHES`]).
    pub fn flags(&self) -> Vec<(&'static str, bool)> {
        let mut copy = *self;
        let shapes = (shape::KINDS.iter().enumerate())
            .map(|(position, k)| (k.feature, self.shapes & 1 << position != 0));
        let mut flags: Vec<(&'static str, bool)> = shapes
            .chain(
                SWITCHES
                    .iter()
                    .map(|(name, switch)| (*name, *switch(&mut copy))),
            )
            .collect();
        let materials = (MaterialFeature::ALL.iter()).map(|&f| (f.name(), self.has_material(f)));
        let geometry = shape::KINDS.len() + GEOMETRY_SWITCHES;
        flags.splice(geometry..geometry, materials);
        flags
    }

    /// Turns the switch `name` (one of [`Features::flags`]) on or off.
    pub fn set(&mut self, name: &str, on: bool) -> Result<(), String> {
        if let Some((_, switch)) = SWITCHES.iter().find(|(n, _)| *n == name) {
            *switch(self) = on;
            return Ok(());
        }
        if let Some(position) = shape::KINDS.iter().position(|k| k.feature == name) {
            self.shapes = if on {
                self.shapes | 1 << position
            } else {
                self.shapes & !(1 << position)
            };
            return Ok(());
        }
        let Some(feature) = MaterialFeature::named(name) else {
            return Err(format!("unknown shader feature {name}"));
        };
        let bit = feature.bit();
        self.materials = if on {
            self.materials | bit
        } else {
            self.materials & !bit
        };
        Ok(())
    }

    /// Whether the kernel holds material feature `feature`.
    pub fn has_material(&self, feature: MaterialFeature) -> bool {
        self.materials & feature.bit() != 0
    }

    /// Whether the kernel holds the shape kind `kind`.
    pub fn has_shape(&self, kind: &ShapeKind) -> bool {
        let position = shape::KINDS.iter().position(|k| k.name == kind.name);
        position.is_some_and(|p| self.shapes & 1 << p != 0)
    }

    /// Whether hits compute surface (UV) coordinates: a material looks something up at them,
    /// or a normal map bends normals by them (the derived switch `READS_UVS`).
    pub fn reads_uvs(&self) -> bool {
        self.normal_maps
            || MaterialFeature::ALL
                .iter()
                .any(|&f| f.reads_uvs() && self.has_material(f))
    }

    /// Whether switch `name` (one of [`Features::flags`], or a derived switch) is on; an error
    /// for a name that is neither.
    fn enabled(&self, name: &str) -> Result<bool, String> {
        if name == "READS_UVS" {
            return Ok(self.reads_uvs());
        }
        self.flags()
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, on)| *on)
            .ok_or_else(|| format!("unknown shader feature {name}"))
    }
}

/// The kernel source for `features`, built for `scene` (whose primitives it may hold as constants).
pub fn compose(features: &Features, scene: &FlatScene) -> Result<String, String> {
    let on: Vec<&str> = features
        .flags()
        .iter()
        .filter(|(_, on)| *on)
        .map(|(n, _)| *n)
        .collect();
    let mut out = format!(
        "// rt-gpu kernel, generated from shaders/*.wgsl for features: {}\n",
        on.join(" ")
    );
    out.push_str(&crate::gpu::layout::wgsl_shared());
    out.push_str(&format!(
        "const MEDIUM_CROSSINGS: u32 = {}u;\nconst F32_MAX: f32 = {};\n",
        scene.medium_crossings,
        float_literal(f32::MAX)
    ));
    // The traversal stack sized to this scene's hierarchy (GPU memory per invocation); a kernel
    // of constants has none (its hierarchy is not made).
    let (stack, root) = if features.bvh {
        let kernel_bvh = scene.kernel_bvh();
        (
            kernel_bvh.stack_bound(scene.largest_instance_leaf()),
            kernel_bvh.root,
        )
    } else {
        (1, crate::shared::layout::BVH_LEAF)
    };
    out.push_str(&format!(
        "const BVH_STACK: u32 = {stack}u;\nconst BVH_ROOT: u32 = {root}u;\n"
    ));
    if features.uniform_scene {
        out.push_str(&format!(
            "const SCENE_CAPACITY: u32 = {}u;\n",
            features.scene_capacity.max(1)
        ));
    }
    if features.uniform_bvh {
        out.push_str(&format!(
            "const BVH_CAPACITY: u32 = {}u;\nconst BVH_PRIMITIVE_CAPACITY: u32 = {}u;\n",
            features.bvh_capacity.max(1),
            features.bvh_primitive_capacity.max(1)
        ));
    }
    for (name, source) in MODULES {
        out.push_str(&format!("\n// ---- {name} ----\n"));
        out.push_str(&preprocess(source, name, features)?);
        if *name == "materials.wgsl" {
            for kind in features.kinds() {
                let name = format!("materials/{}.wgsl", kind.name);
                out.push_str(&format!("\n// ---- {name}'s parameters, generated ----\n"));
                out.push_str(&(kind.params_wgsl)(kind.name));
                out.push_str(&format!("\n// ---- {name} ----\n"));
                out.push_str(&preprocess(kind.wgsl, &name, features)?);
            }
            out.push_str(&material_dispatch(features));
        }
        if *name == "intersect.wgsl" {
            out.push_str(&super::shape_dispatch::wgsl(features)?);
        }
    }
    if features.inline_scene {
        out.push_str(&inline_scene(scene, features));
        out.push_str(&inline_materials(scene));
        if features.nee {
            out.push_str(&inline_lights(scene));
        }
    }
    Ok(out)
}

/// The material interface as switches on the kind over the materials the kernel holds:
/// `emitted`, `bsdf_sample`, and with nee `samples_lights`, `bsdf_eval` and `bsdf_pdf`.
fn material_dispatch(features: &Features) -> String {
    // Assignments, not early returns: under divergent control flow lavapipe runs returns with a
    // mask, a cost in every lane.
    let mut out = String::from("\n// ---- the material interface, generated ----\n");
    // With normal maps, the materials' own BSDFs are the facets' of a microsurface
    // (shaders/microsurface.wgsl defines the bsdf_* the path loop calls).
    let bsdf = if features.normal_maps {
        "facet"
    } else {
        "bsdf"
    };
    let case = |kind: &MaterialKind, call: &str| {
        format!(
            "    if m.kind == MAT_{} {{\n        out = {}_{call};\n    }}\n",
            kind.feature, kind.name
        )
    };
    out.push_str("fn emitted(m: Material, hit: Hit) -> vec3f {\n    var out = vec3f(0.0);\n");
    for kind in features.kinds() {
        if let Some(feature) = kind.emits_under
            && features.has_material(feature)
        {
            out.push_str(&case(kind, "emitted(m, hit)"));
        }
    }
    out.push_str("    return out;\n}\n\n");
    if features.nee {
        let lit: Vec<String> = features
            .kinds()
            .filter(|k| k.samples_lights)
            .map(|k| {
                if k.samples_lights_per_instance {
                    format!(
                        "(m.kind == MAT_{} && {}_samples_lights(m))",
                        k.feature, k.name
                    )
                } else {
                    format!("m.kind == MAT_{}", k.feature)
                }
            })
            .collect();
        out.push_str(&format!(
            "// Whether next-event estimation samples lights here: the BSDF has a lobe that is neither a delta nor absent.\nfn samples_lights(m: Material) -> bool {{\n    return {};\n}}\n\n",
            if lit.is_empty() { "false".to_string() } else { lit.join(" || ") }
        ));
        out.push_str(&format!("fn {bsdf}_eval(m: Material, wo: vec3f, wi: vec3f, hit: Hit) -> vec3f {{\n    var out = vec3f(0.0);\n"));
        for kind in features.kinds().filter(|k| k.samples_lights) {
            out.push_str(&case(kind, "eval(m, wo, wi, hit)"));
        }
        out.push_str("    return out;\n}\n\n");
        out.push_str(&format!("fn {bsdf}_pdf(m: Material, wo: vec3f, wi: vec3f, hit: Hit) -> f32 {{\n    var out = 0.0;\n"));
        for kind in features.kinds().filter(|k| k.samples_lights) {
            out.push_str(&case(kind, "pdf(m, wo, wi, hit)"));
        }
        out.push_str("    return out;\n}\n\n");
    }
    out.push_str(&format!(
        "fn {bsdf}_sample(m: Material, wo: vec3f, hit: Hit, sampler: ptr<function, Sampler>) -> BsdfSample {{\n    var out = BsdfSample(vec3f(0.0), vec3f(0.0, 1.0, 0.0), 0.0, 0u);\n",
    ));
    for kind in features.kinds() {
        out.push_str(&case(kind, "sample(m, wo, hit, sampler)"));
    }
    out.push_str("    return out;\n}\n");
    out
}

/// `inline_scene`: every primitive tested in the order of their packed references (the shapes
/// by kind, each with its index among its kind, as the CPU orders them), a box's six quads as
/// one (`box_test`); with nee, for shadow rays (`intersect_emitter`), the same tests keeping
/// only the closest's distance and index (`inline_scene_first`) and the full tests of the
/// emitting primitives alone (`inline_emitters`). Quads have tests of their own here (their
/// constant zeros folded, boxes as slabs); every other shape is its twin's
/// `consider_<name>` with the shape as a constant.
fn inline_scene(scene: &FlatScene, features: &Features) -> String {
    let constants = shape_constants(scene);
    let held = |k: &ShapeKind| features.has_shape(k);
    let quads: Vec<GpuQuad> = if features.shapes & 1 << quad_position() != 0 {
        scene.shapes.quads.iter().map(SurfaceShape::gpu).collect()
    } else {
        Vec::new()
    };
    // Boxes tested as one, by their first quad. Not where hits need UV coordinates: a box
    // test finds which face it hit, not where on it.
    let boxes: &[u32] = if quads.is_empty() || scene.uv_textures {
        &[]
    } else {
        &scene.boxes
    };
    let box_at = |i: usize| boxes.iter().position(|&first| first as usize == i);
    let in_box = |i: usize| {
        boxes
            .iter()
            .any(|&first| (first as usize..first as usize + 6).contains(&i))
    };
    let full = |k: &ShapeKind, i: usize, constant: &str| {
        format!("    consider_{}({constant}, {i}u, ray, true, c);\n", k.name)
    };
    let full_quad = |i: usize, q: &GpuQuad| {
        format!(
            "    consider_quad_at(quad_distance_{i}(ray), {}, {i}u, ray, true, c);\n",
            q.wgsl_constructor()
        )
    };
    let mut out = String::from("\n// ---- the scene's primitives, generated ----\n");
    out.push_str("fn inline_scene(ray: Ray, c: ptr<function, Closest>) {\n");
    for (k, shapes) in shape::KINDS.iter().zip(&constants).filter(|(k, _)| held(k)) {
        if k.kind != Quad::KIND {
            for (i, (constant, _)) in shapes.iter().enumerate() {
                out.push_str(&full(k, i, constant));
            }
            continue;
        }
        for (i, q) in quads.iter().enumerate() {
            if let Some(b) = box_at(i) {
                out.push_str(&format!("    consider_box_{b}(ray, c);\n"));
            } else if !in_box(i) {
                out.push_str(&full_quad(i, q));
            }
        }
    }
    out.push_str("}\n");
    if features.nee {
        out.push_str("\nfn inline_scene_first(ray: Ray, c: ptr<function, Closest>) {\n");
        for (k, shapes) in shape::KINDS.iter().zip(&constants).filter(|(k, _)| held(k)) {
            let kind = format!("KIND_{}", k.name.to_uppercase());
            if k.kind != Quad::KIND {
                for (i, (constant, _)) in shapes.iter().enumerate() {
                    out.push_str(&format!(
                        "    consider_first({}_distance({constant}, ray), ({kind} << PRIMITIVE_INDEX_BITS) | {i}u, c);\n",
                        k.name
                    ));
                }
                continue;
            }
            for i in 0..quads.len() {
                if let Some(b) = box_at(i) {
                    out.push_str(&format!(
                        "    let box_{b} = box_test_{b}(ray);\n    consider_first(box_{b}.t, ({kind} << PRIMITIVE_INDEX_BITS) | ({i}u + box_{b}.face), c);\n"
                    ));
                } else if !in_box(i) {
                    out.push_str(&format!(
                        "    consider_first(quad_distance_{i}(ray), ({kind} << PRIMITIVE_INDEX_BITS) | {i}u, c);\n"
                    ));
                }
            }
        }
        out.push_str("}\n\nfn inline_emitters(ray: Ray, c: ptr<function, Closest>) {\n");
        for (k, shapes) in shape::KINDS.iter().zip(&constants).filter(|(k, _)| held(k)) {
            for (i, (constant, light)) in shapes.iter().enumerate() {
                if *light == 0 {
                    continue;
                }
                if k.kind == Quad::KIND {
                    out.push_str(&full_quad(i, &quads[i]));
                } else {
                    out.push_str(&full(k, i, constant));
                }
            }
        }
        out.push_str("}\n");
    }
    for (i, q) in quads.iter().enumerate() {
        if !in_box(i) || (features.nee && q.light > 0) {
            out.push_str(&quad_distance_inlined(i, q));
        }
    }
    for (b, &first) in boxes.iter().enumerate() {
        let first = first as usize;
        out.push_str(&box_test(b, first, &quads[first..first + 6]));
    }
    out
}

/// Quads' position in `shape::KINDS` (which `inline_scene` tests its own way).
fn quad_position() -> usize {
    (shape::KINDS.iter())
        .position(|k| k.kind == Quad::KIND)
        .expect("quads are a shape")
}

/// Each shape kind's shapes (in the order of `shape::KINDS`) as WGSL constants, with their
/// light indices.
fn shape_constants(scene: &FlatScene) -> Vec<Vec<(String, u32)>> {
    struct Constants(Vec<Vec<(String, u32)>>);
    impl ShapeVisitor for Constants {
        fn visit<S: SurfaceShape>(&mut self, _: &'static ShapeKind, shapes: &[S]) {
            let constant = |s: &S| (s.gpu().wgsl_constructor(), s.light());
            self.0.push(shapes.iter().map(constant).collect());
        }
    }
    let mut constants = Constants(Vec::new());
    scene.shapes.visit(&mut constants);
    constants.0
}

/// A box's six quads (`faces`, from quad `first` on) tested as one (`slab_hit` in
/// shaders/intersect.wgsl): where the ray crosses each face's plane, as quad_distance finds it
/// (the same arithmetic, so a face coincident with another quad, a box's bottom on a floor,
/// resolves as between quads), then the closest so far updated once, with the constants of
/// the face hit: less work than six quad tests, since opposite faces share a plane's
/// normal.
fn box_test(b: usize, first: usize, faces: &[GpuQuad]) -> String {
    // box_faces' order: +z, +x, -z, -x, +y, -y; the pairs by axis, low (-) and high (+).
    let (low, high) = ([3, 5, 2], [1, 4, 0]);
    let per_axis = |sides: [usize; 3], value: &dyn Fn(usize) -> String| {
        let [x, y, z] = sides.map(value);
        format!("vec3f({x}, {y}, {z})")
    };
    let denominator = |f: usize| constant_dot(faces[f].normal, "ray.dir");
    let numerator = |f: usize| constant_dot(faces[f].normal, &format!("to_corner_{f}"));
    let corners: String = (0..6)
        .map(|f| {
            format!(
                "    let to_corner_{f} = {} - ray.origin;\n",
                faces[f].q.literal()
            )
        })
        .collect();
    // select(select(... faces[5], faces[1], face == 1), faces[0], face == 0) of a field.
    let by_face = |value: &dyn Fn(&GpuQuad) -> String| {
        (0..5).rev().fold(value(&faces[5]), |rest, f| {
            format!("select({rest}, {}, hit.face == {f}u)", value(&faces[f]))
        })
    };
    format!(
        "fn box_test_{b}(ray: Ray) -> BoxHit {{
{corners}    let low_denominator = {low_denominator};
    let high_denominator = {high_denominator};
    let crosses = abs(low_denominator) >= vec3f(PARALLEL_DENOMINATOR);
    let low_numerator = {low_numerator};
    let high_numerator = {high_numerator};
    let between = (low_numerator >= vec3f(0.0)) & (high_numerator >= vec3f(0.0));
    let low = low_numerator / select(vec3f(1.0), low_denominator, crosses);
    let high = high_numerator / select(vec3f(1.0), high_denominator, crosses);
    return slab_hit(low, high, crosses, between);
}}

fn consider_box_{b}(ray: Ray, c: ptr<function, Closest>) {{
    let hit = box_test_{b}(ray);
    if replaces_in_order(hit.t, c) {{
        record_hit(hit.t, (KIND_QUAD << PRIMITIVE_INDEX_BITS) | ({first}u + hit.face), c);
        (*c).material = {material};
        (*c).outward = {outward};
        (*c).shape.w = {offset};
    }}
}}
",
        low_denominator = per_axis(low, &denominator),
        high_denominator = per_axis(high, &denominator),
        low_numerator = per_axis(low, &numerator),
        high_numerator = per_axis(high, &numerator),
        material = faces[0].material.literal(),
        outward = by_face(&|q| q.normal.literal()),
        offset = by_face(&|q| float_literal(q.d)),
    )
}

/// quad_distance (shaders/intersect.wgsl) for one quad, its fields as constants and the terms
/// of its dot products that multiply by a constant 0 left out: a compiler may not drop them
/// itself (0 * x is NaN for an infinite x), and most quads of a box are axis-aligned, so this
/// is about a third of a quad's test (the same arithmetic on every finite value).
fn quad_distance_inlined(i: usize, q: &GpuQuad) -> String {
    let corner = q.q.literal();
    let denom = constant_dot(q.normal, "ray.dir");
    let distance = constant_dot(q.normal, "to_corner");
    let alpha = constant_dot(q.alpha_axis, "planar");
    let beta = constant_dot(q.beta_axis, "planar");
    let lo = float_literal(-q.edge_tolerance);
    let hi = float_literal(1.0 + q.edge_tolerance);
    format!(
        "fn quad_distance_{i}(ray: Ray) -> f32 {{
    let denom = {denom};
    let facing = abs(denom) >= PARALLEL_DENOMINATOR;
    let to_corner = {corner} - ray.origin;
    let t = {distance} / select(1.0, denom, facing);
    let planar = t * ray.dir - to_corner;
    let alpha = {alpha};
    let beta = {beta};
    let inside = alpha >= {lo} && alpha <= {hi} && beta >= {lo} && beta <= {hi};
    return select(-1.0, t, facing && inside);
}}
"
    )
}

/// dot(constant, vector) as WGSL, in dot's order x, y, z, without the terms whose constant is
/// 0 (and without the product where it is 1).
fn constant_dot(constant: [f32; 3], vector: &str) -> String {
    let terms: Vec<String> = constant
        .iter()
        .zip(["x", "y", "z"])
        .filter(|(c, _)| **c != 0.0)
        .map(|(c, axis)| {
            if *c == 1.0 {
                format!("{vector}.{axis}")
            } else {
                format!("{} * {vector}.{axis}", float_literal(*c))
            }
        })
        .collect();
    if terms.is_empty() {
        "0.0".to_string()
    } else {
        format!("({})", terms.join(" + "))
    }
}

/// `fn {signature} { switch {selector} { case k: { return v; } ... default: { return d; } } }`.
fn switch_function(
    signature: &str,
    selector: &str,
    cases: impl IntoIterator<Item = (usize, String)>,
    default: &str,
) -> String {
    let mut out = format!("fn {signature} {{\n    switch {selector} {{\n");
    for (k, value) in cases {
        out.push_str(&format!(
            "        case {k}u: {{\n            return {value};\n        }}\n"
        ));
    }
    out.push_str(&format!(
        "        default: {{\n            return {default};\n        }}\n    }}\n}}\n"
    ));
    out
}

/// `material_at` as a switch over the scene's materials (the last is the default).
fn inline_materials(scene: &FlatScene) -> String {
    let mut constants: Vec<(usize, String)> = SceneBuffers::new(scene)
        .materials
        .iter()
        .map(WgslStruct::wgsl_constructor)
        .enumerate()
        .collect();
    let (_, default) = constants
        .pop()
        .expect("a scene has at least one material slot");
    format!(
        "\n// ---- the scene's materials, generated ----\n{}",
        switch_function("material_at(i: u32) -> Material", "i", constants, &default)
    )
}

/// The light list as constants: `pick_light` as a chain of comparisons, `light_of` and
/// `light_at` as switches.
fn inline_lights(scene: &FlatScene) -> String {
    let mut out = String::from(
        "\n// ---- the scene's lights, generated ----\nfn pick_light(u: f32) -> u32 {\n",
    );
    let last = scene.lights.len().saturating_sub(1);
    for (i, l) in scene.lights.iter().enumerate().take(last) {
        out.push_str(&format!(
            "    if u < {} {{\n        return {i}u;\n    }}\n",
            float_literal(l.cdf)
        ));
    }
    out.push_str(&format!("    return {last}u;\n}}\n\n"));
    let emitters = scene
        .primitives()
        .map(|p| (p.packed() as usize, scene.light_of(p)))
        .filter(|(_, light)| *light > 0)
        .map(|(primitive, light)| (primitive, format!("{light}u")));
    out.push_str(&switch_function(
        "light_of(primitive: u32) -> u32",
        "primitive",
        emitters,
        "0u",
    ));
    let mut constants: Vec<(usize, String)> = SceneBuffers::new(scene)
        .lights
        .iter()
        .take(scene.lights.len())
        .map(WgslStruct::wgsl_constructor)
        .enumerate()
        .collect();
    let (_, default) = constants.pop().expect("nee kernels have a light");
    out.push('\n');
    out.push_str(&switch_function(
        "light_at(i: u32) -> Light",
        "i",
        constants,
        &default,
    ));
    out
}

/// `source` (the module `shaders/{name}`) with the blocks `features` turns off left out. Where
/// lines were left out, a `//# shaders/{name}:LINE` line says where the next one comes from,
/// so that an error in the composed kernel names its `.wgsl` file and line ([`validate`]).
pub(super) fn preprocess(source: &str, name: &str, features: &Features) -> Result<String, String> {
    let located = |number: usize, e: &str| format!("shaders/{name}:{}: {e}", number + 1);
    // Each open block: (whether its branch is kept, whether the enclosing text is kept).
    let mut stack: Vec<(bool, bool)> = Vec::new();
    let mut keep = true;
    let mut skipped = false;
    let mut out = String::new();
    for (number, line) in source.lines().enumerate() {
        let directive = line.trim();
        if let Some(condition) = directive.strip_prefix("//#if ") {
            let mut value = false;
            for feature in condition.split("||") {
                value |= features
                    .enabled(feature.trim())
                    .map_err(|e| located(number, &e))?;
            }
            stack.push((value, keep));
            keep = keep && value;
        } else if directive == "//#else" {
            let &(value, outer) = stack
                .last()
                .ok_or_else(|| located(number, "#else without #if"))?;
            keep = outer && !value;
        } else if directive == "//#endif" {
            let (_, outer) = stack
                .pop()
                .ok_or_else(|| located(number, "#endif without #if"))?;
            keep = outer;
        } else if keep {
            if skipped {
                out.push_str(&format!("{SOURCE_MARK}shaders/{name}:{}\n", number + 1));
            }
            out.push_str(line);
            out.push('\n');
            skipped = false;
            continue;
        }
        skipped = true;
    }
    if !stack.is_empty() {
        return Err(format!("shaders/{name}: #if without #endif"));
    }
    Ok(out)
}

/// Starts a line of the composed kernel that says where the next line comes from.
const SOURCE_MARK: &str = "//# ";

/// Where line `line` (1-based) of a composed kernel comes from: `shaders/FILE.wgsl:LINE`, or
/// the generated part it is in (`// ---- NAME ----` headers start each part); `None` for
/// WGSL that is not a composed kernel.
pub fn source_of(kernel: &str, line: usize) -> Option<String> {
    let lines: Vec<&str> = kernel.lines().take(line.saturating_sub(1)).collect();
    for (index, text) in lines.iter().enumerate().rev() {
        let below = lines.len() - index;
        if let Some(mark) = text.strip_prefix(SOURCE_MARK)
            && let Some((file, first)) = mark.rsplit_once(':')
            && let Ok(first) = first.parse::<usize>()
        {
            return Some(format!("{file}:{}", first + below - 1));
        }
        if let Some(part) = text
            .strip_prefix("// ---- ")
            .and_then(|t| t.strip_suffix(" ----"))
        {
            return Some(if part.ends_with(".wgsl") {
                format!("shaders/{part}:{below}")
            } else {
                format!("{part} (line {line} of the composed kernel: rt-gpu SCENE --print-shader)")
            });
        }
    }
    None
}

/// Parses and validates WGSL with naga, as wgpu will; the error is one line.
pub fn validate(
    source: &str,
) -> Result<(wgpu::naga::Module, wgpu::naga::valid::ModuleInfo), String> {
    use wgpu::naga;
    // Named where a composed kernel's line comes from, not only by its line in the kernel.
    let at = |location: Option<naga::SourceLocation>| {
        location
            .and_then(|l| source_of(source, l.line_number as usize))
            .map_or(String::new(), |place| format!("{place}: "))
    };
    let module = naga::front::wgsl::parse_str(source).map_err(|e| {
        format!(
            "{}WGSL parse error: {}",
            at(e.location(source)),
            e.emit_to_string(source).replace('\n', " ")
        )
    })?;
    let info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::empty(),
    )
    .validate(&module)
    .map_err(|e| {
        format!(
            "{}WGSL validation error: {}",
            at(e.location(source)),
            e.emit_to_string(source).replace('\n', " ")
        )
    })?;
    Ok((module, info))
}
