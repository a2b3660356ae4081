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
//! sample them ([`CoatTable::exact`]).
//!
//! A scene's coats of index 1 to 100 read their tables off a grid of exact ones over index and
//! roughness (`coat_grid.bin`, 49 x 33 tables written by the ignored test `write_coat_grid`),
//! bicubic between them, as Cycles reads its glass albedos off tables over (ior, roughness,
//! cosine): thousands of distinct plastics then load in milliseconds, not a minute. The grid's
//! index axis is ln(1 + 4 sqrt(ior - 1)), fine where the index nears 1 (where grazing Fresnel
//! turns on over a tiny range) and logarithmic for large ones; how close its tables are to exact
//! ones is in docs/benchmarks.md and bounded by the tests. Coats of index below 1 (total
//! internal reflection from outside puts a step in the table that moves with the index) are
//! computed.

use super::coat::coat_fresnel;
use super::fresnel::refract_cos;
use super::microfacet::Ggx;
use crate::assets::image::Image;
use glam::Vec3;
use std::collections::HashMap;
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
    pub image: std::sync::Arc<Image>,
    /// K: 2 int_0^1 R_inside(mu) mu dmu, the coat's reflectance of diffuse light from the base.
    pub internal_reflectance: f32,
}

impl CoatTable {
    /// The table of a coat of index `ior` (> 0) and GGX `alpha` (>= `MIN_ALPHA`): read off the
    /// grid for an index in [1, 100], else computed; made once per pair and kept for the
    /// process (as images are).
    pub fn of(ior: f32, alpha: f32) -> &'static CoatTable {
        type Tables = HashMap<(u32, u32), &'static CoatTable>;
        static TABLES: Mutex<Option<Tables>> = Mutex::new(None);
        let key = (ior.to_bits(), alpha.to_bits());
        let mut tables = TABLES
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner());
        let tables = tables.get_or_insert_with(HashMap::new);
        if let Some(table) = tables.get(&key) {
            return table;
        }
        let table = if (1.0..=grid::MAX_IOR).contains(&ior) {
            grid::table(ior, alpha)
        } else {
            CoatTable::exact(ior, alpha)
        };
        let table: &'static CoatTable = Box::leak(Box::new(table));
        tables.insert(key, table);
        table
    }

    /// Tables computed by quadrature on this thread so far (what loading a scene of many
    /// plastics must not pay for).
    pub fn computed_on_this_thread() -> usize {
        COMPUTED.with(|c| c.get())
    }

    /// The table from opacities at the table's cosines and K.
    fn from_values(ior: f32, alpha: f32, opacities: &[f32], internal_reflectance: f32) -> Self {
        let texels = opacities.iter().flat_map(|&o| [o; 3]).collect();
        let source = format!("coat table (ior {ior}, alpha {alpha})");
        CoatTable {
            image: Image::from_linear(&source, COAT_TABLE_SIZE as u32, 1, texels)
                .expect("opacities are finite and in [0, 1]")
                .shared(),
            internal_reflectance,
        }
    }

    /// The table of a coat of index `ior` and GGX `alpha`, by quadrature.
    pub fn exact(ior: f32, alpha: f32) -> Self {
        COMPUTED.with(|c| c.set(c.get() + 1));
        let ggx = Ggx { alpha };
        let last = (COAT_TABLE_SIZE - 1) as f32;
        let opacities: Vec<f32> = (0..COAT_TABLE_SIZE)
            .map(|i| {
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
                if transmitted.is_finite() {
                    (1.0 - transmitted).clamp(0.0, 1.0) as f32
                } else {
                    1.0
                }
            })
            .collect();
        let k = internal_reflectance(ggx, ior) as f32;
        CoatTable::from_values(ior, alpha, &opacities, k)
    }

    /// The table's opacities at its cosines.
    #[cfg(test)]
    fn opacities(&self) -> impl Iterator<Item = f32> + '_ {
        self.image.texels.iter().step_by(3).copied()
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

thread_local! {
    /// Tables computed by quadrature on this thread ([`CoatTable::computed_on_this_thread`]).
    static COMPUTED: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

/// The grid of exact tables over index (1 to 100) and roughness (0.01 to 1) that coats read
/// theirs off.
mod grid {
    use super::{COAT_TABLE_SIZE, CoatTable};

    /// The largest index on the grid (the largest a coat may have: `fresnel::MAX_IOR`).
    pub const MAX_IOR: f32 = 100.0;
    /// Indices, at ln(1 + 4 sqrt(ior - 1)) evenly spaced.
    pub const IORS: usize = 49;
    /// Roughnesses (sqrt(alpha)), evenly spaced from `MIN_ROUGHNESS`.
    pub const ROUGHNESSES: usize = 33;
    /// sqrt(`MIN_ALPHA`).
    const MIN_ROUGHNESS: f64 = 0.01;
    /// Values per table: its opacities, then K.
    pub const VALUES: usize = COAT_TABLE_SIZE + 1;

    /// The grid as written: for each index, each roughness, the table's values as u16 (x / 65535,
    /// 1.5e-5 apart, below the quadrature's accuracy), little-endian.
    static GRID: &[u8] = include_bytes!("coat_grid.bin");
    const _: () = assert!(GRID.len() == IORS * ROUGHNESSES * VALUES * 2);

    fn coordinate_of_ior(ior: f64) -> f64 {
        let warp = |ior: f64| (1.0 + 4.0 * (ior - 1.0).max(0.0).sqrt()).ln();
        warp(ior) / warp(MAX_IOR as f64) * (IORS - 1) as f64
    }

    /// The index of the grid's `i`-th row.
    #[cfg(test)]
    pub fn ior_at(i: usize) -> f32 {
        let warp_max = (1.0 + 4.0 * (MAX_IOR as f64 - 1.0).sqrt()).ln();
        let root = ((i as f64 / (IORS - 1) as f64 * warp_max).exp() - 1.0) / 4.0;
        if i == IORS - 1 {
            MAX_IOR
        } else {
            (1.0 + root * root) as f32
        }
    }

    /// The GGX alpha of the grid's `j`-th column.
    #[cfg(test)]
    pub fn alpha_at(j: usize) -> f32 {
        let roughness = MIN_ROUGHNESS + (1.0 - MIN_ROUGHNESS) * j as f64 / (ROUGHNESSES - 1) as f64;
        (roughness * roughness) as f32
    }

    fn value(i: usize, j: usize, k: usize) -> f64 {
        let at = 2 * ((i * ROUGHNESSES + j) * VALUES + k);
        u16::from_le_bytes([GRID[at], GRID[at + 1]]) as f64 / 65535.0
    }

    /// Catmull-Rom's cubic through `p` at `t` in [0, 1] between p[1] and p[2].
    fn cubic(p: [f64; 4], t: f64) -> f64 {
        p[1] + 0.5
            * t
            * (p[2] - p[0]
                + t * (2.0 * p[0] - 5.0 * p[1] + 4.0 * p[2] - p[3]
                    + t * (3.0 * (p[1] - p[2]) + p[3] - p[0])))
    }

    /// The table of a coat of index `ior` in [1, `MAX_IOR`] and GGX `alpha`, bicubic between
    /// the grid's (each value within [0, 1]).
    pub fn table(ior: f32, alpha: f32) -> CoatTable {
        let x = coordinate_of_ior(ior as f64).clamp(0.0, (IORS - 1) as f64);
        let y = ((alpha as f64).sqrt() - MIN_ROUGHNESS) / (1.0 - MIN_ROUGHNESS);
        let y = (y * (ROUGHNESSES - 1) as f64).clamp(0.0, (ROUGHNESSES - 1) as f64);
        let (i, j) = (
            (x as usize).min(IORS - 2),
            (y as usize).min(ROUGHNESSES - 2),
        );
        let (tx, ty) = (x - i as f64, y - j as f64);
        // Rows and columns beyond the grid repeat its edge.
        let row = |d: usize| (i + d).saturating_sub(1).min(IORS - 1);
        let column = |d: usize| (j + d).saturating_sub(1).min(ROUGHNESSES - 1);
        let values: Vec<f32> = (0..VALUES)
            .map(|k| {
                let along = |d: usize| cubic([0, 1, 2, 3].map(|e| value(row(d), column(e), k)), ty);
                cubic([0, 1, 2, 3].map(along), tx).clamp(0.0, 1.0) as f32
            })
            .collect();
        CoatTable::from_values(
            ior,
            alpha,
            &values[..COAT_TABLE_SIZE],
            values[COAT_TABLE_SIZE],
        )
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

    /// The grid's values as the quadrature gives them, at its corners and inside (to the u16's
    /// resolution). Rewrite the grid (about 10 s on two cores) with `cargo test --release --lib
    /// write_coat_grid -- --ignored`.
    #[test]
    fn the_grid_holds_exact_tables() {
        for (i, j) in [
            (0, 0),
            (grid::IORS - 1, grid::ROUGHNESSES - 1),
            (0, 17),
            (31, 0),
            (20, 9),
        ] {
            let (ior, alpha) = (grid::ior_at(i), grid::alpha_at(j));
            let (exact, read) = (CoatTable::exact(ior, alpha), grid::table(ior, alpha));
            let k = (exact.internal_reflectance, read.internal_reflectance);
            assert!(
                (k.0 - k.1).abs() < 2e-5,
                "ior {ior}, alpha {alpha}: K {k:?}"
            );
            for (c, (e, r)) in exact.opacities().zip(read.opacities()).enumerate() {
                assert!(
                    (e - r).abs() < 2e-5,
                    "ior {ior}, alpha {alpha}, cosine {c}: {e}, {r}"
                );
            }
        }
    }

    /// Between the grid's nodes, tables are within 1e-4 of exact ones on average, 6e-3 at worst
    /// (grazing, nearly smooth: the grid's largest differences), K within 2e-3, at indices
    /// spread over [1, 100] and roughnesses over [0.01, 1].
    #[test]
    fn tables_off_the_grid_are_close_to_exact_ones() {
        let mut state = 7u64;
        let mut uniform = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let (mut worst, mut sum, mut worst_k, mut n) = (0.0f32, 0.0f32, 0.0f32, 0);
        for pick in 0..24 {
            let ior = match pick % 3 {
                0 => 1.0 + 0.1 * uniform(),
                1 => 1.1 + 1.9 * uniform(),
                _ => 100f32.powf(uniform()),
            };
            let alpha = (0.01 + 0.99 * uniform()).powi(2);
            let (exact, read) = (CoatTable::exact(ior, alpha), CoatTable::of(ior, alpha));
            for (e, r) in exact.opacities().zip(read.opacities()) {
                worst = worst.max((e - r).abs());
                sum += (e - r).abs();
                n += 1;
            }
            let k = (exact.internal_reflectance - read.internal_reflectance).abs();
            worst_k = worst_k.max(k);
        }
        let mean = sum / n as f32;
        eprintln!(
            "grid against exact: opacity mean {mean:.1e}, worst {worst:.1e}; K worst {worst_k:.1e}"
        );
        assert!(
            mean < 1e-4 && worst < 6e-3 && worst_k < 2e-3,
            "{mean} {worst} {worst_k}"
        );
    }

    /// A coat of index in [1, 100] reads its table off the grid: no quadrature (a scene of
    /// 5 000 distinct plastics took 65 s for them); below 1 it is computed.
    #[test]
    fn grid_coats_compute_nothing() {
        let before = CoatTable::computed_on_this_thread();
        for n in 0..200 {
            let table = CoatTable::of(1.0 + n as f32 * 0.37, 0.001 + n as f32 * 0.004);
            assert!((0.0..=1.0).contains(&table.internal_reflectance));
        }
        assert_eq!(CoatTable::computed_on_this_thread(), before);
        CoatTable::of(0.7, 0.25);
        assert_eq!(CoatTable::computed_on_this_thread(), before + 1);
    }

    /// Writes the grid (`coat_grid.bin`) from exact tables.
    #[test]
    #[ignore = "writes src/material/coat_grid.bin; run after changing how tables are computed"]
    fn write_coat_grid() {
        use rayon::prelude::*;
        let nodes: Vec<(usize, usize)> = (0..grid::IORS)
            .flat_map(|i| (0..grid::ROUGHNESSES).map(move |j| (i, j)))
            .collect();
        let bytes: Vec<u8> = nodes
            .par_iter()
            .flat_map_iter(|&(i, j)| {
                let table = CoatTable::exact(grid::ior_at(i), grid::alpha_at(j));
                let values: Vec<f32> = table
                    .opacities()
                    .chain([table.internal_reflectance])
                    .collect();
                assert_eq!(values.len(), grid::VALUES);
                values
                    .into_iter()
                    .flat_map(|v| ((v.clamp(0.0, 1.0) * 65535.0).round() as u16).to_le_bytes())
            })
            .collect();
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/src/material/coat_grid.bin");
        std::fs::write(path, bytes).expect("writes the grid");
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
