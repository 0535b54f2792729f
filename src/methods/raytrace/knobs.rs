//! Ray tracing in the original geometry (§2): its knobs.

use crate::quality::knob::knobs;

knobs! {
    /// Ray tracing in the original geometry (§2).
    pub struct RaytraceKnobs {
        /// ray tracing (§2): capacity of each bounce's ray queue; beyond it the lightest paths are dropped (counted, with their weight)
        ray_budget: u32 = 4, count(1..=64, "rays per pixel");
        /// bvh (§2.3.5): nearest child first with a short stack, or stackless along hit/miss links (CHCH06)
        bvh_stackless as bvh_traversal: bool = "stack", one_of()["stack" => false, "stackless" => true];
        /// grid (§2.3.1): cells of the uniform grid per triangle of the scene
        grid_density: f32 = 2, real(0.01..=64, "cells per triangle");
        /// grid: skip empty space by each empty cell's distance to the nearest non-empty cell (KL04)
        grid_skip: bool = "on", one_of()["on" => true, "off" => false];
        /// kd-tree (§2.3.3): the deepest level; 0: 8 + 1.3 log₂ N
        kd_max_depth: u32 = 0, count(0..=64, "levels");
        /// kd-tree: nodes of at most this many triangles are not split
        kd_leaf_size: u32 = 4, count(1..=64, "triangles");
        /// kd-tree: a short stack with push-down (HSHH07), or kd-restart from the root (FS05)
        kd_restart as kd_traversal: bool = "short-stack", one_of()["short-stack" => false, "restart" => true];
        /// ray-hierarchy (§2.2.1): edge of the ray-texture tiles bounded by one cone each
        tile_size: u32 = "16", one_of("rays")["8" => 8, "16" => 16, "32" => 32];
        /// ray tracing: report rays per bounce, dropped rays and the ray hierarchy's culling rate (an extra pass)
        ray_stats: bool = "off", one_of()["on" => true, "off" => false];
    }
}
