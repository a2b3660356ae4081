//! The form every backend traces: world-space spheres and quads with precomputed planes, the
//! camera as a frame, and resolved materials. Boxes become six quads and instance transforms are
//! applied once here (a rigid motion of a sphere or parallelogram is again one), so no backend
//! transforms rays per hit; only a mesh placed more than once is kept in its own coordinates
//! and instanced (see [`Instance`]), its rays transformed into them.

use super::mesh::Mesh;
use super::{Background, Material, Scene, SceneError, Shape};
use crate::assets::image_lookup::UvSet;
use crate::assets::texture::Texture;
use crate::shape::{ShapeKind, ShapeVisitor, ShapeVisitorMut, SurfaceShape};
use crate::shared::primitive::{
    KIND_INSTANCE, KIND_TRIANGLE, MAX_PRIMITIVES_PER_KIND, PrimitiveRef,
};
use glam::{DVec3, Vec2, Vec3, Vec4};
use std::sync::Arc;

pub use crate::shape::{Disk, Quad, Shapes, Sphere};

/// A triangle `p0 p1 p2`, its front face counter-clockwise (along `(p1 - p0) x (p2 - p0)`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle {
    pub p0: Vec3,
    pub p1: Vec3,
    pub p2: Vec3,
    pub material: u32,
    /// 1 + this triangle's index in [`FlatScene::lights`]; 0 when it does not emit.
    pub light: u32,
}

impl Triangle {
    /// Its area (in f64: tiny triangles far from the origin keep theirs).
    pub fn area(&self) -> f64 {
        let [a, b, c] = [self.p0, self.p1, self.p2].map(|p| p.as_dvec3());
        0.5 * (b - a).cross(c - a).length()
    }
}

/// The camera reduced to what ray generation needs: a ray for film position (s, t) in [0, 1]^2
/// (t down from the top) from `origin` points along `to_upper_left + s * horizontal - t * vertical`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraFrame {
    pub origin: Vec3,
    /// From `origin` to the upper-left corner of the image in the plane of focus.
    pub to_upper_left: Vec3,
    pub horizontal: Vec3,
    pub vertical: Vec3,
    /// Unit vectors to the camera's right and up, for sampling the lens.
    pub right: Vec3,
    pub up: Vec3,
    pub lens_radius: f32,
}

/// A mesh placed by transform rather than copied: the same mesh placed more than once (with the
/// same material) is stored once, its triangles in its own coordinates, under a BVH of its own,
/// and each placement is an instance of it, which rays enter transformed into the mesh's
/// coordinates (two-level BVH).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Instance {
    /// Mesh coordinates to the scene's: row k of the 3x4 affine map, `p'_k = row.xyz . p + row.w`.
    pub to_world: [Vec4; 3],
    /// Its inverse, scene coordinates to the mesh's. Normals are carried by its transpose (the
    /// inverse transpose of `to_world`'s linear part), as flattening carries them.
    pub to_local: [Vec4; 3],
    /// Its placed bounds (in the BVH's top level).
    pub bounds: [Vec3; 2],
    /// Its mesh: an index in [`FlatScene::instanced_meshes`].
    pub mesh: u32,
    /// Its mesh's BVH: the index of the root node in [`FlatScene::bvh`].
    pub root: u32,
    pub material: u32,
}

impl Instance {
    #[inline]
    pub fn point_to_world(&self, p: Vec3) -> Vec3 {
        affine_point(&self.to_world, p)
    }

    #[inline]
    pub fn point_to_local(&self, p: Vec3) -> Vec3 {
        affine_point(&self.to_local, p)
    }

    /// A direction into mesh coordinates, not renormalised: distances along a ray (its t)
    /// stay the same in both.
    #[inline]
    pub fn vector_to_local(&self, v: Vec3) -> Vec3 {
        let [a, b, c] = self.to_local.map(|r| r.truncate().dot(v));
        Vec3::new(a, b, c)
    }

    /// A mesh corner's tangent in scene coordinates, as flattening places a copy's: its
    /// direction by `to_world` (tangents are surface vectors), unit, and its bitangent's sign
    /// turned where the placement mirrors. Zero stays zero.
    #[inline]
    pub fn tangent_to_world(&self, t: Vec4) -> Vec4 {
        let [r0, r1, r2] = self.to_world.map(|r| r.truncate());
        let along = Vec3::new(
            r0.dot(t.truncate()),
            r1.dot(t.truncate()),
            r2.dot(t.truncate()),
        );
        let mirrors = r0.dot(r1.cross(r2)) < 0.0;
        along
            .normalize_or_zero()
            .extend(if mirrors { -t.w } else { t.w })
    }

    /// A mesh normal in scene coordinates (by the transpose of `to_local`), not normalised.
    #[inline]
    pub fn normal_to_world(&self, n: Vec3) -> Vec3 {
        let [r0, r1, r2] = self.to_local.map(|r| r.truncate());
        r0 * n.x + r1 * n.y + r2 * n.z
    }

    /// A bound on every coordinate's magnitude in the sums that map `p` to the scene, per axis:
    /// `|to_world| |p| + |translation|` (what the rounding of `point_to_world` scales with,
    /// whatever cancels in it).
    #[inline]
    pub fn magnitude_to_world(&self, p: Vec3) -> Vec3 {
        let [a, b, c] = self
            .to_world
            .map(|r| r.truncate().abs().dot(p.abs()) + r.w.abs());
        Vec3::new(a, b, c)
    }
}

#[inline]
fn affine_point(rows: &[Vec4; 3], p: Vec3) -> Vec3 {
    let [a, b, c] = rows.map(|r| r.truncate().dot(p) + r.w);
    Vec3::new(a, b, c)
}

/// Flat scenes are re-centred near the camera in steps of this size (a power of two, so the
/// shift is exact): a scene whose camera is within this distance of the origin is not moved.
pub const RECENTRE_STEP: f64 = 1024.0;

/// Whether `material` has a texture looked up by surface (UV) coordinates, a normal map
/// among them.
fn reads_uvs(material: &Material) -> bool {
    material.extra_features().iter().any(|f| f.reads_uvs())
        || material.normal_maps().next().is_some()
        || material.alpha().is_some_and(|a| a.image.is_some())
}

/// Whether `material` reads an image at the second texture coordinate set (glTF's
/// TEXCOORD_1).
fn reads_uv1(material: &Material) -> bool {
    (material.images().iter()).any(|i| i.lookup.uv_set == UvSet::Second)
}

/// Triangle `i` of `mesh`'s corner coordinates of the second set: its first set's where it has
/// no second, as a shape's second coordinates are its first.
fn second_uvs(mesh: &Mesh, i: usize) -> [Vec2; 3] {
    (mesh.uvs1.get(i).or(mesh.uvs.get(i)).copied()).unwrap_or(BARYCENTRIC_UVS)
}

/// A mesh's corner tangents (`scene::tangents::of`), shared by its placements.
type Tangents = std::rc::Rc<[[Vec4; 3]]>;

/// The corner texture coordinates of a triangle whose mesh has none, in a scene where others
/// have them: interpolated, they are the barycentric weights a hit has without them.
pub const BARYCENTRIC_UVS: [Vec2; 3] = [Vec2::ZERO, Vec2::X, Vec2::Y];

/// [`FlatScene::kernel_bvh`], once made: what `bvh` determines, so equal whether made or not
/// (two flat scenes are equal by their hierarchies).
#[derive(Clone, Debug, Default)]
pub struct KernelBvhCache(std::sync::OnceLock<crate::accel::quantized::QuantizedBvh>);

impl PartialEq for KernelBvhCache {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct FlatScene {
    /// The world position of this scene's coordinate origin. Every position below is relative
    /// to it, so that geometry near a camera far from the world origin (1e7 away, say) keeps
    /// the precision it has near the origin: f32 spacing grows with distance from the origin,
    /// and rendering happens near the camera. It is the camera's position rounded toward zero
    /// to a multiple of [`RECENTRE_STEP`]; zero when the camera is within that of the origin.
    pub origin: DVec3,
    pub camera: CameraFrame,
    pub background: Background,
    /// The materials the primitives use (not every one the scene defines), which `material`
    /// fields of shapes and triangles index.
    pub materials: Vec<Material>,
    /// Spheres, quads, disks: every primitive but triangles, an array per kind.
    pub shapes: Shapes,
    /// The triangles placed in the scene, then from `instanced_triangles` on those of meshes
    /// placed as instances, in their meshes' own coordinates.
    pub triangles: Vec<Triangle>,
    /// Per triangle, its corners' unit shading normals, when some mesh of the scene has vertex
    /// normals (triangles of the others take their face's); empty otherwise. Those of
    /// instanced meshes are in their meshes' coordinates.
    pub triangle_normals: Vec<[Vec3; 3]>,
    /// Per triangle, its corners' texture coordinates, when some mesh of the scene has them and
    /// some material reads them (`uv_textures`); empty otherwise. Triangles without them take
    /// (0, 0), (1, 0), (0, 1), so their coordinates are their barycentric weights, as without.
    pub triangle_uvs: Vec<[Vec2; 3]>,
    /// Per triangle, its corners' second texture coordinates (glTF TEXCOORD_1; [`second_uvs`]),
    /// when some material reads them; empty otherwise.
    pub triangle_uvs1: Vec<[Vec2; 3]>,
    /// Per triangle, its corners' vertex colours (`Mesh::colors`), when some mesh of the scene
    /// has them (the other triangles' are white); empty otherwise.
    pub triangle_colors: Vec<[Vec3; 3]>,
    /// Per triangle, its corners' tangents (`scene::tangents`), when some mesh of the scene has
    /// a normal-mapped material (the other triangles' are zero, and never read); empty
    /// otherwise: in scene coordinates, an instanced mesh's in its own (placed at a hit by
    /// [`Instance::tangent_to_world`]).
    pub triangle_tangents: Vec<[Vec4; 3]>,
    /// Where the instanced meshes' triangles begin in `triangles`.
    pub instanced_triangles: usize,
    /// Each instanced mesh's triangles in `triangles`.
    pub instanced_meshes: Vec<std::ops::Range<usize>>,
    /// Every placement of a mesh that is placed more than once with one material (and neither
    /// emits nor bounds a medium): see [`Instance`].
    pub instances: Vec<Instance>,
    /// The deepest instanced mesh's BVH (levels below its root; 0 without instances): a ray
    /// descends the top level and then that many levels more.
    pub instance_depth: u32,
    /// Over every primitive and instance, and after it each instanced mesh's own (see
    /// [`Instance::root`]). The CPU traverses it, but for scenes of a few shapes, which it tests
    /// in turn (`cpu::intersect`); GPU kernels of small scenes test
    /// their primitives as straight-line code instead (see `gpu::shader::Features`).
    pub bvh: crate::accel::Bvh,
    /// The same hierarchy collapsed to `accel::wide::WIDTH` children per node, which the CPU
    /// traverses.
    pub wide_bvh: crate::accel::wide::WideBvh,
    /// The same hierarchy as the kernel traverses it (four wide, its boxes quantized), made
    /// when first asked for ([`Self::kernel_bvh`]): a CPU render never needs it.
    pub quantized_bvh: KernelBvhCache,
    /// The quads four to a block (`shapes.quads` in order), which the CPU tests together where
    /// it tests a scene's shapes in turn; built with the BVH.
    pub quad_blocks: Vec<crate::shape::quad::QuadBlock>,
    /// Every emitting sphere, quad and triangle, and last an environment background, for next-event
    /// estimation (see [`Light`]).
    pub lights: Vec<Light>,
    /// Most invisible medium boundaries a ray steps through between two events: a straight
    /// line crosses a convex surface at most twice, so twice the invisible spheres plus the
    /// invisible quads (six per box, of which a line crosses two) plus 2 for rays grazing a
    /// box's edge, where both faces may count; 0 without them. A path or shadow ray that would
    /// need more ends (only a numerically degenerate one can). It bounds the kernel's loops.
    pub medium_crossings: u32,
    /// Whether some material's texture needs surface (UV) coordinates: hits compute them.
    pub uv_textures: bool,
    /// Whether some material is see-through (`assets::alpha`): the closest-hit search asks it.
    pub see_through: bool,
    /// Where each box's six quads begin in `quads` (in the order of [`box_faces`]): kernels
    /// with the scene inlined test the six as one, as the slabs between opposite faces (see
    /// `box_test` in src/gpu/shader.rs: less work than six quad tests).
    /// The quads stay what the CPU, the BVH, lights and hits use.
    pub boxes: Vec<u32>,
}

/// An emitting primitive as light sampling sees it, picked in proportion to its power.
#[derive(Clone, Debug, PartialEq)]
pub struct Light {
    pub shape: LightShape,
    /// Chance of picking this light or one before it; the last light's is exactly 1.
    pub cdf: f32,
    /// Chance of picking this light.
    pub pick: f32,
}

/// How a light is sampled.
#[derive(Clone, Debug, PartialEq)]
pub enum LightShape {
    /// A shape of `crate::shape` of primitive kind `kind`, sampled as that shape samples it.
    Surface {
        kind: u32,
        light: crate::shape::SurfaceLight,
    },
    /// Uniformly on its area, `corner + a u + b v` with a, b >= 0, a + b <= 1.
    Triangle {
        corner: Vec3,
        u: Vec3,
        v: Vec3,
        /// Unit normal `u x v / |u x v|`.
        normal: Vec3,
        inv_area: f32,
    },
    /// A point light of radiant `intensity` (W/sr), or a spot of it: `axis` the unit direction
    /// it points, `ramp` the scale and offset of its falloff on cos(angle) (`Punctual::spot_ramp`;
    /// a point light's (0, 1): 1 everywhere).
    Point {
        position: Vec3,
        intensity: Vec3,
        axis: Vec3,
        ramp: [f32; 2],
    },
    /// Light arriving from the unit direction `toward` alone, of `irradiance` (W/m^2) on a
    /// surface facing it.
    Directional { toward: Vec3, irradiance: Vec3 },
    /// The environment (always the last light): directions by its image's distribution.
    Environment(crate::assets::environment::Environment),
}

impl LightShape {
    /// A light of no area, found by light sampling alone: its samples are directions with
    /// probability, not density.
    pub fn is_delta(&self) -> bool {
        matches!(
            self,
            LightShape::Point { .. } | LightShape::Directional { .. }
        )
    }
}

/// Most squares a UV checker may put across [0, 1] (f32 resolves 2^24 steps there).
pub const MAX_UV_CHECKS: f32 = 65536.0;

impl FlatScene {
    /// Flattens `scene` for an image of `width` x `height` pixels; a mesh placed more than once
    /// (with one material, neither emitting nor bounding a medium) is kept once and instanced.
    pub fn new(scene: &Scene, width: u32, height: u32) -> Result<Self, SceneError> {
        Self::with_instancing(scene, width, height, true)
    }

    /// As [`FlatScene::new`], but with `instancing` false every mesh placement is copied into
    /// the scene (what instancing must match).
    pub fn with_instancing(
        scene: &Scene,
        width: u32,
        height: u32,
        instancing: bool,
    ) -> Result<Self, SceneError> {
        scene.validate()?;
        crate::film::check_image_size(width, height).map_err(SceneError::Invalid)?;
        let origin = (scene.camera.look_from.as_dvec3() / RECENTRE_STEP).trunc() * RECENTRE_STEP;
        let mut primitives = Flattener::new(scene, instancing);
        // Only the materials some object uses, numbered in order of first use: a scene may
        // define thousands it never places, and the kernel holds every material it is given.
        let mut materials = Vec::new();
        let mut renumbered = vec![u32::MAX; scene.materials.len()];
        for object in &scene.objects {
            let slot = &mut renumbered[object.material as usize];
            if *slot == u32::MAX {
                *slot = materials.len() as u32;
                materials.push(
                    scene.materials[object.material as usize]
                        .clone()
                        .relocated(origin),
                );
            }
            primitives.add(object, origin, *slot);
        }
        let camera = camera_frame(scene, origin, width, height);
        let mut flat = primitives.finish(materials, origin, camera)?;
        flat.uv_textures = flat.materials.iter().any(reads_uvs);
        flat.see_through = flat.materials.iter().any(|m| m.alpha().is_some());
        flat.check_checker_scales()?;
        flat.collect_lights(&scene.punctual);
        flat.medium_crossings = flat.count_medium_crossings();
        flat.build_bvh();
        Ok(flat)
    }

    /// Points this scene's camera as `scene`'s (the scene it was flattened from, its camera
    /// moved) for a `width` x `height` image, if the camera stays in the scene's recentring
    /// cell; `false` (nothing changed) if it left it, when the scene must be flattened again.
    pub fn set_camera(&mut self, scene: &Scene, width: u32, height: u32) -> bool {
        let origin = (scene.camera.look_from.as_dvec3() / RECENTRE_STEP).trunc() * RECENTRE_STEP;
        if origin != self.origin {
            return false;
        }
        self.camera = camera_frame(scene, origin, width, height);
        true
    }

    /// Refuses checkers too fine for f32 to resolve where the scene lies: a solid checker's
    /// cubes must span at least 2^7 f32 steps at the scene's largest (camera-relative)
    /// coordinate, a UV checker at most 2^16 squares across [0, 1]; finer ones alias into
    /// noise or one colour.
    fn check_checker_scales(&self) -> Result<(), SceneError> {
        let extent = (self.bounding_radius() as f32).max(1e-30);
        let finest_solid = extent * 2f32.powi(-16);
        for m in &self.materials {
            for texture in m.textures() {
                match texture {
                    Texture::Checker(c) if c.scale < finest_solid => {
                        return Err(SceneError::Invalid(format!(
                            "checker scale {:e} is finer than f32 resolves in a scene {extent:.3e} across: use at least {finest_solid:.3e}",
                            c.scale
                        )));
                    }
                    Texture::UvChecker(c) if c.scale > MAX_UV_CHECKS => {
                        return Err(SceneError::Invalid(format!(
                            "uv_checker scale {:e} puts more squares across a surface than f32 resolves: use at most {MAX_UV_CHECKS}",
                            c.scale
                        )));
                    }
                    _ => {}
                }
            }
        }
        Ok(())
    }

    /// The hierarchy the kernel traverses (`accel::quantized`), collapsed from `bvh` on first
    /// use.
    pub fn kernel_bvh(&self) -> &crate::accel::quantized::QuantizedBvh {
        self.quantized_bvh.0.get_or_init(|| {
            crate::accel::quantized::QuantizedBvh::new(
                &self.bvh,
                self.instances.iter().map(|i| i.root),
            )
        })
    }

    /// Builds `bvh`: each instanced mesh's hierarchy (in mesh coordinates), then the top level
    /// over the placed primitives and the instances (bounded by their meshes' root boxes,
    /// placed), then the meshes' nodes appended after the top level's; sets each instance's
    /// bounds and root; and collapses it all into `wide_bvh`.
    pub fn build_bvh(&mut self) {
        use crate::accel::Bvh;
        let mesh_bvhs: Vec<Bvh> = self
            .instanced_meshes
            .iter()
            .map(|r| {
                Bvh::build(&mut triangle_items(
                    &self.triangles[r.clone()],
                    r.start as u32,
                ))
            })
            .collect();
        for instance in &mut self.instances {
            let root = &mesh_bvhs[instance.mesh as usize].nodes[0];
            instance.bounds = placed_bounds(instance, root.min, root.max);
        }
        self.bvh = Bvh::build(&mut self.bvh_items());
        self.instance_depth = 0;
        let mut roots = Vec::with_capacity(mesh_bvhs.len());
        for mesh_bvh in mesh_bvhs {
            self.instance_depth = self.instance_depth.max(mesh_bvh.depth);
            roots.push(self.bvh.append_hierarchy(mesh_bvh));
        }
        for instance in &mut self.instances {
            instance.root = roots[instance.mesh as usize];
        }
        let instance_roots = self.instances.iter().map(|i| i.root);
        let triangles = &self.triangles;
        let corners = |packed| match PrimitiveRef::unpacked(packed) {
            PrimitiveRef::Triangle(i) => {
                let t = &triangles[i as usize];
                Some([t.p0, t.p1, t.p2])
            }
            _ => None,
        };
        self.wide_bvh = crate::accel::wide::WideBvh::new(&self.bvh, instance_roots, corners);
        self.quantized_bvh = KernelBvhCache::default();
        self.quad_blocks = crate::shape::quad::QuadBlock::blocks(&self.shapes.quads);
    }

    /// Most instances one leaf of the BVH's top level holds (0 without instances).
    pub fn largest_instance_leaf(&self) -> u32 {
        let Some(first_mesh_node) = self.instances.iter().map(|i| i.root).min() else {
            return 0;
        };
        let instances_in = |n: &crate::accel::Node| {
            let leaf = &self.bvh.primitives[n.offset as usize..][..n.count as usize];
            let instance =
                |p: &&u32| matches!(PrimitiveRef::unpacked(**p), PrimitiveRef::Instance(_));
            leaf.iter().filter(instance).count() as u32
        };
        self.bvh.nodes[..first_mesh_node as usize]
            .iter()
            .filter(|n| n.is_leaf())
            .map(instances_in)
            .max()
            .unwrap_or(0)
    }

    /// Triangles as placed: the scene's own, and each instanced mesh's once per placement.
    pub fn placed_triangles(&self) -> usize {
        let mesh_size = |i: &Instance| self.instanced_meshes[i.mesh as usize].len();
        self.instanced_triangles + self.instances.iter().map(mesh_size).sum::<usize>()
    }

    /// Primitives stored (an instanced mesh's triangles once, however often it is placed).
    pub fn primitive_count(&self) -> usize {
        self.shapes.len() + self.triangles.len()
    }

    /// Every primitive's bounds, padded for the rounding of the intersection tests: what the
    /// BVH is built over.
    pub fn bvh_items(&self) -> Vec<crate::accel::Item> {
        use crate::accel::Item;
        struct Items(Vec<Item>);
        impl ShapeVisitor for Items {
            fn visit<S: SurfaceShape>(&mut self, kind: &'static ShapeKind, shapes: &[S]) {
                self.0.extend(shapes.iter().enumerate().map(|(i, s)| {
                    let [min, max] = s.padded_bounds();
                    let index = i as u32;
                    let primitive = PrimitiveRef::Shape {
                        kind: kind.kind,
                        index,
                    }
                    .packed();
                    Item::new(min, max, primitive)
                }));
            }
        }
        let mut items = Items(Vec::with_capacity(self.primitive_count()));
        self.shapes.visit(&mut items);
        let mut items = items.0;
        items.extend(triangle_items(
            &self.triangles[..self.instanced_triangles],
            0,
        ));
        let instances = self.instances.iter().enumerate().map(|(i, instance)| {
            let primitive = PrimitiveRef::Instance(i as u32).packed();
            Item::new(instance.bounds[0], instance.bounds[1], primitive)
        });
        items.extend(instances);
        items
    }

    /// Every primitive in the BVH's top level, in the order of their packed references: the
    /// shapes, placed triangles, instances (shapes of later kinds, disks, last).
    pub fn primitives(&self) -> impl Iterator<Item = PrimitiveRef> + '_ {
        let mut kinds: Vec<(u32, u32)> = crate::shape::KINDS
            .iter()
            .map(|k| (k.kind, self.shapes.count(k) as u32))
            .collect();
        kinds.push((KIND_TRIANGLE, self.instanced_triangles as u32));
        kinds.push((KIND_INSTANCE, self.instances.len() as u32));
        kinds.sort_by_key(|(kind, _)| *kind);
        kinds
            .into_iter()
            .flat_map(|(kind, count)| (0..count).map(move |index| PrimitiveRef::new(kind, index)))
    }

    fn count_medium_crossings(&self) -> u32 {
        struct Crossings<'a>(&'a [Material], u32);
        impl ShapeVisitor for Crossings<'_> {
            fn visit<S: SurfaceShape>(&mut self, _: &'static ShapeKind, shapes: &[S]) {
                let invisible = |s: &S| self.0[s.material() as usize].is_invisible() as u32;
                self.1 += S::CROSSINGS * shapes.iter().map(invisible).sum::<u32>();
            }
        }
        let mut crossings = Crossings(&self.materials, 0);
        self.shapes.visit(&mut crossings);
        if crossings.1 == 0 { 0 } else { crossings.1 + 2 }
    }

    /// Whether some primitive's material holds a medium.
    pub fn has_media(&self) -> bool {
        self.materials.iter().any(|m| m.interior().is_some())
    }

    /// The medium inside material `medium` - 1 (as the path loops track it; 0: none).
    #[inline]
    pub fn medium(&self, medium: u32) -> Option<&crate::material::Medium> {
        match medium {
            0 => None,
            m => self.materials[m as usize - 1].interior(),
        }
    }

    /// 1 + the index in `lights` of primitive `p`, or 0 when it does not emit.
    #[inline]
    pub fn light_of(&self, p: PrimitiveRef) -> u32 {
        match p {
            PrimitiveRef::Shape { kind, index } => self.shapes.light(kind, index),
            PrimitiveRef::Triangle(i) => self.triangles[i as usize].light,
            PrimitiveRef::Instance(_) => 0,
        }
    }

    /// The index in `lights` of the environment, if the background is one.
    #[inline]
    pub fn environment_light(&self) -> Option<usize> {
        self.lights
            .last()
            .filter(|l| matches!(l.shape, LightShape::Environment(_)))
            .map(|_| self.lights.len() - 1)
    }

    /// The radius of a sphere holding every primitive (half its bounding box's diagonal; 1
    /// without any): how large a disc the environment's light crosses, for weighing it against
    /// the other lights.
    pub fn bounding_radius(&self) -> f64 {
        struct Corners(Vec<Vec3>);
        impl ShapeVisitor for Corners {
            fn visit<S: SurfaceShape>(&mut self, _: &'static ShapeKind, shapes: &[S]) {
                self.0.extend(shapes.iter().flat_map(|s| s.bounds()));
            }
        }
        use rayon::prelude::*;
        let mut shapes = Corners(Vec::new());
        self.shapes.visit(&mut shapes);
        let instances = self.instances.iter().flat_map(|i| i.bounds);
        let none = || (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN));
        let grow =
            |(min, max): (DVec3, DVec3), p: Vec3| (min.min(p.as_dvec3()), max.max(p.as_dvec3()));
        // Minima and maxima are exact in any order: the triangles' in parallel.
        let triangles = (self.triangles[..self.instanced_triangles].par_iter())
            .fold(none, |b, t| [t.p0, t.p1, t.p2].into_iter().fold(b, grow))
            .reduce(none, |(a, b), (c, d)| (a.min(c), b.max(d)));
        let (min, max) = shapes.0.into_iter().chain(instances).fold(triangles, grow);
        let r = 0.5 * (max - min).length();
        if r > 0.0 && r.is_finite() { r } else { 1.0 }
    }

    /// Fills `lights` with every emitting primitive (the shapes in the order of `shapes!`, then
    /// triangles), the punctual lights and the environment,
    /// and links each primitive to its light. Lights are picked in proportion to their power,
    /// pi * luminance * area (twice that for two-sided ones).
    pub fn collect_lights(&mut self, punctual: &[super::punctual::Punctual]) {
        let mut lights = Vec::new();
        let mut powers = Vec::new();
        let materials = &self.materials;
        let mut area_lights = AreaLights {
            materials,
            lights: &mut lights,
            powers: &mut powers,
        };
        self.shapes.visit_mut(&mut area_lights);
        let placed_triangles = &mut self.triangles[..self.instanced_triangles];
        area_lights.add(placed_triangles, |t| t.light_shape());
        let radius = self.bounding_radius();
        for light in punctual {
            let (power, shape) = punctual_light(light, self.origin, radius);
            powers.push(power);
            lights.push(Light {
                shape,
                cdf: 0.0,
                pick: 0.0,
            });
        }
        if let Background::Environment(env) = &self.background {
            powers.push(env.power(self.bounding_radius()));
            lights.push(Light {
                shape: LightShape::Environment(env.clone()),
                cdf: 0.0,
                pick: 0.0,
            });
        }
        // (A light with no power share is never picked; hits on it then count in full.)
        let total: f64 = powers.iter().sum();
        let n = lights.len() as f64;
        let share = |p: f64| if total > 0.0 { p / total } else { 1.0 / n };
        let mut running = 0.0;
        for (light, power) in lights.iter_mut().zip(&powers) {
            light.pick = share(*power) as f32;
            // A share too small for a normal f32 is never drawn in practice; as 0, its samples
            // are refused rather than weighted by 1 / (a subnormal), which overflows.
            if light.pick < f32::MIN_POSITIVE {
                light.pick = 0.0;
            }
            running += share(*power);
            light.cdf = running as f32;
        }
        if let Some(last) = lights.last_mut() {
            last.cdf = 1.0;
        }
        self.lights = lights;
    }
}

/// A punctual light's power (how light picking weighs it) and its shape, in a scene whose
/// coordinates start at `origin` and whose primitives lie within `radius` of their centre: a
/// point's 4 pi I, a spot's 2 pi (1 - (cos inner + cos outer) / 2) I (pbrt-v4's), the sun's
/// pi r^2 E on the disc it crosses, of luminances.
fn punctual_light(
    light: &super::punctual::Punctual,
    origin: DVec3,
    radius: f64,
) -> (f64, LightShape) {
    use super::punctual::Punctual;
    use crate::assets::environment::luminance;
    use std::f64::consts::PI;
    let lum = |c: Vec3| luminance(c.x, c.y, c.z);
    let relative = |p: Vec3| (p.as_dvec3() - origin).as_vec3();
    match *light {
        Punctual::Point {
            position,
            intensity,
        } => (
            4.0 * PI * lum(intensity),
            LightShape::Point {
                position: relative(position),
                intensity,
                axis: Vec3::Z,
                ramp: [0.0, 1.0],
            },
        ),
        Punctual::Spot {
            position,
            direction,
            intensity,
            inner,
            outer,
        } => {
            let (scale, offset) = Punctual::spot_ramp(inner, outer);
            let cone = 1.0 - 0.5 * (inner.cos() as f64 + outer.cos() as f64);
            (
                2.0 * PI * cone * lum(intensity),
                LightShape::Point {
                    position: relative(position),
                    intensity,
                    axis: direction.normalize(),
                    ramp: [scale, offset],
                },
            )
        }
        Punctual::Directional {
            direction,
            irradiance,
        } => (
            PI * radius * radius * lum(irradiance),
            LightShape::Directional {
                toward: -direction.normalize(),
                irradiance,
            },
        ),
    }
}

/// Appends the primitives whose material emits to `lights`, with their power (pi x luminance x
/// area x emitting sides) in `powers`, and records each one's light index: one light-building
/// path for shapes and triangles.
struct AreaLights<'a> {
    materials: &'a [Material],
    lights: &'a mut Vec<Light>,
    powers: &'a mut Vec<f64>,
}

impl AreaLights<'_> {
    /// Adds those of `primitives` that emit, whose area and light `light_shape` gives.
    fn add<P: Emitter>(
        &mut self,
        primitives: &mut [P],
        light_shape: impl Fn(&P) -> (f64, LightShape),
    ) {
        let luminance = |c: Vec3| (0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z) as f64;
        for primitive in primitives {
            primitive.set_light(0);
            let Some((radiance, two_sided)) =
                self.materials[primitive.material() as usize].area_light()
            else {
                continue;
            };
            let (area, shape) = light_shape(primitive);
            let sides = if two_sided { 2.0 } else { 1.0 };
            self.powers
                .push(std::f64::consts::PI * luminance(radiance) * area * sides);
            self.lights.push(Light {
                shape,
                cdf: 0.0,
                pick: 0.0,
            });
            primitive.set_light(self.lights.len() as u32);
        }
    }
}

impl ShapeVisitorMut for AreaLights<'_> {
    fn visit<S: SurfaceShape>(&mut self, kind: &'static ShapeKind, shapes: &mut [S]) {
        self.add(shapes, |s| {
            let (area, light) = s.as_light();
            let shape = LightShape::Surface {
                kind: kind.kind,
                light,
            };
            (area, shape)
        });
    }
}

/// A primitive that may emit: its material and its light index.
trait Emitter {
    fn material(&self) -> u32;
    fn set_light(&mut self, light: u32);
}

impl<S: SurfaceShape> Emitter for S {
    fn material(&self) -> u32 {
        SurfaceShape::material(self)
    }
    fn set_light(&mut self, light: u32) {
        SurfaceShape::set_light(self, light)
    }
}

impl Emitter for Triangle {
    fn material(&self) -> u32 {
        self.material
    }
    fn set_light(&mut self, light: u32) {
        self.light = light;
    }
}

impl Triangle {
    /// Its area, and itself as a light.
    fn light_shape(&self) -> (f64, LightShape) {
        let area = self.area();
        let (u, v) = (self.p1 - self.p0, self.p2 - self.p0);
        let shape = LightShape::Triangle {
            corner: self.p0,
            u,
            v,
            normal: u.cross(v).normalize(),
            inv_area: (1.0 / area) as f32,
        };
        (area, shape)
    }
}

fn triangle_items(triangles: &[Triangle], first: u32) -> Vec<crate::accel::Item> {
    let item = |(i, t): (usize, &Triangle)| {
        let [min, max] = crate::shape::pad(t.p0.min(t.p1).min(t.p2), t.p0.max(t.p1).max(t.p2), 0.0);
        crate::accel::Item::new(min, max, PrimitiveRef::Triangle(first + i as u32).packed())
    };
    triangles.iter().enumerate().map(item).collect()
}

/// Meshes placed more than once with one material, as (mesh address, material).
type InstancingKey = (usize, u32);

/// A scene's objects turned into primitives, one object at a time: spheres, quads (a box is
/// six), the triangles of meshes placed once (copied into the scene) and the placements of
/// meshes placed more than once (instanced: their triangles kept once, in mesh coordinates).
struct Flattener<'a> {
    scene: &'a Scene,
    instancing: bool,
    /// How many objects place each instancing key.
    placements: std::collections::HashMap<InstancingKey, usize>,
    /// Whether every triangle gets corner normals: the scene has vertex normals somewhere.
    smooth: bool,
    /// Whether every triangle gets corner texture coordinates: some mesh of the scene has them
    /// and some material reads them.
    textured: bool,
    /// Whether every triangle gets second texture coordinates: some material reads them.
    textured1: bool,
    /// Whether every triangle gets corner colours: some mesh of the scene has vertex colours.
    coloured: bool,
    shapes: Shapes,
    boxes: Vec<u32>,
    triangles: Vec<Triangle>,
    triangle_normals: Vec<[Vec3; 3]>,
    triangle_uvs: Vec<[Vec2; 3]>,
    triangle_uvs1: Vec<[Vec2; 3]>,
    triangle_colors: Vec<[Vec3; 3]>,
    /// Whether every triangle gets corner tangents: some mesh of the scene is normal-mapped.
    normal_mapped: bool,
    triangle_tangents: Vec<[Vec4; 3]>,
    /// Each normal-mapped mesh's tangents (`scene::tangents::of`), by the mesh's address and UV set:
    /// computed once however many objects place it.
    mesh_tangents: std::collections::HashMap<(usize, UvSet), Option<Tangents>>,
    /// Instanced meshes: their triangles in mesh coordinates, and which of them each holds.
    local_triangles: Vec<Triangle>,
    local_normals: Vec<[Vec3; 3]>,
    local_uvs: Vec<[Vec2; 3]>,
    local_uvs1: Vec<[Vec2; 3]>,
    local_colors: Vec<[Vec3; 3]>,
    /// Their corner tangents, where the scene is `normal_mapped` (zero where the instanced
    /// mesh is not).
    local_tangents: Vec<[Vec4; 3]>,
    meshes: Vec<std::ops::Range<usize>>,
    mesh_of: std::collections::HashMap<InstancingKey, u32>,
    instances: Vec<Instance>,
}

impl<'a> Flattener<'a> {
    fn new(scene: &'a Scene, instancing: bool) -> Self {
        let normal_mapped = scene.objects.iter().any(|o| {
            matches!(o.shape, Shape::Mesh { .. })
                && scene.materials[o.material as usize]
                    .normal_maps()
                    .next()
                    .is_some()
        });
        // A normal map bends a shading normal: every triangle then has corner normals.
        let smooth = normal_mapped
            || scene
                .objects
                .iter()
                .any(|o| matches!(&o.shape, Shape::Mesh { mesh, .. } if !mesh.normals.is_empty()));
        // Decided before copying, as `uv_textures` is after: Blender writes TEXCOORD_0 on every
        // mesh, textured or not, and large meshes should not carry coordinates nothing reads.
        // Asked once per material: a scene may place a material on many objects.
        let reads: Vec<(bool, bool)> = (scene.materials.iter())
            .map(|m| (reads_uvs(m), reads_uv1(m)))
            .collect();
        let textured = scene.objects.iter().any(|o| reads[o.material as usize].0)
            && scene
                .objects
                .iter()
                .any(|o| matches!(&o.shape, Shape::Mesh { mesh, .. } if !mesh.uvs.is_empty()));
        let textured1 = (scene.objects.iter())
            .any(|o| matches!(o.shape, Shape::Mesh { .. }) && reads[o.material as usize].1);
        let coloured = scene
            .objects
            .iter()
            .any(|o| matches!(&o.shape, Shape::Mesh { mesh, .. } if !mesh.colors.is_empty()));
        let mut flattener = Flattener {
            scene,
            instancing,
            placements: Default::default(),
            smooth,
            textured,
            textured1,
            coloured,
            shapes: Shapes::default(),
            boxes: Vec::new(),
            triangles: Vec::new(),
            triangle_normals: Vec::new(),
            triangle_uvs: Vec::new(),
            triangle_uvs1: Vec::new(),
            triangle_colors: Vec::new(),
            normal_mapped,
            triangle_tangents: Vec::new(),
            mesh_tangents: Default::default(),
            local_triangles: Vec::new(),
            local_normals: Vec::new(),
            local_uvs: Vec::new(),
            local_uvs1: Vec::new(),
            local_colors: Vec::new(),
            local_tangents: Vec::new(),
            meshes: Vec::new(),
            mesh_of: Default::default(),
            instances: Vec::new(),
        };
        for object in &scene.objects {
            if let Some(key) = flattener.instancing_key(object) {
                *flattener.placements.entry(key).or_insert(0) += 1;
            }
        }
        flattener
    }

    /// The key under which `object` could be instanced: a mesh whose material neither emits
    /// nor bounds a medium.
    fn instancing_key(&self, object: &super::Object) -> Option<InstancingKey> {
        match &object.shape {
            Shape::Mesh { mesh, .. } if self.instancing => {
                let m = &self.scene.materials[object.material as usize];
                (m.area_light().is_none() && !m.is_invisible())
                    .then_some((Arc::as_ptr(mesh) as usize, object.material))
            }
            _ => None,
        }
    }

    /// Adds `object`'s primitives, in a scene whose coordinates start at `origin`, with
    /// `material` (its index among the flat scene's materials).
    fn add(&mut self, object: &super::Object, origin: DVec3, material: u32) {
        let t = object.transform;
        let place = |p: Vec3| t.apply_point_relative(p, origin);
        match object.shape {
            Shape::Surface(params) => params.place(&t, origin, material, &mut self.shapes),
            Shape::Cuboid { min, max } => {
                self.boxes.push(self.shapes.quads.len() as u32);
                for [q, u, v] in box_faces(min, max) {
                    self.shapes.quads.push(Quad::new(
                        place(q),
                        t.rotate_vector(u),
                        t.rotate_vector(v),
                        material,
                    ));
                }
            }
            Shape::Mesh { ref mesh, scale } => {
                // The UV set its normal map reads, which its tangents follow.
                let normal_map = (self.scene.materials[object.material as usize].normal_maps())
                    .next()
                    .map(|map| map.image.lookup.uv_set);
                match self.instancing_key(object) {
                    Some(key) if self.placements[&key] > 1 => {
                        let mesh_index = self.instanced_mesh(key, mesh, material, normal_map);
                        let instance = instance_of(&t, scale, origin, material, mesh_index);
                        self.instances.push(instance);
                    }
                    _ => self.copy_mesh(mesh, scale, &t, origin, material, normal_map),
                }
            }
        }
    }

    /// The index of `mesh`'s triangles among the instanced meshes', stored at its first
    /// placement (in mesh coordinates, with their tangents along the UV set `normal_map` where
    /// its material has a normal map; degenerate triangles left out).
    fn instanced_mesh(
        &mut self,
        key: InstancingKey,
        mesh: &Mesh,
        material: u32,
        normal_map: Option<UvSet>,
    ) -> u32 {
        if let Some(&index) = self.mesh_of.get(&key) {
            return index;
        }
        let tangents = normal_map.and_then(|set| self.tangents_of(mesh, set));
        let first = self.local_triangles.len();
        for (i, &[a, b, c]) in mesh.triangles.iter().enumerate() {
            let [p0, p1, p2] = [a, b, c].map(|i| mesh.positions[i as usize]);
            let Some(n) = face_normal(p0, p1, p2) else {
                continue;
            };
            self.local_triangles.push(Triangle {
                p0,
                p1,
                p2,
                material,
                light: 0,
            });
            let normals = mesh.normals.get(i).copied();
            self.local_normals
                .push(normals.unwrap_or([n.normalize(); 3]));
            if self.normal_mapped {
                // As a copy's: turned with normals that point against the winding.
                let corners = tangents.as_deref().map_or([Vec4::ZERO; 3], |t| t[i]);
                let against = normals.is_some_and(|[n0, n1, n2]| (n0 + n1 + n2).dot(n) < 0.0);
                self.local_tangents.push(if against {
                    corners.map(|t| -t)
                } else {
                    corners
                });
            }
            self.local_uvs
                .push(mesh.uvs.get(i).copied().unwrap_or(BARYCENTRIC_UVS));
            if self.textured1 {
                self.local_uvs1.push(second_uvs(mesh, i));
            }
            self.local_colors
                .push(mesh.colors.get(i).copied().unwrap_or([Vec3::ONE; 3]));
        }
        self.meshes.push(first..self.local_triangles.len());
        let index = self.meshes.len() as u32 - 1;
        self.mesh_of.insert(key, index);
        index
    }

    /// `mesh`'s corner tangents along UV set `set` (`scene::tangents::of`), computed once
    /// however many objects place it.
    fn tangents_of(&mut self, mesh: &Mesh, set: UvSet) -> Option<Tangents> {
        let key = (std::ptr::from_ref(mesh) as usize, set);
        self.mesh_tangents
            .entry(key)
            .or_insert_with(|| super::tangents::of(mesh, set).map(Into::into))
            .clone()
    }

    /// Copies `mesh`'s triangles, scaled by `scale` and placed by `t`, into the scene (with
    /// their tangents along UV set `normal_map` where its material has a normal map).
    fn copy_mesh(
        &mut self,
        mesh: &Mesh,
        scale: Vec3,
        t: &super::Transform,
        origin: DVec3,
        material: u32,
        normal_map: Option<UvSet>,
    ) {
        use rayon::prelude::*;
        // A mirroring scale turns the winding around: swap two corners so the front face stays
        // the same side of the surface.
        let mirrored = scale.x * scale.y * scale.z < 0.0;
        let place = t.point_placement(origin);
        let rotate = t.vector_rotation();
        let placed: Vec<Vec3> = (mesh.positions.par_iter())
            .map(|&p| place(p * scale))
            .collect();
        // Normals by the inverse transpose: divided by the scale, then rotated.
        let shading = |n: Vec3| rotate(n / scale).normalize_or_zero();
        // Tangents as the surface's vectors; a mirroring scale turns the bitangent around.
        let tangents = normal_map.and_then(|set| self.tangents_of(mesh, set));
        let tangent = |v: Vec4| {
            let along = rotate(v.truncate() * scale).normalize_or_zero();
            along.extend(if mirrored { -v.w } else { v.w })
        };
        let placed_corners = |i: usize| {
            let [a, b, c] = mesh.triangles[i];
            let [b, c] = if mirrored { [c, b] } else { [b, c] };
            [a, b, c].map(|i| placed[i as usize])
        };
        // The triangles kept, with their faces' normals: those that f32 coordinates here
        // flatten to a line are left out.
        let kept: Vec<(usize, Vec3)> = (0..mesh.triangles.len())
            .into_par_iter()
            .filter_map(|i| {
                let [p0, p1, p2] = placed_corners(i);
                face_normal(p0, p1, p2).map(|n| (i, n))
            })
            .collect();
        let corner_normals = |i: usize, n: Vec3| {
            let face = n.normalize();
            match mesh.normals.get(i) {
                Some(&[n0, n1, n2]) => {
                    let [n1, n2] = if mirrored { [n2, n1] } else { [n1, n2] };
                    [n0, n1, n2].map(|n| match shading(n) {
                        Vec3::ZERO => face,
                        n => n,
                    })
                }
                None => [face; 3],
            }
        };
        // The arrays are filled one at a time, each in parallel and in the triangles' order.
        if self.normal_mapped {
            // Hits turn a file's normals that point against the winding around; the frame
            // keeps the map's slopes only with the tangent and its sign turned too. (Without
            // smooth normals, the last ones before this mesh's are what is compared.)
            let earlier = self.triangle_normals.last().copied();
            let smooth = self.smooth;
            let tangents = tangents.as_deref();
            self.triangle_tangents
                .par_extend(kept.par_iter().map(|&(i, n)| {
                    let corners = match tangents.map(|t| t[i]) {
                        Some([t0, t1, t2]) if mirrored => [t0, t2, t1].map(tangent),
                        Some(corners) => corners.map(tangent),
                        None => [Vec4::ZERO; 3],
                    };
                    let normals = if smooth {
                        Some(corner_normals(i, n))
                    } else {
                        earlier
                    };
                    let against = normals.is_some_and(|[n0, n1, n2]| (n0 + n1 + n2).dot(n) < 0.0);
                    if against {
                        corners.map(|t| -t)
                    } else {
                        corners
                    }
                }));
        }
        if self.smooth {
            (self.triangle_normals).par_extend(kept.par_iter().map(|&(i, n)| corner_normals(i, n)));
        }
        if self.textured {
            self.triangle_uvs
                .par_extend(kept.par_iter().map(|&(i, _)| match mesh.uvs.get(i) {
                    Some(&[uv0, uv1, uv2]) if mirrored => [uv0, uv2, uv1],
                    Some(&uvs) => uvs,
                    None => BARYCENTRIC_UVS,
                }));
        }
        if self.textured1 {
            self.triangle_uvs1
                .par_extend(kept.par_iter().map(|&(i, _)| match second_uvs(mesh, i) {
                    [uv0, uv1, uv2] if mirrored => [uv0, uv2, uv1],
                    uvs => uvs,
                }));
        }
        if self.coloured {
            self.triangle_colors.par_extend(kept.par_iter().map(
                |&(i, _)| match mesh.colors.get(i) {
                    Some(&[c0, c1, c2]) if mirrored => [c0, c2, c1],
                    Some(&colors) => colors,
                    None => [Vec3::ONE; 3],
                },
            ));
        }
        self.triangles.par_extend(kept.par_iter().map(|&(i, _)| {
            let [p0, p1, p2] = placed_corners(i);
            Triangle {
                p0,
                p1,
                p2,
                material,
                light: 0,
            }
        }));
    }

    /// The flat scene of these primitives and `materials`, instanced meshes' triangles after the
    /// copied ones (lights and BVH still to be found).
    fn finish(
        self,
        materials: Vec<Material>,
        origin: DVec3,
        camera: CameraFrame,
    ) -> Result<FlatScene, SceneError> {
        let mut triangles = self.triangles;
        let mut triangle_normals = self.triangle_normals;
        let mut triangle_uvs = self.triangle_uvs;
        let mut triangle_uvs1 = self.triangle_uvs1;
        let mut triangle_colors = self.triangle_colors;
        let mut triangle_tangents = self.triangle_tangents;
        let instanced_triangles = triangles.len();
        let instanced_meshes = self
            .meshes
            .iter()
            .map(|r| r.start + instanced_triangles..r.end + instanced_triangles)
            .collect();
        triangles.extend(self.local_triangles);
        if self.smooth {
            triangle_normals.extend(self.local_normals);
        }
        if self.textured {
            triangle_uvs.extend(self.local_uvs);
        }
        triangle_uvs1.extend(self.local_uvs1);
        if self.coloured {
            triangle_colors.extend(self.local_colors);
        }
        if self.normal_mapped {
            triangle_tangents.extend(self.local_tangents);
        }
        let most_shapes = (crate::shape::KINDS.iter())
            .map(|k| self.shapes.count(k))
            .max()
            .unwrap_or(0);
        if most_shapes > MAX_PRIMITIVES_PER_KIND
            || triangles.len() > MAX_PRIMITIVES_PER_KIND
            || self.instances.len() > MAX_PRIMITIVES_PER_KIND
        {
            return Err(SceneError::Invalid(format!(
                "a scene may have at most {MAX_PRIMITIVES_PER_KIND} spheres, as many quads, disks, triangles and mesh placements"
            )));
        }
        Ok(FlatScene {
            origin,
            camera,
            background: self.scene.background.clone(),
            materials,
            shapes: self.shapes,
            triangles,
            triangle_normals,
            triangle_uvs,
            triangle_uvs1,
            triangle_colors,
            triangle_tangents,
            instanced_triangles,
            instanced_meshes,
            instances: self.instances,
            instance_depth: 0,
            bvh: crate::accel::Bvh::default(),
            wide_bvh: crate::accel::wide::WideBvh::default(),
            quantized_bvh: KernelBvhCache::default(),
            quad_blocks: Vec::new(),
            lights: Vec::new(),
            medium_crossings: 0,
            uv_textures: false,
            see_through: false,
            boxes: self.boxes,
        })
    }
}

/// The (not unit) normal of triangle p0 p1 p2 by its winding; `None` for one that f32 flattens
/// to a line or a point.
fn face_normal(p0: Vec3, p1: Vec3, p2: Vec3) -> Option<Vec3> {
    let n = (p1 - p0).cross(p2 - p0);
    (n.length_squared() > 0.0 && n.is_finite()).then_some(n)
}

/// A placement of instanced mesh `mesh` scaled by `scale` and then moved by `t`, in a scene
/// whose coordinates start at `origin` (its bounds and BVH root are set by `build_bvh`).
/// Both maps are worked out in f64 and rounded once.
fn instance_of(
    t: &super::Transform,
    scale: Vec3,
    origin: DVec3,
    material: u32,
    mesh: u32,
) -> Instance {
    let (sin, cos) = (t.rotate_y_degrees.to_radians() as f64).sin_cos();
    let s = scale.as_dvec3();
    let translate = t.translate.as_dvec3() - origin;
    // p' = R_y diag(s) p + translate, and p = diag(1 / s) R_y^T (p' - translate).
    let linear = [
        DVec3::new(cos * s.x, 0.0, sin * s.z),
        DVec3::new(0.0, s.y, 0.0),
        DVec3::new(-sin * s.x, 0.0, cos * s.z),
    ];
    let inverse = [
        DVec3::new(cos / s.x, 0.0, -sin / s.x),
        DVec3::new(0.0, 1.0 / s.y, 0.0),
        DVec3::new(sin / s.z, 0.0, cos / s.z),
    ];
    let row = |r: DVec3, w: f64| r.extend(w).as_vec4();
    Instance {
        to_world: [0, 1, 2].map(|k| row(linear[k], translate[k])),
        to_local: inverse.map(|r| row(r, -r.dot(translate))),
        bounds: [Vec3::ZERO; 2],
        mesh,
        root: 0,
        material,
    }
}

/// The box around a mesh-space box placed by `instance` (its corners placed in f64), padded
/// for the rounding of placing points in f32.
fn placed_bounds(instance: &Instance, min: Vec3, max: Vec3) -> [Vec3; 2] {
    let rows = instance.to_world.map(|r| r.as_dvec4());
    let mut lo = DVec3::splat(f64::MAX);
    let mut hi = DVec3::splat(f64::MIN);
    for corner in 0..8 {
        let p = DVec3::new(
            if corner & 1 == 0 { min.x } else { max.x } as f64,
            if corner & 2 == 0 { min.y } else { max.y } as f64,
            if corner & 4 == 0 { min.z } else { max.z } as f64,
        );
        let placed = DVec3::from(rows.map(|r| r.truncate().dot(p) + r.w));
        lo = lo.min(placed);
        hi = hi.max(placed);
    }
    // Placing rounds each coordinate by a few ulps of the magnitudes summed (see
    // `Instance::magnitude_to_world`), at most those of the box's placed corners and the
    // translation's.
    let translation = Vec3::from(instance.to_world.map(|r| r.w))
        .abs()
        .max_element() as f64;
    let magnitude = lo.abs().max(hi.abs()).max_element() + translation;
    let p = DVec3::splat(16.0 * f32::EPSILON as f64 * magnitude);
    [(lo - p).as_vec3(), (hi + p).as_vec3()]
}

/// The six faces of an axis-aligned box as (corner, u, v), each with u x v pointing outward.
pub fn box_faces(min: Vec3, max: Vec3) -> [[Vec3; 3]; 6] {
    let d = max - min;
    let (dx, dy, dz) = (
        Vec3::new(d.x, 0.0, 0.0),
        Vec3::new(0.0, d.y, 0.0),
        Vec3::new(0.0, 0.0, d.z),
    );
    [
        [Vec3::new(min.x, min.y, max.z), dx, dy],  // front, +z
        [Vec3::new(max.x, min.y, max.z), -dz, dy], // right, +x
        [Vec3::new(max.x, min.y, min.z), -dx, dy], // back, -z
        [Vec3::new(min.x, min.y, min.z), dz, dy],  // left, -x
        [Vec3::new(min.x, max.y, max.z), dx, -dz], // top, +y
        [Vec3::new(min.x, min.y, min.z), dx, dz],  // bottom, -y
    ]
}

fn camera_frame(scene: &Scene, origin: DVec3, width: u32, height: u32) -> CameraFrame {
    let c = &scene.camera;
    let look_from = (c.look_from.as_dvec3() - origin).as_vec3();
    let to_target = (c.look_at.as_dvec3() - c.look_from.as_dvec3()).as_vec3();
    let forward = to_target.normalize();
    // `up` is a direction of any length (validated finite and non-zero): normalised in f64
    // first, since the f32 length of 1e20 overflows.
    let right = forward
        .cross(c.up.as_dvec3().normalize().as_vec3())
        .normalize();
    let up = right.cross(forward);
    let focus = c.focus_distance.unwrap_or(to_target.length());
    let half_height = (c.vfov_degrees.to_radians() * 0.5).tan();
    let half_width = half_height * width as f32 / height as f32;
    let horizontal = right * (2.0 * half_width * focus);
    let vertical = up * (2.0 * half_height * focus);
    CameraFrame {
        origin: look_from,
        to_upper_left: forward * focus - horizontal * 0.5 + vertical * 0.5,
        horizontal,
        vertical,
        right,
        up,
        lens_radius: c.aperture * 0.5,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn primitive_refs_pack_and_unpack() {
        let sphere = |index| PrimitiveRef::Shape { kind: 0, index };
        let quad = |index| PrimitiveRef::Shape { kind: 1, index };
        for p in [
            sphere(0),
            sphere(MAX_PRIMITIVES_PER_KIND as u32 - 1),
            quad(0),
            quad(12345),
            PrimitiveRef::Triangle(7),
            PrimitiveRef::Instance(8),
            PrimitiveRef::Shape { kind: 4, index: 9 },
        ] {
            assert_eq!(PrimitiveRef::unpacked(p.packed()), p);
        }
        assert_ne!(sphere(3).packed(), quad(3).packed());
    }

    #[test]
    fn box_faces_point_outward() {
        let (min, max) = (Vec3::ZERO, Vec3::new(1.0, 2.0, 3.0));
        let centre = (min + max) * 0.5;
        for [q, u, v] in box_faces(min, max) {
            let face_centre = q + 0.5 * (u + v);
            assert!(
                u.cross(v).dot(face_centre - centre) > 0.0,
                "{q:?} {u:?} {v:?}"
            );
        }
    }
}
