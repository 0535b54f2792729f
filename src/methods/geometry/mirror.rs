//! The views of planar mirrors (survey §5, DB97/MBGN00): per frame, a tree of mirrored
//! cameras grown from the camera breadth first — a mirror visible in a view gets a child
//! view, the parent's camera reflected through the mirror's plane — to the recursion depth
//! (`depth`) and at most `mirror_budget` views. A mirror that is visible where no view is
//! left falls back to the environment along its reflected rays (black in a closed room).
//!
//! Each view renders the real scene with `view_proj · R` (R the reflection through the
//! plane), so that a point on the mirror projects to the pixel it has in the parent: the
//! mirrored image needs no resampling, and every camera pass of the frame draws its objects
//! in it as it does from the camera (their maps do not depend on the camera). Geometry
//! behind the mirror is clipped by an oblique near plane (Lengyel): the projection's depth
//! row becomes `w − a·π` for the mirror's plane π, so that `z ≤ w` keeps exactly the
//! mirror's front side; `a` = cos of the frustum's corner angle keeps `z ≥ 0` (the far side)
//! for everything the frustum holds.

use glam::{Mat4, Vec3, Vec4};

use crate::scene::Scene;

/// One planar mirror: its mesh and its world plane n·p + w = 0 (unit n).
#[derive(Clone, Debug)]
pub struct Mirror {
    pub mesh: usize,
    pub plane: Vec4,
    /// The largest coordinate magnitude of its vertices (the scale of their f32 rounding).
    pub far: f32,
    /// The rectangle in its plane that bounds it (a convex polygon whose clipped
    /// projection bounds its pixels).
    pub outline: [Vec3; 4],
    /// Edge of the mirror's bounding box: the scale of "on the plane".
    pub size: f32,
}

impl Mirror {
    /// The mirror of mesh `mesh` in its current pose; `None` for a mesh of no area (no
    /// plane, nothing to reflect).
    pub fn of(scene: &Scene, mesh: usize) -> Option<Mirror> {
        let m = &scene.meshes[mesh];
        if m.hidden {
            return None;
        }
        let points = &m.positions;
        // The plane of the largest-area triangle, oriented by the mean normal.
        let mut best = (0.0f32, Vec3::ZERO, Vec3::ZERO);
        for t in m.indices.chunks_exact(3) {
            let (a, b, c) = (points[t[0] as usize], points[t[1] as usize], points[t[2] as usize]);
            let n = (b - a).cross(c - a);
            if n.length() > best.0 {
                best = (n.length(), n, a);
            }
        }
        let (lo, hi) = points.iter().fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
        let size = (hi - lo).max_element();
        let positive = |x: f32| x.is_finite() && x > 0.0;
        if !positive(best.0) || !positive(size) {
            return None;
        }
        let n = best.1 / best.0;
        // The bounding rectangle in the plane's basis (u, v).
        let u = n.any_orthonormal_vector();
        let v = n.cross(u);
        let origin = best.2;
        let (mut lo, mut hi) = (glam::Vec2::splat(f32::MAX), glam::Vec2::splat(f32::MIN));
        for p in points {
            let q = glam::Vec2::new((*p - origin).dot(u), (*p - origin).dot(v));
            lo = lo.min(q);
            hi = hi.max(q);
        }
        let at = |a: f32, b: f32| origin + u * a + v * b;
        let outline = [at(lo.x, lo.y), at(hi.x, lo.y), at(hi.x, hi.y), at(lo.x, hi.y)];
        let far = points.iter().fold(0.0f32, |a, p| a.max(p.abs().max_element()));
        Some(Mirror { mesh, plane: n.extend(-n.dot(best.2)), far, outline, size })
    }

    fn distance(&self, p: Vec3) -> f32 {
        self.plane.truncate().dot(p) + self.plane.w
    }
}

/// The reflection through the plane n·p + w = 0 (unit n): p ↦ p − 2(n·p + w) n.
pub fn reflection(plane: Vec4) -> Mat4 {
    let n = plane.truncate();
    let lin = glam::Mat3::IDENTITY - 2.0 * glam::Mat3::from_cols(n * n.x, n * n.y, n * n.z);
    Mat4::from_cols(lin.x_axis.extend(0.0), lin.y_axis.extend(0.0), lin.z_axis.extend(0.0), (-2.0 * plane.w * n).extend(1.0))
}

/// `view_proj` with its depth row replaced so that the near clip plane is `plane` (kept side
/// n·p + w ≥ 0): z' = w_clip − a·(n·p + w). `cos_corner` is the cosine of the angle between
/// the view axis and the frustum's corner rays.
pub fn oblique(view_proj: Mat4, plane: Vec4, cos_corner: f32) -> Mat4 {
    let rows = view_proj.transpose(); // columns of the transpose are the rows
    let w_row = rows.w_axis;
    let z_row = w_row - cos_corner * plane;
    Mat4::from_cols(rows.x_axis, rows.y_axis, z_row, w_row).transpose()
}

/// A pixel rectangle [x0, x1) × [y0, y1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Rect {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
}

impl Rect {
    pub fn full(width: u32, height: u32) -> Rect {
        Rect { x0: 0, y0: 0, x1: width, y1: height }
    }

    pub fn is_empty(&self) -> bool {
        self.x0 >= self.x1 || self.y0 >= self.y1
    }

    fn intersect(&self, o: &Rect) -> Rect {
        Rect { x0: self.x0.max(o.x0), y0: self.y0.max(o.y0), x1: self.x1.min(o.x1), y1: self.y1.min(o.y1) }
    }
}

/// One mirrored view of a frame.
#[derive(Clone, Debug)]
pub struct MirrorView {
    /// 1: seen from the camera; k: through k mirrors.
    pub level: u32,
    /// The view it was reflected from (`None`: the camera).
    pub parent: Option<usize>,
    /// Index into `MirrorFrame::mirrors`.
    pub mirror: usize,
    /// Its layer of the views' image (its index in the frame).
    pub layer: u32,
    /// The reflected eye (virtual camera position).
    pub eye: Vec3,
    /// World → clip with the oblique near plane at the mirror (what rasterisation uses).
    pub view_proj: Mat4,
    /// World → clip without it (its inverse unprojects pixels to rays, as the camera's).
    pub plain_view_proj: Mat4,
    /// The kept side of the mirror's plane (towards the parent's eye).
    pub clip: Vec4,
    /// The pixels the mirror covers in the parent (all the view needs to render).
    pub rect: Rect,
}

/// A frame's mirrored views and, per view (and the camera), how each planar mirror it
/// sees is drawn.
#[derive(Clone, Debug, Default)]
pub struct MirrorFrame {
    pub mirrors: Vec<Mirror>,
    pub views: Vec<MirrorView>,
    /// Mirrors that were visible where the depth or the budget left no view for them.
    pub fallbacks: u32,
}

/// What bounds the tree.
#[derive(Clone, Copy, Debug)]
pub struct Limits {
    pub depth: u32,
    pub budget: u32,
    /// Layers of the views' image.
    pub layers: u32,
}

impl MirrorFrame {
    /// The views of the planar mirrors `meshes` of `scene` from the camera (`view_proj`,
    /// `eye`, a `width`×`height` target; `cos_corner` of its frustum).
    pub fn plan(
        scene: &Scene,
        meshes: &[usize],
        view_proj: Mat4,
        eye: Vec3,
        size: (u32, u32),
        cos_corner: f32,
        lim: Limits,
    ) -> MirrorFrame {
        let mirrors: Vec<Mirror> = meshes.iter().filter_map(|&m| Mirror::of(scene, m)).collect();
        let mut frame = MirrorFrame { mirrors, views: Vec::new(), fallbacks: 0 };
        // Breadth first: (parent view, its eye, its plain view_proj, its clip plane, its rect,
        // its mirror, its level).
        struct Node {
            index: Option<usize>,
            eye: Vec3,
            plain: Mat4,
            clip: Vec4,
            rect: Rect,
            mirror: Option<usize>,
            level: u32,
        }
        let mut queue = std::collections::VecDeque::new();
        queue.push_back(Node {
            index: None,
            eye,
            plain: view_proj,
            clip: Vec4::new(0.0, 0.0, 0.0, 1.0),
            rect: Rect::full(size.0, size.1),
            mirror: None,
            level: 0,
        });
        while let Some(parent) = queue.pop_front() {
            for (k, m) in frame.mirrors.iter().enumerate() {
                if parent.mirror == Some(k) {
                    continue; // a plane does not see itself
                }
                let Some(rect) = visible_rect(m, &parent.plain, parent.clip, parent.eye, parent.rect, size) else { continue };
                let level = parent.level + 1;
                if level > lim.depth || frame.views.len() as u32 >= lim.budget.min(lim.layers) {
                    frame.fallbacks += 1;
                    continue;
                }
                // The plane oriented towards the parent's eye: that side is kept, from a hair
                // in front of the mirror on (the mirror itself, and f32 rounding of points
                // on its plane, must not cover the view: 1e-4 of its size, and at least a
                // few ulps of its coordinates).
                let plane = if m.distance(parent.eye) >= 0.0 { m.plane } else { -m.plane };
                let r = reflection(plane);
                let plain = parent.plain * r;
                let keep = plane - Vec4::new(0.0, 0.0, 0.0, (1e-4 * m.size).max(4.0 * f32::EPSILON * m.far));
                let view = MirrorView {
                    level,
                    parent: parent.index,
                    mirror: k,
                    layer: frame.views.len() as u32,
                    eye: r.transform_point3(parent.eye),
                    view_proj: oblique(plain, keep, cos_corner),
                    plain_view_proj: plain,
                    clip: keep,
                    rect,
                };
                frame.views.push(view);
                let index = frame.views.len() - 1;
                let v = &frame.views[index];
                queue.push_back(Node {
                    index: Some(index),
                    eye: v.eye,
                    plain: v.plain_view_proj,
                    clip: keep,
                    rect,
                    mirror: Some(k),
                    level,
                });
            }
        }
        frame
    }

    /// For the camera (`None`) or view `v`: per mirror mesh it sees, its child view.
    pub fn children(&self, v: Option<usize>) -> Vec<(usize, &MirrorView)> {
        self.views.iter().filter(|c| c.parent == v).map(|c| (self.mirrors[c.mirror].mesh, c)).collect()
    }

    /// Views in recording order: deepest level first (a view samples its children).
    pub fn order(&self) -> Vec<usize> {
        let mut o: Vec<usize> = (0..self.views.len()).collect();
        o.sort_by_key(|&i| std::cmp::Reverse(self.views[i].level));
        o
    }
}

/// Clips a convex polygon to the half-space `keep(p) ≥ 0` (Sutherland–Hodgman).
fn clip_polygon<T: Copy>(poly: &[T], keep: impl Fn(&T) -> f32, lerp: impl Fn(&T, &T, f32) -> T) -> Vec<T> {
    let mut out = Vec::with_capacity(poly.len() + 1);
    for (i, a) in poly.iter().enumerate() {
        let b = &poly[(i + 1) % poly.len()];
        let (da, db) = (keep(a), keep(b));
        if da >= 0.0 {
            out.push(*a);
        }
        if (da >= 0.0) != (db >= 0.0) {
            out.push(lerp(a, b, da / (da - db)));
        }
    }
    out
}

/// The pixels mirror `m` covers in a view (its plain world → clip, kept side `clip`, eye,
/// the parent's rectangle), or `None` when it is invisible there: edge-on (the eye on its
/// plane), behind the view's clip plane, outside its frustum or outside the rectangle. The
/// mirror's outline is clipped to the view's clip plane and frustum, then projected.
fn visible_rect(m: &Mirror, plain: &Mat4, clip: Vec4, eye: Vec3, within: Rect, size: (u32, u32)) -> Option<Rect> {
    let eps = 1e-6 * m.size.max(eye.abs().max_element());
    if m.distance(eye).abs() <= eps {
        return None; // seen edge-on: no pixel
    }
    let lerp3 = |a: &Vec3, b: &Vec3, t: f32| *a + (*b - *a) * t;
    let world = clip_polygon(&m.outline, |p| clip.truncate().dot(*p) + clip.w, lerp3);
    let mut poly: Vec<Vec4> = world.iter().map(|p| *plain * p.extend(1.0)).collect();
    let lerp4 = |a: &Vec4, b: &Vec4, t: f32| *a + (*b - *a) * t;
    // In front of the eye, then within the four side planes of the frustum.
    let near = 1e-7f32;
    let sides: [fn(&Vec4) -> f32; 4] = [|c| c.w + c.x, |c| c.w - c.x, |c| c.w + c.y, |c| c.w - c.y];
    poly = clip_polygon(&poly, |c| c.w - near * c.truncate().length().max(1e-30), lerp4);
    for side in sides {
        if poly.is_empty() {
            break;
        }
        poly = clip_polygon(&poly, side, lerp4);
    }
    if poly.is_empty() {
        return None;
    }
    let (w, h) = (size.0 as f32, size.1 as f32);
    let mut lo = glam::Vec2::splat(f32::MAX);
    let mut hi = glam::Vec2::splat(f32::MIN);
    for c in &poly {
        let ndc = glam::Vec2::new(c.x, c.y) / c.w.max(1e-30);
        let px = glam::Vec2::new((ndc.x * 0.5 + 0.5) * w, (ndc.y * 0.5 + 0.5) * h);
        lo = lo.min(px);
        hi = hi.max(px);
    }
    let clampf = |v: f32, max: u32| {
        if v.is_finite() {
            v.clamp(0.0, max as f32) as u32
        } else if v > 0.0 {
            max
        } else {
            0
        }
    };
    let r = Rect {
        x0: clampf(lo.x.floor() - 1.0, size.0),
        y0: clampf(lo.y.floor() - 1.0, size.1),
        x1: clampf(hi.x.ceil() + 1.0, size.0),
        y1: clampf(hi.y.ceil() + 1.0, size.1),
    };
    let r = r.intersect(&within);
    (!r.is_empty()).then_some(r)
}

/// The most views a frame of `mirrors` planar mirrors can have up to recursion `depth`,
/// within `budget`: the layers of the views' image. Level k can have m(m − 1)^(k−1) views.
pub fn layers_needed(mirrors: u32, depth: u32, budget: u32) -> u32 {
    let mut total = 0u64;
    let mut at_level = mirrors as u64;
    for _ in 1..=depth.min(64) {
        total = total.saturating_add(at_level);
        at_level = at_level.saturating_mul(mirrors.saturating_sub(1) as u64);
        if at_level == 0 || total >= budget as u64 {
            break;
        }
    }
    total.min(budget as u64) as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reflection_mirrors_points_through_the_plane() {
        // The plane x = 2 (n = +x, w = −2).
        let r = reflection(Vec4::new(1.0, 0.0, 0.0, -2.0));
        assert!((r.transform_point3(Vec3::new(3.0, 1.0, -1.0)) - Vec3::new(1.0, 1.0, -1.0)).length() < 1e-6);
        assert!((r.transform_point3(Vec3::new(2.0, 5.0, 7.0)) - Vec3::new(2.0, 5.0, 7.0)).length() < 1e-6);
        assert!((r * r - Mat4::IDENTITY).abs_diff_eq(Mat4::ZERO, 1e-6));
    }

    #[test]
    fn oblique_projection_clips_exactly_at_the_plane() {
        let mut proj = Mat4::perspective_infinite_reverse_rh(1.0, 1.0, 0.01);
        proj.y_axis.y = -proj.y_axis.y;
        let view = Mat4::look_at_rh(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y);
        let vp = proj * view;
        let t = (0.5f32).tan();
        let cos_corner = 1.0 / (1.0 + 2.0 * t * t).sqrt();
        // Keep z ≤ 1 (the side towards the eye at z = 5 is z ≥ 1? no: keep z ≤ 1).
        let plane = Vec4::new(0.0, 0.0, -1.0, 1.0);
        let m = oblique(vp, plane, cos_corner);
        for (p, kept) in [(Vec3::new(0.0, 0.0, 0.5), true), (Vec3::new(0.1, 0.0, -30.0), true), (Vec3::new(0.0, 0.1, 1.5), false)] {
            let c = m * p.extend(1.0);
            let inside = c.z >= 0.0 && c.z <= c.w;
            assert_eq!(inside, kept, "{p}: clip {c}");
        }
        // Nearer points along a ray have larger depth (reversed-Z order kept).
        let depth = |z: f32| {
            let c = m * Vec3::new(0.0, 0.0, z).extend(1.0);
            c.z / c.w
        };
        assert!(depth(0.9) > depth(0.0) && depth(0.0) > depth(-10.0));
    }

    #[test]
    fn facing_mirrors_need_one_view_per_level_each() {
        assert_eq!(layers_needed(1, 6, 64), 1);
        assert_eq!(layers_needed(2, 6, 64), 12);
        assert_eq!(layers_needed(2, 6, 5), 5);
        assert_eq!(layers_needed(3, 3, 64), 3 + 6 + 12);
        assert_eq!(layers_needed(0, 6, 8), 0);
    }
}
