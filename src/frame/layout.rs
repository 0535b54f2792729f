//! What Rust and the shaders share, from its one declaration (`layout.in.rs`): the std430
//! structs (`GpuView`, `GpuMaterial`, `GpuObject`, `GpuLight`), the push constants (`Push`,
//! `SearchKnobs`), the consts (`KIND_*`, `LIGHT_*`, `MAP_SHADING_*`, `FLAG_*`) and the
//! descriptor bindings (`BINDINGS`, `MAP_BINDINGS`, `binding::*`). build.rs reads the same
//! declaration (build/layout.rs), checks that std430 and `repr(C)` agree on every offset,
//! and writes the GLSL twin that glsl/common/scene.glsl includes (`generated/layout.glsl`).

/// The Rust type of a declared (GLSL) field type.
macro_rules! rust_ty {
    (float) => {
        f32
    };
    (int) => {
        i32
    };
    (uint) => {
        u32
    };
    (vec3) => {
        [f32; 3]
    };
    (vec4) => {
        [f32; 4]
    };
    (uvec4) => {
        [u32; 4]
    };
    (mat4) => {
        [[f32; 4]; 4]
    };
    ([$t:tt; $n:literal]) => {
        [rust_ty!($t); $n]
    };
    ($s:ident) => {
        $s
    };
}

macro_rules! gpu_structs {
    ($(
        $(#[doc = $doc:literal])*
        struct $rust:ident => $kind:ident $glsl:ident $($instance:ident)? {
            $( $(#[doc = $fdoc:literal])* $field:ident : $ty:tt ),* $(,)?
        }
    )*) => {
        $(
            $(#[doc = $doc])*
            #[repr(C)]
            #[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
            pub struct $rust {
                $( $(#[doc = $fdoc])* pub $field: rust_ty!($ty), )*
            }
        )*

        /// Every shared struct as Rust lays it out: (name, size, [(field, offset)]), for the
        /// test that compares it with the generator's std430 offsets (tests/layout.rs).
        #[doc(hidden)]
        pub const RUST_LAYOUTS: &[(&str, usize, &[(&str, usize)])] = &[$(
            (
                stringify!($rust),
                std::mem::size_of::<$rust>(),
                &[$( (stringify!($field), std::mem::offset_of!($rust, $field)) ),*],
            )
        ),*];
    };
}

macro_rules! gpu_consts {
    ($( $(#[doc = $doc:literal])* $name:ident : $ty:tt = $value:literal; )*) => {
        $( $(#[doc = $doc])* pub const $name: rust_ty!($ty) = $value; )*
    };
}

macro_rules! descriptor_sets {
    ($(
        $(#[doc = $doc:literal])*
        $set_name:ident = set $set:literal {
            $( $(#[doc = $bdoc:literal])* $name:ident = $binding:literal : $ty:ident => $decl:literal; )*
        }
    )*) => {
        $(
            $(#[doc = $doc])*
            pub const $set_name: &[crate::vk::pipeline::Binding] = &[$( ($binding, ash::vk::DescriptorType::$ty, 1) ),*];
        )*

        /// Binding numbers, by the name of what they bind.
        pub mod binding {
            $($( $(#[doc = $bdoc])* #[doc = concat!("`", $decl, "`")] pub const $name: u32 = $binding; )*)*
        }
    };
}

include!("layout.in.rs");
