//! Ray tracing in the sampled geometry (survey §4.1–§4.4): distance maps (radiance and the
//! Euclidean distance from the reference point) searched by the reflected and refracted
//! rays; inter-object cycles (§4.3); self refraction through refractor maps (§4.4) and
//! Wyman's image-space double refraction (§4.4).

pub mod hybrid;
pub mod image_space;
pub mod knobs;
pub mod refractor;
pub mod slots;

use crate::frame::stage::{cube_texel_bytes, describe_cube, order, LayerField, MapInfo, Maps, Stage, StageInit};
use crate::methods::cube_maps::{distance_images, CubeMaps, MapKind};
use crate::methods::registry::{CameraPass, GpuSpec, LeavesOut, MapShading, Method, MethodInfo, ObjectClass, Profiled};
use crate::methods::EVERY_CLASS;

use crate::plan::types::{CameraPlan, Plan};
use crate::quality::Quality;
use crate::quality::{CubeKnobs, DistanceKnobs, FrameKnobs, SearchKnobs};
use crate::Result;

/// `distance.generate`: the distance cube maps (two images, ping-pong, for inter-object
/// cycles).
pub const DISTANCE_CUBES: MapInfo = MapInfo {
    name: "distance.generate",
    order: order::ENVIRONMENT_MAPS,
    cube: true,
    layer_field: Some(LayerField::Envmap),
    create: create_distance,
    bytes: distance_bytes,
    texels: crate::frame::stage::cube_texels,
    describe: |q, _| describe_cube(q),
    shared: false,
};

fn create_distance(init: &StageInit, objects: &[usize], maps: &mut Maps) -> Result<Box<dyn Stage>> {
    Ok(Box::new(CubeMaps::new(init, objects, maps, MapKind::Distance)?))
}

fn distance_bytes(p: &Plan, objects: u32, _: (u32, u32)) -> u64 {
    let s = p.quality.cube.cube_size as u64;
    6 * s * s * cube_texel_bytes(&p.quality) * objects as u64 * distance_images(p)
}

/// `refractor.generate`: each solid refractor's own normal + distance cube map.
pub const REFRACTOR_CUBES: MapInfo = MapInfo {
    name: "refractor.generate",
    order: order::GEOMETRY_MAPS,
    cube: true,
    layer_field: Some(LayerField::Refractor),
    create: refractor::create,
    bytes: |p, n, _| {
        let s = p.quality.cube.cube_size as u64;
        6 * s * s * cube_texel_bytes(&p.quality) * n as u64
    },
    texels: crate::frame::stage::cube_texels,
    describe: |q, _| describe_cube(q) + " (normal, distance)",
    shared: false,
};

/// `image_space.backfaces`: the refractors' back faces from the camera.
pub const BACKFACES: MapInfo = MapInfo {
    name: "image_space.backfaces",
    order: order::CAMERA_MAPS,
    cube: false,
    layer_field: None,
    create: image_space::create,
    bytes: |_, _, (w, h)| w as u64 * h as u64 * 16,
    // Camera-sized and of the refractors' back faces only: screen work, not a map of the
    // scene (counted as texels it was priced as a lit cube of every triangle, 5× a cube at
    // 1080p).
    texels: |_, _, _| 0.0,
    describe: |_, _| "camera-sized RGBA32F back-face normals and depths + per-vertex thickness".into(),
    shared: false,
};

const SEARCH_KNOB_LIST: [&str; 10] = [
    CubeKnobs::cube_size,
    CubeKnobs::cube_precision,
    CubeKnobs::cube_mode,
    FrameKnobs::fresnel,
    CubeKnobs::ref_point,
    SearchKnobs::linear_steps,
    SearchKnobs::secant_steps,
    SearchKnobs::binary_steps,
    SearchKnobs::parallax_iterations,
    SearchKnobs::search_tolerance,
];
/// `image-space-refraction`'s knobs: the search's, and its exit point's refinement.
const IMAGE_SPACE_KNOBS: &[&str] = &{
    let mut all = [""; SEARCH_KNOB_LIST.len() + 1];
    let mut k = 0;
    while k < SEARCH_KNOB_LIST.len() {
        all[k] = SEARCH_KNOB_LIST[k];
        k += 1;
    }
    all[k] = DistanceKnobs::image_space_iterations;
    all
};

/// `distance`'s knobs: the search's, and the hybrid search's ray queries.
const DISTANCE_KNOBS: &[&str] = &{
    let mut all = [""; 11];
    let mut k = 0;
    while k < 10 {
        all[k] = SEARCH_KNOB_LIST[k];
        k += 1;
    }
    all[10] = DistanceKnobs::hybrid;
    all
};

const fn one(_: &Quality) -> u32 {
    1
}

const SEARCH: CameraPass = CameraPass {
    name: "distance.search",
    vertex: "scene/mesh.vert",
    fragment: "distance/search.frag",
    flags: 0,
    order: order::CAMERA,
    create: Some(create_search),
    profiled: Profiled::OWN,
};

/// A camera pass of the plain shader, or with `hybrid=rays|confirm` its HYBRID variant and
/// the ray queries it fires (hybrid.rs).
fn create_hybrid_or_plain(init: &StageInit, c: &CameraPlan) -> Result<Box<dyn Stage>> {
    let mode = init.plan.quality.distance.hybrid;
    if mode.traces() {
        let extra = hybrid::HybridRays::new(init, c)?;
        let mut c = c.clone();
        for (m, f) in c.objects.iter_mut() {
            if mode == knobs::Hybrid::Confirm {
                *f |= crate::frame::layout::FLAG_HYBRID_CONFIRM;
            }
            // Rays that leave an object that is not convex may meet it again.
            let x = init.plan.objects.iter().find(|o| o.mesh == *m).map_or(glam::Vec3::ZERO, |o| o.reference_point);
            if crate::plan::facts::may_meet_itself(&init.scene.meshes[*m], x) {
                *f |= crate::frame::layout::FLAG_HYBRID_REENTERS;
            }
        }
        // Counting the rays writes storage from the fragment shader: only where the device
        // was created with fragmentStoresAndAtomics (the library's own, where present).
        let variant = if init.ctx.fragment_stores { "HYBRID" } else { "HYBRID_UNCOUNTED" };
        return Ok(Box::new(crate::frame::camera::CameraShade::with_extra(
            init.ctx,
            init.layout,
            &c,
            init.multisample,
            Some(variant),
            Some(Box::new(extra)),
        )?));
    }
    Ok(Box::new(crate::frame::camera::CameraShade::new(init.ctx, init.layout, c, init.multisample)?))
}

/// `distance.search`, which the test knob `debug_fault=flip_reflection` breaks on purpose.
fn create_search(init: &StageInit, c: &CameraPlan) -> Result<Box<dyn Stage>> {
    let mut c = c.clone();
    if init.plan.quality.frame.debug_fault == crate::quality::DebugFault::FlipReflection {
        c.objects.iter_mut().for_each(|(_, f)| *f |= crate::frame::layout::FLAG_DEBUG_FLIP_REFLECTION);
    }
    create_hybrid_or_plain(init, &c)
}

const SOLIDS: &[ObjectClass] = &[ObjectClass::SolidDielectric];

/// Ray tracing in the sampled geometry (§4.1–§4.4): its maps, camera passes, the search's
/// push words, and how other families' objects show in its distance maps.
pub const FAMILY: crate::methods::registry::Family = crate::methods::registry::Family {
    name: "distance",
    slots: slots::SLOTS,
    methods: &[DISTANCE_INFO, DISTANCE_MULTI_INFO, REFRACTOR_MAP_INFO, IMAGE_SPACE_REFRACTION_INFO],
    push_words: Some(push_words),
    plan_stages: Some(compose),
    composes: Some(composed),
    ..crate::methods::registry::Family::NONE
};

/// Whether `m` draws the other specular objects by their own maps: distance maps (§4.3),
/// or a curved reflector's virtual objects (`Family::shows_others_by_maps`).
fn shows_by_maps(m: &Method) -> bool {
    let distance = m.gpu.is_some_and(|g| g.maps.iter().any(|i| i.name == DISTANCE_CUBES.name));
    distance || crate::methods::FAMILIES.iter().any(|f| f.shows_others_by_maps.contains(m))
}

/// Whether composition may draw `m`'s radiance cube as a distance map (`Family::cubes_compose`).
fn cube_composes(m: &Method) -> bool {
    crate::methods::FAMILIES.iter().any(|f| f.cubes_compose.contains(m))
}

/// The objects of a mixed plan whose radiance cube composition draws as a distance map
/// (`Family::cubes_compose`: environment mapping): those in view of another specular object
/// either way — it sees one (its cube must show that object by the object's own map), or an
/// object that shows the others by their maps sees it (it must show there by its own cube,
/// traced in it). A converted cube shows the others by their maps, so the set grows to a
/// fixed point. `sight[i]`: the positions of the objects that object i sees.
pub fn cubes_converted(methods: &[Method], sight: &[Vec<usize>]) -> Vec<bool> {
    let mut out: Vec<bool> = methods.iter().zip(sight).map(|(m, s)| cube_composes(m) && !s.is_empty()).collect();
    loop {
        let shows: Vec<bool> = methods.iter().zip(&out).map(|(m, &c)| c || shows_by_maps(m)).collect();
        let seen = |i: usize| sight.iter().enumerate().any(|(j, s)| j != i && shows[j] && s.contains(&i));
        let grow: Vec<usize> = (0..methods.len()).filter(|&i| !out[i] && cube_composes(&methods[i]) && seen(i)).collect();
        if grow.is_empty() {
            return out;
        }
        grow.into_iter().for_each(|i| out[i] = true);
    }
}

/// The objects of `methods` that composition gives maps of their own (or shades by the
/// distance map it keeps): a method that shades its object as the sky in maps — with no
/// cube map of its own, with a distance map of its own (distance, image-space refraction:
/// single-bounce methods), or with maps that are not one cube (image-based captures, relief
/// height maps: the distance map then goes to `shown_layer`) — not drawn by planar views,
/// where another object's method keeps distance maps, draws the others by their maps
/// (curved reflectors, captures, height maps) or has its radiance cube drawn as a distance
/// map (`cubes_converted`).
fn composed(methods: &[Method], sight: &[Vec<usize>]) -> Vec<bool> {
    let gpu = |m: &Method| m.gpu.expect("GPU method");
    let needs = |m: &Method| {
        let g = gpu(m);
        !cube_composes(m) && g.map_shading == MapShading::Sky && m.shape != crate::methods::registry::Shape::Planar
    };
    let converted = cubes_converted(methods, sight);
    let mapped: Vec<bool> = methods.iter().zip(&converted).map(|(m, &c)| c || shows_by_maps(m)).collect();
    let count = mapped.iter().filter(|&&d| d).count();
    // Another object than itself keeps distance maps (or draws the others by theirs).
    methods.iter().zip(&mapped).map(|(m, &d)| needs(m) && count > usize::from(d)).collect()
}

/// Composition across families (§4.3 across methods): an object whose method keeps no cube
/// map of its own (the ray tracers, layered maps, curved reflectors, planar refraction) would
/// show in the other objects' distance maps as a reflection of the sky only (black in a closed
/// room). Where some object has a distance map, each such object gets one of its own, around
/// its own reference point, used only for how it looks in the others' maps (an object whose
/// single-bounce method keeps one already, `distance` or `image-space-refraction`, uses
/// that one: it showed as the sky there, black beside a mirror on distance-multi) — traced in it
/// (a solid dielectric: refracted through its own refractor map first), as distance-multi's
/// objects are — with the inter-object cycles that needs. An environment-mapped object in
/// view of another specular object has its radiance cube drawn as a distance map instead
/// (`cubes_converted`: the same texels, radiance with the distance beside it), in the same
/// cycles, so that its cube shows the others by their maps and it is traced in its cube in
/// theirs. Planar mirrors are drawn into the maps by their mirrored views instead (geometry
/// family). A whole-scene method keeps its own behaviour, fallbacks included (what `tradeoff`
/// and the planner's corpus measure of it): only per-object choices compose; `compose=off`
/// keeps every object as the environment's reflection in the others' maps.
fn compose(_: &crate::scene::Scene, p: &mut Plan, st: &mut crate::plan::types::PlanStages) {
    let whole_scene = matches!(p.choice, crate::plan::ids::Choice::Method(_)) && p.overrides.is_empty();
    if whole_scene || !p.quality.frame.compose {
        return;
    }
    let methods: Vec<Method> = p.objects.iter().map(|o| o.method).collect();
    let sight = p.sight();
    let converted = cubes_converted(&methods, &sight);
    let chosen = composed(&methods, &sight);
    let q = p.quality.clone();
    let mut composed = false;
    for k in (0..p.objects.len()).filter(|&k| converted[k]) {
        for info in p.objects[k].method.gpu.map_or(&[][..], |g| g.maps) {
            st.remove_map(&mut p.objects, k, info.name);
        }
        let o = &mut p.objects[k];
        st.add_map(o, DISTANCE_CUBES.kind(), describe_cube(&q) + " (its cube, with distances: inter-object cycles)");
        o.map_shading = MapShading::Traced;
        o.leaves_out = LeavesOut::Itself;
        o.reason += " · its cube drawn as a distance map in the inter-object cycles: the others shown in it by their maps, itself traced in it in theirs (§4.3)";
        composed = true;
    }
    for (o, _) in p.objects.iter_mut().zip(chosen).filter(|(_, c)| *c) {
        let solid = o.class == ObjectClass::SolidDielectric;
        if solid {
            st.add_map(o, REFRACTOR_CUBES.kind(), describe_cube(&q) + " (normal, distance) for the other objects' maps");
        }
        // Maps of its own that hold its envmap_layer and are not this cube (captures, height
        // maps): the cube goes to shown_layer.
        let apart =
            o.method.gpu.is_some_and(|g| g.maps.iter().any(|i| i.layer_field == Some(LayerField::Envmap) && i.name != DISTANCE_CUBES.name));
        let field = if apart { Some(LayerField::Shown) } else { DISTANCE_CUBES.layer_field };
        let what = describe_cube(&q) + " for the other objects' maps";
        match o.maps.iter_mut().find(|m| m.pass == DISTANCE_CUBES.name) {
            // A distance map it keeps for itself (relief_source=distance) serves.
            Some(m) if apart => m.layer_field = field,
            _ => st.add_map(o, crate::plan::types::MapKind { layer_field: field, ..DISTANCE_CUBES.kind() }, what),
        }
        o.map_shading = if solid { MapShading::Refractor } else { MapShading::Traced };
        o.leaves_out = LeavesOut::Itself;
        o.reason += " · in the other objects' distance maps: traced in a distance map of its own (§4.3)";
        composed = true;
    }
    if composed {
        p.inter_object = true;
        if !p.frame_latency {
            p.cycles = p.cycles.max(2);
        }
    }
}

/// The search's words (every cube-map search reads them) and self refraction's bounces.
fn push_words(q: &crate::quality::Quality, _: &crate::frame::stage::ViewLayout, w: &mut crate::frame::words::PushWords) {
    use crate::frame::layout::*;
    let s = &q.search;
    w.set(SEARCH_LINEAR_STEPS, s.linear_steps);
    w.set(SEARCH_SECANT_STEPS, s.secant_steps);
    w.set(SEARCH_BINARY_STEPS, s.binary_steps);
    w.set(SEARCH_PARALLAX_ITERATIONS, s.parallax_iterations);
    w.set(SEARCH_TOLERANCE, s.search_tolerance);
    w.set(INTERNAL_BOUNCES, q.distance.internal_bounces);
    w.set(IMAGE_SPACE_ITERATIONS, q.distance.image_space_iterations);
}

pub const DISTANCE_INFO: &MethodInfo = &MethodInfo {
    name: "distance",
    abi: 3,
    section: "§4.1, §4.2",
    family: "distance",
    summary: "distance maps (radiance + Euclidean distance from the reference point); reflected and refracted rays traced in them by linear search on the projected segment, secant and binary refinement, or parallax correction (eq. 4, 5)",
    serves: EVERY_CLASS,
    knobs: DISTANCE_KNOBS,
    gpu: Some(GpuSpec { maps: &[DISTANCE_CUBES], camera: SEARCH, map_shading: MapShading::Sky,
        leaves_out: LeavesOut::Itself, cycles: one, views: |_| 0, shades_every_pixel: false }),
    fallback: None,
    shape: crate::methods::registry::Shape::Any,
    needs: crate::methods::registry::DeviceNeeds::Nothing,
};
pub const DISTANCE: Method = Method(DISTANCE_INFO.name);

pub const DISTANCE_MULTI_INFO: &MethodInfo = &MethodInfo {
    name: "distance-multi",
    abi: 4,
    section: "§4.3",
    family: "distance",
    summary: "inter-object reflections and refractions: each object's distance map regenerated in `cycles` cycles, specular objects in maps searching their own previous-cycle maps; `frame_latency=on` does one cycle per frame instead",
    serves: EVERY_CLASS,
    knobs: &[
        CubeKnobs::cube_size, CubeKnobs::cube_precision, CubeKnobs::cube_mode, FrameKnobs::fresnel, CubeKnobs::ref_point, SearchKnobs::linear_steps, SearchKnobs::secant_steps, SearchKnobs::binary_steps, SearchKnobs::parallax_iterations, SearchKnobs::search_tolerance, DistanceKnobs::cycles, DistanceKnobs::frame_latency, DistanceKnobs::hybrid,
    ],
    gpu: Some(GpuSpec {
        maps: &[DISTANCE_CUBES],
        camera: SEARCH,
        map_shading: MapShading::Traced,
        leaves_out: LeavesOut::Itself,
        cycles: |q| if q.distance.frame_latency { 1 } else { q.distance.cycles },
        views: |_| 0,
        shades_every_pixel: false,
    }),
    fallback: None,
    shape: crate::methods::registry::Shape::Any,
    needs: crate::methods::registry::DeviceNeeds::Nothing,
};
pub const DISTANCE_MULTI: Method = Method(DISTANCE_MULTI_INFO.name);

pub const REFRACTOR_MAP_INFO: &MethodInfo = &MethodInfo {
    name: "refractor-map",
    abi: 5,
    section: "§4.4",
    family: "distance",
    summary: "self refraction: each solid refractor's own normal + distance cube map, the refracted ray searched inside it, refracted out (Snell) or internally reflected up to `internal_bounces` times, then traced in the environment's distance map",
    serves: SOLIDS,
    knobs: &[
        CubeKnobs::cube_size, CubeKnobs::cube_precision, CubeKnobs::cube_mode, FrameKnobs::fresnel, CubeKnobs::ref_point, SearchKnobs::linear_steps, SearchKnobs::secant_steps, SearchKnobs::binary_steps, SearchKnobs::parallax_iterations, SearchKnobs::search_tolerance, DistanceKnobs::internal_bounces, DistanceKnobs::hybrid,
    ],
    gpu: Some(GpuSpec {
        maps: &[REFRACTOR_CUBES, DISTANCE_CUBES],
        camera: CameraPass { name: "refractor.search", vertex: "scene/mesh.vert", fragment: "distance/refractor/search.frag", flags: 0, order: order::CAMERA + 1, create: Some(create_hybrid_or_plain), profiled: Profiled::OWN },
        map_shading: MapShading::Refractor,
        leaves_out: LeavesOut::Itself,
        cycles: one,
        views: |_| 0,
        shades_every_pixel: false,
    }),
    fallback: Some(DISTANCE),
    shape: crate::methods::registry::Shape::Any,
    needs: crate::methods::registry::DeviceNeeds::Nothing,
};
pub const REFRACTOR_MAP: Method = Method(REFRACTOR_MAP_INFO.name);

pub const IMAGE_SPACE_REFRACTION_INFO: &MethodInfo = &MethodInfo {
    name: "image-space-refraction",
    abi: 6,
    section: "§4.4",
    family: "distance",
    summary: "Wyman's two-pass double refraction: back-face normals and depths from the camera, per-vertex thickness along the inverted normal, the exit ray traced in the distance map",
    serves: SOLIDS,
    knobs: IMAGE_SPACE_KNOBS,
    gpu: Some(GpuSpec {
        maps: &[DISTANCE_CUBES, BACKFACES],
        camera: CameraPass {
            name: "image_space.refract",
            vertex: "distance/image_space/refract.vert",
            fragment: "distance/image_space/refract.frag",
            flags: 0,
            order: order::CAMERA + 2,
            create: None,
            profiled: Profiled::OWN,
        },
        map_shading: MapShading::Sky,
        leaves_out: LeavesOut::Itself,
        cycles: one,
        views: |_| 0,
        shades_every_pixel: false,
    }),
    fallback: Some(DISTANCE),
    shape: crate::methods::registry::Shape::Any,
    needs: crate::methods::registry::DeviceNeeds::Nothing,
};
pub const IMAGE_SPACE_REFRACTION: Method = Method(IMAGE_SPACE_REFRACTION_INFO.name);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::methods::{BVH, ENVMAP, PROXY_BOX, REFRACTOR_MAP};

    /// Which environment-mapped objects composition draws as distance maps: in view either
    /// way of another specular object, grown to a fixed point through converted ones; and
    /// what the others get beside them.
    #[test]
    fn environment_mapped_cubes_compose_where_in_view() {
        // 0 envmap sees nothing and nobody sees it; 1 envmap sees the bvh object 2; 3
        // proxy-box is seen by 1 only (a converted cube), 4 refractor-map sees nothing.
        let methods = [ENVMAP, ENVMAP, BVH, PROXY_BOX, REFRACTOR_MAP];
        let sight = vec![vec![], vec![2, 3], vec![0], vec![], vec![]];
        assert_eq!(cubes_converted(&methods, &sight), [false, true, false, true, false]);
        // The bvh object gets a distance map of its own (converted cubes show it), the
        // converted ones none (their cube is one), the refractor-mapped glass none (it
        // shades itself in maps).
        assert_eq!(composed(&methods, &sight), [false, false, true, false, false]);
        // Seen by a ray tracer only: nothing to convert (the rays trace it).
        assert_eq!(cubes_converted(&[ENVMAP, BVH], &[vec![], vec![0]]), [false, false]);
    }
}
