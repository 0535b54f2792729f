//! Image work of `specula demo` that needs no GPU: the contact sheet of every method.

use std::path::Path;

use crate::error::{Error, Result};
use crate::image::ImageData;

/// The demo's contact sheet: every method's image in a grid of four columns, as
/// `methods.png` and as `methods.svg` (the same grid with each method's name, referencing
/// the per-method PNGs beside it).
pub fn write_composite(outdir: &Path, images: &[(&str, ImageData)], w: u32, h: u32) -> Result<()> {
    let cols = 4u32.min(images.len() as u32).max(1);
    let rows = (images.len() as u32).div_ceil(cols);
    let (sw, sh) = (cols * w, rows * h);
    let mut sheet = vec![0f32; (sw * sh * 4) as usize];
    for (i, (_, img)) in images.iter().enumerate() {
        let (ox, oy) = ((i as u32 % cols) * w, (i as u32 / cols) * h);
        for y in 0..h {
            let src = (y * w * 4) as usize;
            let dst = (((oy + y) * sw + ox) * 4) as usize;
            sheet[dst..dst + (w * 4) as usize].copy_from_slice(&img.data[src..src + (w * 4) as usize]);
        }
    }
    crate::scene::write_png_srgb(&outdir.join("methods.png"), sw, sh, &sheet)?;
    let label = 24;
    let mut svg =
        format!("<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{sw}\" height=\"{}\" style=\"background:#111\">\n", rows * (h + label));
    for (i, (name, _)) in images.iter().enumerate() {
        let (x, y) = ((i as u32 % cols) * w, (i as u32 / cols) * (h + label));
        svg += &format!(
            "<text x=\"{}\" y=\"{}\" fill=\"#eee\" font-family=\"sans-serif\" font-size=\"16\">{name}</text>\n<image x=\"{x}\" y=\"{}\" width=\"{w}\" height=\"{h}\" href=\"{name}.png\"/>\n",
            x + 6,
            y + 17,
            y + label
        );
    }
    svg += "</svg>\n";
    let path = outdir.join("methods.svg");
    std::fs::write(&path, svg).map_err(|e| Error::io(&path, e))
}
