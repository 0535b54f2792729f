//! Layered distance maps (survey §4.5, UPSK07) against the exact CPU reference, on
//! lavapipe with validation on: a concave mirror that reflects itself, a non-convex glass
//! object, Figure 28's search-step and layer-count artefacts, and what the map allocates.
//! Images are small (64²–96²); floors sit within 1 dB of what was measured (stated beside
//! each).

mod common;

use glam::Vec3;
use specula::metrics::{self, ImageErrors};
use specula::reference::render_reference;
use specula::scene::{shapes, Camera, Material, Mesh, Scene, SurfaceKind};
use specula::vk::{Context, ImageData};
use specula::{Method, Quality};

fn quality(pairs: &[&str]) -> Quality {
    let mut q = Quality::default();
    for p in pairs {
        q.set_pair(p).unwrap();
    }
    q
}

fn gpu(ctx: &Context, scene: &Scene, method: Method, pairs: &[&str], size: u32) -> (ImageData, Vec<(String, f64)>) {
    let f = specula::render(ctx, scene, method, &quality(pairs), (size, size), (0, 1)).unwrap();
    (f.image, f.stats)
}

fn reference(scene: &Scene, pairs: &[&str], size: u32) -> ImageData {
    render_reference(scene, &quality(pairs), (size, size)).unwrap()
}

fn errors(test: &ImageData, reference: &ImageData) -> ImageErrors {
    metrics::compare(test, reference).unwrap()
}

fn stat(stats: &[(String, f64)], name: &str) -> f64 {
    stats.iter().find(|(n, _)| n == name).unwrap_or_else(|| panic!("no stat {name} in {stats:?}")).1
}

/// The lower part of a sphere (centre `c`, radius `r`) below y = c.y + `cut`·r: a concave
/// bowl open upwards.
fn bowl(name: &str, c: Vec3, r: f32, cut: f32, material: usize) -> Mesh {
    let s = shapes::uv_sphere(name, c, r, 64, 32, material);
    let mut m = Mesh { name: name.into(), material, ..Default::default() };
    let keep = |i: u32| s.positions[i as usize].y < c.y + cut * r;
    let mut remap = vec![u32::MAX; s.positions.len()];
    for t in s.indices.chunks(3) {
        if !t.iter().all(|&i| keep(i)) {
            continue;
        }
        for &i in t {
            if remap[i as usize] == u32::MAX {
                remap[i as usize] = m.positions.len() as u32;
                m.positions.push(s.positions[i as usize]);
                // The inside of the bowl faces its centre.
                m.normals.push(-s.normals[i as usize]);
                m.uvs.push(s.uvs[i as usize]);
            }
            m.indices.push(remap[i as usize]);
        }
    }
    m
}

/// The emissive quadrant room with a mirror bowl (a hemisphere, F0 0.9) and a small
/// emissive ball inside it, seen from above at an angle: the bowl reflects the ball and
/// itself.
fn bowl_scene() -> Scene {
    let mut s = Scene::new();
    common::emissive_room(&mut s, Vec3::new(0.0, 2.0, 0.0), 2.0);
    let m = s.add_material(common::mirror(0.9)).unwrap();
    let ball = s
        .add_material(Material { name: "ball".into(), base_color: Vec3::ZERO, emissive: Vec3::new(1.0, 0.6, 0.2), ..Default::default() })
        .unwrap();
    s.add_mesh(bowl("bowl", Vec3::new(0.0, 1.6, 0.0), 1.0, 0.0, m)).unwrap();
    s.add_mesh(shapes::uv_sphere("ball", Vec3::new(0.25, 0.95, 0.1), 0.18, 24, 12, ball)).unwrap();
    s.camera = Some(Camera::look_at(Vec3::new(0.0, 3.3, 1.6), Vec3::new(0.0, 1.0, 0.0), 45f32.to_radians()));
    s
}

/// A torus around the y axis through `c` (ring radius `big`, tube radius `small`),
/// `n`×`n/2` quads, outward normals.
fn torus(name: &str, c: Vec3, big: f32, small: f32, n: u32, material: usize) -> Mesh {
    let mut m = Mesh { name: name.into(), material, ..Default::default() };
    let k = n / 2;
    for i in 0..=n {
        let u = i as f32 / n as f32 * std::f32::consts::TAU;
        for j in 0..=k {
            let v = j as f32 / k as f32 * std::f32::consts::TAU;
            let ring = Vec3::new(u.cos(), 0.0, u.sin());
            let normal = ring * v.cos() + Vec3::Y * v.sin();
            m.positions.push(c + ring * big + normal * small);
            m.normals.push(normal);
            m.uvs.push(glam::Vec2::new(i as f32 / n as f32, j as f32 / k as f32));
        }
    }
    for i in 0..n {
        for j in 0..k {
            let a = i * (k + 1) + j;
            let b = (i + 1) * (k + 1) + j;
            m.indices.extend_from_slice(&[a, a + 1, b, b, a + 1, b + 1]);
        }
    }
    m
}

/// The emissive room with a solid glass torus (ν 1.5) seen from above at an angle: its
/// reference point (the hole's centre) sees only the inner side of the tube.
fn torus_scene() -> Scene {
    let mut s = Scene::new();
    common::emissive_room(&mut s, Vec3::new(0.0, 2.0, 0.0), 2.0);
    let glass = s
        .add_material(Material { name: "glass".into(), kind: SurfaceKind::Dielectric { ior: 1.5, thin: false }, ..Default::default() })
        .unwrap();
    s.add_mesh(torus("torus", Vec3::new(0.0, 1.2, 0.0), 0.7, 0.3, 48, glass)).unwrap();
    s.camera = Some(Camera::look_at(Vec3::new(0.0, 2.9, 1.9), Vec3::new(0.0, 1.1, 0.0), 50f32.to_radians()));
    s
}

/// `scene` with every position, the camera and the lights scaled by `k`.
fn scale_scene(scene: &Scene, k: f32) -> Scene {
    let mut out = scene.clone();
    for m in &mut out.meshes {
        for p in &mut m.positions {
            *p *= k;
        }
    }
    let mut cam = scene.camera_or_default();
    cam.position *= k;
    cam.world_from_camera.w_axis = (cam.world_from_camera.w_axis.truncate() * k).extend(1.0);
    cam.znear *= k;
    cam.zfar = cam.zfar.map(|z| z * k);
    out.camera = Some(cam);
    out
}

const SIZE: u32 = 64;

#[test]
fn a_concave_mirror_reflects_itself_in_the_layers() {
    // The bowl sees itself and the ball inside it: a single-layer distance map leaves the
    // bowl out of its own map (it reflects the room where the bowl should be), the layered
    // map holds the bowl, the ball and what they hide. At each recursion depth R the
    // reference follows R bounces too.
    let ctx = common::gpu();
    let s = bowl_scene();
    let mut rows = Vec::new();
    let mut prev: Option<ImageData> = None;
    for depth in [1, 2, 3, 4] {
        let d = format!("depth={depth}");
        let r = reference(&s, &["spp=1", &d, "caustics=off"], SIZE);
        let knobs = [d.as_str(), "caustics=off", "cube_size=128"];
        let (l, stats) = gpu(&ctx, &s, specula::methods::LAYERED, &knobs, SIZE);
        let (dm, _) = gpu(&ctx, &s, specula::methods::DISTANCE, &knobs, SIZE);
        let l_img = l;
        let (l, dm) = (errors(&l_img, &r), errors(&dm, &r));
        eprintln!("bowl depth {depth}: layered {l}\n              distance {dm}");
        // Each depth is closer to its reference than the previous depth's image: the layers
        // are searched again for every bounce (a search that stops early fails).
        let over_prev = prev.as_ref().map(|p| {
            let pe = errors(p, &r);
            eprintln!("              previous depth's image {pe}");
            l.psnr - pe.psnr
        });
        prev = Some(l_img);
        assert_eq!(stat(&stats, "layered.layers"), 4.0, "ball front and back, bowl, floor");
        // Each face peels only the layers its texels reach (measured 17 of the 24 passes),
        // within the rectangle of its texels that meet that many surfaces; the plan's count
        // (on the CPU, along the texel rays of at most 64² per face) predicts what it draws.
        let (peeled, drawn) = (stat(&stats, "layered.faces_peeled"), stat(&stats, "layered.cubes_drawn"));
        let plan = specula::plan_with(&s, &specula::Choices::all(specula::methods::LAYERED), &quality(&knobs)).unwrap();
        let predicted = specula::methods::layered::drawn_cubes(&plan.quality, plan.layered_extent.as_ref());
        eprintln!("faces peeled {peeled} of 24, cubes drawn {drawn:.3} (predicted {predicted:.3})");
        // Measured: 17 passes, 1.972 cubes of texels of the 4 allocated, predicted 2.053.
        assert!(peeled == 17.0 && (1.972 / 1.122..=1.972 * 1.122).contains(&drawn), "{peeled} passes, {drawn} cubes");
        assert!((predicted / drawn - 1.0).abs() < 0.1, "drawn {drawn}, predicted {predicted}");
        rows.push((depth, l.psnr, dm.psnr, over_prev));
    }
    // Measured (depth 1, 2, 3, 4): layered 23.44, 23.48, 23.50, 23.83 dB; over distance
    // 12.60, 11.04, 10.28, 10.15 dB; over the previous depth's image 9.93, 4.14, 1.31 dB.
    // Floors 1 dB under each (the depth-3 margin 3.13, a hundredth lower, is not clippy's π);
    // the depth-4 margin, under 1 dB, at half the measured value.
    let floors = [(22.44, 11.60, 0.0), (22.48, 10.04, 8.93), (22.50, 9.28, 3.13), (22.83, 9.15, 0.31)];
    for ((depth, l, d, over_prev), (floor, over_distance, prev_floor)) in rows.iter().zip(floors) {
        assert!(*l > floor, "depth {depth}: layered {l:.2} dB");
        assert!(l - d > over_distance, "depth {depth}: layered {l:.2} vs distance {d:.2} dB");
        if let Some(m) = over_prev {
            assert!(*m > prev_floor, "depth {depth}: layered {l:.2} dB, {m:.2} dB over the previous depth's image");
        }
    }
    // distance-multi has no other specular object to cycle through: it is distance.
    let q = ["depth=4", "caustics=off", "cube_size=128"];
    let (a, _) = gpu(&ctx, &s, specula::methods::DISTANCE, &q, SIZE);
    let (b, _) = gpu(&ctx, &s, specula::methods::DISTANCE_MULTI, &q, SIZE);
    assert_eq!(a.data, b.data, "distance-multi with one specular object is distance");
    common::assert_clean(&ctx);
}

#[test]
fn a_non_convex_glass_torus_refracts_through_both_sides_of_its_tube() {
    // From the hole's centre only the inner side of the tube is visible: the refractor map
    // (one layer) misses the outer side, so refracted rays leave the glass in the wrong
    // place; the layered map holds all three surfaces along a ray (depth complexity 3).
    let ctx = common::gpu();
    let s = torus_scene();
    let r = reference(&s, &["spp=1", "caustics=off"], SIZE);
    let knobs = ["caustics=off", "cube_size=128"];
    let (l, stats) = gpu(&ctx, &s, specula::methods::LAYERED, &knobs, SIZE);
    let (rm, _) = gpu(&ctx, &s, specula::methods::REFRACTOR_MAP, &knobs, SIZE);
    let (strongest, _) = gpu(&ctx, &s, specula::methods::LAYERED, &["caustics=off", "cube_size=128", "layered_branches=strongest"], SIZE);
    let (l, rm, strongest) = (errors(&l, &r), errors(&rm, &r), errors(&strongest, &r));
    eprintln!("torus: layered {l}\n       refractor-map {rm}\n       layered, strongest branch only {strongest}");
    assert_eq!(stat(&stats, "layered.layers"), 3.0);
    // Measured: layered 25.11 dB, refractor-map 12.69 dB (12.42 dB under), strongest
    // branch 24.16 dB; floors 1 dB under.
    assert!(l.psnr > 24.11, "layered {l}");
    assert!(l.psnr - rm.psnr > 11.42, "layered {l} vs refractor-map {rm}");
    // Both Fresnel branches beat the stronger one carrying both weights (the reflections
    // of the room in the glass are lost): measured by 0.95 dB; under 1 dB, so asserted at
    // half of it (a knob that is ignored gives 0).
    assert!(l.psnr - strongest.psnr > 0.47, "both {l} vs strongest {strongest}");
    common::assert_clean(&ctx);
}

/// The bowl scene with a thin emissive rod (2 cm) standing in the bowl (Figure 28's green
/// and red frames).
fn rod_scene() -> Scene {
    let mut s = bowl_scene();
    let rod = s
        .add_material(Material { name: "rod".into(), base_color: Vec3::ZERO, emissive: Vec3::new(0.1, 1.0, 0.2), ..Default::default() })
        .unwrap();
    s.add_mesh(shapes::quad("rod", Vec3::new(-0.45, 0.75, -0.2), Vec3::new(0.02, 0.0, 0.0), Vec3::new(0.0, 0.9, 0.0), 1, rod)).unwrap();
    s
}

#[test]
fn figure_28_thin_objects_need_fine_steps_and_hidden_surfaces_need_layers() {
    let ctx = common::gpu();
    let s = rod_scene();
    let r = reference(&s, &["spp=1", "depth=2", "caustics=off"], SIZE);
    let run = |extra: &[&str]| {
        let mut k = vec!["depth=2", "caustics=off", "cube_size=128"];
        k.extend_from_slice(extra);
        let (img, stats) = gpu(&ctx, &s, specula::methods::LAYERED, &k, SIZE);
        (errors(&img, &r), img, stats)
    };
    // Coarse linear steps jump over the thin rod (and the ball's edges): the error falls
    // as the steps grow. Measured RMSE 0.1147, 0.0961, 0.0710 for 2, 8, 32 steps (PSNR
    // 18.81, 20.35, 22.98 dB): ratios 1.194 and 1.353, bounds a factor 1.122 under; the
    // floor on 32 steps 1 dB under.
    let steps: Vec<(u32, ImageErrors)> = [2u32, 8, 32].iter().map(|&n| (n, run(&[&format!("linear_steps={n}")]).0)).collect();
    for (n, e) in &steps {
        eprintln!("rod: linear_steps {n}: {e}");
    }
    assert!(steps[0].1.rmse > steps[1].1.rmse * 1.065, "2 → 8 linear steps: {steps:?}");
    assert!(steps[1].1.rmse > steps[2].1.rmse * 1.206, "8 → 32 linear steps: {steps:?}");
    assert!(steps[2].1.psnr > 21.98, "32 linear steps: {steps:?}");
    // Layers below the depth complexity lose what the missing layers hold (the rod, the
    // bowl and the floor behind the ball); such a cut peel gets one more layer holding the
    // farthest surfaces (`layered.far_layer`), so that rays past the peeled layers meet the
    // room's walls instead of the sky; at the full count no extra layer.
    let (full, full_img, stats) = run(&[]);
    let l = stat(&stats, "layered.layers") as u32;
    assert_eq!(stat(&stats, "layered.far_layer"), 0.0, "a full peel needs no farthest layer");
    // The pixels whose path met the farthest layer, per object (issue 33 item 2): none
    // without one; with one, some of the image's pixels, fewer as more layers are peeled.
    let far_pixels =
        |st: &[(String, f64)]| -> f64 { st.iter().filter(|(k, _)| k.starts_with("layered.far_layer_pixels.")).map(|(_, v)| v).sum() };
    assert_eq!(far_pixels(&stats), 0.0, "{stats:?}");
    let mut by_layers = Vec::new();
    let mut far = Vec::new();
    for n in 1..l {
        let (e, _, st) = run(&[&format!("layers={n}")]);
        assert_eq!((stat(&st, "layered.layers"), stat(&st, "layered.far_layer")), (n as f64, 1.0));
        far.push(far_pixels(&st));
        eprintln!("rod: layers {n}: {e}");
        by_layers.push(e);
    }
    eprintln!("rod: layers auto ({l}): {full}; pixels that met the farthest layer at 1.. layers: {far:?}");
    assert!(far.iter().all(|&p| p > 0.0 && p <= (SIZE * SIZE) as f64), "{far:?}");
    assert!(far.windows(2).all(|w| w[1] <= w[0]), "{far:?}");
    // Measured: RMSE 0.1039 / 0.0872 / 0.0738 at 1 / 2 / 3 layers (each with the farthest
    // surfaces' layer; without it 0.1267 / 0.0971 / 0.0853), 0.0814 at 4 (PSNR 21.79 dB):
    // ratios 1.192 and 1.182, bounds a factor 1.122 under; the farthest layer at 1 layer a
    // factor 1.22 under the bare peel's error, bound 1.122 (0.1129); 3 peeled + farthest is
    // within 1 dB of the full peel (it measured 0.85 dB above: the peel's epsilon drops a
    // near-coincident surface the farthest layer keeps); the floor at 4 layers 1 dB under.
    assert_eq!(by_layers.len(), 3, "the rod scene has 4 layers");
    assert!(by_layers[0].rmse < 0.1267 / 1.122, "the farthest layer at 1 layer: {by_layers:?}");
    assert!(by_layers[0].rmse > by_layers[1].rmse * 1.062, "1 → 2 layers: {by_layers:?}");
    assert!(by_layers[1].rmse > by_layers[2].rmse * 1.054, "2 → 3 layers: {by_layers:?}");
    assert!(by_layers[2].psnr > full.psnr - 1.0, "3 layers and the farthest: {by_layers:?} vs {full}");
    assert!(full.psnr > 20.79, "all layers: {full}");
    let (_, exact_img, _) = run(&[&format!("layers={l}")]);
    assert_eq!(exact_img.data, full_img.data, "layers=auto is layers={l}");
    common::assert_clean(&ctx);
}

#[test]
fn the_map_models_only_the_layers_the_scene_needs() {
    let ctx = common::gpu();
    // Passes and memory: a 3-layer scene allocates 3 layers.
    let s = torus_scene();
    let q = quality(&["caustics=off", "cube_size=32"]);
    let f = specula::render(&ctx, &s, specula::methods::LAYERED, &q, (16, 16), (0, 1)).unwrap();
    let names: Vec<&str> = f.passes.iter().map(|p| p.name.as_str()).collect();
    assert!(names.contains(&"layered.peel") && names.contains(&"layered.search"), "{names:?}");
    let bytes = |name: &str| f.memory.iter().filter(|(n, _)| n == name).map(|(_, b)| *b).sum::<u64>();
    let layer = 6 * 32 * 32 * 8;
    assert!(bytes("layered.cubes") >= 3 * layer && bytes("layered.cubes") < 4 * layer, "{:?}", f.memory);
    assert!(bytes("layered.normals") >= 3 * layer && bytes("layered.normals") < 4 * layer);
    // The plan budgets what the stage allocates (the depth complexity counted when planning,
    // not the most there can be): its map's bytes are the frame's layered memory.
    let plan = specula::plan::plan_with(&s, &specula::plan::Choices::all(specula::methods::LAYERED), &q).unwrap();
    let planned = plan.map("layered.peel").map(|m| m.bytes).unwrap();
    let allocated: u64 = f.memory.iter().filter(|(n, _)| n.starts_with("layered.")).map(|(_, b)| *b).sum();
    assert_eq!(planned, allocated, "plan {planned} B, frame {:?}", f.memory);
    // Without a layered object, nothing of it.
    let f = specula::render(&ctx, &s, specula::methods::REFRACTOR_MAP, &q, (16, 16), (0, 1)).unwrap();
    assert!(f.passes.iter().all(|p| !p.name.starts_with("layered")));
    assert!(f.memory.iter().all(|(n, _)| !n.starts_with("layered")));
    // Objects move: the depth complexity is counted again and the layers follow. The ball
    // leaves the bowl (4 → 2 layers: the bowl and the floor, or the ball and a wall), and
    // the image equals a fresh renderer's.
    let mut s = bowl_scene();
    let plan = specula::plan::plan_with(&s, &specula::plan::Choices::all(specula::methods::LAYERED), &q).unwrap();
    let mut r = specula::Renderer::new(&ctx, &s, plan, 16, 16).unwrap();
    assert_eq!(stat(&r.render(&ctx).unwrap().stats, "layered.layers"), 4.0);
    let ball = s.meshes.iter().position(|m| m.name == "ball").unwrap();
    s.set_object_transform(ball, glam::Mat4::from_translation(Vec3::new(1.2, 1.5, 0.0))).unwrap();
    r.update(&s).unwrap();
    let moved = r.render(&ctx).unwrap();
    let layers = stat(&moved.stats, "layered.layers");
    assert!(layers < 4.0, "{layers}");
    let fresh = specula::render(&ctx, &s, specula::methods::LAYERED, &q, (16, 16), (0, 1)).unwrap();
    assert_eq!(moved.image.data, fresh.image.data, "moved = fresh");
    r.destroy(&ctx);
    common::assert_clean(&ctx);
}

/// What the rule-based planner knew, the measuring planner predicts: a mirror bowl that
/// faces its reference point sees itself, and is predicted more accurate with layered maps
/// than with a single distance map, which leaves it out. (The glass torus, whose rule said
/// the same, is not: at 128² against the converged reference its pixels measure 23.39 dB
/// with distance and 21.59 with layered maps, and the probe's simulated distance lookups
/// predict 23.2.)
#[test]
fn error_models_prefer_layered_maps_for_objects_that_see_themselves() {
    let q = quality(&[]);
    let target = specula::plan::predict::Target::nominal().unwrap();
    let scene = bowl_scene();
    let facts = specula::plan::facts::SceneFacts::new(&scene, &q, true);
    let models = specula::plan::predict::predict_models(&scene, &facts, &q, &target, &["default".into()]).unwrap();
    let f = &facts.objects[0];
    let object = &scene.meshes[f.mesh].name;
    let db = |m: &str| models.variants[0].objects.iter().find(|o| &o.object == object && o.method == m).map(|o| o.psnr_db).unwrap();
    let (layered, distance) = (db("layered"), db("distance"));
    println!(
        "bowl: self-facing {:.2}, visible {:.2}; predicted layered {layered:.1} dB, distance {distance:.1} dB",
        f.self_facing, f.visible_fraction
    );
    assert!(layered > distance, "bowl: layered {layered:.1} dB, distance {distance:.1} dB");
}

#[test]
fn layered_maps_hold_at_1_km_and_1_mm_and_in_half_precision() {
    let ctx = common::gpu();
    let base = bowl_scene();
    let knobs = ["depth=2", "caustics=off", "cube_size=128"];
    let mut psnr = Vec::new();
    let mut half_img = None;
    for k in [1.0f32, 1000.0, 1e-3] {
        let s = scale_scene(&base, k);
        let r = reference(&s, &["spp=1", "depth=2", "caustics=off"], SIZE);
        let (l, _) = gpu(&ctx, &s, specula::methods::LAYERED, &knobs, SIZE);
        let e = errors(&l, &r);
        eprintln!("bowl ×{k}: {e}");
        psnr.push(e.psnr);
        half_img.get_or_insert(l);
    }
    // Measured: 23.48 dB at 1 m, 23.47 dB at 1 km (0.012 dB apart), 22.46 dB at 1 mm (the
    // millimetre scene loses 1.02 dB: left as a finding). Floors 1 dB under each; the
    // kilometre scene within 0.1 dB of the metre one.
    assert!(psnr[0] > 22.48 && psnr[1] > 22.47 && psnr[2] > 21.46, "{psnr:?}");
    assert!((psnr[1] - psnr[0]).abs() < 0.1, "1 km vs 1 m: {psnr:?}");
    assert!((psnr[2] - psnr[0]).abs() < 1.3, "1 mm vs 1 m: {psnr:?}");
    let half_img = half_img.unwrap();
    let r = reference(&base, &["spp=1", "depth=2", "caustics=off"], SIZE);
    let (single_img, _) =
        gpu(&ctx, &base, specula::methods::LAYERED, &["depth=2", "caustics=off", "cube_size=128", "cube_precision=single"], SIZE);
    let single = errors(&single_img, &r);
    eprintln!("bowl, single precision: {single}; half - single {:.3} dB", psnr[0] - single.psnr);
    assert_ne!(single_img.data, half_img.data, "cube_precision reaches the layers");
    // Half precision costs 0.07 dB here (measured 0.068): bound 0.15 dB.
    assert!((single.psnr - psnr[0]).abs() < 0.15, "half {:.2} vs single {single}", psnr[0]);
    common::assert_clean(&ctx);
}
