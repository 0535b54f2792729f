//! Geometry transformation (survey §5): planar mirrors by rendering the mirrored camera's
//! view (`planar-mirror`), against the exact CPU reference at the same recursion depth.

mod common;

use glam::Vec3;
use specula::image::ImageData;
use specula::scene::{shapes, Camera, Material, Scene};
use specula::{Method, Quality};

const SIZE: (u32, u32) = (64, 48);

/// An emissive room (24 distinct quadrants, no lights: nothing but geometry and Fresnel
/// decides the image) of half-size 2 m, an emissive ball, and planar mirrors.
fn room(mirrors: &[(Vec3, Vec3, Vec3)], camera: (Vec3, Vec3)) -> Scene {
    let mut s = Scene::new();
    common::emissive_room(&mut s, Vec3::ZERO, 2.0);
    let ball = s
        .add_material(Material { name: "ball".into(), base_color: Vec3::ZERO, emissive: Vec3::new(1.5, 0.8, 0.2), ..Default::default() })
        .unwrap();
    s.add_mesh(shapes::uv_sphere("ball", Vec3::new(0.4, -0.8, -0.6), 0.35, 24, 12, ball)).unwrap();
    let m = s.add_material(common::mirror(0.9)).unwrap();
    for (i, (o, u, v)) in mirrors.iter().enumerate() {
        s.add_mesh(shapes::quad(&format!("mirror{i}"), *o, *u, *v, 1, m)).unwrap();
    }
    s.camera = Some(Camera::look_at(camera.0, camera.1, 60f32.to_radians()));
    s
}

fn quality(depth: u32) -> Quality {
    let mut q = {
        let mut knobs = Quality::default();
        knobs.frame.depth = depth;
        knobs.reference.spp = 1;
        knobs
    };
    q.set("fresnel", "exact").unwrap();
    q
}

fn psnr(a: &ImageData, b: &ImageData) -> f64 {
    specula::metrics::compare(a, b).unwrap().psnr
}

fn gpu(ctx: &specula::vk::Context, s: &Scene, m: Method, q: &Quality) -> specula::Frame {
    specula::render(ctx, s, m, q, SIZE, (0, 1)).unwrap()
}

#[test]
fn a_mirror_wall_is_exact_up_to_rasterisation() {
    let ctx = common::gpu();
    // A 2.4 m × 2.2 m mirror 0.1 m in front of the back wall, seen at an angle.
    let wall = (Vec3::new(-1.2, -1.0, -1.9), Vec3::new(2.4, 0.0, 0.0), Vec3::new(0.0, 2.2, 0.0));
    let s = room(&[wall], (Vec3::new(0.9, 0.3, 1.5), Vec3::new(-0.3, 0.0, -1.9)));
    let q = quality(4);
    let reference = specula::reference::render_reference(&s, &q, SIZE).unwrap();
    let f = gpu(&ctx, &s, specula::methods::PLANAR_MIRROR, &q);
    let p = psnr(&f.image, &reference);
    let d = psnr(&gpu(&ctx, &s, specula::methods::DISTANCE, &q).image, &reference);
    println!("mirror wall: planar-mirror {p:.2} dB, distance {d:.2} dB");
    let names: Vec<&str> = f.passes.iter().map(|p| p.name.as_str()).collect();
    assert!(names.contains(&"geometry.mirror") && names.contains(&"geometry.mirror_view"), "{names:?}");
    // The view draws on the mirror's pixels only: geometry.stencil marks them first.
    assert!(names.contains(&"geometry.stencil"), "{names:?}");
    // Exact (tests/README.md rule 2): measured 155.30 dB, f32 rounding against f64.
    assert!(p >= 60.0, "planar-mirror {p:.2} dB against the reference");
    // Memory per view: one RGBA32F layer of the frame's size per view the plan may render,
    // and one scratch colour + depth target; the stats agree with the allocator's records.
    let (layers, view, scratch) =
        (stat(&f, "geometry.mirror_layers"), stat(&f, "geometry.mirror_view_bytes"), stat(&f, "geometry.mirror_scratch_bytes"));
    let pixels = (SIZE.0 * SIZE.1) as f64;
    println!("mirror wall: {layers} view layer(s) of {view} B, scratch {scratch} B");
    assert_eq!((view, scratch), (16.0 * pixels, 20.0 * pixels));
    let allocated = |name: &str| f.memory.iter().filter(|(n, _)| n == name).map(|(_, b)| *b as f64).sum::<f64>();
    assert!(layers >= 1.0 && allocated("geometry.mirror_views") >= layers * view, "{:?}", f.memory);
    assert!(allocated("geometry.mirror_views") < (layers + 1.0) * view, "no layer beyond the plan's: {:?}", f.memory);
    assert!(allocated("geometry.mirror_view") + allocated("geometry.mirror_view.depth") >= scratch, "{:?}", f.memory);
    // The same wall served by distance maps allocates none of it.
    let none = gpu(&ctx, &s, specula::methods::DISTANCE, &q);
    assert!(none.stats.iter().all(|(n, _)| !n.starts_with("geometry.")), "{:?}", none.stats);
    assert!(none.memory.iter().all(|(n, _)| !n.starts_with("geometry.")), "{:?}", none.memory);
    common::assert_clean(&ctx);
}

fn stat(f: &specula::Frame, name: &str) -> f64 {
    f.stats.iter().find(|(n, _)| n == name).map_or(f64::NAN, |(_, v)| *v)
}

/// Two facing mirrors on the left and right walls: the corridor of images.
fn corridor() -> Scene {
    let left = (Vec3::new(-1.9, -1.8, 1.8), Vec3::new(0.0, 0.0, -3.6), Vec3::new(0.0, 3.6, 0.0));
    let right = (Vec3::new(1.9, -1.8, -1.8), Vec3::new(0.0, 0.0, 3.6), Vec3::new(0.0, 3.6, 0.0));
    room(&[left, right], (Vec3::new(0.6, 0.2, 1.4), Vec3::new(-1.9, -0.1, -0.6)))
}

#[test]
fn facing_mirrors_recurse_to_the_reference_depth_within_the_budget() {
    let ctx = common::gpu();
    let s = corridor();
    let mut views_at = Vec::new();
    for depth in 1..=6 {
        let mut q = quality(depth);
        q.set("mirror_budget", "64").unwrap();
        let reference = specula::reference::render_reference(&s, &q, SIZE).unwrap();
        let f = gpu(&ctx, &s, specula::methods::PLANAR_MIRROR, &q);
        let p = psnr(&f.image, &reference);
        let (views, deepest) = (stat(&f, "geometry.mirror_views"), stat(&f, "geometry.mirror_depth"));
        println!("depth {depth}: {views} views, deepest {deepest}, {p:.2} dB");
        assert_eq!(deepest, depth as f64, "depth {depth}: the corridor is visible to every level");
        // Every view fits the budget: no fallback map.
        assert!(f.passes.iter().all(|p| p.name != "distance.generate"), "depth {depth}: a map no view needs");
        // Exact (rule 2): measured 152.39, 150.02, 149.23, 148.84, 148.57 and 148.39 dB.
        assert!(p >= 60.0, "depth {depth}: {p:.2} dB against the reference at the same depth");
        views_at.push(views);
    }
    // Each level adds views (the corridor: one per mirror seen at that level).
    assert!(views_at.windows(2).all(|w| w[1] > w[0]), "{views_at:?}");

    // The budget caps the views; the mirrors it leaves out continue in a distance map of
    // their own (the plan gives each mirror one where the budget can cut its views), whose
    // error against the full-depth reference is stated per budget (within 1 dB either way:
    // above, the budget let more views through than it says; below, the views it did render
    // or the fallback got worse), and falls step by step as the budget grows (each step
    // within 1 dB of its measured gain). Measured 22.10, 24.49 and 29.54 dB; with the
    // environment as the fallback (black in this closed room) they were 15.58, 20.30 and
    // 28.96 dB.
    let full = quality(6);
    let reference = specula::reference::render_reference(&s, &full, SIZE).unwrap();
    let mut last = f64::NAN;
    for (budget, measured, gain) in [(1u32, 22.10, f64::NAN), (2, 24.49, 2.39), (4, 29.54, 5.05)] {
        let mut q = full.clone();
        q.set("mirror_budget", &budget.to_string()).unwrap();
        let f = gpu(&ctx, &s, specula::methods::PLANAR_MIRROR, &q);
        let views = stat(&f, "geometry.mirror_views");
        let p = psnr(&f.image, &reference);
        let fallbacks = stat(&f, "geometry.mirror_fallbacks");
        println!("budget {budget}: {views} views, {fallbacks} fallbacks, {p:.2} dB against depth 6");
        assert_eq!(views, budget as f64, "budget {budget}");
        assert!(f.passes.iter().any(|p| p.name == "distance.generate"), "budget {budget}: no fallback map");
        // The corridor's views are a chain: the last view sees the other mirror, one fallback
        // (measured 1 at every budget).
        assert_eq!(fallbacks, 1.0, "budget {budget}");
        let mirror_passes = f.passes.iter().filter(|p| p.name == "geometry.mirror_view").count();
        assert!(mirror_passes >= budget as usize, "{mirror_passes} mirror-view passes for {budget} views");
        assert!((p - measured).abs() <= 1.0, "budget {budget}: {p:.2} dB against depth 6 (measured {measured} dB)");
        assert!(
            last.is_nan() || p >= last + gain - 1.0,
            "budget {budget}: {p:.2} dB (budget {} gave {last:.2} dB; measured gain {gain} dB)",
            budget / 2
        );
        last = p;
    }
    common::assert_clean(&ctx);
}

/// Extremes of the camera against the mirror: grazing incidence, a mirror that reaches
/// behind the camera, and a camera in the mirror's plane (edge-on: no pixel, no view).
#[test]
fn grazing_behind_the_camera_and_edge_on_mirrors() {
    let ctx = common::gpu();
    let wall = (Vec3::new(-1.8, -1.8, -1.9), Vec3::new(3.6, 0.0, 0.0), Vec3::new(0.0, 3.6, 0.0));
    let cases = [
        // 4° above the mirror's plane, looking along it.
        ("grazing", (Vec3::new(-1.2, 0.0, -1.9 + 3.0 * 4f32.to_radians().tan()), Vec3::new(1.8, 0.0, -1.9)), 1.0),
        // 0.3 m in front of the mirror, looking across it: the mirror reaches behind the camera.
        ("behind", (Vec3::new(0.0, 0.2, -1.6), Vec3::new(1.5, -0.3, -1.9)), 1.0),
        // In the mirror's plane: edge-on.
        ("edge-on", (Vec3::new(-1.0, 0.3, -1.9), Vec3::new(1.0, 0.0, -1.9)), 0.0),
    ];
    for (name, camera, views) in cases {
        let s = room(&[wall], camera);
        let q = quality(4);
        let reference = specula::reference::render_reference(&s, &q, SIZE).unwrap();
        let f = gpu(&ctx, &s, specula::methods::PLANAR_MIRROR, &q);
        let p = psnr(&f.image, &reference);
        println!("{name}: {} views, {p:.2} dB", stat(&f, "geometry.mirror_views"));
        assert!(f.image.data.iter().all(|v| v.is_finite()), "{name}: non-finite pixels");
        assert_eq!(stat(&f, "geometry.mirror_views"), views, "{name}");
        // Exact (rule 2): measured 146.53 dB (grazing), 148.41 dB (behind), inf (edge-on: no
        // mirror pixel, the images are equal).
        assert!(p >= 60.0, "{name}: {p:.2} dB");
    }
    common::assert_clean(&ctx);
}

/// The corridor at 1 mm and 1 km: the same image (nothing in the mirrored views depends on
/// absolute size: the clip offset and the edge-on test are relative).
#[test]
fn mirrors_at_a_millimetre_and_a_kilometre() {
    let ctx = common::gpu();
    let base = corridor();
    let q = quality(3);
    let one = gpu(&ctx, &base, specula::methods::PLANAR_MIRROR, &q).image;
    for scale in [1e-3f32, 1e3] {
        let s = common::scaled(&base, scale);
        let f = gpu(&ctx, &s, specula::methods::PLANAR_MIRROR, &q);
        let p = psnr(&f.image, &one);
        println!("scale {scale:e}: {} views, {p:.2} dB against scale 1", stat(&f, "geometry.mirror_views"));
        assert_eq!(stat(&f, "geometry.mirror_views"), 3.0, "scale {scale:e}");
        // Exact (rule 2): measured 153.58 dB (1 mm) and 153.96 dB (1 km).
        assert!(p >= 60.0, "scale {scale:e}: {p:.2} dB");
    }
    common::assert_clean(&ctx);
}

/// What planar-mirror serves: a curved mirror is not planar (chosen for the whole scene it
/// falls back to distance maps, chosen for the object it is refused by name), and a mirror
/// of no area renders nothing and breaks nothing.
#[test]
fn only_planar_reflectors_take_the_mirrored_view() {
    let ctx = common::gpu();
    let mut s = room(&[], (Vec3::new(0.9, 0.3, 1.5), Vec3::new(-0.3, 0.0, -1.9)));
    let m = s.add_material(common::mirror(0.9)).unwrap();
    s.add_mesh(shapes::uv_sphere("sphere", Vec3::new(-0.6, 0.0, -1.0), 0.5, 16, 8, m)).unwrap();
    let plan = specula::plan(&s, specula::methods::PLANAR_MIRROR, &Quality::default());
    let o = plan.objects.iter().find(|o| o.name == "sphere").unwrap();
    assert_eq!(o.method, specula::methods::DISTANCE, "{}", o.reason);
    assert!(o.reason.contains("non-planar"), "{}", o.reason);
    let choices =
        specula::plan::Choices { method: specula::Choice::Auto, objects: vec![("sphere".into(), specula::methods::PLANAR_MIRROR)] };
    let e = specula::plan::plan_with(&s, &choices, &Quality::default()).unwrap_err().to_string();
    assert!(e.contains("'sphere'") && e.contains("planar reflectors only"), "{e}");

    // A degenerate mirror: its vertices on one line.
    let mut s = room(&[], (Vec3::new(0.9, 0.3, 1.5), Vec3::new(-0.3, 0.0, -1.9)));
    let m = s.add_material(common::mirror(0.9)).unwrap();
    s.add_mesh(shapes::quad("sliver", Vec3::new(-1.0, 0.0, -1.9), Vec3::new(2.0, 0.0, 0.0), Vec3::new(1e-12, 0.0, 0.0), 1, m)).unwrap();
    let q = quality(2);
    let plan = specula::plan(&s, specula::methods::PLANAR_MIRROR, &q);
    println!("sliver: {} ({})", plan.objects[0].method, plan.objects[0].reason);
    match specula::render(&ctx, &s, specula::methods::PLANAR_MIRROR, &q, SIZE, (0, 1)) {
        Ok(f) => {
            assert!(f.image.data.iter().all(|v| v.is_finite()));
            // Not planar (no plane to speak of): its fallback; or planar with no view.
            let views = stat(&f, "geometry.mirror_views");
            assert!(plan.objects[0].method != specula::methods::PLANAR_MIRROR || views == 0.0, "{views} views");
        }
        // Refused at import as degenerate geometry is fine too, if it says so.
        Err(e) => assert!(e.to_string().contains("sliver"), "{e}"),
    }
    common::assert_clean(&ctx);
}

/// A mirror wall by planar-mirror and a mirror sphere ray traced (what the rule-based
/// planner chose; per-object choices now): the wall's views show the sphere with its own
/// method. Whatever
/// draws the sphere inside the wall's view also works with a ray tracer (the clip plane of
/// the view), and with MSAA (each view resolved into its layer).
#[test]
fn a_mirror_sphere_beside_a_mirror_wall() {
    let ctx = common::gpu();
    let wall = (Vec3::new(-1.2, -1.0, -1.9), Vec3::new(2.4, 0.0, 0.0), Vec3::new(0.0, 2.2, 0.0));
    let mut s = room(&[wall], (Vec3::new(0.9, 0.3, 1.5), Vec3::new(-0.3, 0.0, -1.9)));
    let m = s.add_material(common::mirror(0.9)).unwrap();
    s.add_mesh(shapes::uv_sphere("sphere", Vec3::new(-0.5, 0.1, -1.0), 0.45, 32, 16, m)).unwrap();
    let q = quality(4);
    let mixed = specula::plan::Choices {
        method: specula::Choice::Auto,
        objects: vec![("mirror0".into(), specula::methods::PLANAR_MIRROR), ("sphere".into(), specula::methods::BVH)],
    };
    let plan = specula::plan::plan_with(&s, &mixed, &q).unwrap();
    let method = |name: &str| plan.objects.iter().find(|o| o.name == name).unwrap().method;
    let reference = specula::reference::render_reference(&s, &q, SIZE).unwrap();
    // The sphere sees the wall: its maps would show the wall as the environment, so it is ray
    // traced (in the camera and in the wall's view).
    let auto = specula::render_plan(&ctx, &s, plan.clone(), SIZE, (0, 1)).unwrap();
    let p_auto = psnr(&auto.image, &reference);
    let distance = psnr(&gpu(&ctx, &s, specula::methods::DISTANCE, &q).image, &reference);
    println!("auto ({}): {p_auto:.2} dB; distance everywhere {distance:.2} dB", method("sphere"));
    assert_eq!(stat(&auto, "geometry.mirror_views"), 1.0);
    // Measured 46.22 vs 21.82 dB: a margin of 24.40 dB, the bound 1 dB under it.
    assert!(p_auto >= distance + 23.4, "auto {p_auto:.2} dB vs distance {distance:.2} dB");

    // The sphere by distance-multi instead: the wall shows the sphere, and the sphere's map
    // shows the wall's reflection by the wall's mirrored view per cube face (map_mirrors);
    // without them the map shows the wall reflecting the environment only. Measured on the
    // sphere's own pixels (where the image differs from the room without the sphere).
    let choices = specula::plan::Choices {
        method: specula::Choice::Auto,
        objects: vec![("mirror0".into(), specula::methods::PLANAR_MIRROR), ("sphere".into(), specula::methods::DISTANCE_MULTI)],
    };
    let without_sphere = {
        let mut w = s.clone();
        w.meshes.retain(|m| m.name != "sphere");
        specula::reference::render_reference(&w, &q, SIZE).unwrap()
    };
    let mut on_sphere = Vec::new();
    for map_mirrors in ["on", "off"] {
        let mut qm = q.clone();
        qm.set("map_mirrors", map_mirrors).unwrap();
        let plan = specula::plan::plan_with(&s, &choices, &qm).unwrap();
        assert_eq!(plan.map_mirrors.len(), (map_mirrors == "on") as usize);
        let mut r = specula::Renderer::new(&ctx, &s, plan, SIZE.0, SIZE.1).unwrap();
        let f = r.render(&ctx).unwrap();
        r.destroy(&ctx);
        let (sphere, n) = psnr_on_glass(&f.image, &reference, &without_sphere);
        println!(
            "wall planar-mirror + sphere distance-multi, map_mirrors={map_mirrors}: {:.2} dB, {sphere:.2} dB on the sphere's {n} pixels",
            psnr(&f.image, &reference)
        );
        on_sphere.push((psnr(&f.image, &reference), sphere));
    }
    let (p_multi, sphere_on) = on_sphere[0];
    let sphere_off = on_sphere[1].1;
    // Measured 46.22 dB (auto) and 31.30 dB: floors 1 dB under auto and under the 14.92 dB
    // margin; on the sphere 19.12 dB with the mirrored views in its maps and 18.23 dB
    // without (only its rim sees the wall): the 0.89 dB gain asserted at half (rule 1).
    assert!(p_auto >= 45.22 && p_auto >= p_multi + 13.92, "auto {p_auto:.2} dB, with distance-multi {p_multi:.2} dB");
    assert!(sphere_on >= sphere_off + 0.445, "on the sphere: {sphere_on:.2} dB with map mirrors, {sphere_off:.2} dB without");

    // MSAA: the views resolve into their layers; against the 16-spp reference it comes
    // nearer than one sample per pixel (the mirror's edges and the reflected edges in it).
    let mut q4 = q.clone();
    q4.set("aa", "msaa4").unwrap();
    let ms = specula::render(&ctx, &s, specula::Choice::Auto, &q4, SIZE, (0, 1)).unwrap();
    assert!(ms.image.data.iter().all(|v| v.is_finite()));
    let smooth = specula::reference::render_reference(
        &s,
        &{
            let mut knobs = q.clone();
            knobs.reference.spp = 16;
            knobs
        },
        SIZE,
    )
    .unwrap();
    let (p_ms, p_one) = (psnr(&ms.image, &smooth), psnr(&auto.image, &smooth));
    println!("against 16 spp: msaa4 {p_ms:.2} dB, one sample {p_one:.2} dB");
    // Measured 35.35 vs 27.01 dB: msaa4's floor and its 8.34 dB margin each 1 dB under.
    assert!(p_ms >= 34.35 && p_ms >= p_one + 7.34, "msaa4 {p_ms:.2} dB vs one sample {p_one:.2} dB");
    common::assert_clean(&ctx);
}

/// A glass slab (solid, flat faces) standing in the emissive room, seen from above at an
/// angle: the room behind and below it is refracted through the top face and out of the
/// bottom and side faces.
fn slab_scene(ior: f32, camera: (Vec3, Vec3)) -> Scene {
    let mut s = room(&[], camera);
    let glass = s
        .add_material(Material {
            name: "glass".into(),
            kind: specula::scene::SurfaceKind::Dielectric { ior, thin: false },
            ..Default::default()
        })
        .unwrap();
    s.add_mesh(shapes::cuboid("slab", Vec3::new(-0.2, -0.9, -0.4), Vec3::new(0.8, 0.25, 0.6), glass)).unwrap();
    s
}

fn glass(s: &mut Scene, ior: f32, thin: bool) -> usize {
    let kind = specula::scene::SurfaceKind::Dielectric { ior, thin };
    s.add_material(Material { name: format!("glass{ior}{}", if thin { " thin" } else { "" }), kind, ..Default::default() }).unwrap()
}

/// PSNR over the pixels where `with` and `without` (the same view without the glass)
/// differ: the glass's own pixels.
fn psnr_on_glass(image: &ImageData, with: &ImageData, without: &ImageData) -> (f64, usize) {
    let (mut se, mut n) = (0.0f64, 0usize);
    for ((a, b), c) in image.data.chunks(4).zip(with.data.chunks(4)).zip(without.data.chunks(4)) {
        if (0..3).any(|k| (b[k] - c[k]).abs() > 1e-4) {
            se += (0..3).map(|k| ((a[k] - b[k]) as f64).powi(2)).sum::<f64>() / 3.0;
            n += 1;
        }
    }
    (10.0 * (n as f64 / se.max(1e-300)).log10(), n)
}

/// A thin-walled pane transmits undeviated and reflects as a mirror: both views are exact,
/// so `planar-refraction` is exact on it, from either side.
#[test]
fn a_thin_pane_is_exact() {
    let ctx = common::gpu();
    for (side, eye) in [("front", Vec3::new(0.9, 0.4, 1.6)), ("back", Vec3::new(-0.75, -0.15, -1.7))] {
        let mut s = room(&[], (eye, Vec3::new(0.0, -0.3, 0.0)));
        let g = glass(&mut s, 1.5, true);
        s.add_mesh(shapes::quad("pane", Vec3::new(-1.0, -1.2, 0.2), Vec3::new(2.0, 0.0, -0.6), Vec3::new(0.0, 2.0, 0.0), 1, g)).unwrap();
        let q = quality(3);
        let plan = specula::plan(&s, specula::methods::PLANAR_REFRACTION, &q);
        assert_eq!(plan.objects[0].method, specula::methods::PLANAR_REFRACTION, "a planar pane is served");
        let reference = specula::reference::render_reference(&s, &q, SIZE).unwrap();
        let f = gpu(&ctx, &s, specula::methods::PLANAR_REFRACTION, &q);
        let p = psnr(&f.image, &reference);
        println!("pane ({side}): {p:.2} dB, {} views", stat(&f, "geometry.mirror_views"));

        assert_eq!(stat(&f, "geometry.mirror_views"), 2.0, "{side}: its transmission and its reflection");
        assert!(p >= 60.0, "{side}: {p:.2} dB");
    }
    // Multisampled and shaded per sample, on the planner corpus's pane (128²): the pane's
    // pixels as the exact tracer's at the same samples. (Positions interpolated at a sample
    // lay ~25 hairs off the pane's plane on lavapipe, and the pane found neither view:
    // measured 11.77 dB here before the plane test allowed for it; 40.04 after.)
    let s = specula::scenes::corpus::scene(10).unwrap();
    let mut ms = quality(3);
    ms.set("aa", "msaa4").unwrap();
    let size = (128, 128);
    let ids = specula::reference::object_ids(&s, size).unwrap();
    let pane = s.meshes.iter().position(|m| m.name == "thin-pane0").unwrap() as u32 + 1;
    let mask: Vec<bool> = ids.iter().map(|&id| id == pane).collect();
    let a = specula::render(&ctx, &s, specula::methods::PLANAR_REFRACTION, &ms, size, (0, 1)).unwrap();
    let b = specula::render(&ctx, &s, specula::methods::BVH, &ms, size, (0, 1)).unwrap();
    let pm = specula::metrics::masked_error(&a.image, &b.image, &mask, "pane").unwrap().unwrap().psnr;
    println!("corpus pane, msaa4: {pm:.2} dB against bvh msaa4 on its pixels");
    assert!(pm >= 39.0, "msaa4: {pm:.2} dB against bvh msaa4");
    common::assert_clean(&ctx);
}

/// The linearised refraction (GS04) against the exact per-pixel refraction, on a glass
/// slab's pixels, as ν and the incidence angle grow; depth 2 (in and out) with a budget
/// large enough that no view falls back, so that what is measured is the linearisation.
#[test]
fn linearised_refraction_error_grows_with_the_index_and_the_incidence() {
    let ctx = common::gpu();
    let centre = Vec3::new(-0.2, -0.9, -0.4);
    let mut q = quality(2);
    q.set("mirror_budget", "64").unwrap();
    let mut table = Vec::new();
    for ior in [1.1f32, 1.5, 2.4] {
        for deg in [0.0f32, 30.0, 60.0, 75.0] {
            // Looking at the slab's centre from 2.4 m at `deg` from its top face's normal
            // (a hair off the normal at 0°, so that the view has an up direction).
            let a = deg.max(0.5).to_radians();
            let eye = centre + 2.4 * Vec3::new(a.sin() * 0.6, a.cos(), a.sin() * 0.8);
            let without = room(&[], (eye, centre));
            let s = slab_scene(ior, (eye, centre));
            let reference = specula::reference::render_reference(&s, &q, SIZE).unwrap();
            let bare = specula::reference::render_reference(&without, &q, SIZE).unwrap();
            let f = gpu(&ctx, &s, specula::methods::PLANAR_REFRACTION, &q);
            assert!(stat(&f, "geometry.mirror_views") < 64.0, "ν {ior}, {deg}°: the budget is not what limits it");
            let (p, n) = psnr_on_glass(&f.image, &reference, &bare);
            let (e, _) = psnr_on_glass(&gpu(&ctx, &s, specula::methods::BVH, &q).image, &reference, &bare);
            println!(
                "ν {ior} at {deg}°: planar-refraction {p:.2} dB on {n} glass pixels ({} views); exact per-pixel (bvh) {e:.2} dB",
                stat(&f, "geometry.mirror_views")
            );
            // The exact per-pixel refraction is exact (rule 2): measured 127.56–129.39 dB.
            assert!(e >= 60.0, "ν {ior} at {deg}°: bvh {e:.2} dB");
            table.push(p);
        }
    }
    // Floors 1 dB under the measured values (rule 1), in the order of the loops.
    let measured = [35.19, 29.36, 24.04, 15.37, 30.99, 21.58, 18.97, 18.23, 27.62, 25.30, 18.49, 19.74];
    for (k, (p, m)) in table.iter().zip(measured).enumerate() {
        assert!(*p >= m - 1.0, "case {k}: {p:.2} dB, measured {m:.2}");
    }
    // Worse with the incidence: 0° → 60° loses 11.15, 12.02 and 9.13 dB at ν 1.1, 1.5, 2.4
    // (at 75° the side faces take over); worse with the index at normal incidence: 4.20
    // and 3.37 dB per step. Each margin 1 dB under its measurement.
    for (i, m) in [11.15, 12.02, 9.13].into_iter().enumerate() {
        assert!(table[4 * i] - table[4 * i + 2] >= m - 1.0, "ν #{i}: {:.2} → {:.2} dB", table[4 * i], table[4 * i + 2]);
        assert!(table[4 * i] > table[4 * i + 1] && table[4 * i + 1] > table[4 * i + 2], "ν #{i}: {:?}", &table[4 * i..4 * i + 3]);
    }
    assert!(table[0] - table[4] >= 3.2 && table[4] - table[8] >= 2.37, "{:?}", [table[0], table[4], table[8]]);
    common::assert_clean(&ctx);
}

/// A triangular prism of ν 1.5 (its 60° corners reflect totally inside) and 2.4, at depth
/// 4: against the reference, and against the budget — the views it renders are capped, the
/// error of what falls back is stated, and budget 0 renders no view at all.
#[test]
fn a_prism_within_the_budget() {
    let ctx = common::gpu();
    let corners = [Vec3::new(0.0, 0.55, 0.0), Vec3::new(-0.48, -0.28, 0.0), Vec3::new(0.48, -0.28, 0.0)];
    let cam = (Vec3::new(0.7, 0.1, 1.6), Vec3::new(-0.1, -0.6, -0.5));
    for ior in [1.5f32, 2.4] {
        let mut s = room(&[], cam);
        let g = glass(&mut s, ior, false);
        let axis = Vec3::new(0.3, 0.0, 1.0).normalize();
        s.add_mesh(shapes::prism("prism", Vec3::new(-0.1, -0.6, -0.5), axis, 1.2, corners.map(|c| c + Vec3::ZERO), g)).unwrap();
        let facts = specula::plan::facts::SceneFacts::new(&s, &quality(4), false);
        let facts = &facts.objects[0];
        assert!(facts.faceted && facts.watertight, "{facts:?}");
        let mut rows = Vec::new();
        let mut fallback_pixels = Vec::new();
        // The reference does not depend on the budget: one per ν.
        let reference = specula::reference::render_reference(&s, &quality(4), SIZE).unwrap();
        for budget in [0u32, 2, 4, 8, 16, 64] {
            let mut q = quality(4);
            q.set("mirror_budget", &budget.to_string()).unwrap();
            let f = gpu(&ctx, &s, specula::methods::PLANAR_REFRACTION, &q);
            let p = psnr(&f.image, &reference);
            // Budget 0 plans no view layer at all (and reports none).
            let views = if budget == 0 { 0.0 } else { stat(&f, "geometry.mirror_views") };
            // Only the fallback pixels' counters (the prism's maps serve every face).
            let counters = |n: &str| n.starts_with("geometry.fallback_pixels");
            if budget == 0 {
                assert!(f.stats.iter().all(|(n, _)| !n.starts_with("geometry.") || counters(n)), "{:?}", f.stats);
                assert!(f.memory.iter().all(|(n, _)| !n.starts_with("geometry.") || counters(n)), "{:?}", f.memory);
            }
            let fell_back = f.stats.iter().find(|(n, _)| n == "geometry.fallback_pixels.prism").map_or(0.0, |s| s.1);
            println!(
                "prism ν {ior}, budget {budget}: {p:.2} dB, {views} views, {} fallbacks, {fell_back} fallback pixels",
                if budget == 0 { 0.0 } else { stat(&f, "geometry.mirror_fallbacks") }
            );
            assert!(views <= budget as f64, "budget {budget}: {views} views");
            rows.push((budget, p, views));
            fallback_pixels.push(fell_back);
        }
        // The frame counts the image's pixels with a branch the budget cut
        // (`geometry.fallback_pixels`): at budget 0 every pixel of the prism, fewer as views
        // are spent on them (measured 248, 248, 248, 213, 213, 25 at ν 1.5 for budgets 0–64).
        println!("prism ν {ior}: fallback pixels by budget {fallback_pixels:?}");
        assert!(fallback_pixels[0] > 0.0 && fallback_pixels.windows(2).all(|w| w[1] <= w[0]), "{fallback_pixels:?}");
        // Budget 0: no view; every face seen falls back to the prism's own maps (the plan gives
        // it a distance and a refractor map where the budget can cut its views): refractor-map's
        // shading.
        assert_eq!(rows[0].2, 0.0);
        let (p0, p2, p4, p8, p16, p64) = (rows[0].1, rows[1].1, rows[2].1, rows[3].1, rows[4].1, rows[5].1);
        println!("prism ν {ior}: gain per budget step {:.2}, {:.2}, {:.2} dB", p4 - p0, p16 - p4, p64 - p16);
        let refractor = psnr(&gpu(&ctx, &s, specula::methods::REFRACTOR_MAP, &quality(4)).image, &reference);
        println!("prism ν {ior}: refractor-map {refractor:.2} dB");
        // Measured (ν 1.5 | 2.4): 20.41 | 20.30 dB with no view (every face refractor-map's
        // shading, 0.06 dB under refractor-map itself), 23.10 | 24.22 with 2, 27.73 | 27.99
        // with 4, 27.60 | 27.47 with 8 (a deeper view's linearisation for a fallback), 31.31 | 29.38
        // with 16, 32.56 | 32.41 with 64 (the views at the depth end where the reference's paths
        // end); refractor-map 20.47 | 20.36. With the environment
        // as the fallback (black here) they were 14.57 | 15.19, 18.70 | 19.29, 29.60 | 28.83
        // and 32.57 | 32.39. Floors and gains 1 dB under (rule 1); from 2 views on never
        // below refractor-map (issue 33: budgets 2, 4, 8), with none within 0.5 dB of it.
        let m = if ior < 2.0 { [20.41, 27.73, 31.31, 32.56, 20.47] } else { [20.30, 27.99, 29.38, 32.41, 20.36] };
        for (p, m) in [p0, p4, p16, p64].iter().zip(m) {
            assert!(*p >= m - 1.0, "ν {ior}: {p:.2} dB, measured {m:.2}");
        }
        for (k, w) in [p0, p4, p16, p64].windows(2).enumerate() {
            let gain = m[k + 1] - m[k];
            assert!(w[1] - w[0] >= gain - 1.0, "ν {ior}: step {k} gains {:.2} dB, measured {gain:.2}", w[1] - w[0]);
        }
        assert!(p64 - refractor >= m[3] - m[4] - 1.0, "ν {ior}: {p64:.2} vs refractor-map {refractor:.2} dB");
        assert!(p0 >= refractor - 0.5, "ν {ior}: no view {p0:.2} dB vs refractor-map {refractor:.2} dB");
        for (budget, p) in [(2, p2), (4, p4), (8, p8), (16, p16), (64, p64)] {
            assert!(p >= refractor, "ν {ior}, budget {budget}: {p:.2} dB below refractor-map's {refractor:.2} dB");
        }
    }
    common::assert_clean(&ctx);
}

/// Extremes: the camera in the slab's top face's plane, ν almost 1 (the slab vanishes), a
/// zero-area triangle in the mesh, 1 mm and 1 km scenes, and a curved solid (not served:
/// its fallback, or refused by name).
#[test]
fn planar_refraction_at_the_extremes() {
    let ctx = common::gpu();
    let centre = Vec3::new(-0.2, -0.9, -0.4);
    let mut q = quality(3);
    q.set("mirror_budget", "64").unwrap();
    // In the top face's plane (y = −0.65), looking along it.
    let s = slab_scene(1.5, (Vec3::new(1.5, -0.65, 1.2), centre));
    let f = gpu(&ctx, &s, specula::methods::PLANAR_REFRACTION, &q);
    let reference = specula::reference::render_reference(&s, &q, SIZE).unwrap();
    let p = psnr(&f.image, &reference);
    println!("edge-on: {p:.2} dB, {} views", stat(&f, "geometry.mirror_views"));
    assert!(f.image.data.iter().all(|v| v.is_finite()));
    // Measured 24.77 dB (the top face is invisible; the others are seen obliquely).
    assert!(p >= 23.77, "edge-on: {p:.2} dB");

    // ν = 1.0001: the slab all but vanishes.
    let cam = (Vec3::new(1.2, 0.0, 1.6), centre);
    let s = slab_scene(1.0001, cam);
    let bare = specula::reference::render_reference(&room(&[], cam), &q, SIZE).unwrap();
    let f = gpu(&ctx, &s, specula::methods::PLANAR_REFRACTION, &q);
    let p = psnr(&f.image, &bare);
    println!("ν 1.0001: {p:.2} dB against the room without it, {} views", stat(&f, "geometry.mirror_views"));
    // Measured 51.69 dB (what remains: views the budget left out, at the slab's edges).
    assert!(p >= 50.69, "ν 1.0001: {p:.2} dB");

    // A zero-area triangle does not make the slab curved, and changes nothing.
    let base = slab_scene(1.5, cam);
    let mut s = base.clone();
    let slab = s.meshes.iter_mut().find(|m| m.name == "slab").unwrap();
    let i = slab.positions.len() as u32;
    slab.positions.extend([Vec3::new(0.6, -0.65, 0.2), Vec3::new(0.6, -0.65, 0.2), Vec3::new(0.0, -0.65, 0.2)]);
    slab.normals.extend([Vec3::Y; 3]);
    slab.uvs.extend([glam::Vec2::ZERO; 3]);
    slab.indices.extend([i, i + 1, i + 2]);
    let one = gpu(&ctx, &base, specula::methods::PLANAR_REFRACTION, &q);
    let degenerate = gpu(&ctx, &s, specula::methods::PLANAR_REFRACTION, &q);
    let plan = specula::plan(&s, specula::methods::PLANAR_REFRACTION, &q);
    assert_eq!(plan.objects[0].method, specula::methods::PLANAR_REFRACTION, "{}", plan.objects[0].reason);
    let p = psnr(&degenerate.image, &one.image);
    println!("zero-area triangle: {p:.2} dB against the slab without it");
    assert!(p >= 60.0, "{p:.2} dB");

    // 1 mm and 1 km: the same image (the linearised maps and the clip offsets are relative).
    for k in [1e-3f32, 1e3] {
        let f = gpu(&ctx, &common::scaled(&base, k), specula::methods::PLANAR_REFRACTION, &q);
        let p = psnr(&f.image, &one.image);
        println!("scale {k:e}: {p:.2} dB against scale 1, {} views", stat(&f, "geometry.mirror_views"));
        assert_eq!(stat(&f, "geometry.mirror_views"), stat(&one, "geometry.mirror_views"), "scale {k:e}");
        // Measured 96.53 dB (1 mm) and 96.02 dB (1 km): the same image up to rounding.
        assert!(p >= 60.0, "scale {k:e}: {p:.2} dB");
    }

    // A glass sphere is curved: the whole-scene choice falls back, the object's choice is
    // refused by name.
    let mut s = room(&[], cam);
    let g = glass(&mut s, 1.5, false);
    s.add_mesh(shapes::uv_sphere("ball of glass", centre, 0.4, 16, 8, g)).unwrap();
    let plan = specula::plan(&s, specula::methods::PLANAR_REFRACTION, &q);
    let o = plan.objects.iter().find(|o| o.name == "ball of glass").unwrap();
    assert_eq!(o.method, specula::methods::DISTANCE, "{}", o.reason);
    assert!(o.reason.contains("curved"), "{}", o.reason);
    let choices = specula::plan::Choices {
        method: specula::Choice::Auto,
        objects: vec![("ball of glass".into(), specula::methods::PLANAR_REFRACTION)],
    };
    let e = specula::plan::plan_with(&s, &choices, &q).unwrap_err().to_string();
    assert!(e.contains("'ball of glass'") && e.contains("flat-faced"), "{e}");
    common::assert_clean(&ctx);
}

/// A mirror wall behind the camera, seen only in the spheres before it (issue 11 item 2):
/// each sphere's cube map draws the wall by its mirrored view per face, so a mirror sphere
/// (distance) and a glass sphere (refractor-map) show the wall's reflection of the room
/// and of themselves. On the spheres' pixels, against the reference, with and without
/// (map_mirrors=off: the wall reflects the environment only, black here); bvh is exact.
#[test]
fn spheres_see_a_mirror_wall_in_their_maps() {
    let ctx = common::gpu();
    let wall = (Vec3::new(-1.8, -1.8, 1.9), Vec3::new(0.0, 3.6, 0.0), Vec3::new(3.6, 0.0, 0.0));
    let mut s = room(&[wall], (Vec3::new(0.2, 0.1, 0.6), Vec3::new(-0.1, -0.2, -1.0)));
    let m = s.add_material(common::mirror(0.9)).unwrap();
    s.add_mesh(shapes::uv_sphere("sphere", Vec3::new(-0.45, -0.2, -0.9), 0.4, 32, 16, m)).unwrap();
    let g = glass(&mut s, 1.5, false);
    s.add_mesh(shapes::uv_sphere("glass", Vec3::new(0.5, -0.3, -0.8), 0.35, 32, 16, g)).unwrap();
    let q = quality(4);
    let reference = specula::reference::render_reference(&s, &q, SIZE).unwrap();
    let bare = {
        let mut w = s.clone();
        w.meshes.retain(|m| m.name != "sphere" && m.name != "glass");
        specula::reference::render_reference(&w, &q, SIZE).unwrap()
    };
    let choices = specula::plan::Choices {
        method: specula::Choice::Auto,
        objects: vec![
            ("mirror0".into(), specula::methods::PLANAR_MIRROR),
            ("sphere".into(), specula::methods::DISTANCE),
            ("glass".into(), specula::methods::REFRACTOR_MAP),
        ],
    };
    let mut rows = Vec::new();
    for map_mirrors in ["on", "off"] {
        let mut qm = q.clone();
        qm.set("map_mirrors", map_mirrors).unwrap();
        let plan = specula::plan::plan_with(&s, &choices, &qm).unwrap();
        let mut r = specula::Renderer::new(&ctx, &s, plan, SIZE.0, SIZE.1).unwrap();
        let f = r.render(&ctx).unwrap();
        r.destroy(&ctx);
        let (p, n) = psnr_on_glass(&f.image, &reference, &bare);
        let draws: f64 = f.stats.iter().filter(|(k, _)| k.starts_with("distance.generate.draws")).map(|(_, v)| v).sum();
        println!("map_mirrors={map_mirrors}: {p:.2} dB on the spheres' {n} pixels, {draws} distance-map draws, {:.1} ms", f.gpu_ms());
        rows.push((p, draws));
    }
    let exact = psnr_on_glass(&gpu(&ctx, &s, specula::methods::BVH, &q).image, &reference, &bare).0;
    println!("bvh: {exact:.2} dB on the spheres");
    // Layered maps (§4.5) keep the whole scene, the wall included, and trace the wall's
    // reflection in their own layers: no mirrored view needed there.
    let layered = psnr_on_glass(&gpu(&ctx, &s, specula::methods::LAYERED, &q).image, &reference, &bare).0;
    println!("layered: {layered:.2} dB on the spheres");
    // Measured 22.31 dB with the mirrored views in the maps, 19.33 dB without (the wall
    // black in them): the floor and the 2.98 dB gain 1 dB under (rule 1). The cost: 324
    // mesh draws into the distance maps against 216 (each face that sees the wall draws the
    // scene again), only when the maps are redrawn. bvh is exact (114.27 dB; rule 2).
    let ((on, draws_on), (off, draws_off)) = (rows[0], rows[1]);
    assert!(on >= 21.31 && on >= off + 1.98, "{on:.2} dB with, {off:.2} dB without");
    assert!(draws_on > draws_off, "{draws_on} vs {draws_off} draws");
    assert!(exact >= 60.0, "bvh {exact:.2} dB");
    // Layered: measured 20.03 dB (its sphere shows the wall and the room in it, with the
    // search's own error); floor 1 dB under.
    assert!(layered >= 19.03, "layered {layered:.2} dB");
    common::assert_clean(&ctx);
}
