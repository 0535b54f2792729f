//! The hybrid search (`hybrid=rays`): the distance-map camera pass (§4.2, and self
//! refraction's, §4.4: inside the refractor map too) traces in the map as always, and where
//! its search cannot answer — the ray escaped (in a closed scene a gap
//! the map does not cover), or its hit is not the surface the map holds in that direction (a
//! point hidden behind a silhouette from the reference point, beyond the search's tolerance)
//! — fires a Vulkan ray query and shades what it meets (`glsl/distance/search.frag`,
//! HYBRID). Approximate where the map is right, exact where it is wrong; the statistics say
//! which fraction of each object's rays were traced in full. `hybrid=confirm` also confirms
//! each answer the map gives by a ray query bounded by its hit (from the ray's start to 1 %
//! past it: the map's answer is the query's t_max, and a face hidden from the reference
//! point before it is found as well) and shades the triangle there (exact point, normal and
//! texture instead of the map's filtered radiance). Both modes trace with the object itself a reflected ray that goes into its own
//! surface (below the fragment's triangle, near a silhouette), which the map cannot see; and
//! on a solid refractor that is neither convex nor flat, every ray that leaves it is traced
//! against it first and followed back in where it meets it again.

use ash::vk;

use crate::frame::camera::PassExtra;
use crate::frame::stage::StageInit;
use crate::methods::raytrace::ray_query::scene::SceneRays;
use crate::plan::types::CameraPlan;
use crate::vk::{Context, Owner, Recorder};
use crate::{Error, Result};

pub struct HybridRays {
    rays: SceneRays,
    /// (mesh, name) of the pass's objects, for the statistics.
    objects: Vec<(usize, String)>,
    /// The pass counts its rays (the device lets fragment shaders write storage).
    counted: bool,
}

impl HybridRays {
    pub fn new(init: &StageInit, plan: &CameraPlan) -> Result<HybridRays> {
        let rays = SceneRays::new(init, "distance.hybrid").map_err(|e| match e {
            Error::Unsupported(why) => Error::Unsupported(format!("knob hybrid=rays traces through {why}: use hybrid=off")),
            e => e,
        })?;
        let objects = plan.objects.iter().map(|&(m, _)| (m, init.scene.meshes[m].name.clone())).collect();
        Ok(HybridRays { rays, objects, counted: init.ctx.fragment_stores })
    }
}

impl PassExtra for HybridRays {
    fn layout(&self) -> vk::PipelineLayout {
        self.rays.layout
    }

    fn before(&mut self, ctx: &Context, rec: &mut Recorder) {
        self.rays.record(ctx, rec);
    }

    fn bind(&self, ctx: &Context, cmd: vk::CommandBuffer) {
        self.rays.bind(ctx, cmd);
    }

    /// The structures it traces through are the frame's (updated by the renderer).
    fn update(&mut self, _: &StageInit, _: &crate::scene::update::Changes) -> Result<()> {
        Ok(())
    }

    /// Per object the fraction of its search's rays that were traced
    /// (`distance.hybrid.traced.<object>`), and the rays searched; nothing where the pass
    /// could not count them (a host's device, HYBRID_UNCOUNTED).
    fn stats(&self) -> Vec<(String, f64)> {
        if !self.counted {
            return Vec::new();
        }
        let counts = self.rays.counts();
        let mut out = Vec::new();
        for (m, name) in &self.objects {
            let Some(&(asked, traced)) = counts.get(*m) else { continue };
            out.push((format!("distance.hybrid.rays.{name}"), asked as f64));
            out.push((format!("distance.hybrid.traced.{name}"), if asked > 0 { traced as f64 / asked as f64 } else { 0.0 }));
        }
        out
    }

    fn destroy(&mut self, ctx: &Context) {
        Owner::destroy(&mut self.rays, ctx);
    }
}
