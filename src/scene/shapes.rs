//! Procedural meshes for scenes built in code (tests, the C ABI's examples, benchmarks).

use glam::{Vec2, Vec3};

use super::Mesh;

/// A UV sphere with analytic normals: `segments` around, `rings` from pole to pole.
pub fn uv_sphere(name: &str, center: Vec3, radius: f32, segments: u32, rings: u32, material: usize) -> Mesh {
    let (segments, rings) = (segments.max(3), rings.max(2));
    let mut m = Mesh { name: name.into(), material, ..Default::default() };
    for r in 0..=rings {
        let theta = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..=segments {
            let phi = 2.0 * std::f32::consts::PI * s as f32 / segments as f32;
            let n = Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin());
            m.positions.push(center + n * radius);
            m.normals.push(n);
            m.uvs.push(Vec2::new(s as f32 / segments as f32, r as f32 / rings as f32));
        }
    }
    let row = segments + 1;
    for r in 0..rings {
        for s in 0..segments {
            let (a, b, c, d) = (r * row + s, r * row + s + 1, (r + 1) * row + s, (r + 1) * row + s + 1);
            if r != 0 {
                m.indices.extend([a, b, c]);
            }
            if r != rings - 1 {
                m.indices.extend([b, d, c]);
            }
        }
    }
    m
}

/// A planar quad `origin + u·[0,1] + v·[0,1]`, tessellated `n`×`n`, facing `u × v`.
pub fn quad(name: &str, origin: Vec3, u: Vec3, v: Vec3, n: u32, material: usize) -> Mesh {
    let n = n.max(1);
    let normal = u.cross(v).normalize();
    let mut m = Mesh { name: name.into(), material, ..Default::default() };
    for j in 0..=n {
        for i in 0..=n {
            let (a, b) = (i as f32 / n as f32, j as f32 / n as f32);
            m.positions.push(origin + u * a + v * b);
            m.normals.push(normal);
            m.uvs.push(Vec2::new(a, b));
        }
    }
    for j in 0..n {
        for i in 0..n {
            let k = j * (n + 1) + i;
            m.indices.extend([k, k + 1, k + n + 2, k, k + n + 2, k + n + 1]);
        }
    }
    m
}

/// Appends `other`'s geometry to `m` (one mesh of both).
pub fn append(m: &mut Mesh, other: &Mesh) {
    let base = m.positions.len() as u32;
    m.positions.extend_from_slice(&other.positions);
    m.normals.extend_from_slice(&other.normals);
    m.uvs.extend_from_slice(&other.uvs);
    m.indices.extend(other.indices.iter().map(|i| base + i));
}

/// An axis-aligned box of half extents `half` around `center`, six flat outward faces
/// (vertices split per face, so each face's normals are its own).
pub fn cuboid(name: &str, center: Vec3, half: Vec3, material: usize) -> Mesh {
    let mut m = Mesh { name: name.into(), material, ..Default::default() };
    for axis in 0..3 {
        for sign in [1.0f32, -1.0] {
            let n = Vec3::AXES[axis] * sign;
            let (u, v) = (Vec3::AXES[(axis + 1) % 3], Vec3::AXES[(axis + 2) % 3]);
            // u × v = n for sign +1; swap for −1 so that every face winds outward.
            let (u, v) = if sign > 0.0 {
                (u * half[(axis + 1) % 3], v * half[(axis + 2) % 3])
            } else {
                (v * half[(axis + 2) % 3], u * half[(axis + 1) % 3])
            };
            let origin = center + n * half[axis] - u - v;
            append(&mut m, &quad("", origin, 2.0 * u, 2.0 * v, 1, material));
        }
    }
    m
}

/// A right prism along `axis` (unit) through `center`, `length` long, over the triangle
/// `corners` (in the plane through `center` perpendicular to `axis`): five flat outward
/// faces.
pub fn prism(name: &str, center: Vec3, axis: Vec3, length: f32, corners: [Vec3; 3], material: usize) -> Mesh {
    let mut m = Mesh { name: name.into(), material, ..Default::default() };
    let h = axis * (0.5 * length);
    let centroid = (corners[0] + corners[1] + corners[2]) / 3.0;
    let mut face = |pts: &[Vec3]| {
        let mut n = (pts[1] - pts[0]).cross(pts[2] - pts[0]).normalize();
        let mut pts = pts.to_vec();
        if n.dot(pts[0] - (center + centroid)) < 0.0 {
            n = -n;
            pts.reverse();
        }
        let base = m.positions.len() as u32;
        for p in &pts {
            m.positions.push(*p);
            m.normals.push(n);
            m.uvs.push(Vec2::ZERO);
        }
        for k in 1..pts.len() as u32 - 1 {
            m.indices.extend([base, base + k, base + k + 1]);
        }
    };
    let c = corners.map(|p| center + p);
    face(&[c[0] + h, c[1] + h, c[2] + h]);
    face(&[c[0] - h, c[1] - h, c[2] - h]);
    for i in 0..3 {
        let (a, b) = (c[i], c[(i + 1) % 3]);
        face(&[a - h, b - h, b + h, a + h]);
    }
    m
}

/// A torus around `axis` (unit) through `center`: ring radius `major`, tube radius `minor`,
/// `segments` around the ring and `sides` around the tube (a closed, non-convex solid:
/// part of its surface hides another part from its centre).
pub fn torus(name: &str, center: Vec3, axis: Vec3, (major, minor): (f32, f32), (segments, sides): (u32, u32), material: usize) -> Mesh {
    let (segments, sides) = (segments.max(3), sides.max(3));
    let axis = axis.normalize();
    let (u, v) = axis.any_orthonormal_pair();
    let mut m = Mesh { name: name.into(), material, ..Default::default() };
    for i in 0..=segments {
        let phi = 2.0 * std::f32::consts::PI * i as f32 / segments as f32;
        let radial = u * phi.cos() + v * phi.sin();
        for j in 0..=sides {
            let theta = 2.0 * std::f32::consts::PI * j as f32 / sides as f32;
            let n = radial * theta.cos() + axis * theta.sin();
            m.positions.push(center + radial * major + n * minor);
            m.normals.push(n);
            m.uvs.push(Vec2::new(i as f32 / segments as f32, j as f32 / sides as f32));
        }
    }
    let row = sides + 1;
    for i in 0..segments {
        for j in 0..sides {
            let (a, b, c, d) = (i * row + j, (i + 1) * row + j, i * row + j + 1, (i + 1) * row + j + 1);
            // Counter-clockwise seen from outside (n = radial·cos θ + axis·sin θ).
            m.indices.extend([a, b, d, a, d, c]);
        }
    }
    fix_winding(&mut m);
    m
}

/// A spherical cap of `radius` around `center` opening towards `opening` (unit): the
/// directions within `half_angle` of `−opening` (a bowl; `half_angle` π/2 is a hemisphere),
/// normals pointing inward (its concave side faces its centre), one-sided and open.
pub fn bowl(
    name: &str,
    center: Vec3,
    opening: Vec3,
    (radius, half_angle): (f32, f32),
    (segments, rings): (u32, u32),
    material: usize,
) -> Mesh {
    let (segments, rings) = (segments.max(3), rings.max(1));
    let down = -opening.normalize();
    let (u, v) = down.any_orthonormal_pair();
    let mut m = Mesh { name: name.into(), material, ..Default::default() };
    for r in 0..=rings {
        let theta = half_angle * r as f32 / rings as f32;
        for s in 0..=segments {
            let phi = 2.0 * std::f32::consts::PI * s as f32 / segments as f32;
            let d = down * theta.cos() + (u * phi.cos() + v * phi.sin()) * theta.sin();
            m.positions.push(center + d * radius);
            m.normals.push(-d);
            m.uvs.push(Vec2::new(s as f32 / segments as f32, r as f32 / rings as f32));
        }
    }
    let row = segments + 1;
    for r in 0..rings {
        for s in 0..segments {
            let (a, b, c, d) = (r * row + s, r * row + s + 1, (r + 1) * row + s, (r + 1) * row + s + 1);
            if r != 0 {
                m.indices.extend([a, b, c]);
            }
            m.indices.extend([b, d, c]);
        }
    }
    fix_winding(&mut m);
    m
}

/// A lumpy closed solid: a UV sphere whose radius varies by up to `amount` (a fraction)
/// with a few low-frequency lobes set by `seed`; normals from the surface. Non-convex for
/// `amount` above about 0.15 (a stand-in for scanned models such as the bunny).
pub fn blob(name: &str, center: Vec3, (radius, amount): (f32, f32), seed: u32, (segments, rings): (u32, u32), material: usize) -> Mesh {
    let mut m = uv_sphere(name, Vec3::ZERO, 1.0, segments, rings, material);
    let k = |i: u32| ((seed.wrapping_mul(2654435761).wrapping_add(i.wrapping_mul(40503))) % 1000) as f32 / 1000.0;
    let lobes: Vec<(Vec3, f32)> = (0..5)
        .map(|i| {
            let (a, b) = (k(3 * i) * std::f32::consts::TAU, k(3 * i + 1) * 2.0 - 1.0);
            let r = (1.0 - b * b).sqrt();
            (Vec3::new(r * a.cos(), b, r * a.sin()), 0.5 + k(3 * i + 2))
        })
        .collect();
    let f = |d: Vec3| 1.0 + amount * lobes.iter().map(|(c, w)| w * (4.0 * (d.dot(*c) - 1.0)).exp()).sum::<f32>();
    for p in m.positions.iter_mut() {
        let d = p.normalize_or_zero();
        *p = center + d * radius * f(d);
    }
    // Area-weighted face normals per vertex, welded across the seam by position.
    let mut acc = vec![Vec3::ZERO; m.positions.len()];
    for t in m.indices.chunks_exact(3) {
        let (a, b, c) = (m.positions[t[0] as usize], m.positions[t[1] as usize], m.positions[t[2] as usize]);
        let n = (b - a).cross(c - a);
        t.iter().for_each(|&i| acc[i as usize] += n);
    }
    let mut welded: std::collections::HashMap<[u32; 3], Vec3> = std::collections::HashMap::new();
    for (p, n) in m.positions.iter().zip(&acc) {
        *welded.entry([p.x.to_bits(), p.y.to_bits(), p.z.to_bits()]).or_default() += *n;
    }
    for (p, n) in m.positions.iter().zip(m.normals.iter_mut()) {
        *n = welded[&[p.x.to_bits(), p.y.to_bits(), p.z.to_bits()]].normalize_or_zero();
    }
    m
}

/// Winds every triangle counter-clockwise around its vertex normals (glTF's convention).
fn fix_winding(m: &mut Mesh) {
    for t in m.indices.chunks_exact_mut(3) {
        let (a, b, c) = (m.positions[t[0] as usize], m.positions[t[1] as usize], m.positions[t[2] as usize]);
        let n = m.normals[t[0] as usize] + m.normals[t[1] as usize] + m.normals[t[2] as usize];
        if (b - a).cross(c - a).dot(n) < 0.0 {
            t.swap(1, 2);
        }
    }
}

/// The six inward-facing walls of an axis-aligned box room, in the order
/// +X, −X, +Y, −Y, +Z, −Z, each split into 2×2 quadrants (24 meshes). Quadrant q of a
/// wall covers the signs (bit 1: second in-plane axis > 0, bit 0: first > 0) of the two
/// other coordinates relative to `center`, the in-plane axes taken in x, y, z order.
/// `material(wall, quadrant)` names each quadrant's material.
pub fn quadrant_room(center: Vec3, half: f32, tessellation: u32, material: impl Fn(usize, usize) -> usize) -> Vec<Mesh> {
    let mut meshes = Vec::new();
    for wall in 0..6 {
        let axis = wall / 2;
        let sign = if wall % 2 == 0 { 1.0 } else { -1.0 };
        let (a1, a2) = match axis {
            0 => (1, 2),
            1 => (0, 2),
            _ => (0, 1),
        };
        for q in 0..4 {
            let (p1, p2) = (if q & 1 != 0 { 1.0 } else { -1.0 }, if q & 2 != 0 { 1.0 } else { -1.0 });
            let mut o = Vec3::ZERO;
            o[axis] = sign * half;
            let mut u = Vec3::ZERO;
            u[a1] = p1 * half;
            let mut v = Vec3::ZERO;
            v[a2] = p2 * half;
            // Orient each quad to face the room's centre.
            let (u, v) = if u.cross(v).dot(-o) > 0.0 { (u, v) } else { (v, u) };
            meshes.push(quad(&format!("wall{wall}.q{q}"), center + o, u, v, tessellation, material(wall, q)));
        }
    }
    meshes
}

/// Which wall and quadrant of `quadrant_room` the ray from `center` along `d` hits.
pub fn quadrant_room_hit(d: Vec3) -> (usize, usize) {
    let a = d.abs();
    let axis = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    let wall = 2 * axis + if d[axis] >= 0.0 { 0 } else { 1 };
    let (a1, a2) = match axis {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    };
    (wall, (d[a1] > 0.0) as usize | (((d[a2] > 0.0) as usize) << 1))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// glTF's convention: counter-clockwise seen from the side the normal points to.
    fn outward_ccw(m: &Mesh) -> bool {
        m.indices.chunks_exact(3).all(|t| {
            let (a, b, c) = (m.positions[t[0] as usize], m.positions[t[1] as usize], m.positions[t[2] as usize]);
            let n = m.normals[t[0] as usize] + m.normals[t[1] as usize] + m.normals[t[2] as usize];
            let f = (b - a).cross(c - a);
            f.length_squared() < 1e-20 || f.dot(n) > 0.0
        })
    }

    #[test]
    fn shapes_wind_counter_clockwise_around_their_normals() {
        assert!(outward_ccw(&uv_sphere("s", Vec3::ZERO, 1.0, 16, 8, 0)));
        assert!(outward_ccw(&quad("q", Vec3::ZERO, Vec3::X, Vec3::Y, 3, 0)));
        assert!(outward_ccw(&torus("t", Vec3::ZERO, Vec3::Y, (1.0, 0.3), (16, 8), 0)));
        assert!(outward_ccw(&bowl("b", Vec3::ZERO, Vec3::Y, (1.0, 1.5), (16, 6), 0)));
        assert!(outward_ccw(&blob("l", Vec3::ZERO, (1.0, 0.3), 7, (16, 8), 0)));
        for m in quadrant_room(Vec3::ZERO, 1.0, 2, |_, _| 0) {
            assert!(outward_ccw(&m), "{}", m.name);
        }
        let demo = crate::scene::load(std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/demo/demo.gltf"))).unwrap();
        for m in &demo.meshes {
            assert!(outward_ccw(m), "demo mesh {}", m.name);
        }
    }
}
