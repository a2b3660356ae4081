//! Up to four quads tested against a ray together, for scenes whose shapes are tested in turn
//! (`intersect::closest_in_turn`): [`crate::shape::quad::hit_quad`]'s operations in its order,
//! lane by lane, so each lane's distance is bit for bit the one it gives its quad (Rust never
//! fuses a multiply and an add unasked; SSE's division is IEEE's, as f32's is).

use super::four_spheres::LaneHits;
use crate::shape::quad::{Quad, QuadBlock};
use crate::shared::ray::Ray;

/// `quads` (at most four), laid out side by side in `block`, against `ray` within (0, `t_max`).
#[inline]
#[cfg(target_arch = "x86_64")]
pub fn hits(_quads: &[Quad], block: &QuadBlock, ray: &Ray, t_max: f32) -> LaneHits {
    use std::arch::x86_64::*;
    // SAFETY: SSE is part of x86-64's baseline; every load reads four f32 of the block's
    // 16-byte aligned rows.
    unsafe {
        let row = |r: &[f32; 4]| _mm_load_ps(r.as_ptr());
        let splat = |v: f32| _mm_set1_ps(v);
        // glam's dot: (x x' + y y') + z z'.
        let dot = |a: [__m128; 3], b: [__m128; 3]| {
            let xy = _mm_add_ps(_mm_mul_ps(a[0], b[0]), _mm_mul_ps(a[1], b[1]));
            _mm_add_ps(xy, _mm_mul_ps(a[2], b[2]))
        };
        let normal = block.normal.each_ref().map(row);
        let dir = [splat(ray.dir.x), splat(ray.dir.y), splat(ray.dir.z)];
        let denom = dot(normal, dir);
        let magnitude = _mm_andnot_ps(splat(-0.0), denom);
        // A NaN denominator fails this as `denom.abs() < PARALLEL_DENOMINATOR` passes it; its t
        // is NaN then,
        // which fails the range test below as it does one lane at a time.
        let crossing = _mm_cmpnlt_ps(
            magnitude,
            splat(crate::shared::constants::PARALLEL_DENOMINATOR),
        );
        let to_corner = [
            _mm_sub_ps(row(&block.q[0]), splat(ray.origin.x)),
            _mm_sub_ps(row(&block.q[1]), splat(ray.origin.y)),
            _mm_sub_ps(row(&block.q[2]), splat(ray.origin.z)),
        ];
        let t = _mm_div_ps(dot(normal, to_corner), denom);
        let ahead = _mm_and_ps(
            _mm_cmpgt_ps(t, _mm_setzero_ps()),
            _mm_cmplt_ps(t, splat(t_max)),
        );
        let mut candidates = _mm_movemask_ps(_mm_and_ps(crossing, ahead)) as u32 & block.present;
        if candidates != 0 {
            let planar = [
                _mm_sub_ps(_mm_mul_ps(t, dir[0]), to_corner[0]),
                _mm_sub_ps(_mm_mul_ps(t, dir[1]), to_corner[1]),
                _mm_sub_ps(_mm_mul_ps(t, dir[2]), to_corner[2]),
            ];
            let alpha = dot(planar, block.alpha_axis.each_ref().map(row));
            let beta = dot(planar, block.beta_axis.each_ref().map(row));
            let (lo, hi) = (row(&block.lo), row(&block.hi));
            let inside = |a| _mm_and_ps(_mm_cmple_ps(lo, a), _mm_cmple_ps(a, hi));
            candidates &= _mm_movemask_ps(_mm_and_ps(inside(alpha), inside(beta))) as u32;
        }
        let mut out = LaneHits {
            t: [0.0; 4],
            hit: candidates,
        };
        _mm_storeu_ps(out.t.as_mut_ptr(), t);
        out
    }
}

/// `quads` (their `block`) against `ray` within (0, `t_max`): `hit_quad` per lane.
#[cfg(not(target_arch = "x86_64"))]
pub fn hits(quads: &[Quad], _block: &QuadBlock, ray: &Ray, t_max: f32) -> LaneHits {
    super::four_spheres::hits_one_by_one(quads, ray, t_max)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cpu::four_spheres::{assert_lanes_as_one_by_one, hits_one_by_one};
    use crate::shared::rng::Rng;
    use glam::Vec3;

    /// Four lanes at once give each quad `hit_quad`'s answer to the bit: random rays against
    /// blocks of one to four random parallelograms (tiny, huge and far ones, some seen edge
    /// on), rays aimed at their corners and edges (where the edge tolerance decides), with
    /// `t_max` beyond them, at a hit's own distance and just past it.
    #[test]
    fn four_lanes_hit_as_hit_quad_does() {
        let mut found = 0;
        for i in 0..40_000u32 {
            let mut rng = Rng::for_sample(i, 0, 17);
            let mut point =
                || Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
            let count = 1 + i as usize % 4;
            let scale = [1.0, 1e-3, 1e4, 1.0][i as usize / 4 % 4];
            let quads: Vec<Quad> = (0..count)
                .map(|k| {
                    let (u, mut v) = (point() * scale, point() * scale);
                    if k == 1 && i % 3 == 0 {
                        v = Vec3::new(-u.y, u.x, 0.3 * u.z); // nearly perpendicular
                    }
                    Quad::new(point() * scale * 2.0, u, v, 0)
                })
                .filter(|q| q.normal.is_finite())
                .collect();
            if quads.is_empty() {
                continue;
            }
            let count = quads.len();
            let origin = point() * 3.0 * scale;
            let aim = &quads[i as usize % count];
            let target = match i % 6 {
                0 => aim.q,                         // a corner
                1 => aim.q + aim.u,                 // another
                2 => aim.q + 0.5 * aim.u,           // an edge
                3 => aim.q + aim.v + 0.999 * aim.u, // near a corner, inside
                _ => aim.q + 0.3 * aim.u + 0.6 * aim.v,
            };
            let mut dir = (target - origin).normalize_or(Vec3::Z);
            if i % 5 == 0 {
                dir = point().normalize_or(Vec3::Y);
            }
            if i % 11 == 0 {
                // Along the quad's plane: edge on.
                dir = aim.u.normalize_or(Vec3::X);
            }
            let ray = Ray { origin, dir };
            let block = QuadBlock::new(&quads);
            found += assert_lanes_as_one_by_one(&quads, &ray, scale, |t_max| {
                hits(&quads, &block, &ray, t_max)
            });
        }
        assert!(found > 20_000, "only {found} hits");
    }

    /// A hit exactly on the edge tolerance's bounds counts, in every lane as one by one (the
    /// unit square in z = 0: a ray straight down meets it at a = its origin's x, exactly).
    #[test]
    fn hits_on_the_tolerance_bounds_count() {
        let square = Quad::new(Vec3::ZERO, Vec3::X, Vec3::Y, 0);
        let tolerance = square.edge_tolerance;
        for x in [
            -tolerance,
            1.0 + tolerance,
            (-tolerance).next_down(),
            (1.0 + tolerance).next_up(),
        ] {
            let ray = Ray {
                origin: Vec3::new(x, 0.5, 1.0),
                dir: Vec3::NEG_Z,
            };
            let quads = [square; 4];
            let (four, one) = (
                hits(&quads, &QuadBlock::new(&quads), &ray, f32::INFINITY),
                hits_one_by_one(&quads, &ray, f32::INFINITY),
            );
            let expected = if (-tolerance..=1.0 + tolerance).contains(&x) {
                0b1111
            } else {
                0
            };
            assert_eq!((four.hit, one.hit), (expected, expected), "x = {x}");
        }
    }
}
