//! glTF's specular strength and colour (KHR_materials_specular) on `pbr`'s dielectric coat and
//! glass (twin: `shaders/specular.wgsl`). The extension reshapes the dielectric's Fresnel:
//!
//! `Fr(cos) = f0 + (1 - f0) w(cos)`, `f0 = min(F(1) x color, 1)` per channel,
//!
//! the coat reflecting `factor x Fr` (a colour) and letting through to the base what
//! `1 - factor x max(Fr)` leaves. The extension writes Schlick's `w = (1 - cos)^5`; pbr's coat
//! already uses exact Fresnel `F` of its ior, so here `w` is exact Fresnel's own shape,
//! `(F(cos) - F(1)) / (1 - F(1))` (clamped to [0, 1]: at large indices Fresnel dips below its
//! head-on value before rising), which makes `Fr` exactly `F` for the default factor 1 and
//! white colour, and keeps Schlick's ends: `f0` at normal incidence, 1 at grazing. `max(Fr)` is
//! the coat's opacity, and its internal reflectance follows from its mean as for a plain coat
//! (`material::coat`), so a smooth coat over a white base still reflects exactly everything in
//! its strongest channel whatever the factor and colour (tests/it/bsdfs/specular.rs).
//!
//! The glass of the mix is reshaped alike (the extension's `fresnel_mix` over its
//! `specular_btdf`): it reflects `factor x Fr` and transmits `1 - factor x max(Fr)`, with `w`
//! exact Fresnel's shape on the side the light comes from, so that seen from inside `Fr` rises
//! to 1 at the critical angle; under total internal reflection, which the extension (drawn by
//! rasterizers, no inside) does not consider, the glass reflects everything, as glass does
//! (`Dielectric::reflectance`). The metal keeps its own Fresnel, as the extension says.

use super::coat::coat_fresnel;
use crate::params::checked;
use glam::Vec3;
use serde::{Deserialize, Serialize};

/// `specular = { factor = 0.5, color = [1, 0.8, 0.8] }` on a `pbr` material: glTF's
/// specularFactor (default 1, in [0, 1]) and specularColorFactor (default white; any
/// non-negative colour, as the extension allows: F(1) x color is clamped to 1).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Specular {
    #[serde(default = "one", with = "checked::number")]
    pub factor: f32,
    #[serde(default = "white", with = "checked::colour")]
    pub color: Vec3,
}

fn one() -> f32 {
    1.0
}

fn white() -> Vec3 {
    Vec3::ONE
}

impl Default for Specular {
    fn default() -> Self {
        Specular {
            factor: 1.0,
            color: Vec3::ONE,
        }
    }
}

impl Specular {
    /// Its parameter ranges; the message names the parameter.
    pub fn validate(&self) -> Result<(), String> {
        if !(0.0..=1.0).contains(&self.factor) {
            return Err(format!(
                "specular factor must be in [0, 1], got {}",
                self.factor
            ));
        }
        if !(self.color.min_element() >= 0.0 && self.color.is_finite()) {
            return Err(format!(
                "specular color must be finite and >= 0 in each channel, got {}",
                self.color
            ));
        }
        Ok(())
    }

    /// Whether it changes anything: a factor below 1 or a colour other than white.
    pub fn is_default(&self) -> bool {
        *self == Specular::default()
    }

    /// Its Fresnel for a coat of index `ior`.
    pub fn fresnel(&self, ior: f32) -> SpecularFresnel {
        SpecularFresnel {
            factor: self.factor,
            tint: coat_fresnel(1.0, ior) * self.color,
            shape_mean: SpecularFresnel::shape_mean(ior),
        }
    }
}

/// The coat's reshaped Fresnel: `factor`, the colour's `tint` of head-on Fresnel (`F(1) x
/// color`, whose clamp to 1 is `f0`), and the mean of Fresnel's shape for its index, from
/// which its mean opacity follows for any factor and colour (so that images of them can
/// change both point by point: `Pbr::layers_at`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpecularFresnel {
    pub factor: f32,
    pub tint: Vec3,
    /// The cosine-weighted mean of [`Self::shape`] over incidence, for the coat's index.
    pub shape_mean: f32,
}

impl SpecularFresnel {
    /// Exact Fresnel's shape between its ends: 0 at normal incidence, 1 at grazing, from `f`
    /// (`coat_fresnel` at some cosine) and `f_normal` (at normal incidence); clamped to 0 where
    /// Fresnel dips below its head-on value (large indices).
    #[inline]
    fn shape(f: f32, f_normal: f32) -> f32 {
        ((f - f_normal) / (1.0 - f_normal)).clamp(0.0, 1.0)
    }

    /// The coloured head-on reflectance: `tint` clamped to 1 in each channel.
    #[inline]
    pub fn f0(&self) -> Vec3 {
        self.tint.min(Vec3::ONE)
    }

    /// This Fresnel with its factor scaled by `factor` and its colour by `color` (texels of
    /// the specular images; twin: `pbr_with_layers`).
    pub fn scaled(self, factor: f32, color: Vec3) -> Self {
        SpecularFresnel {
            factor: self.factor * factor,
            tint: self.tint * color,
            ..self
        }
    }

    /// What the coat of index `ior` reflects at cosine `cos` (to the normal, or to a
    /// microfacet's): `factor x Fr(cos)`.
    #[inline]
    pub fn reflectance(&self, cos: f32, ior: f32) -> Vec3 {
        self.reshaped(coat_fresnel(cos, ior), coat_fresnel(1.0, ior))
    }

    /// `factor x Fr` where exact Fresnel is `f`, and `f_normal` at normal incidence: what a
    /// surface reflects whose Fresnel without the extension would be `f` (from either side).
    #[inline]
    pub fn reshaped(&self, f: f32, f_normal: f32) -> Vec3 {
        let w = Self::shape(f, f_normal);
        let f0 = self.f0();
        self.factor * (f0 + (Vec3::ONE - f0) * w)
    }

    /// The share of light met at cosine `cos` that does not cross the coat: `factor x
    /// max(Fr(cos))` (Fr's largest channel is the one of largest f0).
    #[inline]
    pub fn opacity(&self, cos: f32, ior: f32) -> f32 {
        let w = Self::shape(coat_fresnel(cos, ior), coat_fresnel(1.0, ior));
        let f0 = self.f0().max_element();
        self.factor * (f0 + (1.0 - f0) * w)
    }

    /// The cosine-weighted hemispherical mean of [`Self::opacity`], 2 int_0^1 O(mu) mu dmu:
    /// the opacity is linear in the shape, so it is `factor x (f0 + (1 - f0) x shape_mean)`
    /// with f0 the largest channel's (twin: `pbr_internal_reflectance`).
    #[inline]
    pub fn mean_opacity(&self) -> f32 {
        let f0 = self.f0().max_element();
        self.factor * (f0 + (1.0 - f0) * self.shape_mean)
    }

    /// The cosine-weighted mean of the shape at index `ior`, 2 int_0^1 w(mu) mu dmu, by
    /// Simpson's rule in f64 over 1 000 panels, as `coat::fresnel_mean`. Not from Fresnel's
    /// mean: at large indices Fresnel dips below its head-on value before it rises to 1 (at
    /// index 10, 0.61 at cosine 0.4 against 0.67 head-on), where the shape is clamped to 0.
    pub fn shape_mean(ior: f32) -> f32 {
        const PANELS: usize = 1000;
        let f_normal = coat_fresnel(1.0, ior);
        let f = |mu: f64| Self::shape(coat_fresnel(mu as f32, ior), f_normal) as f64 * mu;
        let h = 1.0 / PANELS as f64;
        let mut sum = f(0.0) + f(1.0);
        for i in 1..PANELS {
            sum += f(i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
        }
        (2.0 * sum * h / 3.0) as f32
    }
}
