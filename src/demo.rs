//! Image work of `specula demo` that needs no GPU: the contact sheet of every method (the
//! trade-off figure is `crate::tradeoff::plot`).

use std::path::Path;

use crate::error::{Error, Result};
use crate::image::ImageData;

/// One tile of the contact sheet: the method's name (its PNG's stem), the label drawn on
/// it (name, frame time, error against the reference) and its image.
pub struct Tile {
    pub name: String,
    pub label: String,
    pub image: ImageData,
}

/// The label strip's font size for tiles `w` pixels wide.
fn label_size(w: u32) -> u32 {
    if w >= 384 {
        22
    } else if w >= 192 {
        16
    } else {
        12
    }
}

/// The demo's contact sheet `methods.png`: every method's image in a grid of four columns,
/// each under a dark strip with its label (first line white, the rest light grey), the
/// text drawn by plotters' bitmap backend in the bundled DejaVu Sans (ab_glyph), cut
/// with "…" where wider than the tile. Returns the sheet's path.
pub fn write_composite(outdir: &Path, tiles: &[Tile], w: u32, h: u32) -> Result<std::path::PathBuf> {
    use plotters::prelude::*;
    if let Some(t) = tiles.iter().find(|t| t.image.width != w || t.image.height != h || t.image.data.len() < (w * h * 4) as usize) {
        return Err(Error::invalid("contact sheet", format!("{} is {}x{}, not {w}x{h}", t.name, t.image.width, t.image.height)));
    }
    let cols = 4u32.min(tiles.len() as u32).max(1);
    let rows = (tiles.len() as u32).div_ceil(cols);
    let size = label_size(w);
    let lines = tiles.iter().map(|t| t.label.lines().count()).max().unwrap_or(1).max(1) as u32;
    let strip = lines * (size * 5 / 4) + size / 2;
    let (sw, sh) = (cols * w, rows * (strip + h));
    let mut sheet = vec![20u8; (sw * sh * 3) as usize];
    for (i, t) in tiles.iter().enumerate() {
        let (ox, oy) = ((i as u32 % cols) * w, (i as u32 / cols) * (strip + h) + strip);
        for y in 0..h {
            for x in 0..w {
                let s = ((y * w + x) * 4) as usize;
                let d = (((oy + y) * sw + ox + x) * 3) as usize;
                for c in 0..3 {
                    sheet[d + c] = crate::scene::linear_to_srgb(t.image.data[s + c]);
                }
            }
        }
    }
    let path = outdir.join("methods.png");
    crate::tradeoff::write_bitmap_png(&path, (sw, sh), Some(sheet), |root| {
        let e = |e: &dyn std::fmt::Display| e.to_string();
        for (i, t) in tiles.iter().enumerate() {
            let (ox, oy) = ((i as u32 % cols) * w, (i as u32 / cols) * (strip + h));
            for (k, line) in t.label.lines().enumerate() {
                let colour = if k == 0 { WHITE } else { RGBColor(205, 205, 205) };
                let style = TextStyle::from(FontDesc::new(FontFamily::SansSerif, size as f64, FontStyle::Normal)).color(&colour);
                let fits = |s: &str| root.estimate_text_size(s, &style).map(|(tw, _)| tw + size / 2 <= w);
                // Cut to the tile: drop characters from the end until the rest and "…" fit.
                let mut text = line.to_string();
                let mut kept = line.chars().count();
                while !fits(&text).map_err(|x| e(&x))? && kept > 0 {
                    kept -= 1;
                    text = format!("{}…", line.chars().take(kept).collect::<String>().trim_end());
                }
                let pos = ((ox + size / 4) as i32, (oy + size / 4 + k as u32 * (size * 5 / 4)) as i32);
                root.draw(&Text::new(text, pos, style)).map_err(|x| e(&x))?;
            }
        }
        Ok(())
    })?;
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_are_drawn_into_the_sheet() {
        let dir = std::env::temp_dir().join(format!("specula-sheet-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let image = ImageData { width: 200, height: 100, layers: 1, channels: 4, data: vec![0.5; 200 * 100 * 4] };
        let tiles = vec![
            Tile { name: "a".into(), label: "image-space-refraction\n12.3 ms  31.25 dB".into(), image: image.clone() },
            Tile { name: "b".into(), label: "bvh".into(), image: image.clone() },
            Tile { name: "c".into(), label: "envmap\n1.0 ms  20.00 dB".into(), image: image.clone() },
            Tile { name: "d".into(), label: "a label far too long for a tile 200 pixels wide".into(), image: image.clone() },
        ];
        let path = write_composite(&dir, &tiles, 200, 100).unwrap();
        let png = ::image::open(&path).unwrap().to_rgb8();
        // 16 px text at 200 px tiles: two lines of 20 px and 8 px of margin above each tile.
        let strip = 48;
        assert_eq!(png.dimensions(), (800, strip + 100));
        let region = |x0: u32, rows: std::ops::Range<u32>| -> Vec<[u8; 3]> {
            (x0..x0 + 200).flat_map(|x| rows.clone().map(move |y| (x, y))).map(|(x, y)| png.get_pixel(x, y).0).collect()
        };
        let bright = |px: &[[u8; 3]]| px.iter().filter(|p| p[0] > 150).count();
        let shades = |px: &[[u8; 3]]| px.iter().collect::<std::collections::HashSet<_>>().len();
        // Each strip carries text: light anti-aliased glyphs on the dark band, more of them
        // for a longer label; the second line is there only where the label has one.
        let (first_a, first_b) = (region(0, 0..24), region(200, 0..24));
        assert!(bright(&first_a) > 3 * bright(&first_b) && bright(&first_b) > 20, "{} vs {}", bright(&first_a), bright(&first_b));
        assert!(shades(&first_a) > 8, "anti-aliased text: {} shades", shades(&first_a));
        assert!(bright(&region(400, 24..strip)) > 40 && bright(&region(200, 24..strip)) == 0);
        // The long name is cut to the tile, not drawn over its neighbour's strip.
        assert!(region(0, 0..strip).iter().any(|p| p[0] > 150) && png.get_pixel(201, 10).0[0] < 60);
        let cut = region(600, 0..24);
        assert!(bright(&cut) > 100 && (0..24).all(|y| png.get_pixel(799, y).0[0] < 60), "the long label is cut before the sheet's edge");
        // The image under the strip, sRGB-encoded (0.5 linear = 188).
        assert_eq!(png.get_pixel(100, strip + 50).0, [188, 188, 188]);
        // Tiles of another size are refused.
        assert!(write_composite(&dir, &tiles, 100, 100).is_err());
        std::fs::remove_dir_all(&dir).ok();
    }
}
