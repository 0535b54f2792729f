//! Displacement-mapped proxies (survey §3.2, PMDS06): localised environment mapping whose
//! proxy is not the scene's box itself but its six faces as rectangles displaced by height
//! maps: for face f, what stands in front of it, rasterised orthographically from the
//! opposite face along f's direction (radiance, and the depth from that opposite face). The
//! camera pass (`glsl/envmap/relief.frag`) marches each reflected or refracted ray through
//! the height maps of the (at most three) faces it moves towards, and the nearest hit that
//! is not a cliff of its height map (the side of something, which a height map stretches
//! over a texel) gives the radiance. The object is left out of its own maps.
//!
//! What a box proxy (`proxy-box`, what engines call a parallax-corrected probe) becomes with
//! depth: a room's contents in front of its walls, seen from every side, so that parts
//! hidden from any one reference point (the far side of a box on the floor) are held. The
//! height maps are rasterised, not sampled from a distance map: sampled from one reference
//! point, they would hold only what that point sees, which is what the distance maps (§4)
//! already search.

use glam::{Mat4, Vec3, Vec4};

use crate::frame::stage::{order, LayerField, MapInfo, ViewFrame};
use crate::plan::types::Plan;
use crate::quality::Quality;

/// The view block of every relief object's six orthographic views, in layer order.
pub const VIEWS: &str = "envmap.relief";

/// `envmap.relief`: per object six height maps `relief_size`², RGBA (radiance, depth).
pub const RELIEF_MAPS: MapInfo = MapInfo {
    name: "envmap.relief",
    order: order::ENVIRONMENT_MAPS,
    cube: false,
    layer_field: Some(LayerField::Envmap),
    create: crate::methods::cube_maps::create_relief,
    bytes: |p, objects, _| {
        let s = p.quality.envmap.relief_size as u64;
        6 * s * s * crate::frame::stage::cube_texel_bytes(&p.quality) * objects as u64
    },
    describe: |q, _| {
        format!(
            "six height maps {}² (one per face of the scene's box: radiance and depth, {})",
            q.envmap.relief_size,
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

/// Margin inside the box where the orthographic views start (a fraction of its diagonal):
/// the opposite face's wall, on the box's side, lies before the near plane and is clipped;
/// face f's lies inside the depth range.
const MARGIN: f32 = 1e-3;

/// Face f's view over box (lo, hi): looking along the cube face's major axis c from just
/// inside the opposite face, the screen axes the cube face's (s, t), reversed depth (1 at
/// the eye's plane, 0 a margin beyond face f). Returns (world → clip, eye, direction).
pub fn face_view(f: usize, (lo, hi): (Vec3, Vec3)) -> (Mat4, Vec3, Vec3) {
    let [a, b, c] = crate::cube::FACE_AXES[f];
    let (centre, half) = ((lo + hi) * 0.5, ((hi - lo) * 0.5).max(Vec3::splat(1e-6)));
    let margin = MARGIN * (hi - lo).length().max(1e-6);
    let extent = |axis: Vec3| axis.abs().dot(half);
    // Inside the opposite face by the margin: that face's own wall is clipped away.
    let eye = centre - c * (extent(c) - margin);
    let far = 2.0 * extent(c);
    let (hw, hh) = (extent(a), extent(b));
    let rows = [
        (a / hw).extend(-a.dot(eye) / hw),
        (b / hh).extend(-b.dot(eye) / hh),
        (-c / far).extend(1.0 + c.dot(eye) / far),
        Vec4::new(0.0, 0.0, 0.0, 1.0),
    ];
    (Mat4::from_cols(rows[0], rows[1], rows[2], rows[3]).transpose(), eye, c)
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

/// Writes the relief objects' views: eye.w 1 (planar depth along dir.xyz).
pub fn write_views(fr: &ViewFrame, table: &mut [crate::gpu_scene::GpuView]) {
    let Some(mut v) = fr.layout.first(VIEWS) else { return };
    for _ in objects(fr.plan) {
        for f in 0..6 {
            let (vp, eye, dir) = face_view(f, fr.plan.proxy_box);
            table[v as usize] = crate::frame::views::view(vp, eye.extend(1.0), dir.extend(0.0));
            v += 1;
        }
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
            let (vp, eye, c) = face_view(f, (lo, hi));
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
}
