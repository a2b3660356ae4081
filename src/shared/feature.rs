//! The kernel's material features: what a material kind, or one of its instances, needs the
//! kernel to hold. Materials declare them (`material::MaterialModel::FEATURE` and
//! `extra_features`), the kernel builder turns on each one a scene uses, and each is the
//! `//#if NAME` switch of the WGSL it guards: a feature misspelt in Rust does not compile, and
//! one misspelt in a `.wgsl` file is an error where the kernel is composed.

/// The enum, its list in bit order and each one's `//#if` name, from one table.
macro_rules! material_features {
    ($($(#[$doc:meta])* $variant:ident = $name:literal,)+) => {
        /// A material feature; its bit in the kernel's features is `1 << (self as u32)`.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub enum MaterialFeature {
            $($(#[$doc])* $variant,)+
        }

        impl MaterialFeature {
            /// Every feature, in bit order.
            pub const ALL: &'static [MaterialFeature] = &[$(MaterialFeature::$variant,)+];

            /// Its `//#if` name.
            pub const fn name(self) -> &'static str {
                match self {
                    $(MaterialFeature::$variant => $name,)+
                }
            }
        }
    };
}

material_features! {
    // Each material kind's own (the kind's file name, upper case).
    Lambertian = "LAMBERTIAN",
    Metal = "METAL",
    Dielectric = "DIELECTRIC",
    Light = "LIGHT",
    Conductor = "CONDUCTOR",
    Plastic = "PLASTIC",
    Pbr = "PBR",
    Medium = "MEDIUM",
    // What some instances need beyond their kind's.
    /// A lambertian surface that glows.
    Emissive = "EMISSIVE",
    /// A solid checker (in space).
    Checker = "CHECKER",
    /// A checker in surface (UV) coordinates.
    UvChecker = "UV_CHECKER",
    /// An image looked up at surface coordinates.
    ImageTexture = "IMAGE_TEXTURE",
    /// A rough (GGX) lobe.
    Microfacet = "MICROFACET",
    /// A medium inside some object.
    Media = "MEDIA",
    /// A see-through surface (glTF's alpha).
    Alpha = "ALPHA",
    /// pbr's metallic-roughness image.
    MetallicRoughness = "METALLIC_ROUGHNESS",
    /// pbr's layer images (its clear coat's and sheen's textures).
    LayerImages = "LAYER_IMAGES",
    /// pbr's emission on top of what it reflects.
    PbrEmission = "PBR_EMISSION",
    /// A rough plastic coat's table.
    CoatTable = "COAT_TABLE",
    Clearcoat = "CLEARCOAT",
    Absorption = "ABSORPTION",
    Sheen = "SHEEN",
    Specular = "SPECULAR",
}

impl MaterialFeature {
    /// The feature named `name` (a `//#if` name), if there is one.
    pub fn named(name: &str) -> Option<Self> {
        Self::ALL.iter().copied().find(|f| f.name() == name)
    }

    /// Its bit in a set of features.
    pub const fn bit(self) -> u32 {
        1 << self as u32
    }

    /// Whether it looks something up at surface (UV) coordinates: hits then compute them (the
    /// kernel's derived switch `READS_UVS`, with normal maps).
    pub const fn reads_uvs(self) -> bool {
        matches!(
            self,
            MaterialFeature::UvChecker
                | MaterialFeature::ImageTexture
                | MaterialFeature::MetallicRoughness
                | MaterialFeature::LayerImages
        )
    }
}

impl std::fmt::Display for MaterialFeature {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn all_lists_each_feature_once_in_bit_order_under_its_own_name() {
        for (i, &f) in MaterialFeature::ALL.iter().enumerate() {
            assert_eq!(f as usize, i, "{f:?}");
            assert_eq!(MaterialFeature::named(f.name()), Some(f));
            let shout = format!("{f:?}")
                .chars()
                .flat_map(|c| {
                    let gap = c.is_uppercase().then_some('_');
                    gap.into_iter().chain(c.to_uppercase())
                })
                .collect::<String>();
            assert_eq!(shout.trim_start_matches('_'), f.name());
        }
        assert_eq!(MaterialFeature::named("MEDIUMS"), None);
    }
}
