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
        ("t_c", f32s(&[0.0, 2.0]), "SCALAR", 2, r#","min":[0],"max":[2]"#.into()),
        // CUBICSPLINE: (in-tangent, value, out-tangent) per key; tangents 0.
        (
            "v_c",
            f32s(&[0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 3.0, 3.0, 3.0, 0.0, 0.0, 0.0]),
            "VEC3",
            6,
            String::new(),
        ),
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

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).length() < 1e-5
}

#[test]
fn every_interpolation_mode_matches_the_closed_form() {
    let dir = std::env::temp_dir().join(format!("specula-anim-{}", std::process::id()));
    let mut s = specula::scene::load(&write_animated(&dir, &[0.0, 1.0])).unwrap();
    assert_eq!(s.meshes.len(), 3);
    assert_eq!(s.animation.as_ref().unwrap().duration, 2.0);
    let q90 = Quat::from_rotation_y(std::f32::consts::FRAC_PI_2);
    for t in [0.0f32, 0.25, 1.0, 1.5, 2.0, 3.0] {
        s.set_time(t).unwrap();
        // LINEAR translation: (0,0,0) → (1,0,0) → (1,2,0), held after the last key.
        let lin = if t <= 1.0 { Vec3::new(t, 0.0, 0.0) } else { Vec3::new(1.0, 2.0 * (t.min(2.0) - 1.0), 0.0) };
        assert!(close(s.meshes[0].positions[1], lin + Vec3::X), "t = {t}: {}", s.meshes[0].positions[1]);
        // STEP rotation: identity before t = 1, 90° about y from then on.
        let r = if t < 1.0 { Quat::IDENTITY } else { q90 };
        assert!(close(s.meshes[1].positions[1], Vec3::new(3.0, 0.0, 0.0) + r * Vec3::X), "t = {t}: {}", s.meshes[1].positions[1]);
        // CUBICSPLINE scale of the parent with zero tangents: 1 + 2 (3u² − 2u³), u = t/2.
        let u = (t / 2.0).min(1.0);
        let k = 1.0 + 2.0 * (3.0 * u * u - 2.0 * u * u * u);
        assert!(close(s.meshes[2].positions[2], k * Vec3::new(0.0, 1.0, 5.0)), "t = {t}: {}", s.meshes[2].positions[2]);
    }
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
    let dir = std::env::temp_dir().join(format!("specula-anim-bad-{}", std::process::id()));
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
    let dir = std::env::temp_dir().join(format!("specula-anim-render-{}", std::process::id()));
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
    let q = specula::Quality { shadow_size: 32, cube_size: 16, ..Default::default() };
    let plan = specula::plan(&scene, specula::methods::ENVMAP, &q);
    let mut r = specula::Renderer::new(&ctx, &scene, plan, 24, 16).unwrap();
    for t in [0.0, 0.5, 1.5] {
        scene.set_time(t).unwrap();
        r.update(&scene).unwrap();
        let got = r.render(&ctx).unwrap();
        let fresh = specula::render(&ctx, &scene, specula::methods::ENVMAP, &q, (24, 16), (0, 1)).unwrap();
        assert!(got.image.data == fresh.image.data, "t = {t}");
        assert!(got.image.data.iter().filter(|v| **v > 0.01).count() > 20, "t = {t}: the triangles are lit and in view");
    }
    r.destroy(&ctx);
    common::assert_clean(&ctx);
    std::fs::remove_dir_all(&dir).ok();
}

/// A node at scale 0 in its static pose that its animation scales up (a pop-in) is imported
/// hidden and appears when the animation gives it a scale.
#[test]
fn a_node_scaled_up_from_zero_appears() {
    let dir = std::env::temp_dir().join(format!("specula-anim-pop-{}", std::process::id()));
    let mut s = specula::scene::load(&write_animated_with(&dir, &[0.0, 1.0], r#","scale":[0,0,0]"#)).unwrap();
    assert_eq!(s.meshes.len(), 3, "the zero-scale node's mesh is imported: {:?}", s.skipped);
    assert!(s.meshes[2].hidden && !s.meshes[0].hidden);
    s.set_time(1.0).unwrap();
    assert!(!s.meshes[2].hidden);
    // Scale 1 + 2 (3u² − 2u³) at u = 1/2: 2.
    assert!(close(s.meshes[2].positions[2], 2.0 * Vec3::new(0.0, 1.0, 5.0)), "{}", s.meshes[2].positions[2]);
    std::fs::remove_dir_all(&dir).ok();
}
