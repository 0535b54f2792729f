//! Image-based reflections (survey §3.3): an object's reflected and refracted rays are
//! reconstructed from several cube maps captured at different points around it, radiance and
//! the distance of what each capture sees (the distance maps' texels, §4), instead of one map
//! at its reference point. The captures lie on a lattice of `captures`³ cell centres over the
//! object's box (moving with it) or the scene's (`capture_box=room`: fixed in the world,
//! redrawn only when something they see changes, as engines' reflection probes). A ray from
//! shaded point x takes the captures at the corners of x's lattice cell with trilinear
//! weights and either warps each by its distances (`capture_warp=depth`: the ray searched in
//! each capture's distance map as in §4.1, the hits a capture does not hold or that lie beyond
//! the nearest any capture holds left out) or blends their parallax-corrected lookups
//! (`capture_warp=blend`: the proxy is the scene's box, §3.2).
//!
//! Here: where the captures lie (`plan_captures`, the family's `plan_views` hook), their
//! views (`write_views`), the map (`CAPTURE_CUBES`, drawn by `cube_maps::CubeMaps`) and the
//! words that tell the camera pass where to find them.

use glam::Vec3;

use crate::frame::stage::{cube_texel_bytes, describe_cube, order, LayerField, MapInfo, Maps, Stage, StageInit, ViewFrame, ViewLayout};
use crate::plan::types::{CaptureSet, Plan};
use crate::quality::{CaptureBox, CaptureWarp, Quality};
use crate::scene::Scene;

/// The view block of every object's captures: six faces per capture, objects in layer
/// order, captures in lattice order (`CaptureSet::centres`).
pub const VIEWS: &str = "envmap.captures";

/// `envmap.captures`: per object `captures`³ cube maps, radiance and distance (the distance
/// maps' shaders, §4), the object left out; after the distance maps, whose last cycle shows
/// the other specular objects in them where the plan composes (`cube_maps::CubeMaps`).
pub const CAPTURE_CUBES: MapInfo = MapInfo {
    name: "envmap.captures",
    order: order::ENVIRONMENT_MAPS + 1,
    cube: true,
    layer_field: Some(LayerField::Envmap),
    create: create_captures,
    bytes: |p, objects, _| {
        let s = p.quality.cube.cube_size as u64;
        6 * s * s * cube_texel_bytes(&p.quality) * objects as u64 * per_object(&p.quality) as u64
    },
    texels: |q, l, size| crate::frame::stage::cube_texels(q, l, size) * per_object(q) as f64,
    describe: |q, _| {
        format!(
            "{} captures ({} per axis, in the {}'s box), each a {} with distance",
            per_object(q),
            q.envmap.captures,
            match q.envmap.capture_box {
                CaptureBox::Object => "object",
                CaptureBox::Room => "scene",
            },
            describe_cube(q)
        )
    },
    shared: false,
};

/// `envmap.captures`' constructor: the cube-map pass over each object's `captures`³ layers in
/// a row, their views this block's.
fn create_captures(init: &StageInit, objects: &[usize], maps: &mut Maps) -> crate::Result<Box<dyn Stage>> {
    let k = per_object(&init.plan.quality) as usize;
    let layers: Vec<usize> = objects.iter().flat_map(|&m| std::iter::repeat_n(m, k)).collect();
    crate::methods::cube_maps::with_views(init, &layers, maps, crate::methods::cube_maps::MapKind::Captures, VIEWS)
}

/// Captures per object: `captures`³.
pub fn per_object(q: &Quality) -> u32 {
    q.envmap.captures.pow(3)
}

/// The nominal lattice of `n`³ cell centres over box (lo, hi), x fastest.
pub fn lattice(lo: Vec3, hi: Vec3, n: u32) -> Vec<Vec3> {
    let n = n.max(1);
    let at = |i: u32| (i as f32 + 0.5) / n as f32;
    let mut out = Vec::with_capacity((n * n * n) as usize);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                out.push(lo + (hi - lo) * Vec3::new(at(x), at(y), at(z)));
            }
        }
    }
    out
}

/// Where object `mesh`'s captures lie: the lattice over its box or the scene's; a centre
/// inside or next to another object moved towards the box's centre until clear (kept, with a
/// note, where no point on the way is).
pub fn place(scene: &Scene, p: &Plan, mesh: usize) -> CaptureSet {
    let q = &p.quality;
    let (lo, hi) = match q.envmap.capture_box {
        CaptureBox::Object => {
            let b = scene.meshes[mesh].bounds();
            (b.min, b.max)
        }
        CaptureBox::Room => p.proxy_box,
    };
    let centre = (lo + hi) * 0.5;
    let clearance = 1e-3 * (hi - lo).length().max(1e-30) as f64;
    let mut notes = Vec::new();
    let centres = lattice(lo, hi, q.envmap.captures)
        .into_iter()
        .enumerate()
        .map(|(k, c)| {
            let Some(why) = crate::plan::facts::blocked(scene, mesh, c, clearance) else { return c };
            let clear = [0.25f32, 0.5, 0.75, 1.0]
                .iter()
                .map(|&t| c + (centre - c) * t)
                .find(|&x| crate::plan::facts::blocked(scene, mesh, x, clearance).is_none());
            notes.push(match clear {
                Some(x) => {
                    format!("capture {k} moved from ({:.3}, {:.3}, {:.3}), {why}, to ({:.3}, {:.3}, {:.3})", c.x, c.y, c.z, x.x, x.y, x.z)
                }
                None => format!(
                    "capture {k} at ({:.3}, {:.3}, {:.3}) lies {why}, and no point towards the box's centre is clear: kept",
                    c.x, c.y, c.z
                ),
            });
            clear.unwrap_or(c)
        })
        .collect();
    CaptureSet { mesh, per_axis: q.envmap.captures.max(1), centres, notes }
}

/// The family's `plan_views` hook: the captures of every object that has them, in the order
/// of its layer in `envmap.captures`.
pub fn plan_captures(scene: &Scene, p: &mut Plan) {
    let mut layered: Vec<(u32, usize)> =
        p.objects.iter().filter_map(|o| o.maps.iter().find(|m| m.pass == CAPTURE_CUBES.name).map(|m| (m.layer, o.mesh))).collect();
    layered.sort_unstable();
    p.captures = layered.into_iter().map(|(_, mesh)| place(scene, p, mesh)).collect();
}

/// The view block's size: six views per capture.
pub fn view_blocks(p: &Plan) -> Vec<(&'static str, u32)> {
    let n: usize = p.captures.iter().map(|c| c.centres.len()).sum();
    if n == 0 {
        Vec::new()
    } else {
        vec![(VIEWS, 6 * n as u32)]
    }
}

/// The words image-based's camera pass reads (`push_capture_*()`).
pub fn push_words(q: &Quality, layout: &ViewLayout, w: &mut crate::frame::words::PushWords) {
    use crate::frame::layout::{CAPTURES_PER_AXIS, CAPTURE_VIEW_BASE, CAPTURE_WARP};
    w.set(CAPTURES_PER_AXIS, q.envmap.captures.max(1));
    w.set(CAPTURE_VIEW_BASE, layout.first(VIEWS).unwrap_or(0));
    w.set(CAPTURE_WARP, matches!(q.envmap.capture_warp, CaptureWarp::Blend) as u32);
}

/// Writes the captures' cube views. Each capture's six views have its centre as eye and its
/// nominal lattice point in `dir.xyz` (the camera pass's trilinear weights are taken over
/// the nominal lattice, whichever captures had to move).
pub fn write_views(fr: &ViewFrame, table: &mut [crate::gpu_scene::GpuView]) {
    let Some(mut v) = fr.layout.first(VIEWS) else { return };
    let q = &fr.plan.quality;
    for set in &fr.plan.captures {
        let nominal = match q.envmap.capture_box {
            CaptureBox::Object => {
                let b = fr.scene.meshes[set.mesh].bounds();
                lattice(b.min, b.max, set.per_axis)
            }
            CaptureBox::Room => lattice(fr.plan.proxy_box.0, fr.plan.proxy_box.1, set.per_axis),
        };
        for (&c, &n) in set.centres.iter().zip(&nominal) {
            for f in 0..6 {
                let vp = crate::cube::face_view_proj(f, c, fr.plan.cube_near);
                table[v as usize] = crate::frame::views::view(vp, c.extend(0.0), n.extend(0.0));
                v += 1;
            }
        }
    }
}

/// `specula plan`'s lines for the captures that had to move.
pub fn describe(p: &Plan, scene: &Scene) -> Option<String> {
    let lines: Vec<String> =
        p.captures.iter().flat_map(|c| c.notes.iter().map(move |n| format!("  {}: {n}", scene.meshes[c.mesh].name))).collect();
    (!lines.is_empty()).then(|| format!("image-based captures:\n{}", lines.join("\n")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lattice_is_cell_centres_x_fastest() {
        let l = lattice(Vec3::ZERO, Vec3::new(4.0, 2.0, 2.0), 2);
        assert_eq!(l.len(), 8);
        assert_eq!(l[0], Vec3::new(1.0, 0.5, 0.5));
        assert_eq!(l[1], Vec3::new(3.0, 0.5, 0.5));
        assert_eq!(l[2], Vec3::new(1.0, 1.5, 0.5));
        assert_eq!(l[7], Vec3::new(3.0, 1.5, 1.5));
        assert_eq!(lattice(Vec3::ZERO, Vec3::ONE, 1), vec![Vec3::splat(0.5)]);
        // A flat box keeps its lattice in its plane.
        assert!(lattice(Vec3::ZERO, Vec3::new(1.0, 0.0, 1.0), 3).iter().all(|c| c.y == 0.0));
    }

    /// A capture inside another object moves towards the box's centre until it is clear and
    /// says so; the others stay on the lattice; `room` puts the lattice in the scene's box.
    #[test]
    fn captures_inside_other_objects_move_out() {
        use crate::scene::{shapes, Material, SurfaceKind};
        let mut s = Scene::new();
        let mirror = s
            .add_material(Material {
                name: "m".into(),
                kind: SurfaceKind::Mirror { nu: Vec3::splat(3.0), kappa: Vec3::ZERO },
                ..Default::default()
            })
            .unwrap();
        let grey = s.add_material(Material { name: "grey".into(), ..Default::default() }).unwrap();
        s.add_mesh(shapes::uv_sphere("ball", Vec3::ZERO, 0.5, 16, 8, mirror)).unwrap();
        // A closed box around the lattice point (0.25, 0.25, 0.25).
        s.add_mesh(shapes::cuboid("block", Vec3::splat(0.25), Vec3::splat(0.15), grey)).unwrap();
        let p = crate::plan::plan(&s, super::super::IMAGE_BASED, &Quality::default());
        assert_eq!(p.captures.len(), 1);
        let set = &p.captures[0];
        let nominal = lattice(s.meshes[0].bounds().min, s.meshes[0].bounds().max, 2);
        assert_eq!(set.centres[..7], nominal[..7]);
        let moved = set.centres[7];
        // Three quarters of the way to the centre: the first of the steps out of the block.
        assert!(moved.distance(Vec3::splat(0.0625)) < 1e-4, "moved towards the centre, out of the block: {moved}");
        assert_eq!(set.notes.len(), 1, "{:?}", set.notes);
        assert!(set.notes[0].starts_with("capture 7 moved"), "{:?}", set.notes);
        let mut q = Quality::default();
        q.set("capture_box", "room").unwrap();
        q.set("captures", "1").unwrap();
        let p = crate::plan::plan(&s, super::super::IMAGE_BASED, &q);
        assert_eq!(p.captures[0].centres, vec![(p.proxy_box.0 + p.proxy_box.1) * 0.5]);
    }
}
