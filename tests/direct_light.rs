//! Non-specular shading: emission + Lambertian direct light with shadows, in the units the
//! README states (a punctual light's glTF intensity used 1:1 as W/sr or W/m²).

mod common;

use glam::Vec3;
use specula::scene::{shapes, Camera, Light, LightKind, Material, Scene};
use specula::Quality;

/// The floor's albedo and the lights' colour, a different value per channel, so that a bug
/// on one channel's path (a channel dropped, swapped or taken from another) shows: every
/// closed form below is checked on red, green and blue.
const ALBEDO: Vec3 = Vec3::new(0.5, 0.3, 0.7);
const COLOUR: Vec3 = Vec3::new(1.0, 0.6, 0.3);

/// The largest relative error over the three channels of `got` against `expected` (whose
/// channels are all > 0).
fn rel_err(got: &[f32], expected: Vec3) -> f32 {
    (0..3).map(|k| (got[k] - expected[k]).abs() / expected[k]).fold(0.0, f32::max)
}

/// The relative error over the channels of a lit point (`expected` > 0), or the absolute
/// error of an unlit one (`expected` = 0): (relative, absolute).
fn errors(got: &[f32], expected: Vec3) -> (f32, f32) {
    if expected.min_element() > 0.0 {
        (rel_err(got, expected), 0.0)
    } else {
        (0.0, common::max_diff(got, expected))
    }
}

/// Relative tolerance of the closed forms at a point or directional light's lit points:
/// the f32 rounding of the shader's arithmetic and of this test's (the interpolated floor
/// position, the inverse square and cosine), 10× the worst measured: 1.5e-7 (point light),
/// 1.5e-7 (directional, shadow test).
const TOL: f32 = 2e-6;
/// The same where a spot ramp or a range window multiplies in: their f32 rounding is
/// amplified by the cancellation in cos θ·scale + offset and 1 − (d/range)⁴ near the cone's
/// edge and the range; 10× the worst measured: 2.8e-6 (spot, reference), 2.6e-6 (range
/// window, GPU).
const TOL_RAMP: f32 = 3e-5;
/// Outside the spot's outer cone and beyond the range, both clamp the factor to exactly 0:
/// measured 0 on the GPU and in the reference.
const ABS_TOL: f32 = 0.0;

/// Lambert's BRDF times the light's colour: the radiance per unit irradiance, per channel.
fn lambert() -> Vec3 {
    ALBEDO * COLOUR / std::f32::consts::PI
}

/// A 4 m floor at y = 0 seen from straight above, an optional 0.4 m occluder at y = 1.
fn floor_scene(occluder: bool) -> Scene {
    let mut s = Scene::new();
    let floor = s.add_material(Material { name: "floor".into(), base_color: ALBEDO, ..Default::default() }).unwrap();
    s.add_mesh(shapes::quad("floor", Vec3::new(-2.0, 0.0, 2.0), Vec3::new(4.0, 0.0, 0.0), Vec3::new(0.0, 0.0, -4.0), 4, floor)).unwrap();
    if occluder {
        let m = s.add_material(Material { name: "occluder".into(), base_color: Vec3::ZERO, ..Default::default() }).unwrap();
        s.add_mesh(shapes::quad("occluder", Vec3::new(-0.2, 1.0, 0.2), Vec3::new(0.4, 0.0, 0.0), Vec3::new(0.0, 0.0, -0.4), 1, m)).unwrap();
    }
    let mut cam = Camera::look_at(Vec3::new(0.0, 3.0, 0.0), Vec3::ZERO, 60f32.to_radians());
    cam.znear = 0.05;
    s.camera = Some(cam);
    s
}

fn light(kind: LightKind, position: Vec3, direction: Vec3, intensity: f32) -> Light {
    Light { name: "l".into(), kind, position, direction, intensity: COLOUR * intensity, range: None }
}

/// Radiance of the floor point under pixel (x, y) of a 64² render from 3 m above.
fn floor_point(x: u32, y: u32) -> Vec3 {
    let tan = (30f32).to_radians().tan();
    let ndc_x = (2.0 * (x as f32 + 0.5) / 64.0 - 1.0) * tan;
    let ndc_y = (1.0 - 2.0 * (y as f32 + 0.5) / 64.0) * tan;
    // Camera looks down −Y with up −Z (look_at's fallback): right is +X, up is −Z.
    Vec3::new(ndc_x * 3.0, 0.0, -ndc_y * 3.0)
}

#[test]
fn point_light_follows_inverse_square_and_cosine() {
    let ctx = common::gpu();
    let mut s = floor_scene(false);
    s.add_light(light(LightKind::Point, Vec3::new(0.0, 2.0, 0.0), Vec3::NEG_Y, 10.0)).unwrap();
    let f = specula::render(&ctx, &s, specula::methods::ENVMAP, &Quality::default(), (64, 64), (0, 1)).unwrap();
    let mut worst = 0.0f32;
    for (x, y) in [(32, 32), (10, 20), (50, 40), (5, 60)] {
        let p = floor_point(x, y);
        let d = Vec3::new(0.0, 2.0, 0.0) - p;
        let e = 10.0 * (d.y / d.length()) / d.length_squared();
        let expected = lambert() * e;
        let got = f.image.texel(0, x, y);
        let err = rel_err(got, expected);
        worst = worst.max(err);
        assert!(err < TOL, "pixel ({x},{y}) at {p}: {got:?} vs {expected}");
    }
    eprintln!("point light: worst relative error {worst:.3e} (tolerance {TOL:e})");
    common::assert_clean(&ctx);
}

/// KHR_lights_punctual's recommended spot falloff, written out as the extension's sample
/// implementation states it (not from the library's code): a ramp linear in cos θ from the
/// outer to the inner cone, squared.
fn gltf_spot_attenuation(cd: f32, inner: f32, outer: f32) -> f32 {
    let light_angle_scale = 1.0 / (inner.cos() - outer.cos()).max(0.001);
    let light_angle_offset = -outer.cos() * light_angle_scale;
    let a = (cd * light_angle_scale + light_angle_offset).clamp(0.0, 1.0);
    a * a
}

#[test]
fn spot_light_follows_the_gltf_falloff_on_the_gpu_and_in_the_reference() {
    let ctx = common::gpu();
    let (inner, outer) = (0.3f32, 0.6f32);
    let mut s = floor_scene(false);
    s.add_light(light(LightKind::Spot { inner_cone: inner, outer_cone: outer }, Vec3::new(0.0, 2.0, 0.0), Vec3::NEG_Y, 10.0)).unwrap();
    let gpu = specula::render(&ctx, &s, specula::methods::ENVMAP, &Quality::default(), (64, 64), (0, 1)).unwrap().image;
    let reference = specula::reference::render_reference(
        &s,
        &{
            let mut knobs = Quality::default();
            knobs.reference.spp = 1;
            knobs
        },
        (64, 64),
    )
    .unwrap();
    // Floor points inside the inner cone, across the ramp, and outside the outer cone.
    let mut ramp_points = 0;
    let mut worst = [(0.0f32, 0.0f32); 2];
    for x in [32, 40, 44, 46, 48, 50, 52, 54, 60] {
        let p = floor_point(x, 32);
        let d = Vec3::new(0.0, 2.0, 0.0) - p;
        let cd = d.y / d.length();
        let att = gltf_spot_attenuation(cd, inner, outer);
        ramp_points += (att > 0.05 && att < 0.95) as usize;
        let expected = lambert() * 10.0 * cd / d.length_squared() * att;
        for (k, (name, img)) in [("gpu", &gpu), ("reference", &reference)].into_iter().enumerate() {
            let got = img.texel(0, x, 32);
            let (rel, abs) = errors(got, expected);
            worst[k] = (worst[k].0.max(rel), worst[k].1.max(abs));
            assert!(
                (0..3).all(|c| (got[c] - expected[c]).abs() <= TOL_RAMP * expected[c] + ABS_TOL),
                "{name}: floor point {p} (cos θ {cd:.4}): {got:?} vs {expected}"
            );
        }
    }
    eprintln!(
        "spot light: worst relative error (lit points) gpu {:.3e} reference {:.3e}; worst absolute error (unlit) gpu {:e} reference {:e}",
        worst[0].0, worst[1].0, worst[0].1, worst[1].1
    );
    assert!(ramp_points >= 3, "the points sample the ramp: {ramp_points}");
    common::assert_clean(&ctx);
}

/// KHR_lights_punctual's recommended range window, written out as the extension states it
/// (not from the library's code): max(min(1 − (d/range)⁴, 1), 0) / d².
fn gltf_range_window(d: f32, range: f32) -> f32 {
    (1.0 - (d / range).powi(4)).clamp(0.0, 1.0)
}

/// A point light 1 m above the floor with range 2.2 m: floor points from its foot (window
/// ≈ 0.96) across the window to beyond the range (0) follow the extension's window on the
/// GPU and in the reference, so a window that is ignored, squared or cut off hard fails.
#[test]
fn point_light_range_follows_the_gltf_window_on_the_gpu_and_in_the_reference() {
    let ctx = common::gpu();
    let range = 2.2f32;
    let position = Vec3::new(0.0, 1.0, 0.0);
    let mut s = floor_scene(false);
    s.add_light(Light { range: Some(range), ..light(LightKind::Point, position, Vec3::NEG_Y, 4.0) }).unwrap();
    let gpu = specula::render(&ctx, &s, specula::methods::ENVMAP, &Quality::default(), (64, 64), (0, 1)).unwrap().image;
    let reference = specula::reference::render_reference(
        &s,
        &{
            let mut knobs = Quality::default();
            knobs.reference.spp = 1;
            knobs
        },
        (64, 64),
    )
    .unwrap();
    let (mut window_points, mut beyond) = (0, 0);
    let mut worst = [(0.0f32, 0.0f32); 2];
    for x in [32, 36, 40, 44, 48, 52, 56, 60, 63] {
        for y in [32, 44, 56, 63] {
            let p = floor_point(x, y);
            let d = position - p;
            let window = gltf_range_window(d.length(), range);
            window_points += (window > 0.05 && window < 0.8) as usize;
            beyond += (window == 0.0) as usize;
            let expected = lambert() * 4.0 * (d.y / d.length()) / d.length_squared() * window;
            for (k, (name, img)) in [("gpu", &gpu), ("reference", &reference)].into_iter().enumerate() {
                let got = img.texel(0, x, y);
                let (rel, abs) = errors(got, expected);
                worst[k] = (worst[k].0.max(rel), worst[k].1.max(abs));
                assert!(
                    (0..3).all(|c| (got[c] - expected[c]).abs() <= TOL_RAMP * expected[c] + ABS_TOL),
                    "{name}: floor point {p} at {:.3} m (window {window:.4}): {got:?} vs {expected}",
                    d.length()
                );
            }
        }
    }
    eprintln!("range window: worst relative error (lit points) gpu {:.3e} reference {:.3e}; worst absolute error (beyond the range) gpu {:e} reference {:e}", worst[0].0, worst[1].0, worst[0].1, worst[1].1);
    assert!(window_points >= 4 && beyond >= 2, "the points sample the window ({window_points}) and beyond the range ({beyond})");
    common::assert_clean(&ctx);
}

#[test]
fn occluder_casts_a_shadow_from_point_spot_and_directional_lights() {
    let ctx = common::gpu();
    let tilted = Vec3::new(0.5, -1.0, 0.0).normalize();
    for kind in [LightKind::Point, LightKind::Directional, LightKind::Spot { inner_cone: 0.5, outer_cone: 0.7 }] {
        let mut s = floor_scene(true);
        // The directional light comes in tilted, so that its shadow falls beside the
        // occluder's own silhouette (straight down, the occluder would hide its shadow).
        let direction = if kind == LightKind::Directional { tilted } else { Vec3::NEG_Y };
        s.add_light(light(kind, Vec3::new(0.0, 2.0, 0.0), direction, 2.0)).unwrap();
        let f = specula::render(&ctx, &s, specula::methods::ENVMAP, &Quality::default(), (64, 64), (0, 1)).unwrap();
        let names: Vec<_> = f.passes.iter().map(|p| p.name.as_str()).collect();
        assert!(names.contains(&"shadow.generate"));
        // A lit floor point away from the occluder gets exactly the direct light: for the
        // spot, one inside its inner cone (0.5 rad: 1.09 m from its foot), so that a spot
        // that emits nothing fails.
        let (lx, ly) = if matches!(kind, LightKind::Spot { .. }) { (46, 32) } else { (8, 8) };
        let lit = f.image.texel(0, lx, ly);
        let p = floor_point(lx, ly);
        let expected = match kind {
            LightKind::Directional => lambert() * 2.0 * -tilted.y,
            _ => {
                let d = Vec3::new(0.0, 2.0, 0.0) - p;
                if let LightKind::Spot { inner_cone, .. } = kind {
                    assert!((d.y / d.length()) > inner_cone.cos(), "{p} lies inside the inner cone");
                }
                lambert() * 2.0 * (d.y / d.length()) / d.length_squared()
            }
        };
        assert!(expected.min_element() > 0.01, "{kind:?}: the lit point is lit ({expected})");
        // Measured: 0 (point), 1.5e-7 (directional), 0 (spot); TOL 2e-6.
        let err = rel_err(lit, expected);
        eprintln!("{kind:?}: lit point relative error {err:.3e}");
        assert!(err < TOL, "{kind:?}: lit {lit:?} vs {expected}");
        // A floor point outside the occluder's silhouette (0.3 m from the centre, seen from
        // 3 m) but inside its shadow.
        let (x, y) = match kind {
            // The point and spot light at 2 m cast the 0.4 m occluder at 1 m to a 0.8 m
            // shadow: pixel 38 sees the floor at x ≈ 0.35 m.
            LightKind::Point | LightKind::Spot { .. } => (38, 32),
            // The tilted sun shifts the shadow by 0.5 m along +x: x ∈ [0.3, 0.7] m; pixel
            // 41 sees the floor at x ≈ 0.5 m.
            LightKind::Directional => (41, 32),
        };
        let p = floor_point(x, y);
        let in_shadow = match kind {
            LightKind::Directional => p.x > 0.31 && p.x < 0.69 && p.z.abs() < 0.19,
            _ => p.x > 0.31 && p.x < 0.39,
        };
        assert!(in_shadow, "{kind:?}: {p}");
        assert_eq!(&f.image.texel(0, x, y)[..3], &[0.0; 3], "{kind:?}: shadowed floor point {p}");
        // Its mirror image across the occluder is lit for the tilted sun (the shadow is
        // where the light says, not all around).
        if kind == LightKind::Directional {
            // The sun lights the whole floor alike: the mirror point gets the lit point's
            // radiance (measured relative error 1.5e-7; TOL 2e-6).
            let mirror = f.image.texel(0, 63 - x, y);
            let err = rel_err(mirror, expected);
            eprintln!("{kind:?}: mirror image of the shadowed point, relative error {err:.3e}");
            assert!(err < TOL, "{kind:?}: floor at {} is lit: {mirror:?} vs {expected}", floor_point(63 - x, y));
        }
    }
    common::assert_clean(&ctx);
}

#[test]
fn emission_is_radiance() {
    let ctx = common::gpu();
    let mut s = floor_scene(false);
    s.materials[0].emissive = Vec3::new(0.25, 0.5, 2.0);
    s.materials[0].base_color = Vec3::ZERO;
    let f = specula::render(&ctx, &s, specula::methods::ENVMAP, &Quality::default(), (64, 64), (0, 1)).unwrap();
    assert_eq!(&f.image.texel(0, 20, 30)[..3], &[0.25, 0.5, 2.0]);
    common::assert_clean(&ctx);
}
