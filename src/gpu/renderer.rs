//! Dispatching the kernel: buffers, tiles, sample slices, timing and readback into a [`Film`].

use super::bindings::{BINDINGS, Binding, layout_entries, shape_binding};
use super::context::{GpuContext, GpuError};
use super::dispatch::{DispatchSizer, LOOP_ITERATION_BUDGET, LoopCost, Tuning};
use super::layout::{ImageArray, SceneBuffers, base_params, whole_image_dispatch};
use super::shader::{Features, compose, validate};
use super::tile::TileRenderer;
use crate::accel::quantized::GROUP_NODE_LIMIT;
use crate::film::Film;
use crate::options::{RenderOptions, SamplerKind};
use crate::scene::flat::FlatScene;
use crate::shared::layout::{
    ACCUM_BYTES_PER_PIXEL, ACCUM_WORDS, BVH_LEAF_COUNT_LIMIT, BVH_LEAF_OFFSET_LIMIT,
    GpuFirstBounce, GpuParams, TEXEL_ROW, WORKGROUP_SIZE, texel_rows,
};
use wgpu::util::DeviceExt;

/// A generous bound on the loop iterations one sample costs: the path loop, and in each segment
/// a trace (one iteration for a scene inlined as straight-line code), counting every loop's
/// exit test as an iteration too (measured on lavapipe: a 1-sphere,
/// depth-2 sample costs about 7).
/// With NEE, a segment also searches the light list and traces a shadow ray. With media, a
/// segment and a shadow ray each trace up to 1 + `medium_crossings` rays (through invisible
/// boundaries). (The samplers have no loops.) Through a BVH a trace has no fixed bound: the
/// kernel counts those iterations itself (`GpuParams::sample_loop_cost` is this bound with
/// traversals counted as one iteration each) and `per_sample` estimates them, for sizing
/// dispatches only.
fn loop_cost(
    scene: &FlatScene,
    features: &Features,
    opts: &RenderOptions,
    traversal_weight: u64,
) -> (LoopCost, u64) {
    let max_depth = opts.max_depth;
    let rays_per_trace = if features.has_material(crate::material::MaterialFeature::Media) {
        2 + scene.medium_crossings as u64
    } else {
        1
    };
    let light_search = 2 + (scene.lights.len().max(1) as u64).ilog2() as u64;
    let bound = |per_trace: u64, rays_per_trace: u64| {
        let trace = rays_per_trace * per_trace;
        let per_segment = if features.nee {
            5 + 2 * trace + light_search
        } else {
            2 + trace
        };
        2 + (max_depth as u64 + 1) * per_segment
    };
    // A BVH kernel's traces count their own iterations, one traversal per boundary crossed,
    // so its fixed part counts each trace once, however many boundaries the scene has (a ray
    // crosses a few of them, not all); for sizing dispatches, a ray is guessed to cross at
    // most SIZING_CROSSINGS.
    const SIZING_CROSSINGS: u64 = 16;
    let fixed = bound(1, if features.bvh { 1 } else { rays_per_trace });
    let per_sample = if features.bvh {
        // Kernels count against half the budget (see shaders/accel.wgsl): doubled here.
        // An instanced mesh's levels below the top level's (each leaf reached may enter one).
        let depth = scene.bvh.depth as u64 + scene.instance_depth as u64;
        let traversal = 4 * (depth + crate::accel::MAX_LEAF as u64);
        let rays = rays_per_trace.min(2 + SIZING_CROSSINGS);
        2 * bound(1 + traversal_weight * traversal, rays)
    } else {
        fixed
    };
    (LoopCost { per_sample }, fixed)
}

/// How many f32 lanes lavapipe's SIMD groups have: its name says how wide its vectors are
/// ("llvmpipe (LLVM 15.0.6, 256 bits)": 8); 16 (512 bits) when it does not say.
fn simd_lanes(adapter_name: &str) -> u32 {
    let bits = adapter_name.find(" bits").and_then(|end| {
        adapter_name[..end]
            .rsplit(|c: char| !c.is_ascii_digit())
            .next()?
            .parse::<u32>()
            .ok()
    });
    bits.map_or(16, |b| (b / 32).max(1))
}

/// A query of the kernel's BSDF interface: `wo` and `wi` at a surface with normal `normal`
/// (shading and geometric alike) made of `material`, reached on its front face or its back.
#[derive(Clone, Copy, Debug)]
pub struct BsdfQuery {
    pub material: u32,
    pub wo: glam::Vec3,
    pub wi: glam::Vec3,
    pub normal: glam::Vec3,
    pub front_face: bool,
}

/// The kernel's answer: its sample (`lobe` 0: none) and `eval`/`pdf` at the query's wo, wi.
#[derive(Clone, Copy, Debug)]
pub struct BsdfAnswer {
    pub weight: glam::Vec3,
    pub wi: glam::Vec3,
    pub pdf: f32,
    pub lobe: u32,
    pub eval: glam::Vec3,
    pub eval_pdf: f32,
}

/// What `GpuRenderer::look_up_environment` finds for one direction and two numbers.
#[derive(Clone, Copy, Debug)]
pub struct EnvironmentLookup {
    pub radiance: glam::Vec3,
    pub pdf: f32,
    pub sampled: glam::Vec3,
    pub sampled_pdf: f32,
}

/// A compiled kernel and the source it was built from.
pub struct Kernel {
    pub features: Features,
    pub source: String,
    pub(super) pipeline: wgpu::ComputePipeline,
    bind_group_layout: wgpu::BindGroupLayout,
}

#[derive(Clone, Debug, Default)]
pub struct Timings {
    /// Sum of per-dispatch GPU time from timestamp queries, where the adapter has them.
    pub gpu_seconds: Option<f64>,
    pub dispatches: u32,
    /// The longest single dispatch, GPU time if known, else wall time.
    pub longest_dispatch_seconds: f64,
    /// Wall time of the host's share of the film: reading each tile's accumulator back (the
    /// copy to a mappable buffer and its mapping), checking its sample counts and turning its
    /// exact sums into the film where they are mapped.
    pub host_seconds: f64,
}

/// What a scene binds: its arrays as buffers (uniform or storage, as the kernel's features
/// say), its BVH's nodes (a texture, or a uniform buffer for small hierarchies) and its images
/// (a texture).
pub(super) struct SceneBindings {
    /// Each shape kind's array, in the order of `shape::KINDS`.
    shapes: Vec<wgpu::Buffer>,
    materials: wgpu::Buffer,
    lights: wgpu::Buffer,
    triangles: wgpu::Buffer,
    bvh_primitives: wgpu::Buffer,
    triangle_normals: wgpu::Buffer,
    triangle_uvs: wgpu::Buffer,
    triangle_tangents: wgpu::Buffer,
    triangle_colors: wgpu::Buffer,
    triangle_uvs1: wgpu::Buffer,
    instances: wgpu::Buffer,
    bvh_nodes: NodeBinding,
    images: wgpu::TextureView,
}

/// The BVH's nodes as the kernel reads them (`Features::uniform_bvh`).
enum NodeBinding {
    Texture(wgpu::TextureView),
    Uniform(wgpu::Buffer),
}

#[derive(Clone)]
pub struct GpuRenderer {
    pub ctx: GpuContext,
    /// Whether its BVH kernels count their loops against lavapipe's budget
    /// (`Features::loop_budget`): on software adapters. Public so that tests can build the
    /// hardware GPU's kernel on lavapipe.
    pub loop_budget: bool,
}

impl GpuRenderer {
    pub fn new(ctx: GpuContext) -> Self {
        let loop_budget =
            ctx.info.device_type == wgpu::DeviceType::Cpu || ctx.info.name.contains("llvmpipe");
        GpuRenderer { ctx, loop_budget }
    }

    /// `features` as this device's kernels have them: the loop budget where its adapter needs
    /// it, and in debug kernels (whose `trace_rays` reports the traversal's count). A kernel's
    /// `features` are these: compare with them, not with what was asked for.
    pub fn for_device(&self, features: Features) -> Features {
        Features {
            loop_budget: features.bvh && (self.loop_budget || features.debug),
            ..features
        }
    }

    /// Builds, validates and compiles the kernel for `features` and `scene`, without wgpu's
    /// bounds checks and loop guards (a large cost in the hot loops), which the kernel's own
    /// bounds make unneeded.
    pub fn kernel(
        &self,
        scene: &FlatScene,
        features: Features,
        entry_point: &str,
    ) -> Result<Kernel, GpuError> {
        let features = self.for_device(features);
        let source = compose(&features, scene).map_err(GpuError::Shader)?;
        // SAFETY: `source` is composed (`shader::compose`) for the scene whose buffers
        // `scene_buffers` binds, with its `Features::of`; every dynamic index is then in range:
        // - BVH stack (`traverse`): every node entry on the stack is of a different interior
        //   node on the path to the node being entered, its strict ancestor (a node pushes <= 1
        //   entry, for its children met but the one entered: `group_entry`; taking a child from
        //   an entry puts back at most that entry, of the child's parent). So entering the k-th
        //   interior node of a top-level path the stack holds <= k - 1 node entries, and <= D
        //   after it (D = `QuantizedBvh::depth`); a top-level leaf pushes <= L =
        //   `largest_instance_leaf` instances; inside an instance, whose entry leaves
        //   <= D + L - 1, its mesh's nodes add <= Dm (Dm = `instance_depth`). So every write
        //   is below BVH_STACK = max(D, 1) + L + Dm (`compose`). An entry's node is an interior
        //   node's index (below the node count, itself below GROUP_NODE_LIMIT: `check_fits`),
        //   and its lanes are below 4; an instance's entry reads node 0 (which exists: an
        //   empty hierarchy gets one).
        // - Node references (`gpu_bvh`): interior ones < the node count (`QuantizedBvh`), a
        //   lane past a node's `lanes` (BVH_EMPTY) is never entered; a leaf's first + count <=
        //   bvh.primitives.len() <= BVH_LEAF_OFFSET_LIMIT, and its count fits its bits (both
        //   checked in `check_fits`). Packed primitive indices are < their
        //   kind's length, and a shape's array is read only under its kind (`consider_shape`,
        //   `shape_light_of` in `shape_dispatch`), declared for every kind the scene has;
        //   instance roots are references of their mesh's root.
        // - Texels: node texels 4i..4i+3 and image texels lie below `texel_rows` rows x TEXEL_ROW
        //   (`check_fits`); image x and y are clamped to the image (`wrap`, `cdf_pick`,
        //   `environment_pdf_at`) at the offsets `ImageArray` placed it.
        // - Uniform arrays hold their capacities (SCENE_CAPACITY, BVH_CAPACITY,
        //   BVH_PRIMITIVE_CAPACITY) >= the counts (`Features::of`); storage arrays are exact, and
        //   empty ones hold one element that is never read.
        // - Materials are renumbered below materials.len() (`FlatScene::with_instancing`); a
        //   medium is its material + 1 and a light 1 + its index, read only when non-zero; NEE
        //   code is composed only for scenes with a light (`Features::with_integrator`), and
        //   `check_kernel` refuses a kernel whose features or source are not this render's.
        // - Corner normals exist (9 floats per triangle) wherever SHADING_NORMALS is on, corner
        //   texture coordinates (6 floats per triangle) wherever TRIANGLE_UVS is, their second
        //   set (6) wherever TRIANGLE_UVS1 is, corner tangents (12) wherever NORMAL_MAPS is, and
        //   corner colours (9) wherever VERTEX_COLORS is.
        // - A normal map's texels lie in the images array: its size is its image's, and its
        //   start where `ImageArray` placed that image; texel indices are wrapped into it.
        // - accum: gid < tile_size <= (width, tile_rows), and the buffer holds tile_rows x width
        //   x ACCUM_WORDS words (below 2^32: `max_tile_pixels`); debug outputs hold a slot per
        //   invocation (`run_debug`).
        unsafe {
            self.compile(
                features,
                source,
                entry_point,
                wgpu::ShaderRuntimeChecks::unchecked(),
            )
        }
    }

    /// [`GpuRenderer::kernel`] with wgpu's bounds checks and loop guards kept: the same
    /// kernel, safe whatever it indexes (tests compare its images with the unchecked one's).
    pub fn checked_kernel(
        &self,
        scene: &FlatScene,
        features: Features,
        entry_point: &str,
    ) -> Result<Kernel, GpuError> {
        let features = self.for_device(features);
        let source = compose(&features, scene).map_err(GpuError::Shader)?;
        self.checked_kernel_from_source(features, source, entry_point)
    }

    /// Compiles any WGSL `source` with wgpu's runtime checks; errors come back as
    /// [`GpuError::Shader`], never a panic.
    pub fn checked_kernel_from_source(
        &self,
        features: Features,
        source: String,
        entry_point: &str,
    ) -> Result<Kernel, GpuError> {
        // SAFETY: with wgpu's runtime checks on, any source is safe to run.
        unsafe {
            self.compile(
                features,
                source,
                entry_point,
                wgpu::ShaderRuntimeChecks::checked(),
            )
        }
    }

    /// Compiles WGSL `source` with `checks`; errors come back as [`GpuError::Shader`].
    ///
    /// # Safety
    /// Unless `checks` are wgpu's full runtime checks, every index the kernel makes must be in
    /// range of what it binds: `source` composed by `shader::compose` for the scene it renders
    /// (see the SAFETY note in [`GpuRenderer::kernel`]).
    unsafe fn compile(
        &self,
        features: Features,
        source: String,
        entry_point: &str,
        checks: wgpu::ShaderRuntimeChecks,
    ) -> Result<Kernel, GpuError> {
        validate(&source).map_err(GpuError::Shader)?;
        let device = &self.ctx.device;
        let bind_group_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("scene"),
            entries: &layout_entries(&features),
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("scene"),
            bind_group_layouts: &[Some(&bind_group_layout)],
            immediate_size: 0,
        });
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let descriptor = wgpu::ShaderModuleDescriptor {
            label: Some("rt-gpu kernel"),
            source: wgpu::ShaderSource::Wgsl(source.as_str().into()),
        };
        // SAFETY: the caller vouches for `source` where `checks` are not wgpu's full checks.
        let module = unsafe { device.create_shader_module_trusted(descriptor, checks) };
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(entry_point),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some(entry_point),
            compilation_options: Default::default(),
            cache: None,
        });
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(GpuError::Shader(e.to_string().replace('\n', " ")));
        }
        if let Some(e) = self.ctx.take_failure() {
            return Err(e);
        }
        Ok(Kernel {
            features,
            source,
            pipeline,
            bind_group_layout,
        })
    }

    /// Most pixels one tile may hold: its accumulator must fit one storage binding.
    pub(super) fn max_tile_pixels(&self) -> u64 {
        let binding = self
            .ctx
            .limits
            .max_storage_buffer_binding_size
            .min(self.ctx.limits.max_buffer_size);
        // The kernel's accumulator index (ACCUM_WORDS x pixel) is a u32.
        (binding / ACCUM_BYTES_PER_PIXEL).min(u32::MAX as u64 / ACCUM_WORDS as u64)
    }

    /// The scene arrays as buffers of the kind `features` asks for: uniform arrays padded to
    /// their fixed capacity, or storage arrays.
    pub(super) fn scene_buffers(
        &self,
        scene: &FlatScene,
        features: &Features,
    ) -> Result<SceneBindings, GpuError> {
        let mut buffers = SceneBuffers::new(scene);
        let (node_rows, image_rows) = self.check_fits(scene, &buffers)?;
        let usage = if features.uniform_scene {
            let capacity = features.scene_capacity.max(1) as usize;
            for shapes in &mut buffers.shapes {
                shapes.resize(capacity);
            }
            buffers.materials.resize(capacity, Default::default());
            buffers.lights.resize(capacity, Default::default());
            wgpu::BufferUsages::UNIFORM
        } else {
            wgpu::BufferUsages::STORAGE
        };
        let make = |label, contents: &[u8]| self.buffer_with(label, contents, usage);
        let primitives_usage = if features.uniform_bvh {
            let words = 4 * features.bvh_primitive_capacity.max(1) as usize;
            buffers.bvh_primitives.resize(words, 0);
            wgpu::BufferUsages::UNIFORM
        } else {
            wgpu::BufferUsages::STORAGE
        };
        let bvh_nodes = if features.uniform_bvh {
            buffers
                .bvh_nodes
                .resize(features.bvh_capacity.max(1) as usize, Default::default());
            NodeBinding::Uniform(self.buffer_with(
                "bvh nodes",
                bytemuck::cast_slice(&buffers.bvh_nodes),
                wgpu::BufferUsages::UNIFORM,
            ))
        } else {
            NodeBinding::Texture(self.texel_texture(
                "bvh nodes",
                bytemuck::cast_slice(&buffers.bvh_nodes),
                node_rows as u32,
            ))
        };
        let images = self.texel_texture(
            "images",
            bytemuck::cast_slice(&ImageArray::new(scene).values),
            image_rows as u32,
        );
        let storage =
            |label, contents: &[u8]| self.buffer_with(label, contents, wgpu::BufferUsages::STORAGE);
        Ok(SceneBindings {
            shapes: (buffers.shapes.iter().zip(crate::shape::KINDS))
                .map(|(records, kind)| make(kind.array, &records.bytes))
                .collect(),
            materials: make("materials", bytemuck::cast_slice(&buffers.materials)),
            lights: make("lights", bytemuck::cast_slice(&buffers.lights)),
            triangles: storage("triangles", bytemuck::cast_slice(&buffers.triangles)),
            bvh_primitives: self.buffer_with(
                "bvh primitives",
                bytemuck::cast_slice(&buffers.bvh_primitives),
                primitives_usage,
            ),
            triangle_normals: storage(
                "triangle normals",
                bytemuck::cast_slice(&buffers.triangle_normals),
            ),
            triangle_uvs: storage(
                "triangle texture coordinates",
                bytemuck::cast_slice(&buffers.triangle_uvs),
            ),
            triangle_tangents: storage(
                "triangle tangents",
                bytemuck::cast_slice(&buffers.triangle_tangents),
            ),
            triangle_colors: storage(
                "triangle colours",
                bytemuck::cast_slice(&buffers.triangle_colors),
            ),
            triangle_uvs1: storage(
                "triangle second texture coordinates",
                bytemuck::cast_slice(&buffers.triangle_uvs1),
            ),
            instances: storage("instances", bytemuck::cast_slice(&buffers.instances)),
            bvh_nodes,
            images,
        })
    }

    /// Refuses a scene whose buffers or textures exceed this device's limits or the kernel's
    /// encodings; the rows of texels its BVH's nodes and its images take.
    fn check_fits(
        &self,
        scene: &FlatScene,
        buffers: &SceneBuffers,
    ) -> Result<(u64, u64), GpuError> {
        let limit = self
            .ctx
            .limits
            .max_storage_buffer_binding_size
            .min(self.ctx.limits.max_buffer_size);
        let shapes = (buffers.shapes.iter().zip(crate::shape::KINDS))
            .map(|(records, kind)| (kind.array, records.bytes.len()));
        let geometry = [
            ("triangles", std::mem::size_of_val(&buffers.triangles[..])),
            (
                "vertex normals",
                std::mem::size_of_val(&buffers.triangle_normals[..]),
            ),
            (
                "texture coordinates",
                std::mem::size_of_val(&buffers.triangle_uvs[..]),
            ),
            (
                "tangents",
                std::mem::size_of_val(&buffers.triangle_tangents[..]),
            ),
            (
                "vertex colours",
                std::mem::size_of_val(&buffers.triangle_colors[..]),
            ),
            (
                "second texture coordinates",
                std::mem::size_of_val(&buffers.triangle_uvs1[..]),
            ),
            ("instances", std::mem::size_of_val(&buffers.instances[..])),
            ("lights", std::mem::size_of_val(&buffers.lights[..])),
        ];
        for (what, bytes) in geometry.into_iter().chain(shapes) {
            if bytes as u64 > limit {
                return Err(GpuError::TooLarge(format!(
                    "the scene's {what} take {} MB, more than this GPU binds at once ({} MB): use fewer triangles, or --backend cpu",
                    bytes >> 20,
                    limit >> 20
                )));
            }
        }
        let max_rows = self.ctx.limits.max_texture_dimension_2d as u64;
        let node_rows = texel_rows(4 * buffers.bvh_nodes.len() as u64);
        let largest_leaf = scene
            .bvh
            .nodes
            .iter()
            .filter(|n| n.is_leaf())
            .map(|n| n.count)
            .max()
            .unwrap_or(0);
        if largest_leaf >= BVH_LEAF_COUNT_LIMIT {
            return Err(GpuError::TooLarge(format!(
                "the scene's BVH has a leaf of {largest_leaf} primitives at its depth limit, more than the kernel's leaves hold: use --backend cpu"
            )));
        }
        if buffers.bvh_primitives.len() as u64 > BVH_LEAF_OFFSET_LIMIT as u64 {
            return Err(GpuError::TooLarge(format!(
                "the scene's BVH has {} primitive references, more than the kernel can address ({BVH_LEAF_OFFSET_LIMIT}): use fewer triangles, or --backend cpu",
                buffers.bvh_primitives.len()
            )));
        }
        if buffers.bvh_nodes.len() as u64 > GROUP_NODE_LIMIT as u64 {
            return Err(GpuError::TooLarge(format!(
                "the scene's BVH has {} nodes, more than the kernel's traversal addresses ({GROUP_NODE_LIMIT}): use fewer triangles, or --backend cpu",
                buffers.bvh_nodes.len()
            )));
        }
        if node_rows > max_rows {
            return Err(GpuError::TooLarge(format!(
                "the scene's BVH nodes take {node_rows} rows of texels, more than this GPU's largest texture ({max_rows}): use fewer triangles, or --backend cpu"
            )));
        }
        let image_rows = texel_rows(buffers.images.bytes() / 16);
        if buffers.images.bytes() / 16 > image_capacity(&self.ctx.limits) {
            let environment = match &scene.background {
                crate::scene::Background::Environment(env) => Some(env.image.clone()),
                _ => None,
            };
            let largest = buffers
                .images
                .largest_texture()
                .into_iter()
                .chain(environment)
                .max_by_key(|i| i.width as u64 * i.height as u64);
            let named = largest.map_or(String::new(), |i| {
                format!(" (the largest: {}, {}x{})", i.source, i.width, i.height)
            });
            return Err(GpuError::TooLarge(format!(
                "the scene's images take {} MB{named}, more than this GPU's largest texture holds ({} MB, {max_rows} rows of {TEXEL_ROW} texels): use smaller images, or --backend cpu",
                buffers.images.bytes() >> 20,
                (max_rows * TEXEL_ROW as u64 * 16) >> 20
            )));
        }
        Ok((node_rows, image_rows))
    }

    /// `bytes` as the `Rgba32Uint` texels of a texture `TEXEL_ROW` wide and `rows` high.
    fn texel_texture(&self, label: &str, bytes: &[u8], rows: u32) -> wgpu::TextureView {
        let mut texels = bytes.to_vec();
        texels.resize(rows as usize * TEXEL_ROW as usize * 16, 0);
        let texture = self.ctx.device.create_texture_with_data(
            &self.ctx.queue,
            &wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d {
                    width: TEXEL_ROW,
                    height: rows,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba32Uint,
                usage: wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            },
            wgpu::util::TextureDataOrder::LayerMajor,
            &texels,
        );
        texture.create_view(&Default::default())
    }

    pub(super) fn bind_group(
        &self,
        kernel: &Kernel,
        [params, dispatch]: [&wgpu::Buffer; 2],
        scene: &SceneBindings,
        accum: &wgpu::Buffer,
        debug: &wgpu::Buffer,
    ) -> wgpu::BindGroup {
        let resource = |binding: Binding| match binding {
            Binding::Params => params.as_entire_binding(),
            Binding::Materials => scene.materials.as_entire_binding(),
            Binding::Accum => accum.as_entire_binding(),
            Binding::Bounces => debug.as_entire_binding(),
            Binding::Lights => scene.lights.as_entire_binding(),
            Binding::Dispatch => dispatch.as_entire_binding(),
            Binding::ImageTexels => wgpu::BindingResource::TextureView(&scene.images),
            Binding::Triangles => scene.triangles.as_entire_binding(),
            Binding::BvhNodes => match &scene.bvh_nodes {
                NodeBinding::Texture(view) => wgpu::BindingResource::TextureView(view),
                NodeBinding::Uniform(buffer) => buffer.as_entire_binding(),
            },
            Binding::BvhPrimitives => scene.bvh_primitives.as_entire_binding(),
            Binding::TriangleNormals => scene.triangle_normals.as_entire_binding(),
            Binding::TriangleUvs => scene.triangle_uvs.as_entire_binding(),
            Binding::TriangleTangents => scene.triangle_tangents.as_entire_binding(),
            Binding::TriangleColors => scene.triangle_colors.as_entire_binding(),
            Binding::TriangleUvs1 => scene.triangle_uvs1.as_entire_binding(),
            Binding::Instances => scene.instances.as_entire_binding(),
        };
        let shapes =
            scene
                .shapes
                .iter()
                .enumerate()
                .map(|(position, buffer)| wgpu::BindGroupEntry {
                    binding: shape_binding(position),
                    resource: buffer.as_entire_binding(),
                });
        let entries: Vec<wgpu::BindGroupEntry> = BINDINGS
            .iter()
            .map(|&b| wgpu::BindGroupEntry {
                binding: b.number(),
                resource: resource(b),
            })
            .chain(shapes)
            .collect();
        self.ctx
            .device
            .create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("scene"),
                layout: &kernel.bind_group_layout,
                entries: &entries,
            })
    }

    pub(super) fn buffer_with(
        &self,
        label: &str,
        contents: &[u8],
        usage: wgpu::BufferUsages,
    ) -> wgpu::Buffer {
        self.ctx
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            })
    }

    pub(super) fn buffer(&self, label: &str, size: u64, usage: wgpu::BufferUsages) -> wgpu::Buffer {
        self.ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: size.max(16),
            usage,
            mapped_at_creation: false,
        })
    }

    /// Copies `size` bytes of `source` back to the host.
    pub(super) fn read_back(&self, source: &wgpu::Buffer, size: u64) -> Result<Vec<u8>, GpuError> {
        let staging = self.buffer(
            "readback",
            size,
            wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        );
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(source, 0, &staging, 0, size);
        self.ctx.queue.submit([encoder.finish()]);
        self.ctx.read_staging(&staging, size, "GPU memory")
    }

    /// Renders `opts.spp` samples per pixel with `kernel`, tile by tile; `on_progress` gets the
    /// fraction done.
    pub fn render(
        &self,
        kernel: &Kernel,
        scene: &FlatScene,
        opts: &RenderOptions,
        tuning: &Tuning,
        on_progress: &dyn Fn(f64),
    ) -> Result<(Film, Timings), GpuError> {
        self.check_kernel(kernel, scene, opts)?;
        let (width, height) = (opts.width, opts.height);
        let plan = self.plan_dispatches(kernel, scene, opts, tuning)?;
        let mut sizer = plan.sizer;
        let tile_rows = sizer.max_tile_rows().min(height);
        let scene_buffers = self.scene_buffers(scene, &kernel.features)?;
        let tiles = TileRenderer::new(self, kernel, opts, &plan.params, &scene_buffers, tile_rows);
        tiles.warm_up()?;
        let mut film = Film::new(width, height);
        film.stratified = opts.sampler == SamplerKind::Sobol;
        let mut timings = Timings::default();
        let mut gpu_seconds = 0.0;
        let mut y0 = 0;
        while y0 < height {
            let rows = sizer.next_tile_rows(height - y0);
            tiles.clear(rows);
            gpu_seconds += tiles.sample(y0, rows, &mut sizer, &mut timings, on_progress)?;
            gpu_seconds +=
                tiles.finish_into(&mut film, y0, rows, sizer.max_slice(), &mut timings)?;
            y0 += rows;
        }
        // Some backends (OpenGL) accept timestamp queries and return zeros.
        timings.gpu_seconds = (tiles.timer.is_some() && gpu_seconds > 0.0).then_some(gpu_seconds);
        Ok((film, timings))
    }

    /// Refuses a kernel built for another integrator, sampler or scene.
    pub(super) fn check_kernel(
        &self,
        kernel: &Kernel,
        scene: &FlatScene,
        opts: &RenderOptions,
    ) -> Result<(), GpuError> {
        if kernel.features.for_render(scene, opts) != kernel.features {
            return Err(GpuError::Runtime(format!(
                "this kernel was not built for the {} integrator and the {} sampler",
                opts.integrator.name(),
                opts.sampler.name()
            )));
        }
        // The unchecked kernel's indices are in range only for the scene it was composed for
        // (its stack depth, capacities and inlined primitives): see the SAFETY note in
        // `kernel`.
        if compose(&kernel.features, scene).map_err(GpuError::Shader)? != kernel.source {
            return Err(GpuError::Runtime(
                "this kernel was composed for another scene: compile one for this scene".into(),
            ));
        }
        Ok(())
    }

    /// How the render's dispatches are sized: the loop budget on lavapipe, the most samples one
    /// dispatch may take, and the render's parameters.
    pub(super) fn plan_dispatches(
        &self,
        kernel: &Kernel,
        scene: &FlatScene,
        opts: &RenderOptions,
        tuning: &Tuning,
    ) -> Result<DispatchPlan, GpuError> {
        let width = opts.width;
        let max_tile_pixels = self.max_tile_pixels();
        if (width as u64) > max_tile_pixels {
            return Err(GpuError::TooLarge(format!(
                "a {width}-pixel row does not fit one GPU storage binding ({max_tile_pixels} pixels)"
            )));
        }
        let is_llvmpipe = self.ctx.info.name.contains("llvmpipe");
        // BVH kernels count their loops against a budget on lavapipe (see shaders/accel.wgsl):
        // half the limit, each traversal iteration counted once per SIMD lane.
        let budget = if kernel.features.loop_budget {
            Some((LOOP_ITERATION_BUDGET / 2, simd_lanes(&self.ctx.info.name)))
        } else {
            None
        };
        let (cost, sample_loop_cost) = loop_cost(
            scene,
            &kernel.features,
            opts,
            budget.map_or(1, |(_, lanes)| lanes as u64),
        );
        let max_slice = match cost.max_samples_per_dispatch() {
            Some(slice) => slice,
            // Traversals count their own iterations: one sample per dispatch at the least.
            None if kernel.features.bvh && budget.is_none_or(|(b, _)| sample_loop_cost < b) => 1,
            None if budget.is_some() || is_llvmpipe => {
                return Err(GpuError::TooLarge(format!(
                    "this scene needs up to {} loop iterations per sample, more than the {LOOP_ITERATION_BUDGET} rt-gpu allows one invocation on lavapipe (which silently ends it at 65535): use fewer primitives or a lower --max-depth, or --backend cpu",
                    cost.per_sample
                )));
            }
            None => 1,
        };
        Ok(DispatchPlan {
            sizer: DispatchSizer::new(width, max_tile_pixels, max_slice, *tuning),
            params: GpuParams {
                sample_loop_cost: sample_loop_cost.min(u32::MAX as u64) as u32,
                traversal_weight: budget.map_or(1, |(_, lanes)| lanes),
                loop_budget: budget.map_or(u32::MAX, |(b, _)| b as u32),
                ..base_params(scene, opts)
            },
        })
    }

    /// The first bounce of sample `opts.first_sample` of every pixel, from the debug kernel.
    pub fn first_bounce(
        &self,
        scene: &FlatScene,
        opts: &RenderOptions,
    ) -> Result<Vec<GpuFirstBounce>, GpuError> {
        let pixels = opts.width as usize * opts.height as usize;
        let slots = vec![GpuFirstBounce::default(); pixels];
        self.run_debug(scene, opts, "first_bounce", slots)
    }

    /// The closest hit of each ray (origin, unit direction), from the debug kernel: `point`,
    /// `normal` and `primitive` are set when `hit` is 1.
    pub fn trace_rays(
        &self,
        scene: &FlatScene,
        rays: &[(glam::Vec3, glam::Vec3)],
    ) -> Result<Vec<GpuFirstBounce>, GpuError> {
        let slots: Vec<GpuFirstBounce> = rays
            .iter()
            .map(|(origin, dir)| GpuFirstBounce {
                point: origin.to_array(),
                dir: dir.to_array(),
                ..Default::default()
            })
            .collect();
        let opts = RenderOptions::new(rays.len().max(1) as u32, 1, 1, 1);
        self.run_debug(scene, &opts, "trace_rays", slots)
    }

    /// The albedo of material `material` (an index into `scene.materials`) at each
    /// `(material, point, uv)`, by the kernel's texture lookup (`look_up_albedo` in
    /// `shaders/kernel.wgsl`).
    pub fn look_up_albedo(
        &self,
        scene: &FlatScene,
        lookups: &[(u32, glam::Vec3, glam::Vec2)],
    ) -> Result<Vec<glam::Vec3>, GpuError> {
        // The kernel reads the material unchecked.
        if let Some((bad, _, _)) = lookups
            .iter()
            .find(|(m, _, _)| *m as usize >= scene.materials.len())
        {
            return Err(GpuError::Runtime(format!(
                "material {bad} does not exist (the scene has {})",
                scene.materials.len()
            )));
        }
        let slots: Vec<GpuFirstBounce> = lookups
            .iter()
            .map(|(material, point, uv)| GpuFirstBounce {
                point: point.to_array(),
                primitive: *material,
                normal: [uv.x, uv.y, 0.0],
                ..Default::default()
            })
            .collect();
        let opts = RenderOptions::new(lookups.len().max(1) as u32, 1, 1, 1);
        let out = self.run_debug(scene, &opts, "look_up_albedo", slots)?;
        Ok(out.iter().map(|b| glam::Vec3::from(b.dir)).collect())
    }

    /// The kernel's BSDF interface (`sample_bsdf` in `shaders/kernel.wgsl`) at each query:
    /// its material's `bsdf_sample` toward `wo` with sample `opts.first_sample`'s numbers of
    /// the query's index (after one `begin`; `opts.width` must be the query count and
    /// `opts.height` 1), and `bsdf_eval` and `bsdf_pdf` at (`wo`, `wi`). The scene must be
    /// built with nee (`opts.integrator`) and a light, as the kernel holds `eval` and `pdf`
    /// only then.
    pub fn sample_bsdf(
        &self,
        scene: &FlatScene,
        opts: &RenderOptions,
        queries: &[BsdfQuery],
    ) -> Result<Vec<BsdfAnswer>, GpuError> {
        if let Some(bad) = queries
            .iter()
            .find(|q| q.material as usize >= scene.materials.len())
        {
            return Err(GpuError::Runtime(format!(
                "material {} does not exist (the scene has {})",
                bad.material,
                scene.materials.len()
            )));
        }
        if (opts.width as usize, opts.height) != (queries.len(), 1) {
            return Err(GpuError::Runtime(format!(
                "{} queries need a {}x1 grid, got {}x{}",
                queries.len(),
                queries.len(),
                opts.width,
                opts.height
            )));
        }
        let slots: Vec<GpuFirstBounce> = queries
            .iter()
            .map(|q| GpuFirstBounce {
                point: q.wo.to_array(),
                primitive: q.material,
                normal: q.normal.to_array(),
                hit: q.front_face as u32,
                dir: q.wi.to_array(),
                ..Default::default()
            })
            .collect();
        let out = self.run_debug(scene, opts, "sample_bsdf", slots)?;
        Ok(out
            .iter()
            .map(|b| BsdfAnswer {
                weight: glam::Vec3::from(b.point),
                pdf: f32::from_bits(b.primitive),
                wi: glam::Vec3::from(b.normal),
                lobe: b.hit,
                eval: glam::Vec3::from(b.dir),
                eval_pdf: f32::from_bits(b.scattered),
            })
            .collect())
    }

    /// The scene's environment as the kernel sees it (`look_up_environment` in
    /// `shaders/kernel.wgsl`): for each (unit direction, u1, u2), the radiance from that
    /// direction and its pdf, and the direction sampled with (u1, u2) and its pdf (0: none).
    pub fn look_up_environment(
        &self,
        scene: &FlatScene,
        lookups: &[(glam::Vec3, f32, f32)],
    ) -> Result<Vec<EnvironmentLookup>, GpuError> {
        let slots: Vec<GpuFirstBounce> = lookups
            .iter()
            .map(|(dir, u1, u2)| GpuFirstBounce {
                point: dir.to_array(),
                normal: [*u1, *u2, 0.0],
                ..Default::default()
            })
            .collect();
        let opts = RenderOptions::new(lookups.len().max(1) as u32, 1, 1, 1);
        let out = self.run_debug(scene, &opts, "look_up_environment", slots)?;
        Ok(out
            .iter()
            .map(|b| EnvironmentLookup {
                radiance: glam::Vec3::from(b.point),
                pdf: f32::from_bits(b.primitive),
                sampled: glam::Vec3::from(b.normal),
                sampled_pdf: f32::from_bits(b.hit),
            })
            .collect())
    }

    /// The first twelve numbers of sample `opts.first_sample` of every pixel, as bits (see
    /// `draw_samples` in `shaders/kernel.wgsl`), under `opts.sampler` and `opts.seed`.
    pub fn draw_samples(
        &self,
        scene: &FlatScene,
        opts: &RenderOptions,
    ) -> Result<Vec<[u32; 12]>, GpuError> {
        let slots = vec![GpuFirstBounce::default(); (opts.width * opts.height) as usize];
        let out = self.run_debug(scene, opts, "draw_samples", slots)?;
        Ok(out
            .iter()
            .map(|b| bytemuck::cast::<GpuFirstBounce, [u32; 12]>(*b))
            .collect())
    }

    /// Runs debug entry point `entry` once over an `opts.width` x `opts.height` grid whose
    /// slots start as `slots` and are read back.
    fn run_debug(
        &self,
        scene: &FlatScene,
        opts: &RenderOptions,
        entry: &str,
        slots: Vec<GpuFirstBounce>,
    ) -> Result<Vec<GpuFirstBounce>, GpuError> {
        let features = Features {
            debug: true,
            sobol: opts.sampler == SamplerKind::Sobol,
            ..Features::of(scene).with_integrator(scene, opts.integrator)
        };
        let kernel = self.kernel(scene, features, entry)?;
        let size = (slots.len().max(1) * std::mem::size_of::<GpuFirstBounce>()) as u64;
        let mut contents = bytemuck::cast_slice(&slots).to_vec();
        contents.resize(size as usize, 0);
        let out = self.buffer_with(
            "debug slots",
            &contents,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        );
        let params_buffer = self.buffer_with(
            "params",
            bytemuck::bytes_of(&base_params(scene, opts)),
            wgpu::BufferUsages::UNIFORM,
        );
        let dispatch_buffer = self.buffer_with(
            "dispatch",
            bytemuck::bytes_of(&whole_image_dispatch(opts)),
            wgpu::BufferUsages::STORAGE,
        );
        let accum = self.buffer("unused", 16, wgpu::BufferUsages::STORAGE);
        let buffers = self.scene_buffers(scene, &kernel.features)?;
        let bind_group = self.bind_group(
            &kernel,
            [&params_buffer, &dispatch_buffer],
            &buffers,
            &accum,
            &out,
        );
        let mut encoder = self.ctx.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&kernel.pipeline);
            pass.set_bind_group(0, &bind_group, &[]);
            pass.dispatch_workgroups(
                opts.width.div_ceil(WORKGROUP_SIZE),
                opts.height.div_ceil(WORKGROUP_SIZE),
                1,
            );
        }
        self.ctx.queue.submit([encoder.finish()]);
        self.ctx.wait()?;
        let bytes = self.read_back(&out, size)?;
        let mut result: Vec<GpuFirstBounce> = bytemuck::cast_slice(&bytes).to_vec();
        result.truncate(slots.len());
        Ok(result)
    }
}

/// The vec4fs of images (an image's texels and an environment's CDFs) a device's kernel holds:
/// its image texture's rows, the device's largest, of `TEXEL_ROW` vec4fs.
pub fn image_capacity(limits: &wgpu::Limits) -> u64 {
    limits.max_texture_dimension_2d as u64 * TEXEL_ROW as u64
}

/// How a render's dispatches are sized, and its parameters.
pub(super) struct DispatchPlan {
    pub(super) sizer: DispatchSizer,
    pub(super) params: GpuParams,
}

#[cfg(test)]
mod tests {
    use super::simd_lanes;

    #[test]
    fn lavapipe_simd_width_is_read_from_its_name() {
        assert_eq!(simd_lanes("llvmpipe (LLVM 15.0.6, 256 bits)"), 8);
        assert_eq!(simd_lanes("llvmpipe (LLVM 19.1.7, 512 bits)"), 16);
        assert_eq!(simd_lanes("llvmpipe (LLVM 15.0.6, 128 bits)"), 4);
        assert_eq!(simd_lanes("llvmpipe"), 16);
    }
}
