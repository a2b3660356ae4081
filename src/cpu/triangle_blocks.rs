//! A block's triangles tested against a ray together (`accel::wide::TriangleBlock`, `WIDTH` lanes
//! of `cpu/lanes.rs`): the watertight test of [`super::intersect::hit_triangle`], its
//! ray-dependent part (which axis becomes z, the shear) computed once per ray, and the rest lane
//! by lane in the same operations in the same order, so that each lane's distance and weights
//! are bit for bit the ones `hit_triangle` gives its triangle (no fused multiply-add).

use super::lanes::{Lanes, equal_bits};
use crate::accel::wide::{EMPTY, TriangleBlock, WIDTH};
use crate::shared::ray::Ray;

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
    pub t: [f32; WIDTH],
    pub b1: [f32; WIDTH],
    pub b2: [f32; WIDTH],
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
    pub fn hits(&self, block: &TriangleBlock, t_max: f32) -> BlockHits {
        let [kx, ky, kz] = self.axes;
        let splat = |k: usize| Lanes::splat(self.ray.origin[k]);
        let (ox, oy, oz) = (splat(kx), splat(ky), splat(kz));
        let [sx, sy, sz] = self.shear.map(Lanes::splat);
        // Each corner relative to the origin, permuted and sheared: (x, y) and the unsheared z.
        let corner = |c: usize| {
            let q = &block.corners[c];
            let qx = Lanes::load(&q[kx]) - ox;
            let qy = Lanes::load(&q[ky]) - oy;
            let qz = Lanes::load(&q[kz]) - oz;
            (qx + sx * qz, qy + sy * qz, qz)
        };
        let (p0, p1, p2) = (corner(0), corner(1), corner(2));
        let edge = |a: (Lanes, Lanes, Lanes), b: (Lanes, Lanes, Lanes)| a.0 * b.1 - a.1 * b.0;
        let (e0, e1, e2) = (edge(p1, p2), edge(p2, p0), edge(p0, p1));
        let zero = Lanes::splat(0.0);
        let negative = e0.lt(zero) | e1.lt(zero) | e2.lt(zero);
        let positive = e0.gt(zero) | e1.gt(zero) | e2.gt(zero);
        let det = e0 + e1 + e2;
        let term = |e: Lanes, qz: Lanes| e * (sz * qz);
        let t = (term(e0, p0.2) + term(e1, p1.2) + term(e2, p2.2)) / det;
        let within = (t.gt(zero) & t.lt(Lanes::splat(t_max))).bits();
        let rejected = (negative & positive | det.eq(zero)).bits();
        let hit = within & !rejected & !equal_bits(&block.triangles, EMPTY);
        let mut out = BlockHits {
            t: [0.0; WIDTH],
            b1: [0.0; WIDTH],
            b2: [0.0; WIDTH],
            hit,
        };
        if hit != 0 {
            t.store(&mut out.t);
            (e1 / det).store(&mut out.b1);
            (e2 / det).store(&mut out.b2);
        }
        out
    }

    /// [`ShearedRay::hits`] one lane at a time, by `hit_triangle` itself: the reference the
    /// test of all lanes is checked against (every build tests its lanes, so nothing else
    /// calls it).
    #[cfg(test)]
    fn hits_lane_by_lane(&self, block: &TriangleBlock, t_max: f32) -> BlockHits {
        let mut out = BlockHits {
            t: [0.0; WIDTH],
            b1: [0.0; WIDTH],
            b2: [0.0; WIDTH],
            hit: 0,
        };
        for lane in (0..WIDTH).filter(|&lane| block.triangles[lane] != EMPTY) {
            let corner = |c: usize| {
                let q = &block.corners[c];
                glam::Vec3::new(q[0][lane], q[1][lane], q[2][lane])
            };
            let triangle = crate::scene::flat::Triangle {
                p0: corner(0),
                p1: corner(1),
                p2: corner(2),
                material: 0,
                light: 0,
            };
            if let Some((t, b1, b2)) =
                super::intersect::hit_triangle(&triangle, &self.ray, 0.0, t_max)
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
    use glam::Vec3;

    /// All lanes at once give each triangle `hit_triangle`'s answer to the bit: over random
    /// rays against blocks of random triangles, of triangles sharing an edge the ray crosses or
    /// runs along, of degenerate ones (a point, a line) and of triangles far off, with `t_max`
    /// beyond them, at a hit's own distance and just past it.
    #[test]
    fn all_lanes_hit_as_hit_triangle_does() {
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
                // Lanes 4 to 7, where blocks are eight wide.
                [c, d, a],
                [d, c, b], // shares the edge c-d with the one before
                [a, c, c], // a line
                [b * scale, c * scale, d * scale],
            ];
            let mut block = TriangleBlock {
                corners: [[[0.0; WIDTH]; 3]; 3],
                triangles: std::array::from_fn(|lane| lane as u32),
            };
            if i % 5 == 0 {
                block.triangles[2] = EMPTY;
            }
            for (lane, corners) in triangles.iter().take(WIDTH).enumerate() {
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
            let nearest = (0..WIDTH)
                .filter(|&l| far.hit & (1 << l) != 0)
                .map(|l| far.t[l])
                .fold(f32::INFINITY, f32::min);
            for t_max in [f32::INFINITY, nearest, nearest.next_up(), 1.0] {
                let (all, one) = (
                    sheared.hits(&block, t_max),
                    sheared.hits_lane_by_lane(&block, t_max),
                );
                assert_eq!(all.hit, one.hit, "{ray:?} t_max {t_max}");
                for lane in (0..WIDTH).filter(|&l| one.hit & (1 << l) != 0) {
                    let bits =
                        |h: &BlockHits| [h.t[lane], h.b1[lane], h.b2[lane]].map(f32::to_bits);
                    assert_eq!(bits(&all), bits(&one), "{ray:?} lane {lane}");
                }
                hits += one.hit.count_ones();
            }
        }
        assert!(hits > 10_000, "only {hits} hits");
    }
}
