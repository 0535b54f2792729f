//! The corpus the measuring planner's models are fitted on (issue 31): scenes generated in
//! code, spanning the object classes the survey names (convex and non-convex mirrors and
//! solids, concave reflectors, flat faces, planar mirrors and thin panes), ν from 1.05 to
//! 2.4, near and far environments, occluders that make the environment concave from the
//! reference point, and several specular objects in mutual view. Every scene is an emissive
//! checkerboard room (`scenes::checker_room`: no lights, so nothing but geometry and Fresnel
//! decides a specular pixel, and every reflected checker edge shows a misplaced lookup);
//! one in four also has a point light over a diffuse floor (shadow maps, caustics).
//!
//! Scenes are numbered; [`scene`] builds one from its number alone (deterministic), so a
//! measurement names its scene by number and a held-out split is a set of numbers.

use glam::Vec3;

use super::checker_room;
use crate::error::Result;
use crate::scene::{shapes, Camera, Light, LightKind, Material, Mesh, Scene, SurfaceKind};

/// How many scenes the corpus has.
pub const SIZE: usize = 36;
const _: () = assert!(SIZE >= 30, "the issue asks for at least 30 scenes");

/// Indices of refraction the corpus draws from (water, glass, flint, diamond and the
/// weak-lens and strong-lens ends).
const NUS: [f32; 7] = [1.05, 1.2, 1.33, 1.5, 1.8, 2.0, 2.4];

/// The kinds of specular object a corpus scene places.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    MirrorSphere,
    GlassSphere,
    MirrorTorus,
    GlassTorus,
    MirrorBowl,
    GlassBlob,
    MirrorBlob,
    GlassCube,
    GlassPrism,
    PlanarMirror,
    ThinPane,
    MirrorBox,
}

const KINDS: [Kind; 12] = [
    Kind::MirrorSphere,
    Kind::GlassSphere,
    Kind::MirrorTorus,
    Kind::GlassBlob,
    Kind::MirrorBowl,
    Kind::GlassCube,
    Kind::PlanarMirror,
    Kind::GlassTorus,
    Kind::MirrorBlob,
    Kind::GlassPrism,
    Kind::ThinPane,
    Kind::MirrorBox,
];

impl Kind {
    fn label(self) -> &'static str {
        match self {
            Kind::MirrorSphere => "mirror-sphere",
            Kind::GlassSphere => "glass-sphere",
            Kind::MirrorTorus => "mirror-torus",
            Kind::GlassTorus => "glass-torus",
            Kind::MirrorBowl => "mirror-bowl",
            Kind::GlassBlob => "glass-blob",
            Kind::MirrorBlob => "mirror-blob",
            Kind::GlassCube => "glass-cube",
            Kind::GlassPrism => "glass-prism",
            Kind::PlanarMirror => "planar-mirror",
            Kind::ThinPane => "thin-pane",
            Kind::MirrorBox => "mirror-box",
        }
    }
}

/// A small deterministic hash of (scene, salt) in [0, 1).
fn unit(i: usize, salt: u32) -> f32 {
    let mut x = (i as u32).wrapping_mul(0x9E37_79B9) ^ salt.wrapping_mul(0x85EB_CA6B);
    x ^= x >> 15;
    x = x.wrapping_mul(0x2C1B_3C6D);
    x ^= x >> 12;
    (x % 10_000) as f32 / 10_000.0
}

/// Scene `i`'s name: its number and what it holds.
pub fn name(i: usize) -> String {
    let (kinds, _) = recipe(i);
    let mut n = format!("corpus-{i:02}");
    for k in kinds {
        n.push('-');
        n.push_str(k.label());
    }
    n
}

/// Scene `i`'s objects, and whether the room is far (half-size 5 m against 2 m).
fn recipe(i: usize) -> (Vec<Kind>, bool) {
    let mut kinds = vec![KINDS[i % KINDS.len()]];
    // Every other scene from the third on: a second specular object in mutual view; every
    // ninth a third.
    if i % 4 >= 2 {
        kinds.push(KINDS[(i * 7 + 3) % KINDS.len()]);
    }
    if i % 9 == 4 {
        kinds.push(KINDS[(i * 5 + 1) % KINDS.len()]);
    }
    (kinds, (i / KINDS.len()) % 2 == 1)
}

/// Corpus scene `i` (< [`SIZE`]; larger numbers continue the pattern).
pub fn scene(i: usize) -> Result<Scene> {
    let (kinds, far) = recipe(i);
    let half = if far { 5.0 } else { 2.0 };
    let centre = Vec3::ZERO;
    let mut s = Scene::new();
    checker_room(&mut s, centre, half)?;
    let floor_y = centre.y - half;
    // One in three: an emissive box on the floor that hides part of the room from the
    // objects (a concave environment, survey Figure 21).
    if i % 3 == 1 {
        let tex = s.add_texture(super::checker_texture("occluder_checker", 4, Vec3::new(0.1, 0.8, 0.2), Vec3::splat(0.8)))?;
        let mat = s.add_material(Material {
            name: "occluder".into(),
            base_color: Vec3::ZERO,
            emissive: Vec3::ONE,
            emissive_texture: Some(tex),
            ..Default::default()
        })?;
        s.add_mesh(shapes::cuboid("occluder", Vec3::new(-0.6, floor_y + 0.35, 0.5), Vec3::new(0.35, 0.35, 0.35), mat))?;
    }
    // One in four: a point light over a diffuse floor slab (shadow maps; caustics where glass
    // focuses its light).
    if i % 4 == 3 {
        let floor = s.add_material(Material { name: "floor".into(), base_color: Vec3::splat(0.6), ..Default::default() })?;
        let y = floor_y + 0.02;
        s.add_mesh(shapes::quad("floor", Vec3::new(-1.8, y, 1.8), Vec3::new(3.6, 0.0, 0.0), Vec3::new(0.0, 0.0, -3.6), 8, floor))?;
        s.add_light(Light {
            name: "lamp".into(),
            kind: LightKind::Point,
            position: Vec3::new(0.8, floor_y + 3.2, 0.4),
            direction: Vec3::NEG_Y,
            intensity: Vec3::splat(4.0),
            range: None,
        })?;
    }
    // Objects side by side on a row across the room, at the floor's height plus their size.
    let n = kinds.len();
    let mut targets = Vec::new();
    for (k, kind) in kinds.iter().enumerate() {
        let nu = NUS[(i * 5 + k * 3) % NUS.len()];
        let size = 0.45 + 0.35 * unit(i, 10 + k as u32);
        let x = (k as f32 - (n as f32 - 1.0) * 0.5) * 1.5;
        let c = Vec3::new(x, floor_y + 0.4 + size + 0.5 * unit(i, 20 + k as u32), -0.4 - 0.4 * unit(i, 30 + k as u32));
        let mesh = object(&mut s, *kind, &format!("{}{k}", kind.label()), c, size, nu, i)?;
        s.add_mesh(mesh)?;
        targets.push(c);
    }
    // The camera looks at the objects from 1.5–3.5 sizes away, from above or level.
    let target = targets.iter().copied().sum::<Vec3>() / n as f32;
    let spread = 1.2 + 1.3 * unit(i, 40) + 0.6 * (n as f32 - 1.0);
    let dir = Vec3::new(0.6 * (unit(i, 41) - 0.5), 0.2 + 0.5 * unit(i, 42), 1.0).normalize();
    let eye = (target + dir * spread * 1.4).clamp(Vec3::splat(-half * 0.9), Vec3::splat(half * 0.9));
    s.camera = Some(Camera::look_at(eye, target, 50f32.to_radians()));
    Ok(s)
}

/// A mirror material of reflectance `f0` at normal incidence (`scenes::mirror_material`).
fn mirror(s: &mut Scene, f0: f32) -> Result<usize> {
    s.add_material(super::mirror_material(&format!("mirror{f0}"), f0))
}

fn glass(s: &mut Scene, nu: f32, thin: bool) -> Result<usize> {
    s.add_material(Material {
        name: format!("glass{nu}{}", if thin { "thin" } else { "" }),
        kind: SurfaceKind::Dielectric { ior: nu, thin },
        ..Default::default()
    })
}

fn object(s: &mut Scene, kind: Kind, name: &str, c: Vec3, size: f32, nu: f32, i: usize) -> Result<Mesh> {
    let f0 = 0.8 + 0.15 * unit(i, 50);
    // Tessellation varies too (the cost model's triangle counts).
    let fine = 1 + (i % 3) as u32;
    Ok(match kind {
        Kind::MirrorSphere => shapes::uv_sphere(name, c, size, 24 * fine, 12 * fine, mirror(s, f0)?),
        Kind::GlassSphere => shapes::uv_sphere(name, c, size, 24 * fine, 12 * fine, glass(s, nu, false)?),
        Kind::MirrorTorus => shapes::torus(name, c, Vec3::new(0.3, 1.0, 0.2), (size * 0.75, size * 0.3), (24 * fine, 12), mirror(s, f0)?),
        Kind::GlassTorus => {
            shapes::torus(name, c, Vec3::new(0.2, 0.4, 1.0), (size * 0.75, size * 0.3), (24 * fine, 12), glass(s, nu, false)?)
        }
        Kind::MirrorBowl => {
            shapes::bowl(name, c, Vec3::new(0.0, 0.6, 1.0), (size, 1.2 + 0.35 * unit(i, 60)), (24 * fine, 6 * fine), mirror(s, f0)?)
        }
        Kind::GlassBlob => {
            shapes::blob(name, c, (size * 0.8, 0.25 + 0.2 * unit(i, 61)), i as u32, (24 * fine, 12 * fine), glass(s, nu, false)?)
        }
        Kind::MirrorBlob => {
            shapes::blob(name, c, (size * 0.8, 0.25 + 0.2 * unit(i, 62)), i as u32 + 100, (24 * fine, 12 * fine), mirror(s, f0)?)
        }
        Kind::GlassCube => shapes::cuboid(name, c, Vec3::new(size * 0.7, size * 0.5, size * 0.6), glass(s, nu, false)?),
        Kind::GlassPrism => {
            let corners = [Vec3::new(0.0, 0.6, 0.0) * size, Vec3::new(-0.55, -0.35, 0.0) * size, Vec3::new(0.55, -0.35, 0.0) * size];
            shapes::prism(name, c, Vec3::new(0.3, 0.0, 1.0).normalize(), size * 1.6, corners, glass(s, nu, false)?)
        }
        Kind::PlanarMirror => {
            // A square mirror standing behind the row, tilted towards the camera.
            let (u, v) = (Vec3::new(2.0 * size, 0.0, 0.3 * size), Vec3::new(0.0, 2.0 * size, -0.4 * size));
            let o = c - (u + v) * 0.5 - Vec3::Z * 0.3;
            shapes::quad(name, o, u, v, 2, mirror(s, f0)?)
        }
        Kind::ThinPane => {
            let (u, v) = (Vec3::new(1.8 * size, 0.0, -0.5 * size), Vec3::new(0.0, 1.8 * size, 0.0));
            shapes::quad(name, c - (u + v) * 0.5, u, v, 2, glass(s, nu, true)?)
        }
        Kind::MirrorBox => shapes::cuboid(name, c, Vec3::new(size * 0.6, size * 0.6, size * 0.4), mirror(s, f0)?),
    })
}

/// Every corpus scene with its name.
pub fn all() -> Result<Vec<(String, Scene)>> {
    (0..SIZE).map(|i| Ok((name(i), scene(i)?))).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::methods::registry::ObjectClass;

    /// The corpus spans what the issue asks: at least 30 scenes, every object class, ν from
    /// 1.05 to 2.4, near and far rooms, several specular objects in mutual view, every
    /// scene valid.
    #[test]
    fn corpus_spans_the_classes_indices_and_environments() {
        let mut classes = std::collections::BTreeSet::new();
        let (mut nus, mut far, mut several) = (Vec::new(), 0, 0);
        for i in 0..SIZE {
            let s = scene(i).unwrap();
            s.validate().unwrap();
            let specular: Vec<&Mesh> = s.specular_meshes().map(|(_, m)| m).collect();
            several += (specular.len() >= 2) as usize;
            far += recipe(i).1 as usize;
            for m in specular {
                let kind = &s.materials[m.material].kind;
                classes.insert(ObjectClass::of(kind).unwrap().label());
                if let SurfaceKind::Dielectric { ior, .. } = kind {
                    nus.push(*ior);
                }
            }
        }
        assert_eq!(classes.len(), 3, "{classes:?}");
        assert!(nus.iter().any(|n| *n <= 1.05) && nus.iter().any(|n| *n >= 2.4), "{nus:?}");
        assert!(far >= 6 && several >= 10, "far {far}, several {several}");
        assert_eq!(name(0), "corpus-00-mirror-sphere");
    }
}
