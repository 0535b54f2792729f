//! How many reflection points a curved mirror has for the environment's vertices (survey
//! §5): geometry transformation moves each environment vertex to the one point of the
//! reflector where the normal bisects the directions to the eye and to the vertex, which a
//! search on the reflector finds only where that point is unique. A saddle has several
//! (`facts::curvature` refuses it); so do meshes that are convex or concave edge by edge and
//! still hold several minima — two separate balls in one mesh, a ring of bumps. This is the
//! planner's check of that, on the CPU from the mesh and the camera, before anything is
//! drawn (the GPU search checks again per frame: `geometry.curved_multiple_minima`).

use std::collections::HashMap;

use glam::DVec3;

use crate::scene::{Mesh, Scene};

/// Environment vertices sampled (evenly by index over the other visible meshes), at most;
/// fewer on large reflectors, so that a check scores at most [`WORK`] vertices in all (the
/// planner runs it on every plan and every move).
pub const SAMPLES: usize = 64;
const WORK: usize = 1 << 21;
/// A reflector is refused where at least [`MIN_FOUND`] and more than this share of the
/// sampled environment vertices that have a reflection point on it have a second one: on
/// the two-ball mesh of `tests/curved.rs` 26 % of the GPU's checks find one (61 of 61
/// here), on a sphere and a bowl none. Well above one sample's share, so that a small move
/// does not flip the verdict.
pub const SHARE: f64 = 0.10;
pub const MIN_FOUND: u32 = 3;
/// Two reflection points count as two when their normals differ by more than this cosine
/// (the GPU search's `CURVED_MIN_COS`): not the same valley reached twice.
const APART_COS: f64 = 0.98;

/// Sampled environment vertices with a second reflection point on mesh `index` seen from
/// `eye`, and those with one at all: (found, checked). Per sample, every welded vertex of
/// the mesh facing both the eye and the sample scores the cosine between its normal and the
/// bisector; a reflection point is a vertex that scores at least as well as its neighbours
/// and lies within the mesh's angular resolution (the largest turn of the normal along an
/// edge, plus 2°) of the law. A second one counts when it lies outside the first's two rings
/// of neighbours with a normal `APART_COS` apart.
pub fn several(scene: &Scene, index: usize, eye: glam::Vec3) -> (u32, u32) {
    let Some(mesh) = scene.meshes.get(index) else { return (0, 0) };
    let w = Welded::new(mesh);
    if w.positions.len() < 3 {
        return (0, 0);
    }
    let tolerance = (w.turn + 0.035).min(std::f64::consts::FRAC_PI_4).cos();
    let eye = eye.as_dvec3();
    let others: Vec<&Mesh> = scene.meshes.iter().enumerate().filter(|(i, m)| *i != index && !m.hidden).map(|(_, m)| m).collect();
    let total: usize = others.iter().map(|m| m.positions.len()).sum();
    let samples = SAMPLES.min(WORK / w.positions.len()).max(4);
    let stride = total.div_ceil(samples).max(1);
    let samples = others.iter().flat_map(|m| m.positions.iter()).step_by(stride).map(|p| p.as_dvec3());
    let (mut found, mut checked) = (0, 0);
    let mut score = vec![0.0f64; w.positions.len()];
    for x in samples {
        for (v, s) in score.iter_mut().enumerate() {
            let (p, n) = (w.positions[v], w.normals[v]);
            let (to_eye, to_x) = (eye - p, x - p);
            *s = if n.dot(to_eye) > 0.0 && n.dot(to_x) > 0.0 {
                let h = to_eye.normalize_or_zero() + to_x.normalize_or_zero();
                if h.length() > 1e-9 {
                    n.dot(h.normalize())
                } else {
                    -2.0
                }
            } else {
                -2.0
            };
        }
        let points: Vec<usize> =
            (0..score.len()).filter(|&v| score[v] >= tolerance && w.neighbours[v].iter().all(|&u| score[u as usize] <= score[v])).collect();
        let Some(&best) = points.iter().max_by(|&&a, &&b| score[a].total_cmp(&score[b])) else { continue };
        checked += 1;
        let near = w.rings(best, 2);
        if points.iter().any(|&v| !near.contains(&v) && w.normals[v].dot(w.normals[best]) < APART_COS) {
            found += 1;
        }
    }
    (found, checked)
}

/// Whether (found, checked) means several minima: more than [`SHARE`] of the checks, and at
/// least [`MIN_FOUND`].
pub fn refused((found, checked): (u32, u32)) -> bool {
    found >= MIN_FOUND && found as f64 > SHARE * checked as f64
}

/// A mesh with coincident vertices (seams, poles) merged, normals averaged: the surface the
/// search sees, without the parameterisation's cuts.
struct Welded {
    positions: Vec<DVec3>,
    normals: Vec<DVec3>,
    neighbours: Vec<Vec<u32>>,
    /// The largest angle between the normals at an edge's ends (radians).
    turn: f64,
}

impl Welded {
    fn new(m: &Mesh) -> Welded {
        let step = (m.bounds().diagonal() as f64 * 1e-5).max(1e-12);
        let mut ids: HashMap<[i64; 3], u32> = HashMap::new();
        let (mut positions, mut normals) = (Vec::new(), Vec::<DVec3>::new());
        let map: Vec<u32> = m
            .positions
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let p = p.as_dvec3();
                let key = [(p.x / step).round() as i64, (p.y / step).round() as i64, (p.z / step).round() as i64];
                let id = *ids.entry(key).or_insert_with(|| {
                    positions.push(p);
                    normals.push(DVec3::ZERO);
                    positions.len() as u32 - 1
                });
                normals[id as usize] += m.normals.get(i).map_or(DVec3::ZERO, |n| n.as_dvec3());
                id
            })
            .collect();
        let normals: Vec<DVec3> = normals.into_iter().map(|n| n.normalize_or_zero()).collect();
        let mut neighbours = vec![Vec::new(); positions.len()];
        for t in m.indices.chunks_exact(3) {
            let c = [t[0], t[1], t[2]].map(|i| map.get(i as usize).copied());
            let [Some(a), Some(b), Some(c)] = c else { continue };
            for (u, v) in [(a, b), (b, c), (c, a)] {
                if u != v {
                    neighbours[u as usize].push(v);
                    neighbours[v as usize].push(u);
                }
            }
        }
        let mut turn = 0.0f64;
        for (u, list) in neighbours.iter_mut().enumerate() {
            list.sort_unstable();
            list.dedup();
            for &v in list.iter() {
                turn = turn.max(normals[u].dot(normals[v as usize]).clamp(-1.0, 1.0).acos());
            }
        }
        Welded { positions, normals, neighbours, turn }
    }

    /// `v` and the vertices within `k` edges of it.
    fn rings(&self, v: usize, k: usize) -> std::collections::HashSet<usize> {
        let mut set = std::collections::HashSet::from([v]);
        let mut frontier = vec![v];
        for _ in 0..k {
            let mut next = Vec::new();
            for &u in &frontier {
                for &n in &self.neighbours[u] {
                    if set.insert(n as usize) {
                        next.push(n as usize);
                    }
                }
            }
            frontier = next;
        }
        set
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{shapes, Material, Scene};
    use glam::Vec3;

    fn room_with(mesh: impl FnOnce(usize) -> Mesh) -> Scene {
        let mut s = Scene::new();
        let grey = s.add_material(Material { name: "grey".into(), ..Default::default() }).unwrap();
        let mirror = s
            .add_material(Material {
                name: "mirror".into(),
                kind: crate::scene::SurfaceKind::Mirror { nu: Vec3::splat(10.0), kappa: Vec3::ZERO },
                ..Default::default()
            })
            .unwrap();
        s.meshes.push(mesh(mirror));
        s.meshes.push(shapes::cuboid("room", Vec3::ZERO, Vec3::splat(2.0), grey));
        s
    }

    /// One ball: one reflection point for every environment vertex; two balls in one mesh
    /// (convex along every edge): a second one for many.
    #[test]
    fn two_balls_in_one_mesh_have_several_reflection_points() {
        let eye = Vec3::new(0.0, 0.3, 1.9);
        let one = room_with(|m| shapes::uv_sphere("ball", Vec3::new(0.0, -0.3, 0.0), 0.4, 32, 16, m));
        let (found, checked) = several(&one, 0, eye);
        assert!(checked > 10 && found == 0 && !refused((found, checked)), "{found} of {checked}");
        let two = room_with(|m| {
            let mut a = shapes::uv_sphere("pair", Vec3::new(-0.5, -0.3, 0.0), 0.4, 32, 16, m);
            let b = shapes::uv_sphere("pair", Vec3::new(0.5, -0.3, 0.0), 0.4, 32, 16, m);
            let base = a.positions.len() as u32;
            a.positions.extend(&b.positions);
            a.normals.extend(&b.normals);
            a.uvs.extend(&b.uvs);
            a.indices.extend(b.indices.iter().map(|i| i + base));
            a
        });
        let (found, checked) = several(&two, 0, eye);
        eprintln!("two balls: {found} of {checked}");
        assert!(refused((found, checked)), "{found} of {checked}");
    }
}
