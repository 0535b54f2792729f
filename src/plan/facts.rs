//! Geometry facts the planner decides from, computed once per mesh and cached: planarity,
//! watertightness, convexity from the reference point (the area fraction of the surface
//! visible from it), whether other specular objects are visible from it, and whether the
//! automatic reference point lies inside or too close to another object (a reference
//! point inside another object sees nothing but that object: it is moved).

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use glam::{DVec3, Vec3};

use crate::optics::ray_triangle;
use crate::plan::ids::ObjectClass;
use crate::quality::Quality;
use crate::reference::bvh::Bvh;
use crate::scene::{Mesh, Scene};

/// Facts of one specular object in its scene.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ObjectFacts {
    pub mesh: usize,
    pub class: ObjectClass,
    /// A solid dielectric whose index varies in space (survey §6.5): its rays curve, which
    /// only the methods of `Family::curved_rays` trace.
    pub graded: bool,
    /// All vertices within 1e-4 of the object's size of one plane, normals agreeing.
    pub planar: bool,
    /// A closed convex solid of at most `faces::MAX_FACES` flat faces (each face's vertex
    /// normals its plane's): a gem, a prism, a slab (survey §5, GS04).
    pub faceted: bool,
    /// Every edge shared by exactly two triangles (positions welded).
    pub watertight: bool,
    /// Convex, concave (towards its normals), flat or neither (saddle-shaped): the
    /// reflection-point search of curved reflectors (§5) has one minimum on the first three.
    pub curvature: Curvature,
    /// A curved mirror's reflection points (survey §5): of the environment vertices sampled
    /// with one on it seen from the camera, those with a second one — (found, checked)
    /// (`reflection_points::several`; (0, 0) for other objects, planar, saddle-shaped).
    pub reflection_points: (u32, u32),
    /// Farthest over nearest distance of the surfaces around the reference point (2048 rays;
    /// 1 without deep facts): the environment's depth variation.
    pub depth_ratio: f32,
    /// The nearest surface of the environment from the reference point over the object's
    /// bounding radius (same rays; 0 without deep facts): how far what it reflects lies
    /// relative to its size (a map's parallax error grows as this falls).
    pub near_ratio: f32,
    /// The largest angle (radians) an edge of another object's triangles subtends from the
    /// reference point: how coarsely the environment is tessellated as seen from the
    /// object (geometry transformation bends only vertices, survey Table 1). 0 without deep
    /// facts.
    pub edge_angle: f32,
    /// Area fraction of the surface visible from the reference point (1: convex from it,
    /// as a single-layer map needs). Computed for `auto` only, else 1.
    pub visible_fraction: f32,
    /// Other specular objects visible from the reference point: (mesh, fraction of the
    /// sphere of directions they cover), largest first.
    pub sees_specular: Vec<(usize, f32)>,
    /// Fraction of the directions from the reference point whose first surface lies on the
    /// scene's bounding box (1: the environment is a box room with nothing in it, and the
    /// proxy box of §3.2 is exact). 0 without deep facts.
    pub box_fraction: f32,
    /// A planar mirror or thin pane covers at least `MIN_COVERAGE` of its directions: cube
    /// maps show a planar mirror one reflection deep and a pane reflecting and transmitting
    /// the environment only, so such an object needs rays to see them exactly.
    pub sees_planar_mirror: bool,
    /// Area fraction of the surface whose normal faces the reference point (0: convex
    /// around it; a concave mirror that reflects itself, such as a bowl, faces it).
    pub self_facing: f32,
    pub reference_point: Vec3,
    pub reference_note: Option<String>,
    pub triangles: usize,
}

/// The facts of every specular object of a scene.
pub struct SceneFacts {
    pub objects: Vec<ObjectFacts>,
}

/// What depends on the mesh alone.
#[derive(Clone, Debug)]
struct MeshFacts {
    planar: bool,
    faceted: bool,
    watertight: bool,
    curvature: Curvature,
}

/// How a mesh bends, seen from the side its vertex normals point to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Curvature {
    /// No edge bends (a plane).
    Flat,
    /// Every edge bends away from the normals (a sphere seen from outside).
    Convex,
    /// Every edge bends towards the normals (the inside of a bowl).
    Concave,
    /// Both (a saddle, a torus): neither convex nor concave.
    Saddle,
}

impl Curvature {
    pub fn label(self) -> &'static str {
        match self {
            Curvature::Flat => "flat",
            Curvature::Convex => "convex",
            Curvature::Concave => "concave",
            Curvature::Saddle => "saddle-shaped (neither convex nor concave)",
        }
    }
}

/// The fraction of the total bending (dihedral angle × edge length) that may go the other
/// way before a mesh counts as neither convex nor concave: tessellation noise of a
/// curved surface stays far below it.
pub const SADDLE_FRACTION: f64 = 0.02;

/// A triangle on an edge: (triangle, the edge's first corner, the opposite corner).
type Corner = (usize, u32, u32);

/// Classifies mesh `m` by how its surface bends relative to its normals. Where the vertex
/// normals vary (a smooth mesh: what the reflection search reads, interpolated), by the sign
/// of (n_b − n_a)·(p_b − p_a) along every triangle edge: the normal curvature in the edge's
/// direction, positive where the normals diverge (convex), negative where they converge
/// (concave), of both signs on a saddle; this does not depend on how the surface was
/// triangulated. Where they do not (a faceted mesh), by the signs of the dihedral angles at
/// edges shared by two triangles (positions welded at 1e-6 of its size): whether the
/// opposite corner of each lies behind (convex) or in front of (concave) the other's plane.
/// Each sign is weighted by its magnitude; a mesh counts as neither convex nor concave when
/// the lesser sign carries more than `SADDLE_FRACTION` of the total.
pub fn curvature(m: &Mesh) -> Curvature {
    let diag = m.bounds().diagonal() as f64;
    if m.indices.len() < 3 || diag <= 0.0 || !diag.is_finite() || m.normals.len() != m.positions.len() {
        return Curvature::Flat;
    }
    let p = |i: u32| m.positions[i as usize].as_dvec3();
    let n = |i: u32| m.normals[i as usize].as_dvec3().normalize_or_zero();
    let classify = |convex: f64, concave: f64| {
        let total = convex + concave;
        if total <= 0.0 {
            Curvature::Flat
        } else if concave <= SADDLE_FRACTION * total {
            Curvature::Convex
        } else if convex <= SADDLE_FRACTION * total {
            Curvature::Concave
        } else {
            Curvature::Saddle
        }
    };
    let (mut convex, mut concave) = (0.0f64, 0.0f64);
    let flat = 1e-9 * diag * diag;
    for t in m.indices.chunks_exact(3) {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let s = (n(b) - n(a)).dot(p(b) - p(a));
            if s > flat {
                convex += s;
            } else if s < -flat {
                concave -= s;
            }
        }
    }
    if convex + concave > 0.0 {
        return classify(convex, concave);
    }
    // Faceted: the dihedral angles.
    let scale = 1e-6 * diag;
    let key = |v: Vec3| ((v.x as f64 / scale).round() as i64, (v.y as f64 / scale).round() as i64, (v.z as f64 / scale).round() as i64);
    let mut ids: HashMap<(i64, i64, i64), u32> = HashMap::new();
    let weld: Vec<u32> = m
        .positions
        .iter()
        .map(|&v| {
            let n = ids.len() as u32;
            *ids.entry(key(v)).or_insert(n)
        })
        .collect();
    let mut normals = Vec::with_capacity(m.indices.len() / 3);
    let mut edges: HashMap<(u32, u32), Vec<Corner>> = HashMap::new();
    for (t, tri) in m.indices.chunks_exact(3).enumerate() {
        let g = (p(tri[1]) - p(tri[0])).cross(p(tri[2]) - p(tri[0]));
        let shading: DVec3 = tri.iter().map(|&i| n(i)).sum();
        normals.push((if g.dot(shading) < 0.0 { -g } else { g }).try_normalize());
        if normals[t].is_none() {
            continue;
        }
        for k in 0..3 {
            let (a, b) = (weld[tri[k] as usize], weld[tri[(k + 1) % 3] as usize]);
            if a != b {
                edges.entry((a.min(b), a.max(b))).or_default().push((t, tri[k], tri[(k + 2) % 3]));
            }
        }
    }
    let flat = 1e-7 * diag;
    for tris in edges.values() {
        let [(t1, a, c), (t2, _, d)] = tris[..] else { continue };
        let (Some(n1), Some(n2)) = (normals[t1], normals[t2]) else { continue };
        let (h1, h2) = (n1.dot(p(d) - p(a)), n2.dot(p(c) - p(a)));
        if h1.abs() <= flat && h2.abs() <= flat {
            continue;
        }
        let bend = n1.dot(n2).clamp(-1.0, 1.0).acos();
        if h1 < 0.0 && h2 < 0.0 {
            convex += bend;
        } else if h1 > 0.0 && h2 > 0.0 {
            concave += bend;
        }
    }
    classify(convex, concave)
}

static CACHE: Mutex<Option<HashMap<u64, Arc<MeshFacts>>>> = Mutex::new(None);
/// Visible fractions by (mesh hash, reference point bits).
type VisibleCache = HashMap<(u64, [u32; 3]), f32>;
static VISIBLE: Mutex<Option<VisibleCache>> = Mutex::new(None);
/// Reflection-point counts by (the reflector's hash, the other visible meshes' hashes
/// combined, the eye's bits): the check scores up to 2²¹ vertex pairs, and every plan of a
/// scene with a curved mirror asks for it (each re-plan of a frame that moved nothing else).
type SeveralCache = HashMap<(u64, u64, [u32; 3]), (u32, u32)>;
static SEVERAL: Mutex<Option<SeveralCache>> = Mutex::new(None);

/// `reflection_points::several`, remembered for the same geometry and eye.
fn several_cached(scene: &Scene, index: usize, eye: Vec3) -> (u32, u32) {
    let others = scene
        .meshes
        .iter()
        .enumerate()
        .filter(|(i, m)| *i != index && !m.hidden)
        .fold(0xcbf2_9ce4_8422_2325u64, |h, (i, m)| (h ^ mesh_hash(m) ^ i as u64).wrapping_mul(0x0100_0000_01b3));
    let key = (mesh_hash(&scene.meshes[index]), others, [eye.x.to_bits(), eye.y.to_bits(), eye.z.to_bits()]);
    memo(&SEVERAL, key, || super::reflection_points::several(scene, index, eye))
}

fn mesh_hash(m: &Mesh) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    let mut eat = |x: u32| {
        for b in x.to_le_bytes() {
            h = (h ^ b as u64).wrapping_mul(0x0100_0000_01b3);
        }
    };
    for p in &m.positions {
        eat(p.x.to_bits());
        eat(p.y.to_bits());
        eat(p.z.to_bits());
    }
    for n in &m.normals {
        eat(n.x.to_bits() ^ n.y.to_bits().rotate_left(11) ^ n.z.to_bits().rotate_left(22));
    }
    for &i in &m.indices {
        eat(i);
    }
    h
}

fn mesh_facts(m: &Mesh) -> Arc<MeshFacts> {
    let key = mesh_hash(m);
    if let Some(f) = CACHE.lock().ok().and_then(|c| c.as_ref().and_then(|c| c.get(&key).cloned())) {
        return f;
    }
    let watertight = is_watertight(m);
    let faceted = watertight && is_faceted(m);
    let f = Arc::new(MeshFacts { planar: is_planar(m), faceted, watertight, curvature: curvature(m) });
    if let Ok(mut c) = CACHE.lock() {
        let map = c.get_or_insert_with(HashMap::new);
        if map.len() > 1024 {
            map.clear();
        }
        map.insert(key, f.clone());
    }
    f
}

/// A convex solid of flat faces (`scene::faces`).
pub fn is_faceted(m: &Mesh) -> bool {
    use crate::scene::faces;
    faces::planar_faces(m, faces::MAX_FACES).is_some_and(|f| f.len() >= 4 && faces::is_convex(m, &f))
}

/// All vertices within 1e-4 · diagonal of the area-weighted plane, and every vertex normal
/// within ~2.5° of its normal.
pub fn is_planar(m: &Mesh) -> bool {
    let diag = m.bounds().diagonal() as f64;
    if m.indices.len() < 3 || diag <= 0.0 {
        return false;
    }
    let p = |i: u32| m.positions[i as usize].as_dvec3();
    let mut n = DVec3::ZERO;
    for t in m.indices.chunks_exact(3) {
        n += (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0]));
    }
    let Some(n) = n.try_normalize() else { return false };
    let o = m.positions[0].as_dvec3();
    let flat = m.positions.iter().all(|v| (v.as_dvec3() - o).dot(n).abs() <= 1e-4 * diag);
    let normals = m.normals.iter().all(|v| v.as_dvec3().normalize_or_zero().dot(n).abs() >= 0.999);
    flat && normals
}

/// Every edge (positions welded at 1e-6 of the size) shared by exactly two triangles.
pub fn is_watertight(m: &Mesh) -> bool {
    if m.indices.len() < 12 {
        return false;
    }
    let scale = 1e-6 * m.bounds().diagonal().max(1e-30);
    let key = |v: Vec3| ((v.x / scale).round() as i64, (v.y / scale).round() as i64, (v.z / scale).round() as i64);
    let mut ids: HashMap<(i64, i64, i64), u32> = HashMap::new();
    let weld: Vec<u32> = m
        .positions
        .iter()
        .map(|&v| {
            let n = ids.len() as u32;
            *ids.entry(key(v)).or_insert(n)
        })
        .collect();
    let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
    for t in m.indices.chunks_exact(3) {
        let w = [weld[t[0] as usize], weld[t[1] as usize], weld[t[2] as usize]];
        if w[0] == w[1] || w[1] == w[2] || w[0] == w[2] {
            continue; // degenerate: no edge
        }
        for k in 0..3 {
            let (a, b) = (w[k], w[(k + 1) % 3]);
            *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    !edges.is_empty() && edges.values().all(|&c| c == 2)
}

/// Crossings of the ray o + t d (t > 0) with mesh `m`'s triangles: odd = inside.
fn crossings(m: &Mesh, o: DVec3, d: DVec3) -> usize {
    let p = |i: u32| m.positions[i as usize].as_dvec3();
    m.indices.chunks_exact(3).filter(|t| ray_triangle(o, d, p(t[0]), p(t[1]), p(t[2]), 0.0, f64::INFINITY).is_some()).count()
}

/// Distance from point x to triangle (a, b, c) (Ericson's closest point, Real-Time
/// Collision Detection §5.1.5).
pub fn point_triangle_distance(x: DVec3, a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let (ab, ac, ap) = (b - a, c - a, x - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return x.distance(a);
    }
    let bp = x - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return x.distance(b);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return x.distance(a + ab * (d1 / (d1 - d3)));
    }
    let cp = x - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return x.distance(c);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return x.distance(a + ac * (d2 / (d2 - d6)));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return x.distance(b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))));
    }
    let denom = 1.0 / (va + vb + vc);
    x.distance(a + ab * (vb * denom) + ac * (vc * denom))
}

fn distance_to_mesh(m: &Mesh, x: DVec3) -> f64 {
    let p = |i: u32| m.positions[i as usize].as_dvec3();
    m.indices.chunks_exact(3).map(|t| point_triangle_distance(x, p(t[0]), p(t[1]), p(t[2]))).fold(f64::INFINITY, f64::min)
}

/// Why point x cannot serve as object `own`'s reference point: it lies inside another
/// (closed) object, or closer to another object's surface than `clearance`.
pub(crate) fn blocked(scene: &Scene, own: usize, x: Vec3, clearance: f64) -> Option<String> {
    let xd = x.as_dvec3();
    for (i, m) in scene.meshes.iter().enumerate() {
        if i == own || m.indices.is_empty() {
            continue;
        }
        let b = m.bounds();
        let margin = Vec3::splat(clearance as f32);
        if x.cmplt(b.min - margin).any() || x.cmpgt(b.max + margin).any() {
            continue;
        }
        // Parity along three skewed directions, majority vote (robust to a ray grazing an edge).
        let dirs = [DVec3::new(1.0, 0.123, 0.057), DVec3::new(-0.071, 1.0, 0.193), DVec3::new(0.137, -0.089, -1.0)];
        let inside = dirs.iter().filter(|d| crossings(m, xd, d.normalize()) % 2 == 1).count() >= 2;
        if inside && mesh_facts(m).watertight {
            return Some(format!("inside '{}'", m.name));
        }
        let d = distance_to_mesh(m, xd);
        if d < clearance {
            return Some(format!("{d:.3e} m from '{}'", m.name));
        }
    }
    None
}

/// The automatic reference point of object `mesh`: its box centre, or, when that lies
/// inside or next to another object, the first of its area centroid and eight points
/// around the centre that is clear; with the reason.
fn reference_point(scene: &Scene, mesh: usize) -> (Vec3, Option<String>) {
    let m = &scene.meshes[mesh];
    let b = m.bounds();
    let centre = b.center();
    let clearance = 1e-3 * b.diagonal().max(1e-30) as f64;
    let Some(why) = blocked(scene, mesh, centre, clearance) else { return (centre, None) };
    let half = (b.max - b.min) * 0.5;
    let mut candidates = vec![area_centroid(m)];
    for s in [0.25f32, 0.5] {
        for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
            candidates.push(centre + axis * half * s);
            candidates.push(centre - axis * half * s);
        }
    }
    for c in candidates {
        if blocked(scene, mesh, c, clearance).is_none() {
            return (c, Some(format!("moved from the box centre ({:.3}, {:.3}, {:.3}), which lies {why}", centre.x, centre.y, centre.z)));
        }
    }
    (centre, Some(format!("the box centre lies {why} and no nearby point is clear: kept (the map sees mostly that object)")))
}

fn area_centroid(m: &Mesh) -> Vec3 {
    let p = |i: u32| m.positions[i as usize].as_dvec3();
    let (mut sum, mut area) = (DVec3::ZERO, 0.0);
    for t in m.indices.chunks_exact(3) {
        let a = (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0])).length() * 0.5;
        sum += (p(t[0]) + p(t[1]) + p(t[2])) / 3.0 * a;
        area += a;
    }
    if area > 0.0 {
        (sum / area).as_vec3()
    } else {
        m.bounds().center()
    }
}

/// Whether a ray that leaves mesh `m` may meet it again: its surface bends inwards or both
/// ways, or part of it is hidden by itself from `x` (its reference point), as a torus's outer
/// side from its centre.
pub fn may_meet_itself(m: &Mesh, x: Vec3) -> bool {
    matches!(curvature(m), Curvature::Concave | Curvature::Saddle) || visible_fraction_cached(m, x) < 0.999
}

/// `visible_fraction`, cached per mesh and reference point.
fn visible_fraction_cached(m: &Mesh, x: Vec3) -> f32 {
    memo(&VISIBLE, (mesh_hash(m), [x.x.to_bits(), x.y.to_bits(), x.z.to_bits()]), || visible_fraction(m, x))
}

/// `cache`'s value for `key`, else `f()` remembered there (at most 1024 entries: a full
/// cache starts over).
fn memo<K: std::hash::Hash + Eq, V: Copy>(cache: &Mutex<Option<HashMap<K, V>>>, key: K, f: impl FnOnce() -> V) -> V {
    if let Some(v) = cache.lock().ok().and_then(|c| c.as_ref().and_then(|c| c.get(&key).copied())) {
        return v;
    }
    let v = f();
    if let Ok(mut c) = cache.lock() {
        let map = c.get_or_insert_with(HashMap::new);
        if map.len() > 1024 {
            map.clear();
        }
        map.insert(key, v);
    }
    v
}

/// Area fraction of mesh `m`'s triangles whose centroid is the first surface of the mesh
/// along the ray from `x` (at most 4096 triangles, strided).
fn visible_fraction(m: &Mesh, x: Vec3) -> f32 {
    let own = Scene { meshes: vec![Mesh { material: 0, ..m.clone() }], materials: vec![Default::default()], ..Default::default() };
    let bvh = Bvh::new(&own);
    let n = m.triangle_count();
    if n == 0 {
        return 1.0;
    }
    let step = n.div_ceil(4096);
    let (xd, p) = (x.as_dvec3(), |i: u32| m.positions[i as usize].as_dvec3());
    let (mut seen, mut total) = (0.0, 0.0);
    for k in (0..n).step_by(step) {
        let t = &m.indices[3 * k..3 * k + 3];
        let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
        let area = (b - a).cross(c - a).length() * 0.5;
        if area <= 0.0 {
            continue;
        }
        let to = (a + b + c) / 3.0 - xd;
        let dist = to.length();
        total += area;
        let Some(d) = to.try_normalize() else {
            seen += area;
            continue;
        };
        match bvh.intersect(xd, d, 0.0, f64::INFINITY, None) {
            Some(h) if h.t < dist * (1.0 - 1e-4) && h.triangle as usize != k => {}
            _ => seen += area,
        }
    }
    if total > 0.0 {
        (seen / total) as f32
    } else {
        1.0
    }
}

/// Area fraction of mesh `m`'s triangles whose interpolated normal at the centroid faces
/// `x` (by more than 1 % of the distance: a plane through `x` faces it nowhere).
fn self_facing(m: &Mesh, x: Vec3) -> f32 {
    let (mut facing, mut total) = (0.0f64, 0.0f64);
    for t in m.indices.chunks_exact(3) {
        let p = |k: usize| m.positions[t[k] as usize];
        let area = ((p(1) - p(0)).cross(p(2) - p(0)).length() * 0.5) as f64;
        let n = m.normals.get(t[0] as usize).copied().unwrap_or_default()
            + m.normals.get(t[1] as usize).copied().unwrap_or_default()
            + m.normals.get(t[2] as usize).copied().unwrap_or_default();
        let to = (p(0) + p(1) + p(2)) / 3.0 - x;
        total += area;
        if n.normalize_or_zero().dot(to) < -0.01 * to.length() {
            facing += area;
        }
    }
    if total > 0.0 {
        (facing / total) as f32
    } else {
        0.0
    }
}

/// What rays from `x` (2048 directions of a Fibonacci sphere, stepping through the object
/// itself) reach first: the other specular objects with the fraction of directions that
/// reach each, and the fraction of directions whose hit lies on the scene's bounding box
/// (within 1 % of its diagonal: the environment is then its own proxy box, §3.2).
fn visible_specular(scene: &Scene, bvh: &Bvh, mesh: usize, x: Vec3) -> (Vec<(usize, f32)>, f32, f32, f32) {
    let mut hits: HashMap<usize, u32> = HashMap::new();
    let (mut nearest, mut farthest) = (f64::INFINITY, 0.0f64);
    let mut on_box = 0u32;
    let n = 2048;
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let bounds = scene.bounds();
    let (lo, hi) = (bounds.min.as_dvec3(), bounds.max.as_dvec3());
    let diag = bounds.diagonal().max(1e-30) as f64;
    let eps = 1e-6 * diag;
    for i in 0..n {
        let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
        let r = (1.0 - z * z).sqrt();
        let phi = golden * i as f64;
        let d = DVec3::new(r * phi.cos(), z, r * phi.sin());
        let mut o = x.as_dvec3();
        // Step through the object's own surface (the map leaves it out).
        for _ in 0..32 {
            let Some(h) = bvh.intersect(o, d, eps, f64::INFINITY, None) else { break };
            let hit_mesh = bvh.triangles[h.triangle as usize].mesh as usize;
            if hit_mesh == mesh {
                o += d * (h.t + eps);
                continue;
            }
            if scene.materials[scene.meshes[hit_mesh].material].kind.is_specular() {
                *hits.entry(hit_mesh).or_insert(0) += 1;
            }
            let p = o + d * h.t;
            let dist = p.distance(x.as_dvec3());
            nearest = nearest.min(dist);
            farthest = farthest.max(dist);
            let to_face = (p - lo).abs().min_element().min((hi - p).abs().min_element());
            if to_face <= 0.01 * diag {
                on_box += 1;
            }
            break;
        }
    }
    let mut out: Vec<(usize, f32)> = hits.into_iter().map(|(m, k)| (m, k as f32 / n as f32)).collect();
    out.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    let ratio = if nearest > 0.0 && farthest.is_finite() && farthest >= nearest { (farthest / nearest) as f32 } else { 1.0 };
    (out, on_box as f32 / n as f32, ratio, if nearest.is_finite() { nearest as f32 } else { 0.0 })
}

/// The largest angle an edge of a triangle of any other mesh subtends from `x`.
fn edge_angle(scene: &Scene, own: usize, x: Vec3) -> f32 {
    let x = x.as_dvec3();
    let mut largest = 0.0f64;
    for (i, m) in scene.meshes.iter().enumerate() {
        if i == own || m.hidden {
            continue;
        }
        let d = |k: u32| (m.positions[k as usize].as_dvec3() - x).normalize_or_zero();
        for t in m.indices.chunks_exact(3) {
            for k in 0..3 {
                let c = d(t[k]).dot(d(t[(k + 1) % 3])).clamp(-1.0, 1.0);
                largest = largest.max(c.acos());
            }
        }
    }
    largest as f32
}

impl ObjectFacts {
    /// The fraction of directions from the reference point that reach other specular
    /// objects.
    pub fn specular_coverage(&self) -> f32 {
        self.sees_specular.iter().map(|(_, f)| f).sum()
    }

    /// Whether mesh `m` covers at least `MIN_COVERAGE` of this object's directions.
    pub fn sees(&self, m: usize) -> bool {
        self.sees_specular.iter().any(|&(k, f)| k == m && f >= MIN_COVERAGE)
    }
}

/// Other specular objects covering less than this fraction of the sphere of directions
/// from a reference point are not worth an inter-object map cycle (each cycle regenerates
/// every distance map, with the self refraction of glass in it): measured on the demo
/// scene (the mirror sees the glass over 1.1 % of its directions), inter-object cycles
/// cost 4.3× the frame time for +0.06 dB; on the mirror-and-glass test scene (3.8 %) they
/// gain 2.7 dB (tests/per_object.rs, BENCHMARKS.md).
pub const MIN_COVERAGE: f32 = 0.02;

impl SceneFacts {
    /// Per object the positions (in `objects`) of the other objects it sees
    /// (`ObjectFacts::sees`): composition's input (`registry::Composes`).
    pub fn sight(&self) -> Vec<Vec<usize>> {
        let sees = |f: &ObjectFacts, j: usize| self.objects[j].mesh != f.mesh && f.sees(self.objects[j].mesh);
        self.objects.iter().map(|f| (0..self.objects.len()).filter(|&j| sees(f, j)).collect()).collect()
    }

    /// Facts of every specular object. `deep`: also convexity and mutual visibility (ray
    /// casting; the planner needs them, a fixed method does not).
    pub fn new(scene: &Scene, quality: &Quality, deep: bool) -> SceneFacts {
        // The scene's BVH only where there is a specular object to ask about.
        let bvh = if deep && scene.specular_meshes().next().is_some() { Some(Bvh::new(scene)) } else { None };
        let objects = scene
            .specular_meshes()
            .filter_map(|(i, m)| {
                let class = ObjectClass::of(&scene.materials[m.material].kind)?;
                let (reference_point, reference_note) = match (quality.cube.ref_point, m.reference_point) {
                    (Some(p), _) => (p, Some("set by the ref_point knob".to_string())),
                    (None, Some(p)) => {
                        (p, Some("set by the scene (Mesh::reference_point; glTF extras.specula.reference_point)".to_string()))
                    }
                    (None, None) => reference_point(scene, i),
                };
                let mf = mesh_facts(m);
                let (visible, (sees, box_fraction, depth_ratio, nearest)) = match &bvh {
                    Some(b) => (visible_fraction_cached(m, reference_point), visible_specular(scene, b, i, reference_point)),
                    None => (1.0, (Vec::new(), 0.0, 1.0, 0.0)),
                };
                let radius = 0.5 * m.bounds().diagonal();
                Some(ObjectFacts {
                    mesh: i,
                    class,
                    planar: mf.planar,
                    faceted: mf.faceted,
                    watertight: mf.watertight,
                    curvature: mf.curvature,
                    reflection_points: match (class, mf.planar, mf.curvature) {
                        (ObjectClass::Mirror, false, Curvature::Convex | Curvature::Concave) => {
                            several_cached(scene, i, scene.camera_or_default().position)
                        }
                        _ => (0, 0),
                    },
                    depth_ratio,
                    near_ratio: if radius > 0.0 { nearest / radius } else { 0.0 },
                    edge_angle: if bvh.is_some() { edge_angle(scene, i, reference_point) } else { 0.0 },
                    visible_fraction: visible,
                    sees_specular: sees,
                    box_fraction,
                    sees_planar_mirror: false,
                    self_facing: self_facing(m, reference_point),
                    reference_point,
                    reference_note,
                    triangles: m.triangle_count(),
                    graded: scene.materials[m.material].medium().is_some(),
                })
            })
            .collect::<Vec<ObjectFacts>>();
        let mut objects = objects;
        // Planar mirrors and planar thin panes: what the planner serves by planar views.
        let planar_mirrors: Vec<usize> =
            objects.iter().filter(|o| o.planar && o.class != ObjectClass::SolidDielectric).map(|o| o.mesh).collect();
        for o in &mut objects {
            o.sees_planar_mirror = planar_mirrors.iter().any(|&m| m != o.mesh && o.sees(m));
        }
        SceneFacts { objects }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::shapes;

    /// The hybrid search follows rays back into an object only where they may meet it again:
    /// never a sphere's, a torus's (saddle-shaped, its outer side hidden from its centre)
    /// and a thick torus's whose inner bend is too slight to count as a saddle (hidden from
    /// its centre all the same).
    #[test]
    fn rays_may_meet_a_torus_again_never_a_sphere() {
        let s = shapes::uv_sphere("s", Vec3::ZERO, 1.0, 24, 12, 0);
        assert!(!may_meet_itself(&s, Vec3::ZERO));
        let t = shapes::torus("t", Vec3::ZERO, Vec3::Y, (0.6, 0.25), (48, 24), 0);
        assert!(may_meet_itself(&t, Vec3::ZERO));
        let fat = shapes::torus("fat", Vec3::ZERO, Vec3::Y, (0.6, 0.55), (48, 24), 0);
        assert!(visible_fraction(&fat, Vec3::ZERO) < 0.999 && may_meet_itself(&fat, Vec3::ZERO));
    }

    #[test]
    fn sphere_is_closed_and_convex_quad_is_planar() {
        let s = shapes::uv_sphere("s", Vec3::ZERO, 1.0, 24, 12, 0);
        assert!(is_watertight(&s));
        assert!(!is_planar(&s));
        assert!(visible_fraction(&s, Vec3::ZERO) > 0.999);
        let q = shapes::quad("q", Vec3::ZERO, Vec3::X, Vec3::Z, 3, 0);
        assert!(is_planar(&q));
        assert!(!is_watertight(&q));
        // From outside, a sphere shows about half its surface.
        let f = visible_fraction(&s, Vec3::new(0.0, 0.0, 10.0));
        assert!((0.3..0.6).contains(&f), "{f}");
    }
}
