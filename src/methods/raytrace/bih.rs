//! The bounding interval hierarchy (survey §2.3.4; WMS06, the skd-tree of OMSD87 and
//! SKSS06): a binary tree whose node cuts its cell by two planes on one axis, the left
//! child's maximum and the right child's minimum; every triangle belongs to exactly one
//! child, the one that completely contains it, so the children may overlap (or leave a gap
//! of empty space between them).
//!
//! **Build** (WMS06's global heuristic, no sort and no cost model): a node's candidate
//! plane halves its *candidate box* (the scene's box at the root, then the halves it made)
//! on the box's longest axis, and its triangles are partitioned in place by their boxes'
//! centres against it; the two planes are then the left triangles' greatest and the right
//! triangles' least coordinate on that axis. When one side would be empty, the candidate box
//! shrinks to the other half and the step repeats, making no node (at most `MAX_EMPTY`
//! times, then the node is a leaf). A node of at most `leaf_size` triangles, or `max_depth`
//! levels down, is a leaf. Each step is one pass over the node's triangles: O(N log N) in
//! all, 0.10–0.19 µs per triangle on this project's 2-core machine for 10⁴–10⁶ triangles,
//! against the SAH BVH's 0.46–0.74 µs and the SAH kd-tree's 3.9–5.1 µs (BENCHMARKS.md,
//! Table 1); its traversal pays for it, about 1.9× the BVH's frame at 10⁶ triangles.
//!
//! **Robustness.** The planes are widened by a `slack` (the kd-tree's: 1e-5 of the scene's
//! extent plus its largest coordinate), so that the f32 crossings the GPU computes never cut
//! a child's interval short of a triangle it holds.
//!
//! **Encoding.** Node k is `accel_nodes[k]`:
//! - interior: (left maximum as f32 bits, right minimum as f32 bits, left child, axis
//!   0/1/2): the right child is the left child + 1;
//! - leaf: (first reference, count, 0, `LEAF`): triangles `refs[first..first + count]`.
//!
//! Node 0 is the root; `accel.bounds_min/max` hold the scene's box widened by the slack.
//! The traversal (glsl/raytrace/intersect_bih.comp) keeps far children on a stack of
//! `MAX_DEPTH` entries, one pass over the tree per ray (SKSS06).

use glam::DVec3;

use super::{Packed, TriangleList};
use crate::error::{Error, Result};

/// The axis word of a leaf (glsl BIH_LEAF).
pub const LEAF: u32 = 3;
/// The deepest tree, the traversal's stack size (glsl BIH_MAX_DEPTH).
pub const MAX_DEPTH: u32 = 48;
/// Empty halvings a node may try before it is made a leaf.
const MAX_EMPTY: u32 = 32;
/// Nodes with more triangles build their subtrees in parallel.
const PARALLEL_MIN: usize = 4096;

/// The depth limit by default: 2 log₂ N + 8 (a BIH is less balanced than an SAH tree),
/// capped at `MAX_DEPTH`.
pub fn auto_depth(n: usize) -> u32 {
    (2.0 * (n.max(1) as f64).log2() + 8.0).round().min(MAX_DEPTH as f64) as u32
}

enum Built {
    Leaf(Vec<u32>),
    Split { axis: usize, left_max: f32, right_min: f32, children: Box<[Built; 2]> },
}

/// A built hierarchy, before packing.
#[derive(Clone, Debug)]
pub struct Bih {
    pub nodes: Vec<[u32; 4]>,
    pub refs: Vec<u32>,
    pub lo: DVec3,
    pub hi: DVec3,
    pub depth: u32,
}

struct Builder<'a> {
    lo: &'a [DVec3],
    hi: &'a [DVec3],
    slack: f64,
    max_depth: u32,
    leaf_size: usize,
}

impl Bih {
    /// Builds the hierarchy over `list`; `max_depth` 0 means [`auto_depth`].
    pub fn build(list: &TriangleList, max_depth: u32, leaf_size: u32) -> Result<Bih> {
        super::check_tree_knobs(max_depth, MAX_DEPTH, leaf_size, ("bih_max_depth", "bih_leaf_size"), "2 log2 N + 8")?;
        let max_depth = if max_depth == 0 { auto_depth(list.len()) } else { max_depth };
        let lo: Vec<DVec3> = list.triangles.iter().map(|t| t[0].min(t[1]).min(t[2]).as_dvec3()).collect();
        let hi: Vec<DVec3> = list.triangles.iter().map(|t| t[0].max(t[1]).max(t[2]).as_dvec3()).collect();
        let (blo, bhi, slack) = list.slack_bounds();
        let builder = Builder { lo: &lo, hi: &hi, slack, max_depth, leaf_size: leaf_size as usize };
        let mut all: Vec<u32> = (0..list.len() as u32).collect();
        let built = builder.node(&mut all, blo, bhi, 0);
        let f32_box = |v: DVec3| v.as_vec3().as_dvec3();
        let mut tree = Bih {
            nodes: vec![[0; 4]],
            refs: Vec::new(),
            lo: f32_box(blo - DVec3::splat(slack)),
            hi: f32_box(bhi + DVec3::splat(slack)),
            depth: 0,
        };
        tree.flatten(built, 0, 0);
        if tree.refs.len() > u32::MAX as usize / 2 || tree.nodes.len() > u32::MAX as usize / 2 {
            return Err(Error::invalid("bih", format!("{} nodes: too many", tree.nodes.len())));
        }
        Ok(tree)
    }

    fn flatten(&mut self, b: Built, slot: usize, depth: u32) {
        self.depth = self.depth.max(depth);
        match b {
            Built::Leaf(tris) => {
                self.nodes[slot] = [self.refs.len() as u32, tris.len() as u32, 0, LEAF];
                self.refs.extend(tris);
            }
            Built::Split { axis, left_max, right_min, children } => {
                let first = self.nodes.len();
                self.nodes.resize(first + 2, [0; 4]);
                self.nodes[slot] = [left_max.to_bits(), right_min.to_bits(), first as u32, axis as u32];
                let [l, r] = *children;
                self.flatten(l, first, depth + 1);
                self.flatten(r, first + 1, depth + 1);
            }
        }
    }
}

impl Builder<'_> {
    fn node(&self, tris: &mut [u32], mut clo: DVec3, mut chi: DVec3, depth: u32) -> Built {
        let n = tris.len();
        if n <= self.leaf_size || depth >= self.max_depth {
            return Built::Leaf(tris.to_vec());
        }
        for _ in 0..MAX_EMPTY {
            let axis = (chi - clo).max_position();
            let plane = 0.5 * (clo[axis] + chi[axis]);
            // Partition in place by box centre (twice the centre against twice the plane).
            let mut split = 0;
            for i in 0..n {
                let t = tris[i] as usize;
                if self.lo[t][axis] + self.hi[t][axis] < 2.0 * plane {
                    tris.swap(i, split);
                    split += 1;
                }
            }
            if split == 0 {
                clo[axis] = plane;
                continue;
            }
            if split == n {
                chi[axis] = plane;
                continue;
            }
            let (left, right) = tris.split_at_mut(split);
            let left_max = left.iter().map(|&t| self.hi[t as usize][axis]).fold(f64::NEG_INFINITY, f64::max) + self.slack;
            let right_min = right.iter().map(|&t| self.lo[t as usize][axis]).fold(f64::INFINITY, f64::min) - self.slack;
            let (mut lhi, mut rlo) = (chi, clo);
            lhi[axis] = plane;
            rlo[axis] = plane;
            let (l, r) = if n > PARALLEL_MIN {
                rayon::join(|| self.node(left, clo, lhi, depth + 1), || self.node(right, rlo, chi, depth + 1))
            } else {
                (self.node(left, clo, lhi, depth + 1), self.node(right, rlo, chi, depth + 1))
            };
            return Built::Split { axis, left_max: f32_up(left_max), right_min: -f32_up(-right_min), children: Box::new([l, r]) };
        }
        Built::Leaf(tris.to_vec())
    }
}

/// `v` rounded up to an f32 (a plane rounded outwards never cuts into a triangle's extent).
fn f32_up(v: f64) -> f32 {
    let f = v as f32;
    if (f as f64) >= v || !f.is_finite() {
        f
    } else if f == 0.0 {
        f32::from_bits(1)
    } else if f > 0.0 {
        f32::from_bits(f.to_bits() + 1)
    } else {
        f32::from_bits(f.to_bits() - 1)
    }
}

pub fn pack(list: &TriangleList, max_depth: u32, leaf_size: u32) -> Result<Packed> {
    let tree = Bih::build(list, max_depth, leaf_size)?;
    Ok(Packed {
        nodes: tree.nodes,
        refs: tree.refs,
        aux: Vec::new(),
        accel: super::tree_accel(list, tree.lo.as_vec3(), tree.hi.as_vec3(), 1),
        shader: "raytrace/intersect_bih.comp",
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// Every triangle is in exactly one leaf, inside every plane on its way there.
    #[test]
    fn every_triangle_in_one_leaf_inside_its_planes() {
        let tris: Vec<[Vec3; 3]> = (0..2000)
            .map(|i| {
                let f = i as f32;
                let c = Vec3::new((f * 0.37).sin(), (f * 0.71).cos(), (f * 1.3).sin()) * 3.0;
                [c, c + Vec3::new(0.1, 0.02, 0.0), c + Vec3::new(0.0, 0.05, 0.08)]
            })
            .collect();
        let list = TriangleList::from_soup(tris.clone()).unwrap();
        let tree = Bih::build(&list, 0, 2).unwrap();
        let mut seen = vec![0u32; tris.len()];
        let mut todo = vec![(0usize, tree.lo, tree.hi)];
        while let Some((k, lo, hi)) = todo.pop() {
            let w = tree.nodes[k];
            if w[3] == LEAF {
                for &t in &tree.refs[w[0] as usize..(w[0] + w[1]) as usize] {
                    seen[t as usize] += 1;
                    for v in tris[t as usize] {
                        let v = v.as_dvec3();
                        assert!(v.cmpge(lo).all() && v.cmple(hi).all(), "triangle {t} outside its node's planes");
                    }
                }
                continue;
            }
            let a = w[3] as usize;
            let (mut lhi, mut rlo) = (hi, lo);
            lhi[a] = f32::from_bits(w[0]) as f64;
            rlo[a] = f32::from_bits(w[1]) as f64;
            todo.push((w[2] as usize, lo, lhi));
            todo.push((w[2] as usize + 1, rlo, hi));
        }
        assert!(seen.iter().all(|&c| c == 1), "a triangle in {} leaves", seen.iter().max().unwrap());
        assert!(tree.depth <= auto_depth(tris.len()));
    }
}
