//! Displacement-mapped proxies (survey §3.2, PMDS06): localised environment mapping whose
//! proxy is not the scene's box itself but its six faces as rectangles displaced by height
//! maps: for face f, what stands in front of it, rasterised orthographically from the
//! opposite face along f's direction (radiance, and the depth from that opposite face). The
//! camera pass (`glsl/envmap/relief.frag`) marches each reflected or refracted ray through
//! the height maps of the (at most three) faces it moves towards, and the nearest hit that
//! is not a cliff of its height map (the side of something, which a height map stretches
//! over a texel) gives the radiance. The object is left out of its own maps, and each of
//! its maps starts at the object's own side away from the face (PMDS06's impostors are the
//! scene seen from the reflector): a ray from the object towards face f never meets what
//! lies behind that plane, and a height map that held it (a ball between the object and
//! the opposite wall) would hide from the object's rays everything in front of face f
//! behind it — they would start "behind the map's surface" and see the sky.
//!
//! What a box proxy (`proxy-box`, what engines call a parallax-corrected probe) becomes with
//! depth: a room's contents in front of its walls, seen from every side, so that parts
//! hidden from any one reference point (the far side of a box on the floor) are held.
//! The height maps are rasterised (`relief_source=raster`, the default) or, as PMDS06 and the
//! survey put it, sampled from the object's distance map (`relief_source=distance`: per texel
//! the distance-map search along the face's direction, `ReliefSampled`): then they hold only
//! what the object's reference point sees, as the distance map does (BENCHMARKS.md compares
//! the two).

use ash::vk;
use glam::{Mat4, Vec3, Vec4};

use crate::frame::stage::{order, FrameIo, LayerField, MapInfo, Maps, Stage, StageInit, ViewFrame};
use crate::frame::{destroy_pipelines, FrameInputs};
use crate::plan::types::{Plan, PlanStages};
use crate::quality::{Quality, ReliefSource};
use crate::vk::pipeline::{graphics_pipeline, GraphicsDesc, Multisample, VertexInput};
use crate::vk::{begin_rendering, build, Access, Context, Image, ImageDesc, ImageKind, Owner, Recorder, Target};
use crate::Result;

/// The view block of every relief object's six orthographic views, in layer order.
pub const VIEWS: &str = "envmap.relief";

/// `envmap.relief`: per object six height maps `relief_size`², RGBA (radiance, depth); after
/// the distance maps, which `relief_source=distance` samples.
pub const RELIEF_MAPS: MapInfo = MapInfo {
    name: "envmap.relief",
    order: order::ENVIRONMENT_MAPS + 1,
    cube: false,
    layer_field: Some(LayerField::Envmap),
    create,
    bytes: |p, objects, _| {
        let s = p.quality.envmap.relief_size as u64;
        6 * s * s * crate::frame::stage::cube_texel_bytes(&p.quality) * objects as u64
    },
    texels: |q, _, _| 6.0 * (q.envmap.relief_size as f64).powi(2),
    describe: |q, _| {
        format!(
            "six height maps {}² (one per face of the scene's box: radiance and depth, {}, {})",
            q.envmap.relief_size,
            match q.envmap.relief_source {
                ReliefSource::Raster => "rasterised",
                ReliefSource::Distance => "sampled from its distance map",
            },
            match q.cube.cube_precision {
                crate::quality::Precision::Half => "RGBA16F",
                crate::quality::Precision::Single => "RGBA32F",
            }
        )
    },
    shared: false,
};

/// The objects with height maps, in layer order.
pub fn objects(p: &Plan) -> Vec<usize> {
    let mut layered: Vec<(u32, usize)> =
        p.objects.iter().filter_map(|o| o.maps.iter().find(|m| m.pass == RELIEF_MAPS.name).map(|m| (m.layer, o.mesh))).collect();
    layered.sort_unstable();
    layered.into_iter().map(|(_, m)| m).collect()
}

/// A margin, as a fraction of the box's diagonal: the views' eye lies this far inside the
/// opposite face (whose own wall is clipped), their near plane this far past the object's
/// side (a surface it rests on is clipped, not left to rounding), and depth 0 this far
/// beyond face f (whose wall lies inside the depth range).
const MARGIN: f32 = 1e-3;

/// Face f's view over box (lo, hi): looking along the cube face's major axis c, the screen
/// axes the cube face's (s, t). Its eye (from which the maps' depths are measured) lies just
/// inside the opposite face; its near plane (reversed depth 1) a margin past `start` along c
/// (the object's side away from face f, [`starts`]; `None` or anything before the eye: the
/// eye's plane), depth 0 a margin beyond face f. Returns (world → clip, eye, direction).
pub fn face_view(f: usize, (lo, hi): (Vec3, Vec3), start: Option<f32>) -> (Mat4, Vec3, Vec3) {
    let [a, b, c] = crate::cube::FACE_AXES[f];
    let (centre, half) = ((lo + hi) * 0.5, ((hi - lo) * 0.5).max(Vec3::splat(1e-6)));
    let margin = MARGIN * (hi - lo).length().max(1e-6);
    let extent = |axis: Vec3| axis.abs().dot(half);
    // Just inside the opposite face: that face's own wall clipped away.
    let eye = centre - c * (extent(c) - margin);
    let (first, end) = (c.dot(eye), c.dot(centre) + extent(c) + margin);
    let near = start.map_or(first, |s| s + margin).clamp(first, end - 2.0 * margin);
    let depth = end - near;
    let (hw, hh) = (extent(a), extent(b));
    let rows = [
        (a / hw).extend(-a.dot(eye) / hw),
        (b / hh).extend(-b.dot(eye) / hh),
        (-c / depth).extend(end / depth),
        Vec4::new(0.0, 0.0, 0.0, 1.0),
    ];
    (Mat4::from_cols(rows[0], rows[1], rows[2], rows[3]).transpose(), eye, c)
}

/// Per face f, where object `mesh`'s height maps start along f's axis c (c·x of its box's
/// side away from face f): a ray from the object towards face f never meets what lies
/// behind that plane, and a map that held it (a ball between the object and the opposite
/// wall) would hide from the object's rays what stands before face f behind it.
pub fn starts(scene: &crate::scene::Scene, mesh: usize) -> [f32; 6] {
    let b = scene.meshes.get(mesh).map(|m| m.bounds());
    std::array::from_fn(|f| {
        let c = crate::cube::FACE_AXES[f][2];
        b.map_or(f32::NEG_INFINITY, |b| c.dot(b.min).min(c.dot(b.max)))
    })
}

/// Whether a mesh other than `own` (drawn in its maps) has a triangle that face f's view
/// sees (not edge-on along its axis c) reaching between the planes c·x = `s0` and `s1`:
/// moving the start of that face's map between them changes what it holds.
pub fn holds_between(scene: &crate::scene::Scene, own: usize, f: usize, s0: f32, s1: f32) -> bool {
    let c = crate::cube::FACE_AXES[f][2];
    let (lo, hi) = (s0.min(s1), s0.max(s1));
    if hi - lo <= 0.0 {
        return false;
    }
    scene.meshes.iter().enumerate().filter(|(m, mesh)| *m != own && !mesh.hidden).any(|(_, mesh)| {
        let b = mesh.bounds();
        let (a, z) = (c.dot(b.min).min(c.dot(b.max)), c.dot(b.min).max(c.dot(b.max)));
        a < hi
            && z > lo
            && mesh.indices.chunks_exact(3).any(|t| {
                let [p, q, r] = [0, 1, 2].map(|i| mesh.positions[t[i] as usize]);
                let (ta, tz) = (c.dot(p).min(c.dot(q)).min(c.dot(r)), c.dot(p).max(c.dot(q)).max(c.dot(r)));
                let area = (q - p).cross(r - p);
                ta < hi && tz > lo && area.dot(c).abs() > 1e-6 * area.length()
            })
    })
}

/// The view block's size: six views per relief object.
pub fn view_blocks(p: &Plan) -> Vec<(&'static str, u32)> {
    let n = objects(p).len() as u32;
    if n == 0 {
        Vec::new()
    } else {
        vec![(VIEWS, 6 * n)]
    }
}

/// Writes the relief objects' views (each from the object's own box, as it is this frame):
/// eye.w 1 (planar depth along dir.xyz); dir.w the object's layer in the distance maps
/// (`relief_source=distance`), else 0.
pub fn write_views(fr: &ViewFrame, table: &mut [crate::gpu_scene::GpuView]) {
    let Some(mut v) = fr.layout.first(VIEWS) else { return };
    for mesh in objects(fr.plan) {
        let layer = distance_layer(fr.plan, mesh).unwrap_or(0);
        let from = starts(fr.scene, mesh);
        for (f, &start) in from.iter().enumerate() {
            let (vp, eye, dir) = face_view(f, fr.plan.proxy_box, Some(start));
            table[v as usize] = crate::frame::views::view(vp, eye.extend(1.0), dir.extend(layer as f32));
            v += 1;
        }
    }
}

/// Object `mesh`'s layer in the distance maps, if it has one.
fn distance_layer(p: &Plan, mesh: usize) -> Option<u32> {
    p.object(mesh)?.maps.iter().find(|m| m.pass == crate::methods::distance::DISTANCE_CUBES.name).map(|m| m.layer)
}

/// The family's `plan_stages` part: with `relief_source=distance` every proxy-relief object
/// gets a distance map of its own to sample (its layer not the object's `envmap_layer`, which
/// stays its height maps').
pub fn plan_sources(_: &crate::scene::Scene, p: &mut Plan, st: &mut PlanStages) {
    if p.quality.envmap.relief_source != ReliefSource::Distance {
        return;
    }
    let what = crate::frame::stage::describe_cube(&p.quality) + " with distance, which its height maps sample";
    for o in p.objects.iter_mut().filter(|o| o.method == super::PROXY_RELIEF) {
        let kind = crate::plan::types::MapKind { layer_field: None, ..crate::methods::distance::DISTANCE_CUBES.kind() };
        st.add_map(o, kind, what.clone());
    }
}

/// `envmap.relief`'s constructor: rasterised (`cube_maps::CubeMaps`) or sampled.
fn create(init: &StageInit, objects: &[usize], maps: &mut Maps) -> Result<Box<dyn Stage>> {
    match init.plan.quality.envmap.relief_source {
        ReliefSource::Raster => {
            crate::methods::cube_maps::with_views(init, objects, maps, crate::methods::cube_maps::MapKind::Relief, VIEWS)
        }
        ReliefSource::Distance => Ok(Box::new(ReliefSampled::new(init, objects, maps)?)),
    }
}

/// `relief_source=distance`: the height maps sampled from the objects' distance maps, one
/// full-screen draw per layer (`glsl/envmap/relief_sample.frag`), drawn again whenever
/// anything the distance maps hold changed.
pub struct ReliefSampled {
    objects: Vec<usize>,
    pipeline: vk::Pipeline,
    dirty: bool,
    /// `map_updates=always`: every frame.
    always: bool,
}

impl ReliefSampled {
    fn new(init: &StageInit, objects: &[usize], maps: &mut Maps) -> Result<ReliefSampled> {
        let (ctx, q) = (init.ctx, &init.plan.quality);
        let me =
            ReliefSampled { objects: objects.to_vec(), pipeline: vk::Pipeline::null(), dirty: true, always: q.frame.map_updates_always };
        build(ctx, me, |me| {
            let format = crate::methods::cube_maps::radiance_format(q.cube.cube_precision);
            let usage = vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::TRANSFER_SRC;
            let size = q.envmap.relief_size;
            let kind = ImageKind::D2Array { layers: 6 * me.objects.len() as u32 };
            maps.push_image(
                &super::slots::RELIEF,
                Image::new(ctx, &ImageDesc { name: "envmap.relief", format, width: size, height: size, kind, usage })?,
            );
            me.pipeline = graphics_pipeline(
                ctx,
                init.layout,
                &GraphicsDesc {
                    name: "envmap.relief.sample",
                    vertex: "scene/sky.vert",
                    fragment: "envmap/relief_sample.frag",
                    vertex_input: VertexInput::None,
                    color_formats: &[format],
                    depth_format: None,
                    depth_test: false,
                    depth_write: false,
                    view_mask: 0,
                    cull: vk::CullModeFlags::NONE,
                    multisample: Multisample::OFF,
                    blend: crate::vk::pipeline::Blend::Replace,
                    depth_op: crate::vk::pipeline::DepthOp::Nearer,
                },
            )?;
            Ok(())
        })
    }
}

impl Stage for ReliefSampled {
    fn name(&self) -> &'static str {
        "envmap.relief"
    }

    fn update(&mut self, _: &StageInit, changes: &crate::scene::update::Changes, _: &mut Maps) -> Result<()> {
        self.dirty |= !changes.moved.is_empty() || !changes.materials.is_empty() || !changes.lights.is_empty();
        Ok(())
    }

    fn redraw(&self) -> Option<(u32, u32)> {
        let all = 6 * self.objects.len() as u32;
        Some((if self.dirty || self.always { all } else { 0 }, all))
    }

    fn record(&mut self, rec: &mut Recorder, f: &FrameInputs, io: &mut FrameIo) {
        let Some(mut image) = io.maps.take_images(&super::slots::RELIEF).into_iter().next() else { return };
        let distance = io.maps.image(&crate::methods::distance::slots::DISTANCE);
        let mut pass = rec.pass("envmap.relief").writes(&mut image, Access::ColorAttachment);
        for img in io.scene_images.iter().copied().chain(distance) {
            pass = pass.reads(img, Access::FragmentSampled);
        }
        let open = pass.begin();
        let (ctx, cmd) = (rec.ctx, rec.cmd);
        let sets = io.sets.camera.get(io.maps.latest).copied().unwrap_or(io.sets.empty);
        let base = io.views.first(VIEWS).unwrap_or(0);
        for (k, &mesh) in self.objects.iter().enumerate() {
            for face in 0..6u32 {
                let layer = 6 * k as u32 + face;
                let colors = [image.layer_view(layer)];
                let target = Target {
                    color: &colors,
                    depth: None,
                    width: image.width,
                    height: image.height,
                    view_mask: 0,
                    layer_count: 1,
                    clear_color: [0.0, 0.0, 0.0, 1e30],
                    clear: true,
                };
                begin_rendering(ctx, cmd, &target);
                f.bind(ctx, cmd, self.pipeline);
                f.bind_maps(ctx, cmd, sets);
                f.push(ctx, cmd, base + layer, mesh as u32);
                unsafe {
                    ctx.device.cmd_draw(cmd, 3, 1, 0, 0);
                    ctx.device.cmd_end_rendering(cmd);
                }
            }
        }
        rec.end(open);
        io.maps.set_images(&super::slots::RELIEF, vec![image]);
        self.dirty = false;
    }

    fn destroy(&mut self, ctx: &Context) {
        destroy_pipelines(ctx, &mut [self.pipeline]);
        self.pipeline = vk::Pipeline::null();
    }
}

impl Owner for ReliefSampled {
    fn destroy(&mut self, ctx: &Context) {
        Stage::destroy(self, ctx)
    }
}

/// Its words: where its views start, the march's steps.
pub fn push_words(q: &Quality, layout: &crate::frame::stage::ViewLayout, w: &mut crate::frame::words::PushWords) {
    use crate::frame::layout::{RELIEF_STEPS, RELIEF_VIEW_BASE};
    w.set(RELIEF_VIEW_BASE, layout.first(VIEWS).unwrap_or(0));
    w.set(RELIEF_STEPS, q.envmap.relief_steps.max(1));
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each face's view maps the box's cross-section onto the whole image, the opposite
    /// face to depth 1 and face f to depth 0 (reversed), with the cube face's screen axes.
    #[test]
    fn face_views_cover_the_box_from_the_opposite_face() {
        let (lo, hi) = (Vec3::new(-1.0, 0.0, -2.0), Vec3::new(3.0, 2.0, 2.0));
        let pick = |v: Vec3| {
            Vec3::new(if v.x > 0.0 { hi.x } else { lo.x }, if v.y > 0.0 { hi.y } else { lo.y }, if v.z > 0.0 { hi.z } else { lo.z })
        };
        for f in 0..6 {
            let (vp, eye, c) = face_view(f, (lo, hi), None);
            let [a, b, _] = crate::cube::FACE_AXES[f];
            // The box corner where a·p and b·p are largest: clip (1, 1); smallest: (−1, −1).
            let (top, bottom) = (vp * pick(a + b).extend(1.0), vp * pick(-(a + b)).extend(1.0));
            assert!((top.x - 1.0).abs() < 1e-5 && (top.y - 1.0).abs() < 1e-5, "face {f}: {top}");
            assert!((bottom.x + 1.0).abs() < 1e-5 && (bottom.y + 1.0).abs() < 1e-5, "face {f}: {bottom}");
            assert!(((vp * eye.extend(1.0)).z - 1.0).abs() < 1e-6, "face {f}: the eye's plane at depth 1");
            // Face f's plane (the box's side along c) lies just before depth 0.
            let on_f = (lo + hi) * 0.5 + c * (c.abs().dot(hi - lo) * 0.5);
            let z = (vp * on_f.extend(1.0)).z;
            assert!(z > 0.0 && z < 0.01, "face {f}: {z}");
            assert!(c.dot(on_f - eye) > 0.0);
        }
    }

    /// A view from an object's box starts at the object's side away from face f (what lies
    /// behind it is clipped), its eye where the box's views' eye is (the maps' depths keep
    /// their meaning), face f still at depth just above 0; a start outside the box is
    /// clamped into it.
    #[test]
    fn face_views_start_at_the_objects_back() {
        let (lo, hi) = (Vec3::new(-2.0, 0.0, -2.0), Vec3::new(2.0, 3.0, 2.0));
        let mut scene = crate::scene::Scene::new();
        let m = scene.add_material(crate::scene::Material::default()).unwrap();
        let ball = scene.add_mesh(crate::scene::shapes::uv_sphere("ball", Vec3::new(1.0, 1.0, 0.0), 0.5, 8, 4, m)).unwrap();
        let from = starts(&scene, ball);
        for (f, &start) in from.iter().enumerate() {
            let (vp, eye, c) = face_view(f, (lo, hi), Some(start));
            let (_, box_eye, _) = face_view(f, (lo, hi), None);
            assert!((eye - box_eye).length() < 1e-6, "face {f}");
            let back = Vec3::new(1.0, 1.0, 0.0) - c * 0.5;
            let z = (vp * back.extend(1.0)).z;
            assert!(z > 1.0 && z < 1.01, "face {f}: the ball's back just before the near plane (clipped): {z}");
            let on_f = (lo + hi) * 0.5 + c * (c.abs().dot(hi - lo) * 0.5);
            let z = (vp * on_f.extend(1.0)).z;
            assert!(z > 0.0 && z < 0.01, "face {f}: {z}");
            assert!((vp * (back - c * 0.1).extend(1.0)).z > 1.0, "face {f}: behind the ball clipped");
        }
        for (f, s) in [(0, 100.0), (1, -100.0)] {
            let (vp, eye, c) = face_view(f, (lo, hi), Some(s));
            let z = |x: f32| (vp * (eye + c * x).extend(1.0)).z;
            assert!(z(0.0) >= 1.0 - 1e-5 && z(3.99) > 0.0 && z(4.01) < 0.0 + 1e-2, "face {f}: {} {} {}", z(0.0), z(3.99), z(4.01));
        }
        // Moving the ball's start across the room's empty middle changes no map; across
        // another ball it does, but not along an axis that sees that ball edge-on.
        assert!(!holds_between(&scene, ball, 0, -1.0, 0.0));
        let other = scene.add_mesh(crate::scene::shapes::uv_sphere("other", Vec3::new(-0.5, 1.0, 0.0), 0.2, 8, 4, m)).unwrap();
        assert!(holds_between(&scene, ball, 0, -1.0, 0.0) && holds_between(&scene, ball, 1, 1.0, 0.0));
        assert!(!holds_between(&scene, other, 0, -1.0, 0.0) && !holds_between(&scene, ball, 1, -1.0, 0.0));
        // A floor-like quad at y 0.5 over x −1…0: edge-on along x, seen along y.
        let quad = crate::scene::Mesh {
            indices: vec![0, 1, 2],
            positions: vec![Vec3::new(-1.0, 0.5, -1.0), Vec3::new(0.0, 0.5, -1.0), Vec3::new(-0.5, 0.5, 1.0)],
            ..Default::default()
        };
        let mut flat = crate::scene::Scene::new();
        flat.meshes.push(quad);
        assert!(!holds_between(&flat, 9, 0, -1.0, 0.0) && holds_between(&flat, 9, 2, 0.0, 1.0));
    }
}
