//! Shared helpers of the GPU tests: a validated context, scenes built in code.
#![allow(dead_code)]

use glam::Vec3;
use specula::scene::{shapes, Material, Scene, SurfaceKind};
use specula::vk::{Context, DeviceOptions};

/// A context with the Khronos validation layer on (every GPU test uses one).
pub fn gpu() -> Context {
    Context::new(&DeviceOptions { validation: true, device_filter: None })
        .expect("Vulkan context with validation (is vulkan-validationlayers installed?)")
}

/// Fails the test on any validation error.
pub fn assert_clean(ctx: &Context) {
    assert_eq!(ctx.validation.error_count(), 0, "validation errors: {:#?}", ctx.validation.error_messages());
}

/// The emitted colour of quadrant `q` of wall `w` in `quadrant_room`: distinct for all 24.
pub fn quadrant_color(w: usize, q: usize) -> Vec3 {
    Vec3::new((w + 1) as f32 / 8.0, (q + 1) as f32 / 8.0, 0.25 + 0.5 * ((w + q) % 2) as f32)
}

/// A room of 24 emissive quadrants (no lights) of half-size `half` around `center`.
pub fn emissive_room(scene: &mut Scene, center: Vec3, half: f32) {
    let mut mats = vec![vec![0; 4]; 6];
    for (w, row) in mats.iter_mut().enumerate() {
        for (q, m) in row.iter_mut().enumerate() {
            *m = scene
                .add_material(Material {
                    name: format!("w{w}q{q}"),
                    base_color: Vec3::ZERO,
                    emissive: quadrant_color(w, q),
                    ..Default::default()
                })
                .unwrap();
        }
    }
    for mesh in shapes::quadrant_room(center, half, 2, |w, q| mats[w][q]) {
        scene.add_mesh(mesh).unwrap();
    }
}

/// A mirror material of reflectance `f0` at normal incidence (κ = 0, ν from eq. 2).
pub fn mirror(f0: f32) -> Material {
    let s = f0.sqrt();
    let nu = (1.0 + s) / (1.0 - s);
    Material { name: format!("mirror{f0}"), kind: SurfaceKind::Mirror { nu: Vec3::splat(nu), kappa: Vec3::ZERO }, ..Default::default() }
}

/// Maximum absolute difference of two RGB triples.
pub fn max_diff(a: &[f32], b: Vec3) -> f32 {
    (a[0] - b.x).abs().max((a[1] - b.y).abs()).max((a[2] - b.z).abs())
}
