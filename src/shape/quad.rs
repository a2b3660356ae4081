//! A parallelogram (twin: `shaders/shapes/quad.wgsl`): hit where the ray crosses its plane
//! within its edges, put back onto its plane, sampled as a light uniformly on its area.

use super::{
    LightSample, ShapeParams, SurfaceLight, SurfaceShape, area_pdf, area_sample, pad, plane_surface,
};
use crate::params::checked;
use crate::placement::{MAX_EXTENT, MIN_SIZE, Transform};
use crate::shared::layout::{WgslStruct, WgslType, gpu_struct};
use crate::shared::ray::Ray;
use bytemuck::{Pod, Zeroable};
use glam::{DVec3, Vec2, Vec3};

/// Its scene syntax: `quad = { q = [x, y, z], u = [x, y, z], v = [x, y, z] }`, the
/// parallelogram `q + a u + b v`, a, b in [0, 1]; its front face is along `u x v`.
#[derive(Clone, Copy, Debug, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct QuadParams {
    #[serde(with = "checked::vector")]
    pub q: Vec3,
    #[serde(with = "checked::vector")]
    pub u: Vec3,
    #[serde(with = "checked::vector")]
    pub v: Vec3,
}

impl ShapeParams for QuadParams {
    type Flat = Quad;
    fn validate(&self) -> Result<(), String> {
        let (q, u, v) = (self.q, self.u, self.v);
        let area = u.cross(v).length();
        if !q.is_finite() || !(area > 0.0) || !area.is_finite() {
            return Err("quad has zero area: its edges u and v are parallel or zero".into());
        }
        let (lu, lv) = (u.length(), v.length());
        let sized = lu.min(lv) >= MIN_SIZE && lu.max(lv) <= MAX_EXTENT;
        if !(sized && area >= MIN_SIZE * MIN_SIZE) {
            return Err(format!(
                "quad edges of length {lu} and {lv} (area {area}) are outside what f32 geometry handles: use sizes between {MIN_SIZE:e} and {MAX_EXTENT:e}"
            ));
        }
        Ok(())
    }
    fn reach(&self) -> (Vec3, Vec3) {
        (self.q, self.q.abs() + self.u.abs() + self.v.abs())
    }
    fn placed(&self, transform: &Transform, origin: DVec3, material: u32) -> Quad {
        Quad::new(
            transform.apply_point_relative(self.q, origin),
            transform.rotate_vector(self.u),
            transform.rotate_vector(self.v),
            material,
        )
    }
}

/// The parallelogram `q + a u + b v`, with its plane `normal . p = d` and two axes precomputed
/// so that a hit costs one division and two dot products: for a point p in the plane,
/// a = (p - q) . alpha_axis and b = (p - q) . beta_axis, where with n = u x v and
/// w = n / |n|^2, alpha_axis = v x w and beta_axis = w x u.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Quad {
    pub q: Vec3,
    pub u: Vec3,
    pub v: Vec3,
    pub normal: Vec3,
    pub d: f32,
    pub alpha_axis: Vec3,
    pub beta_axis: Vec3,
    pub material: u32,
    /// 1 + this quad's index in the scene's lights; 0 when it does not emit.
    pub light: u32,
    /// How far past its edges, as a fraction of each edge, the quad still counts as hit: the
    /// quads meeting at a box edge have their corners rounded independently, by a few units in
    /// the last place of their coordinates, and rays must not slip between them.
    pub edge_tolerance: f32,
}

gpu_struct! {
    /// The parallelogram q + a u + b v, a, b in [0, 1] (see [`Quad`] for the axes).
    pub struct GpuQuad as "Quad" {
        q: [f32; 3],
        /// Plane: dot(normal, p) = d.
        d: f32,
        normal: [f32; 3],
        material: u32,
        alpha_axis: [f32; 3],
        /// 1 + its index in the light list; 0 when it does not emit.
        light: u32,
        beta_axis: [f32; 3],
        /// Counts as hit this far (a fraction of each edge) past its edges.
        edge_tolerance: f32,
    }
}

impl Quad {
    pub fn new(q: Vec3, u: Vec3, v: Vec3, material: u32) -> Self {
        let n = u.cross(v);
        let normal = n.normalize();
        let w = n / n.length_squared();
        Quad {
            q,
            u,
            v,
            normal,
            d: normal.dot(q),
            alpha_axis: v.cross(w),
            beta_axis: w.cross(u),
            material,
            light: 0,
            edge_tolerance: edge_tolerance(q, u, v),
        }
    }

    fn corners(&self) -> [Vec3; 4] {
        [
            self.q,
            self.q + self.u,
            self.q + self.v,
            self.q + self.u + self.v,
        ]
    }
}

/// Up to four quads' hit-test values side by side (a structure of arrays, a row per
/// coordinate), as the CPU's four-lane test (`cpu::four_quads`) loads them: built once per
/// scene for scenes whose shapes are tested in turn. Lanes past the quads repeat the first.
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(16))]
pub struct QuadBlock {
    pub normal: [[f32; 4]; 3],
    pub q: [[f32; 4]; 3],
    pub alpha_axis: [[f32; 4]; 3],
    pub beta_axis: [[f32; 4]; 3],
    /// Where a hit's a and b may lie: -edge_tolerance to 1 + edge_tolerance, as `hit_quad`
    /// computes them.
    pub lo: [f32; 4],
    pub hi: [f32; 4],
    /// The lanes holding a quad (bit k: lane k).
    pub present: u32,
}

impl QuadBlock {
    /// The block of `quads` (one to four).
    pub fn new(quads: &[Quad]) -> Self {
        assert!((1..=4).contains(&quads.len()), "one to four quads");
        let lane = |i: usize| quads.get(i).unwrap_or(&quads[0]);
        let rows = |f: &dyn Fn(&Quad) -> f32| std::array::from_fn(|i| f(lane(i)));
        let vector =
            |f: &dyn Fn(&Quad) -> Vec3| [rows(&|q| f(q).x), rows(&|q| f(q).y), rows(&|q| f(q).z)];
        QuadBlock {
            normal: vector(&|q| q.normal),
            q: vector(&|q| q.q),
            alpha_axis: vector(&|q| q.alpha_axis),
            beta_axis: vector(&|q| q.beta_axis),
            lo: rows(&|q| -q.edge_tolerance),
            hi: rows(&|q| 1.0 + q.edge_tolerance),
            present: (1 << quads.len()) - 1,
        }
    }

    /// `quads` four to a block, in order.
    pub fn blocks(quads: &[Quad]) -> Vec<QuadBlock> {
        quads.chunks(4).map(QuadBlock::new).collect()
    }
}

/// Eight units in the last place of the quad's largest coordinate, as a fraction of its shorter
/// edge, and at least 1e-5.
fn edge_tolerance(q: Vec3, u: Vec3, v: Vec3) -> f32 {
    let magnitude = q.abs().max_element() + u.abs().max_element() + v.abs().max_element();
    (8.0 * f32::EPSILON * magnitude / u.length().min(v.length())).max(1e-5)
}

/// Distance along the ray to `quad` within (t_min, t_max), if any. Rays parallel to its plane
/// miss: they have no single crossing point.
#[inline]
pub fn hit_quad(quad: &Quad, ray: &Ray, t_min: f32, t_max: f32) -> Option<f32> {
    let denom = quad.normal.dot(ray.dir);
    if denom.abs() < crate::shared::constants::PARALLEL_DENOMINATOR {
        return None;
    }
    // From the ray's origin to the quad's corner first: far from the world's origin the two
    // are close and their difference exact, where n . q - n . o would cancel catastrophically.
    let to_corner = quad.q - ray.origin;
    let t = quad.normal.dot(to_corner) / denom;
    if !(t > t_min && t < t_max) {
        return None;
    }
    let planar = t * ray.dir - to_corner;
    let alpha = planar.dot(quad.alpha_axis);
    let beta = planar.dot(quad.beta_axis);
    let (lo, hi) = (-quad.edge_tolerance, 1.0 + quad.edge_tolerance);
    let inside = |a: f32| (lo..=hi).contains(&a);
    (inside(alpha) && inside(beta)).then_some(t)
}

impl SurfaceShape for Quad {
    type Gpu = GpuQuad;
    const CROSSINGS: u32 = 1;

    fn material(&self) -> u32 {
        self.material
    }
    fn light(&self) -> u32 {
        self.light
    }
    fn set_light(&mut self, light: u32) {
        self.light = light;
    }
    fn bounds(&self) -> [Vec3; 2] {
        let corners = self.corners();
        let min = corners.iter().fold(Vec3::MAX, |m, c| m.min(*c));
        let max = corners.iter().fold(Vec3::MIN, |m, c| m.max(*c));
        [min, max]
    }
    /// Also by its edge tolerance: it counts as hit a little past its edges.
    fn padded_bounds(&self) -> [Vec3; 2] {
        let [min, max] = self.bounds();
        let tolerance = self.edge_tolerance * (self.u.abs() + self.v.abs()).max_element();
        pad(min, max, tolerance)
    }
    #[inline]
    fn hit(&self, ray: &Ray, t_max: f32) -> Option<f32> {
        hit_quad(self, ray, 0.0, t_max)
    }
    fn as_quads(shapes: &[Self]) -> Option<&[Quad]> {
        Some(shapes)
    }
    #[inline]
    fn outward(&self, _ray: &Ray, _t: f32) -> Vec3 {
        self.normal
    }
    /// Projected onto its plane.
    fn surface(&self, along_ray: Vec3) -> (Vec3, f32) {
        plane_surface(along_ray, self.normal, self.d)
    }
    /// (a, b) of `q + a u + b v`.
    fn uv(&self, _point: Vec3, along_ray: Vec3) -> Vec2 {
        let d = along_ray - self.q;
        Vec2::new(d.dot(self.alpha_axis), d.dot(self.beta_axis))
    }
    /// `position` its corner, `u` and `v` its edges, `size` 1 / its area.
    fn as_light(&self) -> (f64, SurfaceLight) {
        let area = self.u.cross(self.v).length();
        let light = SurfaceLight {
            position: self.q,
            u: self.u,
            v: self.v,
            normal: self.normal,
            size: 1.0 / area,
        };
        (area as f64, light)
    }
    fn sample_light(l: &SurfaceLight, pick: f32, x: Vec3, u1: f32, u2: f32) -> Option<LightSample> {
        area_sample(pick, l.position + u1 * l.u + u2 * l.v, l.normal, l.size, x)
    }
    fn light_pdf(l: &SurfaceLight, pick: f32, x: Vec3, p: Vec3, dir: Vec3) -> f32 {
        area_pdf(pick, l.normal, l.size, x, p, dir)
    }
    fn gpu(&self) -> GpuQuad {
        GpuQuad {
            q: self.q.to_array(),
            d: self.d,
            normal: self.normal.to_array(),
            material: self.material,
            alpha_axis: self.alpha_axis.to_array(),
            beta_axis: self.beta_axis.to_array(),
            light: self.light,
            edge_tolerance: self.edge_tolerance,
        }
    }
}
