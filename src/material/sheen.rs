//! glTF's sheen (KHR_materials_sheen) over `pbr`'s mix (twin: `shaders/sheen.wgsl`): the
//! back-scattering of velvet's fibres, as the extension defines it after Estevez and Kulla
//! ("Production Friendly Microfacet Sheen BRDF", 2017): the "Charlie" distribution
//! `D = (2 + 1/a) sin(h)^(1/a) / (2 pi)` with `a` the sheen roughness squared (the extension's
//! mapping, as the Khronos sample renderer has it), their fitted visibility
//! `1 / ((1 + L(cos_o) + L(cos_i)) 4 cos_o cos_i)` of the same `a`, no Fresnel, times the sheen
//! colour. Below it the mix is scaled by the extension's albedo scaling in its view-only
//! form, `1 - m E(cos_o)` (m the colour's largest channel, E the sheen's directional albedo), as
//! the clear coat scales what is below it (`clearcoat.rs`) and as Cycles layers its sheen: a
//! white sheen over a lossless base reflects exactly everything. The extension's full form,
//! `min(1 - m E(cos_o), 1 - m E(cos_i))`, is reciprocal but loses light (a white sheen over the
//! lossless smooth dielectric reflected 0.88-0.95 of it at normal incidence, measured).
//!
//! E(cos, roughness) is tabulated ([`albedo_table`]: 32 cosines x 32 roughnesses, each a
//! quadrature in f64 over the hemisphere, read from `sheen_albedo.bin`), bilinear between its
//! entries on both backends (the kernel reads it from the images array:
//! `GpuMaterial::sheen_table`). The visibility is clamped to 1, as the sample renderer clamps
//! it, and roughness below [`MIN_ROUGHNESS`] is taken as it (a note names the files that ask
//! for less).
//!
//! Sampling picks the sheen with chance `m E(cos_o)` and then a cosine-distributed direction
//! (the sheen is broad; its distribution has no closed-form inverse), else the mix.

use crate::assets::image::Image;
use crate::params::checked;
use crate::shared::ray::{Hit, below_surface};
use glam::Vec3;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use std::sync::{Arc, OnceLock};

/// The least roughness the distribution takes (its a = 0.0625): below it, E at grazing angles
/// exceeds 1 (2.7 at roughness 0.07, a = 0.0049: the fitted visibility is not energy-conserving
/// there), which albedo scaling cannot take.
pub const MIN_ROUGHNESS: f32 = 0.25;
/// The albedo table's cosines and roughnesses: (i / (N - 1)) over [0, 1] and over
/// [`MIN_ROUGHNESS`, 1].
pub const TABLE_SIZE: usize = 32;

/// `sheen = { color = [0.8, 0.2, 0.2], roughness = 0.5 }` on a `pbr` material: glTF's
/// sheenColorFactor and sheenRoughnessFactor (defaults: white, and 0, taken as
/// [`MIN_ROUGHNESS`]).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Sheen {
    #[serde(default = "white", with = "checked::albedo")]
    pub color: Vec3,
    #[serde(default, with = "checked::number")]
    pub roughness: f32,
}

fn white() -> Vec3 {
    Vec3::ONE
}

/// The fitted exponent of Estevez and Kulla's visibility, in f64 (for the table) and f32.
fn l(x: f64, a: f64) -> f64 {
    let t = (1.0 - a) * (1.0 - a);
    let mix = |p: f64, q: f64| p + (q - p) * t;
    let (pa, pb, pc) = (
        mix(21.5473, 25.3245),
        mix(3.82987, 3.32435),
        mix(0.19823, 0.16801),
    );
    let (pd, pe) = (mix(-1.97760, -1.27393), mix(-4.32054, -4.85967));
    pa / (1.0 + pb * x.powf(pc)) + pd * x + pe
}

fn lambda(cos: f64, a: f64) -> f64 {
    if cos < 0.5 {
        l(cos, a).exp()
    } else {
        (2.0 * l(0.5, a) - l(1.0 - cos, a)).exp()
    }
}

/// E(cos, a) at the table's entries, row by row of roughness: the hemispherical integral of
/// the sheen's BSDF x cos_i for colour 1 (D V cos_i) by the midpoint rule over `cosines` x
/// `azimuths` (half the azimuths, by symmetry), in f64. `sheen_albedo.bin` holds it at 256 x
/// 256 (tests/it/bsdfs/sheen.rs bounds its quadrature error).
pub fn albedo_values(cosines: usize, azimuths: usize) -> Vec<f64> {
    let mut out = Vec::with_capacity(TABLE_SIZE * TABLE_SIZE);
    for r in 0..TABLE_SIZE {
        let a = (table_roughness(r) as f64).powi(2);
        let lambdas: Vec<f64> = (0..cosines)
            .map(|i| lambda((i as f64 + 0.5) / cosines as f64, a))
            .collect();
        for c in 0..TABLE_SIZE {
            let cos_o = (c as f64 / (TABLE_SIZE - 1) as f64).max(1e-4);
            let sin_o = (1.0 - cos_o * cos_o).sqrt();
            let lambda_o = lambda(cos_o, a);
            let mut sum = 0.0;
            for (i, lambda_i) in lambdas.iter().enumerate() {
                let cos_i = (i as f64 + 0.5) / cosines as f64;
                let sin_i = (1.0 - cos_i * cos_i).sqrt();
                // The visibility clamped to 1, as the sample renderer clamps it; times cos_i.
                let v =
                    (1.0 / ((1.0 + lambda_o + lambda_i) * 4.0 * cos_o * cos_i)).min(1.0) * cos_i;
                for j in 0..azimuths {
                    let phi = PI * (j as f64 + 0.5) / azimuths as f64;
                    let h = [sin_o + sin_i * phi.cos(), sin_i * phi.sin(), cos_o + cos_i];
                    let len2 = h[0] * h[0] + h[1] * h[1] + h[2] * h[2];
                    let sin2 = 1.0 - h[2] * h[2] / len2;
                    let d = (2.0 + 1.0 / a) * sin2.max(0.0).powf(0.5 / a) / (2.0 * PI);
                    sum += d * v;
                }
            }
            // d omega = d cos_i d phi over [0, 1] x [0, 2 pi]: the half computed, twice.
            out.push(sum * 2.0 * PI / (cosines * azimuths) as f64);
        }
    }
    out
}

/// The table as `sheen_albedo.bin` holds it: little-endian f32, row by row of roughness.
pub fn table_bytes(values: &[f64]) -> Vec<u8> {
    values
        .iter()
        .flat_map(|&e| (e as f32).to_le_bytes())
        .collect()
}

/// The table's roughness at row `r`.
fn table_roughness(r: usize) -> f32 {
    MIN_ROUGHNESS + (1.0 - MIN_ROUGHNESS) * r as f32 / (TABLE_SIZE - 1) as f32
}

/// The sheen's directional albedo E(cos, roughness) for every cosine and roughness of the
/// table, as an image of [`TABLE_SIZE`] x [`TABLE_SIZE`] texels (cosine across, roughness down;
/// E in every channel) that the GPU's images array holds; read once per process from
/// `sheen_albedo.bin` ([`albedo_values`] at 256 x 256, written by the ignored test
/// `write_sheen_table`).
pub fn albedo_table() -> &'static Arc<Image> {
    static TABLE: OnceLock<Arc<Image>> = OnceLock::new();
    TABLE.get_or_init(|| {
        let bytes = include_bytes!("sheen_albedo.bin");
        let texels = bytes
            .chunks_exact(4)
            .flat_map(|b| [f32::from_le_bytes([b[0], b[1], b[2], b[3]]); 3])
            .collect();
        let size = TABLE_SIZE as u32;
        Arc::new(
            Image::from_linear("sheen albedo table", size, size, texels)
                .expect("its size is valid"),
        )
    })
}

impl Sheen {
    /// Its parameter ranges; the message names the parameter.
    pub fn validate(&self) -> Result<(), String> {
        if !(0.0..=1.0).contains(&self.roughness) {
            return Err(format!(
                "sheen roughness must be in [0, 1], got {}",
                self.roughness
            ));
        }
        if !(self.color.min_element() >= 0.0 && self.color.max_element() <= 1.0) {
            return Err(format!(
                "sheen color must be in [0, 1] in each channel, got {}",
                self.color
            ));
        }
        Ok(())
    }

    /// The roughness the distribution takes: its own, at least [`MIN_ROUGHNESS`] (its `a` is
    /// the square).
    #[inline]
    pub fn alpha(&self) -> f32 {
        self.roughness.max(MIN_ROUGHNESS)
    }

    /// Its largest colour channel times its directional albedo at `cos` (either side): the share
    /// of light it reflects there at most, and the chance of sampling it.
    #[inline]
    pub fn reflectance(&self, cos: f32) -> f32 {
        self.color.max_element() * albedo(cos.abs(), self.alpha())
    }

    /// What of the mix below it shows toward `wo`: the albedo scaling.
    #[inline]
    pub fn through(&self, wo: Vec3, hit: &Hit) -> f32 {
        1.0 - self.reflectance(wo.dot(hit.shading))
    }

    /// The sheen's BSDF x cos at (wo, wi), both above the shading normal (and the geometric
    /// surface), else 0.
    pub fn eval(&self, wo: Vec3, wi: Vec3, hit: &Hit) -> Vec3 {
        let n = hit.shading;
        // Unit vectors' dot products round up to 1 + 1 ulp.
        let (cos_o, cos_i) = (wo.dot(n).min(1.0), wi.dot(n).min(1.0));
        if !(cos_o > super::microfacet::MIN_COSINE && cos_i > super::microfacet::MIN_COSINE)
            || below_surface(hit, wi)
        {
            return Vec3::ZERO;
        }
        let h = (wo + wi).normalize();
        let a = self.alpha() * self.alpha();
        let sin2 = (1.0 - h.dot(n).powi(2)).max(0.0);
        let d = (2.0 + 1.0 / a) * sin2.powf(0.5 / a) * (0.5 * std::f32::consts::FRAC_1_PI);
        // The visibility clamped to 1, as the sample renderer clamps it; times cos_i.
        let v = (1.0 / ((1.0 + lambda32(cos_o, a) + lambda32(cos_i, a)) * 4.0 * cos_o * cos_i))
            .min(1.0)
            * cos_i;
        self.color * (d * v)
    }
}

/// [`lambda`] in f32, as the kernel computes it.
fn lambda32(cos: f32, a: f32) -> f32 {
    let t = (1.0 - a) * (1.0 - a);
    let l = |x: f32| {
        let mix = |p: f32, q: f32| p + (q - p) * t;
        mix(21.5473, 25.3245) / (1.0 + mix(3.82987, 3.32435) * x.powf(mix(0.19823, 0.16801)))
            + mix(-1.97760, -1.27393) * x
            + mix(-4.32054, -4.85967)
    };
    if cos < 0.5 {
        l(cos).exp()
    } else {
        (2.0 * l(0.5) - l((1.0 - cos).max(0.0))).exp()
    }
}

/// E(cos, roughness) read off [`albedo_table`], bilinear between its entries (twin:
/// `sheen_albedo` in `shaders/sheen.wgsl`).
pub fn albedo(cos: f32, roughness: f32) -> f32 {
    let table = albedo_table();
    let last = (TABLE_SIZE - 1) as f32;
    let x = cos.clamp(0.0, 1.0) * last;
    let y = ((roughness - MIN_ROUGHNESS) / (1.0 - MIN_ROUGHNESS)).clamp(0.0, 1.0) * last;
    let (i, j) = (
        (x as usize).min(TABLE_SIZE - 2),
        (y as usize).min(TABLE_SIZE - 2),
    );
    let (fx, fy) = (x - i as f32, y - j as f32);
    let at = |i: usize, j: usize| table.texel(i as u32, j as u32).x;
    let top = at(i, j) * (1.0 - fx) + at(i + 1, j) * fx;
    let bottom = at(i, j + 1) * (1.0 - fx) + at(i + 1, j + 1) * fx;
    top * (1.0 - fy) + bottom * fy
}
