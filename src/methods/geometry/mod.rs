//! Geometry transformation (survey §5). Planar reflectors are exact: the scene is rendered
//! again from the camera mirrored through the reflector's plane (DB97, MBGN00), clipped at
//! that plane by an oblique near plane, and the image is laid onto the mirror's pixels with
//! its Fresnel weight (`geometry.mirror`). Mirrors seen in mirrors recurse: every mirrored
//! view is a camera view of its own, in which every camera pass of the frame draws its
//! objects (`mirror::MirrorViews` plans the views of a frame; the renderer records them
//! before the camera's own view, deepest first). Curved reflectors (EMD*05, EMDT06) move the
//! environment's vertices to their virtual positions instead (`curved`).

pub mod curved;
pub mod faces;
pub mod knobs;
pub mod mirror;
pub mod views;

pub use curved::CURVED_REFLECTOR;

use crate::frame::stage::order;
use crate::methods::registry::{CameraPass, GpuSpec, LeavesOut, MapShading, Method, MethodInfo, ObjectClass, Shape, Verdict};
use crate::quality::Quality;
use crate::quality::{FrameKnobs, GeometryKnobs};

const fn one(_: &Quality) -> u32 {
    1
}

/// `geometry.mirror`: each planar mirror drawn from the camera (and from every mirrored view
/// that sees it) with the mirrored view's image at its pixels, weighted by Fresnel.
pub const MIRROR_PASS: CameraPass = CameraPass {
    name: "geometry.mirror",
    vertex: "scene/mesh.vert",
    fragment: "geometry/mirror.frag",
    flags: 0,
    order: order::CAMERA,
    create: None,
};

pub const PLANAR_MIRROR: Method = Method(&MethodInfo {
    name: "planar-mirror",
    abi: 12,
    section: "§5",
    family: "geometry",
    summary: "planar reflectors by geometry transformation: the scene rendered again from the camera mirrored through the mirror's plane (oblique near plane at the mirror), laid onto the mirror's pixels with its Fresnel weight; mirrors in mirrors recurse up to depth, at most mirror_budget views a frame",
    serves: &[ObjectClass::Mirror],
    knobs: &[FrameKnobs::depth, GeometryKnobs::mirror_budget, GeometryKnobs::map_mirrors, FrameKnobs::fresnel],
    gpu: Some(GpuSpec { maps: &[], camera: MIRROR_PASS, map_shading: MapShading::Sky, leaves_out: LeavesOut::Itself, cycles: one }),
    fallback: Some(crate::methods::DISTANCE),
    shape: Shape::Planar,
    rule: |f, _| {
        f.planar.then(|| Verdict {
            score: 5.0,
            reason: "planar reflector: exact by rendering the mirrored camera's view (§5, Table 1: exact, multiple reflections)".into(),
        })
    },
});

/// `geometry.refract`: each flat-faced dielectric (and thin pane) drawn from the camera (and
/// from every view that sees it) with its faces' reflected and refracted views at their
/// pixels, split by the pixel's own Fresnel weights.
pub const REFRACT_PASS: CameraPass = CameraPass {
    name: "geometry.refract",
    vertex: "scene/mesh.vert",
    fragment: "geometry/refract.frag",
    flags: 0,
    order: order::CAMERA,
    create: None,
};

pub const PLANAR_REFRACTION: Method = Method(&MethodInfo {
    name: "planar-refraction",
    abi: 14,
    section: "§5",
    family: "geometry",
    summary: "flat-faced dielectrics (slabs, prisms, gems; convex) and thin panes by geometry transformation: per face seen, the scene rendered through it by the linearised refraction of the eye ray (GS04: an affine map per face, exact on the face's central ray; exact for thin panes) and reflected in it (exact), recursing through internal reflections to the exit faces up to depth, at most mirror_budget views a frame, with the pixel's own Fresnel split",
    serves: &[ObjectClass::SolidDielectric, ObjectClass::ThinDielectric],
    knobs: &[FrameKnobs::depth, GeometryKnobs::mirror_budget, FrameKnobs::fresnel],
    gpu: Some(GpuSpec { maps: &[], camera: REFRACT_PASS, map_shading: MapShading::Sky, leaves_out: LeavesOut::Itself, cycles: one }),
    fallback: Some(crate::methods::DISTANCE),
    shape: Shape::Faceted,
    rule: |f, _| {
        // A solid's linearisation and its deep internal paths lose to refractor maps and ray
        // tracing on the measured scenes (BENCHMARKS.md): only the pane, exact, is taken.
        (f.class == ObjectClass::ThinDielectric && f.planar).then(|| Verdict {
            score: 5.0,
            reason: "planar thin pane: exact by its reflected and transmitted views (§5; two views, tests/geometry.rs: 154 dB)".into(),
        })
    },
});
