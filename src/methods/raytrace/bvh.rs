//! The BVH scheme (survey §2.3.5): the CPU reference's SAH BVH (`reference::bvh`, one
//! builder for both), packed for the GPU. Node k is the words 2k (min, first) and 2k + 1
//! (max, count): the boxes as f32 bits, `count` 0 for interior nodes whose children are
//! `first` and `first + 1`, else the leaf's references `refs[first..first + count]`.
//! `aux[k]` is node k's miss link (the node to visit when k's box is missed or k's subtree
//! is done; `BVH_END` after the last), for the stackless traversal of CHCH06.

use glam::DVec3;

use super::{Packed, TriangleList};
use crate::error::{Error, Result};
use crate::frame::layout::GpuAccel;
use crate::reference::bvh::Bvh;

/// The traversal stack of glsl/raytrace/bvh.glsl: a tree deeper than this is refused.
pub const STACK: usize = 96;
/// The miss link after the last node.
pub const BVH_END: u32 = u32::MAX;

pub fn pack(list: &TriangleList, stackless: bool) -> Result<Packed> {
    let bvh = Bvh::build(list.triangles.iter().enumerate().map(|(i, t)| (t.map(|v| v.as_dvec3()), 0, i as u32)));
    let nodes: Vec<(DVec3, DVec3, u32, u32)> = bvh.nodes().collect();
    // The corners are f32 values, so every box bound converts to f32 exactly.
    let mut words = Vec::with_capacity(2 * nodes.len());
    for &(lo, hi, first, count) in &nodes {
        let (lo, hi) = if list.is_empty() { (DVec3::ZERO, DVec3::ZERO) } else { (lo, hi) };
        let b = |v: f64| (v as f32).to_bits();
        words.push([b(lo.x), b(lo.y), b(lo.z), first]);
        words.push([b(hi.x), b(hi.y), b(hi.z), count]);
    }
    let (miss, depth) = miss_links(&nodes);
    if depth >= STACK {
        return Err(Error::invalid("bvh", format!("depth {depth} exceeds the traversal stack of {STACK}")));
    }
    let refs = bvh.triangles.iter().map(|t| t.tri).collect();
    let node_count = if list.is_empty() { 0 } else { nodes.len() as u32 };
    Ok(Packed {
        nodes: words,
        refs,
        aux: miss,
        accel: GpuAccel { triangle_count: list.len() as u32, node_count, ..bytemuck::Zeroable::zeroed() },
        shader: if stackless { "raytrace/intersect_bvh_stackless.comp" } else { "raytrace/intersect_bvh.comp" },
    })
}

/// Each node's miss link (the right sibling of a left child; the parent's miss link for a
/// right child; `BVH_END` for the root) and the tree's depth.
fn miss_links(nodes: &[(DVec3, DVec3, u32, u32)]) -> (Vec<u32>, usize) {
    let mut miss = vec![BVH_END; nodes.len()];
    let mut depth = 0;
    let mut stack = vec![(0usize, BVH_END, 0usize)];
    while let Some((k, link, d)) = stack.pop() {
        if k >= nodes.len() {
            continue;
        }
        miss[k] = link;
        depth = depth.max(d);
        let (_, _, first, count) = nodes[k];
        // Children follow their parent; an empty tree's root is a leaf of no triangles.
        if count == 0 && first as usize > k {
            let l = first as usize;
            stack.push((l, l as u32 + 1, d + 1));
            stack.push((l + 1, link, d + 1));
        }
    }
    (miss, depth)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn miss_links_thread_the_tree_in_pre_order() {
        let soup: Vec<[Vec3; 3]> =
            (0..40).map(|i| [Vec3::new(i as f32, 0.0, 0.0), Vec3::new(i as f32 + 0.5, 1.0, 0.0), Vec3::new(i as f32, 0.0, 1.0)]).collect();
        let p = pack(&TriangleList::from_soup(soup).unwrap(), true).unwrap();
        // Walking hit links (the left child of interior nodes, the miss link of leaves)
        // from the root visits every node once and ends at BVH_END.
        let n = p.nodes.len() / 2;
        let mut seen = vec![false; n];
        let mut k = 0u32;
        while k != BVH_END {
            assert!(!seen[k as usize], "node {k} twice");
            seen[k as usize] = true;
            let (first, count) = (p.nodes[2 * k as usize][3], p.nodes[2 * k as usize + 1][3]);
            k = if count == 0 { first } else { p.aux[k as usize] };
        }
        assert!(seen.iter().all(|&s| s));
        let mut refs = p.refs.clone();
        refs.sort();
        assert_eq!(refs, (0..40).collect::<Vec<u32>>());
    }
}
