//! A pool of water under the sun (survey §6.4: simplified water caustics, `caustic_paths=surface`).

use glam::{Vec2, Vec3};

use crate::error::Result;
use crate::scene::{shapes, Camera, Light, LightKind, Material, Mesh, Scene, SurfaceKind};

/// The water body's half-width (x and z), its bottom (just under the floor at y = 0, so that
/// the floor lies inside the water) and its mean level.
pub const POOL_HALF: f32 = 1.5;
pub const POOL_BOTTOM: f32 = -0.02;
pub const POOL_LEVEL: f32 = 0.45;

/// The sun's direction of travel and irradiance [W/m²] over the pool.
pub const SUN: Vec3 = Vec3::new(0.15, -1.0, 0.1);
pub const SUN_IRRADIANCE: f32 = 2.0;

/// The waves: (amplitude m, wavelength m, direction, phase), each travelling at deep water's
/// speed (ω = √(g k)).
const WAVES: [(f32, f32, Vec2, f32); 3] =
    [(0.02, 0.9, Vec2::new(1.0, 0.3), 0.0), (0.015, 0.6, Vec2::new(-0.4, 1.0), 1.3), (0.01, 0.37, Vec2::new(0.7, -0.7), 2.1)];

/// The water's height at (x, z) and time t [s], and its gradient (∂h/∂x, ∂h/∂z).
pub fn wave_height(x: f32, z: f32, t: f32) -> (f32, Vec2) {
    let mut h = POOL_LEVEL;
    let mut g = Vec2::ZERO;
    for (a, lambda, dir, phase) in WAVES {
        let k = dir.normalize() * (std::f32::consts::TAU / lambda);
        let omega = (9.81 * k.length()).sqrt();
        let arg = k.dot(Vec2::new(x, z)) - omega * t + phase;
        h += a * arg.sin();
        g += k * (a * arg.cos());
    }
    (h, g)
}

/// The water body at time t: a closed solid whose top is the wave height field (`grid`² cells
/// with the analytic normals), its sides vertical and its bottom flat under the floor.
pub fn water_body(material: usize, grid: u32, t: f32) -> Mesh {
    let n = grid.max(1);
    let a = POOL_HALF;
    let mut m = Mesh { name: "water".into(), material, ..Default::default() };
    let at = |i: u32| -a + 2.0 * a * i as f32 / n as f32;
    // The top: the height field.
    for j in 0..=n {
        for i in 0..=n {
            let (x, z) = (at(i), at(j));
            let (h, g) = wave_height(x, z, t);
            m.positions.push(Vec3::new(x, h, z));
            m.normals.push(Vec3::new(-g.x, 1.0, -g.y).normalize());
            m.uvs.push(Vec2::new(i as f32, j as f32) / n as f32);
        }
    }
    for j in 0..n {
        for i in 0..n {
            let (p, q, r, s) = (j * (n + 1) + i, j * (n + 1) + i + 1, (j + 1) * (n + 1) + i, (j + 1) * (n + 1) + i + 1);
            m.indices.extend([p, r, q, q, r, s]);
        }
    }
    // The sides: from the top's edge down to the bottom, facing out.
    type Side = (fn(f32, f32) -> Vec3, Vec3);
    let sides: [Side; 4] = [
        (|u, y| Vec3::new(u, y, -POOL_HALF), Vec3::NEG_Z),
        (|u, y| Vec3::new(u, y, POOL_HALF), Vec3::Z),
        (|u, y| Vec3::new(-POOL_HALF, y, u), Vec3::NEG_X),
        (|u, y| Vec3::new(POOL_HALF, y, u), Vec3::X),
    ];
    for (point, normal) in sides {
        let first = m.positions.len() as u32;
        for i in 0..=n {
            let top = point(at(i), 0.0);
            let (h, _) = wave_height(top.x, top.z, t);
            for y in [h, POOL_BOTTOM] {
                m.positions.push(point(at(i), y));
                m.normals.push(normal);
                m.uvs.push(Vec2::ZERO);
            }
        }
        for i in 0..n {
            let (p, q, r, s) = (first + 2 * i, first + 2 * i + 1, first + 2 * i + 2, first + 2 * i + 3);
            m.indices.extend([p, q, r, r, q, s]);
        }
    }
    let first = m.positions.len() as u32;
    for (x, z) in [(-a, -a), (a, -a), (-a, a), (a, a)] {
        m.positions.push(Vec3::new(x, POOL_BOTTOM, z));
        m.normals.push(Vec3::NEG_Y);
        m.uvs.push(Vec2::ZERO);
    }
    m.indices.extend([first, first + 1, first + 2, first + 1, first + 3, first + 2]);
    // Every triangle wound counter-clockwise seen from outside: against its vertices' normal.
    for t in m.indices.chunks_exact_mut(3) {
        let [p0, p1, p2] = [t[0], t[1], t[2]].map(|i| m.positions[i as usize]);
        if (p1 - p0).cross(p2 - p0).dot(m.normals[t[0] as usize]) < 0.0 {
            t.swap(1, 2);
        }
    }
    m
}

/// A pool of water (index 1.33) over a diffuse floor under the sun, its surface the waves at
/// time `t`: the floor under the water is lit only by the light the waves focus (survey §6.4).
pub fn pool_at(t: f32) -> Result<Scene> {
    let mut s = Scene::new();
    let floor = s.add_material(Material { name: "floor".into(), base_color: Vec3::splat(0.8), ..Default::default() })?;
    s.add_mesh(shapes::quad("floor", Vec3::new(-2.5, 0.0, 2.5), Vec3::new(5.0, 0.0, 0.0), Vec3::new(0.0, 0.0, -5.0), 8, floor))?;
    let water =
        s.add_material(Material { name: "water".into(), kind: SurfaceKind::Dielectric { ior: 1.33, thin: false }, ..Default::default() })?;
    // The caustic cube's centre (the generator's reference point) well above the water: seen
    // from there the floor's texels are alike in size (from the water's own centre, 0.2 m
    // over the floor, the texels under it are a hundredth of those at its rim, finer than
    // the photons: holes between their triangles and splats).
    let mut body = water_body(water, 48, t);
    body.reference_point = Some(Vec3::new(0.0, 2.0, 0.0));
    s.add_mesh(body)?;
    s.add_light(Light {
        name: "sun".into(),
        kind: LightKind::Directional,
        position: Vec3::new(0.0, 5.0, 0.0),
        direction: SUN,
        intensity: Vec3::splat(SUN_IRRADIANCE),
        range: None,
    })?;
    s.camera = Some(Camera::look_at(Vec3::new(0.02, 2.4, 2.9), Vec3::new(0.0, 0.0, -0.2), 50f32.to_radians()));
    Ok(s)
}

/// [`pool_at`] at time 0.
pub fn pool() -> Result<Scene> {
    pool_at(0.0)
}
