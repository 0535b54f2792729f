//! Environment maps in and rendered images out.
//!
//! `load_environment` reads an equirectangular linear-radiance image: OpenEXR through the
//! `exr` crate, Radiance `.hdr` (linear) and 8/16-bit PNG/JPEG (sRGB-encoded, decoded to
//! linear) through the `image` crate. Negative radiance is clamped to 0; NaN or infinite
//! pixels are an error.

use std::path::Path;

use super::EnvironmentMap;
use crate::error::{Error, Result};

/// sRGB-encoded 8-bit value → linear [0, 1].
pub fn srgb_to_linear(v: u8) -> f32 {
    srgb_decode(v as f32 / 255.0)
}

/// Linear value → sRGB-encoded 8-bit value, clamped to [0, 1] first (NaN → 0).
pub fn linear_to_srgb(v: f32) -> u8 {
    let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    let e = if v <= 0.003_130_8 { 12.92 * v } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 };
    (e * 255.0 + 0.5).clamp(0.0, 255.0) as u8
}

fn srgb_decode(e: f32) -> f32 {
    if e <= 0.040_45 {
        e / 12.92
    } else {
        ((e + 0.055) / 1.055).powf(2.4)
    }
}

fn image_error(path: &Path, e: image::ImageError) -> Error {
    match e {
        image::ImageError::IoError(io) => Error::io(path, io),
        other => Error::Image(format!("{}: {other}", path.display())),
    }
}

fn exr_error(path: &Path, e: exr::error::Error) -> Error {
    match e {
        exr::error::Error::Io(io) => Error::io(path, io),
        other => Error::Image(format!("{}: {other}", path.display())),
    }
}

/// How large an image a loader accepts, checked against the file's declared size before
/// any pixel is allocated (a small file may declare a huge image).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoadLimits {
    /// Longest edge in pixels.
    pub max_edge: u32,
    /// Most pixels (width × height); decoded as RGBA32F, 16 bytes each.
    pub max_pixels: u64,
}

impl Default for LoadLimits {
    /// 16384 pixels an edge, 64 Mpixels (1 GiB of RGBA32F).
    fn default() -> LoadLimits {
        LoadLimits { max_edge: 16384, max_pixels: 64 << 20 }
    }
}

impl LoadLimits {
    /// Refuses a declared `width`×`height` beyond the limits, naming the file.
    pub fn check(&self, what: &str, width: u64, height: u64) -> Result<()> {
        if width > self.max_edge as u64 || height > self.max_edge as u64 || width.saturating_mul(height) > self.max_pixels {
            return Err(Error::Image(format!(
                "{what}: declares {width}×{height} pixels, beyond the loader's limits ({} pixels an edge, {} pixels)",
                self.max_edge, self.max_pixels
            )));
        }
        Ok(())
    }

    /// The `image` crate's limits for the same bounds.
    pub fn image_limits(&self) -> image::Limits {
        let mut l = image::Limits::default();
        l.max_image_width = Some(self.max_edge);
        l.max_image_height = Some(self.max_edge);
        l.max_alloc = Some(self.max_pixels.saturating_mul(16));
        l
    }
}

/// Loads an equirectangular environment map as linear RGBA32F radiance, within the
/// default `LoadLimits`.
pub fn load_environment(path: &Path) -> Result<EnvironmentMap> {
    load_environment_with(path, &LoadLimits::default())
}

/// `load_environment` within `limits`.
pub fn load_environment_with(path: &Path, limits: &LoadLimits) -> Result<EnvironmentMap> {
    // Report a missing file as such, whatever the decoder would say.
    std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
    let (width, height, mut rgba32f) = if ext == "exr" {
        // The header first: its data window is the size the pixels would take.
        let meta = exr::meta::MetaData::read_from_file(path, false).map_err(|e| exr_error(path, e))?;
        for h in meta.headers.iter() {
            limits.check(&path.display().to_string(), h.layer_size.width() as u64, h.layer_size.height() as u64)?;
        }
        let image = exr::prelude::read_first_rgba_layer_from_file(
            path,
            |resolution, _| (resolution.width(), vec![0f32; resolution.width() * resolution.height() * 4]),
            |(w, pixels): &mut (usize, Vec<f32>), pos, (r, g, b, a): (f32, f32, f32, f32)| {
                let i = (pos.y() * *w + pos.x()) * 4;
                pixels[i..i + 4].copy_from_slice(&[r, g, b, a]);
            },
        )
        .map_err(|e| exr_error(path, e))?;
        let size = image.layer_data.size;
        let (_, pixels) = image.layer_data.channel_data.pixels;
        (size.width() as u32, size.height() as u32, pixels)
    } else {
        let open = || -> Result<image::ImageReader<std::io::BufReader<std::fs::File>>> {
            image::ImageReader::open(path).map_err(|e| Error::io(path, e))?.with_guessed_format().map_err(|e| Error::io(path, e))
        };
        // The header's declared size first, in the loader's words.
        let (w, h) = open()?.into_dimensions().map_err(|e| image_error(path, e))?;
        limits.check(&path.display().to_string(), w as u64, h as u64)?;
        let mut reader = open()?;
        reader.limits(limits.image_limits());
        let img = reader.decode().map_err(|e| image_error(path, e))?;
        let (w, h) = (img.width(), img.height());
        let linear = matches!(img.color(), image::ColorType::Rgb32F | image::ColorType::Rgba32F);
        let mut data = img.into_rgba32f().into_raw();
        if !linear {
            for px in data.chunks_exact_mut(4) {
                for c in &mut px[..3] {
                    *c = srgb_decode(*c);
                }
            }
        }
        (w, h, data)
    };
    if width == 0 || height == 0 {
        return Err(Error::Image(format!("{}: empty image ({width}×{height})", path.display())));
    }
    if let Some(i) = rgba32f.iter().position(|v| !v.is_finite()) {
        let px = i / 4;
        return Err(Error::Image(format!(
            "{}: pixel ({}, {}) is not finite ({})",
            path.display(),
            px as u32 % width,
            px as u32 / width,
            rgba32f[i]
        )));
    }
    for v in &mut rgba32f {
        *v = v.max(0.0);
    }
    Ok(EnvironmentMap { width, height, rgba32f })
}

fn check_size(path: &Path, width: u32, height: u32, rgba32f: &[f32]) -> Result<()> {
    let expected = width as usize * height as usize * 4;
    if width == 0 || height == 0 || rgba32f.len() != expected {
        return Err(Error::invalid(
            format!("image {}", path.display()),
            format!("{width}×{height} RGBA needs {expected} floats, got {}", rgba32f.len()),
        ));
    }
    Ok(())
}

/// Writes linear RGBA32F pixels (row-major, top row first) as an OpenEXR file.
pub fn write_exr(path: &Path, width: u32, height: u32, rgba32f: &[f32]) -> Result<()> {
    check_size(path, width, height, rgba32f)?;
    use exr::prelude::{Image, SpecificChannels, Vec2, WritableImage};
    let w = width as usize;
    let channels = SpecificChannels::rgba(|Vec2(x, y): Vec2<usize>| {
        let i = (y * w + x) * 4;
        (rgba32f[i], rgba32f[i + 1], rgba32f[i + 2], rgba32f[i + 3])
    });
    let image = Image::from_channels((w, height as usize), channels);
    let mut bytes = std::io::Cursor::new(Vec::new());
    image.write().to_buffered(&mut bytes).map_err(|e| exr_error(path, e))?;
    crate::output::write_file(path, bytes.get_ref())
}

/// Writes linear RGBA32F pixels as an 8-bit sRGB-encoded PNG (clamped; alpha 255).
pub fn write_png_srgb(path: &Path, width: u32, height: u32, rgba32f: &[f32]) -> Result<()> {
    check_size(path, width, height, rgba32f)?;
    let bytes: Vec<u8> =
        rgba32f.chunks_exact(4).flat_map(|p| [linear_to_srgb(p[0]), linear_to_srgb(p[1]), linear_to_srgb(p[2]), 255]).collect();
    let mut png = Vec::new();
    image::ImageEncoder::write_image(image::codecs::png::PngEncoder::new(&mut png), &bytes, width, height, image::ExtendedColorType::Rgba8)
        .map_err(|e| image_error(path, e))?;
    crate::output::write_file(path, &png)
}
