//! The CPU reference against a renderer no one here wrote (issue 16): small scenes built
//! here, rendered by `specula::reference` and by Mitsuba 3's path tracer (`scalar_rgb`,
//! installed from PyPI into `target/mitsuba-venv` by scripts/setup.sh; `SPECULA_PYTHON`
//! names another interpreter). The conventions mapping lives in tests/mitsuba/render.py.
//!
//! The scenes keep to light transport both renderers compute: the reference is Whitted-style
//! (perfect specular chains, direct light at diffuse surfaces, no diffuse interreflection),
//! so diffuse surfaces are either emitters of albedo 0 or the only lit diffuse surface in a
//! scene whose other surfaces are black (a path tracer's extra bounces then find nothing).
//! Point lights make caustics unsampleable for Mitsuba's unidirectional path tracer: the
//! caustics test renders with its particle tracer instead and compares the floor's pixels.

mod common;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use glam::Vec3;
use serde_json::json;
use specula::image::ImageData;
use specula::scene::{shapes, Camera, Light, LightKind, Material, Scene, SurfaceKind};
use specula::Quality;

const SIZE: (u32, u32) = (48, 36);

fn python() -> PathBuf {
    if let Some(p) = std::env::var_os("SPECULA_PYTHON") {
        return p.into();
    }
    let venv = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/mitsuba-venv/bin/python");
    assert!(
        venv.exists(),
        "{} is missing: scripts/setup.sh installs Mitsuba 3 there (or set SPECULA_PYTHON to a Python with `mitsuba`)",
        venv.display()
    );
    venv
}

fn dir() -> PathBuf {
    let d = common::scratch_dir("mitsuba");
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn write_obj(path: &Path, m: &specula::scene::Mesh) {
    let mut s = String::new();
    for p in &m.positions {
        let _ = writeln!(s, "v {} {} {}", p.x, p.y, p.z);
    }
    for n in &m.normals {
        let _ = writeln!(s, "vn {} {} {}", n.x, n.y, n.z);
    }
    // Texture coordinates flipped in v (glTF's v = 0 is the image's top row, Mitsuba's
    // bitmap puts it at v = 1: render.py states it).
    for t in &m.uvs {
        let _ = writeln!(s, "vt {} {}", t.x, 1.0 - t.y);
    }
    let uv = m.uvs.len() == m.positions.len();
    for t in m.indices.chunks_exact(3) {
        let [a, b, c] = [t[0] + 1, t[1] + 1, t[2] + 1];
        if uv {
            let _ = writeln!(s, "f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}");
        } else {
            let _ = writeln!(s, "f {a}//{a} {b}//{b} {c}//{c}");
        }
    }
    std::fs::write(path, s).unwrap();
}

/// The scene as render.py reads it.
fn describe(s: &Scene, name: &str, spp: u32, depth: u32) -> serde_json::Value {
    let d = dir();
    let mut meshes = Vec::new();
    for (i, m) in s.meshes.iter().enumerate() {
        let obj = d.join(format!("{name}_{i}.obj"));
        write_obj(&obj, m);
        let mat = &s.materials[m.material];
        let v = |v: Vec3| json!([v.x, v.y, v.z]);
        let bsdf = match mat.kind {
            SurfaceKind::Diffuse if mat.base_color == Vec3::ZERO => json!({ "type": "black" }),
            SurfaceKind::Diffuse => json!({ "type": "diffuse", "reflectance": v(mat.base_color) }),
            SurfaceKind::Mirror { nu, kappa } => json!({ "type": "conductor", "eta": v(nu), "k": v(kappa) }),
            SurfaceKind::Dielectric { ior, thin: false } if mat.absorbs() => {
                json!({ "type": "dielectric", "ior": ior, "sigma_a": v(mat.absorption) })
            }
            SurfaceKind::Dielectric { ior, thin: false } => json!({ "type": "dielectric", "ior": ior }),
            SurfaceKind::Dielectric { ior, thin: true } => json!({ "type": "thindielectric", "ior": ior }),
        };
        let mut e = json!({ "obj": obj.to_str().unwrap(), "bsdf": bsdf });
        if mat.emissive != Vec3::ZERO {
            e["radiance"] = v(mat.emissive);
        }
        if let Some(t) = mat.emissive_texture {
            // The texture's sRGB bytes as a PNG (Mitsuba decodes sRGB to linear as the
            // reference does); the factor must be 1 (Mitsuba's bitmap has no scale).
            assert_eq!(mat.emissive, Vec3::ONE, "render.py takes an emissive texture with factor 1");
            let t = &s.textures[t];
            let png = d.join(format!("{name}_{i}.png"));
            image::RgbaImage::from_raw(t.width, t.height, t.rgba8.clone()).unwrap().save(&png).unwrap();
            e["radiance_texture"] = json!(png.to_str().unwrap());
        }
        meshes.push(e);
    }
    let lights: Vec<_> = s
        .lights
        .iter()
        .map(|l| match l.kind {
            LightKind::Point => json!({ "type": "point", "position": l.position.to_array(), "intensity": l.intensity.to_array() }),
            LightKind::Directional => {
                json!({ "type": "directional", "direction": l.direction.to_array(), "irradiance": l.intensity.to_array() })
            }
            // Mitsuba's spot ramps between beam_width and cutoff_angle by its own curve, not
            // glTF's squared ramp in cos θ: the test compares outside the ramp.
            LightKind::Spot { inner_cone, outer_cone } => json!({
                "type": "spot", "position": l.position.to_array(), "direction": l.direction.to_array(),
                "intensity": l.intensity.to_array(), "beam_deg": inner_cone.to_degrees(), "cutoff_deg": outer_cone.to_degrees(),
            }),
        })
        .collect();
    let cam = s.camera_or_default();
    let forward = -cam.world_from_camera.z_axis.truncate();
    let up = cam.world_from_camera.y_axis.truncate();
    json!({
        "camera": {
            "eye": cam.position.to_array(), "target": (cam.position + forward).to_array(), "up": up.to_array(),
            "yfov_deg": cam.yfov.to_degrees(), "znear": cam.znear, "width": SIZE.0, "height": SIZE.1,
        },
        "meshes": meshes,
        "lights": lights,
        "spp": spp,
        "max_depth": depth + 1,
    })
}

fn mitsuba(s: &Scene, name: &str, spp: u32, depth: u32) -> ImageData {
    mitsuba_with(s, name, spp, depth, "path")
}

/// Mitsuba with `integrator` (render.py: `path` or `ptracer`).
fn mitsuba_with(s: &Scene, name: &str, spp: u32, depth: u32, integrator: &str) -> ImageData {
    let d = dir();
    let (json_path, exr) = (d.join(format!("{name}.json")), d.join(format!("{name}.exr")));
    let mut desc = describe(s, name, spp, depth);
    desc["integrator"] = json!(integrator);
    std::fs::write(&json_path, desc.to_string()).unwrap();
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/mitsuba/render.py");
    let o = std::process::Command::new(python()).arg(&script).arg(&json_path).arg(&exr).output().unwrap();
    assert!(o.status.success(), "mitsuba on {name}: {}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    let e = specula::scene::load_environment(&exr).unwrap();
    ImageData { width: e.width, height: e.height, layers: 1, channels: 4, data: e.rgba32f }
}

fn reference(s: &Scene, depth: u32) -> ImageData {
    let mut q = {
        let mut knobs = Quality::default();
        knobs.frame.depth = depth;
        knobs.reference.spp = 16;
        knobs
    };
    q.set("fresnel", "exact").unwrap();
    specula::reference::render_reference(s, &q, SIZE).unwrap()
}

/// Mitsuba's image has no alpha; compare colour only.
fn psnr(a: &ImageData, b: &ImageData) -> f64 {
    let strip = |i: &ImageData| {
        let mut c = i.clone();
        c.data.chunks_exact_mut(4).for_each(|p| p[3] = 1.0);
        c
    };
    specula::metrics::compare(&strip(a), &strip(b)).unwrap().psnr
}

fn save(name: &str, img: &ImageData) {
    img.write_exr(&dir().join(format!("{name}_specula.exr"))).ok();
}

/// An emissive room of 24 distinct quadrants (albedo 0) around a specular ball, seen from
/// a corner.
fn room_with(material: Material) -> Scene {
    let mut s = Scene::new();
    common::emissive_room(&mut s, Vec3::ZERO, 2.0);
    let m = s.add_material(material).unwrap();
    s.add_mesh(shapes::uv_sphere("ball", Vec3::new(0.2, -0.3, -0.4), 0.8, 96, 48, m)).unwrap();
    s.camera = Some(Camera::look_at(Vec3::new(1.3, 0.9, 1.6), Vec3::new(0.1, -0.3, -0.4), 55f32.to_radians()));
    s
}

#[test]
fn specular_balls_agree_with_mitsuba() {
    let ctx = common::gpu();
    // A gold ball (published n, k at about 650, 550 and 450 nm) and solid glass of two
    // indices: conductor Fresnel with κ > 0, Snell, dielectric Fresnel and total internal
    // reflection along the whole specular chain.
    let gold = Material {
        name: "gold".into(),
        kind: SurfaceKind::Mirror { nu: Vec3::new(0.16, 0.42, 1.37), kappa: Vec3::new(3.6, 2.35, 1.8) },
        ..Default::default()
    };
    let glass =
        |ior: f32| Material { name: format!("glass{ior}"), kind: SurfaceKind::Dielectric { ior, thin: false }, ..Default::default() };
    let thin = Material { name: "thin".into(), kind: SurfaceKind::Dielectric { ior: 1.5, thin: true }, ..Default::default() };
    // Measured here (48×36; the reference at 16 spp, Mitsuba at 256, both deterministic):
    // mirror (F0 0.8, κ 0) 45.1300 dB, gold 46.0580 dB, glass 1.5 46.9140 dB, glass 1.1
    // 47.3426 dB. The GPU's bvh measured 2.00–2.25 dB above the reference (its 4×4 grid is
    // Mitsuba's stratified pattern more nearly than the reference's jitter): 47.1808,
    // 48.3116, 48.9167 and 49.5970 dB.
    // Thin-walled glass differs on purpose, 37.4306 dB (GPU 37.4999 dB): specula follows
    // glTF's thin-walled model (one interface: reflect F, pass 1 − F undeviated), Mitsuba's
    // `thindielectric` a physical slab summing its internal reflections (2F/(1 + F)
    // reflected).
    // Absorbing glass 1.5 (KHR_materials_volume, σ = (0.2, 0.6, 1.5) /m; Mitsuba: a purely
    // absorbing homogeneous medium inside, its volumetric path tracer at 2048 spp, whose
    // absorption is a random event per path: 35.71 dB at 256 spp was its noise): 43.84 dB,
    // GPU 45.05 dB; the same glass without absorption against it 15.41 dB.
    // Every floor is its measured value less 1 dB, rounded down to 0.01 dB.
    for (name, material, floor, gpu_floor) in [
        ("mirror", common::mirror(0.8), 44.13, 46.18),
        ("gold", gold, 45.05, 47.31),
        ("glass1.5", glass(1.5), 45.91, 47.91),
        ("glass1.1", glass(1.1), 46.34, 48.59),
        ("absorbing", Material { absorption: Vec3::new(0.2, 0.6, 1.5), ..glass(1.5) }, 42.84, 44.05),
        ("thin", thin, 36.43, 36.49),
    ] {
        let s = room_with(material);
        let (r, m) = (reference(&s, 16), mitsuba(&s, name, if name == "absorbing" { 2048 } else { 256 }, 16));
        save(name, &r);
        let p = psnr(&r, &m);
        // The GPU's exact ray tracer too (4×4 supersampled, as the reference's 16 samples).
        let mut q = {
            let mut knobs = Quality::default();
            knobs.frame.depth = 16;
            knobs
        };
        q.set("fresnel", "exact").unwrap();
        q.set("aa", "ssaa4").unwrap();
        let gpu = specula::render(&ctx, &s, specula::methods::BVH, &q, SIZE, (0, 1)).unwrap().image;
        let g = psnr(&gpu, &m);
        println!("{name}: reference vs Mitsuba {p:.2} dB, GPU bvh vs Mitsuba {g:.2} dB");
        assert!(p >= floor, "{name}: {p:.2} dB against Mitsuba (floor {floor} dB)");
        if name == "absorbing" {
            // The absorption shows: the same glass without it, against this image.
            let clear = psnr(&reference(&room_with(glass(1.5)), 16), &m);
            println!("absorbing: the reference without absorption vs Mitsuba {clear:.2} dB");
            assert!(clear < p - 10.0, "absorbing: {clear:.2} dB without absorption, {p:.2} dB with it");
        }
        assert!(g >= gpu_floor, "{name}: GPU bvh {g:.2} dB against Mitsuba (floor {gpu_floor} dB)");
    }
    common::assert_clean(&ctx);
}

#[test]
fn direct_light_and_shadows_agree_with_mitsuba() {
    // A diffuse floor, a black occluder, a point light, then a tilted directional light:
    // inverse square, cosine, the light units (W/sr, W/m²) and hard shadows.
    for (name, light) in [
        (
            "point",
            Light {
                name: "l".into(),
                kind: LightKind::Point,
                position: Vec3::new(0.4, 2.0, 0.2),
                direction: Vec3::NEG_Y,
                intensity: Vec3::new(6.0, 5.0, 4.0),
                range: None,
            },
        ),
        (
            "directional",
            Light {
                name: "l".into(),
                kind: LightKind::Directional,
                position: Vec3::ZERO,
                direction: Vec3::new(0.4, -1.0, 0.3).normalize(),
                intensity: Vec3::new(1.5, 1.2, 1.0),
                range: None,
            },
        ),
    ] {
        let s = lit_floor(light);
        let (r, m) = (reference(&s, 4), mitsuba(&s, name, 64, 4));
        save(name, &r);
        let p = psnr(&r, &m);
        println!("{name}: reference vs Mitsuba {p:.2} dB");
        // Measured 55.2441 dB (point) and 50.3122 dB (directional); floors 1 dB below,
        // rounded down to 0.01 dB.
        let floor = if name == "point" { 54.24 } else { 49.31 };
        assert!(p >= floor, "{name}: {p:.2} dB against Mitsuba (floor {floor} dB)");
    }
}

/// The floor, the occluder and the camera of the direct-light scenes.
fn lit_floor(light: Light) -> Scene {
    let mut s = Scene::new();
    let floor = s.add_material(Material { name: "floor".into(), base_color: Vec3::new(0.6, 0.5, 0.4), ..Default::default() }).unwrap();
    s.add_mesh(shapes::quad("floor", Vec3::new(-2.0, 0.0, 2.0), Vec3::new(4.0, 0.0, 0.0), Vec3::new(0.0, 0.0, -4.0), 8, floor)).unwrap();
    let black = s.add_material(Material { name: "occluder".into(), base_color: Vec3::ZERO, ..Default::default() }).unwrap();
    s.add_mesh(shapes::quad("occluder", Vec3::new(-0.4, 0.9, 0.4), Vec3::new(0.8, 0.0, 0.0), Vec3::new(0.0, 0.0, -0.8), 1, black)).unwrap();
    s.add_light(light).unwrap();
    s.camera = Some(Camera::look_at(Vec3::new(0.0, 2.6, 2.4), Vec3::new(0.0, 0.0, -0.2), 55f32.to_radians()));
    s
}

/// A spot light on the floor with the occluder's shadow inside its inner cone. The two
/// renderers' falloffs differ on purpose inside the ramp (render.py): the pixels whose floor
/// point lies within the ramp (between the inner and the outer cone, widened by 2°) are
/// compared apart and their difference stated; everywhere else, inside the inner cone and
/// outside the outer, the images must agree.
#[test]
fn spot_light_agrees_with_mitsuba_outside_its_ramp() {
    let (inner, outer) = (0.55f32, 0.7f32);
    let position = Vec3::new(0.3, 2.0, 0.1);
    let direction = Vec3::new(-0.1, -1.0, -0.1).normalize();
    let s = lit_floor(Light {
        name: "l".into(),
        kind: LightKind::Spot { inner_cone: inner, outer_cone: outer },
        position,
        direction,
        intensity: Vec3::new(6.0, 5.0, 4.0),
        range: None,
    });
    let (r, m) = (reference(&s, 4), mitsuba(&s, "spot", 64, 4));
    save("spot", &r);
    // Each pixel's floor point (y = 0) through its centre, and its angle off the spot's axis.
    let rays = specula::reference::CameraRays::new(&s.camera_or_default(), SIZE.0, SIZE.1);
    let margin = 2f64.to_radians();
    let (mut outside, mut ramp) = ((0.0, 0usize, 0.0f64), (0.0, 0usize));
    for y in 0..SIZE.1 {
        for x in 0..SIZE.0 {
            let (o, d, _) = rays.ray(x as f64 + 0.5, y as f64 + 0.5);
            let t = -o.y / d.y;
            let angle = if t > 0.0 {
                let p = o + d * t;
                (p - position.as_dvec3()).normalize().dot(direction.as_dvec3()).clamp(-1.0, 1.0).acos()
            } else {
                std::f64::consts::PI
            };
            let i = ((y * SIZE.0 + x) * 4) as usize;
            let se: f64 = (0..3).map(|c| ((r.data[i + c] - m.data[i + c]) as f64).powi(2)).sum::<f64>() / 3.0;
            if angle > inner as f64 - margin && angle < outer as f64 + margin {
                ramp = (ramp.0 + se, ramp.1 + 1);
            } else {
                outside = (outside.0 + se, outside.1 + 1, outside.2.max(r.data[i] as f64));
            }
        }
    }
    let db = |se: f64, n: usize| -10.0 * (se / n as f64).log10();
    let (p_out, p_ramp) = (db(outside.0, outside.1), db(ramp.0, ramp.1));
    println!(
        "spot: outside the ramp ({} px, brightest red {:.4}) {p_out:.2} dB, inside it ({} px) {p_ramp:.2} dB",
        outside.1, outside.2, ramp.1
    );
    // Measured 1222 pixels outside the ramp, the brightest red 0.2797 among them (the lit
    // cone), 506 in it; each bound within a factor 1.122.
    assert!(
        outside.1 >= 1090 && ramp.1 >= 451 && outside.2 >= 0.249,
        "the pixels sample the lit cone, the ramp and the dark: {} outside (brightest red {}), {} in the ramp",
        outside.1,
        outside.2,
        ramp.1
    );
    // Measured 54.9404 dB outside the ramp (36.2960 dB inside it); the floor 1 dB below,
    // rounded down to 0.01 dB.
    assert!(p_out >= 53.94, "spot outside its ramp: {p_out:.2} dB against Mitsuba");
}

/// A wall whose emission is a texture (4 × 4 texels of distinct colours, sampled bilinearly
/// with repeat), seen straight and in a mirror ball: texture orientation (u, v and their
/// flips), sRGB decoding and filtering against Mitsuba's bitmap emitter.
#[test]
fn emissive_textured_wall_agrees_with_mitsuba() {
    let mut s = Scene::new();
    let mut rgba8 = Vec::new();
    for k in 0..16u32 {
        rgba8.extend_from_slice(&[(k * 53 % 256) as u8, (k * 97 % 256) as u8, (255 - k * 16) as u8, 255]);
    }
    let t = s.add_texture(specula::scene::Texture { name: "checker".into(), width: 4, height: 4, rgba8 }).unwrap();
    let wall = s
        .add_material(Material {
            name: "wall".into(),
            base_color: Vec3::ZERO,
            emissive: Vec3::ONE,
            emissive_texture: Some(t),
            ..Default::default()
        })
        .unwrap();
    // A 3 × 2 m wall facing +z, towards the camera (Mitsuba's area emitters emit on their
    // front only): u along −x, v down (glTF's image rows top to bottom).
    s.add_mesh(shapes::quad("wall", Vec3::new(1.5, 2.0, -1.0), Vec3::new(-3.0, 0.0, 0.0), Vec3::new(0.0, -2.0, 0.0), 1, wall)).unwrap();
    let m = s.add_material(common::mirror(0.8)).unwrap();
    s.add_mesh(shapes::uv_sphere("ball", Vec3::new(0.6, 0.5, 0.2), 0.35, 64, 32, m)).unwrap();
    s.camera = Some(Camera::look_at(Vec3::new(0.2, 1.0, 2.2), Vec3::new(0.0, 1.0, -1.0), 60f32.to_radians()));
    let (r, mi) = (reference(&s, 4), mitsuba(&s, "textured", 64, 4));
    save("textured", &r);
    let p = psnr(&r, &mi);
    // The GPU's texture sampling too, 4×4 supersampled (2×2 measured 39.6 dB: the wall's and
    // the ball's edges, not the texels).
    let ctx = common::gpu();
    let q = {
        let mut knobs = Quality::default();
        knobs.frame.depth = 4;
        knobs.frame.aa = specula::quality::Aa::Ssaa(4);
        knobs
    };
    let gpu = specula::render(&ctx, &s, specula::methods::BVH, &q, SIZE, (0, 1)).unwrap().image;
    let g = psnr(&gpu, &mi);
    println!("textured wall: reference vs Mitsuba {p:.2} dB, GPU bvh vs Mitsuba {g:.2} dB");
    // Measured 47.0306 dB (the reference) and 44.4849 dB (the GPU); the floors 1 dB below,
    // rounded down to 0.01 dB.
    assert!(p >= 46.03, "textured wall: {p:.2} dB against Mitsuba");
    assert!(g >= 43.48, "textured wall: GPU bvh {g:.2} dB against Mitsuba");
    common::assert_clean(&ctx);
}

/// A glass ball and a mirror wall over a diffuse floor under a point light (issue 34 item 2):
/// the reference's caustics against Mitsuba's particle tracer, on the pixels whose whole
/// footprint is floor, where the caustics add light (the reference with caustics against the
/// same without, over 2 % of the floor's brightest direct light): the region's energy and
/// RMSE. The ball focuses the light into a spot beside its shadow (its focal length, 0.6 m
/// from its centre, ends 0.1 m above the floor); the wall throws the light's mirror image onto
/// the floor, bounded by the wall's outline. The progressive estimate (the reference's
/// converging one) must agree; the fixed kernel (the default) is measured beside it.
/// The CPU reference of the caustic cross-checks: depth 8, exact Fresnel, 4·10⁶ photons in
/// 32 progressive passes, `spp` samples a pixel, the caustics and their estimate as given.
fn caustic_reference(s: &Scene, spp: u32, estimate: &str, caustics: &str) -> ImageData {
    let mut q = Quality::default();
    q.frame.depth = 8;
    q.reference.spp = spp;
    for pair in ["fresnel=exact", "reference_photons=4000000", "ppm_passes=32"] {
        q.set_pair(pair).unwrap();
    }
    q.set("caustic_estimate", estimate).unwrap();
    q.set("caustics", caustics).unwrap();
    specula::reference::render_reference(s, &q, SIZE).unwrap()
}

#[test]
fn caustics_agree_with_mitsubas_particle_tracer() {
    let mut s = Scene::new();
    let floor = s.add_material(Material { name: "floor".into(), base_color: Vec3::splat(0.7), ..Default::default() }).unwrap();
    s.add_mesh(shapes::quad("floor", Vec3::new(-2.0, 0.0, 2.0), Vec3::new(4.0, 0.0, 0.0), Vec3::new(0.0, 0.0, -4.0), 8, floor)).unwrap();
    let glass = s
        .add_material(Material { name: "glass".into(), kind: SurfaceKind::Dielectric { ior: 1.5, thin: false }, ..Default::default() })
        .unwrap();
    s.add_mesh(shapes::uv_sphere("ball", Vec3::new(-0.6, 0.7, -0.2), 0.4, 96, 48, glass)).unwrap();
    let mirror = s.add_material(common::mirror(0.9)).unwrap();
    // A mirror wall at x = 1.1 facing −x (u × v: Mitsuba's conductor reflects on its front
    // only), 1.2 m high, from z = −1.2 to 0.4.
    s.add_mesh(shapes::quad("wall", Vec3::new(1.1, 0.0, 0.4), Vec3::new(0.0, 1.2, 0.0), Vec3::new(0.0, 0.0, -1.6), 1, mirror)).unwrap();
    s.add_light(Light {
        name: "l".into(),
        kind: LightKind::Point,
        position: Vec3::new(0.1, 2.2, 0.0),
        direction: Vec3::NEG_Y,
        intensity: Vec3::new(8.0, 7.5, 7.0),
        range: None,
    })
    .unwrap();
    s.camera = Some(Camera::look_at(Vec3::new(-0.2, 2.6, 2.8), Vec3::new(0.0, 0.0, -0.4), 55f32.to_radians()));
    // 256 samples a pixel: a focused spot smaller than the spacing of 16 samples' floor
    // points is hit by one or two of them, which moved the spot's two pixels by 30 %.
    let reference = |estimate: &str, caustics: &str| caustic_reference(&s, 256, estimate, caustics);
    let (progressive, kernel, off) =
        (reference("progressive", "triangles"), reference("kernel", "triangles"), reference("progressive", "off"));
    let m = mitsuba_with(&s, "caustics", 4096, 8, "ptracer");
    save("caustics", &progressive);
    // The pixels whose whole footprint is floor (4 × 4 first hits each): the particle tracer
    // leaves specular surfaces seen directly black, so a pixel the ball or the wall covers in
    // part differs by construction.
    let fine = specula::reference::object_ids(&s, (SIZE.0 * 4, SIZE.1 * 4)).unwrap();
    let floor_id = 1; // mesh 0 + 1
    let all_floor = |p: usize| {
        let (x, y) = (p % SIZE.0 as usize, p / SIZE.0 as usize);
        (0..16).all(|k| fine[(y * 4 + k / 4) * SIZE.0 as usize * 4 + x * 4 + k % 4] == floor_id)
    };
    let pixels: Vec<usize> = (0..(SIZE.0 * SIZE.1) as usize).filter(|&p| all_floor(p)).collect();
    let lum = |img: &ImageData, p: usize| (0..3).map(|c| img.data[p * 4 + c] as f64).sum::<f64>() / 3.0;
    let brightest_direct = pixels.iter().map(|&p| lum(&off, p)).fold(0.0, f64::max);
    let caustic: Vec<usize> = pixels.iter().copied().filter(|&p| lum(&progressive, p) - lum(&off, p) > 0.02 * brightest_direct).collect();
    // Mitsuba's caustic energy over the reference's, the RMSE over the caustics' mean, and
    // the whole floor's PSNR.
    let measure = |r: &ImageData| {
        let se = |p: usize| (0..3).map(|c| ((r.data[p * 4 + c] - m.data[p * 4 + c]) as f64).powi(2)).sum::<f64>() / 3.0;
        let energy = |img: &ImageData| caustic.iter().map(|&p| lum(img, p) - lum(&off, p)).sum::<f64>();
        let rmse = (caustic.iter().map(|&p| se(p)).sum::<f64>() / caustic.len() as f64).sqrt();
        let floor = -10.0 * (pixels.iter().map(|&p| se(p)).sum::<f64>() / pixels.len() as f64).log10();
        (energy(&m) / energy(r), rmse / (energy(r) / caustic.len() as f64), floor)
    };
    let (p, k) = (measure(&progressive), measure(&kernel));
    println!(
        "caustics: {} caustic pixels of {} floor pixels; Mitsuba's caustic energy / the reference's {:.4} (kernel {:.4}), \
         RMSE {:.4} of the caustics' mean (kernel {:.4}); the whole floor {:.2} dB (kernel {:.2} dB)",
        caustic.len(),
        pixels.len(),
        p.0,
        k.0,
        p.1,
        k.1,
        p.2,
        k.2
    );
    assert!(caustic.len() >= 100, "the caustics cover {} floor pixels: the scene does not show them", caustic.len());
    assert!((p.0 - 1.0).abs() <= 0.04, "Mitsuba's caustic energy is {:.4} of the reference's", p.0);
    assert!(p.1 <= 0.3, "the caustics' RMSE is {:.4} of their mean", p.1);
    // Measured (the adaptive start): energy 1.0259, RMSE 0.2659 of the mean, the floor
    // 33.74 dB; the kernel 0.9935, 0.4573, 29.06 dB.
    assert!(p.2 >= 32.74, "the floor: {:.2} dB against Mitsuba", p.2);
    assert!(p.1 < 0.7 * k.1, "the progressive estimate ({:.4}) is not clearly nearer Mitsuba than the kernel's ({:.4})", p.1, k.1);
}

/// Issue 34: on `caustic-ball` (a glass ball resting on the floor) the kernel and the
/// progressive estimates disagree near the ball (BENCHMARKS.md); on the pixels whose whole
/// footprint is floor, Mitsuba's particle tracer puts almost no caustic light, and neither
/// reference nor any GPU filter may add enough there to move the floor's PSNR against it by
/// half a dB below caustics off. Measured (48×36): the references 40.40 (progressive) and
/// 41.96 dB (kernel) against 39.97 without caustics; the GPU (bvh) 38.56 off, 38.59 splat,
/// 38.59 triangles, 38.75 photon map. On the 44 floor pixels (by their centre) whose footprint
/// touches the ball, Mitsuba does put caustic light (energy 0.447; the progressive estimate
/// 0.505, the kernel 0.648; against Mitsuba 33.60 dB progressive, 40.04 kernel, 20.90 without
/// caustics): both references see the contact's caustic. Run by hand (`cargo test --test
/// mitsuba -- --ignored`): 17 s beside the CI's budget.
#[test]
#[ignore]
fn caustic_ball_against_mitsubas_particle_tracer() {
    let s = specula::scenes::caustic_ball().unwrap();
    let reference = |estimate: &str, caustics: &str| caustic_reference(&s, 64, estimate, caustics);
    let (progressive, kernel, off) =
        (reference("progressive", "triangles"), reference("kernel", "triangles"), reference("progressive", "off"));
    let m = mitsuba_with(&s, "caustic-ball", 4096, 8, "ptracer");
    let fine = specula::reference::object_ids(&s, (SIZE.0 * 4, SIZE.1 * 4)).unwrap();
    let all_floor = |p: usize| {
        let (x, y) = (p % SIZE.0 as usize, p / SIZE.0 as usize);
        (0..16).all(|k| fine[(y * 4 + k / 4) * SIZE.0 as usize * 4 + x * 4 + k % 4] == 1)
    };
    let pixels: Vec<usize> = (0..(SIZE.0 * SIZE.1) as usize).filter(|&p| all_floor(p)).collect();
    let lum = |img: &ImageData, p: usize| (0..3).map(|c| img.data[p * 4 + c] as f64).sum::<f64>() / 3.0;
    let energy = |img: &ImageData| pixels.iter().map(|&p| lum(img, p) - lum(&off, p)).sum::<f64>();
    let floor = |r: &ImageData| {
        let se = |p: usize| (0..3).map(|c| ((r.data[p * 4 + c] - m.data[p * 4 + c]) as f64).powi(2)).sum::<f64>() / 3.0;
        -10.0 * (pixels.iter().map(|&p| se(p)).sum::<f64>() / pixels.len() as f64).log10()
    };
    println!(
        "caustic-ball, {} floor pixels: caustic energy on the visible floor: Mitsuba {:.3}, progressive {:.3}, kernel {:.3}; \
         the floor against Mitsuba: progressive {:.2} dB, kernel {:.2} dB, caustics off {:.2} dB",
        pixels.len(),
        energy(&m),
        energy(&progressive),
        energy(&kernel),
        floor(&progressive),
        floor(&kernel),
        floor(&off)
    );
    assert!(floor(&progressive) >= floor(&off) - 0.5 && floor(&kernel) >= floor(&off) - 0.5, "the references' caustics on the floor");
    {
        let centre = specula::reference::object_ids(&s, SIZE).unwrap();
        let edge: Vec<usize> = (0..(SIZE.0 * SIZE.1) as usize).filter(|&p| centre[p] == 1 && !all_floor(p)).collect();
        let psnr = |r: &ImageData| {
            let se = |p: usize| (0..3).map(|c| ((r.data[p * 4 + c] - m.data[p * 4 + c]) as f64).powi(2)).sum::<f64>() / 3.0;
            -10.0 * (edge.iter().map(|&p| se(p)).sum::<f64>() / edge.len() as f64).log10()
        };
        let e = |img: &ImageData| edge.iter().map(|&p| lum(img, p) - lum(&off, p)).sum::<f64>();
        println!(
            "the {} floor pixels whose footprint touches the ball: caustic energy Mitsuba {:.3}, progressive {:.3}, kernel {:.3}; \
             against Mitsuba progressive {:.2} dB, kernel {:.2} dB, caustics off {:.2} dB",
            edge.len(),
            e(&m),
            e(&progressive),
            e(&kernel),
            psnr(&progressive),
            psnr(&kernel),
            psnr(&off)
        );
    }
    let ctx = common::gpu();
    let mut gpu_off = f64::NAN;
    for c in ["off", "splat", "triangles", "photon-map"] {
        let mut q = Quality::default();
        q.set_pair("fresnel=exact").unwrap();
        q.set("caustics", c).unwrap();
        let img = specula::render(&ctx, &s, specula::methods::BVH, &q, SIZE, (0, 1)).unwrap().image;
        let f = floor(&img);
        println!("GPU bvh caustics={c}: caustic energy on the visible floor {:.3}, the floor against Mitsuba {f:.2} dB", energy(&img));
        if c == "off" {
            gpu_off = f;
        }
        assert!(f >= gpu_off - 0.5, "caustics={c}: the floor {f:.2} dB against Mitsuba, {gpu_off:.2} without caustics");
    }
    common::assert_clean(&ctx);
}
