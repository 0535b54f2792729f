//! Scenes built in code for the demo and the benchmarks (the bundled glTF scenes are in
//! `assets/`).

use glam::Vec3;

use crate::error::Result;
use crate::scene::{shapes, Camera, Material, Scene, SurfaceKind};

/// The emitted colour of quadrant `q` of wall `w` of `emissive_room`: distinct for all 24.
pub fn quadrant_color(w: usize, q: usize) -> Vec3 {
    Vec3::new((w + 1) as f32 / 8.0, (q + 1) as f32 / 8.0, 0.25 + 0.5 * ((w + q) % 2) as f32)
}

/// A room of 24 emissive quadrants (`shapes::quadrant_room`, no lights) of half-size `half`
/// around `center`.
pub fn emissive_room(scene: &mut Scene, center: Vec3, half: f32) -> Result<()> {
    let mut mats = [[0usize; 4]; 6];
    for (w, row) in mats.iter_mut().enumerate() {
        for (q, m) in row.iter_mut().enumerate() {
            let name = format!("w{w}q{q}");
            *m = scene.add_material(Material { name, base_color: Vec3::ZERO, emissive: quadrant_color(w, q), ..Default::default() })?;
        }
    }
    for mesh in shapes::quadrant_room(center, half, 2, |w, q| mats[w][q]) {
        scene.add_mesh(mesh)?;
    }
    Ok(())
}

/// Flat glass (survey §5, `planar-refraction`'s showcase): the emissive quadrant room of
/// half-size 2 m (24 distinct colours, no lights: nothing but geometry and Fresnel decides a
/// pixel), an emissive ball, a glass slab (6 faces) and a glass prism (5 faces) of ν 1.5,
/// seen from above at an angle.
pub fn flat_glass() -> Result<Scene> {
    let mut s = Scene::new();
    emissive_room(&mut s, Vec3::ZERO, 2.0)?;
    let ball =
        s.add_material(Material { name: "ball".into(), base_color: Vec3::ZERO, emissive: Vec3::new(1.5, 0.8, 0.2), ..Default::default() })?;
    s.add_mesh(shapes::uv_sphere("ball", Vec3::new(0.6, -1.5, -1.2), 0.35, 32, 16, ball))?;
    let glass =
        s.add_material(Material { name: "glass".into(), kind: SurfaceKind::Dielectric { ior: 1.5, thin: false }, ..Default::default() })?;
    s.add_mesh(shapes::cuboid("slab", Vec3::new(-0.7, -1.6, -0.2), Vec3::new(0.6, 0.25, 0.5), glass))?;
    let corners = [Vec3::new(0.0, 0.45, 0.0), Vec3::new(-0.4, -0.23, 0.0), Vec3::new(0.4, -0.23, 0.0)];
    s.add_mesh(shapes::prism("prism", Vec3::new(0.6, -1.0, 0.1), Vec3::new(0.3, 0.0, 1.0).normalize(), 1.0, corners, glass))?;
    s.camera = Some(Camera::look_at(Vec3::new(1.0, 0.8, 1.9), Vec3::new(-0.1, -1.3, -0.3), 55f32.to_radians()));
    Ok(s)
}
