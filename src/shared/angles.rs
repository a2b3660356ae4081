//! Angles of directions (twin: `shaders/angles.wgsl`): atan2 and acos as short polynomials,
//! within 5e-7 rad of the exact angle (two f32 steps at pi; tested against f64), because every
//! escaped ray and textured sphere hit needs them and libm's f32 atan2 is slow on the CPU (the
//! profile is in docs/benchmarks.md); both backends evaluate the same polynomials, in the same
//! order. `sin_cos_pi` is the CPU's alone: the kernel keeps WGSL's `sin` and `cos`, instructions
//! of their own on GPUs.

use std::f32::consts::{FRAC_PI_2, PI};

/// p(x) for coefficients `c`, highest power first (Horner).
#[inline]
fn horner(x: f32, c: &[f32]) -> f32 {
    // From the first coefficient, not 0 * x + it: the same value for every finite x.
    c[1..].iter().fold(c[0], |p, &c| p * x + c)
}

/// atan(a) for a in [0, 1]: a + a^3 p(a^2), p minimax (coefficients of SLEEF's `atanf`).
#[inline]
fn atan_unit(a: f32) -> f32 {
    const P: [f32; 8] = [
        0.002_823_639,
        -0.015_956_903,
        0.042_504_99,
        -0.074_890_09,
        0.106_347_93,
        -0.142_027_36,
        0.199_926_96,
        -0.333_331,
    ];
    let t = a * a;
    a + a * (t * horner(t, &P))
}

/// The angle of (x, y) from +x, in [-pi, pi]. Off the origin, y's sign bit picks the side as
/// libm's does: (-1, -0) is at -pi, (-1, 0) at pi; at the origin, 0 (libm: +-0 or +-pi by the
/// signs of zeros, which unit directions never are both).
#[inline]
pub fn atan2(y: f32, x: f32) -> f32 {
    let (ax, ay) = (x.abs(), y.abs());
    let (low, high) = (ax.min(ay), ax.max(ay));
    let a = if high > 0.0 { low / high } else { 0.0 };
    let mut r = atan_unit(a);
    if ay > ax {
        r = FRAC_PI_2 - r;
    }
    if x < 0.0 {
        r = PI - r;
    }
    if y.is_sign_negative() { -r } else { r }
}

/// acos(x) for x in [-1, 1] (clamped): sqrt(1 - |x|) q(|x|) (Abramowitz and Stegun 4.4.46).
#[inline]
pub fn acos(x: f32) -> f32 {
    const Q: [f32; 8] = [
        -0.001_262_491_1,
        0.006_670_09,
        -0.017_088_126,
        0.030_891_88,
        -0.050_174_303,
        0.088_978_99,
        -0.214_598_8,
        FRAC_PI_2,
    ];
    let a = x.abs().min(1.0);
    let q = horner(a, &Q);
    let r = (1.0 - a).sqrt() * q;
    if x < 0.0 { PI - r } else { r }
}

/// (sin(pi x), cos(pi x)) for x in [-1, 1], within 1.2e-7 of the exact values, branch-free:
/// libm's `sinf`/`cosf` reduce any argument, a cost the profile showed (docs/benchmarks.md),
/// where every sampled angle is pi times a number in [-1, 1]. x is split into quarter turns k = round(2x)
/// and y = x - k/2 in [-1/4, 1/4], exactly (Sterbenz), and pi y's Taylor polynomials (degree 9
/// and 10: terms beyond are below 2e-9 there) are turned by k quarter turns.
#[inline]
pub fn sin_cos_pi(x: f32) -> (f32, f32) {
    // pi^9 / 9!, -pi^7 / 7!, ..., pi; then pi^10 / 10!, ..., 1, with their signs.
    const SIN: [f32; 5] = [0.082145885, -0.5992645, 2.550164, -5.1677127, PI];
    const COS: [f32; 6] = [
        -0.02580689,
        0.23533063,
        -1.3352628,
        4.058712,
        -4.934802,
        1.0,
    ];
    // k = round(2x) from the exact 4x's integer part q: (q + 1) / 2 above 0, (q - 1) / 2
    // below, in integers (no SSE4.1 `round` needed for a portable build; 2x + 1/2 in f32 can
    // round up to the next integer just below a quarter).
    let q = (4.0 * x) as i32;
    let k = (q + if x < 0.0 { -1 } else { 1 }) / 2;
    let y = x - 0.5 * k as f32;
    let t = y * y;
    let (s, c) = (y * horner(t, &SIN), horner(t, &COS));
    // Quarter turns: odd k swaps sin and cos; k = 2, 3 mod 4 negates sin, k = 1, 2 cos.
    let (sin, cos) = if k & 1 == 0 { (s, c) } else { (c, s) };
    let negated = |v: f32, turn: i32| f32::from_bits(v.to_bits() ^ (((turn & 2) as u32) << 30));
    (negated(sin, k), negated(cos, k + 1))
}

#[cfg(test)]
mod tests {
    use super::*;
    const PI_F64: f64 = std::f64::consts::PI;

    /// Within 1.2e-7 (one f32 step at 1, two just below) of f64's sin(pi x) and cos(pi x) over
    /// a dense sweep of [-1, 1], the quarter turns and the ends exact.
    #[test]
    fn sin_cos_pi_is_within_1_2e7_of_the_exact_values() {
        let mut worst = 0.0f64;
        let n = 1 << 21;
        for i in 0..=n {
            let x = (-1.0 + 2.0 * i as f64 / n as f64) as f32;
            for x in [
                x,
                f32::from_bits(x.to_bits() + 1),
                f32::from_bits(x.to_bits().max(1) - 1),
            ] {
                if !(-1.0..=1.0).contains(&x) {
                    continue;
                }
                let (sin, cos) = sin_cos_pi(x);
                let exact = (PI_F64 * x as f64).sin_cos();
                worst = worst
                    .max((sin as f64 - exact.0).abs())
                    .max((cos as f64 - exact.1).abs());
            }
        }
        assert!(worst < 1.2e-7, "worst error {worst:e}");
        for (x, sin, cos) in [
            (0.0f32, 0.0f32, 1.0),
            (0.5, 1.0, 0.0),
            (-0.5, -1.0, 0.0),
            (1.0, 0.0, -1.0),
        ] {
            let (s, c) = sin_cos_pi(x);
            assert_eq!((s.abs(), c), (sin.abs(), cos), "at {x}");
        }
        assert_eq!(sin_cos_pi(-1.0).1, -1.0);
        // A turn's sign wrong in one quadrant shows.
        let (s, _) = sin_cos_pi(0.8);
        assert!((s as f64 - (PI_F64 * 0.8f32 as f64).sin()).abs() < 1.2e-7 && s > 0.0);
    }

    /// Both within 5e-7 rad (two f32 steps at pi) of f64's angle over a dense sweep of the circle and of [-1, 1],
    /// the axes, the origin and the ends included.
    #[test]
    fn polynomials_are_within_5e7_of_the_exact_angles() {
        let mut worst = (0.0f64, 0.0f64);
        for i in 0..=200_000 {
            let angle = -std::f64::consts::PI + std::f64::consts::TAU * i as f64 / 200_000.0;
            for r in [1e-30, 1e-3, 1.0, 7.5e4] {
                let (y, x) = ((r * angle.sin()) as f32, (r * angle.cos()) as f32);
                let exact = (y as f64).atan2(x as f64);
                let error = (atan2(y, x) as f64 - exact).abs();
                // The ends of the circle: -pi and pi are the same angle.
                let error = error.min((error - std::f64::consts::TAU).abs());
                worst.0 = worst.0.max(error);
            }
            let x = (-1.0 + 2.0 * i as f64 / 200_000.0) as f32;
            worst.1 = worst.1.max((acos(x) as f64 - (x as f64).acos()).abs());
        }
        assert!(worst.0 < 5e-7 && worst.1 < 5e-7, "worst errors {worst:?}");
        assert_eq!(atan2(0.0, 0.0), 0.0);
        assert_eq!((atan2(-0.0, -1.0), atan2(0.0, -1.0)), (-PI, PI));
        assert_eq!(acos(1.0), 0.0);
        assert!((acos(-1.0) - PI).abs() < 1e-7);
        // A small drift in one coefficient shows.
        let drifted = |a: f32| atan_unit(a) * (1.0 + 1e-5);
        assert!((drifted(0.9) as f64 - 0.9f64.atan()).abs() > 5e-7);
    }
}
