//! Normal maps: an image of tangent-space normals that bends a mesh's shading normal, as glTF's
//! `normalTexture` and Blender's Normal Map node (tangent space) define it. Plain data, and with
//! serde its scene-file syntax `normal_map = { image = "file.png", scale = 1.0 }` on the
//! materials that take one. Applied where a hit is completed (`cpu::intersect::normal_mapped`, twin
//! `shaders/normal_map.wgsl`), with MikkTSpace tangents (`scene::tangents`).

use crate::assets::image::Image;
use crate::params::checked;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

/// Texels hold (x, y, z) of the normal in the tangent frame as `2 * value - 1` (linear 8- or
/// 16-bit values: OpenGL's convention, green toward +v, as glTF and Blender write them); `scale`
/// multiplies x and y (glTF's `normalTexture.scale`).
#[derive(Clone, Debug, PartialEq, Deserialize, Serialize)]
#[serde(try_from = "NormalMapDoc", into = "NormalMapDoc")]
pub struct NormalMap {
    pub image: Arc<Image>,
    pub scale: f32,
}

/// Largest |scale| accepted: beyond it a map's x and y swamp z everywhere.
pub const MAX_SCALE: f32 = 100.0;

#[derive(Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
struct NormalMapDoc {
    image: String,
    #[serde(default = "one", with = "checked::number")]
    scale: f32,
}

fn one() -> f32 {
    1.0
}

impl TryFrom<NormalMapDoc> for NormalMap {
    type Error = String;
    fn try_from(d: NormalMapDoc) -> Result<Self, String> {
        let image = crate::assets::loader::data_image(&d.image)?;
        let map = NormalMap {
            image,
            scale: d.scale,
        };
        map.validate()?;
        Ok(map)
    }
}

impl From<NormalMap> for NormalMapDoc {
    fn from(m: NormalMap) -> Self {
        NormalMapDoc {
            image: m.image.source.clone(),
            scale: m.scale,
        }
    }
}

impl NormalMap {
    pub fn validate(&self) -> Result<(), String> {
        if !(self.scale.abs() <= MAX_SCALE) {
            return Err(format!(
                "normal map scale must be within [-{MAX_SCALE}, {MAX_SCALE}], got {}",
                self.scale
            ));
        }
        if self.image.max_value() > 1.0 {
            return Err(format!(
                "normal map {} has values up to {}: a normal map's values lie in [0, 1]",
                self.image.source,
                self.image.max_value()
            ));
        }
        Ok(())
    }
}

/// Unit `n`, a mapped normal on the side of the unit geometric normal `ng` that faces `wo`
/// (unit, toward where the light leaves), bent toward `ng` in their plane where it must be so
/// that `wo`'s mirror image about it leaves above the surface, at a cosine to `ng` of at least
/// min(0.9 wo.ng, 0.01): as Cycles bends the normals its glossy closures shade with
/// (`ensure_valid_specular_reflection`), here for a clear coat's normal map (`Hit::coat`),
/// whose mirror would otherwise send much of what it reflects below the surface and darken
/// the map's steep slopes to black. The bent normal's height over the surface, `u = n.ng`
/// squared, solves `2 (n.wo) sqrt(u) - wo.ng = threshold` with
/// `n = sqrt(1 - u) x + sqrt(u) ng`: a quadratic in `u`, `4 a u^2 - 2 b u + c = 0`, whose
/// root is the one on `wo`'s side. Twin: `valid_reflection` in shaders/normal_map.wgsl.
pub fn valid_reflection(ng: glam::Vec3, wo: glam::Vec3, n: glam::Vec3) -> glam::Vec3 {
    let iz = wo.dot(ng).max(0.0);
    let threshold = (0.9 * iz).min(0.01);
    let reflected = 2.0 * n.dot(wo) * n - wo;
    if reflected.dot(ng) >= threshold {
        return n;
    }
    let along = n - n.dot(ng) * ng;
    let len2 = along.dot(along);
    if !(len2 > 1e-20) {
        return n;
    }
    let x = along / len2.sqrt();
    let ix = wo.dot(x);
    let a = ix * ix + iz * iz;
    if !(a > 1e-20) {
        return n;
    }
    let b = 2.0 * (a + iz * threshold);
    let c = (threshold + iz) * (threshold + iz);
    let root = (b * b - 4.0 * a * c).max(0.0).sqrt();
    // The smaller root as c / (b + root), which keeps its digits where it is near 0.
    let u = if ix < 0.0 {
        0.25 * (b + root) / a
    } else {
        c / (b + root)
    }
    .clamp(0.0, 1.0);
    let bent = (1.0 - u).sqrt() * x + u.sqrt() * ng;
    bent / bent.length()
}

#[cfg(test)]
mod tests {
    use super::valid_reflection;
    use glam::Vec3;

    /// Over views and normals leaning up to 80 degrees every way: a normal whose mirror image
    /// of the view leaves above the threshold is kept; any other is bent, unit, within the
    /// plane of it and the surface's normal, toward the latter, and its mirror image leaves at
    /// the threshold (to 1e-4).
    #[test]
    fn a_bent_normal_reflects_the_view_above_the_surface() {
        let ng = Vec3::Z;
        let mut bent = 0;
        for i in 0..40 {
            for j in 0..40 {
                let view = (i as f32 + 0.5) / 40.0 * 1.5;
                let lean = (j as f32 + 0.5) / 40.0 * 1.4;
                let wo = Vec3::new(view.sin(), 0.0, view.cos());
                for azimuth in [0.0f32, 1.0, 2.5, 3.0] {
                    let n = Vec3::new(
                        lean.sin() * azimuth.cos(),
                        lean.sin() * azimuth.sin(),
                        lean.cos(),
                    );
                    let out = valid_reflection(ng, wo, n);
                    let threshold = (0.9 * wo.z).min(0.01);
                    let reflected = |n: Vec3| (2.0 * n.dot(wo) * n - wo).z;
                    if reflected(n) >= threshold {
                        assert_eq!(out, n);
                        continue;
                    }
                    bent += 1;
                    assert!((out.length() - 1.0).abs() < 1e-5, "{out}");
                    assert!(out.z > n.z, "{n} -> {out}: not toward the surface's normal");
                    assert!(
                        n.cross(ng).dot(out).abs() < 1e-4,
                        "{n} -> {out}: out of plane"
                    );
                    assert!(
                        (reflected(out) - threshold).abs() < 1e-4,
                        "view {view}, {n} -> {out}: leaves at {} against {threshold}",
                        reflected(out)
                    );
                }
            }
        }
        assert!(bent > 500, "{bent} bent");
    }
}
