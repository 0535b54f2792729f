//! Every file the library and the CLI write (PNG, EXR, trace JSON, CSV, SVG, tables) goes
//! through `write_file`: the bytes are written and flushed with every error checked, to a
//! temporary file beside the target that is then renamed over it, so that a failed write
//! (disk full, no permission) is an error naming the path and leaves no partial file under
//! the final name. A target that exists and is not a regular file (a device such as
//! /dev/full, a pipe) is written in place, its errors checked all the same.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

/// Creates `path`'s parent folders; a parent that is a file is named as such.
pub fn create_parent(path: &Path) -> Result<()> {
    let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) else { return Ok(()) };
    // The nearest existing ancestor must be a folder.
    let mut a = Some(dir);
    while let Some(d) = a {
        if let Ok(meta) = std::fs::metadata(d) {
            if !meta.is_dir() {
                return Err(Error::invalid(path.display().to_string(), format!("cannot write: {} is not a folder", d.display())));
            }
            break;
        }
        a = d.parent().filter(|p| !p.as_os_str().is_empty());
    }
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))
}

fn temporary(path: &Path) -> PathBuf {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_else(|| "out".into());
    path.with_file_name(format!(".{name}.{}.partial", std::process::id()))
}

/// Writes `bytes` to `path` (see the module documentation).
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<()> {
    create_parent(path)?;
    let special = std::fs::metadata(path).is_ok_and(|m| !m.is_file() && !m.is_dir());
    if special {
        let mut f = std::fs::OpenOptions::new().write(true).truncate(true).open(path).map_err(|e| Error::io(path, e))?;
        return f.write_all(bytes).and_then(|_| f.flush()).map_err(|e| Error::io(path, e));
    }
    let tmp = temporary(path);
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.flush()?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    result.map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        Error::io(path, e)
    })
}

/// DejaVu Sans (assets/fonts/, Bitstream Vera licence): every figure's text, in the PNGs
/// rasterised by ab_glyph, so no system font is needed.
static FONT: &[u8] = include_bytes!("../assets/fonts/DejaVuSans.ttf");

/// Registers the bundled font as plotters' `sans-serif` (once): every figure the library
/// writes (tradeoff plots, raytrace-bench's Table 1) draws its text in it.
pub fn register_font() -> Result<()> {
    static DONE: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    let ok = *DONE.get_or_init(|| plotters::style::register_font("sans-serif", plotters::style::FontStyle::Normal, FONT).is_ok());
    if ok {
        Ok(())
    } else {
        Err(Error::Image("the bundled font assets/fonts/DejaVuSans.ttf does not parse".into()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_replace_atomically_and_failures_name_the_path() {
        let dir = std::env::temp_dir().join(format!("specula-output-{}", std::process::id()));
        let path = dir.join("sub/a.txt");
        write_file(&path, b"one").unwrap();
        write_file(&path, b"two").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"two");
        assert_eq!(std::fs::read_dir(path.parent().unwrap()).unwrap().count(), 1, "no temporary file left");
        // A full device: the error names it.
        if Path::new("/dev/full").exists() {
            let e = write_file(Path::new("/dev/full"), &[0u8; 65536]).unwrap_err().to_string();
            assert!(e.contains("/dev/full"), "{e}");
        }
        // A parent that is a file.
        let e = write_file(&path.join("x.png"), b"x").unwrap_err().to_string();
        assert!(e.contains("is not a folder") && e.contains("a.txt"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
