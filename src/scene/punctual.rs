//! Punctual lights: a point, a spot, or a direction (the sun), lights of no area that only
//! next-event estimation finds (a ray never hits one). Radiometric units: a point or spot gives
//! its radiant intensity (W/sr, per colour channel), a directional light the irradiance on a
//! surface facing it (W/m^2). glTF's `KHR_lights_punctual` gives photometric units (candela and
//! lux), which `gltf_scene` divides by 683 lm/W, as Blender's exporter multiplied by it.
//!
//! A spot's falloff is the extension's: 1 inside the inner cone, 0 outside the outer, and
//! between them the square of the linear ramp in cos(angle) (its recommended
//! implementation).

use glam::Vec3;

/// The largest intensity or irradiance accepted (squares of radiance stay far from overflow).
pub const MAX_POWER: f32 = 1e12;
/// The smallest squared distance a point light's falloff divides by: I / d^2 stays finite (at
/// most 1e32) for a light touching a surface.
pub const MIN_DISTANCE_SQUARED: f32 = 1e-20;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Punctual {
    Point {
        position: Vec3,
        intensity: Vec3,
    },
    Spot {
        position: Vec3,
        /// Unit: where the spot points.
        direction: Vec3,
        intensity: Vec3,
        /// Half-angles of the cones, radians: 0 <= inner < outer <= pi / 2.
        inner: f32,
        outer: f32,
    },
    Directional {
        /// Unit: where the light travels (from the sun to the scene).
        direction: Vec3,
        irradiance: Vec3,
    },
}

impl Punctual {
    pub fn validate(&self) -> Result<(), String> {
        let colour = |what: &str, c: Vec3| {
            if c.is_finite() && c.min_element() >= 0.0 && c.max_element() <= MAX_POWER {
                Ok(())
            } else {
                Err(format!(
                    "a light's {what} must be three numbers in [0, {MAX_POWER:e}], got {c}"
                ))
            }
        };
        let unit = |what: &str, d: Vec3| {
            if d.is_finite() && (d.length() - 1.0).abs() < 1e-3 {
                Ok(())
            } else {
                Err(format!(
                    "a light's {what} must be a non-zero direction, got {d}"
                ))
            }
        };
        let position = |p: Vec3| {
            if p.is_finite() && p.abs().max_element() <= super::MAX_EXTENT {
                Ok(())
            } else {
                Err(format!(
                    "a light's position must lie within {:e} of the origin, got {p}",
                    super::MAX_EXTENT
                ))
            }
        };
        match *self {
            Punctual::Point {
                position: p,
                intensity,
            } => {
                position(p)?;
                colour("intensity", intensity)
            }
            Punctual::Spot {
                position: p,
                direction,
                intensity,
                inner,
                outer,
            } => {
                position(p)?;
                unit("direction", direction)?;
                colour("intensity", intensity)?;
                if !(0.0 <= inner && inner < outer && outer <= std::f32::consts::FRAC_PI_2) {
                    return Err(format!(
                        "a spot light's cones must have 0 <= inner < outer <= 90 degrees, got inner {} and outer {} degrees",
                        inner.to_degrees(),
                        outer.to_degrees()
                    ));
                }
                Ok(())
            }
            Punctual::Directional {
                direction,
                irradiance,
            } => {
                unit("direction", direction)?;
                colour("irradiance", irradiance)
            }
        }
    }

    /// The spot's falloff as a scale and offset on cos(angle) from its axis: `saturate(cos *
    /// scale + offset)`, squared. Worked out in f64, so that narrow cones (Blender's 1-degree
    /// spot: 1 - cos 0.5 degrees = 4e-5) keep their ramp; cones whose cosines f32 cannot tell
    /// apart get a step (scale 1e7: the ramp is narrower than cos's f32 resolution).
    pub fn spot_ramp(inner: f32, outer: f32) -> (f32, f32) {
        let (cos_inner, cos_outer) = ((inner as f64).cos(), (outer as f64).cos());
        let scale = 1.0 / (cos_inner - cos_outer).max(1e-7);
        (scale as f32, (-cos_outer * scale) as f32)
    }
}
