//! The octree scheme (survey §2.3.2, Figure 8): the scene's bounding cube halved along all
//! three axes, cell by cell, until a cell lists at most `leaf_size` triangles or is
//! `max_depth` levels down; traversed on the GPU as MGK05 does: the leaf holding the ray's
//! current point is found by a top-down containment test from the root, its triangles are
//! tested, and the ray moves on to the point where it leaves the cell, nudged across the
//! face it leaves through.
//!
//! **Build.** A triangle is listed in every cell that its part clipped to the cell (the
//! kd-tree's Sutherland–Hodgman clip, `kdtree::clip`) reaches, within a `slack` of the
//! cell's box (1e-5 of the scene's extent plus its largest coordinate, as for the kd-tree),
//! so that a point the GPU's f32 arithmetic attributes to a neighbouring cell still finds
//! it. Cells are computed in f32 exactly as the traversal computes them (`mid = lo + half`).
//!
//! **Volumetric approximation** (`octree_volume=on`, MGK05): instead of its triangles, each
//! leaf stores one plane, the area-weighted mean of the parts of its triangles inside the
//! cell (their mean unit normal, through their area-weighted centroid), and a
//! representative triangle (the one with the largest part in the cell). The ray meets the
//! cell's plane inside the cell, and the hit is reported on the representative triangle
//! (barycentrics of the plane hit projected into it, clamped to it): an approximate scene,
//! whose error against the exact tracers the tests and BENCHMARKS measure. Leaves may be
//! made finer by `octree_max_depth`.
//!
//! **Encoding.** Node k is `accel_nodes[k]`:
//! - interior: (first child, 0, 0, `INTERIOR`): its eight children are nodes first + i,
//!   i = x | y << 1 | z << 2 the upper halves taken on each axis;
//! - leaf: (first reference, count, aux offset, `LEAF`): triangles `refs[first..first +
//!   count]`; with the volumetric approximation `aux[offset..offset + 5]` is the plane (unit
//!   normal xyz, then w with n·p + w = 0, as f32 bits) and the representative triangle (or
//!   `NO_TRIANGLE` for an empty leaf).
//!
//! Node 0 is the root; `accel.bounds_min/max` hold its cube (f32).

use glam::{DVec3, Vec3};

use super::{Packed, TriangleList};
use crate::error::{Error, Result};
use crate::frame::layout::RAY_NO_TRIANGLE;

/// The type word of an interior node (glsl/raytrace/intersect_octree.comp OCT_INTERIOR).
pub const INTERIOR: u32 = 0;
/// The type word of a leaf (OCT_LEAF).
pub const LEAF: u32 = 1;
/// The deepest level: cells of 2⁻²⁰ of the root's edge are far below f32's resolution of
/// points in a scene of that extent anyway (glsl OCT_MAX_DEPTH).
pub const MAX_DEPTH: u32 = 20;
/// Cells with more triangles build their children in parallel.
const PARALLEL_MIN: usize = 4096;

/// The depth a scene of `n` triangles gets by default: enough levels for cells of about
/// `leaf_size` triangles on a surface (a surface's cells grow 4× per level), plus two.
pub fn auto_depth(n: usize, leaf_size: u32) -> u32 {
    let cells = (n.max(1) as f64 / leaf_size.max(1) as f64).max(1.0);
    ((cells.log2() / 2.0).ceil() as u32 + 2).min(MAX_DEPTH)
}

/// A built octree (node 0 the root), before packing.
#[derive(Clone, Debug)]
pub struct Octree {
    pub nodes: Vec<[u32; 4]>,
    pub refs: Vec<u32>,
    /// The volumetric approximation's leaf words (empty without it).
    pub aux: Vec<u32>,
    /// The root's cube (f32 values).
    pub lo: Vec3,
    pub hi: Vec3,
    /// The deepest leaf's depth (the root's is 0).
    pub depth: u32,
}

enum Built {
    Leaf(Vec<u32>, Option<Volume>),
    Split(Box<[Built; 8]>),
}

/// The volumetric approximation of one leaf.
#[derive(Clone, Copy, Debug)]
struct Volume {
    normal: DVec3,
    w: f64,
    representative: u32,
}

struct Builder<'a> {
    triangles: &'a [[DVec3; 3]],
    slack: f64,
    max_depth: u32,
    leaf_size: usize,
    volume: bool,
}

impl Octree {
    /// Builds the octree over `list`; `max_depth` 0 means [`auto_depth`].
    pub fn build(list: &TriangleList, max_depth: u32, leaf_size: u32, volume: bool) -> Result<Octree> {
        super::check_tree_knobs(max_depth, MAX_DEPTH, leaf_size, ("octree_max_depth", "octree_leaf_size"), "one from the triangle count")?;
        let max_depth = if max_depth == 0 { auto_depth(list.len(), leaf_size) } else { max_depth };
        let triangles: Vec<[DVec3; 3]> = list.triangles.iter().map(|t| t.map(|v| v.as_dvec3())).collect();
        let (lo, hi, slack) = list.slack_bounds();
        // The cube: the box's longest edge on every axis, widened by the slack, in f32.
        let edge = (hi - lo).max_element().max(1e-30) + 4.0 * slack;
        let lo = (lo - DVec3::splat(2.0 * slack)).as_vec3();
        let hi = lo + Vec3::splat(edge as f32);
        let builder = Builder { triangles: &triangles, slack, max_depth, leaf_size: leaf_size as usize, volume };
        let all: Vec<u32> = (0..triangles.len() as u32).collect();
        let built = builder.cell(all, lo, hi, 0);
        let mut tree = Octree { nodes: vec![[0; 4]], refs: Vec::new(), aux: Vec::new(), lo, hi, depth: 0 };
        tree.flatten(built, 0, 0);
        if tree.refs.len() > u32::MAX as usize / 2 || tree.nodes.len() > u32::MAX as usize / 8 {
            return Err(Error::invalid(
                "octree",
                format!("{} references in {} nodes: lower octree_max_depth", tree.refs.len(), tree.nodes.len()),
            ));
        }
        Ok(tree)
    }

    /// Writes `b` at `slot`, its children (8 consecutive slots) after everything so far.
    fn flatten(&mut self, b: Built, slot: usize, depth: u32) {
        self.depth = self.depth.max(depth);
        match b {
            Built::Leaf(tris, volume) => {
                let aux = self.aux.len() as u32;
                if let Some(v) = volume {
                    let n = v.normal.as_vec3();
                    self.aux.extend([n.x.to_bits(), n.y.to_bits(), n.z.to_bits(), (v.w as f32).to_bits(), v.representative]);
                }
                self.nodes[slot] = [self.refs.len() as u32, tris.len() as u32, aux, LEAF];
                self.refs.extend(tris);
            }
            Built::Split(children) => {
                let first = self.nodes.len();
                self.nodes.resize(first + 8, [0; 4]);
                self.nodes[slot] = [first as u32, 0, 0, INTERIOR];
                for (i, c) in children.into_iter().enumerate() {
                    self.flatten(c, first + i, depth + 1);
                }
            }
        }
    }
}

impl Builder<'_> {
    fn cell(&self, tris: Vec<u32>, lo: Vec3, hi: Vec3, depth: u32) -> Built {
        if tris.len() <= self.leaf_size || depth >= self.max_depth {
            let volume = self.volume.then(|| self.volume_of(&tris, lo, hi));
            return Built::Leaf(tris, volume);
        }
        // The traversal's f32 arithmetic: mid = lo + half.
        let half = (hi - lo) * 0.5;
        let mid = lo + half;
        let boxes: [(Vec3, Vec3); 8] = std::array::from_fn(|i| {
            let upper = [i & 1 != 0, i & 2 != 0, i & 4 != 0];
            let pick = |k: usize, a: f32, b: f32| if upper[k] { b } else { a };
            (
                Vec3::new(pick(0, lo.x, mid.x), pick(1, lo.y, mid.y), pick(2, lo.z, mid.z)),
                Vec3::new(pick(0, mid.x, hi.x), pick(1, mid.y, hi.y), pick(2, mid.z, hi.z)),
            )
        });
        let s = DVec3::splat(self.slack);
        let lists: Vec<Vec<u32>> = boxes
            .iter()
            .map(|(a, b)| {
                tris.iter()
                    .copied()
                    .filter(|&t| super::kdtree::clip(&self.triangles[t as usize], a.as_dvec3() - s, b.as_dvec3() + s).is_some())
                    .collect()
            })
            .collect();
        let build = |(l, (a, b)): (Vec<u32>, &(Vec3, Vec3))| self.cell(l, *a, *b, depth + 1);
        let children: Vec<Built> = if tris.len() > PARALLEL_MIN {
            use rayon::prelude::*;
            lists.into_par_iter().zip(boxes.par_iter()).map(build).collect()
        } else {
            lists.into_iter().zip(boxes.iter()).map(build).collect()
        };
        let children: [Built; 8] = children.try_into().unwrap_or_else(|_| unreachable!("eight octants"));
        Built::Split(Box::new(children))
    }

    /// The leaf's plane and representative triangle (see the module documentation).
    fn volume_of(&self, tris: &[u32], lo: Vec3, hi: Vec3) -> Volume {
        let (mut normal, mut centroid, mut area) = (DVec3::ZERO, DVec3::ZERO, 0.0);
        let mut best = (0.0, RAY_NO_TRIANGLE);
        for &t in tris {
            let tri = &self.triangles[t as usize];
            let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
            let Some(unit) = n.try_normalize() else { continue };
            // The part inside the cell: its area from the clipped polygon's extent is not
            // kept by `clip`; weigh by the triangle's area times the share of its box inside.
            let (tlo, thi) = (tri[0].min(tri[1]).min(tri[2]), tri[0].max(tri[1]).max(tri[2]));
            let (clo, chi) = (tlo.max(lo.as_dvec3()), thi.min(hi.as_dvec3()));
            let share = |a: DVec3, b: DVec3| (b - a).max(DVec3::splat(1e-12)).element_product();
            let inside = (share(clo, chi) / share(tlo, thi)).clamp(0.0, 1.0);
            let a = 0.5 * n.length() * inside;
            if a <= 0.0 {
                continue;
            }
            // Orient normals alike (one side of a surface: the first triangle's).
            let unit = if normal.dot(unit) < 0.0 { -unit } else { unit };
            normal += unit * a;
            centroid += (clo + chi) * 0.5 * a;
            area += a;
            if a > best.0 {
                best = (a, t);
            }
        }
        let normal = normal.try_normalize().unwrap_or(DVec3::Y);
        let centroid = if area > 0.0 { centroid / area } else { (lo.as_dvec3() + hi.as_dvec3()) * 0.5 };
        Volume { normal, w: -normal.dot(centroid), representative: best.1 }
    }
}

pub fn pack(list: &TriangleList, max_depth: u32, leaf_size: u32, volume: bool) -> Result<Packed> {
    let tree = Octree::build(list, max_depth, leaf_size, volume)?;
    Ok(Packed {
        nodes: tree.nodes,
        refs: tree.refs,
        aux: tree.aux,
        accel: super::tree_accel(list, tree.lo, tree.hi, 1),
        shader: if volume { "raytrace/intersect_octree.comp#OCTREE_VOLUME" } else { "raytrace/intersect_octree.comp" },
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every triangle is listed in every leaf whose box (widened by the slack) its clipped
    /// part reaches: the invariant the traversal relies on.
    #[test]
    fn every_leaf_lists_what_passes_through_it() {
        let mut tris = Vec::new();
        for i in 0..300 {
            let f = i as f32;
            let c = Vec3::new((f * 0.37).sin(), (f * 0.71).cos(), (f * 0.13).sin()) * 2.0;
            tris.push([c, c + Vec3::new(0.3, 0.05, 0.0), c + Vec3::new(0.0, 0.2, 0.25)]);
        }
        let list = TriangleList::from_soup(tris.clone()).unwrap();
        let tree = Octree::build(&list, 0, 2, false).unwrap();
        // Walk the tree with boxes.
        let mut todo = vec![(0usize, tree.lo, tree.hi)];
        let mut leaves = 0;
        while let Some((k, lo, hi)) = todo.pop() {
            let w = tree.nodes[k];
            if w[3] == INTERIOR {
                let half = (hi - lo) * 0.5;
                let mid = lo + half;
                for i in 0..8 {
                    let u = [i & 1 != 0, i & 2 != 0, i & 4 != 0];
                    let a = Vec3::new(if u[0] { mid.x } else { lo.x }, if u[1] { mid.y } else { lo.y }, if u[2] { mid.z } else { lo.z });
                    let b = Vec3::new(if u[0] { hi.x } else { mid.x }, if u[1] { hi.y } else { mid.y }, if u[2] { hi.z } else { mid.z });
                    todo.push((w[0] as usize + i, a, b));
                }
                continue;
            }
            leaves += 1;
            let listed = &tree.refs[w[0] as usize..(w[0] + w[1]) as usize];
            for (t, tri) in tris.iter().enumerate() {
                let d = tri.map(|v| v.as_dvec3());
                if super::super::kdtree::clip(&d, lo.as_dvec3(), hi.as_dvec3()).is_some() {
                    assert!(listed.contains(&(t as u32)), "triangle {t} passes through leaf {k} but is not listed");
                }
            }
        }
        assert!(leaves > 8, "{leaves} leaves");
    }

    #[test]
    fn knobs_are_checked() {
        let list = TriangleList::from_soup(vec![[Vec3::ZERO, Vec3::X, Vec3::Y]]).unwrap();
        assert!(Octree::build(&list, MAX_DEPTH + 1, 4, false).is_err());
        assert!(Octree::build(&list, 0, 0, false).is_err());
        assert!(auto_depth(1_000_000, 4) <= MAX_DEPTH);
    }
}
