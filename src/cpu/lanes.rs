//! `WIDTH` floats handled as one (`accel::wide::WIDTH`): eight in an AVX2 register where the build
//! targets a CPU with AVX2, else four in an SSE register, else four in an array with SSE's
//! semantics. A wide node's boxes and a triangle block's triangles are tested through it, so the
//! tests are written once for every width; each operation is the IEEE one of its scalar twin
//! (no fused multiply-add), and `min`/`max` are SSE's: `a < b ? a : b`, `a > b ? a : b`.

pub use crate::accel::wide::WIDTH;

#[cfg(all(target_arch = "x86_64", target_feature = "avx2"))]
mod imp {
    use super::WIDTH;
    use std::arch::x86_64::*;
    const _: () = assert!(WIDTH == 8);

    #[derive(Clone, Copy)]
    pub struct Lanes(__m256);
    #[derive(Clone, Copy)]
    pub struct Mask(__m256);

    // SAFETY (every block below): the build enables AVX2 (this module's cfg), and the loads and
    // stores read and write arrays of exactly `WIDTH` elements.
    impl Lanes {
        #[inline(always)]
        pub fn splat(x: f32) -> Self {
            Lanes(unsafe { _mm256_set1_ps(x) })
        }
        #[inline(always)]
        pub fn load(x: &[f32; WIDTH]) -> Self {
            Lanes(unsafe { _mm256_loadu_ps(x.as_ptr()) })
        }
        #[inline(always)]
        pub fn store(self, to: &mut [f32; WIDTH]) {
            unsafe { _mm256_storeu_ps(to.as_mut_ptr(), self.0) }
        }
        #[inline(always)]
        pub fn min(self, o: Self) -> Self {
            Lanes(unsafe { _mm256_min_ps(self.0, o.0) })
        }
        #[inline(always)]
        pub fn max(self, o: Self) -> Self {
            Lanes(unsafe { _mm256_max_ps(self.0, o.0) })
        }
        #[inline(always)]
        pub fn lt(self, o: Self) -> Mask {
            Mask(unsafe { _mm256_cmp_ps::<_CMP_LT_OQ>(self.0, o.0) })
        }
        #[inline(always)]
        pub fn gt(self, o: Self) -> Mask {
            Mask(unsafe { _mm256_cmp_ps::<_CMP_GT_OQ>(self.0, o.0) })
        }
        #[inline(always)]
        pub fn le(self, o: Self) -> Mask {
            Mask(unsafe { _mm256_cmp_ps::<_CMP_LE_OQ>(self.0, o.0) })
        }
        #[inline(always)]
        pub fn eq(self, o: Self) -> Mask {
            Mask(unsafe { _mm256_cmp_ps::<_CMP_EQ_OQ>(self.0, o.0) })
        }
    }

    impl Mask {
        /// One bit per lane, lane 0 the lowest.
        #[inline(always)]
        pub fn bits(self) -> u32 {
            unsafe { _mm256_movemask_ps(self.0) as u32 }
        }
    }

    /// The lanes of `x` equal to `value`, as bits.
    #[inline(always)]
    pub fn equal_bits(x: &[u32; WIDTH], value: u32) -> u32 {
        unsafe {
            let x = _mm256_loadu_si256(x.as_ptr() as *const __m256i);
            let equal = _mm256_cmpeq_epi32(x, _mm256_set1_epi32(value as i32));
            _mm256_movemask_ps(_mm256_castsi256_ps(equal)) as u32
        }
    }
    impl std::ops::Add for Lanes {
        type Output = Lanes;
        #[inline(always)]
        fn add(self, o: Lanes) -> Lanes {
            Lanes(unsafe { _mm256_add_ps(self.0, o.0) })
        }
    }

    impl std::ops::Sub for Lanes {
        type Output = Lanes;
        #[inline(always)]
        fn sub(self, o: Lanes) -> Lanes {
            Lanes(unsafe { _mm256_sub_ps(self.0, o.0) })
        }
    }

    impl std::ops::Mul for Lanes {
        type Output = Lanes;
        #[inline(always)]
        fn mul(self, o: Lanes) -> Lanes {
            Lanes(unsafe { _mm256_mul_ps(self.0, o.0) })
        }
    }

    impl std::ops::Div for Lanes {
        type Output = Lanes;
        #[inline(always)]
        fn div(self, o: Lanes) -> Lanes {
            Lanes(unsafe { _mm256_div_ps(self.0, o.0) })
        }
    }

    impl std::ops::BitOr for Mask {
        type Output = Mask;
        #[inline(always)]
        fn bitor(self, o: Mask) -> Mask {
            Mask(unsafe { _mm256_or_ps(self.0, o.0) })
        }
    }

    impl std::ops::BitAnd for Mask {
        type Output = Mask;
        #[inline(always)]
        fn bitand(self, o: Mask) -> Mask {
            Mask(unsafe { _mm256_and_ps(self.0, o.0) })
        }
    }
}

#[cfg(all(target_arch = "x86_64", not(target_feature = "avx2")))]
mod imp {
    use super::WIDTH;
    use std::arch::x86_64::*;
    const _: () = assert!(WIDTH == 4);

    #[derive(Clone, Copy)]
    pub struct Lanes(__m128);
    #[derive(Clone, Copy)]
    pub struct Mask(__m128);

    // SAFETY (every block below): SSE and SSE2 are part of x86-64's baseline, and the loads and
    // stores read and write arrays of exactly `WIDTH` elements.
    impl Lanes {
        #[inline(always)]
        pub fn splat(x: f32) -> Self {
            Lanes(unsafe { _mm_set1_ps(x) })
        }
        #[inline(always)]
        pub fn load(x: &[f32; WIDTH]) -> Self {
            Lanes(unsafe { _mm_loadu_ps(x.as_ptr()) })
        }
        #[inline(always)]
        pub fn store(self, to: &mut [f32; WIDTH]) {
            unsafe { _mm_storeu_ps(to.as_mut_ptr(), self.0) }
        }
        #[inline(always)]
        pub fn min(self, o: Self) -> Self {
            Lanes(unsafe { _mm_min_ps(self.0, o.0) })
        }
        #[inline(always)]
        pub fn max(self, o: Self) -> Self {
            Lanes(unsafe { _mm_max_ps(self.0, o.0) })
        }
        #[inline(always)]
        pub fn lt(self, o: Self) -> Mask {
            Mask(unsafe { _mm_cmplt_ps(self.0, o.0) })
        }
        #[inline(always)]
        pub fn gt(self, o: Self) -> Mask {
            Mask(unsafe { _mm_cmpgt_ps(self.0, o.0) })
        }
        #[inline(always)]
        pub fn le(self, o: Self) -> Mask {
            Mask(unsafe { _mm_cmple_ps(self.0, o.0) })
        }
        #[inline(always)]
        pub fn eq(self, o: Self) -> Mask {
            Mask(unsafe { _mm_cmpeq_ps(self.0, o.0) })
        }
    }

    impl Mask {
        /// One bit per lane, lane 0 the lowest.
        #[inline(always)]
        pub fn bits(self) -> u32 {
            unsafe { _mm_movemask_ps(self.0) as u32 }
        }
    }

    /// The lanes of `x` equal to `value`, as bits.
    #[inline(always)]
    pub fn equal_bits(x: &[u32; WIDTH], value: u32) -> u32 {
        unsafe {
            let x = _mm_loadu_si128(x.as_ptr() as *const __m128i);
            let equal = _mm_cmpeq_epi32(x, _mm_set1_epi32(value as i32));
            _mm_movemask_ps(_mm_castsi128_ps(equal)) as u32
        }
    }
    impl std::ops::Add for Lanes {
        type Output = Lanes;
        #[inline(always)]
        fn add(self, o: Lanes) -> Lanes {
            Lanes(unsafe { _mm_add_ps(self.0, o.0) })
        }
    }

    impl std::ops::Sub for Lanes {
        type Output = Lanes;
        #[inline(always)]
        fn sub(self, o: Lanes) -> Lanes {
            Lanes(unsafe { _mm_sub_ps(self.0, o.0) })
        }
    }

    impl std::ops::Mul for Lanes {
        type Output = Lanes;
        #[inline(always)]
        fn mul(self, o: Lanes) -> Lanes {
            Lanes(unsafe { _mm_mul_ps(self.0, o.0) })
        }
    }

    impl std::ops::Div for Lanes {
        type Output = Lanes;
        #[inline(always)]
        fn div(self, o: Lanes) -> Lanes {
            Lanes(unsafe { _mm_div_ps(self.0, o.0) })
        }
    }

    impl std::ops::BitOr for Mask {
        type Output = Mask;
        #[inline(always)]
        fn bitor(self, o: Mask) -> Mask {
            Mask(unsafe { _mm_or_ps(self.0, o.0) })
        }
    }

    impl std::ops::BitAnd for Mask {
        type Output = Mask;
        #[inline(always)]
        fn bitand(self, o: Mask) -> Mask {
            Mask(unsafe { _mm_and_ps(self.0, o.0) })
        }
    }
}

/// The lanes as an array, where there is no SSE (and in the tests, which check it everywhere).
#[cfg(any(not(target_arch = "x86_64"), test))]
mod scalar {
    use super::WIDTH;

    #[derive(Clone, Copy)]
    pub struct Lanes([f32; WIDTH]);
    #[derive(Clone, Copy)]
    pub struct Mask(u32);

    impl Lanes {
        #[inline(always)]
        fn map(self, o: Self, f: impl Fn(f32, f32) -> f32) -> Self {
            Lanes(std::array::from_fn(|i| f(self.0[i], o.0[i])))
        }
        #[inline(always)]
        fn test(self, o: Self, f: impl Fn(f32, f32) -> bool) -> Mask {
            Mask((0..WIDTH).fold(0, |m, i| m | (f(self.0[i], o.0[i]) as u32) << i))
        }
        pub fn splat(x: f32) -> Self {
            Lanes([x; WIDTH])
        }
        pub fn load(x: &[f32; WIDTH]) -> Self {
            Lanes(*x)
        }
        pub fn store(self, to: &mut [f32; WIDTH]) {
            *to = self.0;
        }
        pub fn min(self, o: Self) -> Self {
            self.map(o, |a, b| if a < b { a } else { b })
        }
        pub fn max(self, o: Self) -> Self {
            self.map(o, |a, b| if a > b { a } else { b })
        }
        pub fn lt(self, o: Self) -> Mask {
            self.test(o, |a, b| a < b)
        }
        pub fn gt(self, o: Self) -> Mask {
            self.test(o, |a, b| a > b)
        }
        pub fn le(self, o: Self) -> Mask {
            self.test(o, |a, b| a <= b)
        }
        pub fn eq(self, o: Self) -> Mask {
            self.test(o, |a, b| a == b)
        }
    }

    impl Mask {
        /// One bit per lane, lane 0 the lowest.
        pub fn bits(self) -> u32 {
            self.0
        }
    }

    /// The lanes of `x` equal to `value`, as bits.
    pub fn equal_bits(x: &[u32; WIDTH], value: u32) -> u32 {
        (0..WIDTH).fold(0, |m, i| m | ((x[i] == value) as u32) << i)
    }
    impl std::ops::Add for Lanes {
        type Output = Lanes;
        #[inline(always)]
        fn add(self, o: Lanes) -> Lanes {
            self.map(o, |a, b| a + b)
        }
    }

    impl std::ops::Sub for Lanes {
        type Output = Lanes;
        #[inline(always)]
        fn sub(self, o: Lanes) -> Lanes {
            self.map(o, |a, b| a - b)
        }
    }

    impl std::ops::Mul for Lanes {
        type Output = Lanes;
        #[inline(always)]
        fn mul(self, o: Lanes) -> Lanes {
            self.map(o, |a, b| a * b)
        }
    }

    impl std::ops::Div for Lanes {
        type Output = Lanes;
        #[inline(always)]
        fn div(self, o: Lanes) -> Lanes {
            self.map(o, |a, b| a / b)
        }
    }

    impl std::ops::BitOr for Mask {
        type Output = Mask;
        #[inline(always)]
        fn bitor(self, o: Mask) -> Mask {
            Mask(self.0 | o.0)
        }
    }

    impl std::ops::BitAnd for Mask {
        type Output = Mask;
        #[inline(always)]
        fn bitand(self, o: Mask) -> Mask {
            Mask(self.0 & o.0)
        }
    }
}

#[cfg(not(target_arch = "x86_64"))]
use scalar as imp;

pub use imp::{Lanes, Mask, equal_bits};

#[cfg(test)]
mod tests {
    /// Each lane is its scalar twin's IEEE operation, and `min`/`max`/comparisons treat NaN as
    /// SSE does (the box and triangle tests rely on both).
    macro_rules! lanes_do_what_their_scalars_do {
        ($name:ident, $imp:path) => {
            #[test]
            fn $name() {
                use super::WIDTH;
                use lanes::{Lanes, equal_bits};
                use $imp as lanes;
                // Lane 1 (and 5) holds -0 against +0: SSE's min and max give their second.
                let a: [f32; WIDTH] = std::array::from_fn(|i| match i % 4 {
                    1 => -0.0,
                    k => [1.5, 0.0, f32::NAN, 3.0][k] + i as f32,
                });
                let b: [f32; WIDTH] =
                    std::array::from_fn(|i| [0.1, 0.0, 2.0, f32::NAN][i % 4] * 3.0);
                let (x, y) = (Lanes::load(&a), Lanes::load(&b));
                let lanes = |l: Lanes| {
                    let mut out = [0.0; WIDTH];
                    l.store(&mut out);
                    out.map(f32::to_bits)
                };
                let each: &dyn Fn(fn(f32, f32) -> f32) -> [u32; WIDTH] =
                    &|f| std::array::from_fn(|i| f(a[i], b[i]).to_bits());
                // Arithmetic's NaNs compare as NaN: a NaN it makes (0 / 0) has the sign x86
                // gives it in SSE and another where the compiler folds the scalar.
                let nan = |bits: [u32; WIDTH]| {
                    bits.map(|b| {
                        if f32::from_bits(b).is_nan() {
                            u32::MAX
                        } else {
                            b
                        }
                    })
                };
                assert_eq!(nan(lanes(x + y)), nan(each(|p, q| p + q)));
                assert_eq!(nan(lanes(x - y)), nan(each(|p, q| p - q)));
                assert_eq!(nan(lanes(x * y)), nan(each(|p, q| p * q)));
                assert_eq!(nan(lanes(x / y)), nan(each(|p, q| p / q)));
                assert_eq!(lanes(x.min(y)), each(|p, q| if p < q { p } else { q }));
                assert_eq!(lanes(x.max(y)), each(|p, q| if p > q { p } else { q }));
                assert_eq!(lanes(Lanes::splat(2.5)), [2.5f32.to_bits(); WIDTH]);
                let bits: &dyn Fn(fn(f32, f32) -> bool) -> u32 =
                    &|f| (0..WIDTH).fold(0, |m, i| m | (f(a[i], b[i]) as u32) << i);
                assert_eq!(x.lt(y).bits(), bits(|p, q| p < q));
                assert_eq!(x.gt(y).bits(), bits(|p, q| p > q));
                assert_eq!(x.le(y).bits(), bits(|p, q| p <= q));
                assert_eq!(x.eq(y).bits(), bits(|p, q| p == q));
                assert_eq!((x.lt(y) | x.eq(y)).bits(), bits(|p, q| p <= q));
                assert_eq!((x.le(y) & x.gt(y)).bits(), 0);
                let ids: [u32; WIDTH] =
                    std::array::from_fn(|i| if i % 3 == 0 { u32::MAX } else { i as u32 });
                let expected = (0..WIDTH).fold(0, |m, i| m | ((i % 3 == 0) as u32) << i);
                assert_eq!(equal_bits(&ids, u32::MAX), expected);
            }
        };
    }

    lanes_do_what_their_scalars_do!(the_builds_lanes_do_what_their_scalars_do, super::imp);
    lanes_do_what_their_scalars_do!(the_array_lanes_do_what_their_scalars_do, super::scalar);
}
