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

/// What happens at a plane of the tree: a planar mirror reflects; a glass interface (a
/// face of a flat-faced solid dielectric, or a thin-walled pane) reflects and refracts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Interface {
    Mirror,
    /// `ior` relative to the outside; `thin`: a thin-walled pane (light passes undeviated).
    Glass {
        ior: f32,
        thin: bool,
    },
}

/// One planar reflector or refracting face: its mesh and its world plane n·p + w = 0
/// (unit n; a solid's face: outward).
#[derive(Clone, Debug)]
pub struct Mirror {
    pub mesh: usize,
    pub plane: Vec4,
    /// The largest coordinate magnitude of its vertices (the scale of their f32 rounding).
    pub far: f32,
    /// A convex polygon in its plane that bounds it (its clipped projection bounds its
    /// pixels).
    pub outline: Vec<Vec3>,
    /// Edge of the mirror's bounding box: the scale of "on the plane".
    pub size: f32,
    pub interface: Interface,
}

impl Mirror {
    /// The planes of mesh `mesh` in its current pose: a planar mirror or a thin pane is
    /// one; a flat-faced solid dielectric is one per face (none once it is no longer
    /// flat-faced); a mesh of no area has none (nothing to reflect).
    pub fn of(scene: &Scene, mesh: usize) -> Vec<Mirror> {
        let m = &scene.meshes[mesh];
        if m.hidden {
            return Vec::new();
        }
        let kind = scene.materials.get(m.material).map(|mat| mat.kind);
        match kind {
            Some(crate::scene::SurfaceKind::Dielectric { ior, thin: false }) => {
                let Some(faces) = crate::scene::faces::planar_faces(m, crate::scene::faces::MAX_FACES) else { return Vec::new() };
                let far = m.positions.iter().fold(0.0f32, |a, p| a.max(p.abs().max_element()));
                faces
                    .into_iter()
                    .map(|f| {
                        let (lo, hi) =
                            f.outline.iter().fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
                        let size = (hi - lo).max_element();
                        Mirror { mesh, plane: f.plane, far, outline: f.outline, size, interface: Interface::Glass { ior, thin: false } }
                    })
                    .collect()
            }
            Some(crate::scene::SurfaceKind::Dielectric { ior, thin: true }) => {
                Self::plane_of(mesh, m, Interface::Glass { ior, thin: true }).into_iter().collect()
            }
            _ => Self::plane_of(mesh, m, Interface::Mirror).into_iter().collect(),
        }
    }

    /// A planar mesh as one plane (that of its largest triangle, oriented by the mean
    /// normal) with its bounding rectangle in the plane.
    fn plane_of(mesh: usize, m: &crate::scene::Mesh, interface: Interface) -> Option<Mirror> {
        let points = &m.positions;
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
        let outline = vec![at(lo.x, lo.y), at(hi.x, lo.y), at(hi.x, hi.y), at(lo.x, hi.y)];
        let far = points.iter().fold(0.0f32, |a, p| a.max(p.abs().max_element()));
        Some(Mirror { mesh, plane: n.extend(-n.dot(best.2)), far, outline, size, interface })
    }

    fn distance(&self, p: Vec3) -> f32 {
        self.plane.truncate().dot(p) + self.plane.w
    }

    /// How far in front of its plane a view's clip plane sits: the mirror itself, and f32
    /// rounding of points on its plane, must not cover the view (1e-4 of its size, and at
    /// least a few ulps of its coordinates).
    pub fn hair(&self) -> f32 {
        (1e-4 * self.size).max(4.0 * f32::EPSILON * self.far)
    }
}

/// The linearised refraction of GS04 through the plane `plane` (unit n towards the eye),
/// for eye rays around the central direction `d` (unit, towards the plane), from a medium
/// into one `eta` = ν₂/ν₁ times as dense: the affine map p ↦ p + (n·p + w)·v that fixes the
/// plane and moves each point behind it to where it appears through the plane. The central
/// ray is exact: a point on its refracted branch lands on its incident line. Around it,
/// Snell's law in tangent space (tan θ_t as a function of tan θ_i) is linearised by one
/// isotropic slope k, the mean of its radial derivative cos³θ_i / (η cos³θ_t) and its
/// tangential ratio tan θ_t / tan θ_i (the two agree, 1/η, at normal incidence, where the
/// map is the apparent depth d/η). `None` when the central ray is reflected totally or
/// grazes the plane.
pub fn linearised_refraction(plane: Vec4, d: Vec3, eta: f32) -> Option<Mat4> {
    let n = plane.truncate();
    let cos_i = -n.dot(d);
    if cos_i.is_nan() || cos_i <= 1e-6 || eta.is_nan() || eta <= 0.0 {
        return None;
    }
    let sin2_i = (1.0 - cos_i * cos_i).max(0.0);
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return None; // total internal reflection of the central ray
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    if cos_t.is_nan() || cos_t <= 1e-6 {
        return None;
    }
    let t = d / eta + (cos_i / eta - cos_t) * n;
    // Lateral tangents of the incident and refracted directions.
    let x0 = (d + cos_i * n) / cos_i;
    let y0 = (t + cos_t * n) / cos_t;
    let radial = cos_i.powi(3) / (eta * cos_t.powi(3));
    let tan_i = sin2_i.sqrt() / cos_i;
    let tangential = if tan_i > 1e-4 { (sin2_t.sqrt() / cos_t) / tan_i } else { 1.0 / eta };
    let k = 0.5 * (radial + tangential);
    let v = (k - 1.0) * n + (y0 - k * x0);
    let lin = glam::Mat3::IDENTITY + glam::Mat3::from_cols(v * n.x, v * n.y, v * n.z);
    Some(Mat4::from_cols(lin.x_axis.extend(0.0), lin.y_axis.extend(0.0), lin.z_axis.extend(0.0), (plane.w * v).extend(1.0)))
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

    /// Pixels covered.
    pub fn area(&self) -> u64 {
        if self.is_empty() {
            0
        } else {
            (self.x1 - self.x0) as u64 * (self.y1 - self.y0) as u64
        }
    }

    fn intersect(&self, o: &Rect) -> Rect {
        Rect { x0: self.x0.max(o.x0), y0: self.y0.max(o.y0), x1: self.x1.min(o.x1), y1: self.y1.min(o.y1) }
    }
}

/// What a view shows through its plane.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ViewKind {
    /// The reflection: the parent's camera mirrored through the plane (exact).
    Reflect,
    /// The refraction: the parent's camera seen through the plane (GS04's linearised map;
    /// exact for a thin pane, which transmits undeviated).
    Refract,
}

/// One mirrored (or refracted) view of a frame.
#[derive(Clone, Debug)]
pub struct MirrorView {
    /// 1: seen from the camera; k: through k planes.
    pub level: u32,
    /// The view it was reflected from (`None`: the camera).
    pub parent: Option<usize>,
    /// Index into `MirrorFrame::mirrors`.
    pub mirror: usize,
    pub kind: ViewKind,
    /// The solid dielectric whose inside the view looks through (its mesh), if any.
    pub medium: Option<usize>,
    /// Its layer of the views' image (its index in the frame).
    pub layer: u32,
    /// The reflected eye (virtual camera position).
    pub eye: Vec3,
    /// World → clip with the oblique near plane at the mirror (what rasterisation uses).
    pub view_proj: Mat4,
    /// World → clip without it (its inverse unprojects pixels to rays, as the camera's).
    pub plain_view_proj: Mat4,
    /// The kept side of the mirror's plane (towards the parent's eye when reflecting, away
    /// from it when refracting), `hair` beyond the plane.
    pub clip: Vec4,
    pub hair: f32,
    /// The pixels the mirror covers in the parent (all the view needs to render).
    pub rect: Rect,
}

/// A frame's mirrored views and, per view (and the camera), how each planar mirror it
/// sees is drawn.
#[derive(Clone, Debug, Default)]
pub struct MirrorFrame {
    pub mirrors: Vec<Mirror>,
    pub views: Vec<MirrorView>,
    /// Views that were needed where the depth or the budget left none (each falls back
    /// to the environment along its rays).
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
    /// The views of the planar mirrors and refracting faces of `meshes` of `scene` from the
    /// camera (`view_proj`, `eye`, a `width`×`height` target; `cos_corner` of its frustum).
    ///
    /// The tree grows best first: of all the views that could be rendered next (a plane
    /// visible in the camera or in a view already chosen, within the recursion depth), the
    /// one whose image weighs most — the pixels it covers times the product of the Fresnel
    /// weights of its path's central ray — until `mirror_budget` views are chosen. Through
    /// glass the refraction carries most of the light and a weak external reflection waits;
    /// a total internal reflection carries all of it. The chosen views are then numbered
    /// breadth first, so that each view's children of one mesh are consecutive layers.
    pub fn plan(
        scene: &Scene,
        meshes: &[usize],
        view_proj: Mat4,
        eye: Vec3,
        size: (u32, u32),
        cos_corner: f32,
        lim: Limits,
    ) -> MirrorFrame {
        let mirrors: Vec<Mirror> = meshes.iter().flat_map(|&m| Mirror::of(scene, m)).collect();
        let mut frame = MirrorFrame { mirrors, views: Vec::new(), fallbacks: 0 };
        let root = Node {
            eye,
            plain: view_proj,
            clip: Vec4::new(0.0, 0.0, 0.0, 1.0),
            rect: Rect::full(size.0, size.1),
            mirror: None,
            medium: None,
            level: 0,
            weight: 1.0,
        };
        let budget = lim.budget.min(lim.layers) as usize;
        // Chosen views in the order they were chosen: (parent in this list, its candidate).
        let mut chosen: Vec<(Option<usize>, Candidate)> = Vec::new();
        let mut heap = std::collections::BinaryHeap::new();
        let mut seq = 0u64;
        let mut offer = |heap: &mut std::collections::BinaryHeap<Ranked>, parent: Option<usize>, node: &Node, frame: &mut MirrorFrame| {
            for c in candidates(&frame.mirrors, node, size) {
                if c.level > lim.depth {
                    frame.fallbacks += 1;
                    continue;
                }
                let importance = c.weight as f64 * c.rect.area() as f64;
                let candidate = Candidate { seq, ..c };
                heap.push(Ranked { importance, seq, parent, candidate });
                seq += 1;
            }
        };
        offer(&mut heap, None, &root, &mut frame);
        while let Some(r) = heap.pop() {
            if chosen.len() >= budget {
                frame.fallbacks += 1 + heap.len() as u32;
                break;
            }
            let node = r.candidate.node(r.parent.map_or(&root, |p| &chosen[p].1.child));
            let mut c = r.candidate;
            c.child = node;
            chosen.push((r.parent, c));
            let index = chosen.len() - 1;
            let child = chosen[index].1.child.clone();
            offer(&mut heap, Some(index), &child, &mut frame);
        }
        // Breadth-first numbering: children in the order their parent offered them.
        let mut order: Vec<usize> = Vec::with_capacity(chosen.len());
        let mut layer_of = vec![u32::MAX; chosen.len()];
        let mut frontier: Vec<Option<usize>> = vec![None];
        while !frontier.is_empty() {
            let mut next = Vec::new();
            for parent in frontier {
                let mut kids: Vec<usize> = (0..chosen.len()).filter(|&i| chosen[i].0 == parent).collect();
                kids.sort_by_key(|&i| chosen[i].1.seq);
                for i in kids {
                    layer_of[i] = order.len() as u32;
                    order.push(i);
                    next.push(Some(i));
                }
            }
            frontier = next;
        }
        for &i in &order {
            let (parent, c) = &chosen[i];
            let n = &c.child;
            frame.views.push(MirrorView {
                level: n.level,
                parent: parent.map(|p| layer_of[p] as usize),
                mirror: c.mirror,
                kind: c.kind,
                medium: n.medium,
                layer: layer_of[i],
                eye: n.eye,
                view_proj: oblique(n.plain, n.clip, cos_corner),
                plain_view_proj: n.plain,
                clip: n.clip,
                hair: c.hair,
                rect: n.rect,
            });
        }
        frame
    }

    /// For the camera (`None`) or view `v`: per mesh it sees planes of, the layers of its
    /// child views, (first, count); a mesh's children are consecutive layers.
    pub fn children(&self, v: Option<usize>) -> Vec<(usize, u32, u32)> {
        let mut out: Vec<(usize, u32, u32)> = Vec::new();
        for c in self.views.iter().filter(|c| c.parent == v) {
            let mesh = self.mirrors[c.mirror].mesh;
            match out.last_mut() {
                Some((m, first, count)) if *m == mesh && *first + *count == c.layer => *count += 1,
                _ => out.push((mesh, c.layer, 1)),
            }
        }
        out
    }

    /// Views in recording order: deepest level first (a view samples its children).
    pub fn order(&self) -> Vec<usize> {
        let mut o: Vec<usize> = (0..self.views.len()).collect();
        o.sort_by_key(|&i| std::cmp::Reverse(self.views[i].level));
        o
    }
}

/// A view of the tree as its children are planned from it.
#[derive(Clone, Debug)]
struct Node {
    eye: Vec3,
    plain: Mat4,
    clip: Vec4,
    rect: Rect,
    mirror: Option<usize>,
    medium: Option<usize>,
    level: u32,
    /// Product of the Fresnel weights of its path's central ray.
    weight: f32,
}

/// A view that could be rendered: a plane seen from a node, and which branch.
#[derive(Clone, Debug)]
struct Candidate {
    mirror: usize,
    kind: ViewKind,
    /// World → world: the reflection or the linearised refraction.
    transform: Mat4,
    keep: Vec4,
    medium: Option<usize>,
    level: u32,
    rect: Rect,
    weight: f32,
    hair: f32,
    seq: u64,
    /// Filled in when chosen.
    child: Node,
}

impl Candidate {
    fn node(&self, parent: &Node) -> Node {
        Node {
            eye: self.transform.inverse().transform_point3(parent.eye),
            plain: parent.plain * self.transform,
            clip: self.keep,
            rect: self.rect,
            mirror: Some(self.mirror),
            medium: self.medium,
            level: self.level,
            weight: self.weight,
        }
    }
}

/// A candidate ranked by its image's weight (ties: the earlier offered first).
struct Ranked {
    importance: f64,
    seq: u64,
    parent: Option<usize>,
    candidate: Candidate,
}

impl PartialEq for Ranked {
    fn eq(&self, o: &Ranked) -> bool {
        self.cmp(o) == std::cmp::Ordering::Equal
    }
}
impl Eq for Ranked {}
impl PartialOrd for Ranked {
    fn partial_cmp(&self, o: &Ranked) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Ranked {
    fn cmp(&self, o: &Ranked) -> std::cmp::Ordering {
        self.importance.total_cmp(&o.importance).then(o.seq.cmp(&self.seq))
    }
}

/// The views node `p` could have: per plane it sees (from inside a solid only that solid's
/// faces, from within; from outside a solid's faces only from without: its far faces hide
/// behind its near ones, the solids being convex), its reflection and, through glass, its
/// refraction (none where the central ray is reflected totally).
fn candidates(mirrors: &[Mirror], p: &Node, size: (u32, u32)) -> Vec<Candidate> {
    let mut out = Vec::new();
    for (k, m) in mirrors.iter().enumerate() {
        if p.mirror == Some(k) {
            continue; // a plane does not see itself
        }
        let side = m.distance(p.eye);
        let seen = match (m.interface, p.medium) {
            (Interface::Glass { thin: false, .. }, None) => side > 0.0,
            (Interface::Glass { thin: false, .. }, Some(o)) => o == m.mesh && side < 0.0,
            (_, medium) => medium.is_none(),
        };
        if !seen {
            continue;
        }
        let Some(rect) = visible_rect(m, &p.plain, p.clip, p.eye, p.rect, size) else { continue };
        let level = p.level + 1;
        // The plane oriented towards the node's eye.
        let plane = if side >= 0.0 { m.plane } else { -m.plane };
        let hair = m.hair();
        let hair4 = Vec4::new(0.0, 0.0, 0.0, hair);
        let make = |kind, transform, keep, medium, weight: f32| Candidate {
            mirror: k,
            kind,
            transform,
            keep,
            medium,
            level,
            rect,
            weight: p.weight * weight,
            hair,
            seq: 0,
            child: p.clone(),
        };
        match m.interface {
            Interface::Mirror => out.push(make(ViewKind::Reflect, reflection(plane), plane - hair4, p.medium, 1.0)),
            Interface::Glass { ior, thin } => {
                let d = central_ray(&p.plain, p.eye, rect, size, plane, &m.outline);
                let (eta, inside) = if thin || p.medium.is_none() { (ior, Some(m.mesh)) } else { (1.0 / ior, None) };
                let f = crate::optics::fresnel_dielectric((-plane.truncate().dot(d)) as f64, eta as f64) as f32;
                // Refraction first: through glass it carries most of the light.
                let refract = if thin { Some(Mat4::IDENTITY) } else { linearised_refraction(plane, d, eta) };
                if let Some(t) = refract {
                    let medium = if thin { None } else { inside };
                    out.push(make(ViewKind::Refract, t, -plane - hair4, medium, 1.0 - f));
                }
                let f = if refract.is_some() { f } else { 1.0 };
                out.push(make(ViewKind::Reflect, reflection(plane), plane - hair4, p.medium, f));
            }
        }
    }
    out
}

/// The unit direction from `eye` to the middle of a plane's visible pixels `rect` (through
/// the view's `plain` projection), or to its outline's centroid when that ray misses the
/// plane: the ray the linearised refraction is exact for.
fn central_ray(plain: &Mat4, eye: Vec3, rect: Rect, size: (u32, u32), plane: Vec4, outline: &[Vec3]) -> Vec3 {
    let (cx, cy) = (0.5 * (rect.x0 + rect.x1) as f32, 0.5 * (rect.y0 + rect.y1) as f32);
    let ndc = glam::Vec2::new(2.0 * cx / size.0 as f32 - 1.0, 2.0 * cy / size.1 as f32 - 1.0);
    let near = plain.inverse() * Vec4::new(ndc.x, ndc.y, 1.0, 1.0);
    let n = plane.truncate();
    let centroid = outline.iter().copied().sum::<Vec3>() / outline.len().max(1) as f32;
    let fallback = (centroid - eye).normalize_or_zero();
    if near.w.abs() < 1e-30 {
        return fallback;
    }
    let dir = (near.truncate() / near.w - eye).normalize_or_zero();
    let denom = n.dot(dir);
    let t = -(n.dot(eye) + plane.w) / denom;
    if denom < -1e-6 && t.is_finite() && t > 0.0 {
        dir
    } else {
        fallback
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

/// The planes mesh `mesh` of `scene` brings to the tree, counting each child view it can
/// have: a planar mirror 1; a pane 2 (its reflection and its transmission); a flat-faced
/// solid 2 per face. Hidden or not, as it may be shown again without a new plan.
pub fn plane_count(scene: &Scene, mesh: usize) -> u32 {
    let m = &scene.meshes[mesh];
    match scene.materials.get(m.material).map(|mat| &mat.kind) {
        Some(crate::scene::SurfaceKind::Dielectric { thin: false, .. }) => {
            crate::scene::faces::planar_faces(m, crate::scene::faces::MAX_FACES).map_or(0, |f| 2 * f.len() as u32)
        }
        Some(crate::scene::SurfaceKind::Dielectric { thin: true, .. }) => 2,
        _ => 1,
    }
}

/// The most views a frame of `planes` planes (planar mirrors, and two per refracting face:
/// its reflection and its refraction) can have up to recursion `depth`, within `budget`:
/// the layers of the views' image. Level k can have m(m − 1)^(k−1) views.
/// Whether the views that `planes` planes can need within `depth` exceed `budget` (each
/// plane sees every other, as `layers_needed` counts).
pub fn budget_cuts(planes: u32, depth: u32, budget: u32) -> bool {
    planes > 0 && layers_needed(planes, depth, budget.saturating_add(1)) > budget
}

pub fn layers_needed(planes: u32, depth: u32, budget: u32) -> u32 {
    let mut total = 0u64;
    let mut at_level = planes as u64;
    for _ in 1..=depth.min(64) {
        total = total.saturating_add(at_level);
        at_level = at_level.saturating_mul(planes.saturating_sub(1) as u64);
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
