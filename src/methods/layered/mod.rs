//! Ray tracing in layered distance maps (survey §4.5, UPSK07): one multi-layer cube map of
//! the whole scene around one reference point, made by depth peeling (`layered.peel`), in
//! which the camera pass traces every specular object's rays recursively
//! (`layered.search`): each layer searched with the combined linear + secant search, the
//! nearest hit over the layers wins, specular hits continue the ray. Self reflections of
//! concave mirrors, non-convex refractors and surfaces hidden from the reference point,
//! which single-layer maps miss (Figures 21, 28), come from the same loop.
//!
//! The objects that take this method share the one map (Table 1: one map for the whole
//! scene, O(N·L) to build, O(L) per lookup): its reference point is the centre of their
//! bounding box (or the `ref_point` knob), the number of layers L the scene's depth
//! complexity from there (`layers=auto`, counted on the GPU) or the `layers` knob.

pub mod knobs;
pub mod peel;
pub mod slots;

use glam::Vec3;

use crate::frame::stage::{order, FramePart, MapInfo, StageInit, ViewFrame};
use crate::methods::registry::{CameraPass, GpuSpec, LeavesOut, MapShading, Method, MethodInfo, Profiled, Shape};
use crate::methods::EVERY_CLASS;
use crate::plan::types::Plan;
use crate::quality::{CubeKnobs, FrameKnobs, LayeredKnobs, SearchKnobs};
use crate::quality::{Quality, MAX_LAYERS};

/// `layered.peel`: the layers of the whole scene's map (see `peel`).
pub const LAYERED_CUBES: MapInfo = MapInfo {
    name: "layered.peel",
    order: order::ENVIRONMENT_MAPS + 1,
    cube: true,
    layer_field: None,
    create: peel::create,
    bytes: |p, objects, _| if objects == 0 { 0 } else { peel::bytes(&p.quality, planned_layers(p)) },
    texels: |q, layers, size| crate::frame::stage::cube_texels(q, layers, size) * layers as f64,
    describe: |q, _| {
        let layers = q.layered.layers.map_or(format!("auto (the depth complexity, at most {MAX_LAYERS})"), |l| l.to_string());
        format!(
            "one map of the whole scene, shared: layers {layers} (one more, the farthest surfaces, where they are fewer than the depth complexity), each {}",
            peel::describe_layer(q)
        )
    },
    shared: true,
};

/// The layers the plan budgets: the knob or (`auto`) the depth complexity counted when the
/// plan was made (at most `MAX_LAYERS`; without a count, that most), and one more for the
/// farthest surfaces where they are fewer than the complexity (`peel`). The stage allocates
/// what it counts on the GPU (`layered.layers` in the frame's stats).
pub fn planned_layers(p: &Plan) -> u32 {
    layers_for(&p.quality, p.layered_extent.as_ref().map(peel::PeelExtent::depth))
}

/// [`planned_layers`] under `q` where the depth complexity counted is `depth`.
pub fn layers_for(q: &Quality, depth: Option<u32>) -> u32 {
    let (peeled, cut) = peeled(q, depth);
    peeled + u32::from(cut)
}

/// The layers peeled under `q` where the depth complexity counted is `depth` (the knob, else
/// the complexity, at most `MAX_LAYERS`; that most without a count), and whether the peel is
/// cut (one more layer then holds the farthest surfaces).
pub(super) fn peeled(q: &Quality, depth: Option<u32>) -> (u32, bool) {
    let layers = q.layered.layers.unwrap_or_else(|| depth.map_or(MAX_LAYERS, |d| d.clamp(1, MAX_LAYERS)));
    (layers, depth.is_some_and(|d| d > layers))
}

/// The cubes' worth of texels the peel draws under `q` where its layers hold surfaces as
/// `extent` says (`peel`: each layer of each face drawn only where its texels meet that many
/// surfaces; the farthest surfaces' layer, where the peel is cut, whole); without a count, or
/// in one multiview pass per layer (which draws every face), every layer whole.
pub fn drawn_cubes(q: &Quality, extent: Option<&peel::PeelExtent>) -> f64 {
    let Some(extent) = extent else { return layers_for(q, None) as f64 };
    if q.cube.cube_mode != crate::quality::CubeMode::SixPasses {
        return layers_for(q, Some(extent.depth())) as f64;
    }
    let (layers, cut) = peeled(q, Some(extent.depth()));
    extent.drawn_cubes(layers) + f64::from(u32::from(cut))
}

const fn one(_: &Quality) -> u32 {
    1
}

pub const SEARCH: CameraPass = CameraPass {
    name: "layered.search",
    vertex: "scene/mesh.vert",
    fragment: "layered/search.frag",
    flags: 0,
    order: order::CAMERA,
    create: Some(search_pass),
    profiled: Profiled::OWN,
};

/// `layered.search`: where the device lets fragment shaders write, its COUNT_FAR variant,
/// which counts per object the pixels whose path met the farthest layer of a cut peel
/// (`layered.far_layer_pixels.<object>`; the counters exist only while the peel is cut).
fn search_pass(init: &StageInit, plan: &crate::plan::types::CameraPlan) -> crate::Result<Box<dyn crate::frame::stage::Stage>> {
    let variant = init.ctx.fragment_stores.then_some("COUNT_FAR");
    Ok(Box::new(crate::frame::camera::CameraShade::with_extra(init.ctx, init.layout, plan, init.multisample, variant, None)?))
}

pub const LAYERED_INFO: &MethodInfo = &MethodInfo {
    name: "layered",
    abi: 13,
    section: "§4.5",
    family: "layered",
    summary: "layered distance maps of the whole scene by depth peeling (layers = its depth complexity from one reference point); recursive ray tracing in the fragment shader: every layer searched (linear + secant), the nearest hit wins, specular hits reflected and refracted with Fresnel up to depth",
    serves: EVERY_CLASS,
    knobs: &[
        LayeredKnobs::layers, LayeredKnobs::layered_branches, FrameKnobs::depth, CubeKnobs::cube_size, CubeKnobs::cube_precision, CubeKnobs::cube_mode, FrameKnobs::fresnel, CubeKnobs::ref_point, SearchKnobs::linear_steps, SearchKnobs::secant_steps, SearchKnobs::binary_steps, SearchKnobs::search_tolerance,
    ],
    gpu: Some(GpuSpec { maps: &[LAYERED_CUBES], camera: SEARCH, map_shading: MapShading::Sky, leaves_out: LeavesOut::Nothing, cycles: one, views: |_| 0, shades_every_pixel: false }),
    fallback: None,
    shape: Shape::Any,
    needs: crate::methods::registry::DeviceNeeds::Nothing,
};
pub const LAYERED: Method = Method(LAYERED_INFO.name);

/// Below this visible fraction from its own reference point an object is not convex from
/// there: it sees itself (a concave mirror) or hides part of itself (a non-convex
/// refractor), which a single layer cannot hold.
pub const CONVEX_FRACTION: f32 = 0.98;

/// Above this area fraction of its surface facing its reference point an object is
/// concave there (a bowl): its reflections see itself.
pub const SELF_FACING: f32 = 0.02;

/// The layered map's reference point: the `ref_point` knob, else the centre of the
/// bounding box of the objects that take the method (`meshes`).
pub fn centre(scene: &crate::scene::Scene, q: &Quality, meshes: &[usize]) -> Vec3 {
    if let Some(p) = q.cube.ref_point {
        return p;
    }
    let mut b = crate::scene::Aabb::EMPTY;
    for &m in meshes {
        b = b.union(&scene.meshes[m].bounds());
    }
    if b.is_empty() {
        Vec3::ZERO
    } else {
        b.center()
    }
}

/// Layered maps (§4.5): one map of the whole scene, shared by the objects that take it.
pub const FAMILY: crate::methods::registry::Family = crate::methods::registry::Family {
    name: "layered",
    slots: slots::SLOTS,
    methods: &[LAYERED_INFO],
    plan_objects: Some(share_centre),
    views: Some(|p| if p.layered_centre.is_some() { vec![(VIEWS, 6)] } else { Vec::new() }),
    frame_part: Some(|init, _| Ok(init.plan.layered_centre.map(|_| Box::new(LayeredViews) as Box<dyn FramePart>))),
    ..crate::methods::registry::Family::NONE
};

/// The view block of the shared layered map's six faces, around `plan.layered_centre`.
pub const VIEWS: &str = "layered.views";

/// The layered map's part of a frame: its six cube views.
struct LayeredViews;

impl FramePart for LayeredViews {
    fn write_views(&mut self, fr: &ViewFrame, table: &mut [crate::gpu_scene::GpuView]) {
        let (Some(c), Some(base)) = (fr.plan.layered_centre, fr.layout.first(VIEWS)) else { return };
        for f in 0..6 {
            let vp = crate::cube::face_view_proj(f as usize, c, fr.plan.cube_near);
            table[(base + f) as usize] = crate::frame::views::view(vp, c.extend(0.0), glam::Vec4::ZERO);
        }
    }

    fn destroy(&mut self, _ctx: &crate::vk::Context) {}
}

/// Gives every layered object of the plan the shared map's reference point.
pub fn share_centre(scene: &crate::scene::Scene, p: &mut Plan) {
    let meshes = p.objects_with(LAYERED);
    if meshes.is_empty() {
        return;
    }
    let c = centre(scene, &p.quality, &meshes);
    p.layered_centre = Some(c);
    p.layered_extent = Some(peel::extent_on_cpu(scene, c, p.quality.cube.cube_size.min(64)));
    for o in p.objects.iter_mut().filter(|o| o.method == LAYERED) {
        o.reference_point = c;
        o.reference_note = Some(if p.quality.cube.ref_point.is_some() {
            "the layered map's, set by the ref_point knob".into()
        } else {
            "the layered map's: the centre of its objects' bounding box".into()
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The peel draws a face's layer k where its texels meet more than k surfaces (the
    /// rectangle around them); the farthest surfaces' layer, where the layers are fewer than
    /// the deepest texel's, whole.
    #[test]
    fn a_face_peels_only_the_layers_it_reaches() {
        // 4² faces: face 0 meets 3 surfaces at texel (1, 2), 1 elsewhere; face 1 none; the
        // others 1 everywhere.
        let e = peel::PeelExtent::from_counts(4, |face, x, y| match face {
            0 if (x, y) == (1, 2) => 3,
            1 => 0,
            _ => 1,
        });
        assert_eq!(e.depth(), 3);
        assert_eq!(e.faces[0], vec![[0, 0, 4, 4], [1, 2, 2, 3], [1, 2, 2, 3]]);
        assert!(e.faces[1].is_empty());
        let mut q = Quality::default();
        // Layer 0 of five faces whole, layers 1 and 2 one texel each of face 0.
        assert_eq!(drawn_cubes(&q, Some(&e)), (5.0 + 2.0 / 16.0) / 6.0);
        assert_eq!(drawn_cubes(&q, None), layers_for(&q, None) as f64);
        // Two layers: the farthest surfaces' layer whole.
        q.layered.layers = Some(2);
        assert_eq!(drawn_cubes(&q, Some(&e)), (5.0 + 1.0 / 16.0) / 6.0 + 1.0);
    }
}
