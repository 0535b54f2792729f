//! Environment mapping (survey §3) and, with distances stored alongside the radiance,
//! distance maps (§4): `generate` rasterises each specular object's cube map from its
//! reference point with the object left out. The shading passes are `methods::shade`.

pub mod generate;

pub use generate::{CubeMaps, MapKind};
