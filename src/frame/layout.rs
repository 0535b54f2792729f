//! What Rust and the shaders share, from its declarations (the frame's in `layout.in.rs`,
//! each family's in `src/methods/<family>/layout.in.rs`): the std430 structs (`GpuView`,
//! `GpuMaterial`, `GpuObject`, `GpuLight`, the families' own), the push constants (`Push`
//! and the typed `Word`s of `Push.words`), the consts (`KIND_*`, `LIGHT_*`, `MAP_SHADING_*`, `FLAG_*`, …) and the
//! descriptor bindings (`BINDINGS`, `MAP_BINDINGS`, …, `binding::*`). build.rs concatenates the
//! declarations (build/layout.rs), checks that std430 and `repr(C)` agree on every offset and
//! that no two owners' push flags collide, and writes this Rust side and the GLSL twin that
//! glsl/common/scene.glsl includes (`generated/layout.glsl`).

include!(concat!(env!("OUT_DIR"), "/layout.rs"));
