//! A material's own GPU parameters: each material kind declares them once with
//! [`material_params!`] (its file in `src/material/`), which gives the Rust struct its `gpu`
//! method fills, how it packs into `GpuMaterial::params`, and the WGSL struct of the same name
//! with the functions that read and write it: `<name>_params(m: Material)` and
//! `<name>_with_params(m, p)`. The kernel's material code reads its parameters by name, never
//! by a slot shared with the other kinds; the kernel-against-CPU tests of every material's
//! `sample`, `eval` and `pdf` (`tests/it/bsdfs`) check what it reads.

/// The 32-bit words `GpuMaterial::params` holds: enough for the largest kind's parameters.
pub const PARAM_WORDS: usize = 20;

/// What [`material_params!`] gives a material's parameters.
pub trait MaterialParams: bytemuck::Pod {
    /// The WGSL struct's name: the Rust one.
    const WGSL_NAME: &'static str;
    /// (name, WGSL type, words) of every field, in order.
    fn fields() -> &'static [(&'static str, &'static str, usize)];

    /// The words of `GpuMaterial::params`, unused ones 0.
    fn words(&self) -> [[u32; 4]; PARAM_WORDS / 4] {
        let mine = bytemuck::bytes_of(self);
        let mut words = [0u32; PARAM_WORDS];
        bytemuck::cast_slice_mut::<u32, u8>(&mut words)[..mine.len()].copy_from_slice(mine);
        bytemuck::cast(words)
    }

    /// The WGSL declaration of the struct and of its reader and writer for the material named
    /// `material` (the kind's file name): word i is `params[i / 4]`'s component i % 4, read as
    /// the field's type (`u32` words as they are).
    fn wgsl(material: &str) -> String {
        use std::fmt::Write;
        const COMPONENTS: [&str; 4] = ["x", "y", "z", "w"];
        let slot = |i: usize| format!("params[{}].{}", i / 4, COMPONENTS[i % 4]);
        let name = Self::WGSL_NAME;
        let (mut declaration, mut reads, mut writes) = (String::new(), Vec::new(), String::new());
        let mut at = 0;
        for &(field, ty, words) in Self::fields() {
            let _ = writeln!(declaration, "    {field}: {ty},");
            let slots: Vec<String> = (at..at + words).map(slot).collect();
            let parts: Vec<String> = slots.iter().map(|s| format!("m.{s}")).collect();
            reads.push(match (ty, words) {
                ("u32", _) => parts.join(""),
                (_, 1) => format!("bitcast<{ty}>({})", parts[0]),
                _ => format!("bitcast<{ty}>(vec{words}u({}))", parts.join(", ")),
            });
            for (i, s) in slots.iter().enumerate() {
                let value = match words {
                    1 => format!("p.{field}"),
                    _ => format!("p.{field}.{}", COMPONENTS[i]),
                };
                let value = match ty {
                    "u32" => value,
                    _ => format!("bitcast<u32>({value})"),
                };
                let _ = writeln!(writes, "    out.{s} = {value};");
            }
            at += words;
        }
        format!(
            "struct {name} {{\n{declaration}}}\n\nfn {material}_params(m: Material) -> {name} {{\n    return {name}({});\n}}\n\nfn {material}_with_params(m: Material, p: {name}) -> Material {{\n    var out = m;\n{writes}    return out;\n}}\n",
            reads.join(", ")
        )
    }
}

/// A material without parameters of its own (what it needs is in `GpuMaterial`'s shared
/// fields).
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable, PartialEq)]
#[repr(C)]
pub struct NoParams;

impl MaterialParams for NoParams {
    const WGSL_NAME: &'static str = "NoParams";
    fn fields() -> &'static [(&'static str, &'static str, usize)] {
        &[]
    }
    fn wgsl(_: &str) -> String {
        String::new()
    }
}

/// Defines a material's parameters: a `#[repr(C)]` Pod struct of `f32`, `u32` and `[f32; 3]`
/// fields (no padding: they pack into words in order; WGSL types as `layout::WgslType` names
/// them), at most [`PARAM_WORDS`] words, and its [`MaterialParams`].
macro_rules! material_params {
    (
        $(#[$meta:meta])*
        pub struct $name:ident {
            $($(#[$field_meta:meta])* $field:ident: $ty:ty,)*
        }
    ) => {
        $(#[$meta])*
        #[repr(C)]
        #[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable, PartialEq)]
        pub struct $name {
            $($(#[$field_meta])* pub $field: $ty,)*
        }

        const _: () = assert!(
            std::mem::size_of::<$name>() <= 4 * $crate::shared::params::PARAM_WORDS,
            "a material's parameters fit GpuMaterial::params"
        );

        impl $crate::shared::params::MaterialParams for $name {
            const WGSL_NAME: &'static str = stringify!($name);
            fn fields() -> &'static [(&'static str, &'static str, usize)] {
                &[$((
                    stringify!($field),
                    <$ty as $crate::shared::layout::WgslType>::WGSL,
                    std::mem::size_of::<$ty>() / 4,
                ),)*]
            }
        }
    };
}
pub(crate) use material_params;

#[cfg(test)]
mod tests {
    use super::*;

    material_params! {
        pub struct Example {
            first: [f32; 3],
            scalar: f32,
            second: [f32; 3],
            flag: u32,
        }
    }

    material_params! {
        pub struct Spanning {
            a: f32,
            b: f32,
            c: [f32; 3],
        }
    }

    #[test]
    fn fields_pack_into_words_in_order_and_wgsl_reads_them_there() {
        let p = Example {
            first: [1.0, 2.0, 3.0],
            scalar: 4.0,
            second: [5.0, 6.0, 7.0],
            flag: 9,
        };
        let words = p.words();
        assert_eq!(words[0], [1.0f32, 2.0, 3.0, 4.0].map(f32::to_bits));
        assert_eq!(
            words[1],
            [5.0f32.to_bits(), 6.0f32.to_bits(), 7.0f32.to_bits(), 9]
        );
        let wgsl = Example::wgsl("example");
        for expected in [
            "struct Example {\n    first: vec3f,\n    scalar: f32,\n    second: vec3f,\n    flag: u32,\n}",
            "fn example_params(m: Material) -> Example {\n    return Example(bitcast<vec3f>(vec3u(m.params[0].x, m.params[0].y, m.params[0].z)), bitcast<f32>(m.params[0].w), bitcast<vec3f>(vec3u(m.params[1].x, m.params[1].y, m.params[1].z)), m.params[1].w);",
            "    out.params[1].z = bitcast<u32>(p.second.z);\n    out.params[1].w = p.flag;\n    return out;",
        ] {
            assert!(wgsl.contains(expected), "{expected}\nnot in\n{wgsl}");
        }
        // A field across the two vec4s.
        let spanning = Spanning {
            a: 1.0,
            b: 2.0,
            c: [3.0, 4.0, 5.0],
        };
        let words = spanning.words();
        assert_eq!(words[0], [1.0f32, 2.0, 3.0, 4.0].map(f32::to_bits));
        assert_eq!(words[1], [5.0f32.to_bits(), 0, 0, 0]);
        assert!(words[2..].iter().all(|w| *w == [0; 4]));
        let wgsl = Spanning::wgsl("spanning");
        for expected in [
            "bitcast<vec3f>(vec3u(m.params[0].z, m.params[0].w, m.params[1].x))",
            "    out.params[0].w = bitcast<u32>(p.c.y);\n    out.params[1].x = bitcast<u32>(p.c.z);",
        ] {
            assert!(wgsl.contains(expected), "{expected}\nnot in\n{wgsl}");
        }
        assert_eq!(NoParams.words(), [[0; 4]; PARAM_WORDS / 4]);
        assert_eq!(NoParams::wgsl("medium"), "");
    }
}
