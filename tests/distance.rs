//! Ray tracing in the sampled geometry (survey §4) against the exact CPU reference, on
//! lavapipe with validation on. Floors and margins were set from the numbers measured when
//! the tests were written (stated beside each); the images are small (64²–96²) to keep the
//! suite fast, so the absolute PSNRs are those of small images.

mod common;

use glam::{DVec3, Vec3};
use specula::metrics::{self, ImageErrors};
use specula::reference::render_reference;
use specula::scene::{shapes, Camera, Material, Scene, SurfaceKind};
use specula::vk::{Context, ImageData};
use specula::{Method, Quality};

fn quality(pairs: &[&str]) -> Quality {
    let mut q = Quality::default();
    for p in pairs {
        q.set_pair(p).unwrap();
    }
    q
}

fn gpu(ctx: &Context, scene: &Scene, method: Method, q: &Quality, size: u32) -> ImageData {
    specula::render(ctx, scene, method, q, (size, size), (0, 1)).unwrap().image
}

fn reference(scene: &Scene, pairs: &[&str], size: u32) -> ImageData {
    render_reference(scene, &quality(pairs), (size, size)).unwrap()
}

fn errors(test: &ImageData, reference: &ImageData) -> ImageErrors {
    metrics::compare(test, reference).unwrap()
}

/// RMSE of `distance` against `refimg` for each value of one knob over fixed `base` knobs,
/// printed as `label value: errors`.
fn knob_sweep(ctx: &Context, scene: &Scene, refimg: &ImageData, base: &[&str], knob: &str, values: &[u32], label: &str) -> Vec<f64> {
    let size = refimg.width;
    values
        .iter()
        .map(|v| {
            let pair = format!("{knob}={v}");
            let q = quality(&base.iter().copied().chain(std::iter::once(pair.as_str())).collect::<Vec<_>>());
            let e = errors(&gpu(ctx, scene, specula::methods::DISTANCE, &q, size), refimg);
            eprintln!("{label} {v:2}: {e}");
            e.rmse
        })
        .collect()
}

/// The quadrant room (half-size 2 around (0, 2, 0), 24 distinct emissive colours) with a
/// mirror sphere of radius 0.5 moved into a corner: the survey's Figure 14/20 situation.
fn corner_mirror_scene() -> Scene {
    let mut s = Scene::new();
    common::emissive_room(&mut s, Vec3::new(0.0, 2.0, 0.0), 2.0);
    let m = s.add_material(common::mirror(0.8)).unwrap();
    s.add_mesh(shapes::uv_sphere("mirror", Vec3::new(-1.25, 0.75, -1.25), 0.5, 96, 48, m)).unwrap();
    s.camera = Some(Camera::look_at(Vec3::new(0.4, 1.4, 0.6), Vec3::new(-1.25, 0.75, -1.25), 40f32.to_radians()));
    s
}

#[test]
fn distance_map_beats_environment_map_for_a_mirror_in_a_corner() {
    let ctx = common::gpu();
    let scene = corner_mirror_scene();
    let size = 96;
    let refimg = reference(&scene, &["spp=4", "depth=1"], size);
    // The reference point at the room's centre, far from the sphere: classic environment
    // mapping ignores the ray origin and reflects the wrong walls (§3, Figure 14).
    let q = quality(&["cube_size=128", "ref_point=0,2,0"]);
    let env = errors(&gpu(&ctx, &scene, specula::methods::ENVMAP, &q, size), &refimg);
    let half_img = gpu(&ctx, &scene, specula::methods::DISTANCE, &q, size);
    let dist = errors(&half_img, &refimg);
    eprintln!("corner mirror: envmap {env}\n               distance {dist}");
    // Floors 1 dB under what was measured.
    assert!(env.psnr > 19.06, "envmap {env}"); // measured 20.06 dB
    assert!(dist.psnr > 35.29, "distance {dist}"); // measured 36.29 dB
    assert!(dist.psnr - env.psnr > 15.23, "margin {:.2} dB", dist.psnr - env.psnr); // measured 16.23 dB

    // The proxy box is the room itself here: localisation recovers most of the parallax.
    let boxed = errors(&gpu(&ctx, &scene, specula::methods::PROXY_BOX, &q, size), &refimg);
    let sphere = errors(&gpu(&ctx, &scene, specula::methods::PROXY_SPHERE, &q, size), &refimg);
    eprintln!("               proxy-box {boxed}\n               proxy-sphere {sphere}");
    assert!(boxed.psnr > 35.78, "proxy-box {boxed}"); // measured 36.78 dB
    assert!(boxed.psnr - env.psnr > 15.72, "proxy-box {boxed} vs envmap {env}"); // measured 16.72 dB
    assert!(sphere.psnr > 24.37, "proxy-sphere {sphere}"); // measured 25.37 dB
    assert!(sphere.psnr - env.psnr > 4.31, "proxy-sphere {sphere} vs envmap {env}"); // measured 5.31 dB

    // Half-float distance maps (11-bit mantissa: 1 mm at 2 m, 1/30 of a 3 cm texel) search
    // as well as single: the knob reaches the maps (the images differ: measured 67.85 dB
    // apart) and the error is the same within 0.05 dB (measured 0.0007 dB).
    let single_img =
        gpu(&ctx, &scene, specula::methods::DISTANCE, &quality(&["cube_size=128", "ref_point=0,2,0", "cube_precision=single"]), size);
    let single = errors(&single_img, &refimg);
    eprintln!("               distance, single precision {single}");
    eprintln!("               half - single: {:.5} dB; half vs single image {}", dist.psnr - single.psnr, errors(&half_img, &single_img));
    assert_ne!(half_img.data, single_img.data, "cube_precision reaches the distance maps");
    assert!((single.psnr - dist.psnr).abs() < 0.05, "half {dist} vs single {single}"); // measured 0.0007 dB
    common::assert_clean(&ctx);
}

/// Secant convergence on a convex room (the quadrant room, no box): with more secant steps
/// after a coarse linear search the image error falls monotonically, and from 4 steps on
/// (measured 0.0565 → 0.0320 → 0.0227 → 0.0172 → 0.0160 → 0.0161 RMSE for 0, 1, 2, 4, 8,
/// 16 steps after a 4-step linear search); by 8 steps it is within 1 % of the 16-step
/// error: the search is then below a texel and what remains is the map's own sampling.
/// No secant step is 3.52× the converged error (bound 3.14×, a factor 1.122 under), and the
/// converged error has a floor 1 dB above it.
#[test]
fn secant_steps_converge_monotonically() {
    let ctx = common::gpu();
    let scene = corner_mirror_scene();
    let size = 80;
    let refimg = reference(&scene, &["spp=4", "depth=1"], size);
    let base = ["cube_size=128", "ref_point=0,2,0", "linear_steps=4", "search_tolerance=0"];
    let rmse = knob_sweep(&ctx, &scene, &refimg, &base, "secant_steps", &[0, 1, 2, 4, 8, 16], "secant");
    for w in rmse.windows(2) {
        assert!(w[1] <= w[0] * 1.02, "error rose: {rmse:?}");
    }
    assert!(rmse[0] > rmse[5] * 3.13, "the secant steps matter: {rmse:?}"); // measured 3.52× (÷ 1.122 = 3.137)
    assert!(rmse[5] < 0.01607 * 1.122, "16 steps reach the measured error: {rmse:?}"); // measured 0.01607
    assert!(rmse[4] <= rmse[5] * 1.01, "8 steps reach the converged error: {rmse:?}");
    assert!(rmse[3] <= rmse[5] * 1.15, "4 steps come within 15 %: {rmse:?}");
    common::assert_clean(&ctx);
}

/// Binary refinement (§4.1.4) after a coarse 4-step linear search, no secant: the error falls
/// with the halvings and 8 of them beat none by a wide margin (measured RMSE 0.0556,
/// 0.0237, 0.0201, 0.0195 for 0, 2, 4, 8 steps: none is 2.85× eight, bound 2.55×, a factor
/// 1.122 under; the floor is 1 dB above the last), so a
/// knob that is ignored or halves the wrong side fails.
#[test]
fn binary_steps_refine_the_linear_search() {
    let ctx = common::gpu();
    let scene = corner_mirror_scene();
    let size = 64;
    let refimg = reference(&scene, &["spp=4", "depth=1"], size);
    let base = ["cube_size=128", "ref_point=0,2,0", "linear_steps=4", "secant_steps=0", "search_tolerance=0"];
    let rmse = knob_sweep(&ctx, &scene, &refimg, &base, "binary_steps", &[0, 2, 4, 8], "binary");
    for w in rmse.windows(2) {
        assert!(w[1] < w[0], "each halving lowers the error: {rmse:?}");
    }
    assert!(rmse[0] > rmse[3] * 2.55, "the binary steps matter: {rmse:?}"); // measured 2.85×
    assert!(rmse[3] < 0.0195 * 1.122, "8 halvings reach the measured error: {rmse:?}");
    common::assert_clean(&ctx);
}

/// `linear_steps = 0` is parallax correction only (survey eq. 4), iterated
/// `parallax_iterations` times: from the room's centre the corner mirror's rays end on the
/// convex room's walls, where the iteration converges: each count lowers the error, and
/// the linear search is better than one parallax step (measured RMSE 0.0475, 0.0349,
/// 0.0242 for 1, 2, 4 iterations and 0.0194 with the 16-step linear search: one parallax
/// step is 2.45× the linear search, bound 2.19×, a factor 1.122 under; the floor is 1 dB
/// above the 4 iterations' error).
#[test]
fn parallax_iterations_converge_when_there_is_no_linear_search() {
    let ctx = common::gpu();
    let scene = corner_mirror_scene();
    let size = 64;
    let refimg = reference(&scene, &["spp=4", "depth=1"], size);
    let base = ["cube_size=128", "ref_point=0,2,0", "linear_steps=0"];
    let rmse = knob_sweep(&ctx, &scene, &refimg, &base, "parallax_iterations", &[1, 2, 4], "parallax");
    let linear = errors(&gpu(&ctx, &scene, specula::methods::DISTANCE, &quality(&["cube_size=128", "ref_point=0,2,0"]), size), &refimg);
    eprintln!("linear 16: {linear}");
    for w in rmse.windows(2) {
        assert!(w[1] < w[0], "each iteration lowers the error: {rmse:?}");
    }
    // Measured 2.45×.
    assert!(rmse[0] > linear.rmse * 2.19, "the linear search beats one parallax step: {} vs {rmse:?}", linear.rmse);
    assert!(rmse[2] < 0.0242 * 1.122, "4 iterations reach the measured error: {rmse:?}");
    common::assert_clean(&ctx);
}

/// Distance maps rendered in one multiview pass (`cube_mode = multiview`) draw each object
/// once (counted under face 0; six passes draw per face) and give the same image as six
/// passes.
#[test]
fn multiview_distance_maps_match_six_passes() {
    let ctx = common::gpu();
    let scene = corner_mirror_scene();
    let draws = |q: &Quality| {
        let f = specula::render(&ctx, &scene, specula::methods::DISTANCE, q, (48, 48), (0, 1)).unwrap();
        let d: Vec<u32> = (0..6)
            .map(|k| f.stats.iter().find(|(n, _)| *n == format!("distance.generate.draws.face{k}")).map_or(0, |s| s.1 as u32))
            .collect();
        (f.image, d)
    };
    let (six, d6) = draws(&quality(&["cube_size=64", "ref_point=0,2,0", "caustics=off"]));
    let (multi, dm) = draws(&quality(&["cube_size=64", "ref_point=0,2,0", "caustics=off", "cube_mode=multiview"]));
    eprintln!("draws per face: six passes {d6:?}, multiview {dm:?}");
    assert!(d6[1..].iter().any(|&d| d > 0), "six passes draw in faces other than 0: {d6:?}");
    assert!(dm[1..].iter().all(|&d| d == 0) && dm[0] > 0, "multiview draws in one pass: {dm:?}");
    let p = errors(&multi, &six).psnr;
    eprintln!("multiview vs six passes: {p:.2} dB");
    // An exact equality (rule 2 of tests/README.md: 60 dB); measured: the same bits (inf dB).
    assert!(p > 60.0, "multiview and six passes agree: {p:.2} dB");
    common::assert_clean(&ctx);
}

/// `proxy_radius` (§3.2): the proxy sphere around the room's centre localises best near the
/// room's own size; `auto` is the box's mean half-extent (2 m here: the same bits as 2), and
/// a sphere 4× too small or too large reflects measurably worse walls (measured PSNR
/// 19.98, 25.32 and 21.40 dB for 0.5 m, auto and 8 m; the floor and the margins are 1 dB
/// under what was measured).
#[test]
fn proxy_radius_sizes_the_localising_sphere() {
    let ctx = common::gpu();
    let scene = corner_mirror_scene();
    let size = 64;
    let refimg = reference(&scene, &["spp=4", "depth=1"], size);
    let img = |r: &str| {
        gpu(
            &ctx,
            &scene,
            specula::methods::PROXY_SPHERE,
            &quality(&["cube_size=128", "ref_point=0,2,0", &format!("proxy_radius={r}")]),
            size,
        )
    };
    let (small, auto, two, large) = (img("0.5"), img("auto"), img("2"), img("8"));
    assert!(auto.data == two.data, "auto is the mean half-extent, 2 m");
    let (s, a, l) = (errors(&small, &refimg), errors(&auto, &refimg), errors(&large, &refimg));
    eprintln!("proxy radius 0.5: {s}\n             auto: {a}\n                8: {l}");
    assert!(a.psnr - s.psnr > 4.34, "the room-sized sphere localises better than 0.5 m: {s} / {a}"); // measured 5.34 dB
    assert!(a.psnr - l.psnr > 2.92, "the room-sized sphere localises better than 8 m: {a} / {l}"); // measured 3.92 dB
    assert!(a.psnr > 24.32, "auto: {a}"); // measured 25.32 dB
    common::assert_clean(&ctx);
}

/// The survey's Figure 21: a small box in the room makes the environment concave, with
/// view-dependent occlusions a single-layer map cannot represent. The residual error is
/// measured (and bounded 1 dB under it, so a regression shows). With a single specular
/// object the multi-map method has nothing to compose and must render exactly `distance`.
#[test]
fn concave_occluder_residual_is_bounded_and_one_object_needs_no_cycles() {
    let ctx = common::gpu();
    let mut scene = corner_mirror_scene();
    let m = scene.add_material(Material { name: "box".into(), emissive: Vec3::new(0.9, 0.9, 0.2), ..Default::default() }).unwrap();
    for (o, u, v) in [
        (Vec3::new(-0.6, 0.0, -0.2), Vec3::new(0.5, 0.0, 0.0), Vec3::new(0.0, 0.6, 0.0)),
        (Vec3::new(-0.6, 0.0, -0.2), Vec3::new(0.0, 0.6, 0.0), Vec3::new(0.0, 0.0, -0.5)),
        (Vec3::new(-0.1, 0.0, -0.2), Vec3::new(0.0, 0.0, -0.5), Vec3::new(0.0, 0.6, 0.0)),
        (Vec3::new(-0.6, 0.6, -0.2), Vec3::new(0.5, 0.0, 0.0), Vec3::new(0.0, 0.0, -0.5)),
    ] {
        scene.add_mesh(shapes::quad("box", o, u, v, 2, m)).unwrap();
    }
    let size = 80;
    let refimg = reference(&scene, &["spp=4", "depth=2"], size);
    let q = quality(&["cube_size=128", "ref_point=0,2,0"]);
    let single_img = gpu(&ctx, &scene, specula::methods::DISTANCE, &q, size);
    let single = errors(&single_img, &refimg);
    eprintln!("concave: distance {single}");
    // The residual of Figure 21 (what the reference point cannot see): measured 29.57 dB,
    // floor 1 dB below; multi-layer maps (issue 10) are what removes it.
    assert!(single.psnr > 28.57, "{single}"); // measured 29.57 dB

    // With one specular object there is nothing to compose: distance-multi plans no second
    // cycle and renders the same bits as distance.
    let mq = quality(&["cube_size=128", "ref_point=0,2,0", "cycles=2"]);
    let multi_plan = specula::plan(&scene, specula::methods::DISTANCE_MULTI, &mq);
    let multi_img = gpu(&ctx, &scene, specula::methods::DISTANCE_MULTI, &mq, size);
    assert!(multi_img.data == single_img.data, "one specular object: distance-multi equals distance ({} cycles)", multi_plan.cycles);
    common::assert_clean(&ctx);
}

/// A solid glass sphere in the quadrant room, seen in front of a wall.
fn glass_scene(ior: f32) -> Scene {
    let mut s = Scene::new();
    common::emissive_room(&mut s, Vec3::new(0.0, 2.0, 0.0), 2.0);
    let m = s
        .add_material(Material { name: "glass".into(), kind: SurfaceKind::Dielectric { ior, thin: false }, ..Default::default() })
        .unwrap();
    s.add_mesh(shapes::uv_sphere("glass", Vec3::new(0.0, 1.5, 0.0), 0.6, 96, 48, m)).unwrap();
    s.camera = Some(Camera::look_at(Vec3::new(0.3, 1.8, 1.9), Vec3::new(0.0, 1.5, 0.0), 40f32.to_radians()));
    s
}

/// ν = 1.0001 against the reference without the sphere: measured 41.85 dB, floor 1 dB under.
const ALMOST_FLOOR: f64 = 40.85;

/// Self refraction through the refractor map (§4.4) against the reference for ν = 1.5 and
/// ν = 1.1, better than the single-interface distance method; total internal reflection
/// followed inside the sphere changes the image towards the reference; ν → 1 converges
/// to the image without the sphere.
#[test]
fn refractor_map_self_refraction() {
    let ctx = common::gpu();
    let size = 80;
    // Measured here: refractor-map 36.04 and 36.07 dB, image-space refraction 20.27 and
    // 27.74 dB (its second interface is approximated by the back-face depth), refractor-map
    // over the single-interface distance method 14.69 and 12.28 dB: floors 1 dB below.
    // With image_space_iterations=2 (Newton steps of its exit point onto the back faces'
    // depth): 27.40 and 30.99 dB, gains of 7.13 and 3.25 dB: floors 1 dB under.
    for (ior, floor, wyman_floor, margin, newton_gain) in [(1.5f32, 35.04, 19.27, 13.69, 6.13), (1.1, 35.07, 26.74, 11.28, 2.25)] {
        let scene = glass_scene(ior);
        let refimg = reference(&scene, &["spp=4", "depth=8", "fresnel=exact"], size);
        let q = quality(&["cube_size=128", "fresnel=exact", "internal_bounces=4", "linear_steps=16", "secant_steps=4"]);
        let rm = errors(&gpu(&ctx, &scene, specula::methods::REFRACTOR_MAP, &q, size), &refimg);
        let single = errors(&gpu(&ctx, &scene, specula::methods::DISTANCE, &q, size), &refimg);
        let wyman = errors(&gpu(&ctx, &scene, specula::methods::IMAGE_SPACE_REFRACTION, &q, size), &refimg);
        // Newton steps of the exit point onto the back faces' depth (image_space_iterations).
        let mut q2 = q.clone();
        q2.set("image_space_iterations", "2").unwrap();
        let newton = errors(&gpu(&ctx, &scene, specula::methods::IMAGE_SPACE_REFRACTION, &q2, size), &refimg);
        eprintln!(
            "glass ν={ior}: refractor-map {rm}\n           distance {single}\n           image-space {wyman}\n           image-space, 2 iterations {newton}"
        );
        assert!(rm.psnr > floor, "ν={ior}: {rm}");
        assert!(rm.psnr - single.psnr > margin, "ν={ior}: refractor map {rm} vs single interface {single}");
        assert!(wyman.psnr > wyman_floor, "ν={ior}: image-space refraction {wyman}");
        assert!(newton.psnr > wyman.psnr + newton_gain, "ν={ior}: 2 iterations {newton} against the paper's estimate {wyman}");
    }
    // Total internal reflection: in a ν = 1.5 sphere, rays hitting the far side beyond the
    // critical angle (41.8°) reflect; following them (4 bounces) instead of dropping them
    // (0 bounces) brings the image closer to the reference: measured 36.05 against 28.22 dB,
    // a 7.83 dB margin, floor 1 dB under.
    let scene = glass_scene(1.5);
    let refimg = reference(&scene, &["spp=4", "depth=8", "fresnel=exact"], size);
    let none = errors(
        &gpu(&ctx, &scene, specula::methods::REFRACTOR_MAP, &quality(&["cube_size=128", "fresnel=exact", "internal_bounces=0"]), size),
        &refimg,
    );
    let four = errors(
        &gpu(&ctx, &scene, specula::methods::REFRACTOR_MAP, &quality(&["cube_size=128", "fresnel=exact", "internal_bounces=4"]), size),
        &refimg,
    );
    eprintln!("TIR: 0 bounces {none}\n     4 bounces {four}");
    assert!(four.psnr - none.psnr > 6.83, "internal reflections help: {four} vs {none}");
    // ν → 1: the sphere disappears.
    let mut empty = Scene::new();
    common::emissive_room(&mut empty, Vec3::new(0.0, 2.0, 0.0), 2.0);
    empty.camera = glass_scene(1.0001).camera;
    // Against the reference's image of the room without the sphere (not the GPU's own).
    let q = quality(&["cube_size=128", "fresnel=exact"]);
    let without = reference(&empty, &["spp=4", "depth=8", "fresnel=exact"], size);
    let almost = errors(&gpu(&ctx, &glass_scene(1.0001), specula::methods::REFRACTOR_MAP, &q, size), &without);
    eprintln!("ν=1.0001 vs the reference without the sphere: {almost}");
    assert!(almost.psnr > ALMOST_FLOOR, "{almost}");
    common::assert_clean(&ctx);
}

/// Two mirror spheres facing each other (§4.3): inter-object reflections of depth 1 to 4
/// against the reference with the same depth, each depth closer to its reference than the
/// previous depth's image and the depth-1 image are (a method that stops cycling early
/// fails); the frame-latency mode reaches the cycled result after n frames.
///
/// Measured (depth 1, 2, 3, 4): PSNR 30.68, 29.59, 29.84, 29.98 dB; over the previous depth's
/// image 4.93, 0.33, 0.18 dB; over the depth-1 image 4.93, 5.42, 5.59 dB; each cycle changes
/// the image by RMSE 0.0545, 0.00783, 0.00490. Floors 1 dB under, a factor 1.122 under for
/// the changes; the margins over the previous depth under 1 dB (depths 3 and 4, where the
/// third and fourth bounces are dim) are asserted at half their measured value.
#[test]
fn inter_object_reflections_by_cycles_and_by_frame_latency() {
    let ctx = common::gpu();
    let mut scene = Scene::new();
    common::emissive_room(&mut scene, Vec3::new(0.0, 2.0, 0.0), 2.0);
    let m = scene.add_material(common::mirror(0.9)).unwrap();
    scene.add_mesh(shapes::uv_sphere("a", Vec3::new(-0.7, 1.5, 0.0), 0.5, 64, 32, m)).unwrap();
    scene.add_mesh(shapes::uv_sphere("b", Vec3::new(0.7, 1.5, 0.0), 0.5, 64, 32, m)).unwrap();
    scene.camera = Some(Camera::look_at(Vec3::new(0.0, 1.6, 1.8), Vec3::new(0.0, 1.5, 0.0), 55f32.to_radians()));
    let size = 80;
    // Cycle k of the maps shows k specular bounces: the reference at depth k.
    let depth1 = gpu(&ctx, &scene, specula::methods::DISTANCE_MULTI, &quality(&["cube_size=128", "cycles=1"]), size);
    // (depth, PSNR floor, margin over the previous depth's image, over the depth-1 image,
    // RMSE floor of the change from the previous depth's image)
    let bounds =
        [(1, 29.68, 0.0, 0.0, 0.0), (2, 28.59, 3.93, 3.93, 0.0486), (3, 28.84, 0.16, 4.42, 0.00698), (4, 28.98, 0.09, 4.59, 0.00437)];
    let mut prev: Option<ImageData> = None;
    for (depth, floor, over_prev, over_first, change) in bounds {
        let d = format!("depth={depth}");
        let refimg = reference(&scene, &["spp=4", &d], size);
        let img = gpu(&ctx, &scene, specula::methods::DISTANCE_MULTI, &quality(&["cube_size=128", &format!("cycles={depth}")]), size);
        let e = errors(&img, &refimg);
        let stale = errors(&depth1, &refimg);
        eprintln!("depth {depth}: distance-multi {e} (depth-1 image: {:.2} dB)", stale.psnr);
        assert!(e.psnr > floor, "depth {depth}: {e}");
        if depth > 1 {
            assert!(e.psnr - stale.psnr > over_first, "depth {depth}: {e} vs the depth-1 image {stale}");
        }
        if let Some(p) = &prev {
            let (pe, step) = (errors(p, &refimg), errors(&img, p));
            eprintln!("depth {depth}: previous depth's image {pe}; margin {:.2} dB; image change {step}", e.psnr - pe.psnr);
            assert!(e.psnr - pe.psnr > over_prev, "depth {depth}: {e} vs the previous depth's image {pe}");
            assert!(step.rmse > change, "cycle {depth} changes the image: {step}");
        }
        prev = Some(img);
    }
    // Frame latency: one cycle per frame; after n frames the maps hold n cycles.
    let n = 3;
    let cycled = gpu(&ctx, &scene, specula::methods::DISTANCE_MULTI, &quality(&["cube_size=128", "cycles=3"]), size);
    let plan = specula::plan(&scene, specula::methods::DISTANCE_MULTI, &quality(&["cube_size=128", "frame_latency=on"]));
    assert_eq!(plan.cycles, 1);
    let mut r = specula::Renderer::new(&ctx, &scene, plan, size, size).unwrap();
    let mut frames = Vec::new();
    for _ in 0..n {
        frames.push(r.render(&ctx).unwrap().image);
    }
    r.destroy(&ctx);
    let first = errors(&frames[0], &cycled);
    let last = errors(&frames[n - 1], &cycled);
    eprintln!("frame latency: frame 1 {first}\n               frame {n} {last}");
    // The same bits were measured (max |Δ| 0); the first frame is RMSE 0.0551 from the
    // cycled image (floor a factor 1.122 under).
    assert!(last.max_abs < 1e-5, "after {n} frames the latency mode equals {n} cycles: {last}");
    assert!(first.rmse > 0.0492, "the first frame lacks the inter-reflections: {first}");
    common::assert_clean(&ctx);
}

/// Wyman's first pass keeps the refractor's back faces: at the sphere's centre pixel the
/// stored distance is that of the far side (about |eye − centre| + r: where the pixel's ray
/// leaves the sphere), its normal points away (the sphere's normal there). Closed form, the
/// pixel centre's ray against the analytic sphere; what separates them is the tessellation
/// (96×48): the facets lie inside the sphere by at most r·sin²(π/96) = 6.4e-4, bound 6.5e-4
/// (measured 2.7e-4); the interpolated normal is the radial direction of the facet's point
/// (the vertices sit at centre + r·normal), which lies at most 6.4e-4 nearer along a ray
/// 0.025 rad off the sphere's normal: 2.7e-5 rad at most, bound 5e-5 rad (measured 1.2e-5
/// rad). A front face would be 1.2 m nearer and face the camera.
#[test]
fn image_space_first_pass_sees_back_faces() {
    let ctx = common::gpu();
    let scene = glass_scene(1.5);
    let plan = specula::plan(&scene, specula::methods::IMAGE_SPACE_REFRACTION, &quality(&["cube_size=32"]));
    assert_eq!(plan.objects_with(specula::methods::IMAGE_SPACE_REFRACTION), vec![24]);
    let size = 64;
    let mut r = specula::Renderer::new(&ctx, &scene, plan, size, size).unwrap();
    r.render(&ctx).unwrap();
    let map = specula::vk::read_image(&ctx, r.maps().image(&specula::methods::distance::slots::BACKFACES).unwrap()).unwrap();
    let cam = scene.camera.unwrap();
    let (px, py) = (size / 2, size / 2);
    let t = map.texel(0, px, py);
    // The pixel centre's ray (half a pixel off the view axis in x and y) and where it
    // leaves the sphere, in f64.
    let tan = (cam.yfov as f64 * 0.5).tan();
    let dir = cam
        .world_from_camera
        .as_dmat4()
        .transform_vector3(DVec3::new(
            (2.0 * (px as f64 + 0.5) / size as f64 - 1.0) * tan,
            (1.0 - 2.0 * (py as f64 + 0.5) / size as f64) * tan,
            -1.0,
        ))
        .normalize();
    let (eye, centre, radius) = (cam.position.as_dvec3(), DVec3::new(0.0, 1.5, 0.0), 0.6);
    let oc = eye - centre;
    let b = oc.dot(dir);
    let exit = -b + (b * b - (oc.length_squared() - radius * radius)).sqrt();
    let exit_normal = (eye + dir * exit - centre) / radius;
    let n = DVec3::new(t[0] as f64, t[1] as f64, t[2] as f64).normalize();
    let angle = n.cross(exit_normal).length().atan2(n.dot(exit_normal));
    eprintln!(
        "back face: distance {} vs the ray's exit {exit} (Δ {:e}); normal {n}, {angle:e} rad from the sphere's",
        t[3],
        t[3] as f64 - exit
    );
    assert!((t[3] as f64 - exit).abs() < 6.5e-4, "back-face distance {} vs far side {exit}", t[3]); // measured 2.7e-4
    assert!(angle < 5e-5, "back-face normal {n} vs the sphere's {exit_normal}"); // measured 1.2e-5 rad
    r.destroy(&ctx);
    common::assert_clean(&ctx);
}
