//! Environment mapping (survey §3): one radiance cube map per specular object, rasterised
//! from its reference point without the object (`generate`, shared with the distance maps
//! of §4), looked up in the reflected and refracted directions — as they are (§3.1), or
//! towards where the ray leaves a proxy of the environment (§3.2), or meets a proxy displaced
//! by height maps (§3.2, `relief`); or several cube maps captured around the object, warped
//! by their distances or blended (§3.3, `captures`).

pub mod captures;
pub mod knobs;
pub mod relief;
pub mod slots;

use crate::frame::stage::{cube_texel_bytes, describe_cube, order, LayerField, MapInfo};
use crate::frame::FLAG_PROXY_BOX;
use crate::methods::registry::{CameraPass, GpuSpec, LeavesOut, MapShading, Method, MethodInfo, Profiled};
use crate::methods::EVERY_CLASS;
use crate::plan::types::Plan;
use crate::quality::Quality;
use crate::quality::{CubeKnobs, EnvmapKnobs, FrameKnobs, SearchKnobs};

/// `envmap.generate`: the radiance cube maps.
pub const RADIANCE_CUBES: MapInfo = MapInfo {
    name: "envmap.generate",
    order: order::ENVIRONMENT_MAPS,
    cube: true,
    layer_field: Some(LayerField::Envmap),
    create: crate::methods::cube_maps::create_radiance,
    bytes: radiance_bytes,
    texels: crate::frame::stage::cube_texels,
    describe: |q, _| describe_cube(q),
    shared: false,
};

fn radiance_bytes(p: &Plan, objects: u32, _: (u32, u32)) -> u64 {
    let s = p.quality.cube.cube_size as u64;
    6 * s * s * cube_texel_bytes(&p.quality) * objects as u64
}

const KNOBS: &[&str] = &[CubeKnobs::cube_size, CubeKnobs::cube_precision, CubeKnobs::cube_mode, FrameKnobs::fresnel, CubeKnobs::ref_point];

const fn one(_: &Quality) -> u32 {
    1
}

const fn spec(camera: CameraPass) -> GpuSpec {
    spec_with(&[RADIANCE_CUBES], camera)
}

/// The family's methods' GPU description: its maps and camera pass; shown in the other
/// objects' maps as the environment's reflection, leaving itself out of its own.
const fn spec_with(maps: &'static [MapInfo], camera: CameraPass) -> GpuSpec {
    GpuSpec {
        maps,
        camera,
        map_shading: MapShading::Sky,
        leaves_out: LeavesOut::Itself,
        cycles: one,
        views: |_| 0,
        shades_every_pixel: false,
    }
}

const SHADE: CameraPass = CameraPass {
    name: "envmap.shade",
    vertex: "scene/mesh.vert",
    fragment: "envmap/shade.frag",
    flags: 0,
    order: order::CAMERA,
    create: None,
    profiled: Profiled::OWN,
};

const fn proxy(flags: u32) -> CameraPass {
    CameraPass {
        name: "proxy.shade",
        vertex: "scene/mesh.vert",
        fragment: "envmap/proxy.frag",
        flags,
        order: order::CAMERA,
        create: None,
        profiled: Profiled::OWN,
    }
}

/// Environment mapping (§3): its maps and camera passes; the image-based captures' places,
/// views and words.
pub const FAMILY: crate::methods::registry::Family = crate::methods::registry::Family {
    name: "envmap",
    slots: slots::SLOTS,
    methods: &[ENVMAP_INFO, PROXY_SPHERE_INFO, PROXY_BOX_INFO, PROXY_RELIEF_INFO, IMAGE_BASED_INFO],
    plan_stages: Some(relief::plan_sources),
    plan_views: Some(captures::plan_captures),
    views: Some(|p| captures::view_blocks(p).into_iter().chain(relief::view_blocks(p)).collect()),
    frame_part: Some(frame_part),
    push_words: Some(|q, layout, w| {
        captures::push_words(q, layout, w);
        relief::push_words(q, layout, w);
    }),
    describe: Some(captures::describe),
    cubes_compose: &[ENVMAP, PROXY_SPHERE, PROXY_BOX],
    // Captures and height maps are drawn after the inter-object cycles, from their last maps.
    shows_others_by_maps: &[IMAGE_BASED, PROXY_RELIEF],
    ..crate::methods::registry::Family::NONE
};

/// The family's part of a frame: the captures' cube views and the relief maps' orthographic
/// ones.
struct EnvmapViews;

impl crate::frame::stage::FramePart for EnvmapViews {
    fn write_views(&mut self, fr: &crate::frame::stage::ViewFrame, table: &mut [crate::gpu_scene::GpuView]) {
        captures::write_views(fr, table);
        relief::write_views(fr, table);
    }

    fn destroy(&mut self, _ctx: &crate::vk::Context) {}
}

fn frame_part(
    init: &crate::frame::stage::StageInit,
    _: &mut crate::frame::stage::Maps,
) -> crate::Result<Option<Box<dyn crate::frame::stage::FramePart>>> {
    let any = !init.plan.captures.is_empty() || !relief::objects(init.plan).is_empty();
    Ok(any.then(|| Box::new(EnvmapViews) as Box<dyn crate::frame::stage::FramePart>))
}

pub const ENVMAP_INFO: &MethodInfo = &MethodInfo {
    name: "envmap",
    abi: 0,
    section: "§3, §3.1",
    family: "envmap",
    summary: "classic environment mapping: one cube map per specular object, rasterised from its reference point without the object; looked up in the reflected / refracted direction, weighted by Fresnel",
    serves: EVERY_CLASS,
    knobs: KNOBS,
    gpu: Some(spec(SHADE)),
    fallback: None,
    shape: crate::methods::registry::Shape::Any,
    needs: crate::methods::registry::DeviceNeeds::Nothing,
};
pub const ENVMAP: Method = Method(ENVMAP_INFO.name);

pub const PROXY_SPHERE_INFO: &MethodInfo = &MethodInfo {
    name: "proxy-sphere",
    abi: 1,
    section: "§3.2",
    family: "envmap",
    summary: "localised environment mapping: the ray is intersected with a sphere around the reference point (`proxy_radius`) and the cube map looked up towards the hit",
    serves: EVERY_CLASS,
    knobs: &[CubeKnobs::cube_size, CubeKnobs::cube_precision, CubeKnobs::cube_mode, FrameKnobs::fresnel, CubeKnobs::ref_point, EnvmapKnobs::proxy_radius],
    gpu: Some(spec(proxy(0))),
    fallback: None,
    shape: crate::methods::registry::Shape::Any,
    needs: crate::methods::registry::DeviceNeeds::Nothing,
};
pub const PROXY_SPHERE: Method = Method(PROXY_SPHERE_INFO.name);

pub const PROXY_BOX_INFO: &MethodInfo = &MethodInfo {
    name: "proxy-box",
    abi: 2,
    section: "§3.2",
    family: "envmap",
    summary: "the same with the scene's bounding box as proxy (what engines call a parallax-corrected cube map)",
    serves: EVERY_CLASS,
    knobs: KNOBS,
    gpu: Some(spec(proxy(FLAG_PROXY_BOX))),
    fallback: None,
    shape: crate::methods::registry::Shape::Any,
    needs: crate::methods::registry::DeviceNeeds::Nothing,
};
pub const PROXY_BOX: Method = Method(PROXY_BOX_INFO.name);

const RELIEF_SHADE: CameraPass = CameraPass {
    name: "proxy-relief.shade",
    vertex: "scene/mesh.vert",
    fragment: "envmap/relief.frag",
    flags: 0,
    order: order::CAMERA,
    create: None,
    profiled: Profiled::OWN,
};

pub const PROXY_RELIEF_INFO: &MethodInfo = &MethodInfo {
    name: "proxy-relief",
    abi: 20,
    section: "§3.2",
    family: "envmap",
    summary: "displacement-mapped proxies (PMDS06): the scene's box as six rectangles displaced by height maps (what stands in front of each face, rasterised from the object's far side: radiance and depth); the ray is marched through the height maps of the faces it moves towards (relief_steps, then halvings), on past a silhouette's hidden space, and the nearest hit that is not a height map's cliff is shaded",
    serves: EVERY_CLASS,
    knobs: &[
        EnvmapKnobs::relief_size, EnvmapKnobs::relief_steps, EnvmapKnobs::relief_source, CubeKnobs::cube_precision, FrameKnobs::fresnel, CubeKnobs::cube_size, CubeKnobs::ref_point, SearchKnobs::linear_steps, SearchKnobs::secant_steps, SearchKnobs::binary_steps, SearchKnobs::parallax_iterations, SearchKnobs::search_tolerance,
    ],
    gpu: Some(spec_with(&[relief::RELIEF_MAPS], RELIEF_SHADE)),
    fallback: None,
    shape: crate::methods::registry::Shape::Any,
    needs: crate::methods::registry::DeviceNeeds::Nothing,
};
pub const PROXY_RELIEF: Method = Method(PROXY_RELIEF_INFO.name);

const CAPTURES_SHADE: CameraPass = CameraPass {
    name: "image-based.shade",
    vertex: "scene/mesh.vert",
    fragment: "envmap/captures.frag",
    flags: 0,
    order: order::CAMERA,
    create: None,
    profiled: Profiled::OWN,
};

pub const IMAGE_BASED_INFO: &MethodInfo = &MethodInfo {
    name: "image-based",
    abi: 19,
    section: "§3.3",
    family: "envmap",
    summary: "image-based reflections: captures³ cube maps (radiance and distance) on a lattice over the object's box (or the scene's: fixed probes); a ray takes the captures at its lattice cell's corners, each warped by its distances (the ray searched in it, §4.1; hits it does not hold or beyond the nearest left out) or blended parallax-corrected (capture_warp=blend)",
    serves: EVERY_CLASS,
    knobs: &[
        EnvmapKnobs::captures, EnvmapKnobs::capture_box, EnvmapKnobs::capture_warp, CubeKnobs::cube_size, CubeKnobs::cube_precision, CubeKnobs::cube_mode, FrameKnobs::fresnel, SearchKnobs::linear_steps, SearchKnobs::secant_steps, SearchKnobs::binary_steps, SearchKnobs::parallax_iterations, SearchKnobs::search_tolerance,
    ],
    gpu: Some(spec_with(&[captures::CAPTURE_CUBES], CAPTURES_SHADE)),
    fallback: None,
    shape: crate::methods::registry::Shape::Any,
    needs: crate::methods::registry::DeviceNeeds::Nothing,
};
pub const IMAGE_BASED: Method = Method(IMAGE_BASED_INFO.name);
