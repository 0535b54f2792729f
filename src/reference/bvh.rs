//! A bounding volume hierarchy over every triangle of the scene, built with the surface
//! area heuristic (binned SAH) and traversed in f64, nearest child first. Ray–triangle
//! tests are Möller–Trumbore (survey §2.1.1) through `optics::ray_triangle_edges`, the twin
//! of `glsl/common/ray_triangle.glsl`.

use glam::DVec3;

use crate::optics::{ray_triangle_edges, RAY_TRIANGLE_PARALLEL};
use crate::scene::Scene;

/// One scene triangle, prepared for Möller–Trumbore: v0, its edges and |e1| |e2| for the
/// parallel test, and where it came from.
#[derive(Clone, Copy, Debug)]
pub struct Triangle {
    pub v0: DVec3,
    pub e1: DVec3,
    pub e2: DVec3,
    /// RAY_TRIANGLE_PARALLEL |e1| |e2|: times |d| it is the determinant threshold.
    det_scale: f64,
    pub mesh: u32,
    /// Index of the triangle within its mesh (its indices are 3·tri .. 3·tri + 3).
    pub tri: u32,
}

/// A hit: the ray parameter, the barycentrics of v1 (u) and v2 (v), and the triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f64,
    pub u: f64,
    pub v: f64,
    /// Index into `Bvh::triangles`.
    pub triangle: u32,
}

#[derive(Clone, Copy, Debug)]
struct Node {
    min: DVec3,
    max: DVec3,
    /// Interior: index of the left child (the right one follows it). Leaf: first triangle.
    first: u32,
    /// 0 for interior nodes, else the leaf's triangle count.
    count: u32,
}

pub struct Bvh {
    nodes: Vec<Node>,
    pub triangles: Vec<Triangle>,
}

const BINS: usize = 16;
/// Below this depth the SAH chooses the splits; deeper nodes split at the object median,
/// so no tree is deeper than SAH_DEPTH + 32 and the traversal stack has a fixed size.
const SAH_DEPTH: usize = 48;
const STACK: usize = SAH_DEPTH + 40;
const MAX_LEAF: usize = 4;
/// SAH cost of one traversal step relative to one triangle test.
const TRAVERSAL_COST: f64 = 1.0;

#[derive(Clone, Copy)]
struct Bounds {
    min: DVec3,
    max: DVec3,
}

impl Bounds {
    const EMPTY: Bounds = Bounds { min: DVec3::splat(f64::INFINITY), max: DVec3::splat(f64::NEG_INFINITY) };
    fn grow(&mut self, p: DVec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }
    fn union(&mut self, b: &Bounds) {
        self.min = self.min.min(b.min);
        self.max = self.max.max(b.max);
    }
    fn area(&self) -> f64 {
        let e = self.max - self.min;
        if e.x < 0.0 {
            0.0
        } else {
            2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
        }
    }
}

impl Bvh {
    /// Builds the hierarchy over every triangle of every mesh.
    pub fn new(scene: &Scene) -> Bvh {
        let soup = scene.meshes.iter().enumerate().filter(|(_, mesh)| !mesh.hidden).flat_map(|(m, mesh)| {
            mesh.indices.chunks_exact(3).enumerate().map(move |(k, idx)| {
                let p = |i: u32| mesh.positions[i as usize].as_dvec3();
                ([p(idx[0]), p(idx[1]), p(idx[2])], m as u32, k as u32)
            })
        });
        Bvh::build(soup)
    }

    /// Builds the hierarchy over a triangle soup: (corners, mesh, index within the mesh).
    pub fn build(soup: impl Iterator<Item = ([DVec3; 3], u32, u32)>) -> Bvh {
        let mut triangles = Vec::new();
        let mut boxes = Vec::new();
        for ([a, b, c], m, k) in soup {
            let (e1, e2) = (b - a, c - a);
            triangles.push(Triangle { v0: a, e1, e2, det_scale: RAY_TRIANGLE_PARALLEL * e1.length() * e2.length(), mesh: m, tri: k });
            let mut bb = Bounds::EMPTY;
            for q in [a, b, c] {
                bb.grow(q);
            }
            boxes.push(bb);
        }
        let mut order: Vec<u32> = (0..triangles.len() as u32).collect();
        let centroids: Vec<DVec3> = boxes.iter().map(|b| (b.min + b.max) * 0.5).collect();
        let mut nodes = Vec::with_capacity(2 * triangles.len().max(1));
        nodes.push(Node { min: DVec3::ZERO, max: DVec3::ZERO, first: 0, count: 0 });
        let mut stack = vec![(0usize, 0usize, triangles.len(), 0usize)];
        while let Some((node, start, end, depth)) = stack.pop() {
            let mut bb = Bounds::EMPTY;
            let mut cb = Bounds::EMPTY;
            for &i in &order[start..end] {
                bb.union(&boxes[i as usize]);
                cb.grow(centroids[i as usize]);
            }
            nodes[node].min = bb.min;
            nodes[node].max = bb.max;
            let n = end - start;
            let split = if n <= MAX_LEAF {
                None
            } else if depth < SAH_DEPTH {
                best_split(&order[start..end], &boxes, &centroids, &cb, bb.area(), n)
            } else {
                Some((usize::MAX, 0.0))
            };
            match split {
                None => {
                    nodes[node].first = start as u32;
                    nodes[node].count = n as u32;
                }
                Some((axis, threshold)) => {
                    let slice = &mut order[start..end];
                    let mut mid = 0;
                    if axis != usize::MAX {
                        for k in 0..slice.len() {
                            if centroids[slice[k] as usize][axis] < threshold {
                                slice.swap(k, mid);
                                mid += 1;
                            }
                        }
                    }
                    if mid == 0 || mid == n {
                        // Too deep, or centroids no plane separates: the object median
                        // along the widest centroid extent.
                        let ext = cb.max - cb.min;
                        let axis = if ext.x >= ext.y && ext.x >= ext.z {
                            0
                        } else if ext.y >= ext.z {
                            1
                        } else {
                            2
                        };
                        slice.select_nth_unstable_by(n / 2, |a, b| centroids[*a as usize][axis].total_cmp(&centroids[*b as usize][axis]));
                        mid = n / 2;
                    }
                    let left = nodes.len();
                    nodes.push(Node { min: DVec3::ZERO, max: DVec3::ZERO, first: 0, count: 0 });
                    nodes.push(Node { min: DVec3::ZERO, max: DVec3::ZERO, first: 0, count: 0 });
                    nodes[node].first = left as u32;
                    nodes[node].count = 0;
                    stack.push((left, start, start + mid, depth + 1));
                    stack.push((left + 1, start + mid, end, depth + 1));
                }
            }
        }
        // Store the triangles in leaf order, so a leaf's triangles are contiguous.
        let triangles = order.iter().map(|&i| triangles[i as usize]).collect();
        Bvh { nodes, triangles }
    }

    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// The nodes in their stored order (the root first; an interior node's children are
    /// adjacent, the left one at `first`): (min, max, first, count), count 0 for interior
    /// nodes, else the leaf's triangles `triangles[first..first + count]`.
    pub fn nodes(&self) -> impl Iterator<Item = (DVec3, DVec3, u32, u32)> + '_ {
        self.nodes.iter().map(|n| (n.min, n.max, n.first, n.count))
    }

    /// The nearest hit with t_min < t < t_max, skipping triangle `skip` (the surface a
    /// secondary ray leaves).
    pub fn intersect(&self, o: DVec3, d: DVec3, t_min: f64, t_max: f64, skip: Option<u32>) -> Option<Hit> {
        self.traverse(o, d, t_min, t_max, skip, false)
    }

    /// Whether anything lies on the ray with t_min < t < t_max (shadow rays).
    pub fn occluded(&self, o: DVec3, d: DVec3, t_min: f64, t_max: f64, skip: Option<u32>) -> bool {
        self.traverse(o, d, t_min, t_max, skip, true).is_some()
    }

    fn traverse(&self, o: DVec3, d: DVec3, t_min: f64, mut t_max: f64, skip: Option<u32>, any: bool) -> Option<Hit> {
        if self.triangles.is_empty() || !o.is_finite() || !d.is_finite() {
            return None;
        }
        let inv = d.recip();
        let d_len = d.length();
        let skip = skip.unwrap_or(u32::MAX);
        let mut best = None;
        let mut stack = [0u32; STACK];
        let mut sp = 1usize;
        while sp > 0 {
            sp -= 1;
            let node = &self.nodes[stack[sp] as usize];
            if node.count > 0 {
                let first = node.first as usize;
                for (k, tri) in self.triangles[first..first + node.count as usize].iter().enumerate() {
                    let index = (first + k) as u32;
                    if index == skip {
                        continue;
                    }
                    if let Some(h) = ray_triangle_edges(o, d, tri.v0, tri.e1, tri.e2, tri.det_scale * d_len, t_min, t_max) {
                        t_max = h.t;
                        best = Some(Hit { t: h.t, u: h.u, v: h.v, triangle: index });
                        if any {
                            return best;
                        }
                    }
                }
                continue;
            }
            let (l, r) = (node.first, node.first + 1);
            let tl = self.slab(l, o, inv, t_min, t_max);
            let tr = self.slab(r, o, inv, t_min, t_max);
            // Push the farther child first so the nearer one is visited next.
            match (tl, tr) {
                (Some(a), Some(b)) => {
                    let (near, far) = if a <= b { (l, r) } else { (r, l) };
                    stack[sp] = far;
                    stack[sp + 1] = near;
                    sp += 2;
                }
                (Some(_), None) => {
                    stack[sp] = l;
                    sp += 1;
                }
                (None, Some(_)) => {
                    stack[sp] = r;
                    sp += 1;
                }
                (None, None) => {}
            }
        }
        best
    }

    /// Entry distance of the ray into node `n`'s box within [t_min, t_max], if it enters.
    #[inline]
    fn slab(&self, n: u32, o: DVec3, inv: DVec3, t_min: f64, t_max: f64) -> Option<f64> {
        let node = &self.nodes[n as usize];
        let t0 = (node.min - o) * inv;
        let t1 = (node.max - o) * inv;
        // f64::min/max skip the NaN of 0·∞ (a ray in a box's face plane).
        let near = t0.min(t1).max_element().max(t_min);
        let far = t0.max(t1).min_element().min(t_max);
        // Boxes are grown by the relative rounding of the slab arithmetic so that rays
        // through a box's faces or edges are never lost.
        (near <= far + 4.0 * f64::EPSILON * (near.abs() + far.abs())).then_some(near)
    }
}

/// The binned SAH split (axis, centroid threshold) of a node, or `None` when a leaf is
/// cheaper.
fn best_split(items: &[u32], boxes: &[Bounds], centroids: &[DVec3], cb: &Bounds, area: f64, n: usize) -> Option<(usize, f64)> {
    let mut best: Option<(f64, usize, f64)> = None;
    for (axis, (lo, hi)) in cb.min.to_array().into_iter().zip(cb.max.to_array()).enumerate() {
        if hi.is_nan() || lo.is_nan() || hi <= lo {
            continue;
        }
        let scale = BINS as f64 / (hi - lo);
        let mut bins = [(Bounds::EMPTY, 0usize); BINS];
        for &i in items {
            let b = (((centroids[i as usize][axis] - lo) * scale) as usize).min(BINS - 1);
            bins[b].0.union(&boxes[i as usize]);
            bins[b].1 += 1;
        }
        // Sweep from the right, then from the left, accumulating areas and counts.
        let mut right_area = [0.0; BINS];
        let mut right_count = [0usize; BINS];
        let mut acc = Bounds::EMPTY;
        let mut count = 0;
        for b in (1..BINS).rev() {
            acc.union(&bins[b].0);
            count += bins[b].1;
            right_area[b] = acc.area();
            right_count[b] = count;
        }
        let mut acc = Bounds::EMPTY;
        let mut count = 0;
        for b in 0..BINS - 1 {
            acc.union(&bins[b].0);
            count += bins[b].1;
            if count == 0 || right_count[b + 1] == 0 {
                continue;
            }
            let cost = TRAVERSAL_COST + (acc.area() * count as f64 + right_area[b + 1] * right_count[b + 1] as f64) / area.max(1e-300);
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, lo + (b + 1) as f64 / scale));
            }
        }
    }
    match best {
        Some((cost, axis, threshold)) if cost < n as f64 || n > 4 * MAX_LEAF => Some((axis, threshold)),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{shapes, Material};
    use glam::Vec3;

    /// The BVH finds exactly what testing every triangle finds.
    #[test]
    fn bvh_agrees_with_brute_force() {
        let mut s = Scene::new();
        let m = s.add_material(Material::default()).unwrap();
        s.add_mesh(shapes::uv_sphere("a", Vec3::ZERO, 1.0, 24, 12, m)).unwrap();
        s.add_mesh(shapes::uv_sphere("b", Vec3::new(1.5, 0.3, 0.0), 0.5, 16, 8, m)).unwrap();
        s.add_mesh(shapes::quad("floor", Vec3::new(-3.0, -1.0, 3.0), Vec3::new(6.0, 0.0, 0.0), Vec3::new(0.0, 0.0, -6.0), 5, m)).unwrap();
        let bvh = Bvh::new(&s);
        assert_eq!(bvh.triangles.len(), s.triangle_count());
        assert!(bvh.node_count() > 1);
        let mut seed = 7u64;
        let mut rnd = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let mut hits = 0;
        for _ in 0..3000 {
            let o = DVec3::new(rnd(), rnd(), rnd()) * 4.0;
            let d = (DVec3::new(rnd(), rnd(), rnd()) * 0.8 - o).normalize();
            let fast = bvh.intersect(o, d, 0.0, f64::INFINITY, None);
            let mut slow: Option<Hit> = None;
            for (k, t) in bvh.triangles.iter().enumerate() {
                if let Some(h) = ray_triangle_edges(o, d, t.v0, t.e1, t.e2, t.det_scale, 0.0, slow.map_or(f64::INFINITY, |h| h.t)) {
                    slow = Some(Hit { t: h.t, u: h.u, v: h.v, triangle: k as u32 });
                }
            }
            assert_eq!(fast.map(|h| h.t), slow.map(|h| h.t));
            assert_eq!(bvh.occluded(o, d, 0.0, f64::INFINITY, None), slow.is_some());
            hits += fast.is_some() as usize;
        }
        assert!(hits > 500, "{hits}");
    }
}
