//! Image work of `specula demo` that needs no GPU: the contact sheet of every method.

use std::path::Path;

use crate::error::Result;
use crate::image::ImageData;

/// One tile of the contact sheet: the method's name (its PNG's stem), the label drawn on
/// it (name, frame time, error against the reference) and its image.
pub struct Tile {
    pub name: String,
    pub label: String,
    pub image: ImageData,
}

/// The demo's contact sheet: every method's image in a grid of four columns, each labelled
/// in the picture itself (8×8 bitmap glyphs of font8x8, on a dark band), as `methods.png`;
/// and `methods.svg`, the same grid referencing the per-method PNGs beside it.
pub fn write_composite(outdir: &Path, tiles: &[Tile], w: u32, h: u32) -> Result<()> {
    let images: Vec<(&str, &ImageData)> = tiles.iter().map(|t| (t.name.as_str(), &t.image)).collect();
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
    let scale = if w >= 384 { 2 } else { 1 };
    for (i, t) in tiles.iter().enumerate() {
        let (ox, oy) = ((i as u32 % cols) * w, (i as u32 / cols) * h);
        draw_label(&mut sheet, sw, sh, ox, oy, scale, w, &t.label);
    }
    crate::scene::write_png_srgb(&outdir.join("methods.png"), sw, sh, &sheet)?;
    let label = 24;
    let mut svg =
        format!("<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{sw}\" height=\"{}\" style=\"background:#111\">\n", rows * (h + label));
    for (i, (t, (name, _))) in tiles.iter().zip(&images).enumerate() {
        let text = t.label.replace('&', "&amp;").replace('<', "&lt;").replace('\n', " · ");
        let (x, y) = ((i as u32 % cols) * w, (i as u32 / cols) * (h + label));
        svg += &format!(
            "<text x=\"{}\" y=\"{}\" fill=\"#eee\" font-family=\"sans-serif\" font-size=\"16\">{text}</text>\n<image x=\"{x}\" y=\"{}\" width=\"{w}\" height=\"{h}\" href=\"{name}.png\"/>\n",
            x + 6,
            y + 17,
            y + label
        );
    }
    svg += "</svg>\n";
    let path = outdir.join("methods.svg");
    crate::output::write_file(&path, svg.as_bytes())
}

/// Draws `text` (lines split at '\n') into an RGBA32F linear image of `w`×`h` at (x, y):
/// 8×8 glyphs (font8x8) scaled by `scale`, white on a black band, clipped to `max_w` pixels
/// of width.
#[allow(clippy::too_many_arguments)]
pub fn draw_label(pixels: &mut [f32], w: u32, h: u32, x: u32, y: u32, scale: u32, max_w: u32, text: &str) {
    for (k, line) in text.lines().enumerate() {
        draw_line(pixels, w, h, x, y + k as u32 * 9 * scale, scale, max_w, line);
    }
}

#[allow(clippy::too_many_arguments)]
fn draw_line(pixels: &mut [f32], w: u32, h: u32, x: u32, y: u32, scale: u32, max_w: u32, text: &str) {
    use font8x8::UnicodeFonts;
    let glyph = 8 * scale;
    let band_w = (text.chars().count() as u32 * glyph + 2 * scale).min(max_w);
    let mut put = |px: u32, py: u32, v: f32| {
        if px < w && py < h && px < x + max_w {
            let i = ((py * w + px) * 4) as usize;
            pixels[i..i + 4].copy_from_slice(&[v, v, v, 1.0]);
        }
    };
    for py in y..y + glyph + scale {
        for px in x..x + band_w {
            put(px, py, 0.0);
        }
    }
    for (k, c) in text.chars().enumerate() {
        let rows = font8x8::BASIC_FONTS.get(c).or_else(|| font8x8::BASIC_FONTS.get('?')).unwrap_or([0; 8]);
        for (row, bits) in rows.iter().enumerate() {
            for col in 0..8u32 {
                if bits & (1 << col) == 0 {
                    continue;
                }
                for sy in 0..scale {
                    for sx in 0..scale {
                        put(x + scale + k as u32 * glyph + col * scale + sx, y + scale + row as u32 * scale + sy, 1.0);
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_are_drawn_into_the_sheet() {
        let dir = std::env::temp_dir().join(format!("specula-sheet-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let image = ImageData { width: 64, height: 32, layers: 1, channels: 4, data: vec![0.5; 64 * 32 * 4] };
        let tiles = vec![
            Tile { name: "a".into(), label: "envmap\n1.0 ms".into(), image: image.clone() },
            Tile { name: "b".into(), label: "distance".into(), image },
        ];
        write_composite(&dir, &tiles, 64, 32).unwrap();
        let png = ::image::open(dir.join("methods.png")).unwrap().to_rgb8();
        assert_eq!(png.dimensions(), (128, 32));
        // The band is black, the glyphs white, the rest of the tile grey.
        let px = |x, y| png.get_pixel(x, y).0;
        let count = |rows: std::ops::Range<u32>, c: [u8; 3]| {
            (0..64).flat_map(|x| rows.clone().map(move |y| (x, y))).filter(|&(x, y)| px(x, y) == c).count()
        };
        // Two lines of glyphs, white on black.
        for rows in [0..9, 9..18] {
            let (white, black) = (count(rows.clone(), [255, 255, 255]), count(rows.clone(), [0, 0, 0]));
            assert!(white > 30 && black > 100, "rows {rows:?}: white {white}, black {black}");
        }
        assert!(px(10, 25)[0] > 150 && px(10, 25)[0] < 220, "grey below the label: {:?}", px(10, 25));
        std::fs::remove_dir_all(&dir).ok();
    }
}
