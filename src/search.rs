//! Ray tracing in a distance map (survey §4.1), twin of `glsl/common/search.glsl`: the same
//! functions under the same names, in f64. The CPU side serves the tests (analytic maps,
//! convergence, the extremes) and documents what the shaders do.

use glam::DVec3;

/// Stored distances at or beyond this are "nothing there": the environment at infinity.
pub const SEARCH_SKY: f64 = 1e19;

/// What a distance map answers: the Euclidean distance from its reference point of the
/// surface seen in direction `dir` (not normalised).
pub trait DistanceMap {
    fn distance(&self, dir: DVec3) -> f64;
}

impl<F: Fn(DVec3) -> f64> DistanceMap for F {
    fn distance(&self, dir: DVec3) -> f64 {
        self(dir)
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SearchResult {
    /// Ray parameter of the hit (when not escaped).
    pub d: f64,
    /// Direction, from the reference point, whose texel holds the hit.
    pub dir: DVec3,
    /// No surface: the ray leaves to the environment at infinity.
    pub escaped: bool,
    /// Distance-map fetches spent.
    pub lookups: u32,
}

#[allow(clippy::neg_cmp_op_on_partial_ord)] // NaN counts as sky
pub fn search_is_sky(stored: f64) -> bool {
    !(stored < SEARCH_SKY)
}

fn search_ratio(map: &impl DistanceMap, x: DVec3, r: DVec3, d: f64, lookups: &mut u32) -> f64 {
    let l = x + r * d;
    let len = l.length();
    if len <= 0.0 {
        return 0.0;
    }
    *lookups += 1;
    let stored = map.distance(l);
    if search_is_sky(stored) {
        return 0.0;
    }
    len / stored.max(1e-300)
}

fn search_result(x: DVec3, r: DVec3, d: f64, escaped: bool, lookups: u32) -> SearchResult {
    let mut dir = if escaped { r } else { x + r * d };
    if !escaped && dir.length_squared() <= 0.0 {
        dir = r;
    }
    SearchResult { d, dir, escaped, lookups }
}

/// Parallax correction (survey eq. 4), iterated (§4.1.1).
pub fn parallax_search(map: &impl DistanceMap, x: DVec3, r: DVec3, iterations: u32) -> SearchResult {
    let mut lookups = 1;
    let stored = map.distance(r);
    if search_is_sky(stored) {
        return search_result(x, r, 0.0, true, lookups);
    }
    let mut d = (stored - r.dot(x)).max(0.0);
    for _ in 1..iterations {
        let l = x + r * d;
        let len = l.length();
        if len <= 0.0 {
            break;
        }
        lookups += 1;
        let s = map.distance(l);
        if search_is_sky(s) {
            break;
        }
        d = (r.dot(l / len) * s - r.dot(x)).max(0.0);
    }
    search_result(x, r, d, false, lookups)
}

/// Linear search on the projected segment, d(t) = |x| t/(1−t) (§4.1.2), then binary
/// (§4.1.4) and secant (eq. 5, §4.1.3) refinement with early exit at `tolerance`.
pub fn linear_search(
    map: &impl DistanceMap,
    x: DVec3,
    r: DVec3,
    steps: u32,
    binary_steps: u32,
    secant_steps: u32,
    tolerance: f64,
) -> SearchResult {
    let mut lookups = 1;
    let len_x = x.length();
    let far_stored = map.distance(r);
    // From the reference point the map answers exactly. Off it, an empty far end does not
    // end the search: the ray may meet a surface on the way (an open scene's floor seen
    // past a sphere's horizon).
    if len_x <= 0.0 || (!search_is_sky(far_stored) && len_x <= 1e-6 * far_stored) {
        if search_is_sky(far_stored) {
            return search_result(x, r, 0.0, true, lookups);
        }
        return search_result(x, r, far_stored, false, lookups);
    }
    let (mut d_l, mut a_l) = (0.0, search_ratio(map, x, r, 0.0, &mut lookups));
    if a_l >= 1.0 {
        return search_result(x, r, 0.0, false, lookups);
    }
    let (mut d_p, mut a_p) = (-1.0, 0.0);
    let steps = steps.max(1);
    for i in 1..=steps {
        let (d, a);
        if i < steps {
            let t = i as f64 / steps as f64;
            d = len_x * t / (1.0 - t);
            a = search_ratio(map, x, r, d, &mut lookups);
        } else {
            let far = (!search_is_sky(far_stored)).then(|| search_far_end(map, x, r, far_stored, &mut d_l, &mut a_l, &mut lookups));
            let Some(Some((dd, aa))) = far else { return search_result(x, r, 0.0, true, lookups) };
            (d, a) = (dd, aa);
        }
        if (a - 1.0).abs() <= tolerance {
            return search_result(x, r, d, false, lookups);
        }
        if a > 1.0 {
            (d_p, a_p) = (d, a);
            break;
        }
        (d_l, a_l) = (d, a);
    }
    if d_p < 0.0 {
        return search_result(x, r, 0.0, true, lookups);
    }
    let (d, _) = search_refine(map, x, r, [(d_l, a_l), (d_p, a_p)], binary_steps, secant_steps, tolerance, &mut lookups);
    search_result(x, r, d, false, lookups)
}

/// The ray's end at infinity with something seen there: the parallax estimate pushed out
/// until it overshoots, moving the undershooting end along; `None`: it never does. Twin of
/// `search_far_end` in glsl/common/search.glsl.
fn search_far_end(
    map: &impl DistanceMap,
    x: DVec3,
    r: DVec3,
    far_stored: f64,
    d_l: &mut f64,
    a_l: &mut f64,
    lookups: &mut u32,
) -> Option<(f64, f64)> {
    let len_x = x.length();
    let mut d = (far_stored - r.dot(x)).max(*d_l);
    let mut a = search_ratio(map, x, r, d, lookups);
    let mut k = 0;
    while k < 8 && a < 1.0 {
        (*d_l, *a_l) = (d, a);
        d = 2.0 * d + len_x + far_stored;
        a = search_ratio(map, x, r, d, lookups);
        k += 1;
    }
    (a >= 1.0).then_some((d, a))
}

/// Refinement of a bracket whose ratios lie on either side of 1: `binary_steps` halvings
/// (§4.1.4), then `secant_steps` false-position steps (survey eq. 5). A probe within
/// tolerance is the answer, else it replaces the bracket end on its side; at the end, the
/// better end of the bracket. Also returns the final bracket.
type Bracket = [(f64, f64); 2];
#[allow(clippy::too_many_arguments)]
fn search_refine(
    map: &impl DistanceMap,
    x: DVec3,
    r: DVec3,
    [(mut d_l, mut a_l), (mut d_p, mut a_p)]: Bracket,
    binary_steps: u32,
    secant_steps: u32,
    tolerance: f64,
    lookups: &mut u32,
) -> (f64, Bracket) {
    for i in 0..binary_steps + secant_steps {
        let den = a_p - a_l;
        let d = if i < binary_steps {
            0.5 * (d_l + d_p)
        } else {
            d_l + (d_p - d_l) * (1.0 - a_l) / if den.abs() > 1e-300 { den } else { 1e-300 }
            // survey eq. 5
        };
        let a = search_ratio(map, x, r, d, lookups);
        if (a - 1.0).abs() <= tolerance {
            return (d, [(d_l, a_l), (d_p, a_p)]);
        }
        if (a < 1.0) == (a_l < 1.0) {
            (d_l, a_l) = (d, a);
        } else {
            (d_p, a_p) = (d, a);
        }
    }
    let d = if (a_l - 1.0).abs() < (a_p - 1.0).abs() { d_l } else { d_p };
    (d, [(d_l, a_l), (d_p, a_p)])
}

/// One layer of a multi-layer map (survey §4.5): the first crossing of the layer's surface
/// in either direction, on the linear search's steps; `start_side` (+1 behind the surface,
/// −1 in front, 0 measured) for a ray that starts on this layer's surface; a bracket is a
/// hit only if the refined point, or else the false-position point of the final bracket,
/// lies within `gap` of the surface (silhouettes are gaps, the march goes on). Twin of
/// `layer_search` in glsl/common/search.glsl.
#[allow(clippy::too_many_arguments)]
pub fn layer_search(
    map: &impl DistanceMap,
    x: DVec3,
    r: DVec3,
    steps: u32,
    binary_steps: u32,
    secant_steps: u32,
    tolerance: f64,
    gap: f64,
    start_side: i32,
) -> SearchResult {
    let mut lookups = 1;
    let len_x = x.length();
    let far_stored = map.distance(r);
    // A sparse layer is empty in many directions: an empty far end does not end the march.
    if len_x <= 0.0 || (!search_is_sky(far_stored) && len_x <= 1e-6 * far_stored) {
        if search_is_sky(far_stored) || start_side != 0 {
            return search_result(x, r, 0.0, true, lookups);
        }
        return search_result(x, r, far_stored, false, lookups);
    }
    let (mut d_l, mut a_l) = (0.0, search_ratio(map, x, r, 0.0, &mut lookups));
    if start_side != 0 {
        a_l = if start_side > 0 { 2.0 } else { 0.0 };
    }
    let steps = steps.max(1);
    for i in 1..=steps {
        let (d, a);
        if i < steps {
            let t = i as f64 / steps as f64;
            d = len_x * t / (1.0 - t);
            a = search_ratio(map, x, r, d, &mut lookups);
        } else {
            let far =
                (!search_is_sky(far_stored) && a_l < 1.0).then(|| search_far_end(map, x, r, far_stored, &mut d_l, &mut a_l, &mut lookups));
            let Some(Some((dd, aa))) = far else { return search_result(x, r, 0.0, true, lookups) };
            (d, a) = (dd, aa);
        }
        if (a < 1.0) != (a_l < 1.0) {
            let (h, [(e0, b0), (e1, b1)]) =
                search_refine(map, x, r, [(d_l, a_l), (d, a)], binary_steps, secant_steps, tolerance, &mut lookups);
            if (search_ratio(map, x, r, h, &mut lookups) - 1.0).abs() <= gap {
                return search_result(x, r, h, false, lookups);
            }
            let den = b1 - b0;
            let at = if den.abs() > 1e-30 { e0 + (e1 - e0) * (1.0 - b0) / den } else { h };
            if (search_ratio(map, x, r, at, &mut lookups) - 1.0).abs() <= gap {
                return search_result(x, r, at, false, lookups);
            }
        }
        (d_l, a_l) = (d, a);
    }
    search_result(x, r, 0.0, true, lookups)
}

/// The distance map of an axis-aligned box room seen from `center` (inside it).
pub fn box_room(min: DVec3, max: DVec3, center: DVec3) -> impl Fn(DVec3) -> f64 {
    move |dir: DVec3| {
        let d = dir.normalize();
        let mut t = f64::INFINITY;
        for a in 0..3 {
            if d[a] > 0.0 {
                t = t.min((max[a] - center[a]) / d[a]);
            } else if d[a] < 0.0 {
                t = t.min((min[a] - center[a]) / d[a]);
            }
        }
        t
    }
}

/// Exact ray parameter where x + R d leaves the box (the reference answer for `box_room`).
pub fn box_exit(min: DVec3, max: DVec3, center: DVec3, x: DVec3, r: DVec3) -> f64 {
    let o = center + x;
    let mut t = f64::INFINITY;
    for a in 0..3 {
        if r[a] > 0.0 {
            t = t.min((max[a] - o[a]) / r[a]);
        } else if r[a] < 0.0 {
            t = t.min((min[a] - o[a]) / r[a]);
        }
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    fn room() -> (DVec3, DVec3, DVec3) {
        (DVec3::new(-2.0, 0.0, -2.0), DVec3::new(2.0, 3.0, 2.0), DVec3::new(0.0, 1.5, 0.0))
    }

    fn rays() -> Vec<(DVec3, DVec3)> {
        let mut v = Vec::new();
        for i in 0..40 {
            let a = i as f64 * 0.61;
            let x = DVec3::new(1.3 * a.cos(), 0.9 * (a * 1.7).sin(), 1.2 * (a * 0.3).sin());
            let r = DVec3::new((a * 2.3).cos(), (a * 1.1).sin(), (a * 0.7).cos()).normalize();
            v.push((x, r));
        }
        v
    }

    #[test]
    fn secant_error_falls_monotonically_in_a_convex_room() {
        let (min, max, c) = room();
        let map = box_room(min, max, c);
        for (x, r) in rays() {
            let exact = box_exit(min, max, c, x, r);
            let mut last = f64::INFINITY;
            for secant in [0, 1, 2, 4, 8] {
                let s = linear_search(&map, x, r, 8, 0, secant, 0.0);
                let err = ((c + x + r * s.d) - (c + x + r * exact)).length();
                assert!(err <= last + 1e-9, "secant {secant}: error {err} rose from {last}");
                last = err;
            }
            // False position keeps one end fixed: linear, not quadratic, convergence; 8 steps
            // reach 0.1 mm, far below a texel of a 256² map at 2 m (≈ 1.5 cm).
            assert!(last < 1e-4, "8 secant steps reach 0.1 mm: {last}");
        }
    }

    #[test]
    fn parallax_is_exact_for_a_sphere_room_seen_from_its_centre_direction() {
        // A sphere room and a ray from the reference point's neighbourhood: eq. 4 assumes a
        // perpendicular plane; iterating converges towards the exact hit.
        let map = |_: DVec3| 3.0;
        let x = DVec3::new(0.5, 0.2, -0.1);
        let r = DVec3::new(0.3, 0.9, 0.1).normalize();
        let exact = {
            let b = x.dot(r);
            -b + (b * b - (x.length_squared() - 9.0)).sqrt()
        };
        let e = |n: u32| (parallax_search(&map, x, r, n).d - exact).abs();
        let (e1, e2, e4) = (e(1), e(2), e(4));
        // Measured 3.1e-2, 6.4e-4 and 2.8e-7: each count runs exactly that many iterations
        // (one more or one fewer lands in another band).
        assert!(e1 > 1e-2 && e1 < 1e-1, "1 iteration: {e1}");
        assert!(e2 > 1e-4 && e2 < 2e-3, "2 iterations: {e2}");
        assert!(e4 > 1e-8 && e4 < 1e-6, "4 iterations: {e4}");
    }

    #[test]
    fn an_empty_far_end_does_not_end_the_search() {
        // An open scene: a fence, the strip x = 3, |y| ≤ 1, around the reference point at the
        // origin, sky everywhere else. Direction r = (1, 0.5, 0) passes over the fence seen
        // from the reference point (the map stores sky there), but the ray from x = (0, −1, 0)
        // along r meets it at y = 0.5: the search must find it, not stop at the empty far end.
        let fence = |dir: DVec3| {
            let dir = dir.normalize();
            let t = 3.0 / dir.x;
            if dir.x > 0.0 && (t * dir.y).abs() <= 1.0 {
                t
            } else {
                f64::INFINITY
            }
        };
        let x = DVec3::new(0.0, -1.0, 0.0);
        let r = DVec3::new(1.0, 0.5, 0.0).normalize();
        assert!(search_is_sky(fence.distance(r)));
        let exact = 3.0 / r.x;
        let s = linear_search(&fence, x, r, 16, 0, 8, 0.0);
        assert!(!s.escaped && ((s.d - exact) / exact).abs() < 1e-3, "{s:?} vs {exact}");
        // Steeper, the ray passes over the fence from x too: it escapes.
        let steep = DVec3::new(1.0, 1.0, 0.0).normalize();
        assert!(linear_search(&fence, x, steep, 16, 0, 8, 0.0).escaped);
        // From the reference point itself the map answers at once (one lookup).
        let s0 = linear_search(&fence, DVec3::ZERO, r, 16, 0, 8, 0.0);
        assert!(s0.escaped && s0.lookups == 1, "{s0:?}");
    }

    #[test]
    fn extremes_of_the_search() {
        let (min, max, c) = room();
        let map = box_room(min, max, c);
        // Ray starting at the reference point: the map is exact.
        let r = DVec3::new(0.2, 0.5, -0.8).normalize();
        let s = linear_search(&map, DVec3::ZERO, r, 8, 0, 4, 0.0);
        assert!((s.d - box_exit(min, max, c, DVec3::ZERO, r)).abs() < 1e-12);
        // A ray through the reference point (pointing at it): finds the far wall.
        let x = DVec3::new(0.8, 0.3, 0.4);
        let r = -x.normalize();
        let s = linear_search(&map, x, r, 16, 0, 8, 1e-9);
        assert!((s.d - box_exit(min, max, c, x, r)).abs() < 1e-6, "{s:?}");
        assert!(s.d.is_finite() && s.dir.is_finite());
        // Rays along the axes (cube-face centres) and along face diagonals (face edges).
        for r in [DVec3::X, DVec3::NEG_Y, DVec3::new(1.0, 1.0, 0.0).normalize(), DVec3::new(1.0, 1.0, 1.0).normalize()] {
            let x = DVec3::new(0.1, -0.2, 0.3);
            let s = linear_search(&map, x, r, 16, 0, 8, 1e-9);
            assert!((s.d - box_exit(min, max, c, x, r)).abs() < 1e-4, "{r}: {s:?}");
        }
        // A very distant wall (1e4 m) and a very near one (1 mm).
        for (lo, hi) in [(DVec3::splat(-1e4), DVec3::splat(1e4)), (DVec3::new(-1e-3, -1.0, -1.0), DVec3::splat(1.0))] {
            let map = box_room(lo, hi, DVec3::ZERO);
            let x = DVec3::new(0.0, 0.1, 0.05) * if hi.x > 1.0 { 100.0 } else { 1e-4 };
            let r = DVec3::new(-1.0, 0.2, 0.1).normalize();
            let s = linear_search(&map, x, r, 16, 0, 16, 1e-12);
            let exact = box_exit(lo, hi, DVec3::ZERO, x, r);
            assert!((s.d - exact).abs() <= 1e-6 * exact.max(1e-3), "{lo}: {} vs {exact}", s.d);
        }
        // Nothing in that direction: the ray escapes to the environment.
        let sky = |_: DVec3| f64::INFINITY;
        let s = linear_search(&sky, DVec3::new(0.3, 0.0, 0.0), DVec3::Y, 8, 2, 2, 0.0);
        assert!(s.escaped && s.dir == DVec3::Y);
        assert!(parallax_search(&sky, DVec3::X, DVec3::Y, 3).escaped);
    }

    /// Two layers of nested spheres around the origin (radius 1 and 2): a ray from inside
    /// the inner one hits it (layer 0) and, continuing, the outer one (layer 1); a ray
    /// starting on the inner sphere, told it leaves outwards, does not find it again; a
    /// ray from outside crosses the inner sphere inwards (behind → in front).
    #[test]
    fn layer_search_crosses_either_way_and_skips_its_origin() {
        let inner = |_: DVec3| 1.0;
        let outer = |_: DVec3| 2.0;
        let x = DVec3::new(0.3, 0.1, 0.0);
        let r = DVec3::new(0.2, 1.0, 0.4).normalize();
        let exit = |radius: f64| -x.dot(r) + (x.dot(r).powi(2) - x.length_squared() + radius * radius).sqrt();
        for (map, radius) in [(&inner as &dyn Fn(DVec3) -> f64, 1.0), (&outer, 2.0)] {
            let h = layer_search(&map, x, r, 16, 0, 8, 1e-6, 0.05, 0);
            assert!(!h.escaped && (h.d - exit(radius)).abs() < 1e-4, "{h:?} vs {}", exit(radius));
        }
        // Leaving the inner sphere outwards from its surface: no second hit on it.
        let on = DVec3::new(0.0, 1.0, 0.0);
        let out = DVec3::new(0.3, 1.0, 0.0).normalize();
        assert!(layer_search(&inner, on, out, 16, 0, 8, 1e-6, 0.05, 1).escaped);
        // From outside, inwards: the crossing from behind the layer's surface to in front.
        let o = DVec3::new(0.0, 1.5, 0.0);
        let h = layer_search(&inner, o, DVec3::NEG_Y, 16, 0, 8, 1e-6, 0.05, 0);
        assert!(!h.escaped && (h.d - 0.5).abs() < 1e-4, "{h:?}");
    }
}
