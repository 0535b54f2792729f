//! Flat-faced solids (survey §5, GS04): a mesh split into its planar faces — triangles
//! grouped by plane, each face with its outward plane and its outline (the convex hull of
//! its vertices in the plane) — and the test that the solid is convex (every vertex behind
//! every face's plane), which the linearised refraction of `planar-refraction` needs: a ray
//! that enters a convex solid through one face leaves it through another.

use glam::{DVec3, Vec2, Vec3, Vec4};

use crate::scene::Mesh;

/// The most faces a flat-faced solid may have: beyond it (a finely tessellated curved
/// surface) every face would need views of its own, and distance maps serve it better.
pub const MAX_FACES: usize = 64;

/// Normals of one face agree within this cosine (about 1.8°).
const COS_SAME_PLANE: f64 = 0.9995;

/// One planar face of a mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct Face {
    /// Outward plane n·p + w = 0 (unit n): the vertex normals' side.
    pub plane: Vec4,
    /// Convex hull of its vertices, counter-clockwise around n.
    pub outline: Vec<Vec3>,
    /// Its area.
    pub area: f32,
}

/// The planar faces of `m` (at most `max`), or `None` when it is not flat-faced: more faces
/// than `max`, a vertex normal off its face's plane normal (smooth shading: the surface
/// the normals describe is curved), or no triangle of any area. Planes agree within ~1.8°
/// and 1e-4 of the mesh's size.
pub fn planar_faces(m: &Mesh, max: usize) -> Option<Vec<Face>> {
    let diag = m.bounds().diagonal() as f64;
    if !diag.is_finite() || diag <= 0.0 {
        return None;
    }
    let tol = 1e-4 * diag;
    let p = |i: u32| m.positions[i as usize].as_dvec3();
    // (area-weighted normal sum, a point, triangles)
    struct Group {
        n: DVec3,
        unit: DVec3,
        origin: DVec3,
        tris: Vec<[u32; 3]>,
        area: f64,
    }
    let mut groups: Vec<Group> = Vec::new();
    for t in m.indices.chunks_exact(3) {
        let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
        let cross = (b - a).cross(c - a);
        let twice_area = cross.length();
        if twice_area.is_nan() || twice_area <= 1e-12 * diag * diag {
            continue; // degenerate: no plane of its own, lies in its neighbours'
        }
        let mut n = cross / twice_area;
        // Outward is where the vertex normals point (the winding may be either).
        if !m.normals.is_empty() {
            let vn: DVec3 = t.iter().map(|&i| m.normals[i as usize].as_dvec3()).sum();
            if vn.dot(n) < 0.0 {
                n = -n;
            }
            for &i in t {
                let v = m.normals[i as usize].as_dvec3().normalize_or_zero();
                if v.dot(n) < COS_SAME_PLANE {
                    return None; // smooth shading: not a flat face
                }
            }
        }
        let on = |g: &Group| g.unit.dot(n) >= COS_SAME_PLANE && [a, b, c].iter().all(|v| (*v - g.origin).dot(g.unit).abs() <= tol);
        match groups.iter_mut().find(|g| on(g)) {
            Some(g) => {
                g.n += n * twice_area;
                g.tris.push([t[0], t[1], t[2]]);
                g.area += 0.5 * twice_area;
            }
            None => {
                if groups.len() == max {
                    return None;
                }
                groups.push(Group { n: n * twice_area, unit: n, origin: a, tris: vec![[t[0], t[1], t[2]]], area: 0.5 * twice_area });
            }
        }
    }
    if groups.is_empty() {
        return None;
    }
    let faces = groups
        .iter()
        .map(|g| {
            let n = g.n.normalize();
            // The plane through the face's vertices' mean distance.
            let verts: Vec<DVec3> = g.tris.iter().flatten().map(|&i| p(i)).collect();
            let offset = verts.iter().map(|v| v.dot(n)).sum::<f64>() / verts.len() as f64;
            let u = n.any_orthonormal_vector();
            let v = n.cross(u);
            let flat: Vec<Vec2> = verts.iter().map(|q| Vec2::new(q.dot(u) as f32, q.dot(v) as f32)).collect();
            let hull = convex_hull(&flat);
            let outline = hull.iter().map(|q| (n * offset + u * q.x as f64 + v * q.y as f64).as_vec3()).collect();
            Face { plane: n.as_vec3().extend(-offset as f32), outline, area: g.area as f32 }
        })
        .collect();
    Some(faces)
}

/// Whether the solid bounded by `faces` is convex: every vertex of `m` lies behind (or
/// within 1e-4 of the size on) every face's plane.
pub fn is_convex(m: &Mesh, faces: &[Face]) -> bool {
    let tol = 1e-4 * m.bounds().diagonal();
    faces.iter().all(|f| m.positions.iter().all(|p| f.plane.truncate().dot(*p) + f.plane.w <= tol))
}

/// The convex hull of points in the plane, counter-clockwise (Andrew's monotone chain);
/// collinear points dropped.
pub fn convex_hull(points: &[Vec2]) -> Vec<Vec2> {
    let mut pts: Vec<Vec2> = points.to_vec();
    pts.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    pts.dedup();
    if pts.len() < 3 {
        return pts;
    }
    let cross = |o: Vec2, a: Vec2, b: Vec2| (a - o).perp_dot(b - o);
    let mut hull: Vec<Vec2> = Vec::with_capacity(2 * pts.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &Vec2>> = if pass == 0 { Box::new(pts.iter()) } else { Box::new(pts.iter().rev()) };
        for &q in iter {
            while hull.len() >= start + 2 && cross(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 0.0 {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop(); // the last point starts the other chain
    }
    hull
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::shapes;

    #[test]
    fn a_box_has_six_faces_and_is_convex() {
        let m = shapes::cuboid("slab", Vec3::new(0.0, 0.5, 0.0), Vec3::new(1.0, 0.1, 0.5), 0);
        let faces = planar_faces(&m, MAX_FACES).expect("flat-faced");
        assert_eq!(faces.len(), 6);
        for f in &faces {
            assert_eq!(f.outline.len(), 4, "{f:?}");
            // Outward: the centre lies behind every face.
            assert!(f.plane.truncate().dot(Vec3::new(0.0, 0.5, 0.0)) + f.plane.w < 0.0);
        }
        let top = faces.iter().find(|f| f.plane.y > 0.99).unwrap();
        assert!((top.plane.w + 0.6).abs() < 1e-6 && (top.area - 4.0 * 1.0 * 0.5).abs() < 1e-5, "{top:?}");
        assert!(is_convex(&m, &faces));
    }

    #[test]
    fn smooth_spheres_are_not_flat_faced() {
        let s = shapes::uv_sphere("s", Vec3::ZERO, 1.0, 8, 6, 0);
        assert!(planar_faces(&s, MAX_FACES).is_none());
    }

    #[test]
    fn too_many_faces_or_none_are_refused() {
        let m = shapes::cuboid("slab", Vec3::ZERO, Vec3::ONE, 0);
        assert!(planar_faces(&m, 5).is_none());
        let mut empty = m.clone();
        empty.indices.clear();
        assert!(planar_faces(&empty, MAX_FACES).is_none());
    }

    #[test]
    fn hull_drops_inner_and_collinear_points() {
        let pts = [Vec2::ZERO, Vec2::new(1.0, 0.0), Vec2::new(0.5, 0.0), Vec2::new(1.0, 1.0), Vec2::new(0.0, 1.0), Vec2::splat(0.5)];
        let h = convex_hull(&pts);
        assert_eq!(h, vec![Vec2::ZERO, Vec2::new(1.0, 0.0), Vec2::new(1.0, 1.0), Vec2::new(0.0, 1.0)]);
    }
}
