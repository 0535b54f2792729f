//! Files that declare a huge image in a few bytes are refused before any pixel is
//! allocated, with an error naming the file and the declared size: EXR (data window), PNG
//! (IHDR), Radiance HDR (resolution line) — through the library and through the CLI
//! (`render --env`, `compare`), which exit 1 instead of aborting on a failed allocation.

mod common;

use std::path::{Path, PathBuf};

use specula::scene::{load_environment, load_environment_with, LoadLimits};

/// A scratch directory per test: the tests run in parallel and each removes its own.
fn dir(test: &str) -> PathBuf {
    let d = common::scratch_dir(&format!("limits-{test}"));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A valid 8×8 EXR whose data window is then patched to 65536×65536.
fn huge_exr(d: &Path) -> PathBuf {
    let path = d.join("huge.exr");
    specula::scene::write_exr(&path, 8, 8, &vec![0.5; 8 * 8 * 4]).unwrap();
    let mut bytes = std::fs::read(&path).unwrap();
    let key = b"dataWindow\0box2i\0";
    let at = bytes.windows(key.len()).position(|w| w == key).expect("dataWindow attribute") + key.len() + 4;
    bytes[at + 8..at + 12].copy_from_slice(&65535i32.to_le_bytes());
    bytes[at + 12..at + 16].copy_from_slice(&65535i32.to_le_bytes());
    std::fs::write(&path, bytes).unwrap();
    path
}

fn huge_png(d: &Path) -> PathBuf {
    let path = d.join("huge.png");
    std::fs::write(&path, common::huge_png_bytes()).unwrap();
    path
}

fn huge_hdr(d: &Path) -> PathBuf {
    let path = d.join("huge.hdr");
    let mut bytes = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 65536 +X 65536\n".to_vec();
    bytes.extend([0u8; 64]);
    std::fs::write(&path, bytes).unwrap();
    path
}

#[test]
fn declared_sizes_are_checked_before_allocation() {
    let d = dir("loader");
    for path in [huge_exr(&d), huge_png(&d), huge_hdr(&d)] {
        let e = load_environment(&path).unwrap_err().to_string();
        eprintln!("{e}");
        assert!(e.contains(path.file_name().unwrap().to_str().unwrap()), "{e}");
        assert!(e.contains("declares 65536×65536 pixels, beyond the loader's limits"), "{}: {e}", path.display());
    }
    // The limits are the loader's knobs: a small image passes the default and fails a
    // tighter limit.
    let small = d.join("small.exr");
    specula::scene::write_exr(&small, 64, 32, &vec![0.25; 64 * 32 * 4]).unwrap();
    assert_eq!(load_environment(&small).unwrap().width, 64);
    let tight = LoadLimits { max_edge: 32, max_pixels: 1 << 20 };
    let e = load_environment_with(&small, &tight).unwrap_err().to_string();
    assert!(e.contains("64×32") && e.contains("32 pixels an edge"), "{e}");
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn the_cli_exits_1_on_huge_declared_images() {
    let d = dir("cli");
    let exe = env!("CARGO_BIN_EXE_specula");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/demo/demo.gltf");
    let exr = huge_exr(&d);
    let out = d.join("x.png");
    for args in [
        vec!["render", scene, "--env", exr.to_str().unwrap(), "--size", "16x16", "--out", out.to_str().unwrap()],
        vec!["compare", exr.to_str().unwrap(), exr.to_str().unwrap()],
    ] {
        let o = std::process::Command::new(exe).args(&args).output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert!(err.trim_end().lines().count() == 1 && err.contains("huge.exr"), "{args:?}: {err}");
    }
    std::fs::remove_dir_all(&d).ok();
}

/// A reader that closes the pipe early (`specula knobs | head -1`) ends the CLI quietly: no
/// panic message from a failed `println!`. The read end is closed before the CLI writes.
#[test]
fn the_cli_stops_quietly_when_its_reader_closes_the_pipe() {
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_specula"))
        .arg("knobs")
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("panicked") && !err.contains("Broken pipe"), "{err}");
}
