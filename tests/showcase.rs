//! Issue 15's showcase scenes (`specula::scenes`, `builtin:NAME` on the command line): on
//! each, the knobs of its family move the error where the method acts, on the specular
//! object's pixels; and a deliberately broken method (`debug_fault=flip_reflection`) shows
//! there and nowhere else.

mod common;

use common::{psnr, split};

use specula::{Quality, Scene};

/// Survey Figure 20's set-up: the mirror ball's reference point at the room's centre, so the
/// distance-map search finds what it reflects. From the crudest search (4 linear steps, no
/// secant step) each knob alone raises the ball's PSNR step by step; one sample per pixel
/// in the reference, so that what is left is the method's error, not aliasing.
#[test]
fn corner_mirror_search_steps_move_the_balls_error() {
    const SIZE: (u32, u32) = (64, 64);
    let ctx = common::gpu();
    let scene = specula::scenes::corner_mirror().unwrap();
    let ball = scene.meshes.iter().position(|m| m.name == "mirror_ball").unwrap();
    assert_eq!(scene.meshes[ball].reference_point, Some(specula::scenes::ROOM_CENTER));
    let mut base = {
        let mut knobs = Quality::default();
        knobs.search.linear_steps = 4;
        knobs.search.secant_steps = 0;
        knobs
    };
    base.set("spp", "1").unwrap();
    let reference = specula::reference::render_reference(&scene, &base, SIZE).unwrap();
    let ids = specula::reference::object_ids(&scene, SIZE).unwrap();
    let measure = |knob: &str, values: &[&str]| -> Vec<(f64, f64)> {
        values
            .iter()
            .map(|v| {
                let mut q = base.clone();
                q.set(knob, v).unwrap();
                let f = specula::render(&ctx, &scene, specula::methods::DISTANCE, &q, SIZE, (0, 1)).unwrap();
                let e = split(&scene, &f.image, &reference, &ids);
                let whole = specula::metrics::compare(&f.image, &reference).unwrap().psnr;
                println!(
                    "{knob}={v}: mirror_ball {:.2} dB, non-specular {:.2} dB, whole {whole:.2} dB",
                    psnr(&e, "mirror_ball"),
                    psnr(&e, "non-specular")
                );
                (psnr(&e, "mirror_ball"), psnr(&e, "non-specular"))
            })
            .collect()
    };
    let secant = measure("secant_steps", &["0", "1", "2", "4", "8"]);
    let linear = measure("linear_steps", &["4", "8", "16", "32"]);
    for (knob, curve) in [("secant_steps", &secant), ("linear_steps", &linear)] {
        // The knob acts on the ball's pixels only.
        assert!(curve.iter().all(|c| c.1 == curve[0].1), "{knob}: non-specular moved {curve:?}");
        for w in curve.windows(2) {
            assert!(w[1].0 >= w[0].0 - 0.01, "{knob}: the ball's error rose {curve:?}");
        }
    }
    let gain = |c: &[(f64, f64)]| c.last().unwrap().0 - c[0].0;
    println!("gains: secant {:.2} dB, linear {:.2} dB", gain(&secant), gain(&linear));
    // Measured on the ball's 2960-odd pixels (64x64, lavapipe): secant_steps 0, 1, 2, 4, 8
    // at 4 linear steps: 12.63, 17.81, 23.93, 29.70, 38.77 dB (steps of 5.18, 6.12, 5.77,
    // 9.07 dB, 26.14 dB in all); linear_steps 4, 8, 16, 32 without secant steps: 12.63,
    // 15.09, 17.84, 22.11 dB (2.46, 2.75, 4.27 dB, 9.48 dB in all); the non-specular
    // pixels 64.33 dB throughout. Each step's margin 1 dB under what was measured, the
    // totals 1 dB under (tests/README.md).
    let steps = |c: &[(f64, f64)]| c.windows(2).map(|w| w[1].0 - w[0].0).collect::<Vec<_>>();
    for (d, bound) in steps(&secant).iter().zip([4.18, 5.12, 4.77, 8.07]) {
        assert!(*d >= bound, "secant_steps: a step of {d:.2} dB < {bound} ({secant:?})");
    }
    for (d, bound) in steps(&linear).iter().zip([1.46, 1.75, 3.27]) {
        assert!(*d >= bound, "linear_steps: a step of {d:.2} dB < {bound} ({linear:?})");
    }
    assert!(gain(&secant) >= 25.14 && gain(&linear) >= 8.48);
    assert!(secant[4].0 >= 37.77 && linear[3].0 >= 21.11, "floors: {secant:?} {linear:?}");
    common::assert_clean(&ctx);
}

/// A broken method shows where it acts: `debug_fault=flip_reflection` traces the distance
/// method's reflected rays backwards, so on the demo scene the specular pixels' PSNR drops
/// and the rest of the image stays the same to the bit.
#[test]
fn a_flipped_reflection_shows_on_the_specular_pixels_only() {
    const SIZE: (u32, u32) = (72, 54);
    let ctx = common::gpu();
    let scene = specula::scene::load(std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/demo/demo.gltf"))).unwrap();
    let mut q = {
        let mut knobs = Quality::default();
        knobs.cube.cube_size = 32;
        knobs.frame.shadow_size = 64;
        knobs.frame.depth = 4;
        knobs
    };
    q.set("caustics", "off").unwrap();
    q.set("spp", "1").unwrap();
    let reference = specula::reference::render_reference(&scene, &q, SIZE).unwrap();
    let ids = specula::reference::object_ids(&scene, SIZE).unwrap();
    let mut out = Vec::new();
    for fault in ["none", "flip_reflection"] {
        let mut q = q.clone();
        q.set("debug_fault", fault).unwrap();
        let f = specula::render(&ctx, &scene, specula::methods::DISTANCE, &q, SIZE, (0, 1)).unwrap();
        let e = split(&scene, &f.image, &reference, &ids);
        for x in &e {
            println!("debug_fault={fault}: {} on {} pixels: {:.2} dB", x.name, x.pixels, x.psnr);
        }
        out.push(e);
    }
    assert_eq!(psnr(&out[0], "non-specular"), psnr(&out[1], "non-specular"), "the rest does not move");
    let drop = psnr(&out[0], "specular") - psnr(&out[1], "specular");
    println!("specular drop {drop:.2} dB");
    // Measured (the demo's 6.5 cd light): the specular pixels 27.43 -> 22.46 dB (the mirror
    // sphere's 28.93 -> 18.01, the glass sphere's reflected part 27.00 -> 26.82), the other
    // 3518 pixels 40.40 dB both times. The 4.97 dB and the mirror's 10.92 dB drops asserted
    // 1 dB under. (At the old 25 cd light: 6.93 and 8.29 dB.)
    assert!(drop >= 3.97, "{drop:.2} dB");
    assert!(psnr(&out[0], "mirror_sphere/0") - psnr(&out[1], "mirror_sphere/0") >= 9.92);
    common::assert_clean(&ctx);
}

/// Survey §4.4 on `glass-1.5`: the refractor map's internal bounces and search steps move the
/// glass ball's error, and image-space refraction (one exit guess) is worse than both.
#[test]
fn glass_ball_internal_bounces_and_steps() {
    const SIZE: (u32, u32) = (64, 64);
    let ctx = common::gpu();
    let scene = specula::scenes::glass_sphere(1.5).unwrap();
    let mut base = Quality::default();
    base.set("spp", "1").unwrap();
    let reference = specula::reference::render_reference(&scene, &base, SIZE).unwrap();
    let ids = specula::reference::object_ids(&scene, SIZE).unwrap();
    let ball = |method: specula::Method, knob: &str, v: &str| {
        let mut q = base.clone();
        q.set(knob, v).unwrap();
        let f = specula::render(&ctx, &scene, method, &q, SIZE, (0, 1)).unwrap();
        let p = psnr(&split(&scene, &f.image, &reference, &ids), "glass_ball");
        println!("{} {knob}={v}: glass_ball {p:.2} dB", method.name());
        p
    };
    let bounces: Vec<f64> = ["0", "1", "2", "4"].iter().map(|v| ball(specula::methods::REFRACTOR_MAP, "internal_bounces", v)).collect();
    let steps: Vec<f64> = ["4", "8", "16"].iter().map(|v| ball(specula::methods::REFRACTOR_MAP, "linear_steps", v)).collect();
    let image_space = ball(specula::methods::IMAGE_SPACE_REFRACTION, "linear_steps", "16");
    println!("bounces {bounces:?}, steps {steps:?}, image-space {image_space:.2}");
    // Measured (64x64, one sample per pixel): internal_bounces 0, 1, 2, 4: 28.12, 37.16,
    // 40.52, 42.40 dB (steps of 9.04, 3.36, 1.88 dB); linear_steps 4, 8, 16: 22.72, 38.02,
    // 40.52 dB (15.30, 2.50 dB); image-space refraction 14.67 dB, 25.85 dB under the
    // refractor map. Every margin 1 dB under what was measured.
    let rises = |c: &[f64]| c.windows(2).map(|w| w[1] - w[0]).collect::<Vec<_>>();
    for (d, bound) in rises(&bounces).iter().zip([8.04, 2.36, 0.88]) {
        assert!(*d >= bound, "internal_bounces: {d:.2} dB < {bound} ({bounces:?})");
    }
    for (d, bound) in rises(&steps).iter().zip([14.30, 1.50]) {
        assert!(*d >= bound, "linear_steps: {d:.2} dB < {bound} ({steps:?})");
    }
    assert!(steps[2] - image_space >= 24.85, "{image_space:.2} vs {:.2} dB", steps[2]);
    common::assert_clean(&ctx);
}

/// `builtin:NAME` wherever a scene path goes; an unknown name lists the known ones.
#[test]
fn builtin_scenes_by_name() {
    for name in specula::scenes::BUILTIN {
        let s = specula::scenes::builtin(name).unwrap().unwrap();
        assert!(s.camera.is_some() && s.specular_meshes().count() >= 1, "{name}");
        s.check_renderable().unwrap();
    }
    assert!(specula::scenes::builtin("nope").is_none());
    let bin = env!("CARGO_BIN_EXE_specula");
    let o = std::process::Command::new(bin).args(["info", "builtin:concave-occluder"]).output().unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success() && text.contains("mirror_ball") && text.contains("box"), "{text}");
    let o = std::process::Command::new(bin).args(["plan", "builtin:nope"]).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{err}");
    for name in specula::scenes::BUILTIN {
        assert!(err.contains(&format!("builtin:{name}")), "{err}");
    }
}

/// Survey Figure 21 on `concave-occluder`: the box hides from the ball's reference point
/// faces the ball reflects, so more search steps stop helping a single distance map while
/// layered maps (§4.5), which keep what lies behind the box, do better.
#[test]
fn concave_occluder_fools_one_distance_map_not_layered_maps() {
    const SIZE: (u32, u32) = (64, 64);
    let ctx = common::gpu();
    let scene = specula::scenes::concave_occluder().unwrap();
    let mut base = Quality::default();
    base.set("spp", "1").unwrap();
    let reference = specula::reference::render_reference(&scene, &base, SIZE).unwrap();
    let ids = specula::reference::object_ids(&scene, SIZE).unwrap();
    let ball = |method: specula::Method, steps: &str| {
        let mut q = base.clone();
        q.set("linear_steps", steps).unwrap();
        let f = specula::render(&ctx, &scene, method, &q, SIZE, (0, 1)).unwrap();
        let p = psnr(&split(&scene, &f.image, &reference, &ids), "mirror_ball");
        println!("{} linear_steps={steps}: mirror_ball {p:.2} dB", method.name());
        p
    };
    let distance: Vec<f64> = ["16", "64"].iter().map(|s| ball(specula::methods::DISTANCE, s)).collect();
    let layered: Vec<f64> = ["16", "64"].iter().map(|s| ball(specula::methods::LAYERED, s)).collect();
    println!("distance {distance:?}, layered {layered:?}");
    // Measured (64x64, one sample per pixel): distance 21.75 -> 22.70 dB from 16 to 64
    // linear steps (0.95 dB: the plateau), layered 25.79 -> 28.32 dB (2.53 dB), 5.62 dB over
    // distance at 64 steps. The plateau bounded 1 dB over what was measured, the margins
    // 1 dB under.
    assert!(distance[1] - distance[0] <= 1.95, "distance gains {:.2} dB", distance[1] - distance[0]);
    assert!(layered[1] - layered[0] >= 1.53, "layered gains {:.2} dB", layered[1] - layered[0]);
    assert!(layered[1] - distance[1] >= 4.62, "layered {:.2} vs distance {:.2} dB", layered[1], distance[1]);
    common::assert_clean(&ctx);
}

/// `specula tradeoff builtin:NAME --each`: one curve per method and swept knob it reads
/// (bvh reads neither: its defaults once), the ball's own PSNR column, and a figure with
/// the ball's panel beside the whole image's.
#[test]
fn tradeoff_each_on_a_builtin_scene() {
    let out = common::scratch_dir("showcase-each");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_specula"))
        .args(["tradeoff", "builtin:corner-mirror", "--size", "32x32", "--warmup", "1", "--frames", "1", "--validate"])
        .args([
            "--method",
            "distance",
            "--method",
            "bvh",
            "-q",
            "spp=1",
            "-q",
            "cube_size=32",
            "-q",
            "linear_steps=4",
            "-q",
            "secant_steps=0",
        ])
        .args(["--sweep", "secant_steps=0,2", "--sweep", "linear_steps=4,16", "--each", "--out", out.to_str().unwrap()])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{text}{}", String::from_utf8_lossy(&o.stderr));
    assert!(text.contains("validation: 0 error(s), 0 warning(s)"), "{text}");
    let csv = std::fs::read_to_string(out.join("tradeoff.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert!(lines[0].contains("psnr_db[mirror_ball]"), "{}", lines[0]);
    let rows: Vec<(&str, &str)> =
        lines[1..].iter().map(|l| l.split_once(',').unwrap()).map(|(m, rest)| (m, rest.split(',').next().unwrap())).collect();
    assert_eq!(
        rows,
        [
            ("distance (secant_steps)", "secant_steps=0"),
            ("distance (secant_steps)", "secant_steps=2"),
            ("distance (linear_steps)", "linear_steps=4"),
            ("distance (linear_steps)", "linear_steps=16"),
            ("bvh", "default")
        ]
    );
    let svg = std::fs::read_to_string(out.join("tradeoff.svg")).unwrap();
    assert!(svg.contains("mirror_ball (its pixels)") && svg.contains("whole image"));
    assert!(image::open(out.join("tradeoff.png")).unwrap().width() > 1000);
    std::fs::remove_dir_all(&out).ok();
}

/// The largest radiance any diffuse texel of `scene` can reach in any view, caustics aside:
/// emission + Σ_lights I · albedo_max / (π d²), d the light's distance to each triangle and
/// albedo_max the brightest texel × base colour of its material (cos θ ≤ 1, shadows only
/// lower it). Returns the bound and the surface that reaches it.
fn radiance_bound(scene: &Scene) -> (f64, String) {
    // The brightest texel of texture t, per channel, linear.
    let brightest = |t: usize| {
        let px = &scene.textures[t].rgba8;
        let max = |k: usize| px.chunks_exact(4).map(|p| specula::scene::srgb_to_linear(p[k]) as f64).fold(0.0, f64::max);
        glam::DVec3::new(max(0), max(1), max(2))
    };
    let mut worst = (0.0f64, String::new());
    for m in &scene.meshes {
        let mat = &scene.materials[m.material];
        if mat.kind != specula::scene::SurfaceKind::Diffuse {
            continue;
        }
        let mut albedo = mat.base_color.as_dvec3();
        let mut emission = mat.emissive.as_dvec3();
        if let Some(t) = mat.base_color_texture {
            albedo *= brightest(t);
        }
        if let Some(t) = mat.emissive_texture {
            emission *= brightest(t);
        }
        for tri in m.indices.chunks_exact(3) {
            let [a, b, c] = [0, 1, 2].map(|k| m.positions[tri[k] as usize].as_dvec3());
            let mut l = emission;
            for light in &scene.lights {
                let i = light.intensity.as_dvec3();
                l += match light.kind {
                    specula::scene::LightKind::Directional => i * albedo / std::f64::consts::PI,
                    _ => {
                        let p = light.position.as_dvec3();
                        i * albedo / (std::f64::consts::PI * specula::plan::facts::point_triangle_distance(p, a, b, c).powi(2))
                    }
                };
            }
            if l.max_element() > worst.0 {
                worst = (l.max_element(), format!("{} ({})", m.name, mat.name));
            }
        }
    }
    worst
}

/// Issue 15 item 3: the bundled scenes' light clips no surface at PNG. The bound above holds
/// in every view; the reference (caustics off: a caustic's focus is the specular effect
/// itself and may exceed 1) confirms it on the demo's own view, reflections included.
#[test]
fn the_bundled_scenes_light_clips_no_surface() {
    for name in ["demo/demo.gltf", "mirrors/mirrors.gltf"] {
        let scene = specula::scene::load(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets").join(name)).unwrap();
        let (bound, surface) = radiance_bound(&scene);
        eprintln!("{name}: diffuse radiance at most {bound:.3} ({surface})");
        assert!(bound <= 1.0, "{name}: '{surface}' can reach radiance {bound:.3}: a PNG clips it");
        let mut q = {
            let mut knobs = Quality::default();
            knobs.reference.spp = 1;
            knobs
        };
        q.set_pair("caustics=off").unwrap();
        let image = specula::reference::render_reference(&scene, &q, (48, 48)).unwrap();
        let max = image.data.chunks_exact(4).map(|p| p[0].max(p[1]).max(p[2])).fold(0.0f32, f32::max);
        eprintln!("{name}: the reference's brightest pixel {max:.3}");
        assert!(max as f64 <= bound + 1e-3, "{name}: the reference reaches {max}, over the bound {bound:.3}");
    }
}

/// A showcase scene at 64² against its 1-spp reference, with the reference's first hits.
struct Setup {
    ctx: common::Gpu,
    scene: Scene,
    base: Quality,
    reference: specula::image::ImageData,
    ids: Vec<u32>,
}

impl Setup {
    const SIZE: (u32, u32) = (64, 64);

    fn new(scene: Scene) -> Setup {
        Setup::sampled(scene, 1)
    }

    /// With `spp` samples a pixel in the reference (a focused caustic needs more than the
    /// pixel's centre: the progressive estimate gathers at the camera paths' hits).
    fn sampled(scene: Scene, spp: u32) -> Setup {
        let base = {
            let mut knobs = Quality::default();
            knobs.reference.spp = spp;
            knobs
        };
        let reference = specula::reference::render_reference(&scene, &base, Self::SIZE).unwrap();
        let ids = specula::reference::object_ids(&scene, Self::SIZE).unwrap();
        Setup { ctx: common::gpu(), scene, base, reference, ids }
    }

    /// PSNR per region of `method` under the knobs `pairs` over the base.
    fn regions(&self, method: specula::Method, pairs: &[&str]) -> Vec<specula::metrics::MaskedError> {
        let mut q = self.base.clone();
        for p in pairs {
            q.set_pair(p).unwrap();
        }
        let f = specula::render(&self.ctx, &self.scene, method, &q, Self::SIZE, (0, 1)).unwrap();
        split(&self.scene, &f.image, &self.reference, &self.ids)
    }
}

/// Survey §5.2 on `convex-mirror`: the curved reflector's geometry image resolution and
/// its search's levels move the ball's error (the environment's tessellation is what lets
/// the room's straight edges bend in it).
#[test]
fn convex_mirror_geometry_image_and_search_move_the_balls_error() {
    let s = Setup::new(specula::scenes::convex_mirror().unwrap());
    let ball = |pairs: &[&str]| {
        let p = psnr(&s.regions(specula::methods::CURVED_REFLECTOR, pairs), "mirror_ball");
        println!("curved-reflector {pairs:?}: mirror_ball {p:.2} dB");
        p
    };
    let image: Vec<f64> = ["geometry_image=16", "geometry_image=128"].iter().map(|p| ball(&[p])).collect();
    let search: Vec<f64> = ["curved_search=0", "curved_search=3"].iter().map(|p| ball(&["geometry_image=32", p])).collect();
    let tess: Vec<f64> = ["tessellation=1", "tessellation=8"].iter().map(|p| ball(&[p])).collect();
    println!("geometry image 16 → 128: {image:?}; search 0 → 3 at 32: {search:?}; tessellation 1 → 8: {tess:?}");
    // Measured (64², one sample per pixel in the reference): geometry image 16 → 128
    // 16.12 → 25.76 dB, tessellation 1 → 8 16.78 → 30.48 dB; each rise asserted at half
    // (rule 1). curved_search trades the other way: 0 levels searches the whole geometry
    // image (21.71 dB at 32²), 3 levels searches every 8th texel first and refines (21.41
    // dB, and faster): the exhaustive search at least as good, by half its 0.30 dB.
    assert!(image[1] - image[0] >= 4.82, "geometry_image: {image:?}");
    assert!(tess[1] - tess[0] >= 6.85, "tessellation: {tess:?}");
    assert!(search[0] - search[1] >= 0.15, "curved_search: {search:?}");
    common::assert_clean(&s.ctx);
}

/// Survey §6 on `caustic-ball`: the caustic is the floor's error (without it the floor
/// misses the focused light), and the photon count moves it; against a 16-sample reference
/// (its progressive estimate resolves the focus, which one sample at the pixel's centre
/// misses).
#[test]
fn caustic_ball_caustics_and_photons_move_the_floors_error() {
    let s = Setup::sampled(specula::scenes::caustic_ball().unwrap(), 16);
    let floor = |pairs: &[&str]| {
        let p = psnr(&s.regions(specula::methods::REFRACTOR_MAP, pairs), "non-specular");
        println!("refractor-map {pairs:?}: the floor {p:.2} dB");
        p
    };
    let modes: Vec<f64> = ["caustics=off", "caustics=splat", "caustics=triangles"].iter().map(|p| floor(&[p])).collect();
    let photons: Vec<f64> = ["photons=32", "photons=128", "photons=512"].iter().map(|p| floor(&[p])).collect();
    println!("off / splat / triangles: {modes:?}; photons 32 / 128 / 512: {photons:?}");
    // Measured (64², refractor-map, the floor's pixels, against the reference at 16 samples a
    // pixel with its converged caustics, the progressive estimate: a focus needs more than the
    // pixel's centre): 29.70 dB without caustics, 33.98 with splats, 35.95 with triangles;
    // photons 32 / 128 / 512: 36.96 / 35.95 / 35.73 dB (fewer photons, larger triangles: the
    // one-sample GPU image's focus is aliased, and a smoother caustic meets the reference's
    // 16 samples better). Against the 3 cm kernel's blur this read 26.54 / 33.36 / 33.36 and
    // photons 33.02 / 33.36 / 33.43. The caustics' 4.28 and 6.25 dB and the photons' 1.23 dB
    // asserted at half (rule 1).
    assert!(modes[1] - modes[0] >= 2.14 && modes[2] - modes[0] >= 3.12, "caustics: {modes:?}");
    assert!((photons[0] - photons[2]).abs() >= 0.61, "photons: {photons:?}");
    common::assert_clean(&s.ctx);
}

/// Survey §5 on `flat-glass`: planar refraction's view budget moves the slab's and the
/// prism's error (each face seen is a view; the budget decides how many get one).
#[test]
fn flat_glass_view_budget_moves_the_faces_error() {
    let s = Setup::new(specula::scenes::flat_glass().unwrap());
    let mut faces = Vec::new();
    for budget in ["mirror_budget=2", "mirror_budget=64"] {
        let e = s.regions(specula::methods::PLANAR_REFRACTION, &[budget]);
        println!("planar-refraction {budget}: slab {:.2} dB, prism {:.2} dB", psnr(&e, "slab"), psnr(&e, "prism"));
        faces.push((psnr(&e, "slab"), psnr(&e, "prism")));
    }
    // Measured (64²): budget 2 → 64 the slab 8.04 → 12.60 dB, the prism 6.47 → 11.79 dB
    // (8 views measure as 2: below 16 no path through the prism reaches an exit view, and
    // a face without a view shows the environment, black here); the rises asserted at half
    // (rule 1).
    assert!(faces[1].0 - faces[0].0 >= 2.28 && faces[1].1 - faces[0].1 >= 2.66, "{faces:?}");
    common::assert_clean(&s.ctx);
}
