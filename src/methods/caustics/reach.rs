//! Which generators' caustics a change reaches (issue 33 item 4), and where their light may
//! land afterwards.
//!
//! A generator's caustic is a function of the generator (its place and material), its
//! lights, what stands between them (the photons' shadow test) and the receivers its photons
//! meet. The last record read back where its photons went (caustics/reach.comp: the world
//! bounds of their terminal hits, or that one escaped the receivers); with the generator's
//! box and its caustic cube's centre that bounds the *region* every photon path lies in — a
//! photon leaves the generator on a straight line to its hit, and the receiver distance map's
//! search and the projection's distance test look along lines from the centre to points of
//! those segments (a box holds every segment between two of its points). A move reaches the
//! caustic when the moved box, before or after, meets the region (grown by a margin: the
//! search's step past a hit, the splats' and filter's texels), or meets the light's way to
//! the generator (the shadow the box casts from the light, clipped to the scene, meets the
//! generator's box); otherwise the caustic is what it was, bit for bit.
//!
//! Where the redone caustic's light lands bounds the cube-map faces drawn again
//! (`frame::cube_deps::CausticReach`): a caustic redone because a receiver moved keeps its
//! photons' directions, so their hits stay on the old segments — within the old region —
//! except those the moved box stopped before, which now go on behind it: within the shadow
//! the old box casts from the generator's box (the union over its corners' shadows holds
//! every line from a point of one box through the other). A generator that moved or changed,
//! a changed light, an occluder between light and generator, a photon that escaped or an
//! unread region: anywhere.

use glam::Vec3;

use crate::frame::cube_deps::{shadow_bounds, CausticReach, ShadowFrom};

/// An axis-aligned box (lo, hi).
pub type Bounds = (Vec3, Vec3);

/// What the reach rule needs of one generator.
#[derive(Clone, Debug)]
pub struct GeneratorFacts {
    pub mesh: usize,
    /// Its box before the change (= after, unless it moved).
    pub bounds: Bounds,
    /// Where its lights shine from.
    pub lights: Vec<ShadowFrom>,
    /// Its light indices in the scene.
    pub light_ids: Vec<usize>,
    /// The region its photons' paths lay in at its last record (already grown by the
    /// margin); None: not known, or unbounded (a photon escaped).
    pub region: Option<Bounds>,
    /// Its caustic cubes' centres.
    pub centres: Vec<Vec3>,
    /// Why it is redone whatever moved (its cube's centre moved, the scene's bounds changed,
    /// screen space), if so: its light may land anywhere.
    pub forced: Option<String>,
}

/// A change as the rule sees it: moved meshes with their boxes before and after, the meshes
/// whose material changed, the lights that changed, the scene's bounds before and after.
pub struct Change<'a> {
    pub moved: &'a [(usize, Bounds, Bounds)],
    pub materials: &'a dyn Fn(usize) -> bool,
    pub lights: &'a [usize],
    pub world: Bounds,
    /// A mesh's name, for the reasons.
    pub name: &'a dyn Fn(usize) -> String,
    /// How far a photon's light spreads beyond its hit: `grown`'s (grow, texels, cube_size).
    pub margin: (f32, f32, u32),
}

/// Per generator, why the change reaches its caustic (None: it does not), and where the
/// redone caustics' light may land.
pub fn reached(gens: &[GeneratorFacts], c: &Change) -> (Vec<Option<String>>, CausticReach) {
    let mut why = vec![None; gens.len()];
    let mut boxes = Vec::new();
    let mut anywhere = false;
    for (g, facts) in gens.iter().enumerate() {
        let (reason, lands) = reach_of(facts, c);
        if let Some(r) = reason {
            why[g] = Some(r);
            match lands {
                Some(b) => boxes.extend(b),
                None => anywhere = true,
            }
        }
    }
    let reach = if anywhere {
        CausticReach::Anywhere
    } else if boxes.is_empty() {
        CausticReach::Unchanged
    } else {
        CausticReach::Within(boxes)
    };
    (why, reach)
}

/// One generator: why the change reaches it, and (Some) the boxes its light may land in
/// afterwards, or (None) anywhere.
fn reach_of(g: &GeneratorFacts, c: &Change) -> (Option<String>, Option<Vec<Bounds>>) {
    if c.moved.iter().any(|&(m, _, _)| m == g.mesh) {
        return (Some("it moved".into()), None);
    }
    if (c.materials)(g.mesh) {
        return (Some("its material".into()), None);
    }
    if let Some(l) = c.lights.iter().find(|l| g.light_ids.contains(l)) {
        return (Some(format!("its light {l}")), None);
    }
    if let Some(why) = &g.forced {
        return (Some(why.clone()), None);
    }
    let mut lands: Vec<Bounds> = Vec::new();
    let mut why = None;
    for &(m, before, after) in c.moved {
        // Between a light and the generator: photons start or stop there (the box grown by
        // the margin: the shadow map's texels).
        let shades = |b: Bounds| {
            g.lights.iter().any(|&l| {
                let from = match l {
                    ShadowFrom::Point(p) => p,
                    ShadowFrom::Directional(_) => b.0,
                };
                shadow_bounds(l, grown(b, from, c.margin), c.world).is_none_or(|s| overlaps(s, g.bounds))
            })
        };
        if shades(before) || shades(after) {
            return (Some(format!("'{}' between it and its light", (c.name)(m))), None);
        }
        let Some(region) = g.region else {
            return (Some(format!("'{}' moved and where its photons go is not known", (c.name)(m))), None);
        };
        let (was, is) = (overlaps(before, region), overlaps(after, region));
        if !(was || is) {
            continue;
        }
        why.get_or_insert_with(|| format!("'{}' where its photons go", (c.name)(m)));
        // The photons' directions out of the generator are what they were: only those that
        // meet the box where it was or is land elsewhere — on it, or behind it from the
        // generator (the shadows of its corners and its cubes' centres, from which the
        // receiver maps' distances change too).
        for b in [(was, before), (is, after)].into_iter().filter(|&(meets, _)| meets).map(|(_, b)| b) {
            for &centre in &g.centres {
                lands.push(grown(b, centre, c.margin));
            }
            for from in (0..8).map(|k| pick(g.bounds, k)).chain(g.centres.iter().copied()) {
                match shadow_bounds(ShadowFrom::Point(from), b, c.world) {
                    Some(s) => lands.extend(g.centres.iter().map(|&centre| grown(s, centre, c.margin))),
                    None => return (why, None),
                }
            }
        }
    }
    (why.clone(), why.map(|_| lands))
}

/// `b` grown by `grow` of its size and by `texels` × the cube's texel angle at its farthest
/// corner from `centre` (`margin` = (grow, texels, cube_size)).
fn grown(b: Bounds, centre: Vec3, (grow, texels, cube_size): (f32, f32, u32)) -> Bounds {
    let far = (0..8).map(|k| (pick(b, k) - centre).length()).fold(0.0f32, f32::max);
    let margin = grow * (b.1 - b.0).length() + far * texels * 2.0 / cube_size.max(1) as f32;
    (b.0 - Vec3::splat(margin), b.1 + Vec3::splat(margin))
}

/// Corner k of a box (bit 0: x, 1: y, 2: z from hi).
fn pick((lo, hi): Bounds, k: usize) -> Vec3 {
    Vec3::new(if k & 1 == 0 { lo.x } else { hi.x }, if k & 2 == 0 { lo.y } else { hi.y }, if k & 4 == 0 { lo.z } else { hi.z })
}

/// Whether two boxes meet (touching counts; a box that is not finite meets everything).
pub fn overlaps(a: Bounds, b: Bounds) -> bool {
    if !(a.0.is_finite() && a.1.is_finite() && b.0.is_finite() && b.1.is_finite()) {
        return true;
    }
    a.0.cmple(b.1).all() && b.0.cmple(a.1).all()
}

/// The union of boxes.
pub fn union(a: Bounds, b: Bounds) -> Bounds {
    (a.0.min(b.0), a.1.max(b.1))
}

/// The region a cube's photons' paths and searches lay in: the bounds caustics/reach.comp read
/// back (the hits and the receiver surfaces the search's probes read) with the cube's centre
/// and the generator's box, grown by `grow` of its size (rounding) and by `texels` × the cube's
/// texel angle at its farthest corner (the splats and the filter spread a photon that far).
/// None where the hits' bounds are None (a photon escaped, or a probe saw no receiver).
pub fn region(hits: Option<Option<Bounds>>, centre: Vec3, generator: Bounds, (grow, texels, cube_size): (f32, f32, u32)) -> Option<Bounds> {
    let hits = hits?;
    let mut b = union(generator, (centre, centre));
    if let Some(h) = hits {
        b = union(b, h);
    }
    Some(grown(b, centre, (grow, texels, cube_size)))
}

/// A cube's eight words from caustics/reach.comp (`CAUSTIC_REACH`): None where a photon
/// escaped, Some(None) where none landed, else the hits' bounds.
pub fn hits_of(words: &[u32]) -> Option<Option<Bounds>> {
    let value = |k: u32| f32::from_bits(if k & 0x8000_0000 != 0 { k & 0x7fff_ffff } else { !k });
    if words.len() < 8 || words[6] != 0 {
        return None;
    }
    if words[7] == 0 {
        return Some(None);
    }
    let lo = Vec3::new(value(words[0]), value(words[1]), value(words[2]));
    let hi = Vec3::new(value(words[3]), value(words[4]), value(words[5]));
    // Words not written as a pair (a read before the record) are not bounds.
    if !(lo.is_finite() && hi.is_finite() && lo.cmple(hi).all()) {
        return None;
    }
    Some(Some((lo, hi)))
}

/// A generator as the tracker is told it: its mesh, its lights (where from, and their
/// indices), its caustic cubes with their centres, and why it is redone regardless.
#[derive(Clone, Debug)]
pub struct GeneratorSpec {
    pub mesh: usize,
    pub lights: Vec<ShadowFrom>,
    pub light_ids: Vec<usize>,
    /// Its caustic cubes with their centres when they were last recorded.
    pub cubes: Vec<(usize, Vec3)>,
    /// `GeneratorFacts::forced`.
    pub forced: Option<String>,
}

/// A scene change as the tracker is told it: the moved meshes, whether a mesh's material
/// changed, the changed lights, and the meshes' names (for the reasons).
pub struct Changed<'a> {
    pub moved: &'a [usize],
    pub materials: &'a dyn Fn(usize) -> bool,
    pub lights: &'a [usize],
    pub name: &'a dyn Fn(usize) -> String,
}

/// The caustics stage's record of what it drew from: per generator whether the next record
/// redoes it, per caustic cube where its photons went, per mesh its box.
#[derive(Clone, Debug)]
pub struct Tracker {
    /// Per generator: the next record redoes its caustic, and why.
    pub dirty: Vec<Option<String>>,
    /// Per caustic cube: its hits' bounds at its last record (`hits_of`); None: not known.
    hits: Vec<Option<Option<Bounds>>>,
    /// Per caustic cube: the last record wrote its words, not read back yet.
    unread: Vec<bool>,
    /// Per mesh: its box when the last change was taken.
    bounds: Vec<Bounds>,
    /// Whether the record reads back regions at all (caustic_paths=exact: no; its photons
    /// bounce off every specular surface, so any move may reach them).
    pub tracks: bool,
    /// Whether one record covers every generator at once (the photon map, screen and texture
    /// spaces): any generator reached redoes them all.
    pub whole: bool,
    /// Per generator: its own object moved at the last change. One that moved at the last two
    /// is moving: its next record measures no region (`measures`), which its next move would
    /// make stale anyway; its region is then unknown until a record while it stands still.
    moving: Vec<(bool, bool)>,
}

impl Tracker {
    /// `generators` generators with `cubes` caustic cubes, every one to draw; `bounds`: the
    /// meshes' boxes now.
    pub fn new(generators: usize, cubes: usize, bounds: Vec<Bounds>, (tracks, whole): (bool, bool)) -> Tracker {
        Tracker {
            dirty: vec![Some("first frame".into()); generators],
            hits: vec![None; cubes],
            unread: vec![false; cubes],
            bounds,
            tracks,
            whole,
            moving: vec![(false, false); generators],
        }
    }

    /// Per generator: whether its next record measures where its photons go (it is tracked and
    /// not moving every frame).
    pub fn measures(&self) -> Vec<bool> {
        self.moving.iter().map(|&(last, now)| self.tracks && !(last && now)).collect()
    }

    /// Takes the words the last record wrote (`CAUSTIC_REACH`, eight a cube) for the cubes it
    /// recorded.
    pub fn read(&mut self, words: &[u32]) {
        for (k, unread) in self.unread.iter_mut().enumerate() {
            if std::mem::take(unread) {
                self.hits[k] = if self.tracks { words.get(8 * k..8 * k + 8).and_then(hits_of) } else { None };
            }
        }
    }

    /// After a change: marks the generators it reaches (`reached`) and returns where their
    /// light may land. `gens` gives each generator's mesh, lights and cubes with their
    /// centres; `now` the meshes' boxes after the change; `margin` as `region`'s.
    pub fn change(&mut self, gens: &[GeneratorSpec], c: &Changed, now: Vec<Bounds>, margin: (f32, f32, u32)) -> CausticReach {
        let Changed { moved, materials, lights, name } = *c;
        let before = |m: usize| self.bounds.get(m).copied().unwrap_or((Vec3::splat(f32::NEG_INFINITY), Vec3::splat(f32::INFINITY)));
        let after = |m: usize| now.get(m).copied().unwrap_or((Vec3::splat(f32::NEG_INFINITY), Vec3::splat(f32::INFINITY)));
        let moved: Vec<(usize, Bounds, Bounds)> = moved.iter().map(|&m| (m, before(m), after(m))).collect();
        let finite = |b: &&Bounds| b.0.is_finite() && b.1.is_finite();
        let world = self
            .bounds
            .iter()
            .chain(&now)
            .filter(finite)
            .fold((Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)), |w, &b| union(w, b));
        let facts: Vec<GeneratorFacts> = gens
            .iter()
            .map(|GeneratorSpec { mesh, lights: from, light_ids: ids, cubes, forced }| {
                let bounds = before(*mesh);
                let region = cubes.iter().try_fold(None::<Bounds>, |acc, &(k, centre)| {
                    let r = region(self.hits.get(k).copied().flatten(), centre, bounds, margin)?;
                    Some(Some(acc.map_or(r, |a| union(a, r))))
                });
                let centres = cubes.iter().map(|&(_, c)| c).collect();
                let (lights, light_ids, region) = (from.clone(), ids.clone(), region.flatten());
                GeneratorFacts { mesh: *mesh, bounds, lights, light_ids, region, centres, forced: forced.clone() }
            })
            .collect();
        let (why, reach) = reached(&facts, &Change { moved: &moved, materials, lights, world, name, margin });
        for (m, g) in self.moving.iter_mut().zip(gens) {
            *m = (m.1, moved.iter().any(|&(k, _, _)| k == g.mesh));
        }
        for (d, w) in self.dirty.iter_mut().zip(why) {
            if d.is_none() {
                *d = w;
            }
        }
        if self.whole && self.dirty.iter().any(Option::is_some) {
            for d in self.dirty.iter_mut().filter(|d| d.is_none()) {
                *d = Some("recorded with the others".into());
            }
        }
        self.bounds = now;
        reach
    }

    /// Every generator to redo (a first frame, map_updates=always, the camera in screen space).
    pub fn all(&mut self, why: &str) {
        for d in self.dirty.iter_mut().filter(|d| d.is_none()) {
            *d = Some(why.into());
        }
    }

    /// (generators to redo, generators).
    pub fn count(&self) -> (u32, u32) {
        (self.dirty.iter().filter(|d| d.is_some()).count() as u32, self.dirty.len() as u32)
    }

    /// The record redid the caustic cubes `redone` and measured `measured` of them: their
    /// words are to be read back; the others redone are not known; nothing is left to redo.
    pub fn recorded(&mut self, redone: &[bool], measured: &[bool]) {
        for (k, (&r, &m)) in redone.iter().zip(measured).enumerate() {
            if r && !m {
                self.hits[k] = None;
                self.unread[k] = false;
            }
            self.unread[k] |= r && m;
        }
        self.dirty.iter_mut().for_each(|d| *d = None);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube(c: Vec3, r: f32) -> Bounds {
        (c - Vec3::splat(r), c + Vec3::splat(r))
    }

    /// A glass ball under a light, its caustic on the floor below it; a box far to the side,
    /// one moving into the caustic, one between the light and the ball, the ball itself.
    #[test]
    fn a_move_reaches_the_caustics_whose_region_or_light_it_meets() {
        let ball = cube(Vec3::new(0.0, 1.0, 0.0), 0.3);
        let region = Some(union(ball, (Vec3::new(-0.5, 0.0, -0.5), Vec3::new(0.5, 0.0, 0.5))));
        let g = GeneratorFacts {
            mesh: 0,
            bounds: ball,
            lights: vec![ShadowFrom::Point(Vec3::new(0.0, 3.0, 0.0))],
            light_ids: vec![0],
            region,
            centres: vec![Vec3::new(0.0, 1.0, 0.0)],
            forced: None,
        };
        let world = (Vec3::new(-5.0, 0.0, -5.0), Vec3::new(5.0, 4.0, 5.0));
        let none = |_: usize| false;
        let named = |m: usize| format!("mesh{m}");
        let change = |moved: &[(usize, Bounds, Bounds)]| {
            let c = Change { moved, materials: &none, lights: &[], world, name: &named, margin: (0.0, 0.0, 64) };
            reached(std::slice::from_ref(&g), &c)
        };
        // Far to the side: nothing.
        let side = [(1, cube(Vec3::new(3.0, 0.5, 3.0), 0.2), cube(Vec3::new(3.2, 0.5, 3.0), 0.2))];
        assert_eq!(change(&side), (vec![None], CausticReach::Unchanged));
        // Into the caustic: redone; its light changes on the box and behind it from the ball
        // (the shadows of the ball's corners and centre), not across the rest of the floor.
        let into = [(1, cube(Vec3::new(3.0, 0.5, 3.0), 0.2), cube(Vec3::new(0.3, 0.2, 0.0), 0.2))];
        let (why, reach) = change(&into);
        assert!(why[0].as_deref().is_some_and(|w| w.contains("'mesh1' where its photons go")), "{why:?}");
        let CausticReach::Within(b) = reach else { panic!("{reach:?}") };
        assert_eq!(b.len(), 10);
        assert_eq!(b[0], into[0].2);
        assert!(b.iter().all(|s| overlaps(*s, into[0].2) && !overlaps(*s, cube(Vec3::new(-0.4, 0.0, 0.0), 0.05))), "{b:?}");
        // Out of it: the same where it was.
        let out = [(1, into[0].2, into[0].1)];
        assert_eq!(change(&out).1, CausticReach::Within(b));
        // Between the light and the ball: anywhere.
        let shade = [(1, cube(Vec3::new(3.0, 2.0, 3.0), 0.1), cube(Vec3::new(0.0, 2.0, 0.0), 0.1))];
        let (why, reach) = change(&shade);
        assert!(why[0].as_deref().is_some_and(|w| w.contains("light")) && reach == CausticReach::Anywhere, "{why:?}");
        // The ball itself, its material, its light: anywhere.
        let own = [(0, ball, cube(Vec3::new(0.1, 1.0, 0.0), 0.3))];
        assert_eq!(change(&own).1, CausticReach::Anywhere);
        let mat = |m: usize| m == 0;
        let (why, reach) = reached(
            std::slice::from_ref(&g),
            &Change { moved: &[], materials: &mat, lights: &[], world, name: &named, margin: (0.0, 0.0, 64) },
        );
        assert!(why[0].is_some() && reach == CausticReach::Anywhere);
        let (why, _) = reached(
            std::slice::from_ref(&g),
            &Change { moved: &[], materials: &none, lights: &[0], world, name: &named, margin: (0.0, 0.0, 64) },
        );
        assert!(why[0].is_some());
        // Forced (its cube's centre moved, the scene's bounds changed, screen space): any
        // move reaches it, anywhere.
        let forced = GeneratorFacts { forced: Some("its caustic cube's centre moved".into()), ..g.clone() };
        let (why, reach) =
            reached(&[forced], &Change { moved: &side, materials: &none, lights: &[], world, name: &named, margin: (0.0, 0.0, 64) });
        assert!(why[0].as_deref() == Some("its caustic cube's centre moved") && reach == CausticReach::Anywhere);
        // An unknown region (an escaped photon): any move reaches it.
        let open = GeneratorFacts { region: None, ..g.clone() };
        let (why, reach) =
            reached(&[open], &Change { moved: &side, materials: &none, lights: &[], world, name: &named, margin: (0.0, 0.0, 64) });
        assert!(why[0].is_some() && reach == CausticReach::Anywhere);
    }

    /// The reach is measured (`caustics.reach` planned and recorded) except for exact photons,
    /// fewer than 3 linear steps, no distance test and `map_updates=always`.
    #[test]
    fn what_is_tracked() {
        use crate::quality::{CausticSpace, Caustics, Quality};
        let plan = crate::plan::types::CausticsPlan {
            filter: Caustics::Triangles,
            generators: Vec::new(),
            cubes: Vec::new(),
            space: CausticSpace::Cube,
            photon_layers: 0,
            bytes: 0,
        };
        let tracked = |knobs: &[(&str, &str)]| {
            let mut q = Quality::default();
            for (k, v) in knobs {
                q.set(k, v).unwrap();
            }
            assert_eq!(plan.passes(&q).contains(&"caustics.reach"), plan.tracks_reach(&q));
            plan.tracks_reach(&q)
        };
        assert!(tracked(&[]));
        assert!(tracked(&[("linear_steps", "3")]));
        for knob in [("caustic_paths", "exact"), ("linear_steps", "2"), ("caustic_distance_test", "off"), ("map_updates", "always")] {
            assert!(!tracked(&[knob]), "{knob:?}");
        }
    }

    /// A generator that moves every frame is not measured (its region would be stale at its
    /// next move); once it stands still, the next record measures it again, and until then
    /// any move reaches it.
    #[test]
    fn a_moving_generator_is_measured_once_it_stands_still() {
        let g = |x: f32| (Vec3::new(x, 0.0, 0.0), Vec3::new(x + 1.0, 1.0, 1.0));
        let spec = GeneratorSpec { mesh: 0, lights: Vec::new(), light_ids: Vec::new(), cubes: vec![(0, Vec3::splat(0.5))], forced: None };
        let none = |_: usize| false;
        let name = |m: usize| format!("mesh{m}");
        let mut t = Tracker::new(1, 1, vec![g(0.0), g(5.0)], (true, false));
        let step = |t: &mut Tracker, moved: &[usize], now: Vec<Bounds>| {
            let c = Changed { moved, materials: &none, lights: &[], name: &name };
            t.change(std::slice::from_ref(&spec), &c, now, (0.0, 0.0, 64))
        };
        assert_eq!(t.measures(), [true]);
        t.recorded(&[true], &[true]);
        // A region read back: a move far from it reaches nothing.
        let words = |b: Bounds| {
            let key = |f: f32| if f.to_bits() & 0x8000_0000 != 0 { !f.to_bits() } else { f.to_bits() | 0x8000_0000 };
            vec![key(b.0.x), key(b.0.y), key(b.0.z), key(b.1.x), key(b.1.y), key(b.1.z), 0, 10]
        };
        t.read(&words(g(0.0)));
        assert_eq!(step(&mut t, &[1], vec![g(0.0), g(6.0)]), CausticReach::Unchanged);
        // It moves twice: redone both times, measured the first only.
        step(&mut t, &[0], vec![g(0.1), g(6.0)]);
        assert_eq!(t.measures(), [true]);
        t.recorded(&[true], &[true]);
        step(&mut t, &[0], vec![g(0.2), g(6.0)]);
        assert_eq!(t.measures(), [false]);
        t.recorded(&[true], &[false]);
        t.read(&words(g(0.0)));
        // Standing still: the other's far move now reaches it (its region is not known) …
        assert_eq!(step(&mut t, &[1], vec![g(0.2), g(7.0)]), CausticReach::Anywhere);
        assert_eq!(t.measures(), [true]);
        t.recorded(&[true], &[true]);
        t.read(&words(g(0.2)));
        // … and once measured again, no longer.
        assert_eq!(step(&mut t, &[1], vec![g(0.2), g(8.0)]), CausticReach::Unchanged);
    }

    /// The words caustics/reach.comp writes decode to the hits' bounds; escaped and empty
    /// cubes say so; the region holds the centre, the generator and the hits with a margin.
    #[test]
    fn reach_words_decode_and_grow_into_regions() {
        let key = |f: f32| {
            let b = f.to_bits();
            if b & 0x8000_0000 != 0 {
                !b
            } else {
                b | 0x8000_0000
            }
        };
        let mut w = vec![key(-1.5), key(0.0), key(-0.25), key(2.0), key(0.5), key(-0.0), 0, 7];
        assert_eq!(hits_of(&w), Some(Some((Vec3::new(-1.5, 0.0, -0.25), Vec3::new(2.0, 0.5, 0.0)))));
        // Keys order like the floats they encode.
        let mut fs = [-3.0f32, -0.5, -0.0, 0.0, 1e-30, 2.0, 1e30];
        fs.sort_by_key(|&f| key(f));
        assert_eq!(fs, [-3.0, -0.5, -0.0, 0.0, 1e-30, 2.0, 1e30]);
        w[6] = 1;
        assert_eq!(hits_of(&w), None);
        assert_eq!(hits_of(&[u32::MAX, u32::MAX, u32::MAX, 0, 0, 0, 0, 0]), Some(None));
        // Cleared words that no record wrote: not bounds.
        assert_eq!(hits_of(&[u32::MAX, u32::MAX, u32::MAX, 0, 0, 0, 0, 3]), None);
        let g = cube(Vec3::ZERO, 0.5);
        let r = region(Some(Some((Vec3::new(-1.0, -2.0, -1.0), Vec3::new(1.0, -2.0, 1.0)))), Vec3::ZERO, g, (0.0, 0.0, 64)).unwrap();
        assert_eq!(r, (Vec3::new(-1.0, -2.0, -1.0), Vec3::new(1.0, 0.5, 1.0)));
        let grown = region(Some(None), Vec3::ZERO, g, (0.1, 2.0, 64)).unwrap();
        let m = 0.1 * 3f32.sqrt() + 0.5 * 3f32.sqrt() * 4.0 / 64.0;
        assert!((grown.1.x - (0.5 + m)).abs() < 1e-6, "{grown:?}");
        assert_eq!(region(None, Vec3::ZERO, g, (0.1, 2.0, 64)), None);
    }
}
