//! Issue 35's niches: the methods whose place is measured frame time against the exact
//! tracers on the same scene, in one run. A binary of its own, run alone by
//! `scripts/test.sh` and one test at a time here: a frame timed while another test renders
//! on the same cores (lavapipe is the CPU) measures the other test.

mod common;

use common::{psnr, split};
use specula::{Quality, Scene};

static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// For the niche tests: a method's specular PSNR against `base`'s reference (its `spp`) and
/// its GPU ms (the median of 3 frames after one warm-up, readback left out), at `size`.
fn front_runner<'a>(
    ctx: &'a specula::vk::Context,
    scene: &'a Scene,
    base: &'a Quality,
    size: (u32, u32),
) -> impl Fn(specula::Method) -> (f64, f64) + 'a {
    let reference = specula::reference::render_reference(scene, base, size).unwrap();
    let ids = specula::reference::object_ids(scene, size).unwrap();
    move |m| {
        let f = specula::render(ctx, scene, m, base, size, (1, 3)).unwrap();
        let ms = f.passes.iter().filter(|p| p.name != "frame.readback").map(|p| p.gpu_ms).sum::<f64>();
        (psnr(&split(scene, &f.image, &reference, &ids), "specular"), ms)
    }
}

/// Issue 35's niches on `glass-1.5` at 128²: refractor-map (§4.4) is on the Pareto front of
/// error against time among every method, the exact tracers included — as accurate as they
/// are on the ball, in less time — and image-space refraction (§4.4, Wyman) with two Newton
/// steps is the fastest refraction above 20 dB (refractor-map's accuracy at more time). One
/// run, frames timed the same way (the median of 3 after one warm-up, GPU ms); a ratio that
/// misses its bound is measured once more (the machine is shared: noise only slows a frame).
#[test]
fn glass_ball_refractions_on_the_front() {
    const SIZE: (u32, u32) = (128, 128);
    let _turn = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let ctx = common::gpu();
    let scene = specula::scenes::builtin("glass-1.5").unwrap().unwrap();
    let mut base = Quality::default();
    base.reference.spp = 16;
    base.set("image_space_iterations", "2").unwrap();
    let run = front_runner(&ctx, &scene, &base, SIZE);
    let methods =
        [specula::methods::IMAGE_SPACE_REFRACTION, specula::methods::REFRACTOR_MAP, specula::methods::BVH, specula::methods::RAY_QUERY];
    let measure = || methods.map(&run);
    let mut r = measure();
    let ok = |r: &[(f64, f64); 4]| {
        let exact_ms = r[2].1.min(r[3].1);
        exact_ms >= 1.12 * r[1].1 && r[1].1 >= 1.12 * r[0].1
    };
    if !ok(&r) {
        let again = measure();
        for (a, b) in r.iter_mut().zip(again) {
            a.1 = a.1.min(b.1);
        }
    }
    println!("glass-1.5, the ball at 128²: image-space (2 steps), refractor-map, bvh, ray-query (dB, ms): {r:.2?}");
    let [(image_db, image_ms), (map_db, map_ms), (bvh_db, bvh_ms), (rq_db, rq_ms)] = r;
    // Measured (BENCHMARKS.md, "Every approximate method against the exact tracers"): 24.40 dB
    // in 50.4 ms, 31.70 in 69.6, bvh 31.44 in 177.9, ray-query 31.44 in 137.3. Floors 1 dB
    // under (rule 1); the times as the front needs them: each faster than the next more
    // accurate one beyond the noise (1.12×; measured 1.39× and 1.97×).
    assert!(map_db >= 30.70 && map_db >= bvh_db.max(rq_db) - 0.74, "refractor-map {map_db:.2} dB");
    assert!(image_db >= 23.40, "image-space refraction {image_db:.2} dB");
    assert!(bvh_ms.min(rq_ms) >= 1.12 * map_ms, "refractor-map {map_ms:.1} ms, exact {bvh_ms:.1} / {rq_ms:.1} ms");
    assert!(map_ms >= 1.12 * image_ms, "image-space {image_ms:.1} ms, refractor-map {map_ms:.1} ms");
    common::assert_clean(&ctx);
}

/// Issue 35's niche for distance-multi (§4.3): three mirror balls in mutual view, each
/// reflecting the others' reflections. Inter-object distance maps are on the front of error
/// against time among the methods that serve them, the exact tracers included: none is
/// faster beyond the noise (1.12×) and more accurate by over 0.5 dB (the README's
/// "dominated"), and the exact tracers are slower — while nothing moves: frames timed as
/// above, the maps made in the warm-up frame and searched by the timed ones (a static scene
/// seen from a moving camera reuses them). Measured: distance-multi 25.28 dB in 3.7–3.9 ms,
/// distance 18.85 in 3.6–3.7, envmap 17.09 in 1.5–1.7, proxy-sphere 18.61 in 1.7–2.1, bvh
/// 26.84 in 9.1–14.4, ray-query 26.84 in 8.9–11.8; with its maps made again every frame
/// (`map_updates=always`) distance-multi takes 267 ms, dominated by the exact tracers. A run
/// whose ratios miss is measured once more.
#[test]
fn mirror_balls_in_mutual_view_on_the_front() {
    use glam::Vec3;
    use specula::methods::{BVH, DISTANCE, DISTANCE_MULTI, ENVMAP, PROXY_SPHERE, RAY_QUERY};
    const SIZE: (u32, u32) = (128, 128);
    let _turn = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let ctx = common::gpu();
    let mut scene = Scene::new();
    common::emissive_room(&mut scene, Vec3::new(0.0, 2.0, 0.0), 2.0);
    let m = scene.add_material(common::mirror(0.9)).unwrap();
    for (i, c) in [Vec3::new(-0.6, 1.5, 0.0), Vec3::new(0.6, 1.5, 0.0), Vec3::new(0.0, 1.5, -0.9)].into_iter().enumerate() {
        scene.add_mesh(specula::scene::shapes::uv_sphere(&format!("ball{i}"), c, 0.45, 24, 12, m)).unwrap();
    }
    scene.camera = Some(specula::scene::Camera::look_at(Vec3::new(0.0, 2.2, 2.0), Vec3::new(0.0, 1.5, -0.3), 60f32.to_radians()));
    let mut base = Quality::default();
    base.reference.spp = 16;
    base.set("depth", "4").unwrap();
    let run = front_runner(&ctx, &scene, &base, SIZE);
    let methods = [DISTANCE_MULTI, DISTANCE, ENVMAP, PROXY_SPHERE, BVH, RAY_QUERY];
    let dominated = |r: &[(f64, f64)]| r[1..].iter().any(|&(db, ms)| ms * 1.12 < r[0].1 && db > r[0].0 + 0.5);
    let exact_faster = |r: &[(f64, f64)]| r[4].1.min(r[5].1) < 1.12 * r[0].1;
    let mut r: Vec<(f64, f64)> = methods.iter().map(|&m| run(m)).collect();
    if dominated(&r) || exact_faster(&r) {
        let again: Vec<(f64, f64)> = methods.iter().map(|&m| run(m)).collect();
        for (a, b) in r.iter_mut().zip(again) {
            a.1 = a.1.min(b.1);
        }
    }
    for (m, (db, ms)) in methods.iter().zip(&r) {
        println!("three mirror balls at 128²: {m} {db:.2} dB in {ms:.2} ms");
    }
    assert!(!dominated(&r) && !exact_faster(&r), "distance-multi off the front: {r:.2?}");
    common::assert_clean(&ctx);
}
