//! The SPIR-V modules that build.rs compiled from `glsl/`, by name (path under `glsl/`).

include!(concat!(env!("OUT_DIR"), "/shaders.rs"));

pub fn get(name: &str) -> Option<&'static [u8]> {
    ALL.iter().find(|(n, _)| *n == name).map(|(_, b)| *b)
}
