//! Where a scene's media are, and the checks that keep them well defined. The path loops track
//! the medium a ray is in by the boundaries it crosses, starting from "none" at the camera, so
//! every medium must fill a closed object (a sphere or a box), no two media may overlap, and the
//! camera must be outside all of them; but a purely absorbing medium inside a visible mesh
//! (glTF's KHR_materials_volume) is taken as the extension defines it, closed, unchecked.

use super::{Object, Scene, Shape};
use crate::shape::{SphereParams, SurfaceParams};
use glam::DVec3;

/// A closed object's interior in world space (f64: the checks are exact to far below what the
/// renderer resolves).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Region {
    Ball {
        center: DVec3,
        radius: f64,
    },
    /// A box rotated about +y by `angle` radians (the only rotation objects have).
    Block {
        center: DVec3,
        half: DVec3,
        angle: f64,
    },
}

impl Region {
    /// The region an object fills, if its shape is closed.
    fn of(object: &Object) -> Option<Region> {
        let t = object.transform;
        let place = |p: glam::Vec3| t.apply_point_relative(p, DVec3::ZERO).as_dvec3();
        match object.shape {
            Shape::Surface(SurfaceParams::Sphere(SphereParams { center, radius }))
                if radius > 0.0 =>
            {
                Some(Region::Ball {
                    center: place(center),
                    radius: radius as f64,
                })
            }
            Shape::Cuboid { min, max } => Some(Region::Block {
                center: place((min + max) * 0.5),
                half: (max.as_dvec3() - min.as_dvec3()) * 0.5,
                angle: (t.rotate_y_degrees as f64).to_radians(),
            }),
            _ => None,
        }
    }

    /// `v` in the block's own axes (the inverse of its rotation about y).
    fn to_local(angle: f64, v: DVec3) -> DVec3 {
        let (sin, cos) = angle.sin_cos();
        DVec3::new(cos * v.x - sin * v.z, v.y, sin * v.x + cos * v.z)
    }

    /// The block's local x and z axes in world space.
    fn axes(angle: f64) -> [DVec3; 2] {
        let (sin, cos) = angle.sin_cos();
        [DVec3::new(cos, 0.0, -sin), DVec3::new(sin, 0.0, cos)]
    }

    fn scale(&self) -> f64 {
        match *self {
            Region::Ball { center, radius } => center.abs().max_element() + radius,
            Region::Block { center, half, .. } => center.abs().max_element() + half.max_element(),
        }
    }

    /// Whether `p` is strictly inside, by more than `margin`.
    fn contains(&self, p: DVec3, margin: f64) -> bool {
        match *self {
            Region::Ball { center, radius } => (p - center).length() < radius - margin,
            Region::Block {
                center,
                half,
                angle,
            } => {
                let local = Region::to_local(angle, p - center).abs();
                local.cmplt(half - DVec3::splat(margin)).all()
            }
        }
    }

    /// Whether the interiors overlap by more than `margin` (touching surfaces do not).
    fn overlaps(&self, other: &Region, margin: f64) -> bool {
        match (*self, *other) {
            (
                Region::Ball {
                    center: a,
                    radius: ra,
                },
                Region::Ball {
                    center: b,
                    radius: rb,
                },
            ) => (a - b).length() < ra + rb - margin,
            (
                Region::Ball { center, radius },
                Region::Block {
                    center: c,
                    half,
                    angle,
                },
            )
            | (
                Region::Block {
                    center: c,
                    half,
                    angle,
                },
                Region::Ball { center, radius },
            ) => {
                let local = Region::to_local(angle, center - c);
                let closest = local.clamp(-half, half);
                (local - closest).length() < radius - margin
            }
            (
                Region::Block {
                    center: ca,
                    half: ha,
                    angle: aa,
                },
                Region::Block {
                    center: cb,
                    half: hb,
                    angle: ab,
                },
            ) => {
                // Both are upright: apart in y, or along one of the four horizontal axes of
                // their faces (the separating axis theorem in the xz-plane).
                let d = cb - ca;
                if d.y.abs() >= ha.y + hb.y - margin {
                    return false;
                }
                let (xa, xb) = (Region::axes(aa), Region::axes(ab));
                let extent = |half: DVec3, axes: [DVec3; 2], along: DVec3| {
                    half.x * axes[0].dot(along).abs() + half.z * axes[1].dot(along).abs()
                };
                !xa.iter().chain(&xb).any(|&axis| {
                    d.dot(axis).abs() >= extent(ha, xa, axis) + extent(hb, xb, axis) - margin
                })
            }
        }
    }
}

/// The media problems of `scene`, as (index of the object it is found at, message).
pub fn check(scene: &Scene) -> Result<(), (usize, String)> {
    let mut filled: Vec<(usize, Region)> = Vec::new();
    for (i, object) in scene.objects.iter().enumerate() {
        let material = &scene.materials[object.material as usize];
        let Some(interior) = material.interior() else {
            continue;
        };
        // glTF's volumes: an absorbing inside of a visible surface (glass), which the
        // extension asks be closed. A mesh is taken as closed; where it is not, the light
        // that leaves through a hole is absorbed (finitely: nothing scatters in the open), and
        // its camera and overlaps go unchecked.
        if matches!(object.shape, Shape::Mesh { .. })
            && interior.density == 0.0
            && !material.is_invisible()
        {
            continue;
        }
        let name = scene
            .material_names
            .get(object.material as usize)
            .map_or("?", String::as_str);
        let Some(region) = Region::of(object) else {
            let shape: String = match object.shape {
                Shape::Surface(SurfaceParams::Sphere(_)) => "an inward-facing sphere".into(),
                Shape::Surface(params) => format!("an open {}", params.name()),
                Shape::Mesh { .. } => "a mesh".into(),
                Shape::Cuboid { .. } => "a box".into(),
            };
            return Err((
                i,
                format!(
                    "material \"{name}\" fills its object with a medium, which needs a closed sphere or box, not {shape}"
                ),
            ));
        };
        let margin = 1e-6 * region.scale();
        if region.contains(scene.camera.look_from.as_dvec3(), -margin) {
            return Err((
                i,
                format!(
                    "the camera is inside (or on) this object's medium (material \"{name}\"): the camera must be outside every medium"
                ),
            ));
        }
        for (j, other) in &filled {
            if region.overlaps(other, margin.max(1e-6 * other.scale())) {
                return Err((
                    i,
                    format!(
                        "this object's medium (material \"{name}\") overlaps the medium of object {j}: media may not overlap"
                    ),
                ));
            }
        }
        filled.push((i, region));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn block(center: [f64; 3], half: [f64; 3], degrees: f64) -> Region {
        Region::Block {
            center: DVec3::from(center),
            half: DVec3::from(half),
            angle: degrees.to_radians(),
        }
    }

    #[test]
    fn rotated_blocks_overlap_only_when_they_do() {
        let a = block([0.0, 0.0, 0.0], [1.0, 1.0, 1.0], 0.0);
        // Touching faces do not overlap; a little closer does.
        assert!(!a.overlaps(&block([2.0, 0.0, 0.0], [1.0, 1.0, 1.0], 0.0), 1e-9));
        assert!(a.overlaps(&block([1.99, 0.0, 0.0], [1.0, 1.0, 1.0], 0.0), 1e-9));
        // A cube turned 45 degrees reaches sqrt(2) along x.
        assert!(a.overlaps(&block([2.3, 0.0, 0.0], [1.0, 1.0, 1.0], 45.0), 1e-9));
        assert!(!a.overlaps(&block([2.5, 0.0, 0.0], [1.0, 1.0, 1.0], 45.0), 1e-9));
        // Apart in y.
        assert!(!a.overlaps(&block([0.0, 2.5, 0.0], [1.0, 1.0, 1.0], 30.0), 1e-9));
        // The Cornell box's two boxes, placed as the scene file places them: their bounding
        // boxes overlap, they do not.
        let placed = |max: [f32; 3], degrees: f32, translate: [f32; 3]| {
            Region::of(&Object {
                shape: Shape::Cuboid {
                    min: glam::Vec3::ZERO,
                    max: glam::Vec3::from(max),
                },
                material: 0,
                transform: crate::scene::Transform {
                    rotate_y_degrees: degrees,
                    translate: glam::Vec3::from(translate),
                },
            })
            .expect("a box is closed")
        };
        let tall = placed([165.0, 330.0, 165.0], 15.0, [265.0, 0.0, 295.0]);
        let short = placed([165.0, 165.0, 165.0], -18.0, [130.0, 0.0, 65.0]);
        assert!(!tall.overlaps(&short, 1e-6));
    }

    #[test]
    fn balls_and_blocks() {
        let a = block([0.0, 0.0, 0.0], [1.0, 1.0, 1.0], 0.0);
        let ball = |x: f64, r: f64| Region::Ball {
            center: DVec3::new(x, 0.0, 0.0),
            radius: r,
        };
        assert!(a.overlaps(&ball(1.5, 0.6), 1e-9));
        assert!(!a.overlaps(&ball(1.5, 0.5), 1e-9));
        assert!(ball(0.0, 1.0).overlaps(&ball(1.9, 1.0), 1e-9));
        assert!(!ball(0.0, 1.0).overlaps(&ball(2.0, 1.0), 1e-9));
        assert!(a.contains(DVec3::new(0.9, 0.9, -0.9), 0.0));
        assert!(!a.contains(DVec3::new(1.1, 0.0, 0.0), 0.0));
        assert!(block([0.0; 3], [1.0; 3], 45.0).contains(DVec3::new(1.3, 0.0, 0.0), 0.0));
    }
}
