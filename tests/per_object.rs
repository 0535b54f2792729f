//! Per-object methods and the planner (`--method auto`), on lavapipe with validation on,
//! against the exact CPU reference. Tolerances and floors are stated beside each assertion
//! with the numbers measured when the test was written.

mod common;

use glam::Vec3;
use specula::methods::{BVH, DISTANCE, ENVMAP, IMAGE_SPACE_REFRACTION, LAYERED, PLANAR_REFRACTION, REFRACTOR_MAP};
use specula::metrics;
use specula::plan::{plan_with, Choices};
use specula::reference::{render_reference, CameraRays};
use specula::scene::{shapes, Camera, Material, Scene, SurfaceKind};
use specula::vk::{Context, ImageData};
use specula::{Choice, Method, Quality};

fn quality(pairs: &[&str]) -> Quality {
    let mut q = {
        let mut knobs = Quality::default();
        knobs.cube.cube_size = 64;
        knobs.frame.shadow_size = 128;
        knobs
    };
    for p in pairs {
        q.set_pair(p).unwrap();
    }
    q
}

use common::{GLASS, MIRROR};
const R: f32 = 0.5;

fn mirror_and_glass() -> Scene {
    common::mirror_and_glass(48)
}

fn render(ctx: &Context, scene: &Scene, choices: &Choices, q: &Quality, (w, h): (u32, u32)) -> ImageData {
    let plan = plan_with(scene, choices, q).unwrap();
    specula::render_plan(ctx, scene, plan, (w, h), (0, 1)).unwrap().image
}

fn whole(m: Method) -> Choices {
    Choices::all(m)
}

/// Pixels whose camera ray hits the sphere (centre c, radius r) first, of a w×h image.
fn sphere_mask(scene: &Scene, c: Vec3, r: f32, w: u32, h: u32) -> Vec<bool> {
    let rays = CameraRays::new(&scene.camera.unwrap(), w, h);
    let mut mask = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let (o, d, _) = rays.ray(x as f64 + 0.5, y as f64 + 0.5);
            let oc = o - c.as_dvec3();
            let b = oc.dot(d);
            let disc = b * b - (oc.length_squared() - (r as f64) * (r as f64));
            // Strictly inside the silhouette (edge pixels are partly the background).
            mask.push(disc > 0.02 * (r as f64).powi(2));
        }
    }
    mask
}

fn diff(a: &ImageData, b: &ImageData, i: usize) -> f32 {
    (0..3).map(|c| (a.data[4 * i + c] - b.data[4 * i + c]).abs()).fold(0.0, f32::max)
}

/// PSNR (dB) over the masked pixels.
fn masked_psnr(test: &ImageData, reference: &ImageData, mask: &[bool]) -> f64 {
    let (mut sum, mut n) = (0.0f64, 0usize);
    for (i, &m) in mask.iter().enumerate() {
        if m {
            for c in 0..3 {
                let e = (test.data[4 * i + c] - reference.data[4 * i + c]) as f64;
                sum += e * e;
            }
            n += 3;
        }
    }
    let mse = sum / n.max(1) as f64;
    10.0 * (1.0 / mse.max(1e-12)).log10()
}

/// `--object mirror=distance --object glass=refractor-map`: the glass equals the
/// all-refractor-map image and the mirror the all-distance image except where each sees the
/// other; the mirror's reflection of the glass shows the refracted room (the all-distance
/// image shows it black: a sky-only glass in a room without an environment).
#[test]
fn mixed_methods_compose() {
    let ctx = common::gpu();
    let scene = mirror_and_glass();
    let q = quality(&[]);
    let (w, h) = (96, 64);
    let mixed = Choices { method: Choice::Auto, objects: vec![("mirror".into(), DISTANCE), ("glass".into(), REFRACTOR_MAP)] };
    let p = plan_with(&scene, &mixed, &q).unwrap();
    let methods: Vec<_> = p.objects.iter().map(|o| (o.name.as_str(), o.method.name())).collect();
    assert_eq!(methods, [("glass", "refractor-map"), ("mirror", "distance")]);
    assert!(p.inter_object && p.cycles == 2, "mixed methods compose through two map cycles: {} cycles", p.cycles);
    assert!(p.objects.iter().all(|o| o.reason.starts_with("chosen for this object")), "{:?}", p.objects);
    let img = render(&ctx, &scene, &mixed, &q, (w, h));
    let all_rm = render(&ctx, &scene, &whole(REFRACTOR_MAP), &q, (w, h));
    let all_d = render(&ctx, &scene, &whole(DISTANCE), &q, (w, h));
    if let Some(dir) = std::env::var_os("SPECULA_TEST_IMAGES") {
        let dir = std::path::PathBuf::from(dir);
        for (n, i) in [("mixed", &img), ("all_rm", &all_rm), ("all_d", &all_d)] {
            specula::scene::write_png_srgb(&dir.join(format!("{n}.png")), w, h, &i.data).unwrap();
        }
    }
    let glass = sphere_mask(&scene, GLASS, R, w, h);
    let mirror = sphere_mask(&scene, MIRROR, R, w, h);
    let same = |a: &ImageData, b: &ImageData, m: &[bool]| {
        let n = m.iter().filter(|&&x| x).count();
        m.iter().enumerate().filter(|(i, &x)| x && diff(a, b, *i) <= 1e-3).count() as f64 / n as f64
    };
    let (g, mi) = (same(&img, &all_rm, &glass), same(&img, &all_d, &mirror));
    eprintln!("glass pixels equal to all-refractor-map: {:.1} %, mirror pixels equal to all-distance: {:.1} %", 100.0 * g, 100.0 * mi);
    // Measured 94.1 % and 94.3 %: the glass's rim shows the mirror (traced in the mirror's
    // own distance map, which composition now shades it by: it was the sky there, 100 %
    // equal), the mirror's right side reflects the glass.
    assert!(g > 0.9 && mi > 0.9, "glass {g}, mirror {mi}");
    let reference = render_reference(&scene, &quality(&["spp=1"]), (w, h)).unwrap();
    let (gm, gr) = (masked_psnr(&img, &reference, &glass), masked_psnr(&all_rm, &reference, &glass));
    eprintln!("glass pixels: mixed {gm:.2} dB, all-refractor-map {gr:.2} dB");
    // Measured 33.73 vs 33.41 dB: the mixed glass no worse than all-refractor-map's (0.1 dB).
    assert!(gm >= gr - 0.1, "glass: mixed {gm} vs all-refractor-map {gr}");
    // Where the mirror sees the glass, the all-distance image is black (the glass in its
    // map reflects and refracts the empty sky); the mixed one shows the refracted room.
    let mut seen = Vec::new();
    for (i, &m) in mirror.iter().enumerate() {
        let lum = |im: &ImageData| (0..3).map(|c| im.data[4 * i + c]).sum::<f32>();
        if m && lum(&all_d) < 0.02 {
            seen.push(lum(&img));
        }
    }
    // Measured 38 pixels; the bound within a factor 1.122 (tests/README.md).
    assert!(seen.len() >= 34, "the mirror reflects the glass in {} pixels", seen.len());
    let bright = seen.iter().filter(|&&l| l > 0.1).count() as f64 / seen.len() as f64;
    let mean = seen.iter().sum::<f32>() / seen.len() as f32;
    let spread = seen.iter().map(|l| (l - mean).abs()).sum::<f32>() / seen.len() as f32;
    eprintln!(
        "mirror pixels black in all-distance: {}, lit in the mixed image: {:.0} %, mean {mean:.3}, spread {spread:.3}",
        seen.len(),
        100.0 * bright
    );
    // Measured: 38 such pixels, all lit, mean luminance sum 0.703, mean deviation 0.041 (the
    // bound within a factor 1.122 of it).
    assert!(bright > 0.95, "the reflected glass is lit: {bright}");
    assert!(spread >= 0.0365, "and not one flat colour: mean {mean}, spread {spread}");
    // Against the reference, the mirror of the mixed image is better than all-distance's.
    let (pm, pd) = (masked_psnr(&img, &reference, &mirror), masked_psnr(&all_d, &reference, &mirror));
    eprintln!("mirror pixels: mixed {pm:.2} dB, all-distance {pd:.2} dB");
    // Measured 29.81 vs 25.74 dB: the floor and the 4.07 dB margin each 1 dB under.
    assert!(pm >= 28.81 && pm >= pd + 3.07, "mixed {pm} vs all-distance {pd}");

    // Families that keep no cube map of their own compose too: the glass ray traced (or in
    // layered maps) gets a distance and a refractor map of its own for the mirror's map, so
    // the mirror shows it refracting the room, not a black silhouette.
    for glass_method in [specula::methods::BVH, specula::methods::LAYERED] {
        let mix = Choices { method: Choice::Auto, objects: vec![("mirror".into(), DISTANCE), ("glass".into(), glass_method)] };
        let p = plan_with(&scene, &mix, &q).unwrap();
        let g = p.objects.iter().find(|o| o.name == "glass").unwrap();
        assert!(g.map_shading == specula::plan::MapShading::Refractor && p.inter_object && p.cycles >= 2, "{glass_method}: {g:?}");
        let mixed = render(&ctx, &scene, &mix, &q, (w, h));
        let pg = masked_psnr(&mixed, &reference, &mirror);
        let lit = mirror.iter().enumerate().filter(|(i, &m)| m && (0..3).map(|c| all_d.data[4 * i + c]).sum::<f32>() < 0.02);
        let lit: Vec<f32> = lit.map(|(i, _)| (0..3).map(|c| mixed.data[4 * i + c]).sum::<f32>()).collect();
        let bright = lit.iter().filter(|&&l| l > 0.1).count() as f64 / lit.len().max(1) as f64;
        eprintln!("mirror pixels with the glass on {glass_method}: {pg:.2} dB; lit where all-distance is black: {:.0} %", 100.0 * bright);
        assert!(bright > 0.95 && pg >= pd + 3.07, "{glass_method}: mirror {pg} dB vs all-distance {pd} dB, {bright} lit");
    }
    common::assert_clean(&ctx);
}

/// Per-object choices that cannot be, each a clear error: an unknown object (named, with
/// the specular objects there are), a diffuse one (named, with its material and why: no
/// method serves it, so none is named), a method that cannot serve the object (the object,
/// the method and why).
#[test]
fn per_object_misuse_is_refused() {
    let scene = mirror_and_glass();
    let q = Quality::default();
    let choose = |name: &str, m: Method| plan_with(&scene, &Choices { method: Choice::Auto, objects: vec![(name.into(), m)] }, &q);
    let e = choose("teapot", DISTANCE).unwrap_err().to_string();
    assert!(e.contains("no object is named 'teapot'") && e.contains("glass") && e.contains("mirror"), "{e}");
    let e = choose("mirror", REFRACTOR_MAP).unwrap_err().to_string();
    assert!(e.contains("'mirror'") && e.contains("refractor-map") && e.contains("cannot serve a mirror"), "{e}");
    let wall = scene.meshes.iter().find(|m| !scene.materials[m.material].kind.is_specular()).unwrap();
    let material = &scene.materials[wall.material].name;
    let e = choose(&wall.name, DISTANCE).unwrap_err().to_string();
    assert!(
        e.contains(&format!("'{}'", wall.name))
            && e.contains("is not specular")
            && e.contains(&format!("material '{material}'"))
            && e.contains("only specular objects take a method"),
        "{e}"
    );
    assert!(Method::parse("warp").unwrap_err().to_string().contains("known: auto, envmap"));
}

/// `auto` per object: each object's reason carries its prediction and the runner-up, and
/// no whole-scene method that serves every object is predicted both faster and more accurate
/// than auto's choice (the exact tracer included); `planner=speed` is never slower.
#[test]
fn auto_predicts_per_object_and_no_single_method_beats_it() {
    let q = Quality::default();
    let demo = specula::scene::load(std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/demo/demo.gltf"))).unwrap();
    let target = specula::plan::predict::Target::nominal().unwrap();
    for (name, scene) in [("mirror and glass", mirror_and_glass()), ("demo", demo)] {
        let p = plan_with(&scene, &Choices::default(), &q).unwrap();
        for o in &p.objects {
            assert!(o.reason.starts_with("auto: predicted") && o.reason.contains("runner-up"), "{name}: {}", o.reason);
        }
        let auto = p.prediction.clone().unwrap();
        for &m in Method::ALL.iter().filter(|m| m.is_gpu()) {
            let all = Choices { method: specula::Choice::Auto, objects: p.objects.iter().map(|o| (o.name.clone(), m)).collect() };
            if plan_with(&scene, &all, &q).is_err() {
                continue;
            }
            let Some((_, _, single)) = specula::plan::predict::choose(
                &scene,
                &all,
                &q,
                specula::plan::budget::Budget::MaxMs(f64::INFINITY),
                &target,
                &["default".into()],
            )
            .unwrap() else {
                continue;
            };
            let beats = single.frame_ms < auto.frame_ms && single.specular_psnr_db > auto.specular_psnr_db;
            assert!(
                !beats,
                "{name}: {} predicted {:.2} ms {:.1} dB beats auto's {:.2} ms {:.1} dB",
                m.name(),
                single.frame_ms,
                single.specular_psnr_db,
                auto.frame_ms,
                auto.specular_psnr_db
            );
        }
        // At the same asked knobs (the helper `quality` sets cube and shadow sizes, which
        // would take the cube-size variants out of speed's candidates).
        let mut speed = q.clone();
        speed.set_pair("planner=speed").unwrap();
        let fast = plan_with(&scene, &Choices::default(), &speed).unwrap().prediction.unwrap();
        assert!(fast.frame_ms <= auto.frame_ms + 1e-9, "{name}: speed {} ms, accuracy {} ms", fast.frame_ms, auto.frame_ms);
    }
    // The scene file's choice beats the planner; --method beats the scene file.
    let mut hinted = mirror_and_glass();
    hinted.meshes.iter_mut().find(|m| m.name == "mirror").unwrap().method = Some("proxy-box".into());
    let p = plan_with(&hinted, &Choices::default(), &q).unwrap();
    let m = p.objects.iter().find(|o| o.name == "mirror").unwrap();
    assert_eq!((m.method.name(), m.reason.contains("extras.specula.method")), ("proxy-box", true));
    let p = plan_with(&hinted, &Choices::all(DISTANCE), &q).unwrap();
    assert!(p.objects.iter().all(|o| o.method == DISTANCE));
}

/// `auto` is within 0.5 dB (PSNR against the reference) of the best single approximate
/// method on each scene, and within 1 dB of its own measured PSNR there: a mirror alone, a
/// thin dielectric, the mirror-and-glass pair, the demo (a glass alone: `tests/planner.rs`'s
/// unseen glass sphere).
#[test]
fn auto_is_as_good_as_the_best_single_method() {
    let ctx = common::gpu();
    let (w, h) = (72, 48);
    // Methods compared at one set of knobs against a 1-sample reference: auto may not add
    // anti-aliasing here (tests/planner.rs measures the variants it takes against a
    // converged reference).
    let q = quality(&["plan_knobs=keep"]);
    let full = mirror_and_glass();
    let keep = |name: &str| {
        let mut s = mirror_and_glass();
        s.meshes.retain(|m| m.name != name);
        s
    };
    let mut thin = keep("glass");
    let pane = thin
        .add_material(Material { name: "pane".into(), kind: SurfaceKind::Dielectric { ior: 1.5, thin: true }, ..Default::default() })
        .unwrap();
    thin.meshes.iter_mut().find(|m| m.name == "mirror").unwrap().material = pane;
    let demo = specula::scene::load(std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/demo/demo.gltf"))).unwrap();
    // Each scene with auto's measured PSNR (72×48, cube_size 64).
    // The demo's 31.25 became 26.06 when the reference's caustics converged (progressive photon
    // mapping, 2026-12-07): its focus, sharp at one sample a pixel, is where every method's
    // light cube is blurred (refractor-map 26.05, the methods within 0.74 dB of each other).
    let scenes = [("mirror", keep("glass"), 42.26), ("thin", thin, 40.83), ("mirror+glass", full, 36.29), ("demo", demo, 26.06)];
    for (name, scene, measured) in &scenes {
        let reference = render_reference(scene, &quality(&["spp=1"]), (w, h)).unwrap();
        let psnr = |img: &ImageData| metrics::compare(img, &reference).unwrap().psnr;
        let auto = psnr(&render(&ctx, scene, &Choices::default(), &q, (w, h)));
        // The approximate single-layer methods (the exact ray tracers, survey §2, beat them
        // all, and the measuring planner takes them where it predicts their error within its
        // tolerance of the exact tracer's; tests/planner.rs). Layered maps (§4.5) measured
        // here also win on the thin pane (42.25 vs proxy-box 40.83 dB) at several times the
        // cost; curved reflectors (§5) on the mirror sphere in its box room (43.45 vs
        // proxy-box 42.26 dB). Image-based reflections (§3.3: 45.00 dB with its 8 captures)
        // and displacement-mapped proxies (§3.2: 51.82 dB, the box room's walls as height
        // maps) are left out of the singles here; proxy-relief is one of auto's candidates,
        // image-based is measured by the planner's corpus and calibration but not a
        // candidate (`predict::NOT_CANDIDATES`): its error model predicts it on the thin
        // pane at the exact tracer's 50.7 dB, where it measures 38.56 against proxy-box's
        // 40.83 (auto, taking it, measured 38.56: this test fails).
        let singles: Vec<(&str, f64)> = Method::ALL
            .iter()
            .filter(|m| {
                m.is_gpu()
                    && m.family != "raytrace"
                    && m.family != "layered"
                    && !matches!(m.name(), "curved-reflector" | "image-based" | "proxy-relief")
            })
            .map(|&m| (m.name(), psnr(&render(&ctx, scene, &whole(m), &q, (w, h)))))
            .collect();
        let best = singles.iter().cloned().fold(("", f64::MIN), |a, b| if b.1 > a.1 { b } else { a });
        let worst = singles.iter().map(|s| s.1).fold(f64::MAX, f64::min);
        eprintln!("{name}: auto {auto:.2} dB, best {} {:.2} dB, worst {worst:.2} dB; {singles:?}", best.0, best.1);
        // Measured (72×48, cube_size 64) with the rule-based planner of issue 14: mirror 42.26
        // = proxy-box (the room is its own proxy box; distance 42.05); glass 41.31 =
        // refractor-map; thin 40.83 = proxy-box; mirror+glass 36.29 vs refractor-map 33.54;
        // demo 31.25 = refractor-map (26.06 = 26.05 against the converged caustics). The measuring planner (issue 31) ray traces each of
        // them on lavapipe: at least those floors.
        assert!(auto >= best.1 - 0.5, "{name}: auto {auto} vs best {best:?}");
        // auto's own floor, 1 dB under its measured PSNR (tests/README.md rule 1).
        assert!(auto >= measured - 1.0, "{name}: auto {auto:.2} dB (measured {measured} dB)");
        if *name == "mirror+glass" {
            // Measured margin 2.75 dB (36.29 vs 33.54); the bound within 1 dB of it.
            assert!(auto > best.1 + 2.0, "mixed methods beat every single one: auto {auto} vs {best:?}");
        }
    }
    common::assert_clean(&ctx);
}

/// A reference point inside another object sees nothing but that object: the planner moves
/// it (and says why), and the image is better than with the naive point (the box centre,
/// set through the ref_point knob).
#[test]
fn reference_point_inside_another_object_is_moved() {
    let ctx = common::gpu();
    let mut scene = Scene::new();
    common::emissive_room(&mut scene, Vec3::new(0.0, 2.0, 0.0), 2.0);
    let mirror = scene.add_material(common::mirror(0.9)).unwrap();
    let core = scene
        .add_material(Material { name: "core".into(), base_color: Vec3::ZERO, emissive: Vec3::new(1.0, 0.0, 1.0), ..Default::default() })
        .unwrap();
    let c = Vec3::new(0.0, 1.5, 0.0);
    // A mirror sphere with a small closed box hidden inside it, around its centre.
    scene.add_mesh(shapes::uv_sphere("mirror", c, 0.5, 48, 24, mirror)).unwrap();
    scene.add_mesh(shapes::uv_sphere("core", c, 0.12, 12, 6, core)).unwrap();
    scene.camera = Some(Camera::look_at(Vec3::new(0.0, 1.7, 1.8), c, 45f32.to_radians()));
    let q = quality(&[]);
    let p = plan_with(&scene, &Choices::default(), &q).unwrap();
    let o = &p.objects[0];
    let note = o.reference_note.clone().unwrap_or_default();
    eprintln!("reference point {:?}: {note}", o.reference_point);
    assert!(note.contains("inside 'core'"), "{note}");
    // Out of the core (radius 0.12) and still inside the mirror (radius 0.5): measured 0.125
    // from the centre.
    let moved_by = o.reference_point.distance(c);
    eprintln!("reference point moved {moved_by:.4} from the centre");
    assert!(moved_by > 0.12 && moved_by < 0.5, "moved out of the core: {:?}", o.reference_point);
    let (w, h) = (64, 64);
    let reference = render_reference(&scene, &quality(&["spp=1"]), (w, h)).unwrap();
    let mask = sphere_mask(&scene, c, 0.5, w, h);
    let moved = render(&ctx, &scene, &whole(DISTANCE), &q, (w, h));
    let naive = render(&ctx, &scene, &whole(DISTANCE), &quality(&["ref_point=0,1.5,0"]), (w, h));
    let (pm, pn) = (masked_psnr(&moved, &reference, &mask), masked_psnr(&naive, &reference, &mask));
    eprintln!("mirror pixels: moved point {pm:.2} dB, naive point {pn:.2} dB");
    // Measured 11.02 vs 6.48 dB: the floor and the 4.54 dB margin each 1 dB under.
    assert!(pm >= 10.02 && pm >= pn + 3.54, "moved {pm} vs naive {pn}");
    common::assert_clean(&ctx);
}

/// `specula plan SCENE --method auto`: per object its method, reason, maps with sizes and
/// memory, passes and knobs, as a table and as JSON; `--object` overrides one object.
#[test]
fn plan_command_prints_per_object_methods() {
    let exe = env!("CARGO_BIN_EXE_specula");
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/demo/demo.gltf");
    let run = |args: &[&str]| {
        let o = std::process::Command::new(exe).args(args).output().unwrap();
        assert!(o.status.success(), "{args:?}: {}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8(o.stdout).unwrap()
    };
    // `specula knobs` lists every registered method once, with its C ABI number.
    let knobs = run(&["knobs"]);
    for m in Method::ALL {
        let rows: Vec<&str> = knobs.lines().filter(|l| l.split_whitespace().next() == Some(m.name())).collect();
        assert_eq!(rows.len(), 1, "{}: {rows:?}", m.name());
        assert_eq!(rows[0].split_whitespace().nth(1), Some(m.abi.to_string().as_str()), "{}", rows[0]);
    }
    let table = run(&["plan", scene, "--object", "glass_sphere=refractor-map"]);
    for want in [
        "method auto",
        "mirror_sphere/0 (mirror, material 'mirror'): ",
        "auto: predicted",
        "glass_sphere/0 (solid dielectric, material 'glass'): refractor-map",
        "reason",
        "MiB",
        "knobs",
        "internal_bounces=2",
    ] {
        assert!(table.contains(want), "plan table lacks {want}:\n{table}");
    }
    let json: serde_json::Value = serde_json::from_str(&run(&["plan", scene, "--method", "distance", "--json"])).unwrap();
    let objects = json["objects"].as_array().unwrap();
    assert_eq!(objects.len(), 2);
    for o in objects {
        assert!(o["maps"].as_array().is_some_and(|m| !m.is_empty() && m[0]["bytes"].as_u64().unwrap() > 0), "{o}");
    }
    let json: serde_json::Value = serde_json::from_str(&run(&["plan", scene, "--json"])).unwrap();
    assert!(json["in_view"].is_array(), "the pairs in view: {json}");
    assert!(json["objects"].as_array().unwrap().iter().all(|o| o["reason"].as_str().unwrap().starts_with("auto: predicted")), "{json}");
    // --candidates: each object's Pareto set of predictions.
    let candidates = run(&["plan", scene, "--candidates"]);
    // An exact tracer is on the front (which scheme depends on the device's unit costs: bvh
    // with the stored calibration, ray-query where it dominates bvh).
    let exact = ["bvh", "kd-tree", "grid", "octree", "bih", "ray-query"].iter().any(|m| candidates.contains(&format!("  {m} ")));
    assert!(candidates.contains("mirror_sphere/0: ") && candidates.contains("on the Pareto front") && exact, "{candidates}");
    let json: serde_json::Value = serde_json::from_str(&run(&["plan", scene, "--object", "mirror_sphere=proxy-box", "--json"])).unwrap();
    let mirror = json["objects"].as_array().unwrap().iter().find(|o| o["name"] == "mirror_sphere/0").unwrap().clone();
    assert_eq!(mirror["method"], "proxy-box");
    // A bad --object is a one-line error naming the object.
    let o = std::process::Command::new(exe).args(["plan", scene, "--object", "teapot=distance"]).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!((o.status.code(), err.lines().count()), (Some(1), 1), "{err}");
    assert!(err.contains("teapot"), "{err}");
}

/// Pixels of the sphere (centre `c`) whose reflected ray meets the sphere `other` first of
/// the two: where the first object shows the second (issue 33's composition).
fn sees_mask(scene: &Scene, c: Vec3, other: Vec3, (w, h): (u32, u32)) -> Vec<bool> {
    let rays = CameraRays::new(&scene.camera.unwrap(), w, h);
    let hit = |o: glam::DVec3, d: glam::DVec3, c: Vec3| {
        let oc = o - c.as_dvec3();
        let b = oc.dot(d);
        let disc = b * b - (oc.length_squared() - (R as f64).powi(2));
        (disc > 0.0).then(|| -b - disc.sqrt()).filter(|&t| t > 1e-6)
    };
    let mut mask = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let (o, d, _) = rays.ray(x as f64 + 0.5, y as f64 + 0.5);
            let seen = hit(o, d, c).filter(|&t| hit(o, d, other).is_none_or(|u| t < u)).is_some_and(|t| {
                let p = o + d * t;
                let n = (p - c.as_dvec3()).normalize();
                let r = d - 2.0 * d.dot(n) * n;
                hit(p + n * 1e-6, r, other).is_some()
            });
            mask.push(seen);
        }
    }
    mask
}

/// Mean and standard deviation of the luminance sum over the masked pixels.
fn luminance_stats(img: &ImageData, mask: &[bool]) -> (f64, f64) {
    let l: Vec<f64> = mask.iter().enumerate().filter(|(_, &m)| m).map(|(i, _)| (0..3).map(|c| img.data[4 * i + c] as f64).sum()).collect();
    let mean = l.iter().sum::<f64>() / l.len().max(1) as f64;
    let var = l.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / l.len().max(1) as f64;
    (mean, var.sqrt())
}

/// Issue 33's composition matrix: a mirror sphere and a glass sphere in mutual view, each
/// pair of the methods that serve them (`--object mirror=A --object glass=B`), against the
/// exact reference. Per pair, on the mirror's pixels that reflect the glass (and the glass's
/// pixels that reflect the mirror): the other object is not a black or flat blob (its
/// luminance within a factor of the reference's in mean and spread), and each object is
/// no worse than under its own method alone (1 dB). The table is printed (BENCHMARKS.md).
/// Measured at 64×44: before composition covered them, the glass in the mirror was black
/// (mean 0.02–0.09 of the reference's 0.589) with the mirror on curved-reflector (every glass
/// method) and on distance or distance-multi beside a glass on distance or image-space
/// refraction (the mirror 25.87 dB where alone it had 29.41); the environment-mapping
/// methods showed it at 0.32–0.50 (their radiance cubes reflected the sky there), and
/// image-based and proxy-relief mirrors at 0.02–0.07 beside every glass method but
/// refractor-map. Now the glass in the mirror has 0.69–1.25 of the reference's mean and
/// 0.51–2.01 of its spread over every pair, the mirror seen in the glass 0.76–1.98 of its
/// mean (distance's single refraction brightest); bounds: mean within [0.5, 2], spread
/// within [0.35, 2.8], the mirror in the glass within [0.5, 2.8]. `compose=off` puts the sky
/// back: the glass in an envmap mirror at 0.50 of the reference (asserted below 0.7).
#[test]
fn composition_matrix() {
    use specula::methods::*;
    let ctx = common::gpu();
    let scene = common::mirror_and_glass(32);
    let q = quality(&["depth=4"]);
    let size = (64, 44);
    let reference = render_reference(&scene, &quality(&["depth=4", "spp=1"]), size).unwrap();
    let (mirror, glass) = (sphere_mask(&scene, MIRROR, R, size.0, size.1), sphere_mask(&scene, GLASS, R, size.0, size.1));
    let (mirror_sees, glass_sees) = (sees_mask(&scene, MIRROR, GLASS, size), sees_mask(&scene, GLASS, MIRROR, size));
    let count = |m: &[bool]| m.iter().filter(|&&x| x).count();
    eprintln!(
        "mirror pixels {} ({} reflect the glass), glass pixels {} ({} reflect the mirror)",
        count(&mirror),
        count(&mirror_sees),
        count(&glass),
        count(&glass_sees)
    );
    let mirror_methods =
        [ENVMAP, PROXY_SPHERE, PROXY_BOX, IMAGE_BASED, PROXY_RELIEF, DISTANCE, DISTANCE_MULTI, LAYERED, CURVED_REFLECTOR, BVH];
    let glass_methods = [ENVMAP, REFRACTOR_MAP, IMAGE_SPACE_REFRACTION, DISTANCE, LAYERED, BVH];
    let alone = |m: Method| render(&ctx, &scene, &whole(m), &q, size);
    let own_mirror: Vec<f64> = mirror_methods.iter().map(|&m| masked_psnr(&alone(m), &reference, &mirror)).collect();
    let own_glass: Vec<f64> = glass_methods.iter().map(|&m| masked_psnr(&alone(m), &reference, &glass)).collect();
    let (ref_ms, ref_gs) = (luminance_stats(&reference, &mirror_sees), luminance_stats(&reference, &glass_sees));
    eprintln!(
        "reference: mirror-sees-glass mean {:.3} sd {:.3}; glass-sees-mirror mean {:.3} sd {:.3}",
        ref_ms.0, ref_ms.1, ref_gs.0, ref_gs.1
    );
    eprintln!("| mirror \\ glass | {} |", glass_methods.map(|m| m.name()).join(" | "));
    let mut bad = Vec::new();
    for (i, &a) in mirror_methods.iter().enumerate() {
        let mut row = Vec::new();
        for (j, &b) in glass_methods.iter().enumerate() {
            let pair = Choices { method: Choice::Auto, objects: vec![("mirror".into(), a), ("glass".into(), b)] };
            let img = render(&ctx, &scene, &pair, &q, size);
            let (pm, pg) = (masked_psnr(&img, &reference, &mirror), masked_psnr(&img, &reference, &glass));
            let (ms, gs) = (luminance_stats(&img, &mirror_sees), luminance_stats(&img, &glass_sees));
            row.push(format!("{pm:.1} / {pg:.1} dB, seen {:.2}/{:.2}, {:.2}", ms.0 / ref_ms.0, ms.1 / ref_ms.1, gs.0 / ref_gs.0));
            let name = format!("mirror={} glass={}", a.name(), b.name());
            // No blob: the glass in the mirror has the reference's luminance and spread
            // within a factor.
            let within = |v: f64, r: f64, lo: f64, hi: f64| v >= lo * r && v <= hi * r;
            if !within(ms.0, ref_ms.0, 0.5, 2.0) || !within(ms.1, ref_ms.1, 0.35, 2.8) {
                bad.push(format!(
                    "{name}: the glass in the mirror mean {:.3} sd {:.3} (reference {:.3} / {:.3})",
                    ms.0, ms.1, ref_ms.0, ref_ms.1
                ));
            }
            // And the mirror in the glass's reflection (a weak reflection, a flat spot in the
            // reference: its mean only).
            if !within(gs.0, ref_gs.0, 0.5, 2.8) {
                bad.push(format!("{name}: the mirror in the glass mean {:.3} (reference {:.3})", gs.0, ref_gs.0));
            }
            // Composition makes no object worse than its method alone (1 dB).
            if pm < own_mirror[i] - 1.0 || pg < own_glass[j] - 1.0 {
                bad.push(format!("{name}: mirror {pm:.2} dB (alone {:.2}), glass {pg:.2} dB (alone {:.2})", own_mirror[i], own_glass[j]));
            }
        }
        eprintln!("| {} | {} |", a.name(), row.join(" | "));
    }
    for b in &bad {
        eprintln!("{b}");
    }
    assert!(bad.is_empty(), "{} pair(s) do not compose:\n{}", bad.len(), bad.join("\n"));
    // The plan names per pair in view how each shows in the other's view; compose=off keeps
    // the environment-mapped mirror's radiance cube reflecting the sky where the glass is.
    let pair = Choices { method: Choice::Auto, objects: vec![("mirror".into(), ENVMAP), ("glass".into(), REFRACTOR_MAP)] };
    let plan = plan_with(&scene, &pair, &q).unwrap();
    let lines = specula::plan::in_view(&plan, &scene);
    assert!(lines.iter().any(|l| l.contains("mirror shows glass: in its maps refracted through its refractor map")), "{lines:?}");
    assert!(lines.iter().any(|l| l.contains("glass shows mirror: in its maps traced in its own distance map")), "{lines:?}");
    assert!(plan.map("envmap.generate").is_none(), "{:?}", plan.passes);
    let off = quality(&["depth=4", "compose=off"]);
    let plan = plan_with(&scene, &pair, &off).unwrap();
    assert!(plan.map("envmap.generate").is_some() && !plan.inter_object, "{:?}", plan.passes);
    assert!(specula::plan::in_view(&plan, &scene).iter().any(|l| l.contains("environment map's reflection (compose=off)")));
    let sky = luminance_stats(&render(&ctx, &scene, &pair, &off, size), &mirror_sees);
    eprintln!("compose=off: the glass in the envmap mirror {:.2} of the reference's mean", sky.0 / ref_ms.0);
    assert!(sky.0 < 0.7 * ref_ms.0, "compose=off: {sky:?} against the reference's {ref_ms:?}");
    common::assert_clean(&ctx);
}

/// KHR_materials_volume on every method that renders solid glass, σ = (0.3, 1, 2.5) /m,
/// ν 1.5, in the emissive room. Per method and channel, the mean radiance over the object's
/// pixels with absorption divided by the same without it must match the reference's ratio
/// (each method's own error cancels; what is left is how much it absorbs). A sphere
/// (radius 0.6), which no ray entering from outside leaves by total internal reflection:
/// every method that renders it, the single-refraction ones by the chord through its bounds
/// (exact for a sphere). An axis-aligned cube (1.2 m across), inside which most paths
/// reflect totally: the methods that follow those paths (the exact tracer, refractor maps,
/// layered maps, planar-refraction's views from inside).
#[test]
fn absorption_on_every_dielectric_method() {
    let ctx = common::gpu();
    let sigma = Vec3::new(0.3, 1.0, 2.5);
    let scene = |cube: bool, absorption: Vec3| {
        let mut s = Scene::new();
        common::emissive_room(&mut s, Vec3::ZERO, 2.0);
        let m =
            s.add_material(Material { kind: SurfaceKind::Dielectric { ior: 1.5, thin: false }, absorption, ..Default::default() }).unwrap();
        let c = Vec3::new(0.0, -0.3, -0.3);
        let mesh = if cube { shapes::cuboid("glass", c, Vec3::splat(0.6), m) } else { shapes::uv_sphere("glass", c, 0.6, 48, 24, m) };
        s.add_mesh(mesh).unwrap();
        s.camera = Some(Camera::look_at(Vec3::new(1.2, 0.8, 1.5), c, 55f32.to_radians()));
        s
    };
    let size = (40, 32);
    // One sample at the pixel's centre, as the GPU's.
    let q = quality(&["depth=6", "spp=1"]);
    // The bound on each method's relative error (the largest channel's), about 1.5× what was
    // measured: sphere bvh 0.000 (f32 against f64), layered 0.009, refractor-map 0.004,
    // image-space-refraction 0.199 (its interpolated distance to the back face), distance
    // 0.120 and envmap 0.100 (one refraction: the paths' weights differ, not the chord);
    // cube bvh 0.000, layered 0.008, refractor-map 0.119 (internal_bounces cuts the longest
    // paths) and planar-refraction 0.069. A method that ignores absorption is off by 0.36 to
    // 6.9 (the reference's ratios: sphere (0.73, 0.42, 0.13), cube (0.67, 0.33, 0.14)).
    let sphere = [(BVH, 1e-3), (LAYERED, 0.02), (REFRACTOR_MAP, 0.02), (IMAGE_SPACE_REFRACTION, 0.3), (DISTANCE, 0.18), (ENVMAP, 0.15)];
    let cube = [(BVH, 1e-3), (LAYERED, 0.02), (REFRACTOR_MAP, 0.18), (PLANAR_REFRACTION, 0.11)];
    for (is_cube, methods) in [(false, &sphere[..]), (true, &cube[..])] {
        let (clear, absorbing) = (scene(is_cube, Vec3::ZERO), scene(is_cube, sigma));
        let ids = specula::reference::object_ids(&absorbing, size).unwrap();
        let glass = absorbing.meshes.iter().position(|m| m.name == "glass").unwrap() as u32 + 1;
        let mask: Vec<bool> = ids.iter().map(|&i| i == glass).collect();
        let mean = |img: &ImageData| {
            let mut sum = Vec3::ZERO;
            for (i, _) in mask.iter().enumerate().filter(|(_, &m)| m) {
                sum += Vec3::new(img.data[4 * i], img.data[4 * i + 1], img.data[4 * i + 2]);
            }
            sum / mask.iter().filter(|&&m| m).count() as f32
        };
        let ratio = |a: &ImageData, c: &ImageData| mean(a) / mean(c);
        let expected = ratio(&render_reference(&absorbing, &q, size).unwrap(), &render_reference(&clear, &q, size).unwrap());
        let what = if is_cube { "cube" } else { "sphere" };
        eprintln!("{what}, reference: absorbed / clear = {expected}");
        for &(m, bound) in methods {
            let got = ratio(&render(&ctx, &absorbing, &whole(m), &q, size), &render(&ctx, &clear, &whole(m), &q, size));
            let err = ((got - expected) / expected).abs().max_element();
            eprintln!("{what}, {m}: absorbed / clear = {got} (relative error {err:.3})");
            assert!(
                err < bound,
                "{what}, {m}: absorbed / clear {got} against the reference's {expected}: relative error {err:.3} ≥ {bound}"
            );
        }
    }
    common::assert_clean(&ctx);
}

/// KHR_materials_dispersion through a 60° prism (ν_d 1.5, dispersion 1: Abbe number 20) seen
/// against a black sky with one narrow vertical stripe of light: each channel sees the
/// stripe where its own refraction, in and out, bends the camera ray onto it. The expected
/// column per channel is the closed form (Snell at both faces with the channel's index at
/// its Fraunhofer line, `Material::channel_iors`), the centroid of the stripe's image along
/// the middle row; red and blue land about 39 pixels apart, where a method that ignored
/// dispersion would put them on one column. The reference and the exact tracer follow each
/// channel's path; refractor maps and layered maps search the exit in their maps (a flat
/// exit face: its normal, and so the exit direction, exact).
#[test]
fn dispersion_splits_the_channels_through_a_prism() {
    use specula::scene::EnvironmentMap;
    let ctx = common::gpu();
    let mut s = Scene::new();
    let glass = Material { kind: SurfaceKind::Dielectric { ior: 1.5, thin: false }, dispersion: 1.0, ..Default::default() };
    let iors = glass.channel_iors().unwrap();
    let m = s.add_material(glass).unwrap();
    // An equilateral prism about the vertical axis, turned so that the camera's central
    // ray meets its first face near minimum deviation (incidence asin(ν sin 30°) ≈ 48.6°).
    let c = Vec3::new(0.0, 0.0, -3.0);
    let turn = glam::Quat::from_rotation_y((60.0f32 - 41.4).to_radians());
    let corners: [Vec3; 3] = std::array::from_fn(|j| {
        let a = (120.0 * j as f32).to_radians();
        turn * (Vec3::new(a.cos(), 0.0, a.sin()) * 1.2)
    });
    s.add_mesh(shapes::prism("prism", c, Vec3::Y, 1.0, corners, m)).unwrap();
    s.camera = Some(Camera::look_at(Vec3::ZERO, Vec3::NEG_Z, 0.5f32.to_radians()));
    let (w, h) = (160u32, 9u32);
    let rays = CameraRays::new(&s.camera.unwrap(), w, h);
    let row = (h / 2) as f64 + 0.5;
    // The closed form: each face's outward normal from its corners (face 0: corners 0–1,
    // the one the camera sees; the ray leaves through face 2: corners 2–0).
    let normal = |a: Vec3, b: Vec3| {
        let e = (b - a).as_dvec3();
        let n = glam::DVec3::new(e.z, 0.0, -e.x).normalize();
        let mid = ((a + b) * 0.5).as_dvec3();
        if n.dot(mid) < 0.0 {
            -n
        } else {
            n
        }
    };
    let (n0, n2) = (normal(corners[0], corners[1]), normal(corners[2], corners[0]));
    let exit = |x: f64, nu: f64| {
        let (_, d, _) = rays.ray(x, row);
        let t1 = specula::optics::refract_dir(d, n0, 1.0 / nu).unwrap();
        specula::optics::refract_dir(t1, -n2, nu).unwrap()
    };
    // u of the equirectangular map (docs/conventions.md) along a direction.
    let u_of = |d: glam::DVec3| 0.5 + d.x.atan2(-d.z) / std::f64::consts::TAU;
    // The stripe where green's central ray goes, 0.15° wide (σ).
    let u_stripe = u_of(exit(w as f64 / 2.0, iors.y as f64));
    let sigma = 0.15 / 360.0;
    let stripe = |u: f64| (-0.5 * ((u - u_stripe) / sigma).powi(2)).exp();
    let env_w = 8192u32;
    let mut env = EnvironmentMap { width: env_w, height: 4, rgba32f: Vec::new() };
    for _ in 0..4 {
        for x in 0..env_w {
            let v = stripe((x as f64 + 0.5) / env_w as f64) as f32;
            env.rgba32f.extend([v, v, v, 1.0]);
        }
    }
    s.environment = Some(env);
    let centroid = |f: &dyn Fn(u32) -> f64| {
        let (mut sum, mut wsum) = (0.0, 0.0);
        for x in 0..w {
            let v = f(x);
            sum += v * (x as f64 + 0.5);
            wsum += v;
        }
        sum / wsum
    };
    let expected: [f64; 3] = std::array::from_fn(|k| centroid(&|x| stripe(u_of(exit(x as f64 + 0.5, iors[k] as f64)))));
    eprintln!("closed form: the stripe at columns {expected:.2?} (ν {iors})");
    assert!(expected[2] - expected[0] > 30.0, "the channels separate: {expected:?}");
    let measured = |img: &ImageData| -> [f64; 3] {
        let y = (h / 2) as usize;
        std::array::from_fn(|k| centroid(&|x| img.data[4 * (y * w as usize + x as usize) + k] as f64))
    };
    let q = quality(&["depth=4", "spp=1", "fresnel=exact", "cube_size=128"]);
    let reference = measured(&render_reference(&s, &q, (w, h)).unwrap());
    eprintln!("reference: {reference:.2?}");
    let mut results: Vec<(&str, [f64; 3], f64)> = vec![("reference", reference, 0.0)];
    // Bounds in pixels, about 1.5× what was measured, at least 0.25: reference and bvh 0.00,
    // layered 0.03, refractor-map 0.54 (all three channels alike: the exit point its search
    // finds, not the dispersion). Measured closed form: columns (68.35, 80.02, 107.67).
    for (m, bound) in [(BVH, 0.25), (REFRACTOR_MAP, 0.8), (LAYERED, 0.25)] {
        let got = measured(&render(&ctx, &s, &whole(m), &q, (w, h)));
        eprintln!("{m}: {got:.2?}");
        results.push((m.0, got, bound));
    }
    for (name, got, bound) in results {
        for k in 0..3 {
            let err = (got[k] - expected[k]).abs();
            assert!(err <= bound.max(0.25), "{name}, channel {k}: column {:.2} against {:.2}", got[k], expected[k]);
        }
    }
    common::assert_clean(&ctx);
}
