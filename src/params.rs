//! Parameter values as scene files give them, checked as they are read: finite numbers,
//! vectors, colours (none negative) and albedos (within [0, 1]). Materials and shapes receive
//! their parameters through these (`checked::albedo` and the like) and the scene file's parser
//! builds on them; neither plugin imports the parser (as pbrt-v4's plugins receive a
//! `ParameterDictionary`).

use glam::Vec3;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// A finite number (TOML allows `nan` and `inf`; a scene must not).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Num(pub f32);

impl<'de> Deserialize<'de> for Num {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let x = f64::deserialize(d)?;
        if !x.is_finite() || x.abs() > f32::MAX as f64 {
            return Err(serde::de::Error::custom(format!(
                "expected a finite number, got {x}"
            )));
        }
        Ok(Num(x as f32))
    }
}

impl Serialize for Num {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        // The shortest decimal that reads back as the same f32 (0.65, not 0.6499999761581421).
        let shortest: f64 = self.0.to_string().parse().unwrap_or(self.0 as f64);
        shortest.serialize(s)
    }
}

/// Three finite numbers `[x, y, z]`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct V3(pub [Num; 3]);

impl<'de> Deserialize<'de> for V3 {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let values = Vec::<Num>::deserialize(d)?;
        let array: [Num; 3] = values.try_into().map_err(|v: Vec<Num>| {
            serde::de::Error::custom(format!("expected 3 numbers [x, y, z], got {}", v.len()))
        })?;
        Ok(V3(array))
    }
}

impl V3 {
    pub fn vec(self) -> Vec3 {
        Vec3::new(self.0[0].0, self.0[1].0, self.0[2].0)
    }
    pub fn from(v: Vec3) -> Self {
        V3([Num(v.x), Num(v.y), Num(v.z)])
    }
}

/// A colour: three finite numbers, none negative.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Colour(pub V3);

impl<'de> Deserialize<'de> for Colour {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = V3::deserialize(d)?;
        if v.0.iter().any(|c| c.0 < 0.0) {
            return Err(serde::de::Error::custom(
                "expected a colour with no negative component",
            ));
        }
        Ok(Colour(v))
    }
}

/// A reflectance: a colour with every component in [0, 1] (more would create energy).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Albedo(pub V3);

impl<'de> Deserialize<'de> for Albedo {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let v = V3::deserialize(d)?;
        if v.0.iter().any(|c| !(0.0..=1.0).contains(&c.0)) {
            return Err(serde::de::Error::custom(
                "expected an albedo with every component in [0, 1]",
            ));
        }
        Ok(Albedo(v))
    }
}

/// Checked values as serde `with` modules, for the plain-data types that scene files describe
/// directly (materials, shapes): `#[serde(with = "checked::albedo")] albedo: Vec3`.
pub mod checked {
    use super::{Albedo, Colour, Num, V3};
    use glam::Vec3;
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    /// A finite number.
    pub mod number {
        use super::*;
        pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<f32, D::Error> {
            Num::deserialize(d).map(|n| n.0)
        }
        pub fn serialize<S: Serializer>(x: &f32, s: S) -> Result<S::Ok, S::Error> {
            Num(*x).serialize(s)
        }
    }

    /// A colour: three finite numbers, none negative.
    pub mod colour {
        use super::*;
        pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec3, D::Error> {
            Colour::deserialize(d).map(|c| c.0.vec())
        }
        pub fn serialize<S: Serializer>(v: &Vec3, s: S) -> Result<S::Ok, S::Error> {
            V3::from(*v).serialize(s)
        }
    }

    /// A reflectance: a colour with every component in [0, 1].
    pub mod albedo {
        use super::*;
        pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec3, D::Error> {
            Albedo::deserialize(d).map(|a| a.0.vec())
        }
        pub fn serialize<S: Serializer>(v: &Vec3, s: S) -> Result<S::Ok, S::Error> {
            V3::from(*v).serialize(s)
        }
    }

    /// Three finite numbers `[x, y, z]`: a point or a vector.
    pub mod vector {
        use super::*;
        pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec3, D::Error> {
            V3::deserialize(d).map(V3::vec)
        }
        pub fn serialize<S: Serializer>(v: &Vec3, s: S) -> Result<S::Ok, S::Error> {
            V3::from(*v).serialize(s)
        }
    }

    /// For `skip_serializing_if`: an all-zero colour is the default.
    pub fn is_black(v: &Vec3) -> bool {
        *v == Vec3::ZERO
    }
}
