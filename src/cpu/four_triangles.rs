//! A leaf's triangles tested against a ray together (`wide_bvh::TriangleBlock`): the watertight
//! test of [`super::shapes::hit_triangle`], its ray-dependent part (which axis becomes z, the
//! shear) computed once per ray, and the rest lane by lane in the same operations in the same
//! order, so that each lane's distance and weights are bit for bit the ones `hit_triangle` gives
//! its triangle (no fused multiply-add: the x86-64 baseline has none).

use crate::shared::ray::Ray;
use crate::wide_bvh::{EMPTY, TriangleBlock};
use glam::Vec3;

/// A ray in the frame of the watertight test: the ray, the axes that become x, y and z (z the
/// dominant one) and the shear (`-d.x / d.z`, `-d.y / d.z`, `1 / d.z` in that frame).
pub struct ShearedRay {
    ray: Ray,
    axes: [usize; 3],
    shear: [f32; 3],
}

/// Where the lanes of a block are hit: distance, and the weights of each triangle's second and
/// third corners, valid in the lanes set in `hit`.
pub struct BlockHits {
    pub t: [f32; 4],
    pub b1: [f32; 4],
    pub b2: [f32; 4],
    pub hit: u32,
}

impl ShearedRay {
    #[inline]
    pub fn new(ray: &Ray) -> Self {
        let a = ray.dir.abs();
        let kz = if a.x > a.y && a.x > a.z {
            0
        } else if a.y > a.z {
            1
        } else {
            2
        };
        let axes = [(kz + 1) % 3, (kz + 2) % 3, kz];
        let d = axes.map(|k| ray.dir[k]);
        ShearedRay {
            ray: *ray,
            axes,
            shear: [-d[0] / d[2], -d[1] / d[2], 1.0 / d[2]],
        }
    }

    /// The block's triangles hit within (0, `t_max`).
    #[inline]
    #[cfg(target_arch = "x86_64")]
    pub fn hits(&self, block: &TriangleBlock, t_max: f32) -> BlockHits {
        use std::arch::x86_64::*;
        // SAFETY: SSE and SSE2 are part of x86-64's baseline, and the loads read the block's
        // own 16-byte-aligned arrays.
        unsafe {
            let [kx, ky, kz] = self.axes;
            let splat = |k: usize| _mm_set1_ps(self.ray.origin[k]);
            let (ox, oy, oz) = (splat(kx), splat(ky), splat(kz));
            let (sx, sy, sz) = (
                _mm_set1_ps(self.shear[0]),
                _mm_set1_ps(self.shear[1]),
                _mm_set1_ps(self.shear[2]),
            );
            // Each corner relative to the origin, permuted and sheared: (x, y) and the unsheared z.
            let corner = |c: usize| {
                let q = &block.corners[c];
                let qx = _mm_sub_ps(_mm_load_ps(q[kx].as_ptr()), ox);
                let qy = _mm_sub_ps(_mm_load_ps(q[ky].as_ptr()), oy);
                let qz = _mm_sub_ps(_mm_load_ps(q[kz].as_ptr()), oz);
                let x = _mm_add_ps(qx, _mm_mul_ps(sx, qz));
                let y = _mm_add_ps(qy, _mm_mul_ps(sy, qz));
                (x, y, qz)
            };
            let (p0, p1, p2) = (corner(0), corner(1), corner(2));
            let edge = |a: (__m128, __m128, __m128), b: (__m128, __m128, __m128)| {
                _mm_sub_ps(_mm_mul_ps(a.0, b.1), _mm_mul_ps(a.1, b.0))
            };
            let (e0, e1, e2) = (edge(p1, p2), edge(p2, p0), edge(p0, p1));
            let zero = _mm_setzero_ps();
            let any = |f: unsafe fn(__m128, __m128) -> __m128| {
                _mm_or_ps(_mm_or_ps(f(e0, zero), f(e1, zero)), f(e2, zero))
            };
            let mixed = _mm_and_ps(any(_mm_cmplt_ps), any(_mm_cmpgt_ps));
            let det = _mm_add_ps(_mm_add_ps(e0, e1), e2);
            let term = |e: __m128, qz: __m128| _mm_mul_ps(e, _mm_mul_ps(sz, qz));
            let scaled = _mm_add_ps(_mm_add_ps(term(e0, p0.2), term(e1, p1.2)), term(e2, p2.2));
            let t = _mm_div_ps(scaled, det);
            let within = _mm_and_ps(_mm_cmpgt_ps(t, zero), _mm_cmplt_ps(t, _mm_set1_ps(t_max)));
            let empty = _mm_castsi128_ps(_mm_cmpeq_epi32(
                _mm_load_si128(block.triangles.as_ptr() as *const __m128i),
                _mm_set1_epi32(EMPTY as i32),
            ));
            let rejected = _mm_or_ps(_mm_or_ps(mixed, _mm_cmpeq_ps(det, zero)), empty);
            let hit = _mm_movemask_ps(_mm_andnot_ps(rejected, within)) as u32;
            let mut out = BlockHits {
                t: [0.0; 4],
                b1: [0.0; 4],
                b2: [0.0; 4],
                hit,
            };
            if hit != 0 {
                _mm_storeu_ps(out.t.as_mut_ptr(), t);
                _mm_storeu_ps(out.b1.as_mut_ptr(), _mm_div_ps(e1, det));
                _mm_storeu_ps(out.b2.as_mut_ptr(), _mm_div_ps(e2, det));
            }
            out
        }
    }

    /// The block's triangles hit within (0, `t_max`): [`super::shapes::hit_triangle`] per lane.
    #[cfg(not(target_arch = "x86_64"))]
    pub fn hits(&self, block: &TriangleBlock, t_max: f32) -> BlockHits {
        self.hits_lane_by_lane(block, t_max)
    }

    /// [`ShearedRay::hits`] one lane at a time, by `hit_triangle` itself: the reference the
    /// four-lane test is checked against, and the test where there is no SSE.
    pub fn hits_lane_by_lane(&self, block: &TriangleBlock, t_max: f32) -> BlockHits {
        let mut out = BlockHits {
            t: [0.0; 4],
            b1: [0.0; 4],
            b2: [0.0; 4],
            hit: 0,
        };
        for lane in (0..4).filter(|&lane| block.triangles[lane] != EMPTY) {
            let corner = |c: usize| {
                let q = &block.corners[c];
                Vec3::new(q[0][lane], q[1][lane], q[2][lane])
            };
            let triangle = crate::scene::flat::Triangle {
                p0: corner(0),
                p1: corner(1),
                p2: corner(2),
                material: 0,
                light: 0,
            };
            if let Some((t, b1, b2)) = super::shapes::hit_triangle(&triangle, &self.ray, 0.0, t_max)
            {
                out.t[lane] = t;
                out.b1[lane] = b1;
                out.b2[lane] = b2;
                out.hit |= 1 << lane;
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shared::rng::Rng;

    /// Four lanes at once give each triangle `hit_triangle`'s answer to the bit: over random
    /// rays against blocks of random triangles, of triangles sharing an edge the ray crosses or
    /// runs along, of degenerate ones (a point, a line) and of triangles far off, with `t_max`
    /// beyond them, at a hit's own distance and just past it.
    #[test]
    fn four_lanes_hit_as_hit_triangle_does() {
        let mut hits = 0;
        for i in 0..40_000u32 {
            let mut rng = Rng::for_sample(i, 0, 11);
            let mut point =
                || Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
            let (a, b, c, d) = (point(), point(), point(), point());
            let scale = [1.0, 1e-3, 1e4][i as usize % 3];
            let triangles = [
                [a, b, c],
                [b, a, d], // shares the edge a-b, wound the other way
                [a, a, a], // a point
                [a * scale, b * scale + Vec3::splat(scale), c * scale],
            ];
            let mut block = TriangleBlock {
                corners: [[[0.0; 4]; 3]; 3],
                triangles: [0, 1, 2, 3],
            };
            if i % 5 == 0 {
                block.triangles[2] = EMPTY;
            }
            for (lane, corners) in triangles.iter().enumerate() {
                for (corner, p) in corners.iter().enumerate() {
                    for axis in 0..3 {
                        block.corners[corner][axis][lane] = p[axis];
                    }
                }
            }
            // From outside, aimed at a point of the shared edge, or along it.
            let origin = point() * 4.0;
            let target = match i % 4 {
                0 => a + (b - a) * 0.5,
                1 => (a + b + c) / 3.0,
                _ => point(),
            };
            let dir = if i % 7 == 0 { b - a } else { target - origin };
            let ray = Ray {
                origin,
                dir: dir.normalize_or(Vec3::Z),
            };
            let sheared = ShearedRay::new(&ray);
            let far = sheared.hits_lane_by_lane(&block, f32::INFINITY);
            let nearest = (0..4)
                .filter(|&l| far.hit & (1 << l) != 0)
                .map(|l| far.t[l])
                .fold(f32::INFINITY, f32::min);
            for t_max in [f32::INFINITY, nearest, nearest.next_up(), 1.0] {
                let (four, one) = (
                    sheared.hits(&block, t_max),
                    sheared.hits_lane_by_lane(&block, t_max),
                );
                assert_eq!(four.hit, one.hit, "{ray:?} t_max {t_max}");
                for lane in (0..4).filter(|&l| one.hit & (1 << l) != 0) {
                    let bits =
                        |h: &BlockHits| [h.t[lane], h.b1[lane], h.b2[lane]].map(f32::to_bits);
                    assert_eq!(bits(&four), bits(&one), "{ray:?} lane {lane}");
                }
                hits += one.hit.count_ones();
            }
        }
        assert!(hits > 10_000, "only {hits} hits");
    }
}
