//! Geometry transformation (survey §5). Planar reflectors are exact: the scene is rendered
//! again from the camera mirrored through the reflector's plane (DB97, MBGN00), clipped at
//! that plane by an oblique near plane, and the image is laid onto the mirror's pixels with
//! its Fresnel weight (`geometry.mirror`). Mirrors seen in mirrors recurse: every mirrored
//! view is a camera view of its own, in which every camera pass of the frame draws its
//! objects (`mirror::MirrorViews` plans the views of a frame; the renderer records them
//! before the camera's own view, deepest first). Curved reflectors (EMD*05, EMDT06) move the
//! environment's vertices to their virtual positions instead (`curved`).

pub mod curved;

pub mod knobs;
pub mod mirror;
pub mod slots;
pub mod views;

pub use curved::{CURVED_REFLECTOR, CURVED_REFLECTOR_INFO};

use crate::frame::stage::order;
use crate::methods::registry::{CameraPass, Family, GpuSpec, LeavesOut, MapShading, Method, MethodInfo, ObjectClass, Profiled, Shape};
use crate::quality::Quality;
use crate::quality::{FrameKnobs, GeometryKnobs};

/// Planar mirrors' and refractors' views (§5) are the geometry family's part of a frame.
pub const FAMILY: Family = Family {
    name: "geometry",
    slots: slots::SLOTS,
    methods: &[PLANAR_MIRROR_INFO, PLANAR_REFRACTION_INFO, CURVED_REFLECTOR_INFO],
    plan_stages: Some(plan_fallback_maps),
    shows_others_by_maps: &[CURVED_REFLECTOR],
    plan_views: Some(plan_views),
    views: Some(view_blocks),
    frame_part: Some(views::create_frame_part),
    ..Family::NONE
};

/// The planar mirrors' views (the frame's extra camera views, one per layer), and their
/// mirrored cube views inside other objects' cube maps.
fn view_blocks(p: &crate::plan::types::Plan) -> Vec<(&'static str, u32)> {
    let mut v = vec![(crate::frame::stage::EXTRA_VIEWS, p.mirror_layers)];
    if !p.map_mirrors.is_empty() {
        v.push((crate::methods::cube_maps::MAP_MIRROR_VIEWS, (6 * p.map_mirrors.len() * p.envmaps.len()) as u32));
    }
    v
}

/// Planar mirrors' views (§5): as many layers as the recursion can use, within the budget.
/// Flat-faced refractors' faces bring two views each (reflection and refraction).
fn plan_views(scene: &crate::scene::Scene, p: &mut crate::plan::types::Plan) {
    let q = &p.quality;
    let planar = [PLANAR_MIRROR, PLANAR_REFRACTION];
    p.mirrors = p.objects.iter().filter(|o| planar.contains(&o.method)).map(|o| o.mesh).collect();
    let planes = p.mirrors.iter().map(|&m| mirror::plane_count(scene, m)).sum();
    p.mirror_layers = mirror::layers_needed(planes, q.frame.depth, q.geometry.mirror_budget);
    // Planar mirrors inside cube maps: one mirrored view per cube face per mirror, at most
    // mirror_budget mirrors (the rest show the environment there, as before).
    if !p.envmaps.is_empty() && q.geometry.map_mirrors {
        let mirrors = p.objects.iter().filter(|o| o.method == PLANAR_MIRROR).map(|o| o.mesh);
        p.map_mirrors = mirrors.take(q.geometry.mirror_budget as usize).collect();
    }
}

/// Planar mirrors and refractors whose views the budget can cut (more views within the
/// recursion depth than `mirror_budget`) get maps of their own: a distance map (§4.1), and a
/// refractor map (§4.4) for a solid refractor. A branch the budget or the depth leaves out
/// continues there — searched from the face's pixel along its ray in the distance map
/// around the object's centre, or inside a solid through its refractor map, as
/// refractor-map traces it — instead of with the environment along that ray (black in a
/// closed room). Objects whose every view fits keep no map.
fn plan_fallback_maps(scene: &crate::scene::Scene, p: &mut crate::plan::types::Plan, st: &mut crate::plan::types::PlanStages) {
    use crate::methods::distance::{DISTANCE_CUBES, REFRACTOR_CUBES};
    let q = p.quality.clone();
    let planar = [PLANAR_MIRROR, PLANAR_REFRACTION];
    let planes = p.objects.iter().filter(|o| planar.contains(&o.method)).map(|o| mirror::plane_count(scene, o.mesh)).sum();
    if !mirror::budget_cuts(planes, q.frame.depth, q.geometry.mirror_budget) {
        return;
    }
    let cube = crate::frame::stage::describe_cube(&q);
    for o in p.objects.iter_mut().filter(|o| planar.contains(&o.method)) {
        if o.class == ObjectClass::SolidDielectric {
            st.add_map(o, REFRACTOR_CUBES.kind(), cube.clone() + " (normal, distance) for the views the budget cuts");
        }
        st.add_map(o, DISTANCE_CUBES.kind(), cube.clone() + " for the views the budget cuts");
        o.reason += if o.class == ObjectClass::SolidDielectric {
            " · views beyond mirror_budget or depth: traced in a distance and a refractor map of its own (§4.1, §4.4)"
        } else {
            " · views beyond mirror_budget or depth: traced in a distance map of its own (§4.1)"
        };
    }
}

const fn one(_: &Quality) -> u32 {
    1
}

/// The family's camera passes and what they bring besides their own pass: planar mirrors'
/// and refractors' views (`geometry.mirror_view`, `geometry.stencil`), the curved reflector's
/// geometry image and virtual objects (`geometry.image`, `geometry.virtual…`).
pub const PROFILED: Profiled = Profiled { prefix: "geometry.", shared: false };

/// `geometry.mirror`: each planar mirror drawn from the camera (and from every mirrored view
/// that sees it) with the mirrored view's image at its pixels, weighted by Fresnel.
pub const MIRROR_PASS: CameraPass = CameraPass {
    name: "geometry.mirror",
    vertex: "scene/mesh.vert",
    fragment: "geometry/mirror.frag",
    flags: 0,
    order: order::CAMERA,
    create: Some(views::counting_pass),
    profiled: PROFILED,
};

pub const PLANAR_MIRROR_INFO: &MethodInfo = &MethodInfo {
    name: "planar-mirror",
    abi: 12,
    section: "§5",
    family: "geometry",
    summary: "planar reflectors by geometry transformation: the scene rendered again from the camera mirrored through the mirror's plane (oblique near plane at the mirror), laid onto the mirror's pixels with its Fresnel weight; mirrors in mirrors recurse up to depth, at most mirror_budget views a frame",
    serves: &[ObjectClass::Mirror],
    knobs: &[FrameKnobs::depth, GeometryKnobs::mirror_budget, GeometryKnobs::map_mirrors, FrameKnobs::fresnel],
    gpu: Some(GpuSpec { maps: &[], camera: MIRROR_PASS, map_shading: MapShading::Sky, leaves_out: LeavesOut::Itself, cycles: one, views: |q| q.frame.depth.min(q.geometry.mirror_budget).max(1), shades_every_pixel: false }),
    fallback: Some(crate::methods::DISTANCE),
    shape: Shape::Planar,
    needs: crate::methods::registry::DeviceNeeds::Nothing,
};
pub const PLANAR_MIRROR: Method = Method(PLANAR_MIRROR_INFO.name);

/// `geometry.refract`: each flat-faced dielectric (and thin pane) drawn from the camera (and
/// from every view that sees it) with its faces' reflected and refracted views at their
/// pixels, split by the pixel's own Fresnel weights.
pub const REFRACT_PASS: CameraPass = CameraPass {
    name: "geometry.refract",
    vertex: "scene/mesh.vert",
    fragment: "geometry/refract.frag",
    flags: 0,
    order: order::CAMERA,
    create: Some(views::counting_pass),
    profiled: PROFILED,
};

pub const PLANAR_REFRACTION_INFO: &MethodInfo = &MethodInfo {
    name: "planar-refraction",
    abi: 14,
    section: "§5",
    family: "geometry",
    summary: "flat-faced dielectrics (slabs, prisms, gems; convex) and thin panes by geometry transformation: per face seen, the scene rendered through it by the linearised refraction of the eye ray (GS04: an affine map per face, exact on the face's central ray; exact for thin panes) and reflected in it (exact), recursing through internal reflections to the exit faces up to depth, at most mirror_budget views a frame, with the pixel's own Fresnel split",
    serves: &[ObjectClass::SolidDielectric, ObjectClass::ThinDielectric],
    knobs: &[FrameKnobs::depth, GeometryKnobs::mirror_budget, FrameKnobs::fresnel],
    gpu: Some(GpuSpec { maps: &[], camera: REFRACT_PASS, map_shading: MapShading::Sky, leaves_out: LeavesOut::Itself, cycles: one, views: |q| q.geometry.mirror_budget.max(1), shades_every_pixel: false }),
    fallback: Some(crate::methods::DISTANCE),
    shape: Shape::Faceted,
    needs: crate::methods::registry::DeviceNeeds::Nothing,
};
pub const PLANAR_REFRACTION: Method = Method(PLANAR_REFRACTION_INFO.name);
