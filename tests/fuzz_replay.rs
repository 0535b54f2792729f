//! The fuzz targets of `specula::fuzzing` on the checked-in seed corpus (tests/fuzz/corpus/)
//! with deterministic mutations (byte flips, interesting values, insertions, deletions,
//! splices, and for JSON numbers swapped for extremes), a fixed number of cases per seed so
//! that CI runs the same inputs every time. `SPECULA_FUZZ_CASES=N` runs N cases per seed
//! for a longer session. `cargo fuzz` targets over the same functions are in fuzz/.
//! `SPECULA_UPDATE_CORPUS=1` rewrites the seeds.

mod common;

use std::path::{Path, PathBuf};

const CORPUS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fuzz/corpus");

struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

const EXTREMES: &[&str] =
    &["0", "-1", "1e309", "-1e309", "4294967296", "-2147483649", "1e-320", "3.4e38", "65536", "1.5", "NaN", "null", "\"\"", "[]", "{}"];

fn mutate(seed: &[u8], rng: &mut Rng) -> Vec<u8> {
    let mut v = seed.to_vec();
    for _ in 0..1 + rng.below(4) {
        let n = v.len().max(1);
        match rng.below(7) {
            0 if !v.is_empty() => {
                let i = rng.below(v.len());
                v[i] ^= 1 << rng.below(8);
            }
            1 if !v.is_empty() => {
                let i = rng.below(v.len());
                v[i] = [0u8, 0xff, 0x7f, 0x80, b'"', b'{', b'9'][rng.below(7)];
            }
            2 => {
                let i = rng.below(n);
                v.insert(i.min(v.len()), rng.next() as u8);
            }
            3 if v.len() > 1 => {
                let i = rng.below(v.len());
                let len = 1 + rng.below((v.len() - i).min(64));
                v.drain(i..i + len);
            }
            4 if v.len() > 1 => {
                let (i, j) = (rng.below(v.len()), rng.below(v.len()));
                let len = 1 + rng.below((v.len() - i.max(j)).min(256));
                let chunk = v[i..i + len].to_vec();
                v.splice(j..j, chunk);
            }
            5 => {
                // A JSON number swapped for an extreme (text inputs).
                let digits: Vec<usize> = v.iter().enumerate().filter(|(_, c)| c.is_ascii_digit()).map(|(i, _)| i).collect();
                if !digits.is_empty() {
                    let mut i = digits[rng.below(digits.len())];
                    while i > 0 && (v[i - 1].is_ascii_digit() || v[i - 1] == b'.' || v[i - 1] == b'-') {
                        i -= 1;
                    }
                    let mut j = i;
                    while j < v.len() && (v[j].is_ascii_digit() || v[j] == b'.' || v[j] == b'e' || v[j] == b'-') {
                        j += 1;
                    }
                    let x = EXTREMES[rng.below(EXTREMES.len())].as_bytes().to_vec();
                    v.splice(i..j, x);
                }
            }
            _ => {
                let i = rng.below(n);
                v.truncate(i);
            }
        }
    }
    v
}

/// Keeps a failing input for reproduction (and for the corpus once fixed).
fn keep(seed: &Path, case: usize, input: &[u8]) -> PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("specula-fuzz-findings");
    let _ = std::fs::create_dir_all(&dir);
    let path = dir.join(format!("{}-{case}", seed.file_name().unwrap().to_string_lossy()));
    let _ = std::fs::write(&path, input);
    path
}

fn cases(default: usize) -> usize {
    std::env::var("SPECULA_FUZZ_CASES").ok().and_then(|s| s.parse().ok()).unwrap_or(default)
}

fn seeds(kind: &str) -> Vec<(PathBuf, Vec<u8>)> {
    let dir = Path::new(CORPUS).join(kind);
    let mut v: Vec<(PathBuf, Vec<u8>)> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .flatten()
        .map(|e| (e.path(), std::fs::read(e.path()).unwrap()))
        .collect();
    v.sort();
    assert!(!v.is_empty(), "no seeds in {}", dir.display());
    v
}

/// The seeds, written from code (a quad with an embedded buffer, as .gltf and .glb; small
/// EXR, HDR and PNG maps).
fn write_corpus() {
    let g = Path::new(CORPUS).join("gltf");
    let e = Path::new(CORPUS).join("env");
    std::fs::create_dir_all(&g).unwrap();
    std::fs::create_dir_all(&e).unwrap();
    let positions: [f32; 12] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 0.0];
    let indices: [u32; 6] = [0, 1, 2, 0, 2, 3];
    let mut bin: Vec<u8> = positions.iter().flat_map(|v| v.to_le_bytes()).collect();
    bin.extend(indices.iter().flat_map(|v| v.to_le_bytes()));
    let json = |uri: Option<String>| {
        let buffer = match uri {
            Some(u) => serde_json::json!({ "byteLength": bin.len(), "uri": u }),
            None => serde_json::json!({ "byteLength": bin.len() }),
        };
        serde_json::json!({
            "asset": { "version": "2.0" }, "scene": 0, "scenes": [{ "nodes": [0, 1] }],
            "nodes": [{ "mesh": 0, "name": "mirror" }, { "camera": 0, "translation": [0.5, 0.5, 2.0] }],
            "cameras": [{ "type": "perspective", "perspective": { "yfov": 0.8, "znear": 0.01 } }],
            "materials": [{ "pbrMetallicRoughness": { "metallicFactor": 1.0, "roughnessFactor": 0.0 }, "extras": { "specula": { "method": "distance" } } }],
            "meshes": [{ "name": "quad", "primitives": [{ "attributes": { "POSITION": 0 }, "indices": 1, "material": 0 }] }],
            "accessors": [
                { "bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0] },
                { "bufferView": 1, "componentType": 5125, "count": 6, "type": "SCALAR" }
            ],
            "bufferViews": [{ "buffer": 0, "byteLength": 48 }, { "buffer": 0, "byteOffset": 48, "byteLength": 24 }],
            "buffers": [buffer],
            "extensions": { "KHR_lights_punctual": { "lights": [{ "type": "spot", "intensity": 5.0, "spot": { "outerConeAngle": 0.6 } }] } },
            "extensionsUsed": ["KHR_lights_punctual"]
        })
    };
    use base64::Engine as _;
    let embedded = json(Some(format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(&bin))));
    std::fs::write(g.join("quad.gltf"), serde_json::to_vec(&embedded).unwrap()).unwrap();
    let mut j = serde_json::to_vec(&json(None)).unwrap();
    while j.len() % 4 != 0 {
        j.push(b' ');
    }
    let mut glb = Vec::new();
    glb.extend(b"glTF");
    glb.extend(2u32.to_le_bytes());
    glb.extend(((12 + 8 + j.len() + 8 + bin.len()) as u32).to_le_bytes());
    glb.extend((j.len() as u32).to_le_bytes());
    glb.extend(b"JSON");
    glb.extend(&j);
    glb.extend((bin.len() as u32).to_le_bytes());
    glb.extend(b"BIN\0");
    glb.extend(&bin);
    std::fs::write(g.join("quad.glb"), glb).unwrap();
    let px: Vec<f32> = (0..8 * 4).flat_map(|i| [i as f32 / 32.0, 0.5, 0.25, 1.0]).collect();
    specula::scene::write_exr(&e.join("sky.exr"), 8, 4, &px).unwrap();
    specula::scene::write_png_srgb(&e.join("sky.png"), 8, 4, &px).unwrap();
    let rgb: Vec<f32> = px.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect();
    image::Rgb32FImage::from_raw(8, 4, rgb).unwrap().save(e.join("sky.hdr")).unwrap();
}

#[test]
fn gltf_and_glb_importer_survive_mutations() {
    if std::env::var_os("SPECULA_UPDATE_CORPUS").is_some() {
        write_corpus();
    }
    let mut findings = Vec::new();
    for (path, seed) in seeds("gltf") {
        assert!(specula::fuzzing::gltf(&seed).is_none(), "the seed {} itself", path.display());
        let mut rng = Rng(0x9e37_79b9_7f4a_7c15 ^ seed.len() as u64);
        for i in 0..cases(400) {
            let input = mutate(&seed, &mut rng);
            if let Some(f) = specula::fuzzing::gltf(&input) {
                findings.push(format!("{} case {i}: {f} (input: {})", path.display(), keep(&path, i, &input).display()));
            }
        }
    }
    assert!(findings.is_empty(), "{findings:#?}");
}

#[test]
fn environment_loaders_survive_mutations() {
    let dir = common::scratch_dir("fuzz-env");
    std::fs::create_dir_all(&dir).unwrap();
    let mut findings = Vec::new();
    for (path, seed) in seeds("env") {
        let ext = path.extension().unwrap().to_str().unwrap().to_string();
        assert!(specula::fuzzing::environment(&dir, &ext, &seed).is_none(), "the seed {} itself", path.display());
        let mut rng = Rng(0x2545_f491_4f6c_dd1d ^ seed.len() as u64);
        for i in 0..cases(150) {
            let input = mutate(&seed, &mut rng);
            if let Some(f) = specula::fuzzing::environment(&dir, &ext, &input) {
                findings.push(format!("{} case {i}: {f} (input: {})", path.display(), keep(&path, i, &input).display()));
            }
        }
    }
    std::fs::remove_dir_all(&dir).ok();
    assert!(findings.is_empty(), "{findings:#?}");
}

#[test]
fn c_abi_struct_parsing_survives_random_calls() {
    use specula::ffi::*;
    let ctx = common::c_context();
    let mut rng = Rng(0xdead_beef_cafe_f00d);
    let mut findings = Vec::new();
    for i in 0..cases(300) {
        let input: Vec<u8> = (0..16 + rng.below(400)).map(|_| rng.next() as u8).collect();
        if let Some(f) = unsafe { specula::fuzzing::c_abi(ctx, &input) } {
            findings.push(format!("case {i}: {f}"));
        }
    }
    unsafe { assert_eq!(specula_context_destroy(ctx), SPECULA_SUCCESS) };
    assert!(findings.is_empty(), "{findings:#?}");
    assert_eq!(specula::vk::process_validation_errors(), 0, "validation errors under random C ABI calls");
}
