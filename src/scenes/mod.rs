//! Scenes built in code for the demo and the benchmarks (the bundled glTF scenes are in
//! `assets/`).

pub mod corpus;
pub mod media;
pub mod water;

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

/// The names [`builtin`] knows, in the order `specula` lists them.
pub const BUILTIN: &[&str] = &[
    "corner-mirror",
    "concave-occluder",
    "glass-1.1",
    "glass-1.5",
    "flat-glass",
    "convex-mirror",
    "caustic-ball",
    "caustic-room",
    "mirage",
    "grin-lens",
    "pool",
];

/// A scene built in code by its name (`builtin:NAME` on the command line): `corner-mirror`,
/// `concave-occluder`, `glass-1.1`, `glass-1.5`, `flat-glass`, `convex-mirror`,
/// `caustic-ball`, `caustic-room`, `mirage`, `grin-lens`, `pool`; `None` for another name.
pub fn builtin(name: &str) -> Option<Result<Scene>> {
    if let Some(i) = name.strip_prefix("corpus-").and_then(|n| n.parse::<usize>().ok()).filter(|&i| i < 10_000) {
        return Some(corpus::scene(i));
    }
    Some(match name {
        "corner-mirror" => corner_mirror(),
        "concave-occluder" => concave_occluder(),
        "glass-1.1" => glass_sphere(1.1),
        "glass-1.5" => glass_sphere(1.5),
        "flat-glass" => flat_glass(),
        "convex-mirror" => convex_mirror(),
        "caustic-ball" => caustic_ball(),
        "caustic-room" => caustic_room(),
        "mirage" => media::mirage(),
        "grin-lens" => media::grin_lens(),
        "pool" => water::pool(),
        _ => return None,
    })
}

/// The centre of the showcase rooms ([`checker_room`] of half-size [`ROOM_HALF`]).
pub const ROOM_CENTER: Vec3 = Vec3::ZERO;
pub const ROOM_HALF: f32 = 2.0;

/// An emissive checkerboard texture: `cells`×`cells` squares of `a` and `b` (linear
/// colours, stored sRGB-encoded as textures are), 8 texels per square so that bilinear
/// filtering blurs only a square's rim.
pub fn checker_texture(name: &str, cells: u32, a: Vec3, b: Vec3) -> crate::scene::Texture {
    let n = cells * 8;
    let enc = |c: f32| -> u8 {
        let c = c.clamp(0.0, 1.0);
        let s = if c <= 0.003_130_8 { 12.92 * c } else { 1.055 * c.powf(1.0 / 2.4) - 0.055 };
        (s * 255.0 + 0.5) as u8
    };
    let mut rgba8 = Vec::with_capacity((n * n * 4) as usize);
    for y in 0..n {
        for x in 0..n {
            let c = if (x / 8 + y / 8) % 2 == 0 { a } else { b };
            rgba8.extend([enc(c.x), enc(c.y), enc(c.z), 255]);
        }
    }
    crate::scene::Texture { name: name.into(), width: n, height: n, rgba8 }
}

/// A room of six emissive checkerboard walls (no lights: nothing blows out, and nothing but
/// geometry and Fresnel decides a specular pixel), each wall 8×8 squares of two colours of
/// its own (emitted radiance at most 0.9), around `center` with half-size `half`. Every
/// edge between two squares is a place where a reflection searched in the wrong place
/// shows.
pub fn checker_room(scene: &mut Scene, center: Vec3, half: f32) -> Result<()> {
    const PAIRS: [(Vec3, Vec3); 6] = [
        (Vec3::new(0.9, 0.25, 0.2), Vec3::new(0.3, 0.05, 0.05)),
        (Vec3::new(0.2, 0.8, 0.3), Vec3::new(0.05, 0.25, 0.1)),
        (Vec3::new(0.85, 0.85, 0.8), Vec3::new(0.25, 0.25, 0.3)),
        (Vec3::new(0.6, 0.45, 0.3), Vec3::new(0.15, 0.1, 0.05)),
        (Vec3::new(0.25, 0.45, 0.9), Vec3::new(0.05, 0.1, 0.3)),
        (Vec3::new(0.9, 0.8, 0.2), Vec3::new(0.35, 0.1, 0.4)),
    ];
    for (wall, (a, b)) in PAIRS.iter().enumerate() {
        let axis = wall / 2;
        let sign = if wall % 2 == 0 { 1.0 } else { -1.0 };
        let (a1, a2) = match axis {
            0 => (1, 2),
            1 => (0, 2),
            _ => (0, 1),
        };
        let tex = scene.add_texture(checker_texture(&format!("checker{wall}"), 8, *a, *b))?;
        let mat = scene.add_material(Material {
            name: format!("wall{wall}"),
            base_color: Vec3::ZERO,
            emissive: Vec3::ONE,
            emissive_texture: Some(tex),
            ..Default::default()
        })?;
        let mut o = Vec3::ZERO;
        o[axis] = sign * half;
        let (mut u, mut v) = (Vec3::ZERO, Vec3::ZERO);
        u[a1] = 2.0 * half;
        v[a2] = 2.0 * half;
        // The quad spans the wall from its (−, −) corner; it faces the room's centre.
        let corner = center + o - u * 0.5 - v * 0.5;
        let (u, v) = if u.cross(v).dot(-o) > 0.0 { (u, v) } else { (v, u) };
        scene.add_mesh(shapes::quad(&format!("wall{wall}"), corner, u, v, 4, mat))?;
    }
    Ok(())
}

/// A mirror material of reflectance `f0` at normal incidence (κ = 0, ν from survey eq. 2).
pub(crate) fn mirror_material(name: &str, f0: f32) -> Material {
    let s = f0.sqrt();
    let nu = (1.0 + s) / (1.0 - s);
    Material { name: name.into(), kind: SurfaceKind::Mirror { nu: Vec3::splat(nu), kappa: Vec3::ZERO }, ..Default::default() }
}

/// The mirror ball of [`corner_mirror`] and [`concave_occluder`]: centre and radius.
pub const CORNER_BALL: (Vec3, f32) = (Vec3::new(1.2, -1.25, -1.2), 0.6);

/// Survey Figure 20's set-up (§4.2): a mirror ball (F0 0.9) in a corner of the emissive
/// checkerboard room ([`checker_room`], half-size 2 m, no lights), its maps' reference point
/// forced to the room's centre (`Mesh::reference_point`), 2.1 m from the ball's centre, so
/// that the distance-map search, not the parallax correction, finds what the ball reflects:
/// `linear_steps` and `secant_steps` matter. Seen from the opposite side of the room.
pub fn corner_mirror() -> Result<Scene> {
    let mut s = Scene::new();
    checker_room(&mut s, ROOM_CENTER, ROOM_HALF)?;
    let mirror = s.add_material(mirror_material("mirror", 0.9))?;
    let (c, r) = CORNER_BALL;
    let mut ball = shapes::uv_sphere("mirror_ball", c, r, 64, 32, mirror);
    ball.reference_point = Some(ROOM_CENTER);
    s.add_mesh(ball)?;
    s.camera = Some(Camera::look_at(Vec3::new(-0.2, -0.3, 0.6), c, 45f32.to_radians()));
    Ok(s)
}

/// Survey Figure 21's difficult case (§4.2): [`corner_mirror`] with an emissive chessboard
/// box on the floor between the room's centre (the ball's reference point) and the ball,
/// making the environment concave from the reference point: part of the floor and of the
/// box's far faces that the ball reflects is hidden from the reference point, so a single
/// distance map substitutes the box's edge for it (more search steps do not help; layered
/// maps, §4.5, see behind the box).
pub fn concave_occluder() -> Result<Scene> {
    let mut s = corner_mirror()?;
    let tex = s.add_texture(checker_texture("box_checker", 4, Vec3::new(0.1, 0.85, 0.15), Vec3::new(0.85, 0.85, 0.85)))?;
    let mat = s.add_material(Material {
        name: "box".into(),
        base_color: Vec3::ZERO,
        emissive: Vec3::ONE,
        emissive_texture: Some(tex),
        ..Default::default()
    })?;
    s.add_mesh(shapes::cuboid("box", Vec3::new(0.15, -1.55, -1.4), Vec3::new(0.3, 0.45, 0.3), mat))?;
    Ok(s)
}

/// A solid glass ball of index `ior` (survey §4.4's refractor) in the middle of the emissive
/// checkerboard room, seen from close by: the refractor-map search steps and the internal
/// bounces decide what shows through it (ν 1.1: a weak lens, the refracted rays nearly
/// straight; ν 1.5: strong refraction and total internal reflection at the rim).
pub fn glass_sphere(ior: f32) -> Result<Scene> {
    let mut s = Scene::new();
    checker_room(&mut s, ROOM_CENTER, ROOM_HALF)?;
    let glass =
        s.add_material(Material { name: format!("glass{ior}"), kind: SurfaceKind::Dielectric { ior, thin: false }, ..Default::default() })?;
    s.add_mesh(shapes::uv_sphere("glass_ball", Vec3::new(0.0, -0.6, -0.4), 0.7, 64, 32, glass))?;
    s.camera = Some(Camera::look_at(Vec3::new(0.3, 0.2, 1.6), Vec3::new(0.0, -0.6, -0.4), 50f32.to_radians()));
    Ok(s)
}

/// Curved reflectors by geometry transformation (survey §5.2, `curved-reflector`'s
/// showcase): a mirror ball (F0 0.9) off the middle of the emissive checkerboard room,
/// seen from close by, so that its reflection spans most of the room and each reflected
/// checker edge shows where the geometry image's resolution, the search's levels and the
/// environment's tessellation put it.
pub fn convex_mirror() -> Result<Scene> {
    let mut s = Scene::new();
    checker_room(&mut s, ROOM_CENTER, ROOM_HALF)?;
    let mirror = s.add_material(mirror_material("mirror", 0.9))?;
    let c = Vec3::new(0.3, -0.8, -0.6);
    s.add_mesh(shapes::uv_sphere("mirror_ball", c, 0.7, 64, 32, mirror))?;
    s.camera = Some(Camera::look_at(Vec3::new(-0.4, 0.1, 1.3), c, 50f32.to_radians()));
    Ok(s)
}

/// Caustics (survey §6's showcase): a solid glass ball (ν 1.5, radius 0.5 m) above a grey
/// diffuse floor (albedo 0.7) under a point light (8 cd) 3 m up and to its side, no sky:
/// the ball focuses the light into a bright spot on the floor beside its shadow. The floor
/// lit directly stays under radiance 0.3, so only the caustic is bright: what the photon
/// count, the light cube's filter and the splatting or triangle accumulation change shows
/// there.
/// Two glass balls (ν 1.5) under a lamp in a closed white room of 3 m, each focusing its
/// light onto the floor and walls beside it, and a box on the floor between them: frames over
/// time where a moving object reaches few of the maps (`specula animate builtin:caustic-room
/// --slide box=…`; issue 33 item 4).
pub fn caustic_room() -> Result<Scene> {
    let mut s = Scene::new();
    let white = s.add_material(Material { name: "white".into(), ..Default::default() })?;
    let glass =
        s.add_material(Material { name: "glass".into(), kind: SurfaceKind::Dielectric { ior: 1.5, thin: false }, ..Default::default() })?;
    for m in shapes::quadrant_room(Vec3::new(0.0, 1.5, 0.0), 1.5, 1, |_, _| white) {
        s.add_mesh(m)?;
    }
    s.add_mesh(shapes::uv_sphere("glass_a", Vec3::new(-1.1, 0.6, -0.5), 0.3, 16, 8, glass))?;
    s.add_mesh(shapes::uv_sphere("glass_b", Vec3::new(1.1, 0.6, -0.5), 0.3, 16, 8, glass))?;
    s.add_mesh(shapes::cuboid("box", Vec3::new(0.0, 0.15, 1.0), Vec3::splat(0.15), white))?;
    s.add_light(crate::scene::Light {
        name: "lamp".into(),
        kind: crate::scene::LightKind::Point,
        position: Vec3::new(0.0, 2.8, -0.5),
        direction: Vec3::NEG_Y,
        intensity: Vec3::splat(8.0),
        range: None,
    })?;
    s.camera = Some(Camera::look_at(Vec3::new(0.0, 1.6, 2.9), Vec3::new(0.0, 0.5, 0.0), 1.2));
    Ok(s)
}

pub fn caustic_ball() -> Result<Scene> {
    let mut s = Scene::new();
    let floor = s.add_material(Material { name: "floor".into(), base_color: Vec3::splat(0.7), ..Default::default() })?;
    s.add_mesh(shapes::quad("floor", Vec3::new(-3.0, 0.0, 3.0), Vec3::new(6.0, 0.0, 0.0), Vec3::new(0.0, 0.0, -6.0), 16, floor))?;
    let glass =
        s.add_material(Material { name: "glass".into(), kind: SurfaceKind::Dielectric { ior: 1.5, thin: false }, ..Default::default() })?;
    s.add_mesh(shapes::uv_sphere("glass_ball", Vec3::new(0.0, 0.5, 0.0), 0.5, 64, 32, glass))?;
    s.add_light(crate::scene::Light {
        name: "lamp".into(),
        kind: crate::scene::LightKind::Point,
        position: Vec3::new(1.2, 3.0, 0.0),
        direction: Vec3::NEG_Y,
        intensity: Vec3::splat(8.0),
        range: None,
    })?;
    s.camera = Some(Camera::look_at(Vec3::new(0.2, 2.0, 2.4), Vec3::new(-0.4, 0.2, 0.0), 45f32.to_radians()));
    Ok(s)
}
