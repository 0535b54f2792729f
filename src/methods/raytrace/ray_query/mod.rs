//! `ray-query`: ray tracing in the original geometry (the `bvh` pipeline: primary hits by
//! rasterisation, shade, spawn, Fresnel branches, total internal reflection, exact shadow
//! rays) with Vulkan's ray queries (`VK_KHR_ray_query`) as its intersection step, through
//! acceleration structures the driver builds ([`accel`]). What every engine that traces
//! specular paths on today's GPUs does; on devices without the extensions (or a host device
//! that did not enable them) the plan gives its objects `bvh`, and says why.
//!
//! Its kernel (`glsl/raytrace/intersect_ray_query.comp`) reads the same query buffer and
//! writes the same hit buffer as every other scheme; its one binding of its own, the TLAS,
//! is set 5 (`RAY_QUERY_BINDINGS` in src/methods/raytrace/layout.in.rs).

pub mod accel;
pub mod scene;

use super::{stage, Scheme};
use crate::methods::registry::{DeviceNeeds, Method, MethodInfo};
use crate::methods::EVERY_CLASS;

pub const RAY_QUERY_INFO: &MethodInfo = &MethodInfo {
    name: "ray-query",
    abi: 16,
    section: "§2.3.5",
    family: "raytrace",
    summary: "exact ray tracing in the original geometry (the `bvh` pipeline) with Vulkan ray queries as the intersection step: one BLAS per mesh built by the driver, one instance per object in a TLAS rebuilt when objects move; falls back to `bvh` on devices without VK_KHR_ray_query",
    serves: EVERY_CLASS,
    knobs: super::RAY_KNOBS_ENGINE,
    gpu: Some(super::ray_tracer("raytrace.ray-query", |init, plan| stage::create(init, plan, Scheme::RayQuery))),
    fallback: None,
    shape: crate::methods::registry::Shape::Any,
    needs: DeviceNeeds::RayQuery { otherwise: super::BVH },
};
pub const RAY_QUERY: Method = Method(RAY_QUERY_INFO.name);
