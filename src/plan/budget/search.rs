//! A choice's predicted frame time and rank under a budget, and the search over choices.

use super::candidates::Candidate;
use super::models::{mse_of, psnr_of};
use super::Budget;
use crate::plan::facts::SceneFacts;
use crate::plan::ids::{MapShading, Method};
use crate::quality::Quality;

/// Past this many (variant × per-object candidate) combinations the search is greedy.
pub const MAX_COMBINATIONS: u64 = 2_000_000;

/// The frame time of a choice (see the module doc): what composition through inter-object
/// cycles adds, from the planner's own rule.
pub(super) struct Timing<'a> {
    pub(super) base: f64,
    pub(super) quality: Quality,
    pub(super) facts: &'a SceneFacts,
    /// `facts.sight()`: per object the positions of the others it sees.
    pub(super) sight: Vec<Vec<usize>>,
}

/// A choice's composition (`Timing::composition`).
struct Composition {
    /// Per pick: maps of its own in another family's maps.
    composed: Vec<bool>,
    /// Per pick: its own maps are drawn once per inter-object cycle (distance cubes: its
    /// method's, or its radiance cube drawn as one, `distance::cubes_converted`); other maps
    /// are drawn once a frame (`cube_maps::CubeMaps::record`). The maps composition gives a
    /// pick are distance cubes, drawn each cycle.
    cycled: Vec<bool>,
    /// The inter-object cycles the frame runs.
    cycles: u32,
}

impl Timing<'_> {
    /// Whether every object has the same method (planned as that whole-scene method).
    pub(super) fn uniform(picks: &[&Candidate]) -> bool {
        picks.windows(2).all(|w| w[0].method == w[1].method)
    }

    /// How `plan_with` composes these per-object methods, computed once per choice: which
    /// picks get maps of their own in another family's maps (`registry::Family::composes`;
    /// none when one method serves every object: planned as that whole-scene method, which
    /// keeps its own behaviour), and the inter-object cycles the frame runs.
    fn composition(&self, picks: &[&Candidate]) -> Composition {
        if Self::uniform(picks) {
            let n = picks.len();
            return Composition { composed: vec![false; n], cycled: vec![true; n], cycles: picks.first().map_or(1, |c| c.cycles) };
        }
        let methods: Vec<Method> = picks.iter().map(|c| c.method).collect();
        let mut composed = vec![false; picks.len()];
        if self.quality.frame.compose {
            for f in crate::methods::FAMILIES.iter().filter_map(|f| f.composes) {
                composed.iter_mut().zip(f(&methods, &self.sight)).for_each(|(o, c)| *o |= c);
            }
        }
        let gpu = |m: Method| m.gpu.expect("GPU method");
        let own = picks.iter().map(|c| (gpu(c.method).cycles)(&self.quality)).max().unwrap_or(1).max(1);
        let sees_refractor = picks
            .iter()
            .zip(&self.facts.objects)
            .any(|(c, f)| gpu(c.method).map_shading == MapShading::Refractor && self.facts.objects.iter().any(|g| g.sees(f.mesh)));
        let converted = crate::methods::distance::cubes_converted(&methods, &self.sight);
        let composes = self.quality.frame.compose && (sees_refractor || composed.contains(&true) || converted.contains(&true));
        let distance = |m: Method| gpu(m).maps.iter().any(|i| i.name == crate::methods::distance::DISTANCE_CUBES.name);
        let cycled = picks.iter().enumerate().map(|(i, c)| distance(c.method) || (converted[i] && self.quality.frame.compose)).collect();
        let latency = picks.iter().any(|c| gpu(c.method).map_shading == MapShading::Traced) && self.quality.distance.frame_latency;
        let cycles = if latency {
            1
        } else if composes {
            own.max(2)
        } else {
            own
        };
        Composition { composed, cycled, cycles }
    }

    /// Pick `i`'s maps: its own map share and, composed, the maps composition gives it, each
    /// scaled by the frame's cycles over its calibration's where drawn each cycle (a
    /// whole-scene row runs as measured).
    fn maps_ms(c: &Candidate, i: usize, whole: bool, how: &Composition) -> f64 {
        if whole {
            return c.fixed;
        }
        let per_cycle = how.cycles as f64 / c.cycles as f64;
        let own = if how.cycled[i] { per_cycle } else { 1.0 };
        let compose = if how.composed[i] { c.compose_fixed * per_cycle } else { 0.0 };
        c.fixed * own + compose
    }

    /// Views of the whole scene the picks render (`GpuSpec::views`), `i`'s own left out:
    /// every other object's camera work and its method's kernels repeat in each. Not for a
    /// whole-scene row (measured with its views) nor for a calibration row's candidates,
    /// whose measured camera work includes them.
    fn views(&self, picks: &[&Candidate], i: Option<usize>, whole: bool) -> f64 {
        if whole {
            return 0.0;
        }
        let gpu = |m: Method| m.gpu.expect("GPU method");
        picks.iter().enumerate().filter(|(k, _)| Some(*k) != i).map(|(_, c)| (gpu(c.method).views)(&self.quality) as f64).sum()
    }

    pub(super) fn frame_ms(&self, picks: &[&Candidate], whole: bool) -> f64 {
        let how = self.composition(picks);
        (0..picks.len()).map(|i| self.own_ms(picks, i, whole, &how)).sum::<f64>()
            + self.base
            + self.kernels(picks, whole).iter().map(|(_, s)| s).sum::<f64>()
    }

    /// Object `i`'s maps and camera work, its camera work repeated in the others' views.
    fn own_ms(&self, picks: &[&Candidate], i: usize, whole: bool, how: &Composition) -> f64 {
        let c = picks[i];
        Self::maps_ms(c, i, whole, how) + c.screen * (1.0 + self.views(picks, Some(i), whole))
    }

    /// Per method its whole-screen kernels, once, repeated in the views of objects of other
    /// methods.
    fn kernels(&self, picks: &[&Candidate], whole: bool) -> Vec<(Method, f64)> {
        let mut methods: Vec<(Method, f64)> = Vec::new();
        for c in picks {
            match methods.iter_mut().find(|(m, _)| *m == c.method) {
                Some((_, s)) => *s = s.max(c.shared),
                None => methods.push((c.method, c.shared)),
            }
        }
        for (m, s) in &mut methods {
            let others: Vec<&Candidate> = picks.iter().copied().filter(|c| c.method != *m).collect();
            *s *= 1.0 + self.views(&others, None, whole);
        }
        methods
    }

    /// Object `i`'s part of the frame by pass kind: (its maps, which do not
    /// scale with the output; its camera work, repeated in the others' views, with its
    /// share of its method's whole-screen kernels).
    pub(super) fn object_parts(&self, picks: &[&Candidate], i: usize, whole: bool) -> (f64, f64) {
        let c = picks[i];
        let users = picks.iter().filter(|d| d.method == c.method).count().max(1) as f64;
        let shared = self.kernels(picks, whole).into_iter().find(|(m, _)| *m == c.method).map_or(0.0, |(_, s)| s);
        let how = self.composition(picks);
        let maps = Self::maps_ms(c, i, whole, &how);
        (maps, self.own_ms(picks, i, whole, &how) - maps + shared / users)
    }
}

/// Pixel-weighted specular PSNR of a choice.
pub(super) fn combined_psnr(picks: &[&Candidate]) -> f64 {
    let n: f64 = picks.iter().map(|c| c.pixels.max(1) as f64).sum();
    psnr_of(picks.iter().map(|c| c.pixels.max(1) as f64 * mse_of(c.psnr)).sum::<f64>() / n.max(1.0))
}

/// How a choice ranks under a budget: (meets it, score, tie-break), higher better.
pub(super) fn rank(budget: Budget, ms: f64, picks: &[&Candidate]) -> (bool, f64, f64) {
    let min_psnr = picks.iter().map(|c| c.psnr).fold(f64::INFINITY, f64::min);
    match budget {
        // Within the floor: the fastest; below it: the highest floor, then the fastest.
        Budget::MinPsnr(db) => {
            if min_psnr >= db {
                (true, -ms, 0.0)
            } else {
                (false, min_psnr, -ms)
            }
        }
        // Within the time and the floor: the fastest; else the most accurate within the
        // time, then anything over it, the fastest first.
        Budget::Near { max_ms, floor_db } => {
            let psnr = combined_psnr(picks);
            if ms <= max_ms && psnr >= floor_db {
                (true, -ms, psnr)
            } else if ms <= max_ms {
                (false, psnr, -ms)
            } else {
                (false, -1e9 - ms, psnr)
            }
        }
        // Within the time: the most accurate, then the fastest; over it: the fastest. The
        // time is the prediction times the largest under-prediction margin among the
        // picks' methods (a budget the frame holds, not one its prediction does).
        Budget::MaxMs(t) | Budget::Within(t) => {
            let margin = if matches!(budget, Budget::MaxMs(_)) { picks.iter().map(|c| c.under).fold(1.0, f64::max) } else { 1.0 };
            if ms * margin <= t {
                (true, combined_psnr(picks), -ms)
            } else {
                (false, -ms, combined_psnr(picks))
            }
        }
    }
}

pub(super) fn better(a: (bool, f64, f64), b: (bool, f64, f64)) -> bool {
    (a.0 && !b.0) || (a.0 == b.0 && (a.1 > b.1 || (a.1 == b.1 && a.2 > b.2)))
}

/// Per object one candidate index, exhaustively or greedily; `time` is the frame's.
pub(super) fn search(budget: Budget, time: &dyn Fn(&[&Candidate]) -> f64, per_object: &[Vec<Candidate>]) -> Vec<usize> {
    let eval = |idx: &[usize]| {
        let picks: Vec<&Candidate> = idx.iter().zip(per_object).map(|(&i, c)| &c[i]).collect();
        rank(budget, time(&picks), &picks)
    };
    let combos = per_object.iter().try_fold(1u64, |n, c| n.checked_mul(c.len() as u64)).unwrap_or(u64::MAX);
    if combos <= MAX_COMBINATIONS {
        let mut idx = vec![0usize; per_object.len()];
        let mut best = (idx.clone(), eval(&idx));
        loop {
            let mut k = 0;
            while k < idx.len() {
                idx[k] += 1;
                if idx[k] < per_object[k].len() {
                    break;
                }
                idx[k] = 0;
                k += 1;
            }
            if k == idx.len() {
                return best.0;
            }
            let r = eval(&idx);
            if better(r, best.1) {
                best = (idx.clone(), r);
            }
        }
    }
    // Greedy: from each object's cheapest, change one object at a time while that helps.
    let mut idx: Vec<usize> = per_object
        .iter()
        .map(|c| {
            (0..c.len())
                .min_by(|&a, &b| (c[a].fixed + c[a].screen + c[a].shared).total_cmp(&(c[b].fixed + c[b].screen + c[b].shared)))
                .unwrap_or(0)
        })
        .collect();
    let mut cur = eval(&idx);
    loop {
        let mut step = None;
        for k in 0..idx.len() {
            for i in 0..per_object[k].len() {
                let mut t = idx.clone();
                t[k] = i;
                let r = eval(&t);
                if better(r, step.as_ref().map_or(cur, |(_, s)| *s)) {
                    step = Some((t, r));
                }
            }
        }
        match step {
            Some((t, r)) => {
                idx = t;
                cur = r;
            }
            None => return idx,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plan::budget::PSNR_CAP;

    fn cand(ms: f64, psnr: f64) -> Candidate {
        Candidate {
            method: crate::methods::ENVMAP,
            fixed: 0.0,
            screen: ms,
            shared: 0.0,
            cycles: 1,
            psnr,
            pixels: 100,
            model: String::new(),
            compose_fixed: 0.0,
            under: 1.0,
        }
    }

    /// Base 1 ms plus the candidates' screen parts.
    fn time(p: &[&Candidate]) -> f64 {
        1.0 + p.iter().map(|c| c.screen).sum::<f64>()
    }

    /// Three objects × three candidates: the exhaustive search's answers, by hand.
    #[test]
    fn search_meets_floors_at_least_time_and_times_at_least_error() {
        let per = vec![
            vec![cand(1.0, 20.0), cand(2.0, 30.0), cand(5.0, 40.0)],
            vec![cand(1.0, 25.0), cand(3.0, 35.0), cand(4.0, 45.0)],
            vec![cand(0.5, 18.0), cand(1.5, 33.0), cand(6.0, 50.0)],
        ];
        // Floor 30: the cheapest per object that reaches it.
        assert_eq!(search(Budget::MinPsnr(30.0), &time, &per), [1, 1, 1]);
        // Floor 60: unreachable; the highest floor (40, 45, 50), then the fastest.
        assert_eq!(search(Budget::MinPsnr(60.0), &time, &per), [2, 2, 2]);
        // 8 ms with a 1 ms base: 7 ms for the objects; the least pixel-weighted error.
        let pick = search(Budget::MaxMs(8.0), &time, &per);
        let ms: f64 = pick.iter().zip(&per).map(|(&i, c)| c[i].screen).sum();
        assert!(ms <= 7.0, "{pick:?}");
        let mse = |p: &[usize]| p.iter().zip(&per).map(|(&i, c)| mse_of(c[i].psnr)).sum::<f64>();
        for a in 0..3 {
            for b in 0..3 {
                for c in 0..3 {
                    let t = [a, b, c];
                    let tm: f64 = t.iter().zip(&per).map(|(&i, c)| c[i].screen).sum();
                    if tm <= 7.0 {
                        assert!(mse(&pick) <= mse(&t) + 1e-15, "{t:?} beats {pick:?}");
                    }
                }
            }
        }
        // No time at all: the fastest.
        assert_eq!(search(Budget::MaxMs(0.1), &time, &per), [0, 0, 0]);
    }

    /// `--max-ms` counts a choice's time times its methods' largest margin; `Within` does not.
    #[test]
    fn a_time_budget_keeps_the_cost_models_margin() {
        // One object: a 4 ms candidate at 40 dB whose model under-predicts by 1.5×, and a
        // 5 ms one at 35 dB predicted exactly (base 1 ms).
        let per = vec![vec![Candidate { under: 1.5, ..cand(4.0, 40.0) }, cand(5.0, 35.0)]];
        // 6.5 ms: 5 × 1.5 = 7.5 over it, 6 within: the second. The prediction alone: the first.
        assert_eq!(search(Budget::MaxMs(6.5), &time, &per), [1]);
        assert_eq!(search(Budget::Within(6.5), &time, &per), [0]);
        // 8 ms: both fit with the margin; the more accurate.
        assert_eq!(search(Budget::MaxMs(8.0), &time, &per), [0]);
    }

    /// A mirror on proxy-relief beside a glass ball on refractor-map that sees it: the frame
    /// composes (two cycles); the relief's height maps are drawn once, the distance map
    /// composition gives the mirror once per cycle, as are the maps of methods that have
    /// distance cubes of their own (refractor-map's, distance's); one method everywhere,
    /// asked for by nobody: the whole-scene method, as measured.
    #[test]
    fn maps_drawn_once_a_frame_are_not_counted_per_cycle() {
        use crate::methods::{DISTANCE, PROXY_RELIEF, REFRACTOR_MAP};
        use crate::scene::{shapes, Material, Scene, SurfaceKind};
        use glam::Vec3;
        let mut scene = Scene::new();
        let wall = scene.add_material(Material { emissive: Vec3::ONE, ..Default::default() }).unwrap();
        scene.add_mesh(shapes::cuboid("room", Vec3::ZERO, Vec3::splat(3.0), wall)).unwrap();
        let glass = scene.add_material(Material { kind: SurfaceKind::Dielectric { ior: 1.5, thin: false }, ..Default::default() }).unwrap();
        let mirror = scene
            .add_material(Material { kind: SurfaceKind::Mirror { nu: Vec3::splat(37.0), kappa: Vec3::ZERO }, ..Default::default() })
            .unwrap();
        scene.add_mesh(shapes::uv_sphere("glass", Vec3::new(-0.8, 0.0, 0.0), 0.5, 16, 8, glass)).unwrap();
        scene.add_mesh(shapes::uv_sphere("mirror", Vec3::new(0.8, 0.0, 0.0), 0.5, 16, 8, mirror)).unwrap();
        let q = crate::quality::Quality::default();
        let facts = crate::plan::facts::SceneFacts::new(&scene, &q, true);
        let timing = Timing { base: 0.0, quality: q, facts: &facts, sight: facts.sight() };
        let on = |m, fixed| Candidate { method: m, fixed, compose_fixed: 4.0, ..cand(0.0, 30.0) };
        let (glass_map, relief, distance) = (on(REFRACTOR_MAP, 10.0), on(PROXY_RELIEF, 10.0), on(DISTANCE, 10.0));
        let how = timing.composition(&[&glass_map, &relief]);
        assert_eq!((how.cycles, how.composed.clone(), how.cycled.clone()), (2, vec![false, true], vec![true, false]));
        assert_eq!(timing.object_parts(&[&glass_map, &relief], 1, false).0, 10.0 + 2.0 * 4.0);
        let how = timing.composition(&[&glass_map, &distance]);
        assert_eq!((how.cycles, how.cycled[1]), (2, true));
        assert_eq!(timing.object_parts(&[&glass_map, &distance], 1, false).0, 2.0 * 10.0 + if how.composed[1] { 8.0 } else { 0.0 });
        assert_eq!(timing.frame_ms(&[&relief, &relief], false), 20.0);
    }

    #[test]
    fn combined_psnr_weights_by_pixels() {
        let a = Candidate { pixels: 300, ..cand(1.0, 20.0) };
        let b = Candidate { pixels: 100, ..cand(1.0, 40.0) };
        // MSE 0.01 on 300 px and 0.0001 on 100: mean 0.007525.
        assert!((combined_psnr(&[&a, &b]) - -10.0 * 0.007525f64.log10()).abs() < 1e-9);
        assert_eq!(psnr_of(0.0), PSNR_CAP);
    }
}
