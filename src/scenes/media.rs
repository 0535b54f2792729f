//! Scenes of graded media (survey §6.5: curved rays in varying media, `scene::medium`).

use glam::Vec3;

use super::{checker_room, ROOM_CENTER, ROOM_HALF};
use crate::error::Result;
use crate::scene::medium::GradedIndex;
use crate::scene::{shapes, Camera, Material, Scene, SurfaceKind};

/// The hot layer of [`mirage`]: its box (centre, half-size) over the room's floor.
pub const MIRAGE_LAYER: (Vec3, Vec3) = (Vec3::new(0.0, -1.745, 0.0), Vec3::new(1.6, 0.245, 1.6));

/// A mirage over a hot floor: the emissive checkerboard room ([`checker_room`]) with a
/// layer of hot air on its floor, a box whose index rises with height, n(y) = 1 + 0.2 (y −
/// y_top) (0.902 at the floor, 1 at its top, where it meets the room's air without a
/// seam), seen at grazing angles: rays heading down turn back up inside it (where n(y) =
/// cos of their angle below the horizontal) and show the far wall again, upside down, where
/// the floor would be. The gradient is a million times air's, so that a 4 m room shows it.
pub fn mirage() -> Result<Scene> {
    let mut s = Scene::new();
    checker_room(&mut s, ROOM_CENTER, ROOM_HALF)?;
    let (centre, half) = MIRAGE_LAYER;
    let top = centre.y + half.y;
    let air = s.add_material(Material {
        name: "hot-air".into(),
        kind: SurfaceKind::Dielectric { ior: 1.0, thin: false },
        graded: Some(GradedIndex { origin: Vec3::new(0.0, top, 0.0), gradient: Vec3::new(0.0, 0.2, 0.0), hessian: [Vec3::ZERO; 3] }),
        ..Default::default()
    })?;
    s.add_mesh(shapes::cuboid("hot-layer", centre, half, air))?;
    s.camera = Some(Camera::look_at(Vec3::new(0.013, -1.38, 1.9), Vec3::new(0.007, -1.7, -1.5), 50f32.to_radians()));
    Ok(s)
}

/// A graded-index (GRIN) lens: a flat glass slab, 0.4 m thick, whose index falls off its
/// axis (z) as n = 1.6 − ½·1.2·r², so that it focuses like a convex lens of about 2 m focal
/// length with flat faces, in the emissive checkerboard room, looked through towards the
/// far wall.
pub fn grin_lens() -> Result<Scene> {
    let mut s = Scene::new();
    checker_room(&mut s, ROOM_CENTER, ROOM_HALF)?;
    let glass = s.add_material(Material {
        name: "grin-glass".into(),
        kind: SurfaceKind::Dielectric { ior: 1.6, thin: false },
        graded: Some(GradedIndex { origin: Vec3::ZERO, gradient: Vec3::ZERO, hessian: GradedIndex::radial_hessian(Vec3::Z, 1.2) }),
        ..Default::default()
    })?;
    s.add_mesh(shapes::cuboid("grin-lens", Vec3::new(0.0, 0.0, -0.3), Vec3::new(0.9, 0.9, 0.2), glass))?;
    s.camera = Some(Camera::look_at(Vec3::new(0.013, 0.021, 1.8), Vec3::new(0.007, -0.011, -1.0), 55f32.to_radians()));
    Ok(s)
}
