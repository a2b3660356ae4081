//! Which primitive a hit is on, as both backends name it: a kind and an index, packed into one
//! `u32` for the kernel.

/// A primitive of a flat scene: its kind and its index among the primitives of that kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PrimitiveRef {
    Sphere(u32),
    Quad(u32),
    Triangle(u32),
    /// A placed mesh (in the top level of the BVH; a hit on one of its triangles is reported as
    /// a hit on the instance).
    Instance(u32),
}

/// A packed [`PrimitiveRef`] (as the kernel passes it) holds the kind above this many bits of
/// index.
pub const PRIMITIVE_INDEX_BITS: u32 = 28;
/// Most primitives of one kind a scene may have.
pub const MAX_PRIMITIVES_PER_KIND: usize = 1 << PRIMITIVE_INDEX_BITS;
pub const KIND_SPHERE: u32 = 0;
pub const KIND_QUAD: u32 = 1;
pub const KIND_TRIANGLE: u32 = 2;
pub const KIND_INSTANCE: u32 = 3;

impl PrimitiveRef {
    /// One number for both backends: kind << PRIMITIVE_INDEX_BITS | index.
    pub fn packed(self) -> u32 {
        match self {
            PrimitiveRef::Sphere(i) => KIND_SPHERE << PRIMITIVE_INDEX_BITS | i,
            PrimitiveRef::Quad(i) => KIND_QUAD << PRIMITIVE_INDEX_BITS | i,
            PrimitiveRef::Triangle(i) => KIND_TRIANGLE << PRIMITIVE_INDEX_BITS | i,
            PrimitiveRef::Instance(i) => KIND_INSTANCE << PRIMITIVE_INDEX_BITS | i,
        }
    }

    /// The reference `packed` came from, if it is one.
    pub fn unpacked(packed: u32) -> Option<Self> {
        let index = packed & ((1 << PRIMITIVE_INDEX_BITS) - 1);
        match packed >> PRIMITIVE_INDEX_BITS {
            KIND_SPHERE => Some(PrimitiveRef::Sphere(index)),
            KIND_QUAD => Some(PrimitiveRef::Quad(index)),
            KIND_TRIANGLE => Some(PrimitiveRef::Triangle(index)),
            KIND_INSTANCE => Some(PrimitiveRef::Instance(index)),
            _ => None,
        }
    }
}
