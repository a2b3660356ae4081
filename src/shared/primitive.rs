//! Which primitive a hit is on, as both backends name it: a kind and an index, packed into one
//! `u32` for the kernel.

/// A primitive of a flat scene: its kind and its index among the primitives of that kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PrimitiveRef {
    /// A sphere, a quad, a disk, ...: a shape of the registry in src/shape/, by its kind.
    Shape {
        kind: u32,
        index: u32,
    },
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
/// Kinds a packed reference can hold.
pub const PRIMITIVE_KINDS: u32 = 1 << (32 - PRIMITIVE_INDEX_BITS);
/// The kinds of meshes' primitives; the shapes' kinds are the others (`shape::kind_at`).
pub const KIND_TRIANGLE: u32 = 2;
pub const KIND_INSTANCE: u32 = 3;

impl PrimitiveRef {
    /// One number for both backends: kind << PRIMITIVE_INDEX_BITS | index.
    pub fn packed(self) -> u32 {
        let (kind, index) = match self {
            PrimitiveRef::Shape { kind, index } => (kind, index),
            PrimitiveRef::Triangle(i) => (KIND_TRIANGLE, i),
            PrimitiveRef::Instance(i) => (KIND_INSTANCE, i),
        };
        kind << PRIMITIVE_INDEX_BITS | index
    }

    /// The primitive of `kind` (a shape's, `KIND_TRIANGLE` or `KIND_INSTANCE`) and `index`.
    pub fn new(kind: u32, index: u32) -> Self {
        Self::unpacked(kind << PRIMITIVE_INDEX_BITS | index)
    }

    /// The reference `packed` came from.
    pub fn unpacked(packed: u32) -> Self {
        let index = packed & ((1 << PRIMITIVE_INDEX_BITS) - 1);
        match packed >> PRIMITIVE_INDEX_BITS {
            KIND_TRIANGLE => PrimitiveRef::Triangle(index),
            KIND_INSTANCE => PrimitiveRef::Instance(index),
            kind => PrimitiveRef::Shape { kind, index },
        }
    }
}
