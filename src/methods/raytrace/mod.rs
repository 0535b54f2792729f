//! Ray tracing in the original geometry on the GPU (survey §2): the triangle list, the
//! acceleration schemes and the intersection kernels that answer "the nearest hit of each
//! ray" for a buffer of ray queries (`GpuRayQuery` → `GpuRayHit`, set 2 of
//! src/frame/layout.in.rs), in the spirit of Purcell's decomposition (§2.3.1): every
//! scheme reads the same query buffer and writes the same hit buffer, so traversal is a
//! pluggable step between the passes that make rays and the passes that shade them.
//!
//! Each scheme is built on the CPU (the survey's 2008 state) into one uniform GPU form,
//! [`Packed`]: 16-byte node words whose meaning is the scheme's, a reference list into the
//! triangle list, an auxiliary word list, the kernel's parameters and its shader:
//! - [`Scheme::Brute`]: every triangle for every ray (the baseline the tests compare with);
//! - [`Scheme::Bvh`]: the CPU reference's SAH BVH (`reference::bvh`), or a linear BVH built
//!   on the GPU ([`lbvh`]), traversed nearest
//!   child first with a short stack, or stackless along hit/miss links (CHCH06);
//! - [`Scheme::Grid`]: a uniform grid with 3D-DDA traversal (Amanatides–Woo), optionally
//!   skipping empty space by each empty cell's Chebyshev distance to the nearest
//!   non-empty cell (KL04).
//! - [`Scheme::KdTree`]: an SAH kd-tree over clipped triangle boxes, traversed front to
//!   back with a short stack that falls back to kd-restart (HSHH07), by pure kd-restart
//!   (FS05), or stackless along ropes, each leaf's links to its neighbours (PGSS07).
//!
//! - [`Scheme::Octree`]: cells halved on all three axes (§2.3.2), traversed by MGK05's
//!   exit point and top-down descent, optionally over one averaged plane per leaf (MGK05's
//!   volumetric approximation);
//! - [`Scheme::Bih`]: the bounding interval hierarchy / skd-tree (§2.3.4, WMS06): two
//!   planes per node, every triangle in one child, built by the global heuristic without a
//!   sort, traversed with a stack in one pass (SKSS06).
//!
//! - [`Scheme::RayQuery`]: Vulkan's ray queries through acceleration structures that the
//!   driver builds on the GPU (`ray_query`).
//!
//! The BVH is also built on the GPU ([`lbvh`]: a linear BVH over Morton codes, Karras's
//! construction, and a bottom-up refit of any BVH): `bvh_build=lbvh` for the first build,
//! and by default (`bvh_update=lbvh`) whenever objects move or deform, so that a moving
//! scene does not wait for the CPU's SAH builder every frame. The other schemes are
//! rebuilt on the CPU when geometry changes.

pub mod bench;
pub mod bih;
pub mod bvh;
pub mod gpu;
pub mod grid;
pub mod kdtree;
pub mod knobs;
pub mod lbvh;
pub mod octree;
mod ray_order;
pub mod ray_query;
pub mod stage;

use glam::Vec3;

use crate::error::{Error, Result};
use crate::frame::layout::{GpuAccel, GpuTriangle};
use crate::frame::stage::{order, Stage, StageInit};
use crate::methods::registry::{CameraPass, GpuSpec, LeavesOut, MapShading, Method, MethodInfo, Profiled};
use crate::methods::EVERY_CLASS;

use crate::plan::types::CameraPlan;
use crate::quality::Quality;
use crate::quality::{FrameKnobs, RaytraceKnobs};
use crate::scene::Scene;

const fn one(_: &Quality) -> u32 {
    1
}

/// The camera pass of a ray-tracing method: its own stage (`stage::RayTrace`); the
/// shaders named are its visibility pass.
const fn camera(name: &'static str, create: fn(&StageInit, &CameraPlan) -> Result<Box<dyn Stage>>) -> CameraPass {
    CameraPass {
        name,
        vertex: "raytrace/primary.vert",
        fragment: "raytrace/primary.frag",
        flags: 0,
        order: order::RAYTRACE,
        create: Some(create),
        // Its passes (`raytrace.primary`, `raytrace.intersect.<scheme>`, per bounce
        // `raytrace.spawn` and `raytrace.shade`, `raytrace.resolve`) run over the whole screen.
        profiled: Profiled { prefix: "raytrace.", shared: true },
    }
}

/// Every ray tracer's GPU side: no maps, its own stage, seen in other objects' maps as the
/// environment only.
pub(crate) const fn ray_tracer(name: &'static str, create: fn(&StageInit, &CameraPlan) -> Result<Box<dyn Stage>>) -> GpuSpec {
    GpuSpec {
        maps: &[],
        camera: camera(name, create),
        map_shading: MapShading::Sky,
        leaves_out: LeavesOut::Nothing,
        cycles: one,
        views: |_| 0,
        shades_every_pixel: true,
    }
}

const RAY_KNOBS_BVH: &[&str] = &[
    FrameKnobs::depth,
    FrameKnobs::fresnel,
    RaytraceKnobs::ray_budget,
    RaytraceKnobs::bvh_traversal,
    RaytraceKnobs::bvh_build,
    RaytraceKnobs::bvh_update,
];
const RAY_KNOBS_KD: &[&str] = &[
    FrameKnobs::depth,
    FrameKnobs::fresnel,
    RaytraceKnobs::ray_budget,
    RaytraceKnobs::kd_max_depth,
    RaytraceKnobs::kd_leaf_size,
    RaytraceKnobs::kd_traversal,
];
pub(crate) const RAY_KNOBS_ENGINE: &[&str] = &[FrameKnobs::depth, FrameKnobs::fresnel, RaytraceKnobs::ray_budget];
const RAY_KNOBS_HIERARCHY: &[&str] = &[FrameKnobs::depth, FrameKnobs::fresnel, RaytraceKnobs::ray_budget, RaytraceKnobs::tile_size];
const RAY_KNOBS_OCTREE: &[&str] = &[
    FrameKnobs::depth,
    FrameKnobs::fresnel,
    RaytraceKnobs::ray_budget,
    RaytraceKnobs::octree_max_depth,
    RaytraceKnobs::octree_leaf_size,
    RaytraceKnobs::octree_volume,
];
const RAY_KNOBS_BIH: &[&str] =
    &[FrameKnobs::depth, FrameKnobs::fresnel, RaytraceKnobs::ray_budget, RaytraceKnobs::bih_max_depth, RaytraceKnobs::bih_leaf_size];
const RAY_KNOBS_GRID: &[&str] =
    &[FrameKnobs::depth, FrameKnobs::fresnel, RaytraceKnobs::ray_budget, RaytraceKnobs::grid_density, RaytraceKnobs::grid_skip];

/// Ray tracing in the original geometry (§2): each method's camera stage is the whole ray
/// pipeline; no hooks.
pub const FAMILY: crate::methods::registry::Family = crate::methods::registry::Family {
    name: "raytrace",
    methods: &[BVH_INFO, KD_TREE_INFO, GRID_INFO, OCTREE_INFO, BIH_INFO, RAY_ENGINE_INFO, RAY_HIERARCHY_INFO, ray_query::RAY_QUERY_INFO],
    describe: Some(describe_updates),
    // Every scheme of the compute intersection kernels marches graded media
    // (raytrace/intersect_main.glsl); the ray engine and the ray hierarchy intersect by
    // rasterisation and cone tiles, straight rays only.
    curved_rays: &[BVH, KD_TREE, GRID, OCTREE, BIH, ray_query::RAY_QUERY],
    ..crate::methods::registry::Family::NONE
};

/// `specula plan`'s line on how `bvh` follows moves (`bvh_update`), with the device's
/// predicted costs for the scene's triangles where its calibration measured them.
fn describe_updates(p: &crate::plan::Plan, scene: &Scene) -> Option<String> {
    use crate::methods::raytrace::knobs::BvhUpdate;
    use crate::plan::predict::cost_model::BvhUpdateCosts;
    let traced = p.stages.iter().any(|s| matches!(s, crate::plan::types::StageSpec::Camera(c) if c.name == "raytrace.bvh"));
    if !traced {
        return None;
    }
    let n = scene.triangle_count() as f64;
    let costs = p.target.as_ref().and_then(|t| t.costs.bvh_updates.as_ref());
    let ms = |way: [f64; 2]| BvhUpdateCosts::predict(way, n);
    let predicted = |way: fn(&BvhUpdateCosts) -> [f64; 2], what: &str| {
        costs.map_or(String::new(), |c| format!(" ({what} predicted {:.1} ms)", ms(way(c))))
    };
    let rebuild = match costs {
        Some(c) if ms(c.lbvh) < ms(c.sah) => {
            format!("a linear BVH built on the GPU (predicted {:.1} ms; the CPU's SAH build {:.1} ms)", ms(c.lbvh), ms(c.sah))
        }
        Some(c) => format!("the CPU's SAH build (predicted {:.1} ms; a linear BVH on the GPU {:.1} ms)", ms(c.sah), ms(c.lbvh)),
        None => "the CPU's SAH build where the device computes on the CPU, else a linear BVH on the GPU (no measured update costs)".into(),
    };
    let how = match p.quality.raytrace.bvh_update {
        BvhUpdate::Auto => format!(
            "rigid moves refit it on the GPU{}; a deformation or a turn beyond {:.0}° rebuilds it by {rebuild}",
            predicted(|c| c.refit, "refit"),
            stage::REFIT_TURN.to_degrees()
        ),
        BvhUpdate::Lbvh => format!("every move builds a linear BVH on the GPU{}", predicted(|c| c.lbvh, "build")),
        BvhUpdate::Refit => format!("every move refits it on the GPU{}", predicted(|c| c.refit, "refit")),
        BvhUpdate::Sah => format!("every move rebuilds it on the CPU by SAH{}", predicted(|c| c.sah, "build")),
    };
    Some(format!("bvh over {n} triangles (bvh_update={}): {how}", p.quality.get("bvh_update")))
}

pub const BVH_INFO: &MethodInfo = &MethodInfo {
    name: "bvh",
    abi: 7,
    section: "§2.3.5",
    family: "raytrace",
    summary: "exact ray tracing in the original geometry: primary hits by rasterisation, then per bounce intersect → shade (exact shadow rays) → spawn both Fresnel-weighted branches on the GPU, through the CPU reference's SAH BVH or a linear BVH built on the GPU (short-stack or stackless traversal); moving objects refit or rebuild it on the GPU (bvh_update)",
    serves: EVERY_CLASS,
    knobs: RAY_KNOBS_BVH,
    gpu: Some(ray_tracer("raytrace.bvh", |init, plan| {
            let q = &init.plan.quality;
            stage::create(init, plan, Scheme::Bvh { stackless: q.raytrace.bvh_stackless, gpu: q.raytrace.bvh_gpu_build })
        })),
    fallback: None,
    shape: crate::methods::registry::Shape::Any,
    needs: crate::methods::registry::DeviceNeeds::Nothing,
};
pub const BVH: Method = Method(BVH_INFO.name);

pub const RAY_ENGINE_INFO: &MethodInfo = &MethodInfo {
    name: "ray-engine",
    abi: 10,
    section: "§2.2",
    family: "raytrace",
    summary: "exact ray tracing in the original geometry (the `bvh` pipeline) with the ray engine as the intersection step: the rays as a texture, one quad over it per triangle, Möller–Trumbore in the fragment shader writing the hit distance as depth, the z-test keeping the nearest (O(N) per ray)",
    serves: EVERY_CLASS,
    knobs: RAY_KNOBS_ENGINE,
    gpu: Some(ray_tracer("raytrace.ray-engine", |init, plan| stage::create(init, plan, Scheme::RayEngine))),
    fallback: None,
    shape: crate::methods::registry::Shape::Any,
    needs: crate::methods::registry::DeviceNeeds::Nothing,
};
pub const RAY_ENGINE: Method = Method(RAY_ENGINE_INFO.name);

pub const RAY_HIERARCHY_INFO: &MethodInfo = &MethodInfo {
    name: "ray-hierarchy",
    abi: 11,
    section: "§2.2.1",
    family: "raytrace",
    summary: "the ray engine over tiles of the ray texture (its rays ordered by direction cell, then pixel, so that a tile's rays are coherent), each bounded by a cone built on the GPU from its rays; a tile is rasterised for a triangle only where the cone meets the triangle's bounding sphere (tested in the vertex shader)",
    serves: EVERY_CLASS,
    knobs: RAY_KNOBS_HIERARCHY,
    gpu: Some(ray_tracer("raytrace.ray-hierarchy", |init, plan| {
            stage::create(init, plan, Scheme::RayHierarchy { tile: init.plan.quality.raytrace.tile_size })
        })),
    fallback: None,
    shape: crate::methods::registry::Shape::Any,
    needs: crate::methods::registry::DeviceNeeds::Nothing,
};
pub const RAY_HIERARCHY: Method = Method(RAY_HIERARCHY_INFO.name);

pub const KD_TREE_INFO: &MethodInfo = &MethodInfo {
    name: "kd-tree",
    abi: 9,
    section: "§2.3.3",
    family: "raytrace",
    summary: "exact ray tracing in the original geometry (the `bvh` pipeline) through an SAH kd-tree over clipped triangle boxes, traversed with a short stack and push-down (HSHH07), by kd-restart (FS05) or stackless along ropes between neighbouring leaves (PGSS07)",
    serves: EVERY_CLASS,
    knobs: RAY_KNOBS_KD,
    gpu: Some(ray_tracer("raytrace.kd-tree", |init, plan| {
            let q = &init.plan.quality;
            stage::create(init, plan, Scheme::KdTree { max_depth: q.raytrace.kd_max_depth, leaf_size: q.raytrace.kd_leaf_size, traversal: q.raytrace.kd_traversal })
        })),
    fallback: None,
    shape: crate::methods::registry::Shape::Any,
    needs: crate::methods::registry::DeviceNeeds::Nothing,
};
pub const KD_TREE: Method = Method(KD_TREE_INFO.name);

pub const GRID_INFO: &MethodInfo = &MethodInfo {
    name: "grid",
    abi: 8,
    section: "§2.3.1",
    family: "raytrace",
    summary: "exact ray tracing in the original geometry (the `bvh` pipeline) through a uniform grid traversed by 3D-DDA, with optional empty-space skipping (KL04)",
    serves: EVERY_CLASS,
    knobs: RAY_KNOBS_GRID,
    gpu: Some(ray_tracer("raytrace.grid", |init, plan| {
            let q = &init.plan.quality;
            stage::create(init, plan, Scheme::Grid { density: q.raytrace.grid_density, skip_empty: q.raytrace.grid_skip })
        })),
    fallback: None,
    shape: crate::methods::registry::Shape::Any,
    needs: crate::methods::registry::DeviceNeeds::Nothing,
};
pub const GRID: Method = Method(GRID_INFO.name);

pub const OCTREE_INFO: &MethodInfo = &MethodInfo {
    name: "octree",
    abi: 17,
    section: "§2.3.2",
    family: "raytrace",
    summary: "exact ray tracing in the original geometry (the `bvh` pipeline) through an octree, cells halved on all axes until a few triangles remain, traversed by the exit point and a top-down descent from the root (MGK05); octree_volume=on traces one averaged plane per leaf instead (MGK05's volumetric approximation, approximate)",
    serves: EVERY_CLASS,
    knobs: RAY_KNOBS_OCTREE,
    gpu: Some(ray_tracer("raytrace.octree", |init, plan| {
            let q = &init.plan.quality;
            stage::create(init, plan, Scheme::Octree { max_depth: q.raytrace.octree_max_depth, leaf_size: q.raytrace.octree_leaf_size, volume: q.raytrace.octree_volume })
        })),
    fallback: None,
    shape: crate::methods::registry::Shape::Any,
    needs: crate::methods::registry::DeviceNeeds::Nothing,
};
pub const OCTREE: Method = Method(OCTREE_INFO.name);

pub const BIH_INFO: &MethodInfo = &MethodInfo {
    name: "bih",
    abi: 18,
    section: "§2.3.4",
    family: "raytrace",
    summary: "exact ray tracing in the original geometry (the `bvh` pipeline) through a bounding interval hierarchy (skd-tree): two planes per node, every triangle in exactly one child, built by WMS06's global heuristic without a sort, traversed with a stack in one pass (SKSS06)",
    serves: EVERY_CLASS,
    knobs: RAY_KNOBS_BIH,
    gpu: Some(ray_tracer("raytrace.bih", |init, plan| {
            let q = &init.plan.quality;
            stage::create(init, plan, Scheme::Bih { max_depth: q.raytrace.bih_max_depth, leaf_size: q.raytrace.bih_leaf_size })
        })),
    fallback: None,
    shape: crate::methods::registry::Shape::Any,
    needs: crate::methods::registry::DeviceNeeds::Nothing,
};
pub const BIH: Method = Method(BIH_INFO.name);

/// The scene's triangles in world space in scene order (mesh by mesh, index by index):
/// the ids that every scheme's hits refer to.
#[derive(Clone, Debug, Default)]
pub struct TriangleList {
    pub triangles: Vec<[Vec3; 3]>,
    /// The first triangle id of each mesh.
    pub mesh_offsets: Vec<u32>,
}

impl TriangleList {
    pub fn from_scene(scene: &Scene) -> TriangleList {
        let mut list = TriangleList::default();
        for mesh in &scene.meshes {
            list.mesh_offsets.push(list.triangles.len() as u32);
            for t in mesh.indices.chunks_exact(3) {
                // A hidden object's triangles collapse to a point: zero area, never hit,
                // never rasterised, while every triangle keeps its id.
                let corners = [0, 1, 2].map(|k| mesh.positions[t[k] as usize]);
                list.triangles.push(if mesh.hidden { [corners[0]; 3] } else { corners });
            }
        }
        list
    }

    /// A triangle soup; non-finite corners are refused with the triangle's index.
    pub fn from_soup(triangles: Vec<[Vec3; 3]>) -> Result<TriangleList> {
        if let Some(i) = triangles.iter().position(|t| t.iter().any(|v| !v.is_finite())) {
            return Err(Error::invalid(format!("triangles[{i}]"), format!("corners must be finite, got {:?}", triangles[i])));
        }
        Ok(TriangleList { triangles, mesh_offsets: vec![0] })
    }

    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// What the tree builders (kd-tree, octree, bih) start from: the bounds of every corner
    /// in f64 (a unit box for an empty list) and the slack they list triangles within, 1e-5
    /// of the extent plus the largest coordinate: far above the f32 rounding of any point
    /// in the scene, so that a point the GPU attributes to a neighbouring cell still finds
    /// its triangle.
    pub(crate) fn slack_bounds(&self) -> (glam::DVec3, glam::DVec3, f64) {
        let (lo, hi) = if self.is_empty() { (Vec3::ZERO, Vec3::ONE) } else { self.bounds() };
        let (lo, hi) = (lo.as_dvec3(), hi.as_dvec3());
        (lo, hi, 1e-5 * ((hi - lo).max_element() + lo.abs().max(hi.abs()).max_element()).max(1e-30))
    }

    /// The world-space bounds (min, max) of every corner.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.triangles.iter().flatten().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &v| (lo.min(v), hi.max(v)))
    }

    pub fn gpu(&self) -> Vec<GpuTriangle> {
        self.triangles
            .iter()
            .map(|t| GpuTriangle { v0: t[0].extend(0.0).to_array(), v1: t[1].extend(0.0).to_array(), v2: t[2].extend(0.0).to_array() })
            .collect()
    }
}

/// An acceleration scheme and its knobs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Scheme {
    /// Every triangle for every ray.
    Brute,
    /// SAH BVH built on the CPU, or (`gpu`) a linear BVH built on the GPU (`lbvh`);
    /// `stackless`: the threaded traversal along hit/miss links (CHCH06).
    Bvh { stackless: bool, gpu: bool },
    /// Uniform grid of about `density` × N cells; `skip_empty`: KL04 empty-space skipping.
    Grid { density: f32, skip_empty: bool },
    /// SAH kd-tree of at most `max_depth` levels (0: 8 + 1.3 log₂ N, at most
    /// `kdtree::MAX_DEPTH`), nodes of at most `leaf_size` (≥ 1) references left unsplit;
    /// traversed by `traversal`: the short stack with restart fallback and push-down
    /// (HSHH07), pure kd-restart (FS05) or ropes (PGSS07).
    KdTree { max_depth: u32, leaf_size: u32, traversal: knobs::KdTraversal },
    /// Octree of at most `max_depth` levels (0: `octree::auto_depth`), cells of at most
    /// `leaf_size` triangles left whole; `volume`: MGK05's volumetric approximation.
    Octree { max_depth: u32, leaf_size: u32, volume: bool },
    /// Bounding interval hierarchy of at most `max_depth` levels (0: `bih::auto_depth`),
    /// leaves of at most `leaf_size` triangles.
    Bih { max_depth: u32, leaf_size: u32 },
    /// The ray engine (§2.2, CHH02): the rays as a texture, every triangle rasterised over
    /// it as a quad, Möller–Trumbore in the fragment shader, the z-test keeping the nearest.
    RayEngine,
    /// The ray hierarchy (§2.2.1): the ray engine over `tile`×`tile` tiles of the ray
    /// texture, each tile drawn for a triangle only if its rays' cone meets the triangle's
    /// bounding sphere.
    RayHierarchy { tile: u32 },
    /// Vulkan's ray queries through acceleration structures the driver builds
    /// (`ray_query::accel`): the triangle list is kept for shading, the kernel traverses
    /// the TLAS.
    RayQuery,
}

impl Scheme {
    /// The profiler's name of its intersection pass: `raytrace.intersect.<scheme>`.
    pub fn pass_name(&self) -> &'static str {
        match self {
            Scheme::Brute => "raytrace.intersect.brute",
            Scheme::RayEngine => "raytrace.intersect.ray-engine",
            Scheme::RayHierarchy { .. } => "raytrace.intersect.ray-hierarchy",
            Scheme::Bvh { .. } => "raytrace.intersect.bvh",
            Scheme::Grid { .. } => "raytrace.intersect.grid",
            Scheme::KdTree { .. } => "raytrace.intersect.kdtree",
            Scheme::Octree { .. } => "raytrace.intersect.octree",
            Scheme::Bih { .. } => "raytrace.intersect.bih",
            Scheme::RayQuery => "raytrace.intersect.ray-query",
        }
    }

    /// Builds the scheme over `list` (CPU) into its GPU form.
    pub fn build(&self, list: &TriangleList) -> Result<Packed> {
        match *self {
            // The rasterising schemes keep nothing but the triangle list.
            Scheme::Brute | Scheme::RayEngine | Scheme::RayHierarchy { .. } => Ok(Packed {
                nodes: Vec::new(),
                refs: Vec::new(),
                aux: Vec::new(),
                accel: GpuAccel { triangle_count: list.len() as u32, ..bytemuck::Zeroable::zeroed() },
                shader: "raytrace/intersect_brute.comp",
            }),
            // The structures are the driver's, built on the GPU by the stage.
            Scheme::RayQuery => Ok(Packed {
                nodes: Vec::new(),
                refs: Vec::new(),
                aux: Vec::new(),
                accel: GpuAccel { triangle_count: list.len() as u32, ..bytemuck::Zeroable::zeroed() },
                shader: "raytrace/intersect_ray_query.comp",
            }),
            Scheme::Bvh { stackless, gpu: false } => bvh::pack(list, stackless),
            // The nodes are the GPU's to fill (`lbvh::GpuBvh`).
            Scheme::Bvh { stackless, gpu: true } => lbvh::placeholder(list, stackless),
            Scheme::Grid { density, skip_empty } => grid::pack(list, density, skip_empty),
            Scheme::KdTree { max_depth, leaf_size, traversal } => kdtree::pack(list, max_depth, leaf_size, traversal),
            Scheme::Octree { max_depth, leaf_size, volume } => octree::pack(list, max_depth, leaf_size, volume),
            Scheme::Bih { max_depth, leaf_size } => bih::pack(list, max_depth, leaf_size),
        }
    }
}

/// Checks a tree's depth and leaf-size knobs (named `depth_knob`, `leaf_knob`): the depth
/// at most `limit` (0 picks `auto`, described by `auto_text`), the leaf size at least 1.
pub(crate) fn check_tree_knobs(
    max_depth: u32,
    limit: u32,
    leaf_size: u32,
    (depth_knob, leaf_knob): (&str, &str),
    auto_text: &str,
) -> Result<()> {
    if max_depth > limit {
        return Err(Error::invalid(
            format!("knob {depth_knob}"),
            format!("{max_depth} exceeds the deepest tree the GPU traversal takes ({limit}); 0 picks {auto_text}"),
        ));
    }
    if leaf_size == 0 {
        return Err(Error::invalid(format!("knob {leaf_knob}"), "must be at least 1"));
    }
    Ok(())
}

/// The parameters of a tree scheme's kernel: the root's box (f32 values), the triangle
/// count and `nodes` (0 for an empty list, which every kernel then answers with no hit).
pub(crate) fn tree_accel(list: &TriangleList, lo: Vec3, hi: Vec3, nodes: u32) -> GpuAccel {
    GpuAccel {
        bounds_min: lo.extend(0.0).to_array(),
        bounds_max: hi.extend(0.0).to_array(),
        triangle_count: list.len() as u32,
        node_count: if list.is_empty() { 0 } else { nodes },
        ..bytemuck::Zeroable::zeroed()
    }
}

/// A scheme in its GPU form (see the module documentation).
#[derive(Clone, Debug)]
pub struct Packed {
    pub nodes: Vec<[u32; 4]>,
    pub refs: Vec<u32>,
    pub aux: Vec<u32>,
    /// The kernel's parameters (the query count is bound separately: `RAY_COUNT`).
    pub accel: GpuAccel,
    pub shader: &'static str,
}

impl Packed {
    /// Device bytes of the structure itself (nodes, references, auxiliary words).
    pub fn bytes(&self) -> u64 {
        (self.nodes.len() * 16 + self.refs.len() * 4 + self.aux.len() * 4) as u64
    }
}
