//! Curved reflectors by geometry transformation (survey §5, EMD*05/EMDT06):
//! `curved-reflector` on a convex mirror sphere and a concave bowl against the exact CPU
//! reference and against distance maps on the same scenes; a saddle-shaped reflector
//! refused as unsupported; the knobs' effect; 1 mm and 1 km scales.

mod common;

use glam::{Vec2, Vec3};
use specula::image::ImageData;
use specula::scene::{shapes, Camera, Material, Mesh, Scene};
use specula::{Method, Quality};

const SIZE: (u32, u32) = (64, 48);

/// The emissive quadrant room (half-size 2 m, no lights) with an emissive ball, and
/// `reflector` (made of mirror material F0 0.9), seen from `camera`.
fn room(reflector: impl FnOnce(usize) -> Mesh, camera: (Vec3, Vec3)) -> Scene {
    let mut s = Scene::new();
    common::emissive_room(&mut s, Vec3::ZERO, 2.0);
    let ball = s
        .add_material(Material { name: "ball".into(), base_color: Vec3::ZERO, emissive: Vec3::new(1.5, 0.8, 0.2), ..Default::default() })
        .unwrap();
    s.add_mesh(shapes::uv_sphere("ball", Vec3::new(0.9, -1.2, 0.9), 0.3, 24, 12, ball)).unwrap();
    let m = s.add_material(common::mirror(0.9)).unwrap();
    s.add_mesh(reflector(m)).unwrap();
    s.camera = Some(Camera::look_at(camera.0, camera.1, 50f32.to_radians()));
    s
}

/// A convex mirror sphere of radius 0.6 m, its UV seam (u = 0, towards +x) away from the camera.
fn sphere_scene() -> Scene {
    room(|m| shapes::uv_sphere("sphere", Vec3::new(0.0, -0.3, 0.0), 0.6, 48, 24, m), (Vec3::new(-1.6, 0.4, 0.9), Vec3::new(0.0, -0.3, 0.0)))
}

/// A spherical cap of radius `r` around `centre + r·(0, 1, 0)`'s downward direction: the
/// inside of a bowl of half-angle `angle`, normals towards the sphere's centre, an n×n grid
/// with its own UVs.
fn bowl(name: &str, centre: Vec3, r: f32, angle: f32, n: u32, material: usize) -> Mesh {
    let mut m = Mesh { name: name.into(), material, ..Default::default() };
    for i in 0..=n {
        for j in 0..=n {
            let (u, v) = (i as f32 / n as f32 * 2.0 - 1.0, j as f32 / n as f32 * 2.0 - 1.0);
            // An azimuthal grid: (u, v) in the unit square mapped to the cap by angle.
            let d = Vec3::new((u * angle).sin(), -(u * angle).cos() * (v * angle).cos(), (v * angle).sin() * (u * angle).cos());
            let d = d.normalize();
            m.positions.push(centre + d * r);
            m.normals.push(-d);
            m.uvs.push(Vec2::new(0.5 + 0.5 * u, 0.5 + 0.5 * v));
        }
    }
    let at = |i: u32, j: u32| i * (n + 1) + j;
    for i in 0..n {
        for j in 0..n {
            m.indices.extend([at(i, j), at(i + 1, j), at(i, j + 1), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    m
}

/// A concave bowl (radius 1.6 m, half-angle 40°) on the floor, seen from above.
fn bowl_scene() -> Scene {
    room(
        |m| bowl("bowl", Vec3::new(0.0, -0.2, 0.0), 1.6, 30f32.to_radians(), 24, m),
        (Vec3::new(-1.2, 1.2, 1.4), Vec3::new(0.0, -1.5, 0.0)),
    )
}

fn quality() -> Quality {
    let mut q = {
        let mut knobs = Quality::default();
        knobs.frame.depth = 1;
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

fn stat(f: &specula::Frame, name: &str) -> f64 {
    f.stats.iter().find(|(n, _)| n == name).map_or(f64::NAN, |(_, v)| *v)
}

/// Writes the GPU image, distance maps' and the reference side by side when
/// `SPECULA_TEST_IMAGES` names a folder (for looking at a failure).
fn keep(name: &str, images: &[&ImageData]) {
    if let Some(dir) = std::env::var_os("SPECULA_TEST_IMAGES") {
        let dir = std::path::Path::new(&dir);
        std::fs::create_dir_all(dir).unwrap();
        montage(images, 4).write_png_srgb(&dir.join(format!("curved_{name}.png"))).unwrap();
    }
}

/// Environment vertices at tessellation `t`: every triangle of every object becomes a grid
/// of (t + 1)(t + 2)/2 vertices.
fn environment_vertices(s: &Scene, t: u32) -> f64 {
    s.meshes.iter().map(|m| m.triangle_count() as f64 * ((t + 1) * (t + 2) / 2) as f64).sum()
}

#[test]
fn a_convex_mirror_sphere() {
    let ctx = common::gpu();
    let s = sphere_scene();
    let q = quality();
    let plan = specula::plan(&s, specula::methods::CURVED_REFLECTOR, &q);
    let o = plan.objects.iter().find(|o| o.name == "sphere").unwrap();
    assert_eq!(o.method, specula::methods::CURVED_REFLECTOR, "{}", o.reason);
    let reference = specula::reference::render_reference(&s, &q, SIZE).unwrap();
    let f = gpu(&ctx, &s, specula::methods::CURVED_REFLECTOR, &q);
    let d = gpu(&ctx, &s, specula::methods::DISTANCE, &q);
    let (p, pd) = (psnr(&f.image, &reference), psnr(&d.image, &reference));
    keep("sphere", &[&f.image, &d.image, &reference]);
    println!("sphere: curved-reflector {p:.2} dB, distance {pd:.2} dB against the reference");
    let names: Vec<&str> = f.passes.iter().map(|p| p.name.as_str()).collect();
    for pass in ["geometry.image", "geometry.virtual.search", "geometry.virtual", "geometry.curved"] {
        assert!(names.contains(&pass), "{pass} missing: {names:?}");
    }
    // Rule 1: measured 36.80 dB; distance maps 33.66 dB on the same scene (margin 3.14 dB).
    assert!(p >= 35.80, "curved-reflector {p:.2} dB");
    assert!(p >= pd + 2.14, "curved-reflector {p:.2} dB vs distance {pd:.2} dB");
    // Every vertex of every object is searched (O(S·D), survey Table 1): at the default
    // tessellation 4, 15 vertices per triangle.
    assert_eq!(stat(&f, "geometry.curved_vertices"), environment_vertices(&s, 4));
    // Memory per geometry image (positions + normals, RGBA32F, 128²) and per view (one
    // RGBA32F virtual image per reflector, one D32 depth buffer); the allocator agrees.
    let (image, view, depth) =
        (stat(&f, "geometry.curved_image_bytes"), stat(&f, "geometry.curved_view_bytes"), stat(&f, "geometry.curved_depth_bytes"));
    let pixels = (SIZE.0 * SIZE.1) as f64;
    assert_eq!((image, view, depth), (2.0 * 128.0 * 128.0 * 16.0, 16.0 * pixels, 4.0 * pixels));
    let allocated = |name: &str| f.memory.iter().filter(|(n, _)| n == name).map(|(_, b)| *b as f64).sum::<f64>();
    assert!(allocated("geometry.image.positions") + allocated("geometry.image.normals") >= image, "{:?}", f.memory);
    assert!(allocated("geometry.virtual_images") >= view && allocated("geometry.virtual_depth") >= depth, "{:?}", f.memory);
    assert_eq!(stat(&f, "geometry.curved_projected"), 0.0, "the sphere's own UVs parameterise it");
    // A convex reflector has one reflection point per vertex: none of the checked vertices
    // (every 16th) finds a second.
    println!(
        "sphere: {} of {} checked vertices with several minima",
        stat(&f, "geometry.curved_multiple_minima"),
        stat(&f, "geometry.curved_checked")
    );
    assert_eq!(stat(&f, "geometry.curved_checked"), (environment_vertices(&s, 4) / 16.0).ceil());
    assert_eq!(stat(&f, "geometry.curved_multiple_minima"), 0.0);
    // None of it for distance maps.
    assert!(d.memory.iter().all(|(n, _)| !n.starts_with("geometry.")), "{:?}", d.memory);
    // Its UVs removed (all zero): a closed surface, which a plane's projection would fold onto itself
    // (front and back on one texel), is charted by the cube atlas around its centre.
    let mut bare = s.clone();
    bare.meshes.iter_mut().filter(|m| m.name == "sphere").for_each(|m| m.uvs = vec![Vec2::ZERO; m.positions.len()]);
    let g = gpu(&ctx, &bare, specula::methods::CURVED_REFLECTOR, &q);
    let pg = psnr(&g.image, &reference);
    println!("sphere without UVs: {pg:.2} dB (own UVs {p:.2}, distance {pd:.2})");
    assert_eq!(stat(&g, "geometry.curved_projected"), 1.0);
    assert_eq!(stat(&g, "geometry.curved_multiple_minima"), 0.0);
    // Measured 35.11 dB (20.62 with the plane's projection), distance maps 33.66: floor and
    // margin 1 dB under (rule 1).
    assert!(pg >= 34.11 && pg >= pd + 0.45, "closed, without UVs: {pg:.2} dB vs distance {pd:.2} dB");
    common::assert_clean(&ctx);
}

#[test]
fn a_concave_bowl() {
    let ctx = common::gpu();
    let s = bowl_scene();
    let q = quality();
    let facts = specula::plan::facts::SceneFacts::new(&s, &q, false);
    assert_eq!(facts.objects[0].curvature, specula::plan::facts::Curvature::Concave);
    let reference = specula::reference::render_reference(&s, &q, SIZE).unwrap();
    let f = gpu(&ctx, &s, specula::methods::CURVED_REFLECTOR, &q);
    let d = gpu(&ctx, &s, specula::methods::DISTANCE, &q);
    let (p, pd) = (psnr(&f.image, &reference), psnr(&d.image, &reference));
    keep("bowl", &[&f.image, &d.image, &reference]);
    println!("bowl: curved-reflector {p:.2} dB, distance {pd:.2} dB against the reference");
    println!(
        "bowl: {} of {} checked vertices with several minima",
        stat(&f, "geometry.curved_multiple_minima"),
        stat(&f, "geometry.curved_checked")
    );
    assert_eq!(stat(&f, "geometry.curved_multiple_minima"), 0.0, "a concave cap: one reflection point each");
    // Rule 1: measured 32.25 dB; distance maps 32.62 dB (a shallow bowl whose reference point
    // sees the whole room: distance maps do as well here).
    assert!(p >= 31.25, "curved-reflector {p:.2} dB");
    assert!(p >= pd - 1.37, "curved-reflector {p:.2} dB vs distance {pd:.2} dB (measured 0.37 dB under)");
    // Its UVs removed: the planar projection along its mean normal parameterises it as well.
    let mut bare = s.clone();
    bare.meshes.iter_mut().filter(|m| m.name == "bowl").for_each(|m| m.uvs = vec![Vec2::ZERO; m.positions.len()]);
    let g = gpu(&ctx, &bare, specula::methods::CURVED_REFLECTOR, &q);
    let pg = psnr(&g.image, &reference);
    println!("bowl without UVs: {pg:.2} dB");
    assert_eq!(stat(&g, "geometry.curved_projected"), 1.0);
    assert!(pg >= p - 1.0, "projected {pg:.2} dB vs own UVs {p:.2} dB");
    common::assert_clean(&ctx);
}

/// A saddle z = k(x² − y²) over a square of half-size `half` around `centre` (normals up),
/// an n×n grid.
fn saddle(centre: Vec3, half: f32, k: f32, n: u32, material: usize) -> Mesh {
    let mut m = shapes::quad("saddle", Vec3::ZERO, Vec3::new(2.0 * half, 0.0, 0.0), Vec3::new(0.0, 0.0, 2.0 * half), n, material);
    for (p, nn) in m.positions.iter_mut().zip(m.normals.iter_mut()) {
        let (x, z) = (p.x - half, p.z - half);
        *p = centre + Vec3::new(x, k * (x * x - z * z), z);
        *nn = Vec3::new(-2.0 * k * x, 1.0, 2.0 * k * z).normalize();
    }
    m
}

/// A saddle-shaped mirror has several reflection points for one vertex (survey §5): the
/// planner's convexity test reports it as unsupported, by name when it is asked for the
/// object, and gives it the fallback (distance maps) when it is asked for the whole scene;
/// the frame then has no geometry-transformation pass and renders what distance maps render.
#[test]
fn a_saddle_is_reported_unsupported() {
    let ctx = common::gpu();
    let s = room(|m| saddle(Vec3::new(0.0, -1.2, 0.0), 0.8, 0.6, 16, m), (Vec3::new(-1.2, 1.0, 1.4), Vec3::new(0.0, -1.2, 0.0)));
    let q = quality();
    let facts = specula::plan::facts::SceneFacts::new(&s, &q, false);
    assert_eq!(facts.objects[0].curvature, specula::plan::facts::Curvature::Saddle);
    let choices =
        specula::plan::Choices { method: specula::Choice::Auto, objects: vec![("saddle".into(), specula::methods::CURVED_REFLECTOR)] };
    let e = specula::plan::plan_with(&s, &choices, &q).unwrap_err().to_string();
    println!("{e}");
    assert!(e.contains("'saddle'") && e.contains("saddle-shaped") && e.contains("unsupported"), "{e}");
    let plan = specula::plan(&s, specula::methods::CURVED_REFLECTOR, &q);
    let o = &plan.objects[0];
    println!("{}: {}", o.method, o.reason);
    assert_eq!(o.method, specula::methods::DISTANCE);
    assert!(o.reason.contains("saddle-shaped") && o.reason.contains("unsupported"), "{}", o.reason);
    assert_ne!(specula::plan(&s, specula::Choice::Auto, &q).objects[0].method, specula::methods::CURVED_REFLECTOR);
    let f = gpu(&ctx, &s, specula::methods::CURVED_REFLECTOR, &q);
    assert!(f.passes.iter().all(|p| !p.name.starts_with("geometry.")), "{:?}", f.passes);
    assert!(f.image == gpu(&ctx, &s, specula::methods::DISTANCE, &q).image, "the fallback's image");
    common::assert_clean(&ctx);
}

/// The accuracy knobs: the geometry image's size (the reflection points' sampling) and the
/// environment's tessellation (survey Table 1: "high tessellation"), each against the
/// reference on the sphere, and the coarse-to-fine search against the exhaustive one.
#[test]
fn error_against_geometry_image_size_and_tessellation() {
    let ctx = common::gpu();
    let s = sphere_scene();
    let base = quality();
    let reference = specula::reference::render_reference(&s, &base, SIZE).unwrap();
    let run = |knobs: &[(&str, &str)]| {
        let mut q = base.clone();
        for (k, v) in knobs {
            q.set(k, v).unwrap();
        }
        let f = gpu(&ctx, &s, specula::methods::CURVED_REFLECTOR, &q);
        let search = f.passes.iter().filter(|p| p.name == "geometry.virtual.search").map(|p| p.gpu_ms).sum::<f64>();
        (psnr(&f.image, &reference), stat(&f, "geometry.curved_vertices"), search)
    };
    // Rule 1 and the ordering rule: each floor 1 dB under its measured PSNR, each step's gain
    // bounded within 1 dB of its measured gain (half of it under 1 dB). Measured 33.25,
    // 36.47, 36.80 and 36.80 dB: from 128² on the sub-texel refinement has converged.
    let mut last = f64::NAN;
    for (size, measured, gain) in [("32", 33.25, f64::NAN), ("64", 36.47, 2.22), ("128", 36.80, 0.16), ("256", 36.80, -0.05)] {
        let (p, _, ms) = run(&[("geometry_image", size)]);
        println!("geometry_image {size}: {p:.3} dB, search {ms:.1} ms");
        assert!(p >= measured - 1.0, "geometry_image {size}: {p:.2} dB (measured {measured})");
        assert!(last.is_nan() || p >= last + gain, "geometry_image {size}: {p:.3} dB after {last:.3} dB");
        last = p;
    }
    // Survey Table 1's "high tessellation": measured 29.79, 34.46, 36.80 and 37.50 dB at 1,
    // 2, 4 and 8 (gains 4.67, 2.34 and 0.70 dB). Every vertex is searched: (t + 1)(t + 2)/2
    // per triangle, the search's work (O(S·D)); its time per vertex was 2.3–3.0 µs at each t
    // (BENCHMARKS.md).
    let mut last = f64::NAN;
    for (t, measured, gain) in [(1u32, 29.79, f64::NAN), (2, 34.46, 3.67), (4, 36.80, 1.34), (8, 37.50, 0.35)] {
        let (p, v, ms) = run(&[("tessellation", &t.to_string())]);
        println!("tessellation {t}: {p:.2} dB, {v} vertices, search {ms:.1} ms ({:.2} µs per vertex)", 1e3 * ms / v);
        assert_eq!(v, environment_vertices(&s, t));
        assert!(p >= measured - 1.0, "tessellation {t}: {p:.2} dB (measured {measured})");
        assert!(last.is_nan() || p >= last + gain, "tessellation {t}: {p:.2} dB after {last:.2} dB");
        last = p;
    }
    // The coarse-to-fine search finds what the exhaustive one finds (measured 34.46 dB at
    // every level count, tessellation 2) at a fraction of its time (1215, 103, 42 and 30 ms
    // at 0, 2, 3 and 5 levels).
    let (exhaustive, _, _) = run(&[("curved_search", "0"), ("tessellation", "2")]);
    for levels in ["2", "3", "5"] {
        let (p, _, ms) = run(&[("curved_search", levels), ("tessellation", "2")]);
        println!("curved_search {levels}: {p:.3} dB (exhaustive {exhaustive:.3} dB), search {ms:.1} ms");
        assert!(p >= exhaustive - 0.05, "curved_search {levels}: {p:.3} dB vs exhaustive {exhaustive:.3} dB");
    }
    common::assert_clean(&ctx);
}

/// The sphere's scene at 1 mm and 1 km: the same image as at 1 m (the search compares
/// directions and the virtual depth is relative).
#[test]
fn curved_reflectors_at_a_millimetre_and_a_kilometre() {
    let ctx = common::gpu();
    let base = sphere_scene();
    let q = quality();
    let one = gpu(&ctx, &base, specula::methods::CURVED_REFLECTOR, &q).image;
    for scale in [1e-3f32, 1e3] {
        let s = common::scaled(&base, scale);
        let f = gpu(&ctx, &s, specula::methods::CURVED_REFLECTOR, &q);
        let p = psnr(&f.image, &one);
        let differ =
            f.image.data.chunks_exact(4).zip(one.data.chunks_exact(4)).filter(|(a, b)| (0..3).any(|c| (a[c] - b[c]).abs() > 1e-3)).count();
        println!("scale {scale:e}: {p:.2} dB against scale 1, {differ} pixels differ");
        // Rule 2: measured 117.26 dB (1 mm) and 46.67 dB (1 km: one silhouette pixel whose
        // virtual triangle is kept at one scale and dropped at the other, 0.43 apart).
        let floor = if scale < 1.0 { 60.0 } else { 26.67 };
        assert!(p >= floor && differ <= 1, "scale {scale:e}: {p:.2} dB, {differ} pixels differ");
        keep(&format!("scale{scale:e}"), &[&f.image, &one]);
        assert!(f.image.data.iter().all(|v| v.is_finite()), "scale {scale:e}");
    }
    common::assert_clean(&ctx);
}

/// A mirror sphere in a long hall (the quadrant room stretched 8× along x): deep, but
/// tessellated coarsely as seen from the sphere.
fn hall_scene() -> Scene {
    let mut s = Scene::new();
    common::emissive_room(&mut s, Vec3::ZERO, 2.0);
    for m in &mut s.meshes {
        m.positions.iter_mut().for_each(|p| p.x *= 8.0);
    }
    let m = s.add_material(common::mirror(0.9)).unwrap();
    s.add_mesh(shapes::uv_sphere("sphere", Vec3::new(0.0, -0.4, 0.0), 0.6, 48, 24, m)).unwrap();
    s.camera = Some(Camera::look_at(Vec3::new(-2.5, 0.3, 1.2), Vec3::new(0.0, -0.4, 0.0), 50f32.to_radians()));
    s
}

/// The sphere's room with two more emissive balls close to the mirror: surfaces 0.25 m
/// and 2 m from it, an environment of large depth variation.
fn cluttered_scene() -> Scene {
    let mut s = sphere_scene();
    for (i, (c, e)) in
        [(Vec3::new(-0.2, 0.1, 1.05), Vec3::new(0.2, 1.2, 0.4)), (Vec3::new(-0.9, -0.9, -0.4), Vec3::new(1.2, 0.3, 1.0))].iter().enumerate()
    {
        let m = s.add_material(Material { name: format!("near{i}"), base_color: Vec3::ZERO, emissive: *e, ..Default::default() }).unwrap();
        s.add_mesh(shapes::uv_sphere(&format!("near{i}"), *c, 0.2, 24, 12, m)).unwrap();
    }
    s
}

/// Curved-reflector on a convex mirror in an environment of large depth variation that is
/// tessellated finely as seen from it (two balls close to the sphere) measures better than
/// distance maps and the proxy box; in a long hall, deep but coarse, worse. The measuring
/// planner's choice (knobs included) is at least as accurate as all three (with their
/// default knobs or multisampled) in the first, and is not curved-reflector in the second.
#[test]
fn curved_reflector_wins_in_a_deep_finely_tessellated_environment_and_auto_is_no_worse() {
    let ctx = common::gpu();
    let q = quality();
    let s = cluttered_scene();
    let facts = specula::plan::facts::SceneFacts::new(&s, &q, true);
    let f = facts.objects.iter().find(|o| s.meshes[o.mesh].name == "sphere").unwrap();
    println!("cluttered: depth ratio {:.2}, box fraction {:.3}, edge angle {:.3}", f.depth_ratio, f.box_fraction, f.edge_angle);
    let plan = specula::plan(&s, specula::Choice::Auto, &q);
    let o = plan.objects.iter().find(|o| o.name == "sphere").unwrap();
    println!("auto: {} ({})", o.method, o.reason);
    let reference = specula::reference::render_reference(&s, &q, SIZE).unwrap();
    let images =
        [specula::methods::CURVED_REFLECTOR, specula::methods::DISTANCE, specula::methods::PROXY_BOX].map(|m| gpu(&ctx, &s, m, &q).image);
    let [curved, distance, proxy] = images.each_ref().map(|i| psnr(i, &reference));
    println!("cluttered: curved-reflector {curved:.2}, distance {distance:.2} dB, proxy-box {proxy:.2} dB");
    // Measured 36.80, 29.55 and 26.08 dB (margins 7.25 and 10.72 dB).
    assert!(curved >= 35.80 && curved >= distance + 6.25 && curved >= proxy + 9.72, "curved-reflector {curved:.2} dB");

    // Auto against the anti-aliased reference its models predict (16 samples a pixel), on
    // the sphere's pixels (what it chooses by; anti-aliasing also smooths the diffuse balls'
    // edges, which no choice for the sphere is judged on): it may take knobs, so each of the
    // three is measured with its default knobs and with msaa4.
    let mut q16 = q.clone();
    q16.reference.spp = 16;
    let smooth = specula::reference::render_reference(&s, &q16, SIZE).unwrap();
    let sphere = s.meshes.iter().position(|m| m.name == "sphere").unwrap() as u32 + 1;
    let mask: Vec<bool> = specula::reference::object_ids(&s, SIZE).unwrap().into_iter().map(|id| id == sphere).collect();
    let on_sphere = |i: &ImageData| specula::metrics::masked_error(i, &smooth, &mask, "sphere").unwrap().unwrap().psnr;
    let mut msaa = q.clone();
    msaa.set("aa", "msaa4").unwrap();
    // Each frame's GPU time (the median of 3 after one warm-up), in this run.
    let timed = |choice: specula::Choice, q: &Quality| {
        let f = specula::render(&ctx, &s, choice, q, SIZE, (1, 3)).unwrap();
        (on_sphere(&f.image), f.passes.iter().filter(|p| p.name != "frame.readback").map(|p| p.gpu_ms).sum::<f64>())
    };
    let rivals = [specula::methods::CURVED_REFLECTOR, specula::methods::DISTANCE, specula::methods::PROXY_BOX];
    let others: Vec<(String, f64, f64)> = [("", &q), (" msaa4", &msaa)]
        .into_iter()
        .flat_map(|(aa, q)| rivals.map(|m| (m, aa, q)))
        .map(|(m, aa, q)| {
            let (db, ms) = timed(m.into(), q);
            (format!("{m}{aa}"), db, ms)
        })
        .collect();
    let (auto, auto_ms) = timed(specula::Choice::Auto, &q);
    println!("cluttered, the sphere against 16 samples a pixel: auto {auto:.2} dB in {auto_ms:.1} ms; {others:.2?}");
    // Measured with the calibration of 2026-12-07: auto (bvh: within its default budget, the
    // exact tracer's frame, multisampling does not fit) 25.24 dB; curved-reflector 25.89 /
    // 26.33 (msaa4), distance 24.33 / 29.28, proxy-box 21.16 / 22.48 — the better ones
    // slower (with the calibration before it, whose multisamples were nearly free, auto took
    // ray-query with msaa4: 33.41 dB). Auto is never dominated (issue 31): no rival both
    // faster beyond the noise (1.12×) and more accurate by over 0.5 dB.
    for (name, db, ms) in &others {
        assert!(
            !(*db > auto + 0.5 && *ms * 1.12 < auto_ms),
            "{name} ({db:.2} dB, {ms:.1} ms) dominates auto ({auto:.2} dB, {auto_ms:.1} ms)"
        );
    }

    let hall = hall_scene();
    let plan = specula::plan(&hall, specula::Choice::Auto, &q);
    let o = plan.objects.iter().find(|o| o.name == "sphere").unwrap();
    println!("hall: auto {} ({})", o.method, o.reason);
    assert_ne!(o.method, specula::methods::CURVED_REFLECTOR, "{}", o.reason);
    let reference = specula::reference::render_reference(&hall, &q, SIZE).unwrap();
    let curved = psnr(&gpu(&ctx, &hall, specula::methods::CURVED_REFLECTOR, &q).image, &reference);
    let distance = psnr(&gpu(&ctx, &hall, specula::methods::DISTANCE, &q).image, &reference);
    println!("hall: curved-reflector {curved:.2} dB, distance {distance:.2} dB");
    // Measured 31.77 vs 48.00 dB: the bound half the margin (the reason not to take it).
    assert!(curved <= distance - 8.1, "hall: curved-reflector {curved:.2} dB vs distance {distance:.2} dB");
    common::assert_clean(&ctx);
}

/// The benchmark's sweep through `specula tradeoff` (the library behind it): error and time
/// per geometry-image size and tessellation, the search timed apart, one row each.
#[test]
fn tradeoff_sweeps_the_geometry_image_and_the_tessellation() {
    let out = common::scratch_dir("curved-tradeoff");
    let cfg = specula::tradeoff::Config {
        scene: sphere_scene(),
        scene_name: "sphere".into(),
        quality: quality(),
        sweeps: vec![
            specula::tradeoff::Sweep::parse("geometry_image=32,128").unwrap(),
            specula::tradeoff::Sweep::parse("tessellation=1,4").unwrap(),
        ],
        each: false,
        methods: vec![specula::methods::CURVED_REFLECTOR.into()],
        size: SIZE,
        warmup: 1,
        frames: 1,
        device: specula::vk::DeviceOptions { validation: true, device_filter: None, ..Default::default() },
        out: out.clone(),
        metric: specula::tradeoff::Metric::Psnr,
        calibrate: None,
    };
    let report = specula::tradeoff::run(&cfg, &mut |_| {}).unwrap();
    assert_eq!(report.validation, (0, 0));
    let psnr = |knobs: &str| report.rows.iter().find(|r| r.knobs == knobs).map(|r| r.errors.psnr).unwrap();
    for r in &report.rows {
        let search = r.passes.iter().find(|(n, _)| n == "geometry.virtual.search").map(|p| p.1);
        println!("{}: {:.2} dB, frame {:.1} ms, search {search:?} ms", r.knobs, r.errors.psnr, r.frame_ms);
        assert!(search.is_some_and(|ms| ms > 0.0), "{}: {:?}", r.knobs, r.passes);
    }
    // The same PSNRs as rendered directly (error_against_geometry_image_size_and_tessellation:
    // 36.80 dB at 128² and tessellation 4, 29.79 dB at tessellation 1).
    let (coarse, fine) = (psnr("geometry_image=128 tessellation=1"), psnr("geometry_image=128 tessellation=4"));
    assert!((coarse - 29.79).abs() < 0.01 && (fine - 36.80).abs() < 0.01, "{coarse:.2} dB, {fine:.2} dB");
    assert!(psnr("geometry_image=32 tessellation=4") < fine, "a 32² geometry image is coarser");
    let csv = std::fs::read_to_string(&report.csv).unwrap();
    assert!(csv.lines().next().unwrap().contains("geometry.virtual.search ms"), "{csv}");
    std::fs::remove_dir_all(&out).ok();
}

/// Two curved reflectors (one virtual object per reflector and object pair, EMDT06: twice
/// the searches) beside a planar mirror wall, whose mirrored view records the curved
/// reflectors' passes again from the mirrored eye.
#[test]
fn two_spheres_and_a_mirror_wall() {
    let ctx = common::gpu();
    let mut s = sphere_scene();
    let m = s.add_material(common::mirror(0.9)).unwrap();
    s.add_mesh(shapes::uv_sphere("sphere2", Vec3::new(0.8, 0.6, -0.9), 0.4, 48, 24, m)).unwrap();
    let q = quality();
    let reference = specula::reference::render_reference(&s, &q, SIZE).unwrap();
    let one = gpu(&ctx, &sphere_scene(), specula::methods::CURVED_REFLECTOR, &q);
    let f = gpu(&ctx, &s, specula::methods::CURVED_REFLECTOR, &q);
    let p = psnr(&f.image, &reference);
    let d = psnr(&gpu(&ctx, &s, specula::methods::DISTANCE, &q).image, &reference);
    println!("two spheres: curved-reflector {p:.2} dB, distance {d:.2} dB");
    assert_eq!(stat(&f, "geometry.curved_reflectors"), 2.0);
    // One search dispatch per reflector over the same environment (each sphere is the
    // other's environment, and its own too: 2 × every triangle's vertices).
    assert_eq!(stat(&f, "geometry.curved_vertices"), environment_vertices(&s, 4));
    assert!(stat(&f, "geometry.curved_vertices") > stat(&one, "geometry.curved_vertices"));
    // Rule 1: measured 35.42 dB (distance maps 31.69 dB; depth 1: each sphere shows the
    // other black, as the reference does).
    assert!(p >= 34.42 && p >= d + 2.73, "{p:.2} dB vs distance {d:.2} dB");

    // A mirror wall behind them: its view sees both spheres, drawn by this method from the
    // mirrored eye (depth 2: the spheres seen in the wall).
    let wall = s.add_material(common::mirror(0.9)).unwrap();
    s.add_mesh(shapes::quad("wall", Vec3::new(-1.5, -1.5, -1.9), Vec3::new(3.0, 0.0, 0.0), Vec3::new(0.0, 3.0, 0.0), 1, wall)).unwrap();
    let q2 = {
        let mut knobs = q.clone();
        knobs.frame.depth = 2;
        knobs
    };
    let choices = specula::plan::Choices {
        method: specula::Choice::Auto,
        objects: vec![
            ("sphere".into(), specula::methods::CURVED_REFLECTOR),
            ("sphere2".into(), specula::methods::CURVED_REFLECTOR),
            ("wall".into(), specula::methods::PLANAR_MIRROR),
        ],
    };
    let plan = specula::plan::plan_with(&s, &choices, &q2).unwrap();
    let mut r = specula::Renderer::new(&ctx, &s, plan, SIZE.0, SIZE.1).unwrap();
    let f = r.render(&ctx).unwrap();
    r.destroy(&ctx);
    let reference = specula::reference::render_reference(&s, &q2, SIZE).unwrap();
    let p = psnr(&f.image, &reference);
    let alt = specula::plan::Choices {
        method: specula::Choice::Auto,
        objects: vec![
            ("sphere".into(), specula::methods::DISTANCE),
            ("sphere2".into(), specula::methods::DISTANCE),
            ("wall".into(), specula::methods::PLANAR_MIRROR),
        ],
    };
    let plan = specula::plan::plan_with(&s, &alt, &q2).unwrap();
    let mut r = specula::Renderer::new(&ctx, &s, plan, SIZE.0, SIZE.1).unwrap();
    let g = r.render(&ctx).unwrap();
    r.destroy(&ctx);
    let pd = psnr(&g.image, &reference);
    println!("with the wall, distance spheres: {pd:.2} dB");
    keep("wall", &[&f.image, &g.image, &reference]);
    println!("with the wall: {p:.2} dB, {} mirrored view(s)", stat(&f, "geometry.mirror_views"));
    assert!(f.image.data.iter().all(|v| v.is_finite()));
    assert_eq!(stat(&f, "geometry.mirror_views"), 1.0);
    let searches = f.passes.iter().filter(|p| p.name == "geometry.virtual.search").count();
    assert_eq!(searches, 1, "the camera's search (the view's is profiled as geometry.mirror_view)");
    // Rule 1: measured 23.06 dB, the spheres by distance maps 23.57 dB: both show the wall
    // they see as a mirror of nothing (black), where the depth-2 reference shows the room in
    // it (the planner ray traces an object that sees a planar mirror).
    assert!(p >= 22.06 && p >= pd - 1.51, "{p:.2} dB vs {pd:.2} dB");
    common::assert_clean(&ctx);
}

/// Bad sizes are clear errors before anything is allocated: a tessellation whose vertices
/// exceed the device's storage-buffer range, a geometry image beyond its image limit.
#[test]
fn too_fine_a_tessellation_is_an_error() {
    let ctx = common::gpu();
    let mut s = sphere_scene();
    let ball = s.meshes.iter().find(|m| m.name == "ball").unwrap().material;
    // 80 000 triangles × 561 vertices (tessellation 32) × 48 bytes: 2 GiB.
    s.add_mesh(shapes::uv_sphere("fine", Vec3::new(-1.2, -1.5, -1.2), 0.2, 200, 200, ball)).unwrap();
    let mut q = quality();
    q.set("tessellation", "32").unwrap();
    let e = specula::render(&ctx, &s, specula::methods::CURVED_REFLECTOR, &q, SIZE, (0, 1)).unwrap_err().to_string();
    println!("{e}");
    assert!(e.contains("knob tessellation") && e.contains("storage-buffer range"), "{e}");
    let mut q = quality();
    q.set("geometry_image", "1024").unwrap();
    let f = specula::render(&ctx, &sphere_scene(), specula::methods::CURVED_REFLECTOR, &q, SIZE, (0, 1)).unwrap();
    assert!(f.image.data.iter().all(|v| v.is_finite()));
    assert!(q.clone().set("geometry_image", "2048").is_err() && q.set("tessellation", "0").is_err());
    common::assert_clean(&ctx);
}

/// Frames over time: a moved environment object is tessellated again on the GPU from the
/// scene's updated vertices (`geometry.virtual.tessellate`), a moved reflector also redraws
/// its geometry image (`geometry.image`); a frame with no change does neither. Each frame
/// equals a fresh render of the same scene bit for bit.
#[test]
fn moved_objects_equal_a_fresh_render() {
    let ctx = common::gpu();
    let mut s = sphere_scene();
    let q = quality();
    let plan = specula::plan(&s, specula::methods::CURVED_REFLECTOR, &q);
    let mut r = specula::Renderer::new(&ctx, &s, plan, SIZE.0, SIZE.1).unwrap();
    let names = |f: &specula::Frame| f.passes.iter().map(|p| p.name.clone()).collect::<Vec<_>>();
    let first = names(&r.render(&ctx).unwrap());
    assert!(first.iter().any(|n| n == "geometry.image") && first.iter().any(|n| n == "geometry.virtual.tessellate"), "{first:?}");
    let still = names(&r.render(&ctx).unwrap());
    assert!(still.iter().all(|n| n != "geometry.image" && n != "geometry.virtual.tessellate"), "{still:?}");
    for (name, to, image) in [("ball", Vec3::new(-0.5, 0.3, 0.0), false), ("sphere", Vec3::new(0.2, 0.1, -0.3), true)] {
        let i = s.meshes.iter().position(|m| m.name == name).unwrap();
        s.set_object_transform(i, glam::Mat4::from_translation(to)).unwrap();
        assert_eq!(r.update(&s).unwrap().moved, vec![i]);
        let got = r.render(&ctx).unwrap();
        let passes = names(&got);
        assert!(passes.iter().any(|n| n == "geometry.virtual.tessellate"), "{name}: {passes:?}");
        assert_eq!(passes.iter().any(|n| n == "geometry.image"), image, "{name}: {passes:?}");
        let fresh = gpu(&ctx, &s, specula::methods::CURVED_REFLECTOR, &q);
        assert!(got.image == fresh.image, "{name} moved: {:.2} dB from a fresh render", psnr(&got.image, &fresh.image));
    }
    r.destroy(&ctx);
    common::assert_clean(&ctx);
}

/// Two separate balls in one mesh: every edge bends the convex way, so the convexity test
/// lets it through, yet an environment vertex may have a reflection point on each ball —
/// several minima (survey §5). The planner's check (`plan::reflection_points`, on the CPU
/// from the camera) refuses it by name and gives it the fallback, the refusal its reason —
/// chosen for the object or for the whole scene alike: the refusal holds from this camera
/// only, and a move must not fail the frame (a saddle, refused by its form, is an error when
/// chosen for the object: `a_saddle_is_reported_unsupported` above). The GPU search's own check counts the
/// second points (`geometry.curved_multiple_minima`) where a plan made before brings such
/// a mesh to it: the plan of one ball, rendered with the pair.
#[test]
fn several_minima_are_refused_and_counted() {
    let ctx = common::gpu();
    let camera = (Vec3::new(0.0, 0.3, 1.9), Vec3::new(0.0, -0.3, 0.0));
    let pair = room(
        |m| {
            let mut a = shapes::uv_sphere("pair", Vec3::new(-0.5, -0.3, 0.0), 0.4, 32, 16, m);
            let b = shapes::uv_sphere("pair", Vec3::new(0.5, -0.3, 0.0), 0.4, 32, 16, m);
            let base = a.positions.len() as u32;
            a.positions.extend(&b.positions);
            a.normals.extend(&b.normals);
            // One chart: the second ball's UVs beside the first's.
            a.uvs.iter_mut().for_each(|u| u.x *= 0.5);
            a.uvs.extend(b.uvs.iter().map(|u| Vec2::new(0.5 + 0.5 * u.x, u.y)));
            a.indices.extend(b.indices.iter().map(|i| i + base));
            a
        },
        camera,
    );
    let q = quality();
    let facts = specula::plan::facts::SceneFacts::new(&pair, &q, false);
    let mirror = facts.objects.iter().find(|f| pair.meshes[f.mesh].name == "pair").unwrap();
    let (found, checked) = mirror.reflection_points;
    println!("two balls in one mesh: the planner finds a second reflection point for {found} of {checked} sampled vertices");
    assert_eq!(mirror.curvature, specula::plan::facts::Curvature::Convex);
    let choices =
        specula::plan::Choices { method: specula::Choice::Auto, objects: vec![("pair".into(), specula::methods::CURVED_REFLECTOR)] };
    let chosen = specula::plan::plan_with(&pair, &choices, &q).unwrap();
    let o = chosen.objects.iter().find(|o| o.name == "pair").unwrap();
    println!("{}", o.reason);
    let e = &o.reason;
    assert_eq!(o.method, specula::methods::DISTANCE, "{e}");
    assert!(
        e.contains("refused from this view") && e.contains("second one") && e.contains("several minima") && e.contains("unsupported"),
        "{e}"
    );
    let plan = specula::plan(&pair, specula::methods::CURVED_REFLECTOR, &q);
    let o = plan.objects.iter().find(|o| o.name == "pair").unwrap();
    assert_eq!(o.method, specula::methods::DISTANCE, "{}", o.reason);
    assert!(o.reason.contains("several-minima"), "{}", o.reason);

    // One ball where the pair's first ball is: accepted (no second point), its plan then
    // drawn with the pair's mesh in its place.
    let one = room(|m| shapes::uv_sphere("pair", Vec3::new(-0.5, -0.3, 0.0), 0.4, 32, 16, m), camera);
    let single = specula::plan(&one, specula::methods::CURVED_REFLECTOR, &q);
    assert!(single.objects.iter().any(|o| o.name == "pair" && o.method == specula::methods::CURVED_REFLECTOR));
    let f = specula::render_plan(&ctx, &pair, single, SIZE, (0, 1)).unwrap();
    let (found, checked) = (stat(&f, "geometry.curved_multiple_minima"), stat(&f, "geometry.curved_checked"));
    let reference = specula::reference::render_reference(&pair, &q, SIZE).unwrap();
    println!("drawn anyway: the GPU finds {found} of {checked} checked vertices with several minima, {:.2} dB", psnr(&f.image, &reference));
    // Counts (tests/README.md): measured 648 of 2475 (the convex sphere and the bowl: 0),
    // the bound a factor 1.122 under it.
    assert!(found >= 577.0, "{found} of {checked}");
    common::assert_clean(&ctx);
}

/// Images side by side, each scaled up `k` times (nearest).
fn montage(images: &[&ImageData], k: u32) -> ImageData {
    let (w, h) = (images[0].width, images[0].height);
    let (ow, oh) = (w * k * images.len() as u32, h * k);
    let mut data = vec![0.0; (ow * oh * 4) as usize];
    for (i, im) in images.iter().enumerate() {
        for y in 0..oh {
            for x in 0..w * k {
                let t = im.texel(0, x / k, y / k);
                let o = ((y * ow + i as u32 * w * k + x) * 4) as usize;
                data[o..o + 4].copy_from_slice(&t[..4]);
            }
        }
    }
    ImageData { width: ow, height: oh, layers: 1, channels: 4, data }
}
