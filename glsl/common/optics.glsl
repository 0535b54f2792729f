// Optics of ideal specular surfaces (survey §1.1). Twin of src/optics.rs: same names,
// same formulas, same behaviour at the extremes (documented there). Directions point along
// the light's travel: `i` arrives at the surface.
#ifndef OPTICS_GLSL
#define OPTICS_GLSL

// NaN and ±∞ tested on the exponent bits: a compiler that assumes no NaN (fast math)
// may fold `x != x` or `!(x < y)` away, but not an integer test.
bool is_nan(float x) { return (floatBitsToUint(x) & 0x7fffffffu) > 0x7f800000u; }
bool is_finite(float x) { return (floatBitsToUint(x) & 0x7f800000u) != 0x7f800000u; }
bool is_finite(vec3 v) { return is_finite(v.x) && is_finite(v.y) && is_finite(v.z); }

// cos θ clamped to [0, 1]; NaN counts as 0 (grazing).
float saturate_cos(float c) { return is_nan(c) ? 0.0 : clamp(c, 0.0, 1.0); }

// A Fresnel reflectance forced into [0, 1]; NaN becomes 1 (everything reflected).
float fresnel_sanitize(float f) { return is_nan(f) ? 1.0 : clamp(f, 0.0, 1.0); }
vec3 fresnel_sanitize(vec3 f) { return vec3(fresnel_sanitize(f.x), fresnel_sanitize(f.y), fresnel_sanitize(f.z)); }

// Ideal reflection direction (reflection law): R = I − 2 (N·I) N.
vec3 reflect_dir(vec3 i, vec3 n) {
    return i - 2.0 * dot(n, i) * n;
}

// Refraction by Snell's law (Snellius–Descartes, survey §1.1); `eta` = ν_incident /
// ν_transmitted, `n` faces the incident side. Returns false on total internal reflection
// (sin²θt ≥ 1) and for any non-finite input, instead of a magic vector.
bool refract_dir(vec3 i, vec3 n, float eta, out vec3 t) {
    t = vec3(0.0);
    if (!is_finite(i) || !is_finite(n) || !is_finite(eta)) return false;
    float cos_i = -dot(n, i);
    float sin2_t = eta * eta * max(0.0, 1.0 - cos_i * cos_i);
    if (!is_finite(sin2_t) || sin2_t >= 1.0) return false;
    float cos_t = sqrt(1.0 - sin2_t);  // cos θt from Snell's law
    t = eta * i + (eta * cos_i - cos_t) * n;
    return true;
}

// Reflectance at normal incidence from ν and κ (survey eq. 2), per channel:
// F0 = ((ν − 1)² + κ²) / ((ν + 1)² + κ²).
vec3 fresnel_f0(vec3 nu, vec3 kappa) {
    vec3 k2 = kappa * kappa;
    return fresnel_sanitize(((nu - 1.0) * (nu - 1.0) + k2) / ((nu + 1.0) * (nu + 1.0) + k2));
}

// Schlick's approximation F(θ) = F0 + (1 − F0)(1 − cos θ)^5 (survey eq. 2).
vec3 fresnel_schlick(vec3 f0, float cos_i) {
    float m = 1.0 - saturate_cos(cos_i);
    float m2 = m * m;
    return fresnel_sanitize(f0 + (1.0 - f0) * (m2 * m2 * m));
}

// Exact Fresnel reflectance of unpolarised light at a dielectric interface of relative
// index eta = ν_t / ν_i. Returns 1 under total internal reflection.
float fresnel_dielectric(float cos_i, float eta) {
    cos_i = saturate_cos(cos_i);
    // cos²θt = 1 − (1 − cos²θi)/η², written without the cancellation of 1 − … for η ≈ 1.
    float cos2_t = (cos_i * cos_i + (eta - 1.0) * (eta + 1.0)) / (eta * eta);
    if (!is_finite(cos2_t) || cos2_t <= 0.0) return 1.0;  // total internal reflection
    float cos_t = sqrt(cos2_t);
    float rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    float rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    return fresnel_sanitize(0.5 * (rs * rs + rp * rp));
}

// Exact Fresnel reflectance of a conductor with complex index ν + iκ (from a dielectric
// of index 1), unpolarised, per channel.
vec3 fresnel_conductor(float cos_i, vec3 nu, vec3 kappa) {
    cos_i = saturate_cos(cos_i);
    float c2 = cos_i * cos_i;
    float s2 = 1.0 - c2;
    vec3 n2 = nu * nu, k2 = kappa * kappa;
    // t0 = ν² − κ² − sin²θ, as (ν − 1)(ν + 1) − κ² + cos²θ: no cancellation for ν ≈ 1.
    vec3 t0 = (nu - 1.0) * (nu + 1.0) - k2 + c2;
    vec3 a2b2 = sqrt(t0 * t0 + 4.0 * n2 * k2);
    vec3 a = sqrt(max(0.5 * (a2b2 + t0), 0.0));
    vec3 t1 = a2b2 + c2;
    vec3 t2 = 2.0 * cos_i * a;
    vec3 rs = (t1 - t2) / max(t1 + t2, 1e-30);
    vec3 t3 = c2 * a2b2 + s2 * s2;
    vec3 t4 = t2 * s2;
    vec3 rp = rs * (t3 - t4) / max(t3 + t4, 1e-30);
    return fresnel_sanitize(0.5 * (rp + rs));
}

#endif
