//! Frames over time (issue 13): a renderer takes moved objects, changed materials, lights
//! and cameras in place, regenerates only the maps whose inputs changed, and its image then
//! equals a fresh renderer's for the same state, bit for bit.

mod common;

use glam::{Mat4, Quat, Vec3};
use specula::plan::{plan_with, Choices};
use specula::scene::{Scene, SurfaceKind};
use specula::{Method, Quality, Renderer};

const SIZE: (u32, u32) = (40, 30);

fn quality() -> Quality {
    {
        let mut knobs = Quality::default();
        knobs.cube.cube_size = 32;
        knobs.frame.shadow_size = 64;
        knobs.frame.depth = 4;
        knobs
    }
}

fn renderer(ctx: &specula::vk::Context, scene: &Scene, m: Method, q: &Quality) -> Renderer {
    let plan = plan_with(scene, &Choices::all(m), q).unwrap();
    Renderer::new(ctx, scene, plan, SIZE.0, SIZE.1).unwrap()
}

fn mirror_index(s: &Scene) -> usize {
    s.meshes.iter().position(|m| matches!(s.materials[m.material].kind, SurfaceKind::Mirror { .. })).unwrap()
}

/// The k-th pose of the moving mirror sphere: along a short arc, turning and growing a little.
fn pose(k: usize, centre: Vec3) -> Mat4 {
    let t = k as f32 * 0.07;
    let to = centre + Vec3::new(0.3 * t.sin(), 0.05 * t, 0.2 * (1.0 - t.cos()));
    Mat4::from_translation(to)
        * Mat4::from_scale_rotation_translation(Vec3::splat(1.0 + 0.1 * t), Quat::from_rotation_y(t), Vec3::ZERO)
        * Mat4::from_translation(-centre)
}

fn bits(f: &specula::Frame) -> Vec<u32> {
    f.image.data.iter().map(|v| v.to_bits()).collect()
}

fn fresh(ctx: &specula::vk::Context, scene: &Scene, m: Method, q: &Quality) -> Vec<u32> {
    let mut r = renderer(ctx, scene, m, q);
    let f = r.render(ctx).unwrap();
    r.destroy(ctx);
    bits(&f)
}

/// Every GPU method: the mirror sphere moves for 4 frames (both parities of the ping-pong
/// maps twice; 3 for the schemes that share bvh's update path and differ only in the
/// structure they rebuild: kd-tree, grid, octree, bih); each incrementally updated frame
/// equals a fresh render of the same scene. (`ten_frames_of_a_moving_mirror_sphere` moves
/// the demo's sphere for ten.) The registry's methods alternate between two tests, `half`
/// 0 and 1, so that the suite's two test threads share them (one test took 52 s alone).
fn incremental_equals_fresh(half: usize) {
    let ctx = common::gpu();
    let base = common::mirror_and_glass(24);
    let i = mirror_index(&base);
    let centre = base.meshes[i].bounds().center();
    let q = quality();
    let methods: Vec<Method> = specula::Method::ALL.iter().copied().filter(|m| m.is_gpu()).collect();
    for &m in methods.iter().skip(half).step_by(2) {
        let frames = match m.name() {
            "kd-tree" | "grid" | "octree" | "bih" => 3,
            _ => 4,
        };
        let mut scene = base.clone();
        // bvh follows these moves with a linear BVH built on the GPU (bvh_update=lbvh; auto
        // would refit, `bvh_follows_moves_by_refit_or_rebuild` below), over the CPU's SAH
        // tree of its first frame: a fresh renderer that builds the same tree
        // (bvh_build=lbvh) renders the same bits.
        let (q, fresh_q) = match m == specula::methods::BVH {
            true => {
                let (mut a, mut b) = (q.clone(), q.clone());
                a.set("bvh_update", "lbvh").unwrap();
                b.set("bvh_build", "lbvh").unwrap();
                (a, b)
            }
            false => (q.clone(), q.clone()),
        };
        let mut r = renderer(&ctx, &scene, m, &q);
        r.render(&ctx).unwrap();
        let mut kept = None;
        for k in 1..=frames {
            scene.set_object_transform(i, pose(k, centre)).unwrap();
            let c = r.update(&scene).unwrap();
            assert_eq!(c.moved, vec![i]);
            let f = r.render(&ctx).unwrap();
            if m == specula::methods::BVH {
                let built: Vec<f64> = ["raytrace.gpu_builds", "raytrace.gpu_refits"]
                    .iter()
                    .map(|s| f.stats.iter().find(|(n, _)| n == s).map_or(-1.0, |(_, v)| *v))
                    .collect();
                assert_eq!(built, [k as f64, 0.0], "bvh: frame {k} builds its BVH on the GPU");
                assert!(pass_names(&f).contains(&"raytrace.build"), "{:?}", pass_names(&f));
            }
            let got = bits(&f);
            assert!(got == fresh(&ctx, &scene, m, &fresh_q), "{}: frame {k} after a move differs from a fresh render", m.name());
            // The fresh renderers after the first make no pipeline: the context's serve them.
            let n = ctx.pipeline_counts().0;
            assert!(kept.is_none_or(|k| k == n), "{}: frame {k}'s fresh renderer made pipelines ({kept:?} -> {n})", m.name());
            kept = Some(n);
        }
        r.destroy(&ctx);
    }
    common::assert_clean(&ctx);
}

/// How `bvh` follows moves (`bvh_update=auto`, the default): a rigid move, however far,
/// refits the tree on the GPU (pass `raytrace.refit`); a turn of more than REFIT_TURN since
/// the tree was built, or a deformation, rebuilds it — on lavapipe by the CPU's SAH builder
/// (its compute runs on the same cores); the next move refits again. A rebuilt frame
/// equals a fresh renderer's bit for bit; a refitted one traces the same triangles through
/// looser boxes, the same nearest hits: its pixels equal a fresh render's (at most a
/// pixel where two triangles tie; none measured).
#[test]
fn bvh_follows_moves_by_refit_or_rebuild() {
    let ctx = common::gpu();
    let base = common::mirror_and_glass(24);
    let i = mirror_index(&base);
    let q = quality();
    let mut scene = base.clone();
    let mut r = renderer(&ctx, &scene, specula::methods::BVH, &q);
    r.render(&ctx).unwrap();
    let size = base.meshes[i].bounds().diagonal();
    let stat = |f: &specula::Frame, s: &str| f.stats.iter().find(|(n, _)| n == s).map(|(_, v)| *v);
    let glass = base.meshes.iter().position(|m| m.name == "glass").unwrap();
    let centre = base.meshes[i].bounds().center();
    let turned = |deg: f32| Mat4::from_translation(centre) * Mat4::from_rotation_z(deg.to_radians()) * Mat4::from_translation(-centre);
    // (what changes, the GPU pass expected, the refits its refitter counted)
    let steps: [(&str, Option<&str>, Option<f64>); 5] = [
        ("a move of 0.02 diagonals", Some("raytrace.refit"), Some(1.0)),
        ("a move of 1.5 diagonals", Some("raytrace.refit"), Some(2.0)),
        ("a turn of 30 degrees", None, None),
        ("a move of 0.1 diagonals", Some("raytrace.refit"), Some(1.0)),
        ("a squash of the glass's own vertices", None, None),
    ];
    for (k, (what, pass, refits)) in steps.into_iter().enumerate() {
        match k {
            0 | 1 | 3 => {
                let step = [0.02, 1.5, 0.0, 0.1][k] * size;
                let at = Mat4::from_translation(Vec3::new(0.0, 0.0, -step)) * scene.meshes[i].world;
                scene.set_object_transform(i, at).unwrap();
            }
            2 => {
                let at = scene.meshes[i].world * turned(30.0);
                scene.set_object_transform(i, at).unwrap();
            }
            _ => {
                // The glass, never moved: its world positions are its own.
                let c = scene.meshes[glass].bounds().center();
                for p in &mut scene.meshes[glass].positions {
                    p.y = c.y + (p.y - c.y) * 0.8;
                }
            }
        }
        assert_eq!(r.update(&scene).unwrap().moved, vec![if k == 4 { glass } else { i }], "{what}");
        let f = r.render(&ctx).unwrap();
        let names = pass_names(&f);
        let gpu_pass = names.iter().find(|n| **n == "raytrace.refit" || **n == "raytrace.build").copied();
        assert_eq!((gpu_pass, stat(&f, "raytrace.gpu_refits")), (pass, refits), "{what}: {names:?}");
        let fresh = fresh(&ctx, &scene, specula::methods::BVH, &q);
        let got = bits(&f);
        let differ = got.chunks(4).zip(fresh.chunks(4)).filter(|(a, b)| a != b).count();
        println!("{what}: {gpu_pass:?}, {differ} pixels differ from a fresh render");
        match pass {
            None => assert!(differ == 0, "{what}: a rebuilt tree renders a fresh renderer's bits ({differ} pixels differ)"),
            Some(_) => assert!(differ <= 1, "{what}: the refitted tree's image differs from a fresh render in {differ} pixels"),
        }
    }
    // Ten more moves along an arc (translations: after the rebuild above, ten refits by a
    // new refitter), each frame a fresh render's.
    let start = scene.meshes[i].world;
    for k in 1..=10 {
        let t = k as f32 * 0.3;
        let arc = Vec3::new(0.3 * t.sin(), 0.0, 0.3 * (1.0 - t.cos())) * size;
        scene.set_object_transform(i, Mat4::from_translation(arc) * start).unwrap();
        r.update(&scene).unwrap();
        let f = r.render(&ctx).unwrap();
        assert_eq!(stat(&f, "raytrace.gpu_refits"), Some(k as f64), "move {k} of ten");
        let differ = bits(&f).chunks(4).zip(fresh(&ctx, &scene, specula::methods::BVH, &q).chunks(4)).filter(|(a, b)| a != b).count();
        assert!(differ <= 1, "move {k} of ten: {differ} pixels differ from a fresh render");
    }
    r.destroy(&ctx);
    // Where the device's costs predict the GPU's linear BVH cheaper, a deformation builds
    // it on the GPU (raytrace.build); where they predict the CPU's SAH build cheaper, the CPU
    // builds. (The stored calibration's own costs are lavapipe's: the CPU's build there.)
    let target = specula::target_for(&ctx, SIZE).expect("unit costs");
    for (gpu_cheaper, pass) in [(true, Some("raytrace.build")), (false, None)] {
        let mut costs = (*target.costs).clone();
        let (cheap, dear) = ([0.0, 1.0], [0.0, 100.0]);
        let (sah, lbvh) = if gpu_cheaper { (dear, cheap) } else { (cheap, dear) };
        costs.bvh_updates = Some(specula::plan::predict::cost_model::BvhUpdateCosts { sah, lbvh, refit: cheap });
        let t = specula::plan::predict::Target { size: SIZE, costs: std::sync::Arc::new(costs) };
        let plan = specula::plan::plan_for(&scene, &Choices::all(specula::methods::BVH), &q, Some(&t)).unwrap();
        let mut r = Renderer::new(&ctx, &scene, plan, SIZE.0, SIZE.1).unwrap();
        r.render(&ctx).unwrap();
        for p in &mut scene.meshes[glass].positions {
            p.x *= 1.01;
        }
        r.update(&scene).unwrap();
        let f = r.render(&ctx).unwrap();
        let got = pass_names(&f).iter().find(|n| **n == "raytrace.build" || **n == "raytrace.refit").copied();
        assert_eq!(got, pass, "GPU build predicted cheaper: {gpu_cheaper}");
        r.destroy(&ctx);
    }

    // bvh_update=sah: every move rebuilds on the CPU, never a GPU pass.
    let mut q_sah = q.clone();
    q_sah.set("bvh_update", "sah").unwrap();
    let mut r = renderer(&ctx, &scene, specula::methods::BVH, &q_sah);
    r.render(&ctx).unwrap();
    let at = Mat4::from_translation(Vec3::new(0.0, 0.02 * size, 0.0)) * scene.meshes[i].world;
    scene.set_object_transform(i, at).unwrap();
    r.update(&scene).unwrap();
    let f = r.render(&ctx).unwrap();
    assert!(!pass_names(&f).iter().any(|n| *n == "raytrace.build" || *n == "raytrace.refit"), "{:?}", pass_names(&f));
    assert!(bits(&f) == fresh(&ctx, &scene, specula::methods::BVH, &q_sah));
    r.destroy(&ctx);
    common::assert_clean(&ctx);
}

#[test]
fn incremental_equals_fresh_for_every_gpu_method_first_half() {
    incremental_equals_fresh(0);
}

#[test]
fn incremental_equals_fresh_for_every_gpu_method_second_half() {
    incremental_equals_fresh(1);
}

/// Ten frames of the demo's mirror sphere on a path (distance maps, shadow maps, the
/// point light): incremental equals fresh at every frame.
#[test]
fn ten_frames_of_a_moving_mirror_sphere() {
    let ctx = common::gpu();
    let base = specula::scene::load(std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/demo/demo.gltf"))).unwrap();
    let i = mirror_index(&base);
    let centre = base.meshes[i].bounds().center();
    let q = quality();
    let mut scene = base.clone();
    let mut r = renderer(&ctx, &scene, specula::methods::DISTANCE, &q);
    r.render(&ctx).unwrap();
    for k in 1..=10 {
        scene.set_object_transform(i, pose(k, centre)).unwrap();
        r.update(&scene).unwrap();
        let f = r.render(&ctx).unwrap();
        let rebuilt: Vec<&str> = f.map_updates.iter().map(|u| u.stage).collect();
        assert!(rebuilt.contains(&"shadow.generate") && rebuilt.contains(&"distance.generate"), "frame {k}: {rebuilt:?}");
        assert!(bits(&f) == fresh(&ctx, &scene, specula::methods::DISTANCE, &q), "frame {k} differs from a fresh render");
    }
    r.destroy(&ctx);
    common::assert_clean(&ctx);
}

fn pass_names(f: &specula::Frame) -> Vec<&str> {
    f.passes.iter().map(|p| p.name.as_str()).collect()
}

/// Nothing moves: frame 2 records no map pass. The light moves: shadow and distance maps
/// are rebuilt. The camera moves: no map is. An object moves: the faces that see it.
/// `map_updates=always` rebuilds every frame.
#[test]
fn only_what_changed_is_rebuilt() {
    let ctx = common::gpu();
    let mut scene = specula::scene::load(std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/demo/demo.gltf"))).unwrap();
    let q = quality();
    let mut r = renderer(&ctx, &scene, specula::methods::DISTANCE, &q);
    let first = r.render(&ctx).unwrap();
    assert!(first.map_updates.iter().all(|u| u.reason == "first frame"), "{:?}", first.map_updates);
    assert!(pass_names(&first).contains(&"distance.generate"));
    let second = r.render(&ctx).unwrap();
    assert!(second.map_updates.is_empty(), "{:?}", second.map_updates);
    for p in ["shadow.generate", "distance.generate"] {
        assert!(!pass_names(&second).contains(&p), "static frame 2 recorded {p}: {:?}", pass_names(&second));
    }
    assert!(bits(&second) == bits(&first), "a static scene's frame 2 equals frame 1");

    // The camera moves: only camera passes.
    let mut cam = scene.camera.unwrap();
    cam.position += Vec3::new(0.1, 0.0, 0.0);
    cam.world_from_camera = Mat4::from_translation(Vec3::new(0.1, 0.0, 0.0)) * cam.world_from_camera;
    scene.camera = Some(cam);
    let c = r.update(&scene).unwrap();
    assert!(c.camera && c.moved.is_empty());
    let f = r.render(&ctx).unwrap();
    assert!(f.map_updates.is_empty(), "{:?}", f.map_updates);
    assert!(bits(&f) == fresh(&ctx, &scene, specula::methods::DISTANCE, &q));

    // The light moves: shadow maps and the distance maps (they hold lit radiance).
    let mut light = scene.lights[0].clone();
    light.position += Vec3::new(0.2, -0.1, 0.0);
    scene.set_light(0, light).unwrap();
    r.update(&scene).unwrap();
    let f = r.render(&ctx).unwrap();
    let rebuilt: Vec<(&str, &str)> = f.map_updates.iter().map(|u| (u.stage, u.reason.as_str())).collect();
    // The caustics too (they are lit); not the refractor maps (geometry alone).
    assert_eq!(rebuilt, vec![("shadow.generate", "light 'light'"), ("caustics", "light 'light'"), ("distance.generate", "light 'light'")]);
    assert!(bits(&f) == fresh(&ctx, &scene, specula::methods::DISTANCE, &q));

    // A material: the maps that see it, not the shadow maps.
    let box_material = scene.materials.iter().position(|m| m.name == "box").unwrap();
    let mut m = scene.materials[box_material].clone();
    m.base_color = Vec3::new(0.9, 0.2, 0.1);
    scene.set_material(box_material, m).unwrap();
    r.update(&scene).unwrap();
    let f = r.render(&ctx).unwrap();
    let rebuilt: Vec<&str> = f.map_updates.iter().map(|u| u.stage).collect();
    assert_eq!(rebuilt, vec!["distance.generate"]);
    assert!(bits(&f) == fresh(&ctx, &scene, specula::methods::DISTANCE, &q));

    r.destroy(&ctx);

    // The box moves a little (issue 33 item 4): the distance maps draw again only the faces
    // whose frusta saw it, or its shadow from the light, before or now; the shadow cube the
    // faces that saw it; the glass's refractor map, which sees the glass alone, not at all.
    // (With caustics every face: the light a generator focuses may land anywhere; off here.)
    // The frame equals a fresh context's.
    let mut q = q.clone();
    q.set("caustics", "off").unwrap();
    let mut r = renderer(&ctx, &scene, specula::methods::DISTANCE, &q);
    r.render(&ctx).unwrap();
    let b = scene.meshes.iter().position(|m| m.name.starts_with("box")).unwrap();
    let world = Mat4::from_translation(Vec3::new(0.05, 0.0, 0.0)) * scene.meshes[b].world;
    scene.set_object_transform(b, world).unwrap();
    r.update(&scene).unwrap();
    let f = r.render(&ctx).unwrap();
    let rebuilt: Vec<(&str, &str)> = f.map_updates.iter().map(|u| (u.stage, u.reason.as_str())).collect();
    println!("box moved: {rebuilt:?}");
    let distance = rebuilt.iter().find(|(s, _)| *s == "distance.generate").expect("the distance maps see the box");
    let faces = f.stats.iter().find(|(n, _)| n == "distance.generate.faces_drawn").map(|(_, v)| *v).unwrap();
    assert!((1.0..12.0).contains(&faces) && distance.1.contains(&format!("{faces} of 12 faces")), "{rebuilt:?}, {faces} faces");
    assert!(rebuilt.iter().all(|(s, _)| *s != "refractor.generate"), "{rebuilt:?}");
    assert!(bits(&f) == fresh(&ctx, &scene, specula::methods::DISTANCE, &q), "partly redrawn maps differ from a fresh context's");
    r.destroy(&ctx);

    // Benchmarks: every frame.
    let always = {
        let mut knobs = q.clone();
        knobs.frame.map_updates_always = true;
        knobs
    };
    let mut r = renderer(&ctx, &scene, specula::methods::DISTANCE, &always);
    r.render(&ctx).unwrap();
    let f = r.render(&ctx).unwrap();
    assert!(pass_names(&f).contains(&"distance.generate") && f.map_updates.iter().all(|u| u.reason == "map_updates=always"));
    r.destroy(&ctx);
    common::assert_clean(&ctx);
}

/// Refused updates name the object, the field and the value, and change nothing.
#[test]
fn bad_updates_are_refused_and_keep_the_state() {
    let mut scene = common::mirror_and_glass(12);
    let before = scene.clone();
    let i = mirror_index(&scene);
    let nan = Mat4::from_translation(Vec3::new(f32::NAN, 0.0, 0.0));
    let e = scene.set_object_transform(i, nan).unwrap_err().to_string();
    assert!(e.contains("object 'mirror': transform") && e.contains("NaN"), "{e}");
    let e = scene.set_object_transform(i, Mat4::from_scale(Vec3::new(1.0, 0.0, 1.0))).unwrap_err().to_string();
    assert!(e.contains("determinant 0"), "{e}");
    let e = scene.set_object_transform(i, Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0))).unwrap_err().to_string();
    assert!(e.contains("opposite sign"), "{e}");
    let e = scene.set_object_transform(99, Mat4::IDENTITY).unwrap_err().to_string();
    assert!(e.contains("99 is out of range"), "{e}");
    let far = Mat4::from_scale_rotation_translation(Vec3::new(1e-38, 3e38, 1.0), Quat::IDENTITY, Vec3::ZERO);
    let e = scene.set_object_transform(i, far).unwrap_err().to_string();
    assert!(e.contains("not finite"), "{e}");
    let glass = scene.meshes.iter().find(|m| m.name == "glass").unwrap().material;
    let mut m = scene.materials[glass].clone();
    m.kind = SurfaceKind::Dielectric { ior: -1.0, thin: false };
    let e = scene.set_material(glass, m.clone()).unwrap_err().to_string();
    assert!(e.contains("ior") && e.contains("-1"), "{e}");
    m.kind = SurfaceKind::Diffuse;
    let e = scene.set_material(glass, m).unwrap_err().to_string();
    assert!(e.contains("kind") && e.contains("solid dielectric"), "{e}");
    assert!(scene == before, "refused updates changed the scene");

    // A scene of another topology is refused by a renderer, which keeps its state.
    let ctx = common::gpu();
    let q = quality();
    let mut r = renderer(&ctx, &scene, specula::methods::DISTANCE, &q);
    let a = bits(&r.render(&ctx).unwrap());
    let mut other = scene.clone();
    other.meshes.pop();
    let e = r.update(&other).unwrap_err().to_string();
    assert!(e.contains("objects"), "{e}");
    assert!(bits(&r.render(&ctx).unwrap()) == a);
    r.destroy(&ctx);
    common::assert_clean(&ctx);
}

/// Per-face culling: a small mirror sphere straight ahead (+X) of the light and a floor
/// below it; each shadow-cube face draws only what lies in its frustum, the sphere's own map
/// leaves the sphere out and draws the floor in the two faces it spans, multiview (one pass
/// for six faces) cannot cull, and culling changes no pixel.
#[test]
fn cube_faces_draw_only_what_they_see() {
    use specula::scene::{shapes, Light, LightKind, Material};
    let ctx = common::gpu();
    let mut s = Scene::new();
    let white = s.add_material(Material { name: "white".into(), ..Default::default() }).unwrap();
    let mirror = s
        .add_material(Material {
            name: "mirror".into(),
            kind: SurfaceKind::Mirror { nu: Vec3::splat(0.2), kappa: Vec3::splat(3.0) },
            ..Default::default()
        })
        .unwrap();
    // The floor lies below the light only; the sphere is straight ahead (+X) of the light.
    s.add_mesh(shapes::quad("floor", Vec3::new(-1.0, 0.0, -1.0), Vec3::new(2.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 2.0), 1, white)).unwrap();
    s.add_mesh(shapes::uv_sphere("ball", Vec3::new(3.0, 2.0, 0.0), 0.2, 8, 4, mirror)).unwrap();
    s.add_light(Light {
        name: "lamp".into(),
        kind: LightKind::Point,
        position: Vec3::new(0.0, 2.0, 0.0),
        direction: Vec3::NEG_Y,
        intensity: Vec3::splat(5.0),
        range: None,
    })
    .unwrap();
    s.camera = Some(specula::scene::Camera::look_at(Vec3::new(0.0, 1.5, 4.0), Vec3::new(1.0, 1.0, 0.0), 1.0));
    // Caustics off: lavapipe's multiview rasterises the mirror ball's caustic triangles to
    // within 1e-4 of six passes, not bit for bit (tests/caustics.rs compares the two modes).
    let q = {
        let mut knobs = quality();
        knobs.caustics.caustics = specula::quality::Caustics::Off;
        knobs
    };
    let mut r = renderer(&ctx, &s, specula::methods::ENVMAP, &q);
    let f = r.render(&ctx).unwrap();
    let stat = |name: &str| {
        f.stats.iter().find(|(k, _)| k == name).map(|(_, v)| *v as u32).unwrap_or_else(|| panic!("no stat {name}: {:?}", f.stats))
    };
    let shadow: Vec<u32> = (0..6).map(|k| stat(&format!("shadow.generate.draws.face{k}"))).collect();
    // +X (0) sees the ball, −Y (3) the floor; the other faces nothing.
    assert_eq!(shadow, vec![1, 0, 0, 1, 0, 0], "shadow cube draws per face");
    // The ball's own map leaves the ball out: the floor lies below-left of it (−X and −Y).
    let env: Vec<u32> = (0..6).map(|k| stat(&format!("envmap.generate.draws.face{k}"))).collect();
    assert_eq!(env, vec![0, 1, 0, 1, 0, 0], "envmap draws per face");
    r.destroy(&ctx);
    // Multiview renders the six faces in one pass: no per-face culling.
    let mv = {
        let mut knobs = q.clone();
        knobs.cube.cube_mode = specula::quality::CubeMode::Multiview;
        knobs
    };
    let mut r = renderer(&ctx, &s, specula::methods::ENVMAP, &mv);
    let g = r.render(&ctx).unwrap();
    let env: Vec<u32> =
        (0..6).map(|k| g.stats.iter().find(|(n, _)| *n == format!("envmap.generate.draws.face{k}")).unwrap().1 as u32).collect();
    assert_eq!(env.iter().sum::<u32>(), 1, "multiview: one pass drawing the floor once, counted under face 0: {env:?}");
    assert!(bits(&g) == bits(&f), "culling changes no pixel");
    r.destroy(&ctx);
    common::assert_clean(&ctx);
}

/// A hidden object disappears from every map, the camera passes and the rays: the image
/// equals a fresh render of the scene without it (bit for bit, as measured; the buffers and
/// map layers are laid out differently); shown again, the first image
/// returns bit for bit.
#[test]
fn a_hidden_object_disappears_everywhere() {
    let ctx = common::gpu();
    let base = specula::scene::load(std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/demo/demo.gltf"))).unwrap();
    let i = mirror_index(&base);
    let mut without = base.clone();
    without.meshes.remove(i);
    let q = quality();
    // The largest ulp difference against the scene without the object, measured 0 (bit for
    // bit) with distance maps and with the BVH at this commit; an earlier commit saw 1 value
    // of 4800 one ulp apart with distance maps (the other scene lays its buffers and map
    // layers out differently, which may reorder a rounding), so 4 ulps are allowed.
    for m in [specula::methods::DISTANCE, specula::methods::BVH] {
        let mut scene = base.clone();
        let mut r = renderer(&ctx, &scene, m, &q);
        let shown = bits(&r.render(&ctx).unwrap());
        scene.set_object_visible(i, false).unwrap();
        let c = r.update(&scene).unwrap();
        assert_eq!(c.moved, vec![i]);
        let hidden = bits(&r.render(&ctx).unwrap());
        // Within the measured ulps per value, although the scene without the object lays out
        // its buffers and map layers differently.
        let without = fresh(&ctx, &without, m, &q);
        let ulps = hidden.iter().zip(&without).map(|(a, b)| (*a as i64 - *b as i64).unsigned_abs()).max().unwrap();
        let differing = hidden.iter().zip(&without).filter(|(a, b)| a != b).count();
        let visible = shown.iter().zip(&without).filter(|(a, b)| a != b).count();
        eprintln!(
            "{}: hidden vs a scene without the object: {differing} of {} values differ, by at most {ulps} ulps; shown: {visible} differ",
            m.name(),
            hidden.len()
        );
        assert!(ulps <= 4, "{}: hidden differs from a scene without the object by {ulps} ulps", m.name());
        // The object shows (measured: 3402 of 4800 values differ from the scene without it,
        // both methods), so that a hide that changes nothing fails the comparison above.
        assert!(visible as f64 >= 3402.0 / 1.122, "{}: the object changes only {visible} values", m.name());
        scene.set_object_visible(i, true).unwrap();
        r.update(&scene).unwrap();
        assert!(bits(&r.render(&ctx).unwrap()) == shown, "{}: shown again differs", m.name());
        r.destroy(&ctx);
    }
    assert!(base.clone().set_object_visible(99, false).unwrap_err().to_string().contains("99 is out of range"));
    common::assert_clean(&ctx);
}

/// Frame latency (one inter-object cycle per frame): after a move the cycles start again,
/// so `cycles` frames later the image equals a fresh renderer's after as many frames.
#[test]
fn frame_latency_restarts_its_cycles_after_a_change() {
    let ctx = common::gpu();
    let base = common::mirror_and_glass(16);
    let i = mirror_index(&base);
    let centre = base.meshes[i].bounds().center();
    let q = {
        let mut knobs = quality();
        knobs.distance.frame_latency = true;
        knobs.distance.cycles = 3;
        knobs
    };
    let m = specula::methods::DISTANCE_MULTI;
    let mut scene = base.clone();
    let mut r = renderer(&ctx, &scene, m, &q);
    for _ in 0..4 {
        r.render(&ctx).unwrap();
    }
    scene.set_object_transform(i, pose(3, centre)).unwrap();
    r.update(&scene).unwrap();
    let mut fresh_r = renderer(&ctx, &scene, m, &q);
    for k in 0..3 {
        let a = r.render(&ctx).unwrap();
        let b = fresh_r.render(&ctx).unwrap();
        assert!(bits(&a) == bits(&b), "frame {k} after the move differs from a fresh renderer's frame {k}");
        assert!(a.map_updates.iter().any(|u| u.stage == "distance.generate"), "frame {k}: {:?}", a.map_updates);
    }
    // The cycles have converged: nothing more to regenerate.
    assert!(r.render(&ctx).unwrap().map_updates.is_empty());
    r.destroy(&ctx);
    fresh_r.destroy(&ctx);
    common::assert_clean(&ctx);
}

/// A move that changes the plan's structure (the demo's mirror sphere on distance maps and
/// its glass sphere on refractor maps, the mirror taken to where it sees the glass: the
/// objects now compose through inter-object cycles) is accepted through the C ABI; a
/// standalone context reconfigures at its next render, and the image equals a fresh
/// context's for the same state. Before the move, refused calls (a method the sphere's shape
/// or class cannot take, a bad knob, bad budgets, a NaN transform) change nothing: the next
/// frame is the same bit for bit, and so is the frame after the replan. An unreachable
/// budget configures the nearest choice with a warning code and a log message.
#[test]
fn a_move_that_changes_the_plan_reconfigures_a_standalone_c_context() {
    use specula::ffi::*;
    let demo = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/demo/demo.gltf\0");
    let scene = specula::scene::load(std::path::Path::new(demo.trim_end_matches('\0'))).unwrap();
    let sphere = mirror_index(&scene) as u32;
    // The sphere's place on its glTF path at t = 2.58 s.
    let moved = Mat4::from_translation(Vec3::new(-0.6944, 0.5, -0.4889)).to_cols_array();
    let (w, h) = (32u32, 24u32);
    let auto_desc = || {
        let mut d = common::render_desc(specula::methods::DISTANCE, w, h);
        d.method = specula::methods::registry::ABI_AUTO;
        d
    };
    let desc = auto_desc();
    let render = |ctx: *mut SpeculaContext| {
        let mut px = vec![0f32; (w * h * 4) as usize];
        let r = unsafe { specula_context_render(ctx, SPECULA_PIXEL_RGBA32F, px.as_mut_ptr().cast(), px.len() * 4) };
        assert_eq!(r, SPECULA_SUCCESS, "{}", unsafe { std::ffi::CStr::from_ptr(specula_context_last_error(ctx)) }.to_string_lossy());
        px
    };
    let methods: Vec<(String, specula::Method)> = scene
        .specular_meshes()
        .map(|(_, m)| {
            let glass = matches!(scene.materials[m.material].kind, specula::scene::SurfaceKind::Dielectric { .. });
            (m.name.clone(), if glass { specula::methods::REFRACTOR_MAP } else { specula::methods::DISTANCE })
        })
        .collect();
    let knobs = |ctx: *mut SpeculaContext| {
        for k in ["cube_size=16", "shadow_size=32", "depth=4"] {
            let (key, value) = k.split_once('=').unwrap();
            let (key, value) = (std::ffi::CString::new(key).unwrap(), std::ffi::CString::new(value).unwrap());
            assert_eq!(unsafe { specula_context_set_knob(ctx, key.as_ptr(), value.as_ptr()) }, SPECULA_SUCCESS);
        }
        for (name, m) in &methods {
            let name = std::ffi::CString::new(name.as_str()).unwrap();
            assert_eq!(unsafe { specula_context_set_object_method(ctx, name.as_ptr(), m.abi) }, SPECULA_SUCCESS);
        }
    };
    unsafe {
        let a = common::c_context();
        assert_eq!(specula_context_load_gltf(a, demo.as_ptr().cast()), SPECULA_SUCCESS);
        knobs(a);
        assert_eq!(specula_context_configure(a, &desc), SPECULA_SUCCESS);
        let before = render(a);
        let message = |ctx| std::ffi::CStr::from_ptr(specula_context_last_error(ctx)).to_string_lossy().into_owned();
        let sphere_name = std::ffi::CString::new(scene.meshes[sphere as usize].name.as_str()).unwrap();
        let refused = |r: SpeculaResult, want: &str| {
            assert_eq!(r, SPECULA_ERROR_INVALID_ARGUMENT, "{want}");
            let m = message(a);
            assert!(m.contains(want), "{m}");
            assert!(render(a) == before, "the refused call ({want}) changed the frame");
        };
        // Judged at the call: a planar method on a curved mirror, a dielectric method on a mirror.
        refused(specula_context_set_object_method(a, sphere_name.as_ptr(), specula::methods::PLANAR_MIRROR.abi), "planar reflectors only");
        refused(
            specula_context_set_object_method(a, sphere_name.as_ptr(), specula::methods::PLANAR_REFRACTION.abi),
            "cannot serve a mirror",
        );
        refused(specula_context_set_object_method(a, sphere_name.as_ptr(), 9999), "not a GPU method");
        refused(specula_context_set_knob(a, c"cube_size".as_ptr(), c"7".as_ptr()), "cube_size");
        refused(specula_context_set_object_transform(a, sphere, [f32::NAN; 16].as_ptr()), "NaN");
        refused(specula_context_set_object_visible(a, 999, 0), "999");
        let material = |surface, ior: f32| SpeculaMaterialDesc {
            r#type: SPECULA_STRUCT_MATERIAL_DESC,
            size: std::mem::size_of::<SpeculaMaterialDesc>() as u32,
            surface,
            base_color: [0.5; 3],
            emission: [0.0; 3],
            nu: [0.2; 3],
            kappa: [3.0; 3],
            ior,
            thin: 0,
            attenuation_color: [0.0; 3],
            attenuation_distance: 0.0,
            dispersion: 0.0,
            graded: 0,
            index_origin: [0.0; 3],
            index_gradient: [0.0; 3],
            index_hessian: [0.0; 6],
        };
        let glass_material = scene
            .meshes
            .iter()
            .find(|m| matches!(scene.materials[m.material].kind, specula::scene::SurfaceKind::Dielectric { .. }))
            .unwrap()
            .material as u32;
        refused(specula_context_set_material(a, glass_material, &material(SPECULA_SURFACE_DIELECTRIC, -1.0)), "ior");
        refused(specula_context_set_material(a, glass_material, &material(SPECULA_SURFACE_DIFFUSE, 1.0)), "kind");
        refused(specula_context_set_material(a, 999, &material(SPECULA_SURFACE_DIFFUSE, 1.0)), "999");
        let mut bad_light = SpeculaLightDesc {
            r#type: SPECULA_STRUCT_LIGHT_DESC,
            size: std::mem::size_of::<SpeculaLightDesc>() as u32,
            kind: SPECULA_LIGHT_POINT,
            position: [0.0, f32::NAN, 0.0],
            direction: [0.0, -1.0, 0.0],
            intensity: [5.0; 3],
            inner_cone: 0.0,
            outer_cone: 0.0,
            range: 0.0,
        };
        refused(specula_context_set_light(a, 0, &bad_light), "position");
        bad_light.position = [0.0, 1.0, 0.0];
        refused(specula_context_set_light(a, 99, &bad_light), "99");
        let bad_camera = SpeculaCameraDesc {
            r#type: SPECULA_STRUCT_CAMERA_DESC,
            size: std::mem::size_of::<SpeculaCameraDesc>() as u32,
            position: [0.0, 1.0, 2.0],
            target: [0.0, 1.0, 2.0],
            yfov: 1.0,
            znear: 0.01,
        };
        refused(specula_context_set_camera(a, &bad_camera), "camera");
        // A scene that cannot be loaded replaces nothing.
        assert_eq!(specula_context_load_gltf(a, c"no/such/scene.gltf".as_ptr()), SPECULA_ERROR_IO);
        assert!(message(a).contains("no/such/scene.gltf"), "{}", message(a));
        assert!(render(a) == before, "the refused load changed the frame");
        let mut bad = auto_desc();
        for (max_ms, min_psnr, want) in [(0.0, -5.0, "min_psnr"), (f64::NAN, 0.0, "max_ms"), (1e9, 0.0, "max_ms"), (5.0, 30.0, "not both")]
        {
            (bad.max_ms, bad.min_psnr_db) = (max_ms, min_psnr);
            refused(specula_context_configure(a, &bad), want);
        }
        assert_eq!(specula_context_set_object_transform(a, sphere, moved.as_ptr()), SPECULA_SUCCESS, "the move is accepted");
        let incremental = render(a);

        let b = common::c_context();
        assert_eq!(specula_context_load_gltf(b, demo.as_ptr().cast()), SPECULA_SUCCESS);
        knobs(b);
        assert_eq!(specula_context_set_object_transform(b, sphere, moved.as_ptr()), SPECULA_SUCCESS);
        assert_eq!(specula_context_configure(b, &desc), SPECULA_SUCCESS);
        let fresh = render(b);
        assert!(incremental == fresh, "after the replan the image equals a fresh context's");

        // A floor no choice is predicted to reach: the nearest, a warning code and a log line.
        unsafe extern "C" fn log(user: *mut std::ffi::c_void, level: SpeculaLogLevel, msg: *const std::ffi::c_char) {
            if level == SPECULA_LOG_WARNING {
                (*(user as *mut Vec<String>)).push(std::ffi::CStr::from_ptr(msg).to_string_lossy().into_owned());
            }
        }
        let mut warnings: Vec<String> = Vec::new();
        assert_eq!(specula_context_set_log_callback(b, Some(log), (&mut warnings as *mut Vec<String>).cast()), SPECULA_SUCCESS);
        let mut unreachable = auto_desc();
        unreachable.min_psnr_db = 150.0;
        assert_eq!(specula_context_configure(b, &unreachable), SPECULA_WARNING_BUDGET_UNREACHABLE);
        assert!(warnings.iter().any(|w| w.contains("no choice is predicted to meet it")), "{warnings:?}");
        render(b);
        specula_context_destroy(a);
        specula_context_destroy(b);
    }
    // The Rust API says why: the renderer refuses the update with PlanChanged.
    let ctx = common::gpu();
    let q = {
        let mut knobs = Quality::default();
        knobs.cube.cube_size = 16;
        knobs.frame.shadow_size = 32;
        knobs.frame.depth = 4;
        knobs
    };
    let choices = specula::plan::Choices { method: specula::Choice::Auto, objects: methods.clone() };
    let mut r = Renderer::new(&ctx, &scene, specula::plan::plan_with(&scene, &choices, &q).unwrap(), w, h).unwrap();
    let mut s = scene.clone();
    s.set_object_transform(sphere as usize, Mat4::from_cols_array(&moved)).unwrap();
    let e = r.update(&s).unwrap_err();
    assert!(matches!(e, specula::Error::PlanChanged(_)), "{e}");
    r.destroy(&ctx);
    common::assert_clean(&ctx);
}

/// Caustics redo only the generators a change reaches (issue 33 item 4): where a generator's
/// photons went at its last record bounds what a later move can change of it, so a move
/// that reaches neither that region nor the light's way to the generator keeps its caustic,
/// and the map faces that see none of the redone caustics' changes keep theirs. Two glass
/// balls focus a lamp's light onto the floor of a closed room (refracted paths); a box moves
/// beside them, then under one of them, then one ball moves; every frame equals a fresh
/// renderer's bit for bit. On the demo, whose mirror sphere throws light onto every wall, a
/// box's move reaches both generators (and equals a fresh render too).
#[test]
fn caustics_redo_only_the_generators_a_change_reaches() {
    let ctx = common::gpu();
    let mut s = specula::scenes::caustic_room().unwrap();
    let index = |s: &Scene, name: &str| s.meshes.iter().position(|m| m.name == name).unwrap();
    let (b, cube) = (index(&s, "glass_b"), index(&s, "box"));
    let mut q = quality();
    for k in ["caustic_paths=refracted", "photons=48", "cube_size=128"] {
        let (key, value) = k.split_once('=').unwrap();
        q.set(key, value).unwrap();
    }
    let updates = |r: &mut Renderer, scene: &Scene, q: &Quality, what: &str| {
        r.update(scene).unwrap();
        let f = r.render(&ctx).unwrap();
        let rebuilt: Vec<(String, String)> = f.map_updates.iter().map(|u| (u.stage.to_string(), u.reason.clone())).collect();
        println!("{what}: {rebuilt:?}");
        assert!(bits(&f) == fresh(&ctx, scene, specula::methods::DISTANCE, q), "{what}: differs from a fresh context's");
        rebuilt
    };
    let reason = |u: &[(String, String)], stage: &str| u.iter().find(|(s, _)| s == stage).map(|(_, w)| w.clone());
    let mut r = renderer(&ctx, &s, specula::methods::DISTANCE, &q);
    r.render(&ctx).unwrap();
    let shift = |s: &mut Scene, m: usize, d: Vec3| {
        let world = Mat4::from_translation(d) * s.meshes[m].world;
        s.set_object_transform(m, world).unwrap();
    };
    // Beside them: no caustic is redone, and the balls' maps draw only the faces that see
    // the box or its shadow.
    shift(&mut s, cube, Vec3::new(0.1, 0.0, 0.0));
    let u = updates(&mut r, &s, &q, "box beside");
    assert_eq!(reason(&u, "caustics"), None, "{u:?}");
    let maps = reason(&u, "distance.generate").expect("the balls' maps see the box");
    assert!(maps.contains(" of 12 faces"), "{maps}");
    // Under ball a, where its light lands: a's caustic alone.
    shift(&mut s, cube, Vec3::new(-1.2, 0.0, -0.8));
    let u = updates(&mut r, &s, &q, "box under a");
    let why = reason(&u, "caustics").expect("a's caustic falls on the box");
    assert!(why.contains("1 of 2 generators ('glass_a': 'box' where its photons go)"), "{why}");
    // Ball b moves: its caustic (the box still under a leaves a's as it is).
    shift(&mut s, b, Vec3::new(0.0, 0.0, 0.1));
    let u = updates(&mut r, &s, &q, "b moved");
    let why = reason(&u, "caustics").expect("b's caustic follows it");
    assert!(why.contains("1 of 2 generators ('glass_b': it moved)"), "{why}");
    r.destroy(&ctx);

    // Screen-space caustics splat into the camera's view, depth-tested against everything: a
    // camera move redoes them, and so does any move.
    for k in ["caustics=splat", "caustic_space=screen"] {
        let (key, value) = k.split_once('=').unwrap();
        q.set(key, value).unwrap();
    }
    let mut r = renderer(&ctx, &s, specula::methods::DISTANCE, &q);
    r.render(&ctx).unwrap();
    let mut cam = s.camera.unwrap();
    cam.position += Vec3::new(0.3, 0.0, 0.0);
    cam.world_from_camera = Mat4::from_translation(Vec3::new(0.3, 0.0, 0.0)) * cam.world_from_camera;
    s.camera = Some(cam);
    let u = updates(&mut r, &s, &q, "screen-space camera");
    assert_eq!(reason(&u, "caustics").as_deref(), Some("camera"), "{u:?}");
    shift(&mut s, cube, Vec3::new(0.0, 0.0, 0.1));
    let u = updates(&mut r, &s, &q, "screen-space box");
    assert!(reason(&u, "caustics").is_some(), "{u:?}");
    r.destroy(&ctx);

    // The demo: the mirror sphere's light reaches every wall, so the box's move reaches it.
    let mut demo = specula::scene::load(std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/demo/demo.gltf"))).unwrap();
    let q = quality();
    let mut r = renderer(&ctx, &demo, specula::methods::DISTANCE, &q);
    r.render(&ctx).unwrap();
    let cube = demo.meshes.iter().position(|m| m.name.starts_with("box")).unwrap();
    shift(&mut demo, cube, Vec3::new(0.05, 0.0, 0.0));
    let u = updates(&mut r, &demo, &q, "demo box");
    assert!(reason(&u, "caustics").is_some_and(|w| !w.contains(" of 2 generators")), "{u:?}");
    r.destroy(&ctx);
    common::assert_clean(&ctx);
}
