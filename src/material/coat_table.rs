//! A rough coat's crossings, tabulated (read in the kernel by `coat_table_opacity` in
//! `shaders/coat.wgsl`): the coat is rt-gpu's rough dielectric, and light crossing it loses what
//! that boundary's single-scattering lobes lose. Tabulated are 1 - T(mu), T the directional
//! albedo of its transmission lobe met from outside, at [`COAT_TABLE_SIZE`] cosines (the coat's
//! opacity, light reflected or lost: plastic's closed form takes it where a smooth coat takes
//! Fresnel's F), and K, the cosine-weighted mean albedo of its reflection lobe met from inside.
//! This is Mitsuba 3's `roughplastic` (its tables of 64 cosines, linear between them), with
//! rt-gpu's height-correlated masking, and K integrated over the cosine where Mitsuba takes the
//! plain mean of its 64 samples (about 1.5% lower at roughness 0.3). Each albedo is an
//! expectation over visible normals of its lobe's weight ((1 - F) G2 / G1(wo) refracted,
//! F G2 / G1(wo) reflected), in f64 by Gauss-Legendre quadrature over the two numbers that
//! sample them.

use super::coat::coat_fresnel;
use super::fresnel::refract_cos;
use super::microfacet::Ggx;
use crate::scene::image::Image;
use glam::Vec3;
use std::sync::Mutex;

/// The table's cosines: i / (COAT_TABLE_SIZE - 1) for i in 0..COAT_TABLE_SIZE (Mitsuba's 64).
pub const COAT_TABLE_SIZE: usize = 64;

/// What a coat without a table passes the kernel's coat functions (`u32::MAX`: no image starts
/// there).
pub const NO_COAT_TABLE: u32 = u32::MAX;

/// Quadrature nodes per axis of the visible normals' two numbers, more from inside, where total
/// internal reflection puts a kink in the integrand, and over each side of the critical cosine in
/// K's outer integral: doubling each moves K and T by at most 1e-4 (docs/benchmarks.md).
const OUTSIDE_NODES: usize = 32;
const INSIDE_NODES: usize = 64;
const COSINE_NODES: usize = 32;

#[derive(Debug, PartialEq)]
pub struct CoatTable {
    /// 1 - T at the table's cosines, in every channel of a [`COAT_TABLE_SIZE`] x 1 image: the
    /// GPU's images array holds it.
    pub image: Image,
    /// K: 2 int_0^1 R_inside(mu) mu dmu, the coat's reflectance of diffuse light from the base.
    pub internal_reflectance: f32,
}

impl CoatTable {
    /// The table of a coat of index `ior` (> 0) and GGX `alpha` (>= `MIN_ALPHA`), computed once
    /// per pair and kept for the process (as images are).
    pub fn of(ior: f32, alpha: f32) -> &'static CoatTable {
        static TABLES: Mutex<Vec<((u32, u32), &'static CoatTable)>> = Mutex::new(Vec::new());
        let key = (ior.to_bits(), alpha.to_bits());
        let mut tables = TABLES
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner());
        if let Some((_, table)) = tables.iter().find(|(k, _)| *k == key) {
            return table;
        }
        let table: &'static CoatTable = Box::leak(Box::new(CoatTable::new(ior, alpha)));
        tables.push((key, table));
        table
    }

    fn new(ior: f32, alpha: f32) -> Self {
        let ggx = Ggx { alpha };
        let last = (COAT_TABLE_SIZE - 1) as f32;
        let texels: Vec<f32> = (0..COAT_TABLE_SIZE)
            .flat_map(|i| {
                // At mu = 0 the lobe's weight is 0 / 0; Mitsuba's 1e-6 is as good as grazing.
                let mu = (i as f32 / last).max(1e-6);
                let transmitted = lobe_albedo(
                    ggx,
                    ior,
                    mu,
                    BoundaryLobe::Transmission,
                    Masking::HeightCorrelated,
                    OUTSIDE_NODES,
                );
                // Within [0, 1] whatever the rounding of a sum of weights near 1.
                let opacity = if transmitted.is_finite() {
                    (1.0 - transmitted).clamp(0.0, 1.0) as f32
                } else {
                    1.0
                };
                [opacity; 3]
            })
            .collect();
        let internal_reflectance = internal_reflectance(ggx, ior) as f32;
        let source = format!("coat table (ior {ior}, alpha {alpha})");
        CoatTable {
            image: Image::from_linear(&source, COAT_TABLE_SIZE as u32, 1, texels)
                .expect("opacities are finite and in [0, 1]"),
            internal_reflectance,
        }
    }

    /// The coat's opacity 1 - T at incidence cosine `cos`, linear between the table's cosines.
    #[inline]
    pub fn opacity(&self, cos: f32) -> f32 {
        let x = cos.clamp(0.0, 1.0) * (COAT_TABLE_SIZE - 1) as f32;
        let i = (x as usize).min(COAT_TABLE_SIZE - 2);
        let w = x - i as f32;
        let texels = &self.image.texels;
        (1.0 - w) * texels[3 * i] + w * texels[3 * i + 3]
    }
}

/// One of a dielectric boundary's two lobes.
#[derive(Clone, Copy, PartialEq)]
pub enum BoundaryLobe {
    Reflection,
    Transmission,
}

/// Smith's masking-shadowing of a lobe's pair of directions: rt-gpu's height-correlated G2, or
/// the separable G1 G1 of Mitsuba 3's microfacets (with which the tables are Mitsuba's, as a test
/// shows).
#[derive(Clone, Copy, PartialEq)]
pub enum Masking {
    HeightCorrelated,
    Separable,
}

/// The directional albedo of `lobe` of a GGX dielectric boundary for light leaving at cosine
/// `mu`, on the side where `coat_fresnel(_, ior)` is its Fresnel reflectance (`ior`: the other
/// side's index over this side's): the expectation over visible normals of the lobe's weight,
/// F G2 / G1(wo) reflected and (1 - F) G2 / G1(wo) refracted, by `nodes` x `nodes`
/// Gauss-Legendre.
pub fn lobe_albedo(
    ggx: Ggx,
    ior: f32,
    mu: f32,
    lobe: BoundaryLobe,
    masking: Masking,
    nodes: usize,
) -> f64 {
    let wo = Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    let rule = gauss_legendre(nodes);
    let mut sum = 0.0;
    for &(u1, w1) in &rule {
        for &(u2, w2) in &rule {
            let m = ggx.sample_visible(wo, u1 as f32, u2 as f32);
            let cos_m = wo.dot(m);
            let f = coat_fresnel(cos_m, ior);
            let (wi, share) = match lobe {
                BoundaryLobe::Reflection => (2.0 * cos_m * m - wo, f),
                BoundaryLobe::Transmission => {
                    let eta = 1.0 / ior;
                    let Some(cos_t) = refract_cos(cos_m.clamp(0.0, 1.0), eta) else {
                        continue;
                    };
                    ((eta * cos_m - cos_t) * m - eta * wo, 1.0 - f)
                }
            };
            let on_side = match lobe {
                BoundaryLobe::Reflection => wi.z > 0.0,
                BoundaryLobe::Transmission => wi.z < 0.0,
            };
            if on_side {
                let visible = match masking {
                    Masking::HeightCorrelated => ggx.g2(wo, wi) / ggx.g1(wo),
                    Masking::Separable => ggx.g1(wi),
                };
                sum += w1 * w2 * (share * visible) as f64;
            }
        }
    }
    sum
}

/// K of a coat of index `ior`: 2 int_0^1 R_inside(mu) mu dmu, by Gauss-Legendre on each side of
/// the critical cosine, where total internal reflection puts a kink in R.
fn internal_reflectance(ggx: Ggx, ior: f32) -> f64 {
    let critical = (1.0 - 1.0 / (ior as f64 * ior as f64)).max(0.0).sqrt();
    let mut sum = 0.0;
    // Without total internal reflection (ior <= 1) the first side is empty.
    for (start, end) in [(0.0, critical), (critical, 1.0)]
        .into_iter()
        .filter(|(a, b)| a < b)
    {
        for (x, w) in gauss_legendre(COSINE_NODES) {
            let mu = start + x * (end - start);
            let r = lobe_albedo(
                ggx,
                1.0 / ior,
                mu as f32,
                BoundaryLobe::Reflection,
                Masking::HeightCorrelated,
                INSIDE_NODES,
            );
            sum += w * (end - start) * 2.0 * mu * r;
        }
    }
    sum
}

/// Gauss-Legendre nodes on [0, 1] and their weights (summing to 1): Newton's method on the
/// Legendre polynomial of degree `n` from Tricomi's first guesses.
pub fn gauss_legendre(n: usize) -> Vec<(f64, f64)> {
    (1..=n)
        .map(|i| {
            let mut x = (std::f64::consts::PI * (i as f64 - 0.25) / (n as f64 + 0.5)).cos();
            let mut derivative = 1.0;
            for _ in 0..100 {
                // P_n(x) and P_{n-1}(x) by the three-term recurrence.
                let (mut p, mut previous) = (x, 1.0);
                for k in 2..=n {
                    let next = ((2 * k - 1) as f64 * x * p - (k - 1) as f64 * previous) / k as f64;
                    previous = p;
                    p = next;
                }
                derivative = n as f64 * (x * p - previous) / (x * x - 1.0);
                let step = p / derivative;
                x -= step;
                if step.abs() < 1e-15 {
                    break;
                }
            }
            let weight = 2.0 / ((1.0 - x * x) * derivative * derivative);
            (0.5 * (x + 1.0), 0.5 * weight)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::coat::fresnel_mean;

    #[test]
    fn gauss_legendre_integrates_polynomials_exactly() {
        let rule = gauss_legendre(8);
        assert!((rule.iter().map(|(_, w)| w).sum::<f64>() - 1.0).abs() < 1e-14);
        // Degree 15 is within reach of 8 nodes: int_0^1 x^15 = 1/16.
        let integral: f64 = rule.iter().map(|(x, w)| w * x.powi(15)).sum();
        assert!((integral - 1.0 / 16.0).abs() < 1e-14, "{integral}");
    }

    /// Coats of index 1 or below (no total internal reflection inside) have finite tables
    /// within [0, 1].
    #[test]
    fn coats_of_index_one_or_below_have_finite_tables() {
        for ior in [0.8, 1.0, 1.0001] {
            let table = CoatTable::of(ior, 0.5);
            let k = table.internal_reflectance;
            assert!((0.0..=1.0).contains(&k), "ior {ior}: K {k}");
            for cos in [0.0, 0.3, 1.0] {
                let o = table.opacity(cos);
                assert!((0.0..=1.0).contains(&o), "ior {ior}: opacity {o} at {cos}");
            }
        }
    }

    /// Nearly smooth, 1 - T is smooth Fresnel's reflectance and K the smooth coat's.
    #[test]
    fn a_nearly_smooth_table_is_fresnel() {
        let table = CoatTable::of(1.5, 1e-3);
        for cos in [0.1, 0.5, 0.9, 1.0] {
            let (r, f) = (table.opacity(cos), coat_fresnel(cos, 1.5));
            assert!((r - f).abs() < 2e-3, "cos {cos}: table {r}, fresnel {f}");
        }
        let smooth = 1.0 - (1.0 - fresnel_mean(1.5)) / (1.5 * 1.5);
        let k = table.internal_reflectance;
        assert!((k - smooth).abs() < 1e-4, "K {k}, smooth {smooth}");
    }
}
