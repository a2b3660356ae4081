//! The surfaces a flat scene holds besides meshes (spheres, quads, disks), behind one interface,
//! as materials are (`crate::material`): each shape's file holds its scene syntax, its flat
//! form, its CPU intersection and surface, its sampling as an area light and its GPU record; its
//! WGSL twin `shaders/shapes/<name>.wgsl` defines the same functions. `with_shapes!` below lists
//! them once, and from that list come their primitive kinds, the scene's `SurfaceParams`, the
//! flat scene's arrays ([`Shapes`]), the CPU's dispatch and the kernel's (`gpu::shape_dispatch`).
//!
//! To add a shape: its file here (its scene syntax and `impl ShapeParams`, its flat form and
//! `impl SurfaceShape`), its WGSL twin, one line in `with_shapes!`.

pub mod disk;
pub mod quad;
pub mod sphere;

use crate::placement::Transform;
use crate::shared::constants::MIN_LIGHT_COSINE;
use crate::shared::layout::{KIND_ENVIRONMENT, WgslStruct};
use crate::shared::primitive::{KIND_INSTANCE, KIND_TRIANGLE, PRIMITIVE_KINDS};
use crate::shared::ray::Ray;
use glam::{DVec3, Vec2, Vec3};

/// What each shape provides. Its WGSL twin, `shaders/shapes/<name>.wgsl`, defines
/// `<name>_distance(s, ray)` (-1 for a miss), `consider_<name>(s, index, ray, in_order, c)` (the
/// closest-hit test, which also keeps in `Closest::shape` what the hit's completion needs),
/// `<name>_surface(c, along_ray, n)`, `<name>_hit_uv(c, point)` (under the features that read
/// UVs), and under NEE `<name>_light_sample(l, x, u1, u2)` and `<name>_light_pdf(l, x, p, dir)`:
/// the twins of the methods below, with the same arithmetic.
pub trait SurfaceShape: Copy + std::fmt::Debug + PartialEq + Send + Sync {
    /// Its record in the kernel's array of this shape (named as its WGSL struct).
    type Gpu: WgslStruct + bytemuck::Pod + Default;
    fn material(&self) -> u32;
    /// 1 + its index in the scene's light list; 0 when it does not emit.
    fn light(&self) -> u32;
    fn set_light(&mut self, light: u32);
    /// Its bounding box.
    fn bounds(&self) -> [Vec3; 2];
    /// Its bounding box, padded for the rounding of its intersection test: what the BVH holds.
    fn padded_bounds(&self) -> [Vec3; 2] {
        let [min, max] = self.bounds();
        pad(min, max, 0.0)
    }
    /// How often a straight line crosses its surface at most (a medium's boundary count).
    const CROSSINGS: u32;
    /// Distance along the ray within (0, t_max), if it is hit.
    fn hit(&self, ray: &Ray, t_max: f32) -> Option<f32>;
    /// The outward normal at distance `t` along the ray, not yet of unit length.
    fn outward(&self, ray: &Ray, t: f32) -> Vec3;
    /// These shapes as spheres, if they are: the CPU tests spheres four at a time.
    fn as_spheres(_shapes: &[Self]) -> Option<&[sphere::Sphere]> {
        None
    }
    /// These shapes as quads, if they are: the CPU tests quads four at a time.
    fn as_quads(_shapes: &[Self]) -> Option<&[quad::Quad]> {
        None
    }
    /// The hit `along_ray` (= o + t d) put back onto the surface, and a bound on its error.
    fn surface(&self, along_ray: Vec3) -> (Vec3, f32);
    /// Surface coordinates for textures at `point` (on the surface) or `along_ray`.
    fn uv(&self, point: Vec3, along_ray: Vec3) -> Vec2;
    /// Its area, and itself as a light.
    fn as_light(&self) -> (f64, SurfaceLight);
    /// A direction from `x` toward light `l` (of this shape) from two uniform numbers, its
    /// solid-angle pdf times `pick`, and the point it reaches; `None` where there is none.
    fn sample_light(l: &SurfaceLight, pick: f32, x: Vec3, u1: f32, u2: f32) -> Option<LightSample>;
    /// The pdf `sample_light` gives the direction `dir` from `x` reaching `l` at `p`.
    fn light_pdf(l: &SurfaceLight, pick: f32, x: Vec3, p: Vec3, dir: Vec3) -> f32;
    fn gpu(&self) -> Self::Gpu;
}

/// A shape as a light, in the fields of the kernel's `Light` (`GpuLight`): what each means is
/// the shape's (a sphere's centre and radius; a quad's corner, edges, normal and 1 / area).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SurfaceLight {
    pub position: Vec3,
    pub u: Vec3,
    pub v: Vec3,
    pub normal: Vec3,
    pub size: f32,
}

/// A sample of a light seen from `x`: a unit direction, its solid-angle pdf (with the pick
/// probability), and the point on the light it reaches (where the shadow ray aims; for the
/// environment, which is at infinity, the shadow ray follows `dir` and `point` is unused).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    pub dir: Vec3,
    pub pdf: f32,
    pub point: Vec3,
}

/// Solid-angle pdf of light sampling choosing a flat light's point `p` from `x`, seen along
/// unit `dir`, for a light picked with probability `pick` whose unit normal is `normal` and
/// whose area is 1 / `inv_area`, sampled uniformly on it; 0 where light sampling never goes
/// (twin: `area_pdf` in shaders/lights.wgsl).
#[inline]
pub fn area_pdf(pick: f32, normal: Vec3, inv_area: f32, x: Vec3, p: Vec3, dir: Vec3) -> f32 {
    let cos_light = normal.dot(dir).abs();
    if !(cos_light > MIN_LIGHT_COSINE) {
        return 0.0;
    }
    let dist2 = (p - x).length_squared();
    pick * inv_area * dist2 / cos_light
}

/// A sample of a flat light, uniform on its area, at `point`, seen from `x`.
#[inline]
pub fn area_sample(
    pick: f32,
    point: Vec3,
    normal: Vec3,
    inv_area: f32,
    x: Vec3,
) -> Option<LightSample> {
    let to_light = point - x;
    let dist2 = to_light.length_squared();
    if !(dist2 > 0.0) {
        return None;
    }
    let dir = to_light / dist2.sqrt();
    let pdf = area_pdf(pick, normal, inv_area, x, point, dir);
    (pdf > 0.0).then_some(LightSample { dir, pdf, point })
}

/// `along_ray` projected onto the plane `normal . p = d` (unit `normal`), and a bound on the
/// result's error: a flat shape's hit point put back onto it (twin: `plane_surface` in
/// shaders/intersect.wgsl).
#[inline]
pub fn plane_surface(along_ray: Vec3, normal: Vec3, d: f32) -> (Vec3, f32) {
    let point = along_ray - (normal.dot(along_ray) - d) * normal;
    let scale = point.abs().max_element() + d.abs();
    (point, crate::shared::ray::POINT_ERROR * scale)
}

/// A box padded by a few ulps of its largest coordinate (shapes' bounds are rounded) and by
/// `extra`.
pub fn pad(min: Vec3, max: Vec3, extra: f32) -> [Vec3; 2] {
    let ulps = 4.0 * f32::EPSILON * min.abs().max(max.abs()).max_element();
    let p = Vec3::splat(ulps + extra);
    [min - p, max + p]
}

/// A shape as a scene file describes it (its `[[object]]` table, whose key is its file's name):
/// checked, and placed into the flat scene.
pub trait ShapeParams:
    Copy + std::fmt::Debug + PartialEq + serde::Serialize + serde::de::DeserializeOwned
{
    /// Its flat form.
    type Flat: SurfaceShape;
    /// Whether f32 geometry can hold it (sizes within `scene::MIN_SIZE`..`scene::MAX_EXTENT`).
    fn validate(&self) -> Result<(), String>;
    /// A point of it, and how far from the origin it reaches per axis (for the extent check).
    fn reach(&self) -> (Vec3, Vec3);
    /// It moved by `transform` into a scene whose coordinates start at `origin`.
    fn placed(&self, transform: &Transform, origin: DVec3, material: u32) -> Self::Flat;
}

/// Something done to each shape array in turn (Rust closures cannot be generic over the shape).
pub trait ShapeVisitor {
    fn visit<S: SurfaceShape>(&mut self, kind: &'static ShapeKind, shapes: &[S]);
}

/// [`ShapeVisitor`] for changing the shapes.
pub trait ShapeVisitorMut {
    fn visit<S: SurfaceShape>(&mut self, kind: &'static ShapeKind, shapes: &mut [S]);
}

/// What the kernel's generation needs of a shape.
#[derive(Debug)]
pub struct ShapeKind {
    /// Its file name, and the prefix of its WGSL twin's functions.
    pub name: &'static str,
    /// Its primitive kind (`PrimitiveRef::Shape`'s and `GpuLight::kind`'s).
    pub kind: u32,
    /// The kernel feature that includes its twin: its array's name in upper case.
    pub feature: &'static str,
    /// Its array's name in the flat scene and in the kernel.
    pub array: &'static str,
    /// Its WGSL struct's name.
    pub wgsl_struct: &'static str,
    pub wgsl: &'static str,
}

/// The primitive kind of the shape at `position` in `shapes!`: positions, skipping the kinds of
/// meshes' triangles and instances (kept at 2 and 3: a triangle hit's kind seeds the random
/// number of a see-through surface, so renumbering them would change images).
pub const fn kind_at(position: u32) -> u32 {
    if position < KIND_TRIANGLE {
        position
    } else {
        position + 2
    }
}

const _: () = assert!(KIND_INSTANCE == KIND_TRIANGLE + 1);
// Shape kinds fit a packed reference and stay below the lights' own kinds (`KIND_ENVIRONMENT`).
const _: () = assert!(kind_at(KINDS.len() as u32 - 1) < KIND_ENVIRONMENT);
const _: () = assert!(KIND_ENVIRONMENT < PRIMITIVE_KINDS);

/// Defines [`Shapes`], [`KINDS`], [`SurfaceParams`] and the per-kind dispatch from the list of
/// `with_shapes!`.
macro_rules! shapes {
    ($($module:ident :: $ty:ident ($params:ident) => $array:ident,)+) => {
        #[allow(non_camel_case_types)]
        #[derive(Clone, Copy)]
        enum Position { $($array,)+ }

        /// Every shape kind, in the order of `shapes!`.
        pub const KINDS: &[ShapeKind] = &[$(ShapeKind {
            name: stringify!($module),
            kind: kind_at(Position::$array as u32),
            feature: const_str_upper!(stringify!($array)),
            array: stringify!($array),
            wgsl_struct: <<$ty as SurfaceShape>::Gpu as WgslStruct>::WGSL_NAME,
            wgsl: include_str!(concat!("../../shaders/shapes/", stringify!($module), ".wgsl")),
        },)+];

        $(pub use $module::{$ty, $params};)+

        /// A shape as a scene describes it: its file's `ShapeParams`.
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub enum SurfaceParams {
            $($ty($params),)+
        }

        impl SurfaceParams {
            /// Its scene-file key (its file's name).
            pub fn name(&self) -> &'static str {
                match self { $(SurfaceParams::$ty(_) => stringify!($module),)+ }
            }
            pub fn validate(&self) -> Result<(), String> {
                match self { $(SurfaceParams::$ty(p) => p.validate(),)+ }
            }
            pub fn reach(&self) -> (Vec3, Vec3) {
                match self { $(SurfaceParams::$ty(p) => p.reach(),)+ }
            }
            /// Adds it, placed (see [`ShapeParams::placed`]), to `shapes`.
            pub fn place(&self, transform: &Transform, origin: DVec3, material: u32, shapes: &mut Shapes) {
                match self {
                    $(SurfaceParams::$ty(p) => shapes.$array.push(p.placed(transform, origin, material)),)+
                }
            }
        }

        $(impl $ty {
            /// Its primitive kind.
            pub const KIND: u32 = kind_at(Position::$array as u32);
        })+

        /// The flat scene's shapes, an array per kind.
        #[derive(Clone, Debug, Default, PartialEq)]
        pub struct Shapes {
            $(pub $array: Vec<$ty>,)+
        }

        impl Shapes {
            pub fn visit(&self, v: &mut impl ShapeVisitor) {
                $(v.visit(&KINDS[Position::$array as usize], &self.$array);)+
            }

            pub fn visit_mut(&mut self, v: &mut impl ShapeVisitorMut) {
                $(v.visit(&KINDS[Position::$array as usize], &mut self.$array);)+
            }

            /// Shape `index` of `kind` against the ray within (0, t_max): its distance and
            /// outward normal (not unit), if hit.
            #[inline]
            pub fn hit(&self, kind: u32, index: u32, ray: &Ray, t_max: f32) -> Option<(f32, Vec3)> {
                $(if kind == kind_at(Position::$array as u32) {
                    let s = &self.$array[index as usize];
                    return s.hit(ray, t_max).map(|t| (t, s.outward(ray, t)));
                })+
                None
            }

            /// The hit on shape `index` of `kind` at `along_ray`: its material, its point put
            /// back on the surface and its error bound, and (where `uv`) its texture
            /// coordinates.
            pub fn complete(&self, kind: u32, index: u32, along_ray: Vec3, uv: bool) -> (u32, (Vec3, f32), Vec2) {
                $(if kind == kind_at(Position::$array as u32) {
                    return complete(&self.$array[index as usize], along_ray, uv);
                })+
                unreachable!("shape kind {kind}")
            }

            /// 1 + the light index of shape `index` of `kind`, or 0.
            #[inline]
            pub fn light(&self, kind: u32, index: u32) -> u32 {
                $(if kind == kind_at(Position::$array as u32) {
                    return self.$array[index as usize].light();
                })+
                0
            }
        }

        /// Every shape's GPU record's layout, for the layout test.
        pub fn layouts() -> Vec<crate::shared::layout::StructLayout> {
            vec![$(crate::shared::layout::layout_of::<<$ty as SurfaceShape>::Gpu>(),)+]
        }

        /// Every shape's GPU record's WGSL declaration.
        pub fn wgsl_declarations() -> String {
            [$(<<$ty as SurfaceShape>::Gpu as WgslStruct>::wgsl_declaration(),)+].concat()
        }

        /// The largest shape record, in bytes.
        pub const LARGEST_GPU_RECORD: usize = {
            let mut largest = 0;
            $(if std::mem::size_of::<<$ty as SurfaceShape>::Gpu>() > largest {
                largest = std::mem::size_of::<<$ty as SurfaceShape>::Gpu>();
            })+
            largest
        };

        /// A sample of light `l`, a shape of `kind` (see [`SurfaceShape::sample_light`]).
        #[inline]
        pub fn sample_light(kind: u32, l: &SurfaceLight, pick: f32, x: Vec3, u1: f32, u2: f32) -> Option<LightSample> {
            $(if kind == kind_at(Position::$array as u32) {
                return <$ty as SurfaceShape>::sample_light(l, pick, x, u1, u2);
            })+
            None
        }

        /// [`SurfaceShape::light_pdf`] of light `l`, a shape of `kind`.
        #[inline]
        pub fn light_pdf(kind: u32, l: &SurfaceLight, pick: f32, x: Vec3, p: Vec3, dir: Vec3) -> f32 {
            $(if kind == kind_at(Position::$array as u32) {
                return <$ty as SurfaceShape>::light_pdf(l, pick, x, p, dir);
            })+
            0.0
        }
    };
}

/// An ASCII string literal in upper case, at compile time.
macro_rules! const_str_upper {
    ($s:expr) => {{
        const S: &str = $s;
        const N: usize = S.len();
        const BYTES: [u8; N] = {
            let mut out = [0u8; N];
            let b = S.as_bytes();
            let mut i = 0;
            while i < N {
                out[i] = b[i].to_ascii_uppercase();
                i += 1;
            }
            out
        };
        match std::str::from_utf8(&BYTES) {
            Ok(s) => s,
            Err(_) => panic!("not ASCII"),
        }
    }};
}

/// The registry: every shape once, as `file::FlatForm(SceneParams) => array,` (its file in
/// src/shape/ and shaders/shapes/, its flat form and scene syntax there, the flat scene's and
/// the kernel's array of it). Calls `$m!` with the list: `shapes!` below, and the scene file's
/// object table (`scene::file`).
macro_rules! with_shapes {
    ($m:ident) => {
        $m! {
            sphere::Sphere(SphereParams) => spheres,
            quad::Quad(QuadParams) => quads,
            disk::Disk(DiskParams) => disks,
        }
    };
}
pub(crate) use with_shapes;

with_shapes!(shapes);

/// The completed hit on `shape` (see [`Shapes::complete`]).
fn complete<S: SurfaceShape>(shape: &S, along_ray: Vec3, uv: bool) -> (u32, (Vec3, f32), Vec2) {
    let (point, error) = shape.surface(along_ray);
    let uv = if uv {
        shape.uv(point, along_ray)
    } else {
        Vec2::ZERO
    };
    (shape.material(), (point, error), uv)
}

impl Shapes {
    /// How many shapes of every kind.
    pub fn len(&self) -> usize {
        struct Count(usize);
        impl ShapeVisitor for Count {
            fn visit<S: SurfaceShape>(&mut self, _: &'static ShapeKind, shapes: &[S]) {
                self.0 += shapes.len();
            }
        }
        let mut count = Count(0);
        self.visit(&mut count);
        count.0
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Every shape's material.
    pub fn materials(&self) -> Vec<u32> {
        struct Materials(Vec<u32>);
        impl ShapeVisitor for Materials {
            fn visit<S: SurfaceShape>(&mut self, _: &'static ShapeKind, shapes: &[S]) {
                self.0.extend(shapes.iter().map(|s| s.material()));
            }
        }
        let mut out = Materials(Vec::new());
        self.visit(&mut out);
        out.0
    }

    /// How many shapes of `kind`.
    pub fn count(&self, kind: &ShapeKind) -> usize {
        struct Count<'a>(&'a ShapeKind, usize);
        impl ShapeVisitor for Count<'_> {
            fn visit<S: SurfaceShape>(&mut self, kind: &'static ShapeKind, shapes: &[S]) {
                if kind.kind == self.0.kind {
                    self.1 = shapes.len();
                }
            }
        }
        let mut count = Count(kind, 0);
        self.visit(&mut count);
        count.1
    }
}

/// The [`ShapeKind`] of primitive kind `kind`, if a shape has it.
pub fn kind_of(kind: u32) -> Option<&'static ShapeKind> {
    KINDS.iter().find(|k| k.kind == kind)
}
