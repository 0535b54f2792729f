//! Environment mapping (survey §3): `generate` rasterises each specular object's cube map
//! from its reference point with the object left out; `shade` looks the map up in the
//! reflected and refracted directions, ignoring the ray origin (§3.1).

pub mod generate;
pub mod shade;

pub use generate::EnvmapGenerate;
pub use shade::EnvmapShade;
