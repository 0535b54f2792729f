//! glTF animations: a file written here with one channel per interpolation mode (LINEAR
//! translation, STEP rotation, CUBICSPLINE scale on a parent node), sampled at key times and
//! between keys against the closed form; malformed samplers name their field; an animated
//! scene renders through renderer updates like any moved scene.

mod common;

use std::path::{Path, PathBuf};

use glam::{Quat, Vec3};

fn f32s(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// The CUBICSPLINE scale channel's key times: a key interval t_d = 1.5 s that starts at
/// 0.5 s, so that a sampler that forgets to scale the tangents by t_d, or to start the
/// interval at its first key, is off.
const CUBIC_TIMES: [f32; 2] = [0.5, 2.0];
/// Its keys, (in-tangent a, value v, out-tangent b) each: all tangents non-zero and distinct
/// (per key, per component), so that a sampler that ignores them, swaps in- and out-tangents
/// or takes another key's is off. Key 0's in-tangent and key 1's out-tangent play no part
/// in [0.5, 2]. Key 0's value is the node's static scale (1): the loaded pose is t = 0's.
const CUBIC_KEYS: [[Vec3; 3]; 2] = [
    [Vec3::new(-7.0, -6.0, -5.0), Vec3::new(1.0, 1.0, 1.0), Vec3::new(2.0, 1.0, 0.5)],
    [Vec3::new(-1.0, 0.5, 3.0), Vec3::new(3.0, 2.5, 3.5), Vec3::new(9.0, 8.0, 7.0)],
];

/// The CUBICSPLINE channel at time `t`, as glTF 2.0's Appendix C states it: with
/// t_d = t_{k+1} − t_k and s = (t − t_k)/t_d,
/// p(s) = (2s³ − 3s² + 1) v_k + t_d (s³ − 2s² + s) b_k + (−2s³ + 3s²) v_{k+1} + t_d (s³ − s²) a_{k+1};
/// the first key's value before it, the last key's after.
fn cubic_scale(t: f32) -> Vec3 {
    let [[_, v0, b0], [a1, v1, _]] = CUBIC_KEYS;
    let (t0, t1) = (CUBIC_TIMES[0], CUBIC_TIMES[1]);
    if t <= t0 {
        return v0;
    }
    if t >= t1 {
        return v1;
    }
    let td = t1 - t0;
    let s = (t - t0) / td;
    let (s2, s3) = (s * s, s * s * s);
    (2.0 * s3 - 3.0 * s2 + 1.0) * v0 + td * (s3 - 2.0 * s2 + s) * b0 + (-2.0 * s3 + 3.0 * s2) * v1 + td * (s3 - s2) * a1
}

/// Writes `dir/anim.gltf` + `anim.bin`; `times_b` are the STEP channel's key times.
fn write_animated(dir: &Path, times_b: &[f32]) -> PathBuf {
    write_animated_with(dir, times_b, "")
}

/// As `write_animated`, with extra JSON members on node 3 (the scaled parent).
fn write_animated_with(dir: &Path, times_b: &[f32], node3: &str) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    let q90 = Quat::from_rotation_y(std::f32::consts::FRAC_PI_2);
    // (name, bytes, accessor type, count, extra JSON)
    let parts: Vec<(&str, Vec<u8>, &str, usize, String)> = vec![
        ("positions", f32s(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]), "VEC3", 3, r#","min":[0,0,0],"max":[1,1,0]"#.into()),
        ("t_a", f32s(&[0.0, 1.0, 2.0]), "SCALAR", 3, r#","min":[0],"max":[2]"#.into()),
        ("v_a", f32s(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 2.0, 0.0]), "VEC3", 3, String::new()),
        ("t_b", f32s(times_b), "SCALAR", times_b.len(), String::new()),
        ("v_b", f32s(&[0.0, 0.0, 0.0, 1.0, q90.x, q90.y, q90.z, q90.w]), "VEC4", 2, String::new()),
        ("t_c", f32s(&CUBIC_TIMES), "SCALAR", 2, r#","min":[0.5],"max":[2]"#.into()),
        // CUBICSPLINE: (in-tangent, value, out-tangent) per key.
        ("v_c", f32s(&CUBIC_KEYS.iter().flatten().flat_map(|v| v.to_array()).collect::<Vec<f32>>()), "VEC3", 6, String::new()),
    ];
    let mut bin = Vec::new();
    let mut views = Vec::new();
    let mut accessors = Vec::new();
    for (i, (_, bytes, ty, count, extra)) in parts.iter().enumerate() {
        views.push(format!(r#"{{"buffer":0,"byteOffset":{},"byteLength":{}}}"#, bin.len(), bytes.len()));
        accessors.push(format!(r#"{{"bufferView":{i},"componentType":5126,"count":{count},"type":"{ty}"{extra}}}"#));
        bin.extend_from_slice(bytes);
    }
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0,1,3]}}],
"nodes":[{{"mesh":0}},{{"mesh":0,"translation":[3,0,0]}},{{"mesh":0,"translation":[0,0,5]}},{{"children":[2]{node3}}}],
"meshes":[{{"name":"tri","primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
"animations":[{{"channels":[{{"sampler":0,"target":{{"node":0,"path":"translation"}}}},{{"sampler":1,"target":{{"node":1,"path":"rotation"}}}},{{"sampler":2,"target":{{"node":3,"path":"scale"}}}}],
"samplers":[{{"input":1,"output":2,"interpolation":"LINEAR"}},{{"input":3,"output":4,"interpolation":"STEP"}},{{"input":5,"output":6,"interpolation":"CUBICSPLINE"}}]}}],
"buffers":[{{"uri":"anim.bin","byteLength":{}}}],"bufferViews":[{}],"accessors":[{}]}}"#,
        bin.len(),
        views.join(","),
        accessors.join(",")
    );
    std::fs::write(dir.join("anim.bin"), bin).unwrap();
    let path = dir.join("anim.gltf");
    std::fs::write(&path, json).unwrap();
    path
}

/// Tolerance on a posed vertex (|Δ| in m): the f32 rounding of the sampler's arithmetic and
/// of the world transform it composes (node → parent, scale, rotation, translation), one
/// ulp of the largest coordinate (17.5 m: 1.9e-6); measured worst 1.8e-7 (printed by
/// `every_interpolation_mode_matches_the_closed_form`).
const TOL: f32 = 2e-6;

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).length() < TOL
}

#[test]
fn every_interpolation_mode_matches_the_closed_form() {
    let dir = common::scratch_dir("anim");
    let mut s = specula::scene::load(&write_animated(&dir, &[0.0, 1.0])).unwrap();
    assert_eq!(s.meshes.len(), 3);
    assert_eq!(s.animation.as_ref().unwrap().duration, 2.0);
    let q90 = Quat::from_rotation_y(std::f32::consts::FRAC_PI_2);
    let mut worst = 0.0f32;
    let mut check = |got: Vec3, want: Vec3, what: &str, t: f32| {
        worst = worst.max((got - want).length());
        assert!(close(got, want), "{what}, t = {t}: {got} vs {want}");
    };
    for t in [0.0f32, 0.25, 0.75, 1.0, 1.5, 1.75, 2.0, 3.0] {
        s.set_time(t).unwrap();
        // LINEAR translation: (0,0,0) → (1,0,0) → (1,2,0), held after the last key.
        let lin = if t <= 1.0 { Vec3::new(t, 0.0, 0.0) } else { Vec3::new(1.0, 2.0 * (t.min(2.0) - 1.0), 0.0) };
        check(s.meshes[0].positions[1], lin + Vec3::X, "LINEAR", t);
        // STEP rotation: identity before t = 1, 90° about y from then on.
        let r = if t < 1.0 { Quat::IDENTITY } else { q90 };
        check(s.meshes[1].positions[1], Vec3::new(3.0, 0.0, 0.0) + r * Vec3::X, "STEP", t);
        // CUBICSPLINE scale of the parent (per component: vertices (1, 0, 5) and (0, 1, 5)
        // of the child translated by (0, 0, 5) see x, y and z).
        let k = cubic_scale(t);
        check(s.meshes[2].positions[1], k * Vec3::new(1.0, 0.0, 5.0), "CUBICSPLINE", t);
        check(s.meshes[2].positions[2], k * Vec3::new(0.0, 1.0, 5.0), "CUBICSPLINE", t);
    }
    eprintln!("posed vertices against the closed forms: worst |Δ| {worst:e} m (tolerance {TOL:e})");
    // Back to t = 0: the loaded pose, exactly.
    let rest = specula::scene::load(&dir.join("anim.gltf")).unwrap();
    s.set_time(0.0).unwrap();
    for (a, b) in s.meshes.iter().zip(&rest.meshes) {
        assert_eq!(a.positions, b.positions, "{}", a.name);
    }
    assert!(s.set_time(-1.0).unwrap_err().to_string().contains("≥ 0"));
    assert!(s.set_time(f32::NAN).is_err());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn malformed_samplers_name_their_field() {
    let dir = common::scratch_dir("anim-bad");
    let e = specula::scene::load(&write_animated(&dir, &[1.0, 1.0])).unwrap_err().to_string();
    assert!(e.contains("animations[0].channels[1].sampler.input") && e.contains("must increase"), "{e}");
    let e = specula::scene::load(&write_animated(&dir, &[0.0, f32::NAN])).unwrap_err().to_string();
    assert!(e.contains("animations[0].channels[1].sampler.input") && e.contains("finite"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

/// An animated glTF scene over frames: each posed frame through `Renderer::update` equals a
/// fresh render of the scene posed at that time.
#[test]
fn animated_frames_render_like_fresh_ones() {
    let dir = common::scratch_dir("anim-render");
    let mut scene = specula::scene::load(&write_animated(&dir, &[0.0, 1.0])).unwrap();
    scene.camera = Some(specula::scene::Camera::look_at(Vec3::new(1.0, 2.0, 9.0), Vec3::new(1.0, 1.0, 0.0), 1.0));
    let light = specula::scene::Light {
        name: "lamp".into(),
        kind: specula::scene::LightKind::Point,
        position: Vec3::new(1.0, 1.0, 8.0),
        direction: Vec3::NEG_Z,
        intensity: Vec3::splat(50.0),
        range: None,
    };
    scene.add_light(light).unwrap();
    let ctx = common::gpu();
    let q = {
        let mut knobs = specula::Quality::default();
        knobs.frame.shadow_size = 32;
        knobs.cube.cube_size = 16;
        knobs
    };
    let plan = specula::plan(&scene, specula::methods::ENVMAP, &q);
    let mut r = specula::Renderer::new(&ctx, &scene, plan, 24, 16).unwrap();
    // (t, pixels lit as measured, pixels changed from the previous frame as measured): the
    // three triangles are small at 24 × 16 (12 pixels at t = 0); at t = 1.5 the rotated one
    // is edge-on and the scaled one behind the camera, one pixel of the translated one is
    // left. Floors within a factor 1.122 of the measured counts; each frame changes, so
    // that an update that drops the pose fails the comparison with a fresh render.
    let mut previous: Option<Vec<f32>> = None;
    for (t, lit_measured, changed_measured) in [(0.0, 12, 0), (0.5, 12, 4), (1.5, 1, 13)] {
        scene.set_time(t).unwrap();
        r.update(&scene).unwrap();
        let got = r.render(&ctx).unwrap();
        let fresh = specula::render(&ctx, &scene, specula::methods::ENVMAP, &q, (24, 16), (0, 1)).unwrap();
        assert!(got.image.data == fresh.image.data, "t = {t}");
        // Pixels with some radiance (alpha, 1 everywhere, is not counted).
        let lit = got.image.data.chunks(4).filter(|p| p[..3].iter().any(|v| *v > 0.01)).count();
        let changed = previous.as_ref().map_or(0, |p| p.chunks(4).zip(got.image.data.chunks(4)).filter(|(a, b)| a != b).count());
        eprintln!("t = {t}: {lit} of {} pixels lit, {changed} changed from the previous frame", 24 * 16);
        assert!(lit as f64 >= lit_measured as f64 / 1.122, "t = {t}: the triangles are lit and in view: {lit} pixels");
        assert!(changed as f64 >= changed_measured as f64 / 1.122, "t = {t}: the pose changes the image: {changed} pixels");
        previous = Some(got.image.data);
    }
    r.destroy(&ctx);
    common::assert_clean(&ctx);
    std::fs::remove_dir_all(&dir).ok();
}

/// A node at scale 0 in its static pose that its animation scales up (a pop-in) is imported
/// hidden and appears when the animation gives it a scale.
#[test]
fn a_node_scaled_up_from_zero_appears() {
    let dir = common::scratch_dir("anim-pop");
    let mut s = specula::scene::load(&write_animated_with(&dir, &[0.0, 1.0], r#","scale":[0,0,0]"#)).unwrap();
    assert_eq!(s.meshes.len(), 3, "the zero-scale node's mesh is imported: {:?}", s.skipped);
    assert!(s.meshes[2].hidden && !s.meshes[0].hidden);
    s.set_time(1.0).unwrap();
    assert!(!s.meshes[2].hidden);
    // The CUBICSPLINE scale at t = 1 (s = 1/3).
    assert!(close(s.meshes[2].positions[2], cubic_scale(1.0) * Vec3::new(0.0, 1.0, 5.0)), "{}", s.meshes[2].positions[2]);
    std::fs::remove_dir_all(&dir).ok();
}
