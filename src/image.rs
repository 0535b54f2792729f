//! Images on the CPU: [`ImageData`], the f32 texels every renderer produces (the GPU's
//! readback, the CPU reference) and the metrics compare, with its file encoders.

use std::path::Path;

use crate::error::Result;

/// Texels of an image, layer after layer, row after row; `channels` per texel.
#[derive(Clone, Debug, PartialEq)]
pub struct ImageData {
    pub width: u32,
    pub height: u32,
    pub layers: u32,
    pub channels: u32,
    pub data: Vec<f32>,
}

impl ImageData {
    pub fn texel(&self, layer: u32, x: u32, y: u32) -> &[f32] {
        let c = self.channels as usize;
        let i = ((layer * self.height + y) * self.width + x) as usize * c;
        &self.data[i..i + c]
    }

    /// Writes the texels (one RGBA layer) as linear radiance to an OpenEXR file.
    pub fn write_exr(&self, path: &Path) -> Result<()> {
        crate::scene::write_exr(path, self.width, self.height, &self.data)
    }

    /// Writes the texels (one RGBA layer) sRGB-encoded and clamped to an 8-bit PNG.
    pub fn write_png_srgb(&self, path: &Path) -> Result<()> {
        crate::scene::write_png_srgb(path, self.width, self.height, &self.data)
    }
}
