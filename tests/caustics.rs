//! Caustics (survey §6): photon hit location images, photon splatting and caustic
//! triangles into light cube maps, projection with the distance test; against closed forms
//! and the CPU light tracer (src/reference/caustics.rs).

mod common;

use glam::{DVec3, Vec3};
use specula::quality::Quality;
use specula::scene::{shapes, Camera, Light, LightKind, Material, Scene, SurfaceKind};
use specula::vk::read_image;
use specula::{plan, Renderer};

/// A solid glass sphere (radius `R`, centre `C`) above a diffuse floor, lit by a point
/// light straight above it.
const R: f32 = 0.5;
const C: Vec3 = Vec3::new(0.0, 1.0, 0.0);
const LIGHT: Vec3 = Vec3::new(0.0, 3.0, 0.0);
const INTENSITY: f32 = 10.0;

fn sphere_over_floor(ior: f32) -> Scene {
    let mut s = Scene::new();
    let floor = s.add_material(Material { name: "floor".into(), base_color: Vec3::splat(0.8), ..Default::default() }).unwrap();
    let glass = s
        .add_material(Material { name: "glass".into(), kind: SurfaceKind::Dielectric { ior, thin: false }, ..Default::default() })
        .unwrap();
    s.add_mesh(shapes::quad("floor", Vec3::new(-3.0, 0.0, -3.0), Vec3::new(6.0, 0.0, 0.0), Vec3::new(0.0, 0.0, 6.0), 8, floor)).unwrap();
    s.add_mesh(shapes::uv_sphere("glass", C, R, 48, 24, glass)).unwrap();
    s.add_light(Light {
        name: "lamp".into(),
        kind: LightKind::Point,
        position: LIGHT,
        direction: Vec3::NEG_Y,
        intensity: Vec3::splat(INTENSITY),
        range: None,
    })
    .unwrap();
    s.camera = Some(Camera::look_at(Vec3::new(0.0, 1.2, 3.0), Vec3::new(0.0, 0.0, 0.0), 50f32.to_radians()));
    s
}

fn quality(pairs: &[&str]) -> Quality {
    let mut q = Quality::default();
    for p in ["cube_size=64", "shadow_size=128", "fresnel=exact", "photons=64"].iter().chain(pairs) {
        q.set_pair(p).unwrap();
    }
    q
}

/// The power a point light sends through a glass sphere by two refractions (the closed
/// form the caustic's energy is checked against): ∫ I (1 − F(θ))² dΩ over the sphere's cone,
/// θ the incidence angle at impact parameter b = d sin ψ (exit at the same angle inside).
fn two_refraction_power(ior: f64) -> f64 {
    let d = (LIGHT - C).length() as f64;
    let r = R as f64;
    let psi_max = (r / d).asin();
    let n = 20000;
    let mut sum = 0.0;
    for k in 0..n {
        let psi = (k as f64 + 0.5) / n as f64 * psi_max;
        let sin_i = (d * psi.sin() / r).min(1.0);
        let cos_i = (1.0 - sin_i * sin_i).sqrt();
        let t = 1.0 - specula::optics::fresnel_dielectric(cos_i, ior);
        sum += t * t * 2.0 * std::f64::consts::PI * psi.sin() * (psi_max / n as f64);
    }
    INTENSITY as f64 * sum
}

/// Σ J·Ω over the texels of the light cube `cube` (the caustic's total power, W).
fn cube_power(data: &specula::image::ImageData, cube: u32) -> DVec3 {
    let n = data.width;
    let mut sum = DVec3::ZERO;
    for face in 6 * cube..6 * cube + 6 {
        for y in 0..n {
            for x in 0..n {
                let s = 2.0 * (x as f64 + 0.5) / n as f64 - 1.0;
                let t = 2.0 * (y as f64 + 0.5) / n as f64 - 1.0;
                let omega = (2.0 / n as f64).powi(2) / (1.0 + s * s + t * t).powf(1.5);
                let j = data.texel(face, x, y);
                sum += DVec3::new(j[0] as f64, j[1] as f64, j[2] as f64) * omega;
            }
        }
    }
    sum
}

#[test]
fn caustic_power_matches_the_fresnel_transmittances() {
    let ctx = common::gpu();
    let scene = sphere_over_floor(1.5);
    let expected = two_refraction_power(1.5);
    for filter in ["triangles", "splat"] {
        for photons in ["64", "128"] {
            let q = quality(&[&format!("caustics={filter}"), &format!("photons={photons}")]);
            let p = plan(&scene, specula::methods::REFRACTOR_MAP, &q);
            assert!(p.caustics.is_some(), "{:?}", p.passes);
            let mut r = Renderer::new(&ctx, &scene, p, 32, 32).unwrap();
            let f = r.render(&ctx).unwrap();
            let cube = read_image(&ctx, r.caustic_maps().unwrap()).unwrap();
            let power = cube_power(&cube, 0);
            eprintln!(
                "{filter} photons={photons}: power {power:.4} expected {expected:.4} ratio {:.4}; passes {:?}",
                power.x / expected,
                f.passes.iter().map(|p| p.name.as_str()).collect::<Vec<_>>()
            );
            r.destroy(&ctx);
        }
    }
    common::assert_clean(&ctx);
}

#[test]
fn debug_triangle_flux() {
    let ctx = common::gpu();
    let scene = sphere_over_floor(1.5);
    let q = quality(&["caustics=triangles", "photons=64", "caustic_filter=0"]);
    let p = plan(&scene, specula::methods::REFRACTOR_MAP, &q);
    let mut r = Renderer::new(&ctx, &scene, p, 32, 32).unwrap();
    r.render(&ctx).unwrap();
    let (h, pw) = r.photon_images().unwrap();
    let (h, pw) = (read_image(&ctx, h).unwrap(), read_image(&ctx, pw).unwrap());
    let n = h.width;
    let mut total = 0.0;
    let mut valid = 0.0;
    let mut photons = 0;
    for y in 0..n {
        for x in 0..n {
            if h.texel(0, x, y)[3] != 0.0 {
                photons += 1;
                total += pw.texel(0, x, y)[0] as f64;
            }
        }
    }
    let mut dropped_gap = 0;
    for y in 0..n - 1 {
        for x in 0..n - 1 {
            for tri in [[(0, 0), (1, 0), (0, 1)], [(1, 0), (1, 1), (0, 1)]] {
                let c: Vec<_> = tri.iter().map(|&(dx, dy)| (h.texel(0, x + dx, y + dy).to_vec(), pw.texel(0, x + dx, y + dy)[0])).collect();
                if c.iter().any(|(h, _)| h[3] == 0.0) {
                    continue;
                }
                let l: Vec<f32> = c.iter().map(|(h, _)| Vec3::new(h[0], h[1], h[2]).length()).collect();
                let (lo, hi) = (l.iter().cloned().fold(1e30, f32::min), l.iter().cloned().fold(0.0, f32::max));
                if hi > lo * 1.1 {
                    dropped_gap += 1;
                    continue;
                }
                valid += c.iter().map(|(_, p)| *p as f64).sum::<f64>() / 6.0;
            }
        }
    }
    let cube = read_image(&ctx, r.caustic_maps().unwrap()).unwrap();
    eprintln!(
        "photons {photons} total {total:.4} valid-triangle flux {valid:.4} dropped by gap {dropped_gap} cube {:.4}",
        cube_power(&cube, 0).x
    );
    r.destroy(&ctx);
}
