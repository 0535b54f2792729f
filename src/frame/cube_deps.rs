//! Per-face dependencies of cube maps (issue 33 item 4): which faces of which cube a
//! cube-map stage draws again after the scene changed. A face depends on what lies in its
//! frustum from the cube's centre (`cube::face_sees_box`): it is drawn again when an object
//! that moved was inside it before or is now, or the shadow it casts from a shadowed light
//! (the volume behind it, clipped to the scene's bounds) was or is; when a material of an
//! object inside it changed; when its centre moved (its own object moved); on any light
//! change (every face is lit); where the caustics this frame redoes may have changed the
//! light on its surfaces (`CausticReach`: within the boxes the caustics stage worked out, or
//! anywhere after a generator moved); and — with inter-object cycles, where a face shows
//! the other objects traced in their own maps — when it sees an object whose map is drawn
//! again. A face that shows a planar mirror (its mirrored view sees anywhere) is drawn
//! again on any move. Everything else keeps what it holds.

use glam::Vec3;

use super::ALL_FACES;
use crate::cube::face_sees_box;
use crate::gpu_scene::Draw;
use crate::scene::update::Changes;
use crate::scene::Scene;

/// A light whose shadow map the faces' shading reads: where shadows are cast from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ShadowFrom {
    Point(Vec3),
    /// The direction the light travels.
    Directional(Vec3),
}

/// Where the caustics this frame redoes may have changed the light on the maps' surfaces
/// (set by the caustics stage's update, `methods::caustics::reach`, before the maps' own).
#[derive(Clone, Debug, Default, PartialEq)]
pub enum CausticReach {
    /// No caustic the maps show is redone.
    #[default]
    Unchanged,
    /// Within these boxes.
    Within(Vec<(Vec3, Vec3)>),
    /// Anywhere (a generator moved, a light changed, a photon escaped …).
    Anywhere,
}

/// What else a face's content depends on besides what lies in it.
#[derive(Clone, Debug, Default)]
pub struct Lighting {
    /// The lights whose shadows the maps show.
    pub shadows: Vec<ShadowFrom>,
    /// Where the caustics projected onto what the maps show changed.
    pub caustics: CausticReach,
}

impl Lighting {
    /// What a plan's maps show of the lights: the shadow-mapped lights' shadows, and where
    /// this frame's caustics changed (`maps.caustic_reach`).
    pub fn of(scene: &Scene, plan: &crate::plan::types::Plan, maps: &crate::frame::maps::Maps) -> Lighting {
        let point = plan.shadow_cubes.iter().filter_map(|&i| scene.lights.get(i)).map(|l| ShadowFrom::Point(l.position));
        let directional = plan.shadow_planes.iter().filter_map(|&i| scene.lights.get(i)).map(|l| ShadowFrom::Directional(l.direction));
        let caustics = if plan.caustics.is_some() { maps.caustic_reach.clone() } else { CausticReach::Unchanged };
        Lighting { shadows: point.chain(directional).collect(), caustics }
    }
}

/// The bounds of the shadow box (lo, hi) casts from `light` within the scene's bounds
/// `scene` (the box itself included); None where the light is inside it (everywhere).
pub(crate) fn shadow_bounds(light: ShadowFrom, (lo, hi): (Vec3, Vec3), (slo, shi): (Vec3, Vec3)) -> Option<(Vec3, Vec3)> {
    if !(lo.is_finite() && hi.is_finite() && slo.is_finite() && shi.is_finite()) {
        return None;
    }
    // Where the ray from o along d (away from the light) leaves the scene's bounds.
    let exit = |o: Vec3, d: Vec3| {
        let far = |k: usize| {
            if d[k] > 0.0 {
                (shi[k] - o[k]) / d[k]
            } else if d[k] < 0.0 {
                (slo[k] - o[k]) / d[k]
            } else {
                f32::INFINITY
            }
        };
        let t = far(0).min(far(1)).min(far(2)).max(0.0);
        if t.is_finite() {
            o + d * t
        } else {
            o
        }
    };
    let (mut a, mut b) = (lo, hi);
    for k in 0..8 {
        let c = Vec3::new(if k & 1 == 0 { lo.x } else { hi.x }, if k & 2 == 0 { lo.y } else { hi.y }, if k & 4 == 0 { lo.z } else { hi.z });
        let d = match light {
            ShadowFrom::Point(l) => {
                if l.cmpge(lo).all() && l.cmple(hi).all() {
                    return None;
                }
                c - l
            }
            ShadowFrom::Directional(w) => w,
        };
        let e = exit(c, d);
        (a, b) = (a.min(e), b.max(e));
    }
    Some((a, b))
}

/// The faces a stage's next record draws, and what its last record drew them from.
#[derive(Clone, Debug, Default)]
pub struct FaceDeps {
    /// Per layer the faces to draw (bit f: face f).
    pub faces: Vec<u8>,
    /// Per layer the centre the faces were drawn from.
    eyes: Vec<Vec3>,
    /// Per mesh the bounds the faces were drawn with.
    bounds: Vec<(Vec3, Vec3)>,
    /// Per layer the mesh its faces leave out (`leaving_out`).
    left_out: Vec<Option<usize>>,
}

impl FaceDeps {
    /// `layers` cubes, every face to draw.
    pub fn new(layers: usize) -> FaceDeps {
        FaceDeps { faces: vec![ALL_FACES; layers], eyes: Vec::new(), bounds: Vec::new(), left_out: Vec::new() }
    }

    /// The mesh each layer leaves out of its faces (its own object), whose moves it does not
    /// see (but their shadows, which fall on what it draws).
    pub fn leaving_out(mut self, left_out: Vec<Option<usize>>) -> FaceDeps {
        self.left_out = left_out;
        self
    }

    /// Every face of every layer.
    pub fn all(&mut self) {
        self.faces.iter_mut().for_each(|f| *f = ALL_FACES);
    }

    /// (faces to draw, faces in all).
    pub fn count(&self) -> (u32, u32) {
        (self.faces.iter().map(|f| (f & ALL_FACES).count_ones()).sum(), 6 * self.faces.len() as u32)
    }

    /// After the record: what the faces were drawn from (`eyes` per layer, the draws'
    /// bounds), nothing left to draw.
    pub fn drawn(&mut self, eyes: Vec<Vec3>, draws: &[Draw]) {
        self.eyes = eyes;
        self.bounds = draws.iter().map(|d| (d.lo, d.hi)).collect();
        self.faces.iter_mut().for_each(|f| *f = 0);
    }

    /// Marks the faces `changes` reaches. `objects[k]` is layer k's mesh, `eyes[k]` its
    /// centre now, `draws` the meshes' bounds now; `inter_object`: the faces show the
    /// layers' objects traced in their own maps; `mirrors`: planar mirrors drawn in the maps.
    #[allow(clippy::too_many_arguments)]
    pub fn mark(
        &mut self,
        scene: &Scene,
        objects: &[usize],
        eyes: &[Vec3],
        draws: &[Draw],
        changes: &Changes,
        (inter_object, mirrors): (bool, &[usize]),
        lighting: &Lighting,
    ) {
        let known = self.eyes.len() == objects.len() && self.bounds.len() == draws.len() && eyes.len() == objects.len();
        let changed = !changes.moved.is_empty() || !changes.materials.is_empty();
        let caustics_anywhere = lighting.caustics == CausticReach::Anywhere && changed;
        if !known || !changes.lights.is_empty() || (inter_object && !changes.materials.is_empty()) || caustics_anywhere {
            self.all();
            return;
        }
        // The scene's bounds, before and after: the shadows are clipped there.
        let union = |b: &mut (Vec3, Vec3), (lo, hi): (Vec3, Vec3)| {
            if lo.is_finite() && hi.is_finite() {
                *b = (b.0.min(lo), b.1.max(hi));
            }
        };
        let mut world = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for (k, d) in draws.iter().enumerate() {
            union(&mut world, (d.lo, d.hi));
            union(&mut world, self.bounds[k]);
        }
        // What each moved object reaches: its box before and after (`Some(mesh)`: a layer
        // that leaves the mesh out does not see it), and the shadows those cast (`None`).
        type Reach = (Option<usize>, Option<(Vec3, Vec3)>);
        let mut reached: Vec<Reach> = Vec::new();
        for &m in &changes.moved {
            let now = draws.get(m).map(|d| (d.lo, d.hi));
            for b in [self.bounds.get(m).copied(), now].into_iter().flatten() {
                reached.push((Some(m), Some(b)));
                reached.extend(lighting.shadows.iter().map(|&l| (None, shadow_bounds(l, b, world))));
            }
        }
        let now = |m: usize| draws.get(m).map_or((Vec3::splat(f32::NEG_INFINITY), Vec3::splat(f32::INFINITY)), |d| (d.lo, d.hi));
        let sees = |k: usize, f: usize, (lo, hi): (Vec3, Vec3)| face_sees_box(f, eyes[k], lo, hi);
        let changed_material = |m: usize| scene.meshes.get(m).is_some_and(|mesh| changes.materials.contains(&mesh.material));
        let any_move = !changes.moved.is_empty();
        // Where redone caustics may have changed the light on what the faces show.
        let caustic_boxes: &[(Vec3, Vec3)] = match &lighting.caustics {
            CausticReach::Within(b) => b,
            _ => &[],
        };
        for (k, eye) in eyes.iter().enumerate() {
            if self.eyes[k] != *eye {
                self.faces[k] = ALL_FACES;
                continue;
            }
            for f in 0..6 {
                let own = self.left_out.get(k).copied().flatten();
                let hit = reached.iter().any(|&(m, r)| (m.is_none() || m != own) && r.is_none_or(|b| sees(k, f, b)))
                    || (0..draws.len()).any(|m| changed_material(m) && sees(k, f, now(m)))
                    || (any_move && mirrors.iter().any(|&m| sees(k, f, now(m))))
                    || caustic_boxes.iter().any(|&b| sees(k, f, b));
                if hit {
                    self.faces[k] |= 1 << f;
                }
            }
        }
        // A face shows the other layers' objects through their maps: it follows theirs.
        let mut grew = inter_object;
        while grew {
            grew = false;
            for j in 0..objects.len() {
                if self.faces[j] == 0 {
                    continue;
                }
                let seen = now(objects[j]);
                for k in (0..objects.len()).filter(|&k| k != j) {
                    for f in 0..6 {
                        if self.faces[k] & (1 << f) == 0 && sees(k, f, seen) {
                            self.faces[k] |= 1 << f;
                            grew = true;
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn draw(lo: Vec3, hi: Vec3) -> Draw {
        Draw { first_index: 0, index_count: 3, vertex_offset: 0, mesh: 0, specular: false, lo, hi }
    }

    /// A box moving along +x past a cube centred at the origin: the +x face (and only it)
    /// sees both its places.
    #[test]
    fn a_move_marks_the_faces_that_see_it() {
        let scene = Scene::default();
        let mut d = FaceDeps::new(1);
        let before = [draw(Vec3::new(3.0, -0.1, -0.1), Vec3::new(3.2, 0.1, 0.1))];
        d.drawn(vec![Vec3::ZERO], &before);
        assert_eq!(d.count(), (0, 6));
        let after = [draw(Vec3::new(4.0, -0.1, -0.1), Vec3::new(4.2, 0.1, 0.1))];
        let moved = Changes { moved: vec![0], ..Changes::default() };
        d.mark(&scene, &[7], &[Vec3::ZERO], &after, &moved, (false, &[]), &Lighting::default());
        assert_eq!(d.faces, vec![1], "only +x");
        // The centre moved: every face.
        d.drawn(vec![Vec3::ZERO], &after);
        d.mark(&scene, &[7], &[Vec3::X], &after, &moved, (false, &[]), &Lighting::default());
        assert_eq!(d.count(), (6, 6));
        // A light: every face.
        d.drawn(vec![Vec3::ZERO], &after);
        d.mark(&scene, &[7], &[Vec3::ZERO], &after, &Changes { lights: vec![0], ..Changes::default() }, (false, &[]), &Lighting::default());
        assert_eq!(d.count(), (6, 6));
    }

    /// Two cubes seeing each other with inter-object cycles: a move that one face of the
    /// first sees marks the second's face that sees the first's object too.
    #[test]
    fn inter_object_faces_follow_the_maps_they_show() {
        let scene = Scene::default();
        let a = draw(Vec3::splat(-0.5), Vec3::splat(0.5));
        let b = draw(Vec3::new(4.5, -0.5, -0.5), Vec3::new(5.5, 0.5, 0.5));
        let c = draw(Vec3::new(-0.1, 3.0, -0.1), Vec3::new(0.1, 3.2, 0.1));
        let eyes = vec![Vec3::ZERO, Vec3::new(5.0, 0.0, 0.0)];
        let mut d = FaceDeps::new(2);
        d.drawn(eyes.clone(), &[a, b, c]);
        let c2 = draw(Vec3::new(-0.1, 3.5, -0.1), Vec3::new(0.1, 3.7, 0.1));
        let moved = Changes { moved: vec![2], ..Changes::default() };
        d.mark(&scene, &[0, 1], &eyes, &[a, b, c2], &moved, (false, &[]), &Lighting::default());
        let without = d.faces.clone();
        d.mark(&scene, &[0, 1], &eyes, &[a, b, c2], &moved, (true, &[]), &Lighting::default());
        // Cube 0 sees c above it (+y, bit 2); cube 1 sees c too (up and to the left: −x, +y)
        // and, with cycles, object 0 (−x, bit 1).
        assert_eq!(without[0], 1 << 2);
        assert!(d.faces[1] & (1 << 1) != 0, "{:?}", d.faces);
    }

    /// A box between a point light and the floor: its shadow falls on the floor, which the
    /// −y face of a cube beside it sees, though the box itself lies in its +x face only.
    #[test]
    fn a_moved_caster_marks_the_faces_that_see_its_shadow() {
        let scene = Scene::default();
        let floor = draw(Vec3::new(-5.0, -1.0, -5.0), Vec3::new(5.0, -1.0, 5.0));
        let before = draw(Vec3::new(1.8, 0.8, -0.2), Vec3::new(2.2, 1.2, 0.2));
        let after = draw(Vec3::new(1.9, 0.8, -0.2), Vec3::new(2.3, 1.2, 0.2));
        let eye = Vec3::new(0.0, 1.0, 0.0);
        let mut d = FaceDeps::new(1);
        d.drawn(vec![eye], &[floor, before]);
        let moved = Changes { moved: vec![1], ..Changes::default() };
        d.mark(&scene, &[9], &[eye], &[floor, after], &moved, (false, &[]), &Lighting::default());
        assert_eq!(d.faces, vec![1], "unshadowed: the box's face only");
        d.drawn(vec![eye], &[floor, before]);
        let light = Lighting { shadows: vec![ShadowFrom::Point(Vec3::new(2.0, 3.0, 0.0))], caustics: CausticReach::Unchanged };
        d.mark(&scene, &[9], &[eye], &[floor, after], &moved, (false, &[]), &light);
        assert!(d.faces[0] & 1 != 0 && d.faces[0] & (1 << 3) != 0, "the box and its shadow below: {:#08b}", d.faces[0]);
        // Caustics: every face.
        d.drawn(vec![eye], &[floor, before]);
        d.mark(
            &scene,
            &[9],
            &[eye],
            &[floor, after],
            &moved,
            (false, &[]),
            &Lighting { shadows: Vec::new(), caustics: CausticReach::Anywhere },
        );
        assert_eq!(d.count(), (6, 6));

        // A cube that leaves the box out (its own object, as image-based's fixed captures): the
        // box's move alone marks nothing, its shadow still the faces that see it.
        let mut d = FaceDeps::new(1).leaving_out(vec![Some(1)]);
        d.drawn(vec![eye], &[floor, before]);
        d.mark(&scene, &[9], &[eye], &[floor, after], &moved, (false, &[]), &Lighting::default());
        assert_eq!(d.faces, vec![0], "its own object's move");
        d.mark(&scene, &[9], &[eye], &[floor, after], &moved, (false, &[]), &light);
        assert!(d.faces[0] & (1 << 3) != 0, "its own object's shadow (which reaches up to it): {:#08b}", d.faces[0]);
    }
}
