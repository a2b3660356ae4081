//! Up to four spheres tested against a ray together, for scenes whose few shapes are tested
//! in turn (`intersect::closest_in_turn`): [`crate::shape::sphere::hit_sphere`]'s operations in
//! its order, lane by lane, so each lane's distance is bit for bit the one it gives its sphere
//! (Rust never fuses a multiply and an add unasked; SSE's square root is IEEE's, as
//! `f32::sqrt` is).

use crate::shape::SurfaceShape;
use crate::shape::sphere::Sphere;
use crate::shared::ray::Ray;

// The four floats `hits` loads from a sphere: its centre, then its radius.
const _: () = assert!(
    std::mem::offset_of!(Sphere, center) == 0 && std::mem::offset_of!(Sphere, radius) == 12
);

/// Where each of up to four shapes tested together (spheres here, quads in
/// `cpu::four_quads`) is hit within (0, `t_max`): the distance in the lanes set in `hit`.
pub struct LaneHits {
    pub t: [f32; 4],
    pub hit: u32,
}

/// `spheres` (at most four) against `ray` within (0, `t_max`).
#[inline]
#[cfg(target_arch = "x86_64")]
pub fn hits(spheres: &[Sphere], ray: &Ray, t_max: f32) -> LaneHits {
    use std::arch::x86_64::*;
    assert!((1..=4).contains(&spheres.len()), "one to four spheres");
    // A lane past the spheres repeats the first, and is masked off at the end.
    let lane = |i: usize| spheres.get(i).unwrap_or(&spheres[0]);
    // SAFETY: SSE is part of x86-64's baseline; each load reads the first 16 of a `Sphere`'s
    // 24 bytes through a pointer to the whole sphere: its centre and radius (`repr(C)`,
    // checked below).
    unsafe {
        let load = |i: usize| _mm_loadu_ps((lane(i) as *const Sphere).cast::<f32>());
        let (mut x, mut y, mut z, mut radius) = (load(0), load(1), load(2), load(3));
        _MM_TRANSPOSE4_PS(&mut x, &mut y, &mut z, &mut radius);
        let splat = |v: f32| _mm_set1_ps(v);
        let (dx, dy, dz) = (splat(ray.dir.x), splat(ray.dir.y), splat(ray.dir.z));
        let oc = [
            _mm_sub_ps(x, splat(ray.origin.x)),
            _mm_sub_ps(y, splat(ray.origin.y)),
            _mm_sub_ps(z, splat(ray.origin.z)),
        ];
        // glam's dot: (x x' + y y') + z z'.
        let dot = |a: [__m128; 3], b: [__m128; 3]| {
            let xy = _mm_add_ps(_mm_mul_ps(a[0], b[0]), _mm_mul_ps(a[1], b[1]));
            _mm_add_ps(xy, _mm_mul_ps(a[2], b[2]))
        };
        let h = dot([dx, dy, dz], oc);
        let perpendicular = [
            _mm_sub_ps(oc[0], _mm_mul_ps(h, dx)),
            _mm_sub_ps(oc[1], _mm_mul_ps(h, dy)),
            _mm_sub_ps(oc[2], _mm_mul_ps(h, dz)),
        ];
        let disc = _mm_sub_ps(
            _mm_mul_ps(radius, radius),
            dot(perpendicular, perpendicular),
        );
        let present = (1u32 << spheres.len()) - 1;
        let mut out = LaneHits {
            t: [0.0; 4],
            hit: 0,
        };
        // Most rays miss every sphere: no root to wait for.
        if _mm_movemask_ps(_mm_cmpge_ps(disc, _mm_setzero_ps())) as u32 & present == 0 {
            return out;
        }
        // A negative discriminant's root is NaN, which no comparison below accepts.
        let sq = _mm_sqrt_ps(disc);
        let (near, far) = (_mm_sub_ps(h, sq), _mm_add_ps(h, sq));
        let (zero, limit) = (_mm_setzero_ps(), splat(t_max));
        let within = |t| _mm_and_ps(_mm_cmpgt_ps(t, zero), _mm_cmplt_ps(t, limit));
        let (near_ok, far_ok) = (within(near), within(far));
        let t = _mm_or_ps(_mm_and_ps(near_ok, near), _mm_andnot_ps(near_ok, far));
        out.hit = _mm_movemask_ps(_mm_or_ps(near_ok, far_ok)) as u32 & present;
        _mm_storeu_ps(out.t.as_mut_ptr(), t);
        out
    }
}

/// `spheres` (at most four) against `ray` within (0, `t_max`): `hit_sphere` per lane.
#[cfg(not(target_arch = "x86_64"))]
pub fn hits(spheres: &[Sphere], ray: &Ray, t_max: f32) -> LaneHits {
    hits_one_by_one(spheres, ray, t_max)
}

/// Up to four shapes one at a time, by their own test (`hit_sphere` for spheres, `hit_quad`
/// for quads): the reference the four-lane tests are checked against, and the test where
/// there is no SSE.
pub fn hits_one_by_one<S: SurfaceShape>(shapes: &[S], ray: &Ray, t_max: f32) -> LaneHits {
    let mut out = LaneHits {
        t: [0.0; 4],
        hit: 0,
    };
    for (lane, shape) in shapes.iter().enumerate() {
        if let Some(t) = shape.hit(ray, t_max) {
            out.t[lane] = t;
            out.hit |= 1 << lane;
        }
    }
    out
}

/// Checks a four-lane test against `shapes` one by one, to the bit, at every reach that matters
/// for `ray`: beyond every shape, at the nearest hit's own distance, just past it, and at
/// `scale`. Returns the hits found (for the caller's count of how many cases were exercised).
#[cfg(test)]
pub(crate) fn assert_lanes_as_one_by_one<S: SurfaceShape>(
    shapes: &[S],
    ray: &Ray,
    scale: f32,
    four_lanes: impl Fn(f32) -> LaneHits,
) -> u32 {
    let far = hits_one_by_one(shapes, ray, f32::INFINITY);
    let lanes_hit = |hit: u32| (0..shapes.len()).filter(move |&l| hit & (1 << l) != 0);
    let nearest = lanes_hit(far.hit)
        .map(|l| far.t[l])
        .fold(f32::INFINITY, f32::min);
    let mut found = 0;
    for t_max in [f32::INFINITY, nearest, nearest.next_up(), scale] {
        let (four, one) = (four_lanes(t_max), hits_one_by_one(shapes, ray, t_max));
        assert_eq!(four.hit, one.hit, "{shapes:?} {ray:?} t_max {t_max}");
        for lane in lanes_hit(one.hit) {
            assert_eq!(
                four.t[lane].to_bits(),
                one.t[lane].to_bits(),
                "{ray:?} lane {lane}"
            );
        }
        found += one.hit.count_ones();
    }
    found
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shared::rng::Rng;
    use glam::Vec3;

    /// Four lanes at once give each sphere `hit_sphere`'s answer to the bit: random rays from
    /// inside and outside against blocks of one to four random spheres (hollow ones, tiny and
    /// huge ones, far ones), grazing ones, with `t_max` beyond them, at a hit's own distance and
    /// just past it.
    #[test]
    fn four_lanes_hit_as_hit_sphere_does() {
        let mut found = 0;
        for i in 0..40_000u32 {
            let mut rng = Rng::for_sample(i, 0, 13);
            let mut point =
                || Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
            let count = 1 + i as usize % 4;
            let scale = [1.0, 1e-3, 1e4, 1.0][i as usize / 4 % 4];
            let spheres: Vec<Sphere> = (0..count)
                .map(|k| Sphere {
                    center: point() * scale * 2.0,
                    radius: scale * (0.1 + point().x.abs()) * if k == 1 { -1.0 } else { 1.0 },
                    material: 0,
                    light: 0,
                })
                .collect();
            let origin = point() * 3.0 * scale;
            let target = spheres[i as usize % count].center;
            let mut dir = (target - origin).normalize_or(Vec3::Z);
            if i % 5 == 0 {
                dir = point().normalize_or(Vec3::Y);
            }
            if i % 7 == 0 {
                // Aimed at the rim: a grazing ray.
                let s = &spheres[0];
                let side = (s.center - origin).cross(Vec3::Y).normalize_or(Vec3::X);
                dir = (s.center + side * s.radius.abs() - origin).normalize_or(Vec3::Z);
            }
            let ray = Ray { origin, dir };
            found += assert_lanes_as_one_by_one(&spheres, &ray, scale, |t_max| {
                hits(&spheres, &ray, t_max)
            });
        }
        assert!(found > 20_000, "only {found} hits");
    }
}
