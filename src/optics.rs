//! Optics of ideal specular surfaces (survey §1.1) and the ray–triangle test (§2.1.1),
//! twin of `glsl/common/optics.glsl` and `glsl/common/ray_triangle.glsl`: the same
//! functions under the same names, in f64 for the CPU side. Directions point along the
//! light's travel. `tests/optics_conformance.rs` runs both sides on the same input tables.
//!
//! Behaviour at the extremes, the same on both sides:
//! - `reflect_dir` is one linear formula: non-finite input gives non-finite output.
//! - `refract_dir` reports total internal reflection (TIR) iff sin²θt ≥ 1, the critical
//!   angle itself included (a grazing transmitted ray carries no power, F = 1 there); any
//!   non-finite input reports "no refracted ray" rather than a NaN direction.
//! - Every Fresnel function returns a value in [0, 1] for every input. cos θ is clamped to
//!   [0, 1] (−0 is 0) and a NaN cosine counts as 0 (grazing); a NaN result (NaN, infinite
//!   ν or κ) becomes 1: everything reflected, never a NaN colour.
//! - `ray_triangle` misses on any NaN or infinite input (t_max = +∞ means "no limit"), on
//!   zero-area triangles and on rays parallel to the triangle's plane; the barycentric test
//!   is inclusive, so a ray through a vertex or across an edge hits. The parallel test is
//!   relative (|det| ≤ 1e-6 |d| |e1| |e2|), so it means the same at every scale.

use glam::DVec3;

/// `x` is neither NaN nor ±∞ (GLSL: a test of the exponent bits, which no fast-math
/// optimisation can drop).
pub fn is_finite(x: f64) -> bool {
    x.is_finite()
}

/// cos θ clamped to [0, 1]; NaN counts as 0 (grazing).
pub fn saturate_cos(c: f64) -> f64 {
    if c.is_nan() {
        0.0
    } else {
        c.clamp(0.0, 1.0)
    }
}

/// A Fresnel reflectance forced into [0, 1]; NaN becomes 1 (everything reflected).
pub fn fresnel_sanitize(f: f64) -> f64 {
    if f.is_nan() {
        1.0
    } else {
        f.clamp(0.0, 1.0)
    }
}

/// Ideal reflection direction (reflection law): R = I − 2 (N·I) N.
pub fn reflect_dir(i: DVec3, n: DVec3) -> DVec3 {
    i - 2.0 * n.dot(i) * n
}

/// Snell's law (Snellius–Descartes, survey §1.1); `eta` = ν_incident / ν_transmitted,
/// `n` faces the incident side. `None` on total internal reflection (sin²θt ≥ 1) and for
/// any non-finite input.
pub fn refract_dir(i: DVec3, n: DVec3, eta: f64) -> Option<DVec3> {
    if !(i.is_finite() && n.is_finite() && eta.is_finite()) {
        return None;
    }
    let cos_i = -n.dot(i);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if !is_finite(sin2_t) || sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt(); // cos θt from Snell's law
    Some(eta * i + (eta * cos_i - cos_t) * n)
}

/// Reflectance at normal incidence from ν and κ (survey eq. 2):
/// F0 = ((ν − 1)² + κ²) / ((ν + 1)² + κ²).
pub fn fresnel_f0(nu: f64, kappa: f64) -> f64 {
    let k2 = kappa * kappa;
    fresnel_sanitize(((nu - 1.0).powi(2) + k2) / ((nu + 1.0).powi(2) + k2))
}

/// Schlick's approximation F(θ) = F0 + (1 − F0)(1 − cos θ)^5 (survey eq. 2).
pub fn fresnel_schlick(f0: f64, cos_i: f64) -> f64 {
    let m = 1.0 - saturate_cos(cos_i);
    let m2 = m * m;
    fresnel_sanitize(f0 + (1.0 - f0) * (m2 * m2 * m))
}

/// Exact unpolarised Fresnel reflectance of a dielectric interface, eta = ν_t/ν_i;
/// 1 under total internal reflection.
pub fn fresnel_dielectric(cos_i: f64, eta: f64) -> f64 {
    let cos_i = saturate_cos(cos_i);
    // cos²θt = 1 − (1 − cos²θi)/η², written without the cancellation of 1 − … for η ≈ 1.
    let cos2_t = (cos_i * cos_i + (eta - 1.0) * (eta + 1.0)) / (eta * eta);
    if !is_finite(cos2_t) || cos2_t <= 0.0 {
        return 1.0; // total internal reflection (the critical angle included)
    }
    let cos_t = cos2_t.sqrt();
    let rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    fresnel_sanitize(0.5 * (rs * rs + rp * rp))
}

/// Exact unpolarised Fresnel reflectance of a conductor of complex index ν + iκ seen from
/// a medium of index 1.
pub fn fresnel_conductor(cos_i: f64, nu: f64, kappa: f64) -> f64 {
    let cos_i = saturate_cos(cos_i);
    let (c2, s2) = (cos_i * cos_i, 1.0 - cos_i * cos_i);
    let (n2, k2) = (nu * nu, kappa * kappa);
    // t0 = ν² − κ² − sin²θ, as (ν − 1)(ν + 1) − κ² + cos²θ: no cancellation for ν ≈ 1.
    let t0 = (nu - 1.0) * (nu + 1.0) - k2 + c2;
    let a2b2 = (t0 * t0 + 4.0 * n2 * k2).sqrt();
    let a = (0.5 * (a2b2 + t0)).max(0.0).sqrt();
    let t1 = a2b2 + c2;
    let t2 = 2.0 * cos_i * a;
    let rs = (t1 - t2) / (t1 + t2).max(1e-30);
    let t3 = c2 * a2b2 + s2 * s2;
    let t4 = t2 * s2;
    let rp = rs * (t3 - t4) / (t3 + t4).max(1e-30);
    fresnel_sanitize(0.5 * (rp + rs))
}

/// Rays closer to parallel than this (|det| relative to |d| |e1| |e2|, the sine of the
/// angle between the ray and the plane times the sine of the triangle's corner at v0)
/// miss: below it the determinant is rounding noise of single-precision arithmetic.
pub const RAY_TRIANGLE_PARALLEL: f64 = 1e-6;

/// Where a ray meets a triangle: distance `t` along the (unnormalised) direction and the
/// barycentric weights `u` of v1 and `v` of v2.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    pub t: f64,
    pub u: f64,
    pub v: f64,
}

/// Möller–Trumbore ray–triangle intersection (survey §2.1.1, [MT97]): solves
/// o + t d = (1 − u − v) v0 + u v1 + v v2 by Cramer's rule, without precomputation. A hit
/// needs t_min < t < t_max and u ≥ 0, v ≥ 0, u + v ≤ 1 (inclusive: vertices and edges hit).
pub fn ray_triangle(o: DVec3, d: DVec3, v0: DVec3, v1: DVec3, v2: DVec3, t_min: f64, t_max: f64) -> Option<TriangleHit> {
    let (e1, e2) = (v1 - v0, v2 - v0);
    let det_min = RAY_TRIANGLE_PARALLEL * d.length() * e1.length() * e2.length();
    ray_triangle_edges(o, d, v0, e1, e2, det_min, t_min, t_max)
}

/// `ray_triangle` with the edges e1 = v1 − v0, e2 = v2 − v0 and the parallel threshold
/// `det_min` = RAY_TRIANGLE_PARALLEL |d| |e1| |e2| computed by the caller (the reference
/// renderer's BVH stores them per triangle).
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn ray_triangle_edges(
    o: DVec3,
    d: DVec3,
    v0: DVec3,
    e1: DVec3,
    e2: DVec3,
    det_min: f64,
    t_min: f64,
    t_max: f64,
) -> Option<TriangleHit> {
    if !(o.is_finite() && v0.is_finite() && is_finite(det_min) && is_finite(t_min)) || t_max.is_nan() {
        return None; // NaN or ∞ anywhere (d, e1, e2 enter det_min): a miss, never a NaN hit
    }
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() <= det_min || !is_finite(det) {
        return None; // parallel to the plane, or a zero-area triangle
    }
    let inv = 1.0 / det;
    let s = o - v0;
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = d.dot(q) * inv;
    if v.is_nan() || v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(q) * inv;
    if !is_finite(t) || t <= t_min || t >= t_max {
        return None;
    }
    Some(TriangleHit { t, u, v })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn schlick_and_exact_agree_at_normal_incidence() {
        for nu in [1.1, 1.5, 2.4] {
            assert!((fresnel_schlick(fresnel_f0(nu, 0.0), 1.0) - fresnel_dielectric(1.0, nu)).abs() < 1e-12);
            assert!((fresnel_conductor(1.0, nu, 0.0) - fresnel_f0(nu, 0.0)).abs() < 1e-12);
        }
        assert!((fresnel_conductor(1.0, 0.2, 3.0) - fresnel_f0(0.2, 3.0)).abs() < 1e-12);
    }

    #[test]
    fn grazing_incidence_reflects_everything() {
        assert_eq!(fresnel_schlick(0.04, 0.0), 1.0);
        assert!((fresnel_dielectric(0.0, 1.5) - 1.0).abs() < 1e-12);
        assert!((fresnel_conductor(0.0, 0.2, 3.0) - 1.0).abs() < 1e-9);
    }

    #[test]
    fn refraction_reports_total_internal_reflection() {
        let n = DVec3::Z;
        let i = DVec3::new(0.8, 0.0, -0.6); // 53° from the normal, inside glass
        assert!(refract_dir(i, n, 1.5).is_none());
        let t = refract_dir(i, n, 1.0 / 1.5).unwrap();
        assert!((t.length() - 1.0).abs() < 1e-12);
        assert!((t.x - 0.8 / 1.5).abs() < 1e-12); // Snell: sin θt = sin θi / 1.5
    }

    #[test]
    fn fresnel_never_leaves_unit_interval() {
        for v in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, -0.0, 0.0, 1e-300, 1e300] {
            for f in [fresnel_f0(v, 0.0), fresnel_f0(1.5, v), fresnel_schlick(0.04, v), fresnel_schlick(v, 0.5)] {
                assert!((0.0..=1.0).contains(&f), "{v}: {f}");
            }
            for f in [fresnel_dielectric(v, 1.5), fresnel_dielectric(0.5, v), fresnel_conductor(v, 0.2, 3.0), fresnel_conductor(0.5, v, v)]
            {
                assert!((0.0..=1.0).contains(&f), "{v}: {f}");
            }
        }
        assert_eq!(fresnel_schlick(0.04, f64::NAN), 1.0, "NaN cosine is grazing");
        assert_eq!(fresnel_f0(f64::INFINITY, 0.0), 1.0);
    }

    #[test]
    fn ray_triangle_hits_inside_and_on_the_boundary_misses_outside() {
        let (a, b, c) = (DVec3::ZERO, DVec3::X, DVec3::Y);
        let down = DVec3::NEG_Z;
        let h = ray_triangle(DVec3::new(0.25, 0.25, 2.0), down, a, b, c, 0.0, f64::INFINITY).unwrap();
        assert_eq!((h.t, h.u, h.v), (2.0, 0.25, 0.25));
        assert!(ray_triangle(DVec3::new(0.0, 0.0, 1.0), down, a, b, c, 0.0, f64::INFINITY).is_some(), "through a vertex");
        assert!(ray_triangle(DVec3::new(0.5, 0.0, 1.0), down, a, b, c, 0.0, f64::INFINITY).is_some(), "across an edge");
        assert!(ray_triangle(DVec3::new(0.6, 0.6, 1.0), down, a, b, c, 0.0, f64::INFINITY).is_none());
        assert!(ray_triangle(DVec3::new(0.25, 0.25, 1.0), down, a, b, c, 0.0, 0.5).is_none(), "beyond t_max");
        assert!(ray_triangle(DVec3::new(-1.0, 0.0, 0.0), DVec3::X, a, b, c, 0.0, f64::INFINITY).is_none(), "along an edge");
        assert!(ray_triangle(DVec3::new(0.2, 0.2, 1.0), down, a, b, b * 2.0, 0.0, f64::INFINITY).is_none(), "zero area");
        assert!(ray_triangle(DVec3::new(0.2, f64::NAN, 1.0), down, a, b, c, 0.0, f64::INFINITY).is_none());
        assert!(ray_triangle(DVec3::new(0.2, 0.2, 1.0), down, a, b, c, 0.0, f64::NAN).is_none());
        // Scale invariance: the same configuration at 1e-6 and 1e6 metres.
        for s in [1e-6, 1e6] {
            let h = ray_triangle(DVec3::new(0.25, 0.25, 2.0) * s, down, a * s, b * s, c * s, 0.0, f64::INFINITY).unwrap();
            assert!((h.t / s - 2.0).abs() < 1e-12 && (h.u - 0.25).abs() < 1e-12);
        }
    }
}
