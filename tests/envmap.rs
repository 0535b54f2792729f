//! Classic environment mapping (survey §3, §3.1) against a direct computation, and the
//! Fresnel weight of survey eq. 2. Lavapipe, validation on.

mod common;

use glam::{DVec3, Vec3};
use specula::optics::{fresnel_f0, fresnel_schlick, reflect_dir};
use specula::scene::{shapes, Camera, Scene};
use specula::{plan, Quality, Renderer};

const F0: f32 = 0.3;

/// A mirror sphere (F0 = 0.3) at the centre of the quadrant room, reference point at its
/// centre, camera looking at it. Every pixel on the sphere is predicted on the CPU: hit the
/// analytic sphere, reflect, take the room's colour in the reflected direction from the
/// centre (what environment mapping assumes), weight by Schlick (eq. 2).
/// Unpolarised reflectance of a lossless interface of index n from air at incidence cos θ,
/// from the Fresnel equations written out here (not `specula::optics`).
fn fresnel_equations(n: f64, cos: f64) -> f64 {
    let sin2 = 1.0 - cos * cos;
    let cos_t = (1.0 - sin2 / (n * n)).sqrt();
    let rs = (cos - n * cos_t) / (cos + n * cos_t);
    let rp = (n * cos - cos_t) / (n * cos + cos_t);
    0.5 * (rs * rs + rp * rp)
}

#[test]
fn mirror_sphere_reflects_what_the_reflection_direction_predicts() {
    predict_the_sphere("schlick");
}

/// The same prediction with `fresnel=exact`: every pixel weighted by the Fresnel equations;
/// at mid angles they are 0.02–0.04 above Schlick here, beyond the tolerance, so a shader
/// that ignores the knob fails.
#[test]
fn exact_fresnel_follows_the_fresnel_equations_across_the_sphere() {
    predict_the_sphere("exact");
}

fn predict_the_sphere(fresnel: &str) {
    let ctx = common::gpu();
    let mut scene = Scene::new();
    common::emissive_room(&mut scene, Vec3::ZERO, 2.0);
    let m = scene.add_material(common::mirror(F0)).unwrap();
    scene.add_mesh(shapes::uv_sphere("sphere", Vec3::ZERO, 0.5, 192, 96, m)).unwrap();
    let eye = Vec3::new(0.0, 0.0, 1.5);
    let yfov = 50f32.to_radians();
    scene.camera = Some(Camera::look_at(eye, Vec3::ZERO, yfov));
    let mut q = Quality::default();
    q.set("cube_size", "128").unwrap();
    q.set("fresnel", fresnel).unwrap();
    let p = plan(&scene, specula::methods::ENVMAP, &q);
    assert_eq!(p.envmaps.len(), 1);
    assert_eq!(p.envmaps[0].reference_point, Vec3::ZERO);
    let (w, h) = (96u32, 96u32);
    let mut r = Renderer::new(&ctx, &scene, p, w, h).unwrap();
    let frame = r.render(&ctx).unwrap();

    let nu = ((1.0 + F0.sqrt()) / (1.0 - F0.sqrt())) as f64;
    let f0 = fresnel_f0(nu, 0.0);
    assert!((f0 - F0 as f64).abs() < 1e-6);
    let mut schlick_gap: f64 = 0.0;
    let tan = (yfov as f64 * 0.5).tan();
    let (mut checked, mut bad, mut normal_seen, mut grazing_seen) = (0, 0, false, false);
    for y in 0..h {
        for x in 0..w {
            let d = DVec3::new((2.0 * (x as f64 + 0.5) / w as f64 - 1.0) * tan, (1.0 - 2.0 * (y as f64 + 0.5) / h as f64) * tan, -1.0)
                .normalize();
            let o = eye.as_dvec3();
            // Ray–sphere (radius 0.5 at the origin).
            let b = o.dot(d);
            let disc = b * b - (o.length_squared() - 0.25);
            if disc <= 0.0 {
                continue;
            }
            let hit = o + d * (-b - disc.sqrt());
            let n = hit.normalize();
            let cos = -n.dot(d);
            if cos < 0.15 {
                continue; // the silhouette, where the tessellation shows
            }
            let rdir = reflect_dir(d, n);
            let a = rdir.abs();
            let major = a.max_element();
            let minor = [a.x, a.y, a.z].into_iter().filter(|&c| c != major).fold(f64::INFINITY, f64::min);
            let mid = a.x + a.y + a.z - major - minor;
            // Skip directions within ~3° of an edge between quadrants or walls.
            if minor / major < 0.05 || 1.0 - mid / major < 0.05 {
                continue;
            }
            let (wall, quadrant) = shapes::quadrant_room_hit(rdir.as_vec3());
            let weight = if fresnel == "exact" { fresnel_equations(nu, cos) } else { fresnel_schlick(f0, cos) } as f32;
            schlick_gap = schlick_gap.max((fresnel_equations(nu, cos) - fresnel_schlick(f0, cos)).abs());
            let expected = common::quadrant_color(wall, quadrant) * weight;
            let got = frame.image.texel(0, x, y);
            let err = common::max_diff(got, expected);
            if err > 0.01 * expected.max_element() + 2e-3 {
                bad += 1;
            }
            checked += 1;
            if cos > 0.995 {
                // Normal incidence: the weight is F0 itself (survey eq. 2).
                normal_seen = true;
                let ratio = got[0] / common::quadrant_color(wall, quadrant).x;
                assert!((ratio - F0).abs() < 0.01, "normal incidence: weight {ratio}, F0 {F0}");
            }
            if cos < 0.25 {
                // Towards grazing incidence the weight rises towards 1.
                grazing_seen = true;
                let ratio = got[0] / common::quadrant_color(wall, quadrant).x;
                assert!(ratio > F0 + 0.05 && (ratio - weight).abs() < 0.02, "grazing (cos {cos:.3}): weight {ratio}, {fresnel} {weight}");
            }
        }
    }
    assert!(normal_seen && grazing_seen);
    assert!(checked > 1500, "only {checked} pixels checked");
    assert!(schlick_gap > 0.02, "the two Fresnel modes differ on this sphere by {schlick_gap}");
    // Tolerance: 1 % of the expected value + 0.002; at most 1 % of pixels outside it
    // (texel interpolation next to the skipped edges, half-float storage).
    assert!(bad * 100 <= checked, "{bad} of {checked} sphere pixels differ from the prediction");
    r.destroy(&ctx);
    common::assert_clean(&ctx);
}

/// With the exact Fresnel equations the weight at normal incidence is still F0, and the
/// dielectric branch refracts: a thin-walled ν = 1.0001 pane barely changes anything.
#[test]
fn exact_fresnel_and_refraction_run_clean() {
    let ctx = common::gpu();
    let mut scene = Scene::new();
    common::emissive_room(&mut scene, Vec3::ZERO, 2.0);
    let m = scene.add_material(common::mirror(F0)).unwrap();
    scene.add_mesh(shapes::uv_sphere("sphere", Vec3::ZERO, 0.5, 64, 32, m)).unwrap();
    let glass = scene
        .add_material(specula::scene::Material {
            name: "glass".into(),
            kind: specula::scene::SurfaceKind::Dielectric { ior: 1.5, thin: false },
            ..Default::default()
        })
        .unwrap();
    scene.add_mesh(shapes::uv_sphere("glass", Vec3::new(0.9, 0.0, 0.0), 0.3, 32, 16, glass)).unwrap();
    scene.camera = Some(Camera::look_at(Vec3::new(0.0, 0.0, 1.5), Vec3::ZERO, 1.0));
    let mut q = Quality::default();
    q.set("fresnel", "exact").unwrap();
    q.set("cube_size", "32").unwrap();
    let mut r = Renderer::new(&ctx, &scene, plan(&scene, specula::methods::ENVMAP, &q), 32, 32).unwrap();
    let f = r.render(&ctx).unwrap();
    let centre = f.image.texel(0, 16, 16);
    let wall = common::quadrant_color(4, 0); // +Z wall behind the camera, quadrant (−x, −y)
    assert!((centre[0] / wall.x - F0).abs() < 0.02, "exact Fresnel at normal incidence: {centre:?}");
    assert!(f.image.data.iter().all(|v| v.is_finite()));
    r.destroy(&ctx);
    common::assert_clean(&ctx);
}

/// "Model only what the scene requires": no specular objects → no environment-map pass,
/// no cube map; no lights → no shadow pass, no shadow map.
#[test]
fn only_what_the_scene_requires_is_planned_and_allocated() {
    let ctx = common::gpu();
    let mut scene = Scene::new();
    common::emissive_room(&mut scene, Vec3::ZERO, 2.0);
    scene.camera = Some(Camera::look_at(Vec3::new(0.0, 0.0, 1.5), Vec3::ZERO, 1.0));
    let q = Quality::default();
    let f = specula::render(&ctx, &scene, specula::methods::ENVMAP, &q, (16, 16), (0, 1)).unwrap();
    let names: Vec<_> = f.passes.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(names, ["scene.direct", "frame.readback"]);
    assert!(f.memory.iter().all(|(n, _)| !n.starts_with("envmap") && !n.starts_with("shadow") && n != "scene.lights"), "{:?}", f.memory);

    // A light on a diffuse surface brings its shadow map; still no environment map.
    scene
        .add_light(specula::scene::Light {
            name: "bulb".into(),
            kind: specula::scene::LightKind::Point,
            position: Vec3::new(0.0, 1.0, 0.0),
            direction: Vec3::NEG_Y,
            intensity: Vec3::splat(1.0),
            range: None,
        })
        .unwrap();
    let f = specula::render(&ctx, &scene, specula::methods::ENVMAP, &q, (16, 16), (0, 1)).unwrap();
    let names: Vec<_> = f.passes.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(names, ["shadow.generate", "scene.direct", "frame.readback"]);
    assert!(f.memory.iter().any(|(n, _)| n == "shadow.cubes"));
    assert!(f.memory.iter().all(|(n, _)| !n.starts_with("envmap")));

    // A mirror brings exactly one cube map of cube_size² × 6 texels.
    let m = scene.add_material(common::mirror(0.9)).unwrap();
    scene.add_mesh(shapes::uv_sphere("sphere", Vec3::ZERO, 0.3, 16, 8, m)).unwrap();
    let mut q = Quality::default();
    q.set("cube_size", "64").unwrap();
    let f = specula::render(&ctx, &scene, specula::methods::ENVMAP, &q, (16, 16), (0, 1)).unwrap();
    let names: Vec<_> = f.passes.iter().map(|p| p.name.as_str()).collect();
    // The lit mirror over the floor is a caustic generator (§6): its four passes.
    assert_eq!(
        names,
        [
            "shadow.generate",
            "caustics.receivers",
            "caustics.photons",
            "caustics.triangles",
            "caustics.filter",
            "envmap.generate",
            "scene.direct",
            "caustics.project",
            "envmap.shade",
            "frame.readback"
        ]
    );
    let cubes = f.memory.iter().find(|(n, _)| n == "envmap.cubes").unwrap().1;
    assert!(cubes >= 64 * 64 * 6 * 8, "RGBA16F cube of 64²×6: {cubes} bytes");
    assert!(cubes < 2 * 64 * 64 * 6 * 8);
    common::assert_clean(&ctx);
}

/// An object with no geometry around it sees the environment map: a mirror sphere alone
/// under an equirectangular sky whose upper half is blue and lower half is green reflects
/// blue above its equator's reflection and green below; the background is the sky itself.
#[test]
fn lone_object_sees_the_environment_map() {
    let ctx = common::gpu();
    let mut scene = Scene::new();
    let m = scene.add_material(common::mirror(0.5)).unwrap();
    scene.add_mesh(shapes::uv_sphere("sphere", Vec3::ZERO, 0.5, 64, 32, m)).unwrap();
    let (w, h) = (64u32, 32u32);
    let mut sky = Vec::new();
    // Blue above the horizon, green below; red 0.5 in the half of azimuths u > ½ (dₓ > 0:
    // u = ½ + atan2(dₓ, −d_z)/2π), so that a flipped azimuth shows.
    for y in 0..h {
        for x in 0..w {
            let red = if x >= w / 2 { 0.5 } else { 0.0 };
            sky.extend_from_slice(&if y < h / 2 { [red, 0.0, 1.0, 1.0] } else { [red, 1.0, 0.0, 1.0] });
        }
    }
    scene.set_environment(specula::scene::EnvironmentMap { width: w, height: h, rgba32f: sky }).unwrap();
    scene.camera = Some(Camera::look_at(Vec3::new(0.0, 0.0, 2.0), Vec3::ZERO, 0.9));
    let mut q = Quality::default();
    q.set("cube_size", "32").unwrap();
    let p = plan(&scene, specula::methods::ENVMAP, &q);
    assert_eq!(p.passes, ["scene.upload", "envmap.generate", "scene.direct", "envmap.shade"]);
    let f = specula::render(&ctx, &scene, specula::methods::ENVMAP, &q, (48, 48), (0, 1)).unwrap();
    let px = |x: u32, y: u32| f.image.texel(0, x, y).to_vec();
    // Background corners: the sky straight through.
    assert!(px(1, 1)[2] > 0.99 && px(1, 1)[1] < 0.01, "upper background is blue: {:?}", px(1, 1));
    assert!(px(1, 46)[1] > 0.99 && px(1, 46)[2] < 0.01, "lower background is green: {:?}", px(1, 46));
    // On the sphere, above centre the reflection points up (blue), below it down (green),
    // weighted by Fresnel ≥ F0 = 0.5.
    let (top, bottom) = (px(24, 17), px(24, 31));
    assert!(top[2] >= 0.49 && top[1] < 0.01, "upper sphere reflects the blue sky: {top:?}");
    assert!(bottom[1] >= 0.49 && bottom[2] < 0.01, "lower sphere reflects the green ground: {bottom:?}");
    // Near normal incidence the weight is near F0 = 0.5, not 1 (a missing Fresnel factor).
    assert!(top[2] < 0.75 && bottom[1] < 0.75, "Fresnel-weighted: {top:?} {bottom:?}");
    // Azimuth: the left background and the sphere's left side see dₓ < 0 (no red), the
    // right ones dₓ > 0 (red 0.5, weighted on the sphere).
    assert!(px(1, 24)[0] < 0.01 && px(46, 24)[0] > 0.49, "background azimuth: {:?} {:?}", px(1, 24), px(46, 24));
    let (left, right) = (px(15, 24), px(33, 24));
    assert!(left[0] < 0.01 && right[0] > 0.2 && right[0] < 0.5, "sphere azimuth: left {left:?}, right {right:?}");
    common::assert_clean(&ctx);
}
