//! Dielectrics whose index varies in space (survey §6.5: curved rays in varying media, after
//! Gröller 1995, Ihrke et al. 2007 and Weyrich et al. 2004): the field, and the ray
//! equation integrated through it.
//!
//! In a medium of index n(x) a ray obeys d/ds(n dx/ds) = ∇n (s the arc length). With the
//! optical parameter τ (ds = n dτ) and v = n dx/ds (|v| = n) that is the first-order system
//!
//! ```text
//!     dx/dτ = v,    dv/dτ = n ∇n = ½ ∇(n²),
//! ```
//!
//! which specula integrates by the classical fourth-order Runge–Kutta scheme, one step of
//! dτ = h / n(x) per chord, |v| = n(x) imposed again after each step (the invariant the
//! scheme only keeps to its order). The arc length h of a step is where the ray turns by at
//! most `turn` radians: h = turn · min(n / |∇n|, √(2n / ‖H‖)) (the gradient's bending, and
//! how far the gradient itself may grow by the Hessian H), so that the accuracy knob is an
//! angle and the step follows the scene's scale (1 mm and 1 km scenes take the same steps).
//! Between steps the ray is the chord x_k → x_{k+1}, tested against the geometry for the
//! first hit; a hit ends the march there (its point and the chord's direction are where the
//! ray meets the surface). The GPU's twin is `glsl/common/medium.glsl`, in f32.

use glam::{DMat3, DVec3, Vec3};

/// The index field of a solid dielectric (issue 36 item 7): in world space,
///
/// ```text
///     n(x) = ior + g · (x − o) + ½ (x − o)ᵀ H (x − o),
/// ```
///
/// `ior` the material's index at the origin o, g the gradient there and H the (symmetric)
/// Hessian: a linear gradient (a mirage layer over a hot floor: n rising with height), a
/// radial graded-index lens (H = −k (I − a aᵀ) about the axis a: n falling off the axis
/// quadratically) or any quadratic field. Fixed in the world: an object moved carries its
/// surface, not its field. Below [`MIN_INDEX`] (outside the objects, where validation does
/// not look) the index is clamped.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GradedIndex {
    pub origin: Vec3,
    pub gradient: Vec3,
    /// Rows of the symmetric Hessian H [1/m²].
    pub hessian: [Vec3; 3],
}

/// The least index a field evaluates to (where validation did not look).
pub const MIN_INDEX: f64 = 1e-3;

/// How far a ray may turn in a medium, in steps of `turn` radians, before it is given up
/// as lost (black: a ray trapped in a graded-index fibre, or in a medium that is not
/// closed): at most ⌈MAX_TURN / turn⌉ chords (1024 at the GPU's default turn of 0.05).
pub const MAX_TURN: f64 = 51.2;

/// The chords a march at `turn` may take ([`MAX_TURN`]).
pub fn max_steps(turn: f64) -> u32 {
    (MAX_TURN / turn).ceil().clamp(1.0, 1e7) as u32
}

/// The reference's turn per step [rad]: fine enough that RK4's error (∝ turn⁴ per radian of
/// bending) lies below f64's rounding over every path the tests take.
pub const REFERENCE_TURN: f64 = 2e-3;

/// The reference's refinements of the chord that hits ([`GradedIndex::march`]): its
/// sagitta shrinks by [`REFINE`]² each, 2.6·10⁵ in all.
pub const REFERENCE_REFINE: u32 = 3;

impl GradedIndex {
    /// A radial graded-index profile about the axis through `origin` along `axis`: n falls
    /// off by ½ k r² at distance r from the axis (H = −k (I − a aᵀ), a the unit axis).
    pub fn radial_hessian(axis: Vec3, k: f32) -> [Vec3; 3] {
        let a = axis.normalize_or_zero();
        let m = glam::Mat3::IDENTITY - glam::Mat3::from_cols(a * a.x, a * a.y, a * a.z);
        [m.row(0) * -k, m.row(1) * -k, m.row(2) * -k]
    }

    fn hessian64(&self) -> DMat3 {
        DMat3::from_cols(self.hessian[0].as_dvec3(), self.hessian[1].as_dvec3(), self.hessian[2].as_dvec3()).transpose()
    }

    /// n(p) and ∇n(p), n given at the origin (`ior`).
    pub fn index(&self, ior: f64, p: DVec3) -> (f64, DVec3) {
        let d = p - self.origin.as_dvec3();
        let hd = self.hessian64() * d;
        (self.unclamped(ior, p).max(MIN_INDEX), self.gradient.as_dvec3() + hd)
    }

    /// The quadratic's value at p, unclamped (validation's check that it stays > 0).
    pub fn unclamped(&self, ior: f64, p: DVec3) -> f64 {
        let d = p - self.origin.as_dvec3();
        ior + self.gradient.as_dvec3().dot(d) + 0.5 * d.dot(self.hessian64() * d)
    }

    /// The Frobenius norm of H (the step rule's bound on how fast ∇n changes).
    pub fn hessian_norm(&self) -> f64 {
        self.hessian.iter().map(|r| r.as_dvec3().length_squared()).sum::<f64>().sqrt()
    }

    /// Finite numbers and a symmetric Hessian; `Err(field, why)`.
    pub fn check(&self) -> std::result::Result<(), (&'static str, String)> {
        if !self.origin.is_finite() {
            return Err(("graded_index.origin", format!("must be finite, got {}", self.origin)));
        }
        if !self.gradient.is_finite() {
            return Err(("graded_index.gradient", format!("must be finite, got {}", self.gradient)));
        }
        let h = self.hessian;
        if !h.iter().all(|r| r.is_finite()) {
            return Err(("graded_index.hessian", format!("must be finite, got rows {} {} {}", h[0], h[1], h[2])));
        }
        let asym = (h[0].y - h[1].x).abs().max((h[0].z - h[2].x).abs()).max((h[1].z - h[2].y).abs());
        let scale = h.iter().map(|r| r.abs().max_element()).fold(0.0f32, f32::max);
        if asym > 1e-6 * scale.max(f32::MIN_POSITIVE) {
            return Err(("graded_index.hessian", format!("must be symmetric, got rows {} {} {}", h[0], h[1], h[2])));
        }
        Ok(())
    }

    /// Arc length of one step at p (index n, gradient g): where the ray turns by at most
    /// `turn` radians; infinite in a uniform field (the chord is the ray).
    pub fn step_length(&self, n: f64, g: DVec3, turn: f64) -> f64 {
        let by_gradient = turn * n / g.length();
        let h = self.hessian_norm();
        let by_hessian = (2.0 * turn * n / h).sqrt();
        by_gradient.min(by_hessian)
    }

    /// One classical RK4 step of dτ on (x, v), |v| = n(x) imposed after it.
    pub fn rk4(&self, ior: f64, x: DVec3, v: DVec3, dtau: f64) -> (DVec3, DVec3) {
        let acc = |p: DVec3| {
            let (n, g) = self.index(ior, p);
            n * g
        };
        let (k1x, k1v) = (v, acc(x));
        let (k2x, k2v) = (v + 0.5 * dtau * k1v, acc(x + 0.5 * dtau * k1x));
        let (k3x, k3v) = (v + 0.5 * dtau * k2v, acc(x + 0.5 * dtau * k2x));
        let (k4x, k4v) = (v + dtau * k3v, acc(x + dtau * k3x));
        let x1 = x + dtau / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
        let v1 = v + dtau / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
        let n1 = self.index(ior, x1).0;
        (x1, v1.normalize_or(v.normalize()) * n1)
    }

    /// Marches the ray leaving `o` along `d` through the field, chord by chord, until
    /// `hit(origin, unit direction, t_max, first)` reports a hit on a chord (`first`: the
    /// chord that starts on the surface the ray leaves). The chord that hits is then marched
    /// again `refine` times, each at a [`REFINE`]th of the turn (a chord's sagitta, h²κ/8,
    /// is the march's error at the surface: RK4's nodes are far closer to the curve), so
    /// that the hit lies on a chord of the finest level. Returns the last chord's origin and
    /// direction, the path length before it, and its hit (`None`: in a uniform field, where
    /// the one chord is unbounded, the ray left the scene); `None` when the ray is lost
    /// ([`max_steps`] chords without a hit).
    pub fn march<H>(
        &self,
        ior: f64,
        o: DVec3,
        d: DVec3,
        turn: f64,
        refine: u32,
        mut hit: impl FnMut(DVec3, DVec3, f64, bool) -> Option<H>,
    ) -> Option<March<Option<H>>> {
        let (mut x, mut v) = (o, d.normalize() * self.index(ior, o).0);
        let (mut turn, mut level) = (turn, 0);
        let (mut before, mut budget) = (0.0, f64::INFINITY);
        let mut coarse: Option<March<Option<H>>> = None;
        let mut first = true;
        for _ in 0..max_steps(turn) + refine * 4 * REFINE as u32 {
            if before > budget {
                break; // a refinement that missed what its chord hit (rounding): keep that
            }
            let (n, g) = self.index(ior, x);
            let h = self.step_length(n, g, turn);
            if !h.is_finite() {
                let dir = v.normalize();
                return Some(March { hit: hit(x, dir, f64::INFINITY, first), origin: x, dir, before });
            }
            let (x1, v1) = self.rk4(ior, x, v, h / n);
            let chord = x1 - x;
            let len = chord.length();
            if len > 0.0 {
                let dir = chord / len;
                if let Some(found) = hit(x, dir, len * (1.0 + 1e-9), first) {
                    let m = March { hit: Some(found), origin: x, dir, before };
                    if level == refine {
                        return Some(m);
                    }
                    // March this chord again, finer, from its start.
                    (level, turn, budget) = (level + 1, turn / REFINE, before + 1.5 * len);
                    coarse = Some(m);
                    continue;
                }
            }
            before += len;
            (x, v) = (x1, v1);
            first = false;
        }
        coarse
    }
}

/// How much finer each refinement of the chord that hits marches ([`GradedIndex::march`]).
pub const REFINE: f64 = 8.0;

/// Where a march ended: the hit on its last chord, that chord's origin and unit direction,
/// and the path length before it.
#[derive(Clone, Copy, Debug)]
pub struct March<H> {
    pub hit: H,
    pub origin: DVec3,
    pub dir: DVec3,
    pub before: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn linear(g: f32) -> GradedIndex {
        GradedIndex { origin: Vec3::ZERO, gradient: Vec3::new(0.0, g, 0.0), hessian: [Vec3::ZERO; 3] }
    }

    /// Where the ray launched horizontally at height 0 along +x, in n(y) = n0 + g y, crosses
    /// the plane x = X: the closed form. Snell's invariant n cos θ = n0 makes the path the
    /// catenary n0 + g y = n0 cosh(g x / n0), a parabola y ≈ g x² / (2 n0) near its vertex.
    fn catenary(n0: f64, g: f64, x: f64) -> f64 {
        n0 * ((g * x / n0).cosh() - 1.0) / g
    }

    /// March a ray to the plane x = `plane` (the "hit" test of the chords is the plane).
    fn to_plane(f: &GradedIndex, n0: f64, o: DVec3, d: DVec3, plane: f64, turn: f64) -> DVec3 {
        f.march(n0, o, d, turn, REFERENCE_REFINE, |p, dir, t_max, _| {
            let t = (plane - p.x) / dir.x;
            (dir.x > 0.0 && t >= 0.0 && t <= t_max).then(|| p + dir * t)
        })
        .and_then(|m| m.hit)
        .expect("the ray reaches the plane")
    }

    #[test]
    fn a_linear_gradient_bends_the_ray_onto_the_catenary() {
        // A graded slab (n from 1.2 to 1.7 over 1 m): the ray bends up, towards higher
        // index, along the closed form; the chord error falls with RK4's order.
        let (n0, g) = (1.2, 0.5);
        let f = linear(g as f32);
        let exact = catenary(n0, g, 1.0);
        assert!(exact > 0.15, "the path bends visibly: {exact}");
        let at = |turn| to_plane(&f, n0, DVec3::ZERO, DVec3::X, 1.0, turn).y;
        let fine = (at(REFERENCE_TURN) - exact).abs();
        assert!(fine < 1e-9, "the reference's march lands on the catenary: off by {fine:e} m");
        // RK4's nodes (the chords' ends) follow the curve to the scheme's order; between them
        // the ray is the chord, off the curve by at most its sagitta h²κ/8.
        let nodes = |turn: f64| {
            let mut worst = 0.0f64;
            f.march(n0, DVec3::ZERO, DVec3::X, turn, 0, |p, dir, t_max, _| {
                worst = worst.max((p.y - catenary(n0, g, p.x)).abs());
                let t = (1.0 - p.x) / dir.x;
                (t >= 0.0 && t <= t_max).then_some(())
            });
            worst
        };
        let (coarse, half) = (nodes(0.1), nodes(0.05));
        assert!(coarse < 1e-5, "a 0.1 rad step's nodes stay on the curve: {coarse:e} m");
        assert!(half < coarse / 8.0, "halving the turn shrinks the nodes' error by RK4's order: {coarse:e} → {half:e}");
        let h = 0.1 * n0 / g;
        let sagitta = h * h * (g / n0) / 8.0;
        assert!((at(0.1) - exact).abs() < sagitta + coarse, "the hit lies on a chord: {:e} against {sagitta:e}", (at(0.1) - exact).abs());
        // A uniform field leaves the ray straight (one infinite chord).
        let flat = GradedIndex { gradient: Vec3::ZERO, ..f };
        assert!(to_plane(&flat, n0, DVec3::ZERO, DVec3::X, 1.0, 0.05).y.abs() < 1e-12);
    }

    #[test]
    fn mirage_rays_turn_back_up_below_the_invariant() {
        // n = 1 + 0.05 y over a hot floor (y < 0 lower index): a ray heading down at angle
        // θ below the horizontal turns where n(y) = n(0) cos θ and climbs back symmetrically.
        let f = linear(0.05);
        let theta: f64 = 0.1;
        let d = DVec3::new(theta.cos(), -theta.sin(), 0.0);
        let lowest = (theta.cos() - 1.0) / 0.05; // n(y) = cos θ
        let mut min_y = 0.0f64;
        let m = f
            .march(1.0, DVec3::ZERO, d, REFERENCE_TURN, REFERENCE_REFINE, |p, dir, t_max, first| {
                min_y = min_y.min(p.y);
                // the plane y = 0 again, met from below
                let t = -p.y / dir.y;
                (!first && dir.y > 0.0 && t >= 0.0 && t <= t_max).then(|| p + dir * t)
            })
            .expect("the ray comes back up");
        let hit = m.hit.expect("a hit");
        assert!((min_y - lowest).abs() < 1e-4, "turning point {min_y} against {lowest}");
        // Back at y = 0 at x = 2 (n0/g) asinh-free form: x = 2 (α/g) acosh(1/α)… by symmetry
        // at twice the turning point's x, with the launch angle mirrored.
        let x_turn = (1.0 / 0.05) * theta.cos() * (1.0 / theta.cos()).acosh();
        assert!((hit.x - 2.0 * x_turn).abs() < 1e-6, "lands at {} against {}", hit.x, 2.0 * x_turn);
        assert!((m.dir.y - theta.sin()).abs() < 1e-3, "leaves at the mirrored angle: {}", m.dir.y);
    }

    #[test]
    fn the_field_is_checked() {
        let mut f = linear(1.0);
        assert!(f.check().is_ok());
        f.hessian = [Vec3::new(0.0, 1.0, 0.0), Vec3::ZERO, Vec3::ZERO];
        assert_eq!(f.check().unwrap_err().0, "graded_index.hessian");
        f.hessian = GradedIndex::radial_hessian(Vec3::Z, 2.0);
        assert!(f.check().is_ok());
        // n falls by ½ k r² off the z axis
        let (n, _) = f.index(1.5, DVec3::new(0.5, 0.0, 3.0));
        assert!((n - (1.5 + 0.0 - 0.25)).abs() < 1e-6, "{n}");
        f.origin = Vec3::NAN;
        assert_eq!(f.check().unwrap_err().0, "graded_index.origin");
    }
}
