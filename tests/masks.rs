//! Issue 15's masks: every GPU frame can write each pixel's first-hit object beside the
//! colour (`object_ids=on`, off by default and then costing nothing), the CPU reference
//! writes the same from its first hits, and errors are measured where a method acts: per
//! specular object, on all specular pixels and on the rest.

mod common;

use specula::Quality;

const SIZE: (u32, u32) = (72, 54);

fn demo() -> specula::Scene {
    specula::scene::load(std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/demo/demo.gltf"))).unwrap()
}

#[test]
fn gpu_and_reference_ids_agree_and_cost_nothing_when_off() {
    let ctx = common::gpu();
    let scene = demo();
    let q = {
        let mut knobs = Quality::default();
        knobs.cube.cube_size = 32;
        knobs.frame.shadow_size = 64;
        knobs
    };
    let off = specula::render(&ctx, &scene, specula::Choice::Auto, &q, SIZE, (0, 1)).unwrap();
    assert!(off.object_ids.is_none());
    assert!(off.passes.iter().all(|p| p.name != "frame.object_ids"), "no pass when off");
    assert!(off.memory.iter().all(|(n, _)| !n.starts_with("frame.object_ids")), "no image when off: {:?}", off.memory);
    let mut on = q.clone();
    on.set("object_ids", "on").unwrap();
    let f = specula::render(&ctx, &scene, specula::Choice::Auto, &on, SIZE, (0, 1)).unwrap();
    assert_eq!(f.image.data, off.image.data, "the ids change nothing in the colour");
    let gpu = f.object_ids.expect("ids when on");
    let reference = specula::reference::object_ids(&scene, SIZE).unwrap();
    assert_eq!(gpu.len(), (SIZE.0 * SIZE.1) as usize);
    let (agree, interior) = specula::metrics::id_agreement(&gpu, &reference, SIZE.0, SIZE.1);
    let objects: std::collections::BTreeSet<u32> = reference.iter().copied().collect();
    println!("ids: {:.4} of {interior} interior pixels agree; {} objects seen", agree, objects.len());
    // Measured: every interior pixel (1.0000 of 3330); the issue asks for 99 %.
    assert!(agree >= 0.99, "{agree}");
    assert!(objects.len() >= 4, "{objects:?}");
    common::assert_clean(&ctx);
}

/// The error split by the masks: with caustics off (they are cast through each method's
/// own maps) two specular methods render the non-specular pixels to the same bits, so the
/// split isolates what the method changes; on the specular pixels the environment map (no
/// parallax) is worse than distance maps.
#[test]
fn errors_split_by_object() {
    let ctx = common::gpu();
    let scene = demo();
    let mut q = {
        let mut knobs = Quality::default();
        knobs.cube.cube_size = 32;
        knobs.frame.shadow_size = 64;
        knobs.frame.depth = 4;
        knobs
    };
    q.set("caustics", "off").unwrap();
    let reference = specula::reference::render_reference(&scene, &q, SIZE).unwrap();
    let ids = specula::reference::object_ids(&scene, SIZE).unwrap();
    let specular: Vec<bool> = scene.meshes.iter().map(|m| scene.materials[m.material].kind.is_specular()).collect();
    let names: Vec<String> = scene.meshes.iter().map(|m| m.name.clone()).collect();
    let mut split = Vec::new();
    for m in [specula::methods::ENVMAP, specula::methods::DISTANCE] {
        let f = specula::render(&ctx, &scene, m, &q, SIZE, (0, 1)).unwrap();
        let e = specula::metrics::errors_by_object(&f.image, &reference, &ids, &specular, &names).unwrap();
        for x in &e {
            println!("{}: {} on {} pixels: {:.2} dB", m.name(), x.name, x.pixels, x.psnr);
        }
        split.push(e);
    }
    let get = |k: usize, name: &str| split[k].iter().find(|e| e.name == name).unwrap_or_else(|| panic!("{name}")).psnr;
    assert!(split[0].len() >= 4, "two spheres, the specular pixels, the rest: {:?}", split[0]);
    assert_eq!(get(0, "non-specular"), get(1, "non-specular"), "the rest does not depend on the specular method");
    // On the mirror sphere, where parallax is the whole difference: measured 24.75 dB with
    // distance maps vs 23.55 dB with the environment map (the demo's 6.5 cd light, 72×54;
    // both far under the exact ray tracer's 24.35 dB-at-1-spp ceiling set by aliasing
    // against the 16-spp reference), the 1.20 dB margin asserted at half (rule 1). The glass
    // sphere is not compared: both methods refract once and ignore the exit (refractor-map
    // is the method for solid glass), so neither is nearer by design (measured 29.50 dB
    // envmap, 28.40 dB distance).
    let (envmap, distance) = (get(0, "mirror_sphere/0"), get(1, "mirror_sphere/0"));
    println!("mirror sphere: envmap {envmap:.2} dB, distance {distance:.2} dB");
    assert!(distance >= envmap + 0.60, "{distance:.2} vs {envmap:.2}");
    // The masks partition the image: the objects' pixels add up to the specular ones.
    let count = |name: &str| split[0].iter().find(|e| e.name == name).unwrap().pixels;
    let objects: usize = split[0].iter().filter(|e| e.name != "specular" && e.name != "non-specular").map(|e| e.pixels).sum();
    assert_eq!(objects, count("specular"));
    assert_eq!(count("specular") + count("non-specular"), (SIZE.0 * SIZE.1) as usize);
    common::assert_clean(&ctx);
}

/// `specula compare --scene`: the per-object table and a masked error image; a mask that
/// names nothing is refused by name.
#[test]
fn compare_reports_errors_per_object() {
    let bin = env!("CARGO_BIN_EXE_specula");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/demo/demo.gltf");
    let dir = common::scratch_dir("masks");
    std::fs::create_dir_all(&dir).unwrap();
    let run = |args: &[&str]| std::process::Command::new(bin).args(args).output().unwrap();
    let (r, e, err) = (dir.join("r.exr"), dir.join("e.exr"), dir.join("err.png"));
    for (method, out) in [("reference", &r), ("envmap", &e)] {
        let o =
            run(&["render", scene, "--method", method, "--size", "48x36", "-q", "depth=4", "-q", "spp=1", "--out", out.to_str().unwrap()]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let o = run(&[
        "compare",
        e.to_str().unwrap(),
        r.to_str().unwrap(),
        "--scene",
        scene,
        "--mask",
        "specular",
        "--error-image",
        err.to_str().unwrap(),
    ]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{text}{}", String::from_utf8_lossy(&o.stderr));
    for row in ["mirror_sphere/0", "glass_sphere/0", "specular", "non-specular", "(pixels of specular only)"] {
        assert!(text.contains(row), "{row} missing:\n{text}");
    }
    // The masked error image holds the colour of no error outside the specular pixels:
    // one colour over most of it.
    let img = image::open(&err).unwrap().to_rgb8();
    let mut counts = std::collections::HashMap::new();
    img.pixels().for_each(|p| *counts.entry(p.0).or_insert(0usize) += 1);
    let most = counts.values().copied().max().unwrap_or(0);
    assert!(most * 2 > img.pixels().count() && counts.len() > 1, "{most} of {} pixels, {} colours", img.pixels().count(), counts.len());
    let o = run(&["compare", e.to_str().unwrap(), r.to_str().unwrap(), "--scene", scene, "--mask", "bogus"]);
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("'bogus'"));
    std::fs::remove_dir_all(&dir).ok();
}

/// Issue 15's shared terms: with `shadows=off` in both renderers the non-specular pixels
/// lose the shadow maps' error against exact shadow rays, so what remains on them is
/// rounding; no shadow map is planned, and a ray tracer sends no shadow rays.
#[test]
fn shadows_off_removes_the_shared_shadow_term() {
    let ctx = common::gpu();
    let scene = demo();
    let ids = specula::reference::object_ids(&scene, SIZE).unwrap();
    let specular: Vec<bool> = scene.meshes.iter().map(|m| scene.materials[m.material].kind.is_specular()).collect();
    let names: Vec<String> = scene.meshes.iter().map(|m| m.name.clone()).collect();
    let mut rest = Vec::new();
    for shadows in ["on", "off"] {
        let mut q = {
            let mut knobs = Quality::default();
            knobs.cube.cube_size = 32;
            knobs.frame.shadow_size = 64;
            knobs.frame.depth = 4;
            knobs
        };
        q.set("caustics", "off").unwrap();
        q.set("shadows", shadows).unwrap();
        q.set("spp", "1").unwrap();
        let reference = specula::reference::render_reference(&scene, &q, SIZE).unwrap();
        for m in [specula::methods::DISTANCE, specula::methods::BVH] {
            let f = specula::render(&ctx, &scene, m, &q, SIZE, (0, 1)).unwrap();
            let shadow_passes = f.passes.iter().filter(|p| p.name.starts_with("shadow")).count();
            let e = specula::metrics::errors_by_object(&f.image, &reference, &ids, &specular, &names).unwrap();
            let non = e.iter().find(|x| x.name == "non-specular").unwrap().psnr;
            println!("shadows={shadows} {}: non-specular {non:.2} dB, {shadow_passes} shadow pass(es)", m.name());
            if shadows == "off" {
                assert_eq!(shadow_passes, 0, "{}: no shadow map when off", m.name());
            }
            rest.push(non);
        }
    }
    // Measured (one sample per pixel in both, the demo's 6.5 cd light): distance 40.40 dB on
    // the non-specular pixels with shadow maps against exact shadows, 73.78 dB with shadows
    // off in both (bvh, exact shadow rays: 74.21 and 73.78 dB). Floors 1 dB under; the
    // 33.38 dB gain 1 dB under.
    let (on_distance, on_bvh, off_distance, off_bvh) = (rest[0], rest[1], rest[2], rest[3]);
    assert!(on_bvh >= 60.0 && off_bvh >= 60.0, "bvh {on_bvh:.2} / {off_bvh:.2} dB");
    assert!(off_distance >= 72.78 && off_distance >= on_distance + 32.38, "distance {on_distance:.2} → {off_distance:.2} dB");
    common::assert_clean(&ctx);
}

/// `shadows=off` leaves the GPU caustics as they are: the photon pass's cube index shares
/// bits 8–15 of the push flags with the frame-wide FLAG_UNSHADOWED (and
/// FLAG_LAYERED_STRONGEST), which once sent its photons through cube 32 + n.
#[test]
fn shadows_off_keeps_the_caustics() {
    let ctx = common::gpu();
    let scene = demo();
    let mut term = Vec::new();
    for flags in [["shadows=on", "layered_branches=both"], ["shadows=off", "layered_branches=strongest"]] {
        let mut frames = Vec::new();
        for caustics in ["triangles", "off"] {
            let mut q = {
                let mut knobs = Quality::default();
                knobs.cube.cube_size = 32;
                knobs.frame.shadow_size = 64;
                knobs
            };
            for f in flags {
                q.set_pair(f).unwrap();
            }
            q.set("caustics", caustics).unwrap();
            frames.push(specula::render(&ctx, &scene, specula::methods::DISTANCE, &q, SIZE, (0, 1)).unwrap().image);
        }
        // The caustics' share of the frame.
        let mut c = frames[0].clone();
        c.data.iter_mut().zip(&frames[1].data).for_each(|(a, b)| *a -= b);
        term.push(c);
    }
    let energy: f64 = term[0].data.iter().map(|x| *x as f64).sum();
    let max = term[0].data.iter().zip(&term[1].data).map(|(a, b)| (a - b).abs()).fold(0f32, f32::max);
    println!("caustics' sum {energy:.3}; largest difference between the two {max:e}");
    // Measured (72x54, the demo's 6.5 cd light): the caustic term sums to 68.07 and differs
    // between the two by at most 3.0e-4 (the rounding of the sums it is the difference of;
    // bound 1e-3); with the photon pass's cube index off by 32 it differed by up to 2.36
    // (at the old 25 cd light, where the term summed to 34.28).
    assert!(energy > 60.0, "the demo has caustics: {energy}");
    assert!(max <= 1e-3, "{max:e}");
    common::assert_clean(&ctx);
}
