//! Image error metrics between a test image and a reference of the same size, over the
//! RGB channels of linear-radiance RGBA32F images (alpha is ignored):
//!
//! - RMSE: √(mean of squared channel differences);
//! - PSNR: 10 log10(1 / MSE) in dB, peak 1 = display white in linear radiance;
//! - maximum and 99th-percentile absolute channel difference;
//! - mean FLIP (NVIDIA's perceptual difference, the `nv-flip` crate, LDR-FLIP): both
//!   images as the PNG output shows them (clamped to [0, 1], sRGB-encoded to 8 bits),
//!   67 pixels per degree (a 0.7 m viewing distance from a 24" 4K monitor, FLIP's default).
//!
//! A NaN or infinite channel in either image counts as an infinite error: RMSE, maximum
//! and p99 are then ∞ and PSNR −∞ (a broken image never looks close).

use crate::error::{Error, Result};
use crate::image::ImageData;
use crate::scene::linear_to_srgb;

#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ImageErrors {
    pub rmse: f64,
    /// Peak signal-to-noise ratio in dB (peak 1); +∞ for identical images.
    pub psnr: f64,
    pub max_abs: f64,
    pub p99_abs: f64,
    /// Mean of the FLIP error map, in [0, 1].
    pub flip: f64,
}

impl std::fmt::Display for ImageErrors {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "RMSE {:.6}  PSNR {:.2} dB  max |Δ| {:.6}  p99 |Δ| {:.6}  mean FLIP {:.6}",
            self.rmse, self.psnr, self.max_abs, self.p99_abs, self.flip
        )
    }
}

fn check_same_size(test: &ImageData, reference: &ImageData) -> Result<()> {
    let dims = |i: &ImageData| (i.width, i.height, i.layers);
    if dims(test) != dims(reference) {
        return Err(Error::invalid(
            "compare",
            format!("sizes differ: {}x{} vs reference {}x{}", test.width, test.height, reference.width, reference.height),
        ));
    }
    for i in [test, reference] {
        if i.channels < 3 || i.data.len() != (i.width * i.height * i.layers * i.channels) as usize {
            return Err(Error::invalid("compare", "images must hold RGB(A) texels matching their size"));
        }
    }
    Ok(())
}

/// Absolute differences of every RGB channel (∞ where either value is not finite).
fn abs_differences(test: &ImageData, reference: &ImageData) -> Vec<f64> {
    let (ct, cr) = (test.channels as usize, reference.channels as usize);
    test.data
        .chunks_exact(ct)
        .zip(reference.data.chunks_exact(cr))
        .flat_map(|(a, b)| {
            (0..3).map(move |k| {
                let (x, y) = (a[k] as f64, b[k] as f64);
                if x.is_finite() && y.is_finite() {
                    (x - y).abs()
                } else {
                    f64::INFINITY
                }
            })
        })
        .collect()
}

/// RMSE, PSNR, maximum and p99 absolute error (no FLIP, which is the expensive one).
pub fn pixel_errors(test: &ImageData, reference: &ImageData) -> Result<(f64, f64, f64, f64)> {
    check_same_size(test, reference)?;
    let mut diffs = abs_differences(test, reference);
    let mse = diffs.iter().map(|d| d * d).sum::<f64>() / diffs.len() as f64;
    let rmse = mse.sqrt();
    let psnr = if mse == 0.0 { f64::INFINITY } else { -10.0 * mse.log10() };
    diffs.sort_by(|a, b| a.total_cmp(b));
    let max = diffs.last().copied().unwrap_or(0.0);
    // Nearest-rank 99th percentile.
    let rank = ((0.99 * diffs.len() as f64).ceil() as usize).clamp(1, diffs.len());
    let p99 = diffs[rank - 1];
    Ok((rmse, psnr, max, p99))
}

/// An error restricted to a set of pixels (issue 15: the error where a method acts).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct MaskedError {
    /// What the pixels are: an object's name, "specular" or "non-specular".
    pub name: String,
    pub pixels: usize,
    pub psnr: f64,
    pub rmse: f64,
}

/// PSNR and RMSE of `test` against `reference` over the pixels where `mask` holds
/// (`None` without pixels).
pub fn masked_error(test: &ImageData, reference: &ImageData, mask: &[bool], name: &str) -> Result<Option<MaskedError>> {
    check_same_size(test, reference)?;
    let pixels = (test.width * test.height) as usize;
    if mask.len() != pixels {
        return Err(Error::invalid("mask", format!("{} pixels for a {}x{} image", mask.len(), test.width, test.height)));
    }
    let diffs = abs_differences(test, reference);
    let (mut sum, mut n) = (0.0f64, 0usize);
    for (k, d) in diffs.chunks_exact(3).enumerate() {
        if mask[k] {
            sum += d.iter().map(|d| d * d).sum::<f64>();
            n += 1;
        }
    }
    if n == 0 {
        return Ok(None);
    }
    let mse = sum / (3 * n) as f64;
    let psnr = if mse == 0.0 { f64::INFINITY } else { -10.0 * mse.log10() };
    Ok(Some(MaskedError { name: name.to_string(), pixels: n, psnr, rmse: mse.sqrt() }))
}

/// The errors on each specular object's pixels, on all specular pixels and on the rest,
/// from the reference's first-hit ids (`reference::object_ids`: mesh + 1, 0 the sky, which
/// counts as non-specular). `specular[m]` and `names[m]` describe mesh m.
pub fn errors_by_object(
    test: &ImageData,
    reference: &ImageData,
    ids: &[u32],
    specular: &[bool],
    names: &[String],
) -> Result<Vec<MaskedError>> {
    let is_specular = |id: u32| id > 0 && specular.get(id as usize - 1).copied().unwrap_or(false);
    let mut out = Vec::new();
    for (m, name) in names.iter().enumerate().filter(|(m, _)| specular[*m]) {
        let mask: Vec<bool> = ids.iter().map(|&id| id == m as u32 + 1).collect();
        out.extend(masked_error(test, reference, &mask, name)?);
    }
    let mask: Vec<bool> = ids.iter().map(|&id| is_specular(id)).collect();
    out.extend(masked_error(test, reference, &mask, "specular")?);
    let rest: Vec<bool> = mask.iter().map(|s| !s).collect();
    out.extend(masked_error(test, reference, &rest, "non-specular")?);
    Ok(out)
}

/// The fraction of pixels whose ids agree, over the pixels of `b` that are not on an edge
/// (a pixel whose 3×3 neighbourhood in `b` holds one id only), and that count.
pub fn id_agreement(a: &[u32], b: &[u32], width: u32, height: u32) -> (f64, usize) {
    let (w, h) = (width as i64, height as i64);
    let (mut same, mut n) = (0usize, 0usize);
    for y in 0..h {
        for x in 0..w {
            let id = b[(y * w + x) as usize];
            let interior = (-1..=1).all(|dy| {
                (-1..=1).all(|dx| {
                    let (u, v) = (x + dx, y + dy);
                    u < 0 || v < 0 || u >= w || v >= h || b[(v * w + u) as usize] == id
                })
            });
            if interior {
                n += 1;
                same += (a[(y * w + x) as usize] == id) as usize;
            }
        }
    }
    (if n == 0 { 1.0 } else { same as f64 / n as f64 }, n)
}

/// The 8-bit sRGB RGB triples the PNG output would hold.
fn srgb8(img: &ImageData) -> Vec<u8> {
    let c = img.channels as usize;
    img.data
        .chunks_exact(c)
        .take((img.width * img.height) as usize)
        .flat_map(|p| [linear_to_srgb(p[0]), linear_to_srgb(p[1]), linear_to_srgb(p[2])])
        .collect()
}

/// The FLIP error map (one value in [0, 1] per pixel, row-major) of `test` against
/// `reference`.
pub fn flip_map(test: &ImageData, reference: &ImageData) -> Result<Vec<f32>> {
    check_same_size(test, reference)?;
    let (w, h) = (test.width, test.height);
    let r = nv_flip::FlipImageRgb8::with_data(w, h, &srgb8(reference));
    let t = nv_flip::FlipImageRgb8::with_data(w, h, &srgb8(test));
    let map = nv_flip::flip(r, t, nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    Ok(map.to_vec())
}

/// Every metric of the module.
pub fn compare(test: &ImageData, reference: &ImageData) -> Result<ImageErrors> {
    let (rmse, psnr, max_abs, p99_abs) = pixel_errors(test, reference)?;
    let map = flip_map(test, reference)?;
    let flip = map.iter().map(|&v| v as f64).sum::<f64>() / map.len().max(1) as f64;
    Ok(ImageErrors { rmse, psnr, max_abs, p99_abs, flip })
}

/// A false-colour picture of a FLIP error map (FLIP's magma scale: black = no visible
/// difference, yellow-white = the largest), as 8-bit RGB.
pub fn error_image(map: &[f32], width: u32, height: u32) -> Vec<u8> {
    let n = (width * height) as usize;
    let clamped: Vec<f32> = map.iter().take(n).map(|e| if e.is_nan() { 1.0 } else { e.clamp(0.0, 1.0) }).collect();
    if clamped.len() < n {
        return Vec::new();
    }
    nv_flip::FlipImageFloat::with_data(width, height, &clamped).apply_color_lut(&nv_flip::magma_lut()).to_vec()
}

/// Writes `error_image` as a PNG.
pub fn write_error_png(path: &std::path::Path, map: &[f32], width: u32, height: u32) -> Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    }
    let rgb = error_image(map, width, height);
    image::save_buffer_with_format(path, &rgb, width, height, image::ExtendedColorType::Rgb8, image::ImageFormat::Png)
        .map_err(|e| Error::Image(format!("{}: {e}", path.display())))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn img(w: u32, h: u32, f: impl Fn(u32, u32) -> [f32; 3]) -> ImageData {
        let mut data = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let c = f(x, y);
                data.extend_from_slice(&[c[0], c[1], c[2], 1.0]);
            }
        }
        ImageData { width: w, height: h, layers: 1, channels: 4, data }
    }

    #[test]
    fn identical_images_have_no_error() {
        let a = img(16, 8, |x, y| [x as f32 / 16.0, y as f32 / 8.0, 0.5]);
        let e = compare(&a, &a).unwrap();
        assert_eq!((e.rmse, e.max_abs, e.p99_abs, e.flip), (0.0, 0.0, 0.0, 0.0));
        assert_eq!(e.psnr, f64::INFINITY);
    }

    #[test]
    fn known_differences_give_known_numbers() {
        let a = img(10, 10, |_, _| [0.5; 3]);
        // One pixel of 100 off by 1 in one channel: MSE = 1/300.
        let b = img(10, 10, |x, y| if (x, y) == (3, 4) { [1.5, 0.5, 0.5] } else { [0.5; 3] });
        let (rmse, psnr, max, p99) = pixel_errors(&b, &a).unwrap();
        assert!((rmse - (1.0f64 / 300.0).sqrt()).abs() < 1e-12);
        assert!((psnr - 10.0 * 300f64.log10()).abs() < 1e-9);
        assert_eq!(max, 1.0);
        assert_eq!(p99, 0.0, "one value of 300 is above the 99th percentile");
        // A uniform offset of 0.1: every statistic is 0.1, PSNR 20 dB.
        let c = img(10, 10, |_, _| [0.6; 3]);
        let (rmse, psnr, max, p99) = pixel_errors(&c, &a).unwrap();
        assert!((rmse - 0.1).abs() < 1e-7 && (psnr - 20.0).abs() < 1e-5 && (max - 0.1).abs() < 1e-7 && (p99 - 0.1).abs() < 1e-7);
        let e = compare(&b, &a).unwrap();
        assert!(e.flip > 0.0 && e.flip < 0.05, "one bright pixel: small mean FLIP {}", e.flip);
        let black = img(10, 10, |_, _| [0.0; 3]);
        let white = img(10, 10, |_, _| [1.0; 3]);
        assert!(compare(&black, &white).unwrap().flip > 0.5, "black vs white is a large FLIP error");
    }

    #[test]
    fn nan_and_size_mismatch() {
        let a = img(4, 4, |_, _| [0.5; 3]);
        let b = img(4, 4, |x, _| if x == 0 { [f32::NAN, 0.5, 0.5] } else { [0.5; 3] });
        let (rmse, psnr, max, _) = pixel_errors(&b, &a).unwrap();
        assert_eq!((rmse, psnr, max), (f64::INFINITY, f64::NEG_INFINITY, f64::INFINITY));
        assert!(compare(&img(4, 3, |_, _| [0.5; 3]), &a).is_err());
    }

    #[test]
    fn error_image_is_false_colour() {
        let rgb = error_image(&[0.0, 1.0], 2, 1);
        assert_eq!(rgb.len(), 6);
        assert_ne!(&rgb[..3], &rgb[3..], "no error and full error look different");
        assert!(rgb[3] as u32 + rgb[4] as u32 + rgb[5] as u32 > rgb[0] as u32 + rgb[1] as u32 + rgb[2] as u32);
    }
}
