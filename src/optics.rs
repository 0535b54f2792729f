//! Optics of ideal specular surfaces (survey §1.1), twin of `glsl/common/optics.glsl`:
//! the same functions under the same names, in f64 for the CPU side. Directions point
//! along the light's travel.

use glam::DVec3;

/// Ideal reflection direction (reflection law).
pub fn reflect_dir(i: DVec3, n: DVec3) -> DVec3 {
    i - 2.0 * n.dot(i) * n
}

/// Snell's law; `eta` = ν_incident/ν_transmitted, `n` faces the incident side.
/// `None` on total internal reflection.
pub fn refract_dir(i: DVec3, n: DVec3, eta: f64) -> Option<DVec3> {
    let cos_i = -n.dot(i);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt(); // cos θt from Snell's law
    Some(eta * i + (eta * cos_i - cos_t) * n)
}

/// Reflectance at normal incidence from ν and κ (survey eq. 2).
pub fn fresnel_f0(nu: f64, kappa: f64) -> f64 {
    let k2 = kappa * kappa;
    ((nu - 1.0).powi(2) + k2) / ((nu + 1.0).powi(2) + k2)
}

/// Schlick's approximation F = F0 + (1 − F0)(1 − cos θ)^5 (survey eq. 2).
pub fn fresnel_schlick(f0: f64, cos_i: f64) -> f64 {
    let m = (1.0 - cos_i).clamp(0.0, 1.0);
    f0 + (1.0 - f0) * m.powi(5)
}

/// Exact unpolarised Fresnel reflectance of a dielectric interface, eta = ν_t/ν_i;
/// 1 under total internal reflection.
pub fn fresnel_dielectric(cos_i: f64, eta: f64) -> f64 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    0.5 * (rs * rs + rp * rp)
}

/// Exact unpolarised Fresnel reflectance of a conductor of complex index ν + iκ.
pub fn fresnel_conductor(cos_i: f64, nu: f64, kappa: f64) -> f64 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let (c2, s2) = (cos_i * cos_i, 1.0 - cos_i * cos_i);
    let (n2, k2) = (nu * nu, kappa * kappa);
    let t0 = n2 - k2 - s2;
    let a2b2 = (t0 * t0 + 4.0 * n2 * k2).sqrt();
    let a = (0.5 * (a2b2 + t0)).max(0.0).sqrt();
    let t1 = a2b2 + c2;
    let t2 = 2.0 * cos_i * a;
    let rs = (t1 - t2) / (t1 + t2).max(1e-300);
    let t3 = c2 * a2b2 + s2 * s2;
    let t4 = t2 * s2;
    let rp = rs * (t3 - t4) / (t3 + t4).max(1e-300);
    0.5 * (rp + rs)
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
}
