//! Ray-shape intersection (twin: `shaders/intersect.wgsl`).

use super::accel::{Leaves, reach};
use super::four_spheres::LaneHits;
use crate::assets::image_lookup::UvSet;
use crate::assets::normal_map::NormalMap;
use crate::scene::flat::{FlatScene, Instance, Triangle};
use crate::shape::quad::{Quad, QuadBlock};
use crate::shape::sphere::Sphere;
use crate::shape::{ShapeKind, ShapeVisitor, SurfaceShape};
use crate::shared::primitive::{PRIMITIVE_INDEX_BITS, PrimitiveRef};
use crate::shared::ray::{Hit, POINT_ERROR, Ray};
use crate::shared::rng::alpha_number;
use glam::{Vec2, Vec3, Vec4};

pub use crate::shape::quad::hit_quad;
pub use crate::shape::sphere::hit_sphere;

/// Distance along the ray to `triangle` within (t_min, t_max) and the barycentric weights of
/// its second and third corners there, if it is hit. Watertight (Woop, Benthin and Wald 2013,
/// "Watertight Ray/Triangle Intersection"): in a frame sheared so the ray runs along +z from
/// the origin, the 2D edge functions of an edge shared by two triangles are exact negatives of
/// each other, so a ray crossing the edge hits at least one of them; a ray through a corner or
/// along an edge (an edge function exactly 0) counts as a hit. Rust never fuses `a * b - c * d`
/// into a multiply-add, which would break that antisymmetry; GPU compilers may, so the kernel's
/// twin (`triangle_hit`) computes each edge function with an exact sign instead.
#[inline]
pub fn hit_triangle(
    triangle: &Triangle,
    ray: &Ray,
    t_min: f32,
    t_max: f32,
) -> Option<(f32, f32, f32)> {
    let d = ray.dir;
    // The dominant axis becomes z.
    let a = d.abs();
    let kz = if a.x > a.y && a.x > a.z {
        0
    } else if a.y > a.z {
        1
    } else {
        2
    };
    let (kx, ky) = ((kz + 1) % 3, (kz + 2) % 3);
    let permute = |v: Vec3| Vec3::new(v[kx], v[ky], v[kz]);
    let d = permute(d);
    let (sx, sy, sz) = (-d.x / d.z, -d.y / d.z, 1.0 / d.z);
    let shear = |p: Vec3| {
        let p = permute(p - ray.origin);
        Vec3::new(p.x + sx * p.z, p.y + sy * p.z, p.z)
    };
    let (p0, p1, p2) = (shear(triangle.p0), shear(triangle.p1), shear(triangle.p2));
    let e0 = p1.x * p2.y - p1.y * p2.x;
    let e1 = p2.x * p0.y - p2.y * p0.x;
    let e2 = p0.x * p1.y - p0.y * p1.x;
    if (e0 < 0.0 || e1 < 0.0 || e2 < 0.0) && (e0 > 0.0 || e1 > 0.0 || e2 > 0.0) {
        return None;
    }
    let det = e0 + e1 + e2;
    if det == 0.0 {
        return None;
    }
    let scaled = e0 * (sz * p0.z) + e1 * (sz * p1.z) + e2 * (sz * p2.z);
    let t = scaled / det;
    if !(t > t_min && t < t_max) {
        return None;
    }
    Some((t, e1 / det, e2 / det))
}

/// What the closest-hit search keeps of the best primitive so far.
#[derive(Clone, Copy)]
struct Candidate {
    primitive: PrimitiveRef,
    /// A shape's outward normal, not yet of unit length (a triangle's is found from its corners
    /// once it is known to be the closest: the search need not read them).
    outward: Vec3,
    /// A triangle's barycentric weights of its second and third corners.
    weights: Vec2,
    /// An instance's triangle (index in `FlatScene::triangles`); 0 for other primitives.
    triangle: u32,
}

impl Candidate {
    /// The order in which coincident hits win: primitive, then an instance's triangle.
    fn key(&self) -> (u32, u32) {
        (self.primitive.packed(), self.triangle)
    }

    /// The index in `FlatScene::triangles` of the triangle hit (an instance's in its mesh), whose
    /// corner attributes the hit interpolates; `None` on a shape.
    fn triangle_index(&self) -> Option<u32> {
        match self.primitive {
            PrimitiveRef::Triangle(i) => Some(i),
            PrimitiveRef::Instance(_) => Some(self.triangle),
            PrimitiveRef::Shape { .. } => None,
        }
    }
}

/// Whether a hit at `t` on the primitive keyed `key` replaces the closest so far (see
/// `consider`); `closest` is `found`'s distance.
#[inline]
fn replaces(t: f32, key: (u32, u32), closest: f32, found: &Option<Candidate>) -> bool {
    t < closest || (t == closest && found.is_none_or(|f| key < f.key()))
}

/// Tests primitive `p` against the ray, keeping it if it is closer than `closest`, or as close
/// and earlier in the order of [`FlatScene::primitives`]: surfaces that coincide (a smoke box
/// resting on a floor) resolve the same whatever order a traversal meets them in, as they do
/// when every primitive is tested in that order (the GPU's small kernels).
#[inline]
fn consider<const FIRST: bool>(
    scene: &FlatScene,
    p: PrimitiveRef,
    ray: &Ray,
    closest: &mut f32,
    found: &mut Option<Candidate>,
) {
    let t_max = reach(*closest);
    let tested = match p {
        PrimitiveRef::Shape { kind, index } => scene
            .shapes
            .hit(kind, index, ray, t_max)
            .map(|(t, outward)| (t, outward, Vec2::ZERO)),
        PrimitiveRef::Triangle(i) => {
            let tri = &scene.triangles[i as usize];
            hit_triangle(tri, ray, 0.0, t_max).map(|(t, b1, b2)| (t, Vec3::ZERO, Vec2::new(b1, b2)))
        }
        PrimitiveRef::Instance(i) => {
            return consider_instance::<FIRST>(scene, i, ray, closest, found);
        }
    };
    if let Some(hit) = tested {
        keep(scene, p, hit, ray, closest, found);
    }
}

/// Keeps primitive `p`, hit at `(t, outward normal, weights)`, if it replaces the closest so
/// far and is not seen through there.
#[inline]
fn keep(
    scene: &FlatScene,
    p: PrimitiveRef,
    (t, outward, weights): (f32, Vec3, Vec2),
    ray: &Ray,
    closest: &mut f32,
    found: &mut Option<Candidate>,
) {
    if !replaces(t, (p.packed(), 0), *closest, found) {
        return;
    }
    if let PrimitiveRef::Triangle(i) = p
        && scene.see_through
        && passes_through(
            scene,
            scene.triangles[i as usize].material,
            i,
            weights,
            ray,
            (p.packed(), 0),
        )
    {
        return;
    }
    *closest = t;
    *found = Some(Candidate {
        primitive: p,
        outward,
        weights,
        triangle: 0,
    });
}

/// The closest-hit search through the scene's top level: each leaf's primitives considered in
/// turn, a block of placed triangles kept lane by lane. With `FIRST` it ends at the first hit
/// kept (any one: whether the ray is stopped at all, not where).
struct TopLevel<'a, const FIRST: bool> {
    scene: &'a FlatScene,
    ray: &'a Ray,
    found: &'a mut Option<Candidate>,
}

impl<const FIRST: bool> Leaves for TopLevel<'_, FIRST> {
    #[inline]
    fn primitive(&mut self, packed: u32, closest: &mut f32) {
        let primitive = PrimitiveRef::unpacked(packed);
        consider::<FIRST>(self.scene, primitive, self.ray, closest, self.found);
    }

    #[inline]
    fn finished(&self) -> bool {
        FIRST && self.found.is_some()
    }

    #[inline]
    fn triangle(&mut self, triangle: u32, (t, b1, b2): (f32, f32, f32), closest: &mut f32) {
        if t < reach(*closest) {
            let hit = (t, Vec3::ZERO, Vec2::new(b1, b2));
            let p = PrimitiveRef::Triangle(triangle);
            keep(self.scene, p, hit, self.ray, closest, self.found);
        }
    }
}

/// Tests the triangles of instance `index` against the ray, transformed into its mesh's
/// coordinates (its direction not renormalised, so that distances along it stay those of
/// `ray`), as `consider` does a primitive's. Its normal is found once the closest hit is known.
#[inline]
fn consider_instance<const FIRST: bool>(
    scene: &FlatScene,
    index: u32,
    ray: &Ray,
    closest: &mut f32,
    found: &mut Option<Candidate>,
) {
    let local = local_ray(&scene.instances[index as usize], ray);
    let mut search = InInstance::<FIRST>::new(scene, index, &local, found);
    let (wide, root) = (
        &scene.wide_bvh,
        scene.wide_bvh.instance_roots[index as usize],
    );
    super::accel::traverse_wide(wide, &scene.bvh, root, &local, closest, &mut search);
}

/// The closest-hit search through instance `index`'s mesh, along the ray in its coordinates;
/// with `FIRST`, ended by the first hit kept, as `TopLevel`'s.
struct InInstance<'a, const FIRST: bool> {
    scene: &'a FlatScene,
    index: u32,
    material: u32,
    local: &'a Ray,
    found: &'a mut Option<Candidate>,
}

/// `ray` in the coordinates of `instance`'s mesh, its direction not renormalised.
pub(crate) fn local_ray(instance: &Instance, ray: &Ray) -> Ray {
    Ray {
        origin: instance.point_to_local(ray.origin),
        dir: instance.vector_to_local(ray.dir),
    }
}

impl<'a, const FIRST: bool> InInstance<'a, FIRST> {
    fn new(
        scene: &'a FlatScene,
        index: u32,
        local: &'a Ray,
        found: &'a mut Option<Candidate>,
    ) -> Self {
        let material = scene.instances[index as usize].material;
        InInstance {
            scene,
            index,
            material,
            local,
            found,
        }
    }

    /// Keeps triangle `triangle`, hit at `t` with weights `b1`, `b2`, as `keep` does a
    /// primitive; coincident hits in one instance resolve by triangle.
    #[inline]
    fn keep(&mut self, triangle: u32, (t, b1, b2): (f32, f32, f32), closest: &mut f32) {
        let key = (PrimitiveRef::Instance(self.index).packed(), triangle);
        if !replaces(t, key, *closest, self.found) {
            return;
        }
        let weights = Vec2::new(b1, b2);
        let scene = self.scene;
        if scene.see_through
            && passes_through(scene, self.material, triangle, weights, self.local, key)
        {
            return;
        }
        *closest = t;
        *self.found = Some(Candidate {
            primitive: PrimitiveRef::Instance(self.index),
            outward: Vec3::ZERO,
            weights,
            triangle,
        });
    }
}

impl<const FIRST: bool> Leaves for InInstance<'_, FIRST> {
    #[inline]
    fn finished(&self) -> bool {
        FIRST && self.found.is_some()
    }

    #[inline]
    fn primitive(&mut self, packed: u32, closest: &mut f32) {
        let triangle = packed & ((1 << PRIMITIVE_INDEX_BITS) - 1);
        let tri = &self.scene.triangles[triangle as usize];
        if let Some(hit) = hit_triangle(tri, self.local, 0.0, reach(*closest)) {
            self.keep(triangle, hit, closest);
        }
    }

    #[inline]
    fn triangle(&mut self, triangle: u32, hit: (f32, f32, f32), closest: &mut f32) {
        if hit.0 < reach(*closest) {
            self.keep(triangle, hit, closest);
        }
    }
}

/// Whether `ray` passes through triangle `triangle` (of material `material`) at barycentric
/// weights `weights`, the primitive keyed `key` (as [`Candidate::key`]): never for opaque
/// materials; see `assets::alpha` (twin: `shaders/alpha.wgsl`).
#[inline]
fn passes_through(
    scene: &FlatScene,
    material: u32,
    triangle: u32,
    weights: Vec2,
    ray: &Ray,
    (primitive, instanced): (u32, u32),
) -> bool {
    let Some(alpha) = scene.materials[material as usize].alpha() else {
        return false;
    };
    let texture = match &alpha.image {
        Some(image) => {
            let first = scene.triangle_uvs.get(triangle as usize);
            let corners = match image.lookup.uv_set {
                UvSet::First => first,
                UvSet::Second => scene.triangle_uvs1.get(triangle as usize).or(first),
            };
            let uv = corners.map_or(weights, |uvs| interpolated_uv(uvs, weights));
            crate::assets::image_lookup::image_at(image, uv).x
        }
        None => 1.0,
    };
    let u = alpha_number(
        ray.origin.to_array(),
        ray.dir.to_array(),
        primitive,
        instanced,
    );
    alpha.passes(alpha.factor * texture, u)
}

/// The closest hit along `ray` beyond its origin.
pub fn intersect(scene: &FlatScene, ray: &Ray) -> Option<Hit> {
    super::ray_count::count_ray();
    let (t, found) = closest(scene, ray)?;
    Some(hit_on(scene, ray, t, &found))
}

/// [`intersect`]'s hit where it lies on a primitive of light `light` (its index + 1, as
/// [`FlatScene::light_of`] numbers them), `None` where the closest hit is elsewhere or there
/// is none: a shadow ray's test, which works out the surface only of the light it reaches.
pub fn intersect_light(scene: &FlatScene, ray: &Ray, light: u32) -> Option<Hit> {
    super::ray_count::count_ray();
    let (t, found) = closest(scene, ray)?;
    (scene.light_of(found.primitive) == light).then(|| hit_on(scene, ray, t, &found))
}

/// The hit on `found`, closest along `ray` at distance `t`: its surface worked out.
#[inline]
fn hit_on(scene: &FlatScene, ray: &Ray, t: f32, found: &Candidate) -> Hit {
    let outward = match found.primitive {
        // By the inverse transpose: a mirroring placement turns the winding's normal around
        // with it, as flattening's swapped corners do.
        PrimitiveRef::Instance(i) => {
            let tri = &scene.triangles[found.triangle as usize];
            let instance = &scene.instances[i as usize];
            instance.normal_to_world((tri.p1 - tri.p0).cross(tri.p2 - tri.p0))
        }
        PrimitiveRef::Triangle(i) => {
            let tri = &scene.triangles[i as usize];
            (tri.p1 - tri.p0).cross(tri.p2 - tri.p0)
        }
        PrimitiveRef::Shape { .. } => found.outward,
    }
    .normalize();
    let (material, (point, error), uv) = surface(scene, found, ray.at(t));
    let uv1 = second_uv(scene, found, uv);
    let (shading, (coat, coat_mapped)) = shading(scene, found, material, [uv, uv1], outward);
    let front_face = ray.dir.dot(outward) < 0.0;
    let facing = |n: Vec3| if front_face { n } else { -n };
    let normal = facing(outward);
    // A coat's own map bent where its mirror would send the view below the surface.
    let coat = match coat_mapped {
        false => facing(coat),
        true => crate::assets::normal_map::valid_reflection(normal, -ray.dir, facing(coat)),
    };
    Hit {
        t,
        point,
        error,
        normal,
        shading: facing(shading),
        coat,
        front_face,
        material,
        primitive: found.primitive,
        uv,
        uv1,
        color: vertex_color(scene, found),
    }
}

/// The vertex colour at the hit on `found`: its triangle's corner colours interpolated, white
/// where the scene has none or the hit is on a shape (twin: `vertex_color` in
/// shaders/intersect.wgsl).
#[inline]
fn vertex_color(scene: &FlatScene, found: &Candidate) -> Vec3 {
    let corners = found
        .triangle_index()
        .and_then(|i| scene.triangle_colors.get(i as usize));
    match corners {
        Some(&[c0, c1, c2]) => {
            let (b1, b2) = (found.weights.x, found.weights.y);
            (1.0 - b1 - b2) * c0 + b1 * c1 + b2 * c2
        }
        None => Vec3::ONE,
    }
}

/// The hit on `found`'s second texture coordinates (glTF's TEXCOORD_1) where the scene's
/// materials read them, else `uv`, its first (twin: `second_uv` in shaders/intersect.wgsl).
#[inline]
fn second_uv(scene: &FlatScene, found: &Candidate, uv: Vec2) -> Vec2 {
    let corners = found
        .triangle_index()
        .and_then(|i| scene.triangle_uvs1.get(i as usize));
    match corners {
        Some(uvs) => interpolated_uv(uvs, found.weights),
        None => uv,
    }
}

/// The closest primitive along `ray` beyond its origin, and its distance.
#[inline]
fn closest(scene: &FlatScene, ray: &Ray) -> Option<(f32, Candidate)> {
    if tested_in_turn(scene) {
        closest_in_turn(scene, ray)
    } else {
        closest_through_bvh(scene, ray)
    }
}

/// [`closest`] testing every shape in turn.
#[inline]
fn closest_in_turn(scene: &FlatScene, ray: &Ray) -> Option<(f32, Candidate)> {
    let mut closest = f32::INFINITY;
    let mut found: Option<Candidate> = None;
    let mut in_turn = InTurn {
        ray,
        quad_blocks: &scene.quad_blocks,
        closest: &mut closest,
        found: &mut found,
    };
    scene.shapes.visit(&mut in_turn);
    found.map(|found| (closest, found))
}

/// [`closest`] through the scene's BVH.
fn closest_through_bvh(scene: &FlatScene, ray: &Ray) -> Option<(f32, Candidate)> {
    through_bvh::<false>(scene, ray, f32::INFINITY)
}

/// Whether anything stops `ray` before distance `before` (beyond its origin): exactly when
/// [`intersect`] finds a hit nearer than `before`, as each primitive's test and what passes
/// through are the same, but ended at the first such hit rather than the closest, and without
/// working out its surface. A shadow ray's test toward a light that is not in the scene's
/// primitives (a point, the sun, the environment).
pub fn stopped_before(scene: &FlatScene, ray: &Ray, before: f32) -> bool {
    super::ray_count::count_ray();
    if tested_in_turn(scene) {
        return closest_in_turn(scene, ray).is_some_and(|(t, _)| t < before);
    }
    // Primitives are tested up to and including `closest` (`reach`): strictly before `before`.
    let closest = if before.is_finite() {
        before.next_down()
    } else {
        before
    };
    through_bvh::<true>(scene, ray, closest).is_some()
}

/// The search through the scene's BVH for primitives hit up to `closest`: the closest one, or
/// with `FIRST` the first one found.
#[inline]
fn through_bvh<const FIRST: bool>(
    scene: &FlatScene,
    ray: &Ray,
    mut closest: f32,
) -> Option<(f32, Candidate)> {
    let mut found: Option<Candidate> = None;
    let mut search = TopLevel::<FIRST> {
        scene,
        ray,
        found: &mut found,
    };
    let (wide, root) = (&scene.wide_bvh, scene.wide_bvh.root);
    super::accel::traverse_wide(wide, &scene.bvh, root, ray, &mut closest, &mut search);
    found.map(|found| (closest, found))
}

/// Whether `scene`'s rays go through its BVH (not [`tested_in_turn`]).
pub fn traverses_bvh(scene: &FlatScene) -> bool {
    !tested_in_turn(scene)
}

/// Whether `scene`'s rays test its few shapes in turn rather than through its BVH.
#[inline]
fn tested_in_turn(scene: &FlatScene) -> bool {
    scene.triangles.is_empty() && in_turn_cost(scene) <= MAX_IN_TURN_COST
}

/// The tests a ray of `scene` (of shapes alone) makes testing every shape in turn: spheres and
/// quads four to a test, other shapes one each.
fn in_turn_cost(scene: &FlatScene) -> usize {
    let (spheres, quads) = (scene.shapes.spheres.len(), scene.shapes.quads.len());
    let others = scene.bvh.primitives.len() - spheres - quads;
    spheres.div_ceil(4) + quads.div_ceil(4) + others
}

/// Most tests a ray may make in a scene of shapes alone for its rays to test them all in turn
/// rather than through its BVH: for a handful, the hierarchy's box tests cost more than the
/// primitives' own. At 8 the Cornell boxes (18 quads and at most a sphere: 5-6 tests) are
/// faster in turn, the materials scene (36 shapes, 10 tests) slower (docs/benchmarks.md).
const MAX_IN_TURN_COST: usize = 8;

/// Every shape tested in turn, in the order of their packed references (which `replaces`
/// would impose anyway), as `consider` tests one but monomorphised per kind: no dispatch on
/// the kind per primitive, which for these few primitives costs measurably.
struct InTurn<'a> {
    ray: &'a Ray,
    /// The scene's quads four to a block.
    quad_blocks: &'a [QuadBlock],
    closest: &'a mut f32,
    found: &'a mut Option<Candidate>,
}

impl ShapeVisitor for InTurn<'_> {
    #[inline]
    fn visit<S: SurfaceShape>(&mut self, kind: &'static ShapeKind, shapes: &[S]) {
        if let Some(spheres) = S::as_spheres(shapes) {
            return self.visit_spheres(kind, spheres);
        }
        if let Some(quads) = S::as_quads(shapes) {
            return self.visit_quads(kind, quads);
        }
        for (index, shape) in shapes.iter().enumerate() {
            if let Some(t) = shape.hit(self.ray, reach(*self.closest)) {
                self.keep(kind, index, shape, t);
            }
        }
    }
}

impl InTurn<'_> {
    /// Spheres four at a time: each lane is `hit_sphere`'s answer, kept if still within reach
    /// of the closest hit, which an earlier lane may have shortened (the one-by-one test would
    /// then have found nothing nearer either: a sphere's far root lies beyond its near one).
    #[inline]
    fn visit_spheres(&mut self, kind: &'static ShapeKind, spheres: &[Sphere]) {
        for (block, four) in spheres.chunks(4).enumerate() {
            let hits = super::four_spheres::hits(four, self.ray, reach(*self.closest));
            self.keep_lanes(kind, 4 * block, four, hits);
        }
    }

    /// Quads four at a time, as spheres are: each lane is `hit_quad`'s answer, whose distance
    /// does not depend on the reach it is tested within.
    #[inline]
    fn visit_quads(&mut self, kind: &'static ShapeKind, quads: &[Quad]) {
        // The blocks are built with the BVH, from these quads.
        assert_eq!(self.quad_blocks.len(), quads.len().div_ceil(4));
        for (block, (four, lanes_of)) in quads.chunks(4).zip(self.quad_blocks).enumerate() {
            let hits = super::four_quads::hits(four, lanes_of, self.ray, reach(*self.closest));
            self.keep_lanes(kind, 4 * block, four, hits);
        }
    }

    /// Keeps, lane by lane in order, each shape of `four` (from index `first` of `kind`) that
    /// `hits` found and that is still within reach of the closest hit.
    #[inline]
    fn keep_lanes<S: SurfaceShape>(
        &mut self,
        kind: &'static ShapeKind,
        first: usize,
        four: &[S],
        hits: LaneHits,
    ) {
        let mut lanes = hits.hit;
        while lanes != 0 {
            let lane = lanes.trailing_zeros() as usize;
            lanes &= lanes - 1;
            let t = hits.t[lane];
            if t < reach(*self.closest) {
                self.keep(kind, first + lane, &four[lane], t);
            }
        }
    }

    /// Keeps shape `index` of `kind`, hit at `t`, if it replaces the closest so far.
    #[inline]
    fn keep<S: SurfaceShape>(&mut self, kind: &'static ShapeKind, index: usize, shape: &S, t: f32) {
        let primitive = PrimitiveRef::Shape {
            kind: kind.kind,
            index: index as u32,
        };
        if replaces(t, (primitive.packed(), 0), *self.closest, self.found) {
            *self.closest = t;
            *self.found = Some(Candidate {
                primitive,
                outward: shape.outward(self.ray, t),
                weights: Vec2::ZERO,
                triangle: 0,
            });
        }
    }
}

/// The material of the hit on `found` at `along_ray` (= o + t d), the hit point and a bound on
/// its distance from the true surface point, which the origin of a ray leaving it must clear,
/// and its surface coordinates (zero unless the scene's textures need them). o + t d carries
/// the rounding of the ray's origin and of t (which cancels in the sphere's near root), and
/// that can dwarf the point's own coordinates (a floor at y = 0 seen from 1e6 away), so the
/// point is put back onto the surface, whose own rounding follows the shape's coordinates.
fn surface(scene: &FlatScene, found: &Candidate, along_ray: Vec3) -> (u32, (Vec3, f32), Vec2) {
    let weights = found.weights;
    let weights_uv = if scene.uv_textures {
        weights
    } else {
        Vec2::ZERO
    };
    // Corner texture coordinates, where the scene's meshes have them, replace the weights.
    let corner_uv = |triangle: u32| match scene.triangle_uvs.get(triangle as usize) {
        Some(uvs) => interpolated_uv(uvs, weights),
        None => weights_uv,
    };
    match found.primitive {
        PrimitiveRef::Shape { kind, index } => {
            scene
                .shapes
                .complete(kind, index, along_ray, scene.uv_textures)
        }
        PrimitiveRef::Triangle(i) => {
            let tri = &scene.triangles[i as usize];
            (tri.material, triangle_surface(tri, weights), corner_uv(i))
        }
        PrimitiveRef::Instance(i) => {
            let instance = &scene.instances[i as usize];
            let tri = &scene.triangles[found.triangle as usize];
            let surface = instanced_triangle_surface(instance, tri, weights);
            (instance.material, surface, corner_uv(found.triangle))
        }
    }
}

/// The shading normal of the hit on `found` (whose texture coordinates are `uvs`, both sets),
/// on the side of its unit geometric normal `outward`: a mesh's corner normals interpolated,
/// bent by its material's normal map; and its clear coat's (`Hit::coat`), bent by the coat's
/// (and whether it has one).
fn shading(
    scene: &FlatScene,
    found: &Candidate,
    material: u32,
    uvs: [Vec2; 2],
    outward: Vec3,
) -> (Vec3, (Vec3, bool)) {
    let weights = found.weights;
    let shading = match found.primitive {
        PrimitiveRef::Triangle(i) if !scene.triangle_normals.is_empty() => {
            shading_normal(&scene.triangle_normals[i as usize], weights, outward)
        }
        PrimitiveRef::Instance(i) if !scene.triangle_normals.is_empty() => {
            // Each corner's normal placed as flattening places it (a corner whose normal the
            // placement collapses takes the face's).
            let instance = &scene.instances[i as usize];
            let corners = scene.triangle_normals[found.triangle as usize].map(|n| {
                match instance.normal_to_world(n).normalize_or_zero() {
                    Vec3::ZERO => outward,
                    n => n,
                }
            });
            shading_normal(&corners, weights, outward)
        }
        _ => outward,
    };
    let m = &scene.materials[material as usize];
    let bent = |map: Option<&NormalMap>| match map {
        Some(map) if !scene.triangle_tangents.is_empty() => {
            mapped(scene, found, map, uvs, shading, outward)
        }
        _ => shading,
    };
    let coat_mapped = m.coat_normal_map().is_some() && !scene.triangle_tangents.is_empty();
    (
        bent(m.normal_map()),
        (bent(m.coat_normal_map()), coat_mapped),
    )
}

/// `shading`, the interpolated normal of the hit on `found` (whose texture coordinates are
/// `uvs`), bent by `map` in its triangle's tangent frame.
fn mapped(
    scene: &FlatScene,
    found: &Candidate,
    map: &NormalMap,
    uvs: [Vec2; 2],
    shading: Vec3,
    outward: Vec3,
) -> Vec3 {
    let weights = found.weights;
    let uv = match map.image.lookup.uv_set {
        UvSet::First => uvs[0],
        UvSet::Second => uvs[1],
    };
    match found.primitive {
        PrimitiveRef::Triangle(i) => {
            let tangents = &scene.triangle_tangents[i as usize];
            normal_mapped(map, tangents, weights, uv, shading, outward)
        }
        PrimitiveRef::Instance(i) => {
            // Each corner's tangent placed as flattening places a copy's.
            let instance = &scene.instances[i as usize];
            let tangents = scene.triangle_tangents[found.triangle as usize]
                .map(|t| instance.tangent_to_world(t));
            normal_mapped(map, &tangents, weights, uv, shading, outward)
        }
        PrimitiveRef::Shape { .. } => shading,
    }
}

/// The corner normals `normals` interpolated at barycentric weights (1 - b1 - b2, b1, b2), unit,
/// turned into the hemisphere of the unit geometric normal `outward` (the winding decides the
/// front face, whichever way a file's normals point); `outward` where they cancel.
#[inline]
pub fn shading_normal(normals: &[Vec3; 3], weights: Vec2, outward: Vec3) -> Vec3 {
    let (b1, b2) = (weights.x, weights.y);
    let n = (1.0 - b1 - b2) * normals[0] + b1 * normals[1] + b2 * normals[2];
    let len2 = n.dot(n);
    if !(len2 > 1e-12) {
        return outward;
    }
    let n = n / len2.sqrt();
    if n.dot(outward) < 0.0 { -n } else { n }
}

/// Unit `shading` (on unit `outward`'s side) bent by `map` at texture coordinates `uv`, in the
/// frame of the corner tangents `tangents` interpolated at `weights`, by MikkTSpace's
/// per-pixel rule as Blender applies it: the tangent as interpolated, the bitangent its sign x
/// shading x tangent. `shading` where the tangent or the result vanishes; reflected into
/// `outward`'s hemisphere (twin: `normal_mapped` in shaders/normal_map.wgsl).
#[inline]
pub fn normal_mapped(
    map: &NormalMap,
    tangents: &[Vec4; 3],
    weights: Vec2,
    uv: Vec2,
    shading: Vec3,
    outward: Vec3,
) -> Vec3 {
    let (b1, b2) = (weights.x, weights.y);
    let t = (1.0 - b1 - b2) * tangents[0] + b1 * tangents[1] + b2 * tangents[2];
    let tangent = t.truncate();
    if !(tangent.dot(tangent) > 1e-12) {
        return shading;
    }
    let sign = if t.w < 0.0 { -1.0 } else { 1.0 };
    let bitangent = sign * shading.cross(tangent);
    let texel = crate::assets::image_lookup::image_at(&map.image, uv);
    let local = (2.0 * texel - Vec3::ONE) * Vec3::new(map.scale, map.scale, 1.0);
    let n = local.x * tangent + local.y * bitangent + local.z * shading;
    let len2 = n.dot(n);
    if !(len2 > 1e-12) {
        return shading;
    }
    // Reflected, not negated, into outward's hemisphere: a steep texel keeps the way it slopes.
    let n = n / len2.sqrt();
    let n = n - 2.0 * n.dot(outward).min(0.0) * outward;
    n / n.dot(n).sqrt()
}

/// A triangle's corner texture coordinates interpolated at its hit's `weights` (twin:
/// `interpolated_uv` in shaders/intersect.wgsl).
#[inline]
pub fn interpolated_uv(uvs: &[Vec2; 3], weights: Vec2) -> Vec2 {
    let (b1, b2) = (weights.x, weights.y);
    (1.0 - b1 - b2) * uvs[0] + b1 * uvs[1] + b2 * uvs[2]
}

/// A triangle's point with barycentric weights (1 - b1 - b2, b1, b2), and a bound on its error:
/// the weighted sum is within a few roundings of the corners' magnitudes of the plane.
#[inline]
pub fn triangle_surface(t: &Triangle, weights: Vec2) -> (Vec3, f32) {
    let (b1, b2) = (weights.x, weights.y);
    let b0 = 1.0 - b1 - b2;
    let point = b0 * t.p0 + b1 * t.p1 + b2 * t.p2;
    let scale =
        (b0.abs() * t.p0.abs() + b1.abs() * t.p1.abs() + b2.abs() * t.p2.abs()).max_element();
    (point, POINT_ERROR * scale)
}

/// `triangle_surface` for a triangle of `instance`'s mesh: its corners placed, and a bound that
/// also covers placing them and the transformed ray that found the weights (each a few
/// roundings of the magnitudes summed in placing, whatever cancels there): twice the placed
/// triangle's.
#[inline]
pub fn instanced_triangle_surface(instance: &Instance, t: &Triangle, weights: Vec2) -> (Vec3, f32) {
    let (b1, b2) = (weights.x, weights.y);
    let b0 = 1.0 - b1 - b2;
    let [p0, p1, p2] = [t.p0, t.p1, t.p2].map(|p| instance.point_to_world(p));
    let point = b0 * p0 + b1 * p1 + b2 * p2;
    let [m0, m1, m2] = [t.p0, t.p1, t.p2].map(|p| instance.magnitude_to_world(p));
    let scale = (b0.abs() * m0 + b1.abs() * m1 + b2.abs() * m2).max_element();
    (point, 2.0 * POINT_ERROR * scale)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shared::rng::Rng;

    /// Testing a few shapes in turn finds the hits the BVH finds, to the bit, over random rays
    /// from inside and outside the scenes.
    #[test]
    fn shapes_in_turn_hit_as_through_the_bvh() {
        for name in [
            "spheres",
            "cornell-empty",
            "textured",
            "cornell",
            "cornell-smoke",
            "disks",
        ] {
            let scene = match name {
                "textured" | "disks" => crate::scene::file::load(std::path::Path::new(&format!(
                    "{}/scenes/{name}.toml",
                    env!("CARGO_MANIFEST_DIR")
                )))
                .expect("a shipped scene file"),
                _ => crate::scene::builtin::builtin(name).expect("built-in"),
            };
            let flat = FlatScene::new(&scene, 8, 8).expect("valid");
            assert!(tested_in_turn(&flat), "{name}");
            let radius = flat.bounding_radius() as f32;
            let mut hits = 0;
            for i in 0..20_000 {
                let mut rng = Rng::for_sample(i, 0, 7);
                let mut point = || Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
                let origin = (2.0 * point() - Vec3::ONE) * 1.5 * radius;
                let dir = (2.0 * point() - Vec3::ONE).normalize_or(Vec3::Y);
                let ray = Ray { origin, dir };
                let in_turn =
                    closest_in_turn(&flat, &ray).map(|(t, c)| (t, c.primitive, c.outward));
                let through =
                    closest_through_bvh(&flat, &ray).map(|(t, c)| (t, c.primitive, c.outward));
                assert_eq!(in_turn, through, "{name}: {ray:?}");
                hits += in_turn.is_some() as u32;
            }
            assert!(hits > 1_000, "{name}: only {hits} rays hit");
        }
    }
}

#[cfg(test)]
mod block_tests {
    use super::*;
    use crate::shared::rng::Rng;

    /// The closest-hit search through the wide hierarchy, its small subtrees of triangles tested
    /// as blocks of `WIDTH` lanes, finds what testing every primitive and every instanced
    /// triangle one by one finds, to the bit: in a scene of placed meshes and one of instanced
    /// ones.
    #[test]
    fn triangle_blocks_hit_as_every_triangle_in_turn() {
        for file in ["scenes/meshes.toml", "scenes/knots.toml"] {
            let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(file);
            let scene = crate::scene::file::load(&path).expect(file);
            let flat = FlatScene::new(&scene, 8, 8).expect("valid");
            assert!(!flat.wide_bvh.blocks.is_empty(), "{file}: no blocks");
            let radius = flat.bounding_radius() as f32;
            let mut mesh_hits = 0;
            for i in 0..1_500 {
                let mut rng = Rng::for_sample(i, 0, 5);
                let mut next = || rng.next_f32();
                let origin = Vec3::new(next(), next(), next()) * 2.0 * radius - radius;
                // Aimed at a random triangle's centre, placed or in a random instance.
                let pick = |n: usize, u: f32| ((u * n as f32) as usize).min(n - 1);
                let placed = flat.instanced_triangles;
                let (triangle, to_world) = if flat.instances.is_empty() {
                    (pick(placed, next()), None)
                } else {
                    let instance = &flat.instances[pick(flat.instances.len(), next())];
                    let range = flat.instanced_meshes[instance.mesh as usize].clone();
                    (range.start + pick(range.len(), next()), Some(instance))
                };
                let t = &flat.triangles[triangle];
                let centre = (t.p0 + t.p1 + t.p2) / 3.0;
                let target = to_world.map_or(centre, |i| i.point_to_world(centre));
                let ray = Ray {
                    origin,
                    dir: (target - origin).normalize_or(Vec3::Y),
                };
                let key = |(t, c): (f32, Candidate)| {
                    (t.to_bits(), c.key(), c.weights.to_array().map(f32::to_bits))
                };
                let through = closest_through_bvh(&flat, &ray);
                let in_turn = every_triangle_in_turn(&flat, &ray);
                mesh_hits += through.is_some_and(|(_, c)| {
                    c.triangle != 0 || matches!(c.primitive, PrimitiveRef::Triangle(_))
                }) as u32;
                assert_eq!(through.map(key), in_turn.map(key), "{file}: {ray:?}");
            }
            assert!(mesh_hits > 500, "{file}: only {mesh_hits} rays hit a mesh");
        }
    }

    /// A search for any hit before a distance says "stopped" exactly when the closest hit lies
    /// before it: over random rays through scenes of placed and instanced meshes and of shapes
    /// alone (tested in turn), with the distance beyond everything, at the closest hit, just
    /// past it and halfway to it.
    #[test]
    fn the_first_hit_search_stops_where_the_closest_hit_lies_before() {
        for file in [
            "scenes/meshes.toml",
            "scenes/knots.toml",
            "scenes/textured.toml",
        ] {
            let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(file);
            let scene = crate::scene::file::load(&path).expect(file);
            let flat = FlatScene::new(&scene, 8, 8).expect("valid");
            let radius = flat.bounding_radius() as f32;
            let (mut stopped, mut passed) = (0, 0);
            for i in 0..4_000 {
                let mut rng = Rng::for_sample(i, 0, 9);
                let mut next = || rng.next_f32();
                let origin = Vec3::new(next(), next(), next()) * 2.0 * radius - radius;
                let target = Vec3::new(next(), next(), next()) * radius - 0.5 * radius;
                let ray = Ray {
                    origin,
                    dir: (target - origin).normalize_or(Vec3::Y),
                };
                let closest = intersect(&flat, &ray).map_or(f32::INFINITY, |h| h.t);
                for before in [f32::INFINITY, closest, closest.next_up(), 0.5 * closest] {
                    let expected = closest < before;
                    assert_eq!(
                        stopped_before(&flat, &ray, before),
                        expected,
                        "{file}: {ray:?} before {before}"
                    );
                    (stopped, passed) = if expected {
                        (stopped + 1, passed)
                    } else {
                        (stopped, passed + 1)
                    };
                }
            }
            assert!(
                stopped > 2_000 && passed > 2_000,
                "{file}: {stopped} stopped, {passed} passed"
            );
        }
    }

    /// The closest hit by testing every top-level primitive, and every triangle of an instance,
    /// one by one with `hit_triangle`.
    fn every_triangle_in_turn(scene: &FlatScene, ray: &Ray) -> Option<(f32, Candidate)> {
        let (mut closest, mut found) = (f32::INFINITY, None);
        for &packed in &scene.bvh.primitives[..] {
            match PrimitiveRef::unpacked(packed) {
                PrimitiveRef::Instance(index) => {
                    let instance = &scene.instances[index as usize];
                    let local = local_ray(instance, ray);
                    let mut search = InInstance::<false>::new(scene, index, &local, &mut found);
                    for triangle in scene.instanced_meshes[instance.mesh as usize].clone() {
                        let packed = PrimitiveRef::Triangle(triangle as u32).packed();
                        search.primitive(packed, &mut closest);
                    }
                }
                p => consider::<false>(scene, p, ray, &mut closest, &mut found),
            }
        }
        found.map(|found| (closest, found))
    }
}
