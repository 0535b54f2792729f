//! Ray tracing in the original geometry (§2): its knobs.

use crate::quality::knob::knobs;

knobs! {
    /// Ray tracing in the original geometry (§2).
    pub struct RaytraceKnobs {
        /// ray tracing (§2): capacity of each bounce's ray queue; beyond it the lightest paths are dropped (counted, with their weight)
        ray_budget: u32 = 4, count(1..=64, "rays per pixel");
        /// bvh (§2.3.5): nearest child first with a short stack, or stackless along hit/miss links (CHCH06)
        bvh_stackless as bvh_traversal: bool = "stack", one_of()["stack" => false, "stackless" => true];
        /// bvh: the first build, on the CPU by the surface area heuristic (sah), or on the GPU as a linear BVH over Morton codes (lbvh: Karras's construction, one triangle per leaf; faster to build, slower to traverse)
        bvh_gpu_build as bvh_build: bool = "sah", one_of()["sah" => false, "lbvh" => true];
        /// bvh: when objects move or deform, the current tree's boxes recomputed on the GPU when objects moved rigidly (turned less than 20° in all since the tree was built), else the tree built again where it is faster (auto: by the CPU's SAH builder on a device whose compute runs on the CPU, such as lavapipe, else on the GPU); always a linear BVH built on the GPU (lbvh); always a refit (refit: no new grouping, so boxes grow loose as objects travel apart); or always the SAH tree built on the CPU (sah)
        bvh_update: BvhUpdate = "auto", one_of()["auto" => BvhUpdate::Auto, "lbvh" => BvhUpdate::Lbvh, "refit" => BvhUpdate::Refit, "sah" => BvhUpdate::Sah];
        /// grid (§2.3.1): cells of the uniform grid per triangle of the scene
        grid_density: f32 = 2, real(0.01..=64, "cells per triangle");
        /// grid: skip empty space by each empty cell's distance to the nearest non-empty cell (KL04)
        grid_skip: bool = "on", one_of()["on" => true, "off" => false];
        /// kd-tree (§2.3.3): the deepest level; 0: 8 + 1.3 log₂ N
        kd_max_depth: u32 = 0, count(0..=64, "levels");
        /// kd-tree: nodes of at most this many triangles are not split
        kd_leaf_size: u32 = 4, count(1..=64, "triangles");
        /// kd-tree: a short stack with push-down (HSHH07), kd-restart from the root (FS05), or stackless along each leaf's ropes to its neighbours (PGSS07)
        kd_traversal: KdTraversal = "short-stack", one_of()["short-stack" => KdTraversal::ShortStack, "restart" => KdTraversal::Restart, "ropes" => KdTraversal::Ropes];
        /// octree (§2.3.2): the deepest level; 0: from the triangle count (cells of about octree_leaf_size triangles on a surface)
        octree_max_depth: u32 = 0, count(0..=20, "levels");
        /// octree: cells of at most this many triangles are not halved
        octree_leaf_size: u32 = 4, count(1..=64, "triangles");
        /// octree: MGK05's volumetric approximation, one averaged plane per leaf instead of its triangles (approximate)
        octree_volume: bool = "off", one_of()["off" => false, "on" => true];
        /// bih (§2.3.4): the deepest level; 0: 2 log₂ N + 8
        bih_max_depth: u32 = 0, count(0..=48, "levels");
        /// bih: nodes of at most this many triangles are leaves
        bih_leaf_size: u32 = 4, count(1..=64, "triangles");
        /// ray-hierarchy (§2.2.1): edge of the ray-texture tiles bounded by one cone each
        tile_size: u32 = "16", one_of("rays")["8" => 8, "16" => 16, "32" => 32];
        /// ray tracing: report rays per bounce, dropped rays and the ray hierarchy's culling rate (an extra pass)
        ray_stats: bool = "off", one_of()["on" => true, "off" => false];
    }
}

/// How the kd-tree is traversed (survey §2.3.3).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum KdTraversal {
    /// Front to back with a short stack that falls back to restarting from the push-down
    /// node (HSHH07).
    ShortStack,
    /// kd-restart from the root at each leaf's exit (FS05).
    Restart,
    /// Stackless: each leaf's six ropes name its neighbours across its faces (PGSS07).
    Ropes,
}

/// How the BVH follows objects that move or deform.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum BvhUpdate {
    /// A refit over rigid moves (`stage::REFIT_TURN`), else a rebuild by the builder that
    /// is faster on the device.
    Auto,
    /// A linear BVH built on the GPU from the triangles as they are now.
    Lbvh,
    /// The current tree's boxes recomputed on the GPU (its grouping kept).
    Refit,
    /// The SAH tree built again on the CPU.
    Sah,
}
