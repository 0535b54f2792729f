//! The kd-tree scheme (survey §2.3.3): an SAH kd-tree over the triangle list, built on the
//! CPU and traversed on the GPU with a short stack that falls back to kd-restart when it
//! overflows (HSHH07, with push-down), or by pure kd-restart (FS05).
//!
//! **Build.** Each node splits its box by one axis-aligned plane chosen by the surface area
//! heuristic among the planes of its references' boxes: exactly (a sweep over the sorted
//! box bounds, after Wald–Havran) for nodes of at most `EXACT_MAX` references, over `BINS`
//! bins per axis above that. A reference's box is the bounds of its triangle clipped
//! (Sutherland–Hodgman, f64) to the node's box, so a large triangle is listed only where it
//! really passes and its box shrinks as it descends. The cost model, in units of one
//! traversal step, is
//!
//! `C = COST_TRAVERSAL + COST_INTERSECT · (A_L N_L + A_R N_R) / A`, times
//! `1 − EMPTY_BONUS` when one side is empty (which favours cutting off empty space),
//!
//! against `COST_INTERSECT · N` for a leaf (A: surface areas, N: references); a node
//! becomes a leaf when no plane beats that, when it has at most `leaf_size` references, or
//! at `max_depth`.
//!
//! **Robustness.** The GPU recomputes the ray's crossing of every plane in f32, so a hit
//! point that lies (in exact arithmetic) in one cell may be attributed to its neighbour
//! across a plane by a few ulps. Every triangle is therefore listed in every leaf whose box
//! widened by `slack` (1e-5 of the scene's extent plus its largest coordinate, far above
//! f32 rounding of points in the scene) it meets: the invariant the tests check. (A
//! triangle lying in a split plane thus goes to both sides; the exact SAH's candidate
//! planes keep a slack's distance from the boxes, so that its counts are the split's.)
//!
//! **Encoding.** Node k is the word `accel_nodes[k]`:
//! - interior: (split position as f32 bits, left child, right child, axis 0/1/2), the left
//!   child holding the half below the plane;
//! - leaf: (first reference, count, 0, `LEAF`): triangles `refs[first..first + count]`.
//!
//! Node 0 is the root; `accel.bounds_min/max` hold its box (the scene's bounds widened by
//! `slack`, as f32 values), which the traversal clips each ray to.
//!
//! **Ropes** (PGSS07, `kd_traversal=ropes`): a leaf's third word is the offset of its 12
//! auxiliary words: its box (lo xyz, hi xyz as f32 bits) and its six ropes, one per face in
//! the order −x, +x, −y, +y, −z, +z: the node across that face (`NO_ROPE` outside the
//! root). Built top-down (a split makes each child the other's rope across the plane) and
//! pushed down ("optimised ropes"): from a rope's node, into the child that holds all of the
//! face's region, while one does. The traversal locates the leaf of the ray's entry point
//! from the root, then, leaf by leaf, follows the rope of the face the ray leaves through and
//! descends from there to the leaf holding the exit point: no stack, no restart. A rope
//! always crosses a face in the ray's direction, so the walk cannot return to a leaf.

use glam::DVec3;

use super::knobs::KdTraversal;
use super::{Packed, TriangleList};
use crate::error::{Error, Result};

/// The deepest tree: glsl/raytrace/kdtree.glsl KD_MAX_DEPTH. One restart descends at most
/// this many nodes, which keeps a ray's steps well inside the kernel's step budget (and
/// lavapipe's loop budget, raytrace/rays.glsl); deeper trees are refused.
pub const MAX_DEPTH: u32 = 64;
/// The axis word of a leaf (glsl/raytrace/kdtree.glsl KD_LEAF).
pub const LEAF: u32 = 3;
/// A rope out of the root's box (glsl/raytrace/intersect_kdtree_ropes.comp KD_NO_ROPE).
pub const NO_ROPE: u32 = u32::MAX;
/// The SAH cost of one traversal step (the unit).
pub const COST_TRAVERSAL: f64 = 1.0;
/// The SAH cost of one ray–triangle test: a 48-byte fetch and Möller–Trumbore, against a
/// step's 16-byte fetch and one plane crossing (a judgement, not a measurement).
pub const COST_INTERSECT: f64 = 1.5;
/// The discount on a split that leaves one side empty (Wald–Havran's 20 %).
pub const EMPTY_BONUS: f64 = 0.2;
/// Nodes with more references choose their plane among `BINS` − 1 bin boundaries per
/// axis; smaller ones among every reference box's planes.
const EXACT_MAX: usize = 1024;
const BINS: usize = 64;
/// Nodes with more references build their two subtrees in parallel.
const PARALLEL_MIN: usize = 4096;

/// The usual depth limit 8 + 1.3 log₂ N (PBRT, after Havran), capped at `MAX_DEPTH`.
pub fn auto_depth(n: usize) -> u32 {
    (8.0 + 1.3 * (n.max(1) as f64).log2()).round().min(MAX_DEPTH as f64) as u32
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Node {
    /// `left` holds x[axis] ≤ split, `right` x[axis] ≥ split.
    Interior { axis: usize, split: f32, left: u32, right: u32 },
    /// References `refs[first..first + count]`.
    Leaf { first: u32, count: u32 },
}

/// A built tree (node 0 the root, pre-order), before packing.
#[derive(Clone, Debug)]
pub struct KdTree {
    pub nodes: Vec<Node>,
    pub refs: Vec<u32>,
    /// The root's box (f32 values).
    pub lo: DVec3,
    pub hi: DVec3,
    /// How far beyond a leaf's box its triangles are listed (see the module documentation).
    pub slack: f64,
    /// The deepest leaf's depth (the root's is 0).
    pub depth: u32,
}

/// One triangle in one node: the bounds of its part inside the node's box (widened by the
/// slack).
#[derive(Clone, Copy, Debug)]
struct Ref {
    tri: u32,
    lo: DVec3,
    hi: DVec3,
}

/// A subtree as the recursion returns it, flattened afterwards.
enum Built {
    Leaf(Vec<u32>),
    Split { axis: usize, split: f32, children: Box<[Built; 2]> },
}

#[derive(Clone, Copy, Debug)]
struct Split {
    cost: f64,
    axis: usize,
    /// An f32 value strictly inside the node's box.
    pos: f64,
}

struct Builder<'a> {
    triangles: &'a [[DVec3; 3]],
    slack: f64,
    max_depth: u32,
    leaf_size: usize,
}

impl KdTree {
    /// Builds the tree over `list`; `max_depth` 0 means [`auto_depth`].
    pub fn build(list: &TriangleList, max_depth: u32, leaf_size: u32) -> Result<KdTree> {
        super::check_tree_knobs(max_depth, MAX_DEPTH, leaf_size, ("kd_max_depth", "kd_leaf_size"), "8 + 1.3 log2 N")?;
        let max_depth = if max_depth == 0 { auto_depth(list.len()) } else { max_depth };
        let triangles: Vec<[DVec3; 3]> = list.triangles.iter().map(|t| t.map(|v| v.as_dvec3())).collect();
        let (lo, hi, slack) = list.slack_bounds();
        // The root's box as f32 values (rounding moves it by far less than the slack).
        let f32_box = |v: DVec3| v.as_vec3().as_dvec3();
        let (lo, hi) = (f32_box(lo - DVec3::splat(slack)), f32_box(hi + DVec3::splat(slack)));
        let refs: Vec<Ref> = triangles
            .iter()
            .enumerate()
            .map(|(i, t)| Ref { tri: i as u32, lo: t[0].min(t[1]).min(t[2]), hi: t[0].max(t[1]).max(t[2]) })
            .collect();
        let builder = Builder { triangles: &triangles, slack, max_depth, leaf_size: leaf_size as usize };
        let built = builder.node(refs, lo, hi, 0);
        let mut tree = KdTree { nodes: Vec::new(), refs: Vec::new(), lo, hi, slack, depth: 0 };
        tree.flatten(built, 0);
        if tree.depth > MAX_DEPTH {
            return Err(Error::invalid("kd-tree", format!("depth {} exceeds the GPU traversal's {MAX_DEPTH}", tree.depth)));
        }
        if tree.refs.len() > u32::MAX as usize / 2 || tree.nodes.len() > u32::MAX as usize / 2 {
            return Err(Error::invalid(
                "kd-tree",
                format!("{} references in {} nodes: lower max_depth", tree.refs.len(), tree.nodes.len()),
            ));
        }
        Ok(tree)
    }

    /// Appends `b` in pre-order; returns its index.
    fn flatten(&mut self, b: Built, depth: u32) -> u32 {
        let k = self.nodes.len() as u32;
        self.depth = self.depth.max(depth);
        match b {
            Built::Leaf(tris) => {
                self.nodes.push(Node::Leaf { first: self.refs.len() as u32, count: tris.len() as u32 });
                self.refs.extend(tris);
            }
            Built::Split { axis, split, children } => {
                self.nodes.push(Node::Leaf { first: 0, count: 0 });
                let [l, r] = *children;
                let left = self.flatten(l, depth + 1);
                let right = self.flatten(r, depth + 1);
                self.nodes[k as usize] = Node::Interior { axis, split, left, right };
            }
        }
        k
    }

    /// Per node its box, the root's split down the tree.
    pub fn boxes(&self) -> Vec<(DVec3, DVec3)> {
        let mut boxes = vec![(self.lo, self.hi); self.nodes.len()];
        // Pre-order: a parent comes before its children.
        for k in 0..self.nodes.len() {
            if let Node::Interior { axis, split, left, right } = self.nodes[k] {
                let (lo, hi) = boxes[k];
                let (mut hi_left, mut lo_right) = (hi, lo);
                hi_left[axis] = split as f64;
                lo_right[axis] = split as f64;
                boxes[left as usize] = (lo, hi_left);
                boxes[right as usize] = (lo_right, hi);
            }
        }
        boxes
    }

    /// Per leaf (node index) its six ropes, pushed down (see the module documentation).
    pub fn ropes(&self) -> Vec<(u32, [u32; 6])> {
        let boxes = self.boxes();
        let mut out = Vec::new();
        let mut todo = vec![(0u32, [NO_ROPE; 6])];
        while let Some((k, ropes)) = todo.pop() {
            match self.nodes[k as usize] {
                Node::Interior { axis, left, right, .. } => {
                    let (mut l, mut r) = (ropes, ropes);
                    l[2 * axis + 1] = right;
                    r[2 * axis] = left;
                    todo.push((right, r));
                    todo.push((left, l));
                }
                Node::Leaf { .. } => {
                    let (lo, hi) = boxes[k as usize];
                    let pushed = std::array::from_fn(|f| self.push_down(ropes[f], f, lo, hi));
                    out.push((k, pushed));
                }
            }
        }
        out
    }

    /// From `rope` (across face `face` of the box [lo, hi]) down to the deepest node that
    /// still holds all of the region across the face.
    fn push_down(&self, mut rope: u32, face: usize, lo: DVec3, hi: DVec3) -> u32 {
        let (fa, high) = (face / 2, face % 2 == 1);
        while rope != NO_ROPE {
            let Node::Interior { axis, split, left, right } = self.nodes[rope as usize] else { break };
            let s = split as f64;
            rope = if axis == fa {
                // Split parallel to the face: the child next to it holds the region.
                if high {
                    left
                } else {
                    right
                }
            } else if s >= hi[axis] {
                left
            } else if s <= lo[axis] {
                right
            } else {
                break; // the face straddles the split
            };
        }
        rope
    }

    /// The GPU form (see the module documentation).
    pub fn words(&self) -> Vec<[u32; 4]> {
        self.nodes
            .iter()
            .map(|n| match *n {
                Node::Interior { axis, split, left, right } => [split.to_bits(), left, right, axis as u32],
                Node::Leaf { first, count } => [first, count, 0, LEAF],
            })
            .collect()
    }
}

impl Builder<'_> {
    fn node(&self, refs: Vec<Ref>, lo: DVec3, hi: DVec3, depth: u32) -> Built {
        let n = refs.len();
        let leaf = |refs: Vec<Ref>| Built::Leaf(refs.iter().map(|r| r.tri).collect());
        if n <= self.leaf_size || depth >= self.max_depth {
            return leaf(refs);
        }
        let best = if n <= EXACT_MAX { exact_split(&refs, lo, hi, self.slack) } else { binned_split(&refs, lo, hi, self.slack) };
        let Some(Split { cost, axis, pos }) = best else { return leaf(refs) };
        if cost >= COST_INTERSECT * n as f64 {
            return leaf(refs);
        }
        let (mut hi_left, mut lo_right) = (hi, lo);
        hi_left[axis] = pos;
        lo_right[axis] = pos;
        let s = DVec3::splat(self.slack);
        let (mut left, mut right) = (Vec::new(), Vec::new());
        for r in refs {
            // A reference that reaches past the plane (by more than the slack) is clipped
            // to the child's box; one that does not keeps its bounds.
            if r.lo[axis] <= pos + self.slack {
                if r.hi[axis] <= pos + self.slack {
                    left.push(r);
                } else if let Some((a, b)) = clip(&self.triangles[r.tri as usize], lo - s, hi_left + s) {
                    left.push(Ref { tri: r.tri, lo: a, hi: b });
                }
            }
            if r.hi[axis] >= pos - self.slack {
                if r.lo[axis] >= pos - self.slack {
                    right.push(r);
                } else if let Some((a, b)) = clip(&self.triangles[r.tri as usize], lo_right - s, hi + s) {
                    right.push(Ref { tri: r.tri, lo: a, hi: b });
                }
            }
        }
        if left.len() == n && right.len() == n {
            return leaf(left);
        }
        let (l, r) = if n > PARALLEL_MIN {
            rayon::join(|| self.node(left, lo, hi_left, depth + 1), || self.node(right, lo_right, hi, depth + 1))
        } else {
            (self.node(left, lo, hi_left, depth + 1), self.node(right, lo_right, hi, depth + 1))
        };
        Built::Split { axis, split: pos as f32, children: Box::new([l, r]) }
    }
}

/// Half the surface area of the box [lo, hi].
fn half_area(lo: DVec3, hi: DVec3) -> f64 {
    let e = (hi - lo).max(DVec3::ZERO);
    e.x * e.y + e.y * e.z + e.z * e.x
}

/// The SAH cost (module documentation) of splitting [lo, hi] at `pos` on `axis` with `nl`
/// references on the left and `nr` on the right.
fn sah(lo: DVec3, hi: DVec3, axis: usize, pos: f64, nl: usize, nr: usize) -> f64 {
    let (mut hi_left, mut lo_right) = (hi, lo);
    hi_left[axis] = pos;
    lo_right[axis] = pos;
    let area = half_area(lo, hi);
    let c = COST_TRAVERSAL + COST_INTERSECT * (half_area(lo, hi_left) * nl as f64 + half_area(lo_right, hi) * nr as f64) / area;
    if nl == 0 || nr == 0 {
        c * (1.0 - EMPTY_BONUS)
    } else {
        c
    }
}

/// `pos` rounded to f32 (the GPU's split), if strictly inside the node on `axis`.
fn candidate(pos: f64, lo: DVec3, hi: DVec3, axis: usize) -> Option<f64> {
    let p = pos as f32 as f64;
    (p > lo[axis] && p < hi[axis]).then_some(p)
}

fn better(best: Option<Split>, s: Split) -> Option<Split> {
    match best {
        Some(b) if b.cost <= s.cost => Some(b),
        _ => Some(s),
    }
}

/// The cheapest plane among the references' box planes. The split lists a reference on
/// the left when it starts at most `slack` above the plane and on the right when it ends at
/// most `slack` below it, so the counts are taken over the boxes widened by the slack, and
/// the candidates lie `slack` beyond each widened box (the tightest planes that leave it on
/// one side). Per axis: the widened starts and ends sorted, then each sorted candidate list
/// swept against them.
fn exact_split(refs: &[Ref], lo: DVec3, hi: DVec3, slack: f64) -> Option<Split> {
    let mut best = None;
    let n = refs.len();
    let (mut starts, mut ends) = (Vec::with_capacity(n), Vec::with_capacity(n));
    for axis in 0..3 {
        starts.clear();
        ends.clear();
        starts.extend(refs.iter().map(|r| r.lo[axis] - slack));
        ends.extend(refs.iter().map(|r| r.hi[axis] + slack));
        starts.sort_unstable_by(f64::total_cmp);
        ends.sort_unstable_by(f64::total_cmp);
        // Candidates below each start, above each end: both lists ascending, as f32
        // rounding is monotonic.
        for (list, offset) in [(&starts, -slack), (&ends, slack)] {
            let (mut nl, mut passed) = (0, 0);
            for &x in list.iter() {
                let Some(p) = candidate(x + offset, lo, hi, axis) else { continue };
                while nl < n && starts[nl] <= p {
                    nl += 1;
                }
                while passed < n && ends[passed] < p {
                    passed += 1;
                }
                best = better(best, Split { cost: sah(lo, hi, axis, p, nl, n - passed), axis, pos: p });
            }
        }
    }
    best
}

/// The cheapest of the `BINS` − 1 inner bin boundaries per axis, over the boxes widened by
/// the slack: a box starting in bin j counts on the left of boundaries k > j, one ending in
/// bin j on the right of k ≤ j.
fn binned_split(refs: &[Ref], lo: DVec3, hi: DVec3, slack: f64) -> Option<Split> {
    let mut best = None;
    for axis in 0..3 {
        let width = (hi[axis] - lo[axis]) / BINS as f64;
        if width <= 0.0 {
            continue;
        }
        let bin = |x: f64| (((x - lo[axis]) / width).floor().max(0.0) as usize).min(BINS - 1);
        let (mut starts, mut ends) = ([0usize; BINS], [0usize; BINS]);
        for r in refs {
            starts[bin(r.lo[axis] - slack)] += 1;
            ends[bin(r.hi[axis] + slack)] += 1;
        }
        let (mut nl, mut nr) = (0, refs.len());
        for k in 1..BINS {
            nl += starts[k - 1];
            nr -= ends[k - 1];
            if let Some(p) = candidate(lo[axis] + width * k as f64, lo, hi, axis) {
                best = better(best, Split { cost: sah(lo, hi, axis, p, nl, nr), axis, pos: p });
            }
        }
    }
    best
}

/// The bounds of the part of triangle `t` inside the box [lo, hi] (the triangle clipped
/// to the box's six planes, Sutherland–Hodgman), or None when it misses the box.
pub(super) fn clip(t: &[DVec3; 3], lo: DVec3, hi: DVec3) -> Option<(DVec3, DVec3)> {
    // Each plane adds at most one corner to a convex polygon: at most 3 + 6. Two buffers,
    // read from one and written to the other (no copy of the polygon between planes).
    let mut buf = [[DVec3::ZERO; 9]; 2];
    buf[0][..3].copy_from_slice(t);
    let (mut cur, mut n) = (0, 3);
    for axis in 0..3 {
        // Keep the points p with side · (p[axis] − plane) ≤ 0.
        for (side, plane) in [(-1.0, lo[axis]), (1.0, hi[axis])] {
            let d = |p: DVec3| side * (p[axis] - plane);
            // A plane that every corner lies inside leaves the polygon as it is (the
            // common case: a reference clipped where it crosses the split plane only).
            if buf[cur][..n].iter().all(|&p| d(p) <= 0.0) {
                continue;
            }
            let (a, b) = buf.split_at_mut(1);
            let (poly, next) = if cur == 0 { (&a[0], &mut b[0]) } else { (&b[0], &mut a[0]) };
            let mut m = 0;
            for i in 0..n {
                let (p, q) = (poly[i], poly[if i + 1 == n { 0 } else { i + 1 }]);
                let (dp, dq) = (d(p), d(q));
                if dp <= 0.0 {
                    next[m] = p;
                    m += 1;
                }
                if (dp < 0.0 && dq > 0.0) || (dp > 0.0 && dq < 0.0) {
                    let mut x = p + (q - p) * (dp / (dp - dq));
                    x[axis] = plane;
                    next[m] = x;
                    m += 1;
                }
            }
            if m == 0 {
                return None;
            }
            cur = 1 - cur;
            n = m;
        }
    }
    let (a, b) = buf[cur][..n].iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(a, b), &p| (a.min(p), b.max(p)));
    Some((a.max(lo), b.min(hi)))
}

pub fn pack(list: &TriangleList, max_depth: u32, leaf_size: u32, traversal: KdTraversal) -> Result<Packed> {
    let tree = KdTree::build(list, max_depth, leaf_size)?;
    let mut nodes = tree.words();
    let mut aux = Vec::new();
    if traversal == KdTraversal::Ropes {
        let boxes = tree.boxes();
        for (leaf, ropes) in tree.ropes() {
            nodes[leaf as usize][2] = aux.len() as u32;
            let (lo, hi) = boxes[leaf as usize];
            aux.extend([lo.x, lo.y, lo.z, hi.x, hi.y, hi.z].map(|v| (v as f32).to_bits()));
            aux.extend(ropes);
        }
    }
    Ok(Packed {
        nodes,
        refs: tree.refs.clone(),
        aux,
        accel: super::tree_accel(list, tree.lo.as_vec3(), tree.hi.as_vec3(), tree.nodes.len() as u32),
        shader: match traversal {
            KdTraversal::ShortStack => "raytrace/intersect_kdtree.comp",
            KdTraversal::Restart => "raytrace/intersect_kdtree_restart.comp",
            KdTraversal::Ropes => "raytrace/intersect_kdtree_ropes.comp",
        },
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// Random triangles in [−1, 1]³ (SplitMix64), with zero-area ones, axis-aligned ones
    /// (lying in planes that are split candidates) and a few spanning the whole cube.
    fn soup(n: usize, seed: u64) -> Vec<[Vec3; 3]> {
        let mut state = seed;
        let mut next = move || {
            state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            2.0 * (((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32) - 1.0
        };
        let size = 2.0 / (n as f32).cbrt();
        (0..n)
            .map(|i| {
                let c = Vec3::new(next(), next(), next());
                let s = if i % 97 == 5 { 2.0 } else { size };
                let a = c + Vec3::new(next(), next(), next()) * s;
                let b = c + Vec3::new(next(), next(), next()) * s;
                match i % 10 {
                    3 => [c, a, c + (a - c) * 0.5],
                    4 => [c, Vec3::new(a.x, c.y, a.z), Vec3::new(b.x, c.y, b.z)],
                    5 => [c, Vec3::new(c.x, a.y, a.z), Vec3::new(c.x, b.y, c.z)],
                    _ => [c, a, b],
                }
            })
            .collect()
    }

    /// Every leaf's box, walking down from the root.
    fn leaf_boxes(tree: &KdTree) -> Vec<(usize, DVec3, DVec3)> {
        let mut out = Vec::new();
        let mut stack = vec![(0usize, tree.lo, tree.hi)];
        while let Some((k, lo, hi)) = stack.pop() {
            match tree.nodes[k] {
                Node::Leaf { .. } => out.push((k, lo, hi)),
                Node::Interior { axis, split, left, right } => {
                    let (mut hl, mut lr) = (hi, lo);
                    hl[axis] = split as f64;
                    lr[axis] = split as f64;
                    assert!(split as f64 > lo[axis] && (split as f64) < hi[axis], "node {k}: split outside its box");
                    stack.push((left as usize, lo, hl));
                    stack.push((right as usize, lr, hi));
                }
            }
        }
        out
    }

    #[test]
    fn every_leaf_lists_the_triangles_that_meet_its_box() {
        for (n, leaf_size) in [(1usize, 1u32), (40, 1), (3000, 2)] {
            let list = TriangleList::from_soup(soup(n, 7 + n as u64)).unwrap();
            let tree = KdTree::build(&list, 0, leaf_size).unwrap();
            let tris: Vec<[DVec3; 3]> = list.triangles.iter().map(|t| t.map(|v| v.as_dvec3())).collect();
            let mut listed = vec![false; n];
            let s = DVec3::splat(tree.slack);
            for (k, lo, hi) in leaf_boxes(&tree) {
                let Node::Leaf { first, count } = tree.nodes[k] else { unreachable!() };
                let refs = &tree.refs[first as usize..(first + count) as usize];
                for (i, t) in tris.iter().enumerate() {
                    let listed_here = refs.contains(&(i as u32));
                    // Listed exactly where it meets the leaf's box widened by the slack (up
                    // to the clipping's own rounding, far below the slack).
                    if clip(t, lo - s * 0.99, hi + s * 0.99).is_some() {
                        assert!(listed_here, "N = {n}: triangle {i} meets leaf {k} but is not listed");
                    }
                    if listed_here {
                        assert!(clip(t, lo - s * 1.01, hi + s * 1.01).is_some(), "N = {n}: triangle {i} listed in leaf {k} it misses");
                        listed[i] = true;
                    }
                }
                let mut sorted = refs.to_vec();
                sorted.sort();
                sorted.dedup();
                assert_eq!(sorted.len(), refs.len(), "leaf {k} lists a triangle twice");
            }
            assert!(listed.iter().all(|&l| l), "N = {n}: a triangle in no leaf");
            assert!(tree.depth <= auto_depth(n), "depth {} > {}", tree.depth, auto_depth(n));
            if n == 3000 {
                // The SAH did split, and clipping kept the references near N.
                assert!(tree.nodes.len() > 100 && tree.refs.len() < 8 * n, "{} nodes, {} refs", tree.nodes.len(), tree.refs.len());
            }
        }
    }

    #[test]
    fn depth_is_bounded_and_deeper_trees_are_refused() {
        let list = TriangleList::from_soup(soup(2000, 3)).unwrap();
        for max_depth in [1, 3, 10] {
            let tree = KdTree::build(&list, max_depth, 1).unwrap();
            assert!(tree.depth <= max_depth && tree.depth > 0, "depth {} for max_depth {max_depth}", tree.depth);
        }
        // A pile of identical triangles cannot be split: one leaf, no runaway recursion.
        let pile = TriangleList::from_soup(vec![[Vec3::ZERO, Vec3::X, Vec3::Y]; 500]).unwrap();
        let tree = KdTree::build(&pile, 0, 1).unwrap();
        assert!(tree.depth <= auto_depth(500));
        assert!(tree.nodes.iter().any(|n| matches!(n, Node::Leaf { count: 500, .. })));
        let e = KdTree::build(&list, MAX_DEPTH + 1, 1).unwrap_err().to_string();
        assert!(e.contains("max_depth") && e.contains(&MAX_DEPTH.to_string()), "{e}");
        assert!(KdTree::build(&list, 0, 0).is_err());
        assert!(auto_depth(1) == 8 && auto_depth(100_000) == 30 && auto_depth(usize::MAX) == MAX_DEPTH);
    }

    #[test]
    fn clipping_bounds_the_part_inside_the_box() {
        let t = [DVec3::ZERO, DVec3::new(4.0, 0.0, 0.0), DVec3::new(0.0, 4.0, 0.0)];
        // The box [1, 2] × [1, 2] × [−1, 1] holds the part with x + y ≤ 4: all of it but
        // nothing beyond the hypotenuse, which passes through (2, 2).
        assert_eq!(
            clip(&t, DVec3::new(1.0, 1.0, -1.0), DVec3::new(2.0, 2.0, 1.0)),
            Some((DVec3::new(1.0, 1.0, 0.0), DVec3::new(2.0, 2.0, 0.0)))
        );
        let (lo, hi) = clip(&t, DVec3::new(3.0, 0.0, -1.0), DVec3::new(5.0, 5.0, 1.0)).unwrap();
        assert_eq!((lo, hi), (DVec3::new(3.0, 0.0, 0.0), DVec3::new(4.0, 1.0, 0.0)));
        // The box's corner region beyond the hypotenuse: the bounding boxes overlap, the
        // triangle does not.
        assert_eq!(clip(&t, DVec3::new(2.5, 2.5, -1.0), DVec3::new(3.0, 3.0, 1.0)), None);
        assert_eq!(clip(&t, DVec3::new(0.0, 0.0, 0.5), DVec3::new(1.0, 1.0, 1.0)), None);
    }

    #[test]
    fn packing_encodes_nodes_and_bounds() {
        let list = TriangleList::from_soup(soup(200, 11)).unwrap();
        let p = pack(&list, 0, 2, KdTraversal::ShortStack).unwrap();
        assert_eq!(p.accel.node_count as usize, p.nodes.len());
        for w in &p.nodes {
            if w[3] == LEAF {
                assert!((w[0] + w[1]) as usize <= p.refs.len());
            } else {
                assert!(w[3] < 3 && (w[1] as usize) < p.nodes.len() && (w[2] as usize) < p.nodes.len());
            }
        }
        let (lo, hi) = list.bounds();
        assert!(Vec3::from_slice(&p.accel.bounds_min[..3]).cmplt(lo).all() && Vec3::from_slice(&p.accel.bounds_max[..3]).cmpgt(hi).all());
        let empty = pack(&TriangleList::from_soup(vec![]).unwrap(), 0, 2, KdTraversal::Ropes).unwrap();
        assert_eq!(empty.accel.node_count, 0);
        assert_eq!(empty.shader, "raytrace/intersect_kdtree_ropes.comp");
    }

    /// Every rope leads to a node whose box holds all of the face's region just across the
    /// face (its centre and corners nudged outwards), pushed down as far as one child does;
    /// no rope only on the root's boundary.
    #[test]
    fn ropes_lead_across_each_face() {
        let list = TriangleList::from_soup(soup(400, 5)).unwrap();
        let tree = KdTree::build(&list, 0, 2).unwrap();
        let boxes = tree.boxes();
        let inside = |p: DVec3, (lo, hi): (DVec3, DVec3)| p.cmpge(lo).all() && p.cmple(hi).all();
        let ropes = tree.ropes();
        assert_eq!(ropes.len(), tree.nodes.iter().filter(|n| matches!(n, Node::Leaf { .. })).count());
        for (leaf, r) in ropes {
            let (lo, hi) = boxes[leaf as usize];
            for f in 0..6 {
                let (a, high) = (f / 2, f % 2 == 1);
                let plane = if high { hi[a] } else { lo[a] };
                let out = if high { 1e-9 } else { -1e-9 };
                if r[f] == NO_ROPE {
                    assert_eq!(plane, if high { tree.hi[a] } else { tree.lo[a] }, "leaf {leaf} face {f}: no rope inside the root");
                    continue;
                }
                let (b, c) = ((a + 1) % 3, (a + 2) % 3);
                for (u, v) in [(0.5, 0.5), (0.0, 0.0), (1.0, 1.0), (0.0, 1.0), (1.0, 0.0)] {
                    let mut p = DVec3::ZERO;
                    p[a] = plane + out;
                    p[b] = lo[b] + u * (hi[b] - lo[b]);
                    p[c] = lo[c] + v * (hi[c] - lo[c]);
                    assert!(inside(p, boxes[r[f] as usize]), "leaf {leaf} face {f}: rope {} misses {p}", r[f]);
                }
            }
        }
    }
}
