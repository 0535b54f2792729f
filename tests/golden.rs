//! Behaviour kept across refactors: every GPU method, with a few knob variants, renders the
//! demo scene and a glass-and-mirror test scene to exactly the same bits as the images
//! recorded in `tests/golden/images.txt` (FNV-1a 64 of the RGBA32F pixels). The table was
//! written by the code before the method-registry refactor; a change that alters any pixel
//! of any method fails here. Regenerate on purpose only: `SPECULA_UPDATE_GOLDEN=1 cargo test
//! --test golden`, and say in the commit which images changed and why.

mod common;

use specula::{Method, Quality};

fn fnv(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| (h ^ b as u64).wrapping_mul(0x0100_0000_01b3))
}

/// (label, method, knobs, frames): every GPU method at its defaults, and the knobs that
/// switch code paths (multiview, single precision, exact Fresnel, parallax only, binary
/// search, frame latency over two frames).
fn cases() -> Vec<(String, Method, Vec<&'static str>, u32)> {
    let mut v = Vec::new();
    for &m in Method::ALL.iter().filter(|m| m.is_gpu()) {
        v.push((m.name().to_string(), m, vec![], 1));
    }
    let variants: &[(&str, Method, &[&str], u32)] = &[
        ("distance+multiview", specula::methods::DISTANCE, &["cube_mode=multiview"], 1),
        ("distance+single", specula::methods::DISTANCE, &["cube_precision=single"], 1),
        ("distance+exact", specula::methods::DISTANCE, &["fresnel=exact"], 1),
        ("distance+parallax", specula::methods::DISTANCE, &["linear_steps=0", "parallax_iterations=3"], 1),
        ("distance+binary", specula::methods::DISTANCE, &["binary_steps=4", "secant_steps=0"], 1),
        ("distance-multi+depth2", specula::methods::DISTANCE_MULTI, &["cycles=2"], 1),
        ("distance-multi+latency", specula::methods::DISTANCE_MULTI, &["frame_latency=on"], 2),
        ("refractor-map+bounces0", specula::methods::REFRACTOR_MAP, &["internal_bounces=0"], 1),
        ("envmap+multiview", specula::methods::ENVMAP, &["cube_mode=multiview"], 1),
        ("kd-tree+ropes", specula::methods::KD_TREE, &["kd_traversal=ropes"], 1),
        ("octree+volume", specula::methods::OCTREE, &["octree_volume=on"], 1),
    ];
    for (label, m, knobs, frames) in variants {
        v.push((label.to_string(), *m, knobs.to_vec(), *frames));
    }
    v
}

/// The recorded lines of one half of the cases (alternating, over both scenes): the two
/// halves are two tests, so that the suite's two test threads share them (one test took 44 s
/// alone).
fn renders_the_recorded_bits(half: usize) {
    let ctx = common::gpu();
    let demo = specula::scene::load(std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/demo/demo.gltf"))).unwrap();
    let scenes = [("demo", demo), ("mirror_and_glass", common::mirror_and_glass(32))];
    let mut lines = Vec::new();
    for (scene_name, scene) in &scenes {
        for (label, method, knobs, frames) in cases().into_iter().skip(half).step_by(2) {
            let mut q = {
                let mut knobs = Quality::default();
                knobs.cube.cube_size = 32;
                knobs.frame.shadow_size = 64;
                knobs
            };
            for k in &knobs {
                q.set_pair(k).unwrap();
            }
            // Frame latency needs a second frame to read the first one's maps.
            let f = specula::render(&ctx, scene, method, &q, (40, 30), (frames - 1, 1)).unwrap();
            let bytes: Vec<u8> = f.image.data.iter().flat_map(|x| x.to_bits().to_le_bytes()).collect();
            lines.push(format!("{scene_name} {label} {:016x}", fnv(&bytes)));
        }
    }
    common::assert_clean(&ctx);
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/golden/images.txt");
    if std::env::var_os("SPECULA_UPDATE_GOLDEN").is_some() {
        update(path, half, &lines);
    }
    let want = std::fs::read_to_string(path).unwrap_or_default();
    let want: std::collections::HashMap<&str, &str> = want.lines().filter_map(|l| l.rsplit_once(' ')).collect();
    let mut bad = Vec::new();
    for l in &lines {
        let (key, hash) = l.rsplit_once(' ').unwrap();
        if want.get(key) != Some(&hash) {
            bad.push(format!("{key}: got {hash}, recorded {:?}", want.get(key)));
        }
    }
    assert!(bad.is_empty(), "images differ from the recorded bits:\n{}", bad.join("\n"));
}

/// Writes the table once both halves have rendered, in the order of one full pass (scene,
/// then case), whichever half finishes last.
fn update(path: &str, half: usize, lines: &[String]) {
    static HALVES: std::sync::Mutex<[Option<Vec<String>>; 2]> = std::sync::Mutex::new([None, None]);
    let mut h = HALVES.lock().unwrap_or_else(|e| e.into_inner());
    h[half] = Some(lines.to_vec());
    if let [Some(a), Some(b)] = &*h {
        let by_key: std::collections::HashMap<&str, &String> =
            a.iter().chain(b).filter_map(|l| l.rsplit_once(' ').map(|(key, _)| (key, l))).collect();
        let all: Vec<&str> = ["demo", "mirror_and_glass"]
            .iter()
            .flat_map(|scene| cases().into_iter().map(move |(label, ..)| format!("{scene} {label}")))
            .map(|key| by_key[key.as_str()].as_str())
            .collect();
        std::fs::create_dir_all(std::path::Path::new(path).parent().unwrap()).unwrap();
        std::fs::write(path, all.join("\n") + "\n").unwrap();
    }
}

#[test]
fn every_method_renders_the_recorded_bits_first_half() {
    renders_the_recorded_bits(0);
}

#[test]
fn every_method_renders_the_recorded_bits_second_half() {
    renders_the_recorded_bits(1);
}
