//! The form every backend traces: world-space spheres and quads with precomputed planes, the
//! camera as a frame, and resolved materials. Boxes become six quads and instance transforms are
//! applied once here (a rigid motion of a sphere or parallelogram is again one), so no backend
//! transforms rays per hit.

use super::{Background, Material, Scene, SceneError, Shape};
use glam::{DVec3, Vec3};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sphere {
    pub center: Vec3,
    /// Negative for an inward-facing (hollow) sphere.
    pub radius: f32,
    pub material: u32,
    /// 1 + this sphere's index in [`FlatScene::lights`]; 0 when it does not emit.
    pub light: u32,
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
    /// 1 + this quad's index in [`FlatScene::lights`]; 0 when it does not emit.
    pub light: u32,
    /// How far past its edges, as a fraction of each edge, the quad still counts as hit: the
    /// quads meeting at a box edge have their corners rounded independently, by a few units in
    /// the last place of their coordinates, and rays must not slip between them.
    pub edge_tolerance: f32,
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
}

/// Eight units in the last place of the quad's largest coordinate, as a fraction of its shorter
/// edge, and at least 1e-5.
fn edge_tolerance(q: Vec3, u: Vec3, v: Vec3) -> f32 {
    let magnitude = q.abs().max_element() + u.abs().max_element() + v.abs().max_element();
    (8.0 * f32::EPSILON * magnitude / u.length().min(v.length())).max(1e-5)
}

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

/// A flat triangle's corner normals: its face's, at every corner.
fn face_normals(t: &Triangle) -> [Vec3; 3] {
    [(t.p1 - t.p0).cross(t.p2 - t.p0).normalize(); 3]
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

/// A primitive of a flat scene: its kind and its index among the primitives of that kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PrimitiveRef {
    Sphere(u32),
    Quad(u32),
    Triangle(u32),
}

/// A packed [`PrimitiveRef`] (as the kernel passes it) holds the kind above this many bits of
/// index.
pub const PRIMITIVE_INDEX_BITS: u32 = 28;
/// Most primitives of one kind a scene may have.
pub const MAX_PRIMITIVES_PER_KIND: usize = 1 << PRIMITIVE_INDEX_BITS;
pub const KIND_SPHERE: u32 = 0;
pub const KIND_QUAD: u32 = 1;
pub const KIND_TRIANGLE: u32 = 2;

impl PrimitiveRef {
    /// One number for both backends: kind << PRIMITIVE_INDEX_BITS | index.
    pub fn packed(self) -> u32 {
        match self {
            PrimitiveRef::Sphere(i) => KIND_SPHERE << PRIMITIVE_INDEX_BITS | i,
            PrimitiveRef::Quad(i) => KIND_QUAD << PRIMITIVE_INDEX_BITS | i,
            PrimitiveRef::Triangle(i) => KIND_TRIANGLE << PRIMITIVE_INDEX_BITS | i,
        }
    }

    /// The reference `packed` came from, if it is one.
    pub fn unpacked(packed: u32) -> Option<Self> {
        let index = packed & ((1 << PRIMITIVE_INDEX_BITS) - 1);
        match packed >> PRIMITIVE_INDEX_BITS {
            KIND_SPHERE => Some(PrimitiveRef::Sphere(index)),
            KIND_QUAD => Some(PrimitiveRef::Quad(index)),
            KIND_TRIANGLE => Some(PrimitiveRef::Triangle(index)),
            _ => None,
        }
    }
}

/// Flat scenes are re-centred near the camera in steps of this size (a power of two, so the
/// shift is exact): a scene whose camera is within this distance of the origin is not moved.
pub const RECENTRE_STEP: f64 = 1024.0;

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
    /// fields of spheres and quads index.
    pub materials: Vec<Material>,
    pub spheres: Vec<Sphere>,
    pub quads: Vec<Quad>,
    pub triangles: Vec<Triangle>,
    /// Per triangle, its corners' unit shading normals, when some mesh of the scene has vertex
    /// normals (triangles of the others take their face's); empty otherwise.
    pub triangle_normals: Vec<[Vec3; 3]>,
    /// Over every primitive. The CPU always traverses it (even the Cornell box's 18 primitives
    /// are found 1.3-1.7x faster through it than one by one); GPU kernels of small scenes test
    /// their primitives as straight-line code instead (see `gpu::shader::Features`).
    pub bvh: crate::accel::Bvh,
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
}

/// An emitting primitive as light sampling sees it, picked in proportion to its power.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    pub shape: LightShape,
    /// Chance of picking this light or one before it; the last light's is exactly 1.
    pub cdf: f32,
    /// Chance of picking this light.
    pub pick: f32,
}

/// How a light is sampled.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightShape {
    /// Uniformly in the cone it subtends; `radius` is |radius| (a hollow sphere emits too).
    Sphere { center: Vec3, radius: f32 },
    /// Uniformly on its area, `corner + a u + b v`.
    Quad {
        corner: Vec3,
        u: Vec3,
        v: Vec3,
        /// Unit normal `u x v / |u x v|`.
        normal: Vec3,
        inv_area: f32,
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
    /// The environment (always the last light): directions by its image's distribution.
    Environment(super::environment::Environment),
}

impl FlatScene {
    /// Flattens `scene` for an image of `width` x `height` pixels.
    pub fn new(scene: &Scene, width: u32, height: u32) -> Result<Self, SceneError> {
        scene.validate()?;
        crate::film::check_image_size(width, height).map_err(SceneError::Invalid)?;
        let mut spheres = Vec::new();
        let mut quads = Vec::new();
        let mut triangles = Vec::new();
        let mut triangle_normals: Vec<[Vec3; 3]> = Vec::new();
        let mut smooth = false;
        // Only the materials some object uses, numbered in order of first use: a scene may
        // define thousands it never places, and the kernel holds every material it is given.
        let mut materials = Vec::new();
        let mut renumbered = vec![u32::MAX; scene.materials.len()];
        let origin = (scene.camera.look_from.as_dvec3() / RECENTRE_STEP).trunc() * RECENTRE_STEP;
        for object in &scene.objects {
            let t = object.transform;
            let place = |p: Vec3| t.apply_point_relative(p, origin);
            let slot = &mut renumbered[object.material as usize];
            if *slot == u32::MAX {
                *slot = materials.len() as u32;
                materials.push(scene.materials[object.material as usize].relocated(origin));
            }
            let material = *slot;
            match object.shape {
                Shape::Sphere { center, radius } => spheres.push(Sphere {
                    center: place(center),
                    radius,
                    material,
                    light: 0,
                }),
                Shape::Quad { q, u, v } => quads.push(Quad::new(
                    place(q),
                    t.rotate_vector(u),
                    t.rotate_vector(v),
                    material,
                )),
                Shape::Cuboid { min, max } => {
                    for [q, u, v] in box_faces(min, max) {
                        quads.push(Quad::new(
                            place(q),
                            t.rotate_vector(u),
                            t.rotate_vector(v),
                            material,
                        ));
                    }
                }
                Shape::Mesh { mesh, scale } => {
                    // The first mesh with vertex normals: the triangles before it are flat.
                    if !mesh.normals.is_empty() && !smooth {
                        smooth = true;
                        triangle_normals.extend(triangles.iter().map(face_normals));
                    }
                    // A mirroring scale turns the winding around: swap two corners so the
                    // front face stays the same side of the surface.
                    let mirrored = scale.x * scale.y * scale.z < 0.0;
                    let placed: Vec<Vec3> =
                        mesh.positions.iter().map(|&p| place(p * scale)).collect();
                    // Normals by the inverse transpose: divided by the scale, then rotated.
                    let shading = |n: Vec3| t.rotate_vector(n / scale).normalize_or_zero();
                    for (i, &[a, b, c]) in mesh.triangles.iter().enumerate() {
                        let [b, c] = if mirrored { [c, b] } else { [b, c] };
                        let [p0, p1, p2] = [a, b, c].map(|i| placed[i as usize]);
                        // Triangles that f32 coordinates here flatten to a line are left out.
                        let n = (p1 - p0).cross(p2 - p0);
                        if !(n.length_squared() > 0.0 && n.is_finite()) {
                            continue;
                        }
                        let triangle = Triangle {
                            p0,
                            p1,
                            p2,
                            material,
                            light: 0,
                        };
                        if smooth {
                            let face = n.normalize();
                            triangle_normals.push(match mesh.normals.get(i) {
                                Some(&[n0, n1, n2]) => {
                                    let [n1, n2] = if mirrored { [n2, n1] } else { [n1, n2] };
                                    [n0, n1, n2].map(|n| match shading(n) {
                                        Vec3::ZERO => face,
                                        n => n,
                                    })
                                }
                                None => [face; 3],
                            });
                        }
                        triangles.push(triangle);
                    }
                }
            }
        }
        if spheres.len() > MAX_PRIMITIVES_PER_KIND
            || quads.len() > MAX_PRIMITIVES_PER_KIND
            || triangles.len() > MAX_PRIMITIVES_PER_KIND
        {
            return Err(SceneError::Invalid(format!(
                "a scene may have at most {MAX_PRIMITIVES_PER_KIND} spheres, as many quads and as many triangles"
            )));
        }
        let mut flat = FlatScene {
            origin,
            camera: camera_frame(scene, origin, width, height),
            background: scene.background,
            materials,
            spheres,
            quads,
            triangles,
            triangle_normals,
            bvh: crate::accel::Bvh::default(),
            lights: Vec::new(),
            medium_crossings: 0,
            uv_textures: false,
        };
        flat.uv_textures = flat.materials.iter().any(|m| {
            let features = m.extra_features();
            features.contains(&"UV_CHECKER") || features.contains(&"IMAGE_TEXTURE")
        });
        flat.collect_lights();
        flat.medium_crossings = flat.count_medium_crossings();
        flat.bvh = crate::accel::Bvh::build(&mut flat.bvh_items());
        Ok(flat)
    }

    pub fn primitive_count(&self) -> usize {
        self.spheres.len() + self.quads.len() + self.triangles.len()
    }

    /// Every primitive's bounds, padded for the rounding of the intersection tests: what the
    /// BVH is built over.
    pub fn bvh_items(&self) -> Vec<crate::accel::Item> {
        use crate::accel::Item;
        // A few ulps of the largest coordinate: spheres' bounds are rounded, and quads count
        // as hit a little past their edges.
        let pad = |min: Vec3, max: Vec3, extra: f32| {
            let ulps = 4.0 * f32::EPSILON * min.abs().max(max.abs()).max_element();
            let p = Vec3::splat(ulps + extra);
            (min - p, max + p)
        };
        let mut items = Vec::with_capacity(self.primitive_count());
        for (i, s) in self.spheres.iter().enumerate() {
            let r = Vec3::splat(s.radius.abs());
            let (min, max) = pad(s.center - r, s.center + r, 0.0);
            items.push(Item {
                min,
                max,
                primitive: PrimitiveRef::Sphere(i as u32).packed(),
            });
        }
        for (i, q) in self.quads.iter().enumerate() {
            let corners = [q.q, q.q + q.u, q.q + q.v, q.q + q.u + q.v];
            let min = corners.iter().fold(Vec3::MAX, |m, c| m.min(*c));
            let max = corners.iter().fold(Vec3::MIN, |m, c| m.max(*c));
            let tolerance = q.edge_tolerance * (q.u.abs() + q.v.abs()).max_element();
            let (min, max) = pad(min, max, tolerance);
            items.push(Item {
                min,
                max,
                primitive: PrimitiveRef::Quad(i as u32).packed(),
            });
        }
        let triangles = self.triangles.iter().enumerate().map(|(i, t)| {
            let (min, max) = pad(t.p0.min(t.p1).min(t.p2), t.p0.max(t.p1).max(t.p2), 0.0);
            Item {
                min,
                max,
                primitive: PrimitiveRef::Triangle(i as u32).packed(),
            }
        });
        items.extend(triangles);
        items
    }

    /// Every primitive: spheres, quads, triangles.
    pub fn primitives(&self) -> impl Iterator<Item = PrimitiveRef> + '_ {
        (0..self.spheres.len() as u32)
            .map(PrimitiveRef::Sphere)
            .chain((0..self.quads.len() as u32).map(PrimitiveRef::Quad))
            .chain((0..self.triangles.len() as u32).map(PrimitiveRef::Triangle))
    }

    fn count_medium_crossings(&self) -> u32 {
        let invisible = |m: u32| self.materials[m as usize].is_invisible() as u32;
        let bounds = 2 * self
            .spheres
            .iter()
            .map(|s| invisible(s.material))
            .sum::<u32>()
            + self
                .quads
                .iter()
                .map(|q| invisible(q.material))
                .sum::<u32>();
        if bounds == 0 { 0 } else { bounds + 2 }
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
            PrimitiveRef::Sphere(i) => self.spheres[i as usize].light,
            PrimitiveRef::Quad(i) => self.quads[i as usize].light,
            PrimitiveRef::Triangle(i) => self.triangles[i as usize].light,
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
        let spheres = self.spheres.iter().flat_map(|s| {
            let r = Vec3::splat(s.radius.abs());
            [s.center - r, s.center + r]
        });
        let quads = self
            .quads
            .iter()
            .flat_map(|q| [q.q, q.q + q.u, q.q + q.v, q.q + q.u + q.v]);
        let triangles = self.triangles.iter().flat_map(|t| [t.p0, t.p1, t.p2]);
        let (min, max) = spheres.chain(quads).chain(triangles).fold(
            (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN)),
            |(min, max), p| (min.min(p.as_dvec3()), max.max(p.as_dvec3())),
        );
        let r = 0.5 * (max - min).length();
        if r > 0.0 && r.is_finite() { r } else { 1.0 }
    }

    /// Fills `lights` with every emitting primitive (spheres, then quads) and the environment,
    /// and links each primitive to its light. Lights are picked in proportion to their power,
    /// pi * luminance * area (twice that for two-sided ones).
    pub fn collect_lights(&mut self) {
        let mut lights = Vec::new();
        let mut powers = Vec::new();
        let luminance = |c: Vec3| (0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z) as f64;
        for sphere in &mut self.spheres {
            sphere.light = 0;
            if let Some((radiance, two_sided)) =
                self.materials[sphere.material as usize].area_light()
            {
                let r = sphere.radius.abs();
                let area = 4.0 * std::f64::consts::PI * (r as f64).powi(2);
                let sides = if two_sided { 2.0 } else { 1.0 };
                powers.push(std::f64::consts::PI * luminance(radiance) * area * sides);
                lights.push(Light {
                    shape: LightShape::Sphere {
                        center: sphere.center,
                        radius: r,
                    },
                    cdf: 0.0,
                    pick: 0.0,
                });
                sphere.light = lights.len() as u32;
            }
        }
        for quad in &mut self.quads {
            quad.light = 0;
            if let Some((radiance, two_sided)) = self.materials[quad.material as usize].area_light()
            {
                let area = quad.u.cross(quad.v).length();
                let sides = if two_sided { 2.0 } else { 1.0 };
                powers.push(std::f64::consts::PI * luminance(radiance) * area as f64 * sides);
                lights.push(Light {
                    shape: LightShape::Quad {
                        corner: quad.q,
                        u: quad.u,
                        v: quad.v,
                        normal: quad.normal,
                        inv_area: 1.0 / area,
                    },
                    cdf: 0.0,
                    pick: 0.0,
                });
                quad.light = lights.len() as u32;
            }
        }
        for triangle in &mut self.triangles {
            triangle.light = 0;
            if let Some((radiance, two_sided)) =
                self.materials[triangle.material as usize].area_light()
            {
                let area = triangle.area();
                let sides = if two_sided { 2.0 } else { 1.0 };
                powers.push(std::f64::consts::PI * luminance(radiance) * area * sides);
                let (u, v) = (triangle.p1 - triangle.p0, triangle.p2 - triangle.p0);
                lights.push(Light {
                    shape: LightShape::Triangle {
                        corner: triangle.p0,
                        u,
                        v,
                        normal: u.cross(v).normalize(),
                        inv_area: (1.0 / area) as f32,
                    },
                    cdf: 0.0,
                    pick: 0.0,
                });
                triangle.light = lights.len() as u32;
            }
        }
        if let Background::Environment(env) = self.background {
            powers.push(env.power(self.bounding_radius()));
            lights.push(Light {
                shape: LightShape::Environment(env),
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
            running += share(*power);
            light.cdf = running as f32;
        }
        if let Some(last) = lights.last_mut() {
            last.cdf = 1.0;
        }
        self.lights = lights;
    }
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
        for p in [
            PrimitiveRef::Sphere(0),
            PrimitiveRef::Sphere(MAX_PRIMITIVES_PER_KIND as u32 - 1),
            PrimitiveRef::Quad(0),
            PrimitiveRef::Quad(12345),
        ] {
            assert_eq!(PrimitiveRef::unpacked(p.packed()), Some(p));
        }
        assert_ne!(
            PrimitiveRef::Sphere(3).packed(),
            PrimitiveRef::Quad(3).packed()
        );
        assert_eq!(PrimitiveRef::unpacked(u32::MAX), None);
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
