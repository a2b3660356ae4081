//! What the kernel keeps per invocation and no buffer holds, declared once here and generated
//! into WGSL (`kernel_struct!`): the closest hit of a ray being traced and the path under way.
//! The CPU keeps the same state its own way (`cpu::intersect`' candidate, `cpu::integrator`'s loop).

use crate::shared::layout::kernel_struct;
use crate::shared::primitive::PrimitiveRef;
use crate::shared::ray::Ray;
use glam::{Vec2, Vec3, Vec4};

kernel_struct! {
    /// The closest hit found so far along a ray, and what its shape needs to complete the hit
    /// (`surface` in shaders/intersect.wgsl). `NO_CLOSEST` there builds it field by field, in
    /// this order.
    pub struct Closest as "Closest" {
        outward: Vec3,
        t: f32,
        /// What the shape hit keeps to complete the hit (its `<name>_surface`, `<name>_hit_uv`):
        /// a sphere's centre and radius, a quad's or disk's plane offset in `w`.
        shape: Vec4,
        /// Packed, as in `Hit`.
        primitive: PrimitiveRef,
        material: u32,
        found: bool,
        /// A quad's (a, b), a disk's polar coordinates, for UV textures.
        uv: Vec2,
        /// A triangle's barycentric weights of its second and third corners.
        weights: Vec2,
        /// An instance's: which of its mesh's triangles (index in triangles).
        triangle: u32,
    }
}

kernel_struct! {
    /// A path under way (twin: the loop of `radiance` in src/cpu/integrator.rs, one iteration
    /// per `extend_path` call in shaders/integrator.wgsl). The render kernel advances each
    /// invocation's path a segment at a time and starts its pixel's next sample as soon as one
    /// ends, rather than looping over a sample's segments inside a loop over samples: SIMD lanes
    /// step together, so with nested loops a lane whose path ended early idled until its group's
    /// longest path ended (path regeneration, Novak, Havran and Dachsbacher 2010). `start_path`
    /// builds it field by field, in this order.
    pub struct Path as "Path" {
        ray: Ray,
        total: Vec3,
        throughput: Vec3,
        /// Segments traced so far.
        segment: u32,
        /// The medium the ray is in: 1 + the index of the material filled with it; 0: none.
        medium: u32,
        /// The pdf with which the BSDF (or phase function) chose `ray` from `origin`; 0 when
        /// light sampling could not have chosen it (camera rays, delta BSDFs; always without
        /// NEE), so light it finds counts in full.
        bsdf_pdf: f32,
        origin: Vec3,
    }
}

/// Their WGSL declarations.
pub fn wgsl_declarations() -> String {
    [Closest::wgsl_declaration(), Path::wgsl_declaration()].join("\n")
}
