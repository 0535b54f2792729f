//! Ray tracing in the original geometry on the GPU (survey §2): the `bvh`, `kd-tree`,
//! `grid` and `ray-query` methods against the exact CPU reference at the same depth, pixel-centre sampling
//! on both sides (lavapipe, validation on). They are exact methods: the tolerance is the
//! f32 arithmetic of the GPU against the reference's f64, stated per test with what was
//! measured when it was set.

mod common;

use std::path::Path;

use glam::{Mat4, Vec3};
use specula::methods::{BIH, BVH, GRID, KD_TREE, OCTREE, RAY_QUERY};
use specula::metrics;
use specula::reference::render_reference;
use specula::scene::{shapes, Camera, Material, Scene, SurfaceKind};
use specula::vk::ImageData;
use specula::{Method, Quality};

/// The exact schemes; `ray-query` traces through Vulkan's ray queries (lavapipe from Mesa
/// 25 has them; tests/ray_query.rs checks that the device does).
const EXACT: [Method; 6] = [BVH, KD_TREE, GRID, OCTREE, BIH, RAY_QUERY];

fn demo() -> Scene {
    specula::scene::load(Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/demo/demo.gltf"))).unwrap()
}

fn quality(pairs: &[&str]) -> Quality {
    let mut q = {
        let mut knobs = Quality::default();
        knobs.reference.spp = 1;
        knobs
    };
    for p in pairs {
        q.set_pair(p).unwrap();
    }
    q
}

fn gpu(ctx: &specula::vk::Context, scene: &Scene, m: Method, q: &Quality, size: (u32, u32)) -> ImageData {
    let img = specula::render(ctx, scene, m, q, size, (0, 1)).unwrap().image;
    assert!(img.data.iter().all(|v| v.is_finite()), "{}: non-finite pixel", m.name());
    img
}

fn psnr(a: &ImageData, b: &ImageData) -> f64 {
    metrics::compare(a, b).unwrap().psnr
}

/// Every scheme on the demo scene and on the mirror-and-glass scene, depth 4: ≥ 60 dB
/// against the reference (tests/README.md rule 2; measured at 64²: 66.28 dB on the demo,
/// 125.80 dB on mirror-and-glass, every scheme), and the three schemes agree with each
/// other: ≥ 60 dB (measured: identical images, ∞ dB).
#[test]
fn exact_schemes_match_the_reference() {
    let ctx = common::gpu();
    // The schemes' exactness: caustics, which every method takes from the same light cube
    // maps (approximate, §6; tests/caustics.rs measures them), off.
    let q = quality(&["depth=4", "caustics=off"]);
    for (name, scene) in [("demo", demo()), ("mirror_and_glass", common::mirror_and_glass(24))] {
        let reference = render_reference(&scene, &q, (64, 64)).unwrap();
        let images: Vec<ImageData> = EXACT.iter().map(|&m| gpu(&ctx, &scene, m, &q, (64, 64))).collect();
        for (m, img) in EXACT.iter().zip(&images) {
            let p = psnr(img, &reference);
            eprintln!("{name} {}: {p:.2} dB", m.name());
            // Measured: demo 66.28 dB, mirror_and_glass 125.80 dB (each scheme).
            assert!(p >= 60.0, "{name} {}: {p:.2} dB against the reference", m.name());
        }
        for (m, img) in EXACT.iter().zip(&images).skip(1) {
            let p = psnr(img, &images[0]);
            eprintln!("{name} {} against bvh: {p:.2} dB", m.name());
            // Measured: identical (∞ dB).
            assert!(p >= 60.0, "{name}: {} and bvh differ ({p:.2} dB)", m.name());
        }
        // MGK05's volumetric approximation (octree_volume=on): one averaged plane per leaf,
        // an approximate scene for the secondary rays (primary hits are rasterised); finer
        // leaves (a smaller leaf size, more levels) approach the exact image. Measured: demo
        // 22.88 dB (leaves of 8, 5 levels) → 31.30 dB (2, 8); mirror_and_glass 15.11 → 17.33
        // dB (the glass ball's refractions through planes). Floors 2 dB under; each finer
        // tree at least 1 dB better.
        let floors = if name == "demo" { [20.88, 29.30] } else { [13.11, 15.33] };
        let mut last = 0.0;
        for ((leaf, depth), floor) in [("8", "5"), ("2", "8")].into_iter().zip(floors) {
            let mut qv = q.clone();
            for pair in ["octree_volume=on", &format!("octree_leaf_size={leaf}"), &format!("octree_max_depth={depth}")] {
                qv.set_pair(pair).unwrap();
            }
            let p = psnr(&gpu(&ctx, &scene, OCTREE, &qv, (64, 64)), &reference);
            eprintln!("{name} octree_volume=on leaf {leaf} depth {depth}: {p:.2} dB");
            assert!(
                p >= floor && p >= last + 1.0,
                "{name} octree_volume=on leaf {leaf} depth {depth}: {p:.2} dB (floor {floor}, coarser {last:.2})"
            );
            last = p;
        }
    }
    common::assert_clean(&ctx);
}

/// A glass sphere in the emissive quadrant room at ν → 1 (it disappears), 1.5, and 4
/// (strong total internal reflection inside: the sphere's rim reflects at 100 %), with
/// exact Fresnel, at 96²: ≥ 60 dB against the reference (tests/README.md rule 2; measured
/// 141.81, 122.30 and 114.61 dB). At ν = 1.0001 the image is the sphere-less room's:
/// ≥ 55.5 dB against it (measured 56.46 dB; 1 dB under), while at ν = 1.5 and 4 the
/// sphere shows: < 17 dB against the empty room (measured 16.04 and 16.02 dB, 1 dB over).
#[test]
fn refraction_extremes_and_total_internal_reflection() {
    let ctx = common::gpu();
    let q = quality(&["depth=6", "fresnel=exact"]);
    let size = (96, 96);
    let room = || {
        let mut s = Scene::new();
        common::emissive_room(&mut s, Vec3::new(0.0, 2.0, 0.0), 2.0);
        // Off-centre, so that no row of pixel centres runs exactly along a room edge (where
        // two walls tie and either colour is right).
        s.camera = Some(Camera::look_at(Vec3::new(0.013, 2.021, 1.8), Vec3::new(0.007, 1.993, 0.0), 60f32.to_radians()));
        s
    };
    let empty = gpu(&ctx, &room(), BVH, &q, size);
    for ior in [1.0001f32, 1.5, 4.0] {
        let mut s = room();
        let g = s
            .add_material(Material { name: "glass".into(), kind: SurfaceKind::Dielectric { ior, thin: false }, ..Default::default() })
            .unwrap();
        s.add_mesh(shapes::uv_sphere("glass", Vec3::new(0.0, 2.0, 0.0), 0.6, 32, 16, g)).unwrap();
        let reference = render_reference(&s, &q, size).unwrap();
        let img = gpu(&ctx, &s, BVH, &q, size);
        let e = metrics::compare(&img, &reference).unwrap();
        let p = psnr(&img, &empty);
        eprintln!("ν = {ior}: {e}; against the empty room {p:.2} dB");
        // Measured 141.81 / 122.30 / 114.61 dB.
        assert!(e.psnr >= 60.0, "ν = {ior}: {e}");
        // The same paths through Vulkan's ray queries.
        let rq = metrics::compare(&gpu(&ctx, &s, RAY_QUERY, &q, size), &reference).unwrap();
        eprintln!("ν = {ior}, ray-query: {rq}");
        assert!(rq.psnr >= 60.0, "ν = {ior}, ray-query: {rq}");
        if ior < 1.001 {
            // Measured 56.46 dB.
            assert!(p >= 55.5, "ν = 1.0001 should be invisible: {p:.2} dB against the empty room");
        } else {
            // Measured 16.04 dB (ν = 1.5), 16.02 dB (ν = 4).
            assert!(p < 17.0, "ν = {ior}: the sphere should show, {p:.2} dB against the empty room");
        }
    }
    common::assert_clean(&ctx);
}

/// Two facing mirrors (F0 0.9) in the emissive room: the corridor of images. For R = 1 … 8
/// the GPU matches the reference with the same R (≥ 60 dB each, tests/README.md rule 2;
/// measured 131.14–132.17 dB: the mirrors are flat, so f32 and f64 agree to rounding), and
/// each depth up to 7 differs from the one before by what its bounce adds (PSNR of R
/// against R − 1 at most 1 dB over what was measured).
#[test]
fn recursion_depth_on_facing_mirrors() {
    let ctx = common::gpu();
    let mut s = Scene::new();
    common::emissive_room(&mut s, Vec3::new(0.0, 2.0, 0.0), 2.0);
    let m = s.add_material(common::mirror(0.9)).unwrap();
    s.add_mesh(shapes::quad("left", Vec3::new(-1.0, 1.0, 1.0), Vec3::new(0.0, 0.0, -2.0), Vec3::new(0.0, 2.0, 0.0), 1, m)).unwrap();
    s.add_mesh(shapes::quad("right", Vec3::new(1.0, 1.0, -1.0), Vec3::new(0.0, 0.0, 2.0), Vec3::new(0.0, 2.0, 0.0), 1, m)).unwrap();
    s.camera = Some(Camera::look_at(Vec3::new(-0.6, 2.0, 0.2), Vec3::new(1.0, 2.0, 0.1), 60f32.to_radians()));
    let mut previous: Option<ImageData> = None;
    for r in 1..=8u32 {
        let q = quality(&[&format!("depth={r}")]);
        let reference = render_reference(&s, &q, (40, 40)).unwrap();
        let img = gpu(&ctx, &s, BVH, &q, (40, 40));
        let p = psnr(&img, &reference);
        eprintln!("R = {r}: {p:.2} dB");
        // Measured 132.17 dB (R = 1) down to 131.14 dB (R = 8).
        assert!(p >= 60.0, "R = {r}: {p:.2} dB against the reference");
        if r == 8 {
            let rq = psnr(&gpu(&ctx, &s, RAY_QUERY, &q, (40, 40)), &reference);
            eprintln!("R = 8, ray-query: {rq:.2} dB");
            assert!(rq >= 60.0, "R = 8, ray-query: {rq:.2} dB against the reference");
        }
        // Each bounce adds an image (measured: the mean radiance grows up to R = 7, where
        // the last paths leave the mirrors' edges; R = 8 is R = 7's image). Measured PSNR of
        // R against R − 1 for R = 2 … 7: 18.59, 25.44, 28.72, 31.74, 37.33, 35.14 dB; the
        // ceilings sit 1 dB over (a bounce that adds less, or nothing, reads higher).
        const ADDED_CEILING_DB: [f64; 6] = [19.5, 26.4, 29.7, 32.7, 38.3, 36.1];
        if let (Some(prev), Some(&ceiling)) = (&previous, (r as usize).checked_sub(2).and_then(|i| ADDED_CEILING_DB.get(i))) {
            let added = psnr(&img, prev);
            eprintln!("R = {r} against R = {}: {added:.2} dB", r - 1);
            assert!(added < ceiling, "R = {r} adds too little over R = {}: {added:.2} dB (ceiling {ceiling})", r - 1);
        }
        previous = Some(img);
    }
    common::assert_clean(&ctx);
}

/// The mirror-and-glass scene, with a diffuse floor and a point light whose shadows of the
/// two spheres are in view (directly and in the mirror), scaled to 1 km and to 1 mm
/// (the light's intensity scaled by s² so that irradiance stays put) renders the image of
/// the unscaled scene: the ray and shadow-ray offsets are relative to the scene's size.
/// ≥ 60 dB (tests/README.md rule 2; measured 91.50 dB at 1 km, 116.09 dB at 1 mm, every
/// scheme).
#[test]
fn one_kilometre_and_one_millimetre_scenes() {
    let ctx = common::gpu();
    // Caustics (approximate, from the light cube maps) off: the ray tracers' own offsets.
    let q = quality(&["depth=4", "caustics=off"]);
    let mut base = common::mirror_and_glass(24);
    // A diffuse floor inside the emissive room and a point light above it: the spheres
    // cast shadows on the floor, in view, so that shadow rays (their origin offsets and
    // their distance to the light) are scaled too.
    let floor = base.add_material(Material { name: "floor".into(), base_color: Vec3::splat(0.8), ..Default::default() }).unwrap();
    base.add_mesh(shapes::quad("floor", Vec3::new(-2.0, 0.3, -2.0), Vec3::new(0.0, 0.0, 4.0), Vec3::new(4.0, 0.0, 0.0), 4, floor)).unwrap();
    base.add_light(specula::scene::Light {
        name: "lamp".into(),
        kind: specula::scene::LightKind::Point,
        position: Vec3::new(0.0, 3.6, 1.2),
        direction: Vec3::NEG_Y,
        intensity: Vec3::splat(20.0),
        range: None,
    })
    .unwrap();
    let frame = specula::render(&ctx, &base, BVH, &q, (48, 48), (0, 1)).unwrap();
    let unscaled = frame.image;
    let shadow_rays = frame.stats.iter().find(|(k, _)| k == "raytrace.shadow_rays.bounce0").unwrap().1;
    // The floor is lit by the lamp alone (the room's emission reaches only specular paths):
    // its pixels in the spheres' shadows are black, those outside are not.
    let lum = |img: &ImageData, i: usize| img.data[4 * i..4 * i + 3].iter().map(|&v| v as f64).sum::<f64>();
    let black = (0..48 * 48).filter(|&i| lum(&unscaled, i) == 0.0).count();
    eprintln!("lit scene: {shadow_rays} shadow rays at bounce 0, {black} black (shadowed) pixels");
    // Measured 589 shadow rays and 448 black pixels; floors a factor 1.122 under.
    assert!(shadow_rays >= 525.0 && black >= 399, "the shadows are in view: {shadow_rays} shadow rays, {black} black pixels");
    for s in [1000.0f32, 0.001] {
        let mut scene = base.clone();
        let t = Mat4::from_scale(Vec3::splat(s));
        for m in &mut scene.meshes {
            m.transform(t);
        }
        for l in &mut scene.lights {
            l.position *= s;
            l.intensity *= s * s;
        }
        let c = scene.camera.unwrap();
        let mut cam = Camera::look_at(c.position * s, (c.position + c.world_from_camera.transform_vector3(-Vec3::Z)) * s, c.yfov);
        cam.znear = c.znear * s;
        scene.camera = Some(cam);
        for m in EXACT {
            let img = gpu(&ctx, &scene, m, &q, (48, 48));
            let p = psnr(&img, &unscaled);
            eprintln!("scale {s} {}: {p:.2} dB", m.name());
            // Measured 91.50 dB (1 km), 116.09 dB (1 mm).
            assert!(p >= 60.0, "scale {s}, {}: {p:.2} dB against the unscaled scene", m.name());
        }
    }
    common::assert_clean(&ctx);
}

/// Zero-area triangles (repeated corners, collinear corners) in the scene, one of them in
/// front of the mirror: never hit, never NaN, the image that of the scene without them.
#[test]
fn degenerate_triangles_change_nothing() {
    let ctx = common::gpu();
    let q = quality(&["depth=4"]);
    let base = common::mirror_and_glass(16);
    let mut s = base.clone();
    let mat = s.meshes[0].material;
    let p = common::MIRROR + Vec3::new(0.0, 0.0, 0.6);
    let mesh = specula::scene::Mesh {
        name: "degenerate".into(),
        positions: vec![p, p, p + Vec3::X, p + Vec3::X * 2.0, p + Vec3::Y, p + Vec3::Y],
        indices: vec![0, 1, 2, 0, 2, 3, 4, 5, 0],
        material: mat,
        ..Default::default()
    };
    s.add_mesh(mesh).unwrap();
    for m in EXACT {
        let with = gpu(&ctx, &s, m, &q, (48, 48));
        let without = gpu(&ctx, &base, m, &q, (48, 48));
        let p = psnr(&with, &without);
        eprintln!("{}: with the degenerate triangles against without {p:.2} dB", m.name());
        // Measured: identical images (∞ dB); 60 dB is tests/README.md rule 2.
        assert!(p >= 60.0, "{}: degenerate triangles changed the image ({p:.2} dB)", m.name());
    }
    common::assert_clean(&ctx);
}

/// Three mirrors in mutual view, where maps see each other as the environment only: at the
/// asked knobs (`plan_knobs=keep`) the measuring planner ray traces them (every other
/// candidate is predicted far less accurate), exact against the reference. (Free to choose
/// the knobs it takes inter-object distance maps with 4× multisampling, which measured
/// better than bvh here in both time and error at 128²: 33.7 against 31.9 dB, 9.8 against
/// 17.2 ms, against bvh supersampled 4×4.)
#[test]
fn planner_ray_traces_objects_in_mutual_view() {
    let mut s = Scene::new();
    common::emissive_room(&mut s, Vec3::new(0.0, 2.0, 0.0), 2.0);
    let m = s.add_material(common::mirror(0.9)).unwrap();
    for (i, c) in [Vec3::new(-0.6, 1.5, 0.0), Vec3::new(0.6, 1.5, 0.0), Vec3::new(0.0, 1.5, -0.9)].into_iter().enumerate() {
        s.add_mesh(shapes::uv_sphere(&format!("ball{i}"), c, 0.45, 24, 12, m)).unwrap();
    }
    s.camera = Some(Camera::look_at(Vec3::new(0.0, 2.2, 2.0), Vec3::new(0.0, 1.5, -0.3), 60f32.to_radians()));
    let choices = specula::Choices::default();
    let p = specula::plan_with(&s, &choices, &quality(&["plan_knobs=keep"])).unwrap();
    for o in &p.objects {
        assert_eq!(o.method.family, "raytrace", "{}: {}", o.mesh, o.reason);
        assert!(o.reason.starts_with("auto: predicted"), "{}", o.reason);
    }
    // Rendered: exact against the reference.
    let ctx = common::gpu();
    let q = quality(&["depth=4", "plan_knobs=keep"]);
    let img = specula::render_plan(&ctx, &s, specula::plan_with(&s, &choices, &q).unwrap(), (48, 48), (0, 1)).unwrap().image;
    let p = psnr(&img, &render_reference(&s, &q, (48, 48)).unwrap());
    eprintln!("auto on three mirrors in mutual view: {p:.2} dB against the reference");
    // Measured 133.02 dB; 60 dB is tests/README.md rule 2.
    assert!(p >= 60.0, "auto on three mirrors in mutual view: {p:.2} dB");
    common::assert_clean(&ctx);
}

/// The frame's ray statistics: bounce 0 holds one ray per pixel (the whole scene is traced),
/// shadow rays follow the diffuse hits, nothing is dropped at the default budget; with a
/// budget of one ray per pixel and a glass sphere filling the view (two children per
/// pixel) the overflow is counted; the ray hierarchy reports its culling rate with
/// `ray_stats=on`, the same in every run.
#[test]
fn ray_statistics_count_rays_and_overflow() {
    let ctx = common::gpu();
    let stat = |f: &specula::Frame, name: &str| f.stats.iter().find(|(k, _)| k == name).map(|(_, v)| *v);
    let q = quality(&["depth=2"]);
    let f = specula::render(&ctx, &demo(), BVH, &q, (32, 32), (0, 1)).unwrap();
    eprintln!("demo stats: {:?}", f.stats);
    assert_eq!(stat(&f, "raytrace.rays.bounce0"), Some(1024.0), "{:?}", f.stats);
    // One shadow ray per diffuse hit and light: measured 851 at bounce 0; within a factor
    // 1.122 either way (fewer: diffuse hits left unlit; more: rays spawned twice).
    let shadows = stat(&f, "raytrace.shadow_rays.bounce0").unwrap();
    assert!((759.0..=954.0).contains(&shadows), "{:?}", f.stats);
    assert_eq!(stat(&f, "raytrace.dropped_rays"), Some(0.0));
    // The build's time is reported (its value is the machine's, not bounded).
    assert!(stat(&f, "raytrace.build_ms").is_some(), "{:?}", f.stats);

    let mut s = common::mirror_and_glass(24);
    s.camera = Some(Camera::look_at(common::GLASS + Vec3::new(0.0, 0.0, 0.8), common::GLASS, 50f32.to_radians()));
    let tight = quality(&["depth=2", "ray_budget=1"]);
    let f = specula::render(&ctx, &s, BVH, &tight, (32, 32), (0, 1)).unwrap();
    eprintln!("glass stats: {:?}", f.stats);
    // Every pixel sees the glass: two children each (reflected, refracted), 2048 (measured
    // 2048), of which the budget of 1024 keeps the heaviest weight bins that fit (spawn.comp).
    assert_eq!(stat(&f, "raytrace.rays.bounce1"), Some(2048.0), "{:?}", f.stats);
    let dropped = stat(&f, "raytrace.dropped_rays").unwrap();
    assert!(dropped >= 1024.0, "{:?}", f.stats);
    // What a full queue keeps depends on the paths' weights alone: the same image in every
    // run, and the light missing against an unlimited budget is the light of the lightest
    // paths (the reflections, Fresnel ≈ 4 % at normal incidence). Measured: 2048 rays
    // dropped (1024 at each bounce) of path weight 83.2 in all (0.04 each, where a refracted
    // child weighs ≈ 0.96); PSNR against ray_budget=8 33.65 dB. Asserted: the dropped rays
    // weigh under 0.1 each on average, and the PSNR within 1 dB of the measured.
    let again = specula::render(&ctx, &s, BVH, &tight, (32, 32), (0, 1)).unwrap();
    assert!(f.image.data == again.image.data, "an overflowing frame differs between runs");
    let weight = stat(&f, "raytrace.dropped_weight").unwrap();
    let full = specula::render(&ctx, &s, BVH, &quality(&["depth=2", "ray_budget=8"]), (32, 32), (0, 1)).unwrap();
    assert_eq!(stat(&full, "raytrace.dropped_rays"), Some(0.0));
    let psnr = psnr(&f.image, &full.image);
    eprintln!("dropped weight {weight}, PSNR against an unlimited budget {psnr:.2} dB");
    assert!(weight > 0.0 && weight < 0.1 * dropped, "{:?}", f.stats);
    assert!(psnr >= 32.65, "{psnr:.2} dB");
    // Seen from further, the glass covers part of the view: more children than the queue
    // holds, but fewer heavy ones. The cut falls inside a bin of reflections, of which a
    // spatially even subset (sub-bins by a hash of pixel and direction) fills the queue.
    // Measured: 1264 children, 242 dropped, 1022 of the 1024 places filled.
    s.camera = Some(Camera::look_at(common::GLASS + Vec3::new(0.0, 0.0, 1.3), common::GLASS, 50f32.to_radians()));
    let one = quality(&["depth=1", "ray_budget=1"]);
    let f = specula::render(&ctx, &s, BVH, &one, (32, 32), (0, 1)).unwrap();
    eprintln!("partial glass stats: {:?}", f.stats);
    let again = specula::render(&ctx, &s, BVH, &one, (32, 32), (0, 1)).unwrap();
    assert!(f.image.data == again.image.data, "an overflowing frame differs between runs");
    let spawned = stat(&f, "raytrace.rays.bounce1").unwrap();
    let kept = spawned - stat(&f, "raytrace.dropped_rays").unwrap();
    assert!(spawned > 1024.0 && (1000.0..=1024.0).contains(&kept), "{:?}", f.stats);

    // The ray hierarchy orders each queue by direction cell and pixel before building its
    // tiles' cones (src/methods/raytrace/ray_order.rs): its culling is the same in every
    // run. Measured at 48², tile 8: bounce 0 rays 0.99782 (the cone test keeps 0.22 % of
    // the tile × triangle pairs), bounce 0 shadow rays 0.8036 (16 % in append order at 256²,
    // 0 % at 16²), bounce 1 shadow rays 0.1475, bounce 1 rays 0.1110 (0 when ordered by
    // pixel alone: after the curved mirror and the glass the rays of a screen block diverge
    // and their cone covered everything; 0.1033 with 2 × 2 direction cells, 0.1168 with
    // 8 × 8). Asserted: two renders agree to the bit; each rate kept to within a factor
    // 1.122 of what it keeps (bounce 0 rays ≥ 0.99758) or rejects (the others).
    let h = quality(&["depth=1", "ray_stats=on", "tile_size=8"]);
    let hierarchy = |ctx| specula::render(ctx, &demo(), specula::methods::RAY_HIERARCHY, &h, (48, 48), (0, 1)).unwrap();
    let f = hierarchy(&ctx);
    eprintln!("hierarchy stats: {:?}", f.stats);
    let rates = |f: &specula::Frame| -> Vec<(String, f64)> { f.stats.iter().filter(|(k, _)| k.contains("cull_rate")).cloned().collect() };
    assert_eq!(rates(&f), rates(&hierarchy(&ctx)), "the ray order is the same in every run");
    let rate = |name: &str| stat(&f, &format!("raytrace.cull_rate.{name}"));
    assert!(rate("bounce0.rays").is_some_and(|r| r >= 0.99758), "{:?}", f.stats);
    assert!(rate("bounce0.shadow_rays").is_some_and(|r| r >= 0.8036 / 1.122), "{:?}", f.stats);
    assert!(rate("bounce1.shadow_rays").is_some_and(|r| r >= 0.1475 / 1.122), "{:?}", f.stats);
    assert!(rate("bounce1.rays").is_some_and(|r| r >= 0.1110 / 1.122), "{:?}", f.stats);

    // Camera rays beyond what one storage buffer holds on the device (lavapipe: 128 MiB,
    // 2.8 M rays; 512² supersampled 4×4 is 4.2 M): an error naming the frame, before any
    // descriptor could point past the range.
    let max = ctx.properties.limits.max_storage_buffer_range as u64;
    let side = (((max / 48) as f64).sqrt() as u32 / 4 + 8).min(4096);
    let e = specula::render(&ctx, &demo(), BVH, &quality(&["depth=1", "aa=ssaa4"]), (side, side), (0, 1)).unwrap_err().to_string();
    assert!(e.contains("frame size") && e.contains("camera rays") && e.contains("storage-buffer range"), "{e}");
    common::assert_clean(&ctx);
}

/// KHR_materials_specular on solid glass (factor 0.5, colour (1, 0.5, 0.2), Schlick): the
/// reference scales F0 by the colour and the reflected lobe by the factor (its formula is
/// anchored in tests/physics_anchors.rs); the GPU's exact ray tracer must match it on that
/// scene, and the extension must change the image, so that a GPU or a reference that
/// ignores it fails.
#[test]
fn khr_materials_specular_scales_the_reflection() {
    let ctx = common::gpu();
    let scene = |factor: f32, color: Vec3| {
        let mut s = Scene::new();
        common::emissive_room(&mut s, Vec3::ZERO, 2.0);
        let m = s
            .add_material(Material {
                name: "glass".into(),
                kind: SurfaceKind::Dielectric { ior: 1.5, thin: false },
                specular_factor: factor,
                specular_color: color,
                ..Default::default()
            })
            .unwrap();
        s.add_mesh(shapes::uv_sphere("ball", Vec3::new(0.0, -0.3, -0.4), 0.9, 64, 32, m)).unwrap();
        s.camera = Some(Camera::look_at(Vec3::new(1.3, 0.9, 1.6), Vec3::new(0.0, -0.3, -0.4), 50f32.to_radians()));
        s
    };
    let (plain, specular) = (scene(1.0, Vec3::ONE), scene(0.5, Vec3::new(1.0, 0.5, 0.2)));
    let q = quality(&["depth=8"]);
    let size = (48, 36);
    let (ref_plain, ref_spec) = (render_reference(&plain, &q, size).unwrap(), render_reference(&specular, &q, size).unwrap());
    let gpu_spec = gpu(&ctx, &specular, BVH, &q, size);
    let (matched, ignored, effect) = (psnr(&gpu_spec, &ref_spec), psnr(&ref_plain, &ref_spec), psnr(&gpu_spec, &ref_plain));
    eprintln!("KHR_materials_specular: GPU vs reference {matched:.2} dB; the reference with and without it {ignored:.2} dB; GPU vs plain {effect:.2} dB");
    // Measured: 128.01 dB matched (f32 rounding against f64; the floor is tests/README.md
    // rule 2's 60 dB), 33.50 dB between the two references and between the GPU and the
    // plain reference (ceiling 1 dB over).
    assert!(matched > 60.0, "GPU bvh vs the reference: {matched:.2} dB");
    assert!(ignored < 34.5 && effect < 34.5, "the extension shows: {matched:.2} vs {ignored:.2} / {effect:.2} dB");
    common::assert_clean(&ctx);
}

/// Curved rays in graded media (survey §6.5, issue 36 item 7): the mirage over a hot floor
/// and the graded-index lens (`builtin:mirage`, `builtin:grin-lens`), the GPU's RK4 march
/// (f32, medium_turn 0.05 and 0.01) against the reference's (f64, turn 0.002), through a
/// compute scheme and through ray queries. The closed-form ray paths are checked in
/// src/scene/medium.rs's unit tests (the catenary of a linear gradient, the mirage's turning
/// point). The curving must show: the same scenes with the index uniform (its value at the
/// field's origin) differ from the reference by far more than the GPU does. Measured at
/// 64×48: mirage bvh 49.69 dB (medium_turn 0.01: 57.11), ray-query 49.69, straight 15.93;
/// grin-lens 41.40 (54.93), 41.40, straight 12.45. Floors: 40 dB; straight under 25.
#[test]
fn curved_rays_through_graded_media() {
    let ctx = common::gpu();
    let size = (64, 48);
    for name in ["mirage", "grin-lens"] {
        let scene = specula::scenes::builtin(name).unwrap().unwrap();
        let q = quality(&["depth=6"]);
        let reference = render_reference(&scene, &q, size).unwrap();
        let mut uniform = scene.clone();
        for m in &mut uniform.materials {
            m.graded = None;
        }
        let straight = psnr(&render_reference(&uniform, &q, size).unwrap(), &reference);
        let bvh = psnr(&gpu(&ctx, &scene, BVH, &q, size), &reference);
        let fine = psnr(&gpu(&ctx, &scene, BVH, &quality(&["depth=6", "medium_turn=0.01"]), size), &reference);
        let rq = psnr(&gpu(&ctx, &scene, RAY_QUERY, &q, size), &reference);
        eprintln!("{name}: bvh {bvh:.2} dB (medium_turn 0.01: {fine:.2} dB), ray-query {rq:.2} dB; straight rays {straight:.2} dB");
        assert!(bvh >= 40.0 && rq >= 40.0 && fine >= 40.0, "{name}: {bvh:.2} / {rq:.2} / {fine:.2} dB");
        // The knob is the march's accuracy: a fifth of the turn, measured +7.42 and +13.53 dB.
        assert!(fine > bvh + 6.42, "{name}: medium_turn 0.01 {fine:.2} dB against 0.05 {bvh:.2} dB");
        assert!(straight < 25.0, "{name}: the curving shows: {straight:.2} dB");
    }
    // 1 km and 1 mm: the step is an angle, the field scales with the scene (n(x/k)).
    let mirage = specula::scenes::builtin("mirage").unwrap().unwrap();
    let q = quality(&["depth=6"]);
    for k in [1000.0f32, 0.001] {
        let s = common::scaled(&mirage, k);
        let p = psnr(&gpu(&ctx, &s, BVH, &q, size), &render_reference(&s, &q, size).unwrap());
        eprintln!("mirage ×{k}: bvh {p:.2} dB");
        assert!(p >= 40.0, "mirage ×{k}: {p:.2} dB");
    }
    common::assert_clean(&ctx);
}

/// Only the ray pipeline's compute schemes trace curved rays: `--method` of another falls
/// back to `bvh` for a graded medium (saying why), a per-object choice of one is refused
/// naming the object, and `auto` gives it a curved-ray tracer.
#[test]
fn graded_media_are_served_by_curved_ray_tracers() {
    let scene = specula::scenes::builtin("mirage").unwrap().unwrap();
    let q = Quality::default();
    let p = specula::plan::plan(&scene, specula::methods::DISTANCE, &q);
    let o = p.objects.iter().find(|o| scene.meshes[o.mesh].name == "hot-layer").unwrap();
    assert_eq!(o.method, BVH, "{}", o.reason);
    assert!(o.reason.contains("curved rays"), "{}", o.reason);
    let choices =
        specula::plan::Choices { method: specula::Choice::Auto, objects: vec![("hot-layer".into(), specula::methods::RAY_ENGINE)] };
    let e = specula::plan::plan_with(&scene, &choices, &q).unwrap_err().to_string();
    assert!(e.contains("hot-layer") && e.contains("ray-engine") && e.contains("graded-index") && e.contains("bvh"), "{e}");
    let auto = specula::plan::plan(&scene, specula::Choice::Auto, &q);
    assert!(
        auto.objects.iter().all(|o| o.method.traces_curved_rays()),
        "{:?}",
        auto.objects.iter().map(|o| o.method.name()).collect::<Vec<_>>()
    );
}

/// A graded medium moved between frames (an engine moves objects every frame): its surface
/// moves, its field stays in the world (docs/conventions.md); the incremental frame equals
/// a fresh renderer's bit for bit (bvh rebuilt by SAH on each move, as a fresh one builds it).
#[test]
fn a_moved_graded_medium_renders_as_a_fresh_frame() {
    let ctx = common::gpu();
    let mut scene = specula::scenes::builtin("grin-lens").unwrap().unwrap();
    let lens = scene.meshes.iter().position(|m| m.name == "grin-lens").unwrap();
    let q = quality(&["depth=4", "bvh_update=sah"]);
    let size = (48, 36);
    let plan = specula::plan::plan(&scene, BVH, &q);
    let mut r = specula::Renderer::new(&ctx, &scene, plan, size.0, size.1).unwrap();
    let first = r.render(&ctx).unwrap().image;
    for k in 1..=2 {
        scene.set_object_transform(lens, Mat4::from_translation(Vec3::new(0.1 * k as f32, -0.05 * k as f32, 0.0))).unwrap();
        r.update(&scene).unwrap();
        let moved = r.render(&ctx).unwrap().image;
        let fresh = gpu(&ctx, &scene, BVH, &q, size);
        assert!(moved.data == fresh.data, "move {k}: the incremental frame differs from a fresh one");
        assert!(psnr(&moved, &first) < 40.0, "move {k}: the lens moved in the image");
    }
    r.destroy(&ctx);
    common::assert_clean(&ctx);
}
