// Optics of ideal specular surfaces (survey §1.1). Twin of src/optics.rs: same names,
// same formulas. Directions point along the light's travel: `i` arrives at the surface.
#ifndef OPTICS_GLSL
#define OPTICS_GLSL

// Ideal reflection direction (reflection law).
vec3 reflect_dir(vec3 i, vec3 n) {
    return i - 2.0 * dot(n, i) * n;
}

// Refraction by Snell's law; `eta` = ν_incident / ν_transmitted, `n` faces the incident side.
// Returns false on total internal reflection instead of a magic vector.
bool refract_dir(vec3 i, vec3 n, float eta, out vec3 t) {
    float cos_i = -dot(n, i);
    float sin2_t = eta * eta * max(0.0, 1.0 - cos_i * cos_i);
    if (sin2_t >= 1.0) { t = vec3(0.0); return false; }
    float cos_t = sqrt(1.0 - sin2_t);  // cos θt from Snell's law
    t = eta * i + (eta * cos_i - cos_t) * n;
    return true;
}

// Reflectance at normal incidence from ν and κ (survey eq. 2), per channel.
vec3 fresnel_f0(vec3 nu, vec3 kappa) {
    vec3 k2 = kappa * kappa;
    return ((nu - 1.0) * (nu - 1.0) + k2) / ((nu + 1.0) * (nu + 1.0) + k2);
}

// Schlick's approximation F(θ) = F0 + (1 − F0)(1 − cos θ)^5 (survey eq. 2).
vec3 fresnel_schlick(vec3 f0, float cos_i) {
    float m = clamp(1.0 - cos_i, 0.0, 1.0);
    float m2 = m * m;
    return f0 + (1.0 - f0) * (m2 * m2 * m);
}

// Exact Fresnel reflectance of unpolarised light at a dielectric interface of relative
// index eta = ν_t / ν_i. Returns 1 under total internal reflection.
float fresnel_dielectric(float cos_i, float eta) {
    cos_i = clamp(cos_i, 0.0, 1.0);
    float sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if (sin2_t >= 1.0) return 1.0;
    float cos_t = sqrt(1.0 - sin2_t);
    float rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    float rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    return 0.5 * (rs * rs + rp * rp);
}

// Exact Fresnel reflectance of a conductor with complex index ν + iκ (from a dielectric
// of index 1), unpolarised, per channel.
vec3 fresnel_conductor(float cos_i, vec3 nu, vec3 kappa) {
    cos_i = clamp(cos_i, 0.0, 1.0);
    float c2 = cos_i * cos_i;
    float s2 = 1.0 - c2;
    vec3 n2 = nu * nu, k2 = kappa * kappa;
    vec3 t0 = n2 - k2 - s2;
    vec3 a2b2 = sqrt(t0 * t0 + 4.0 * n2 * k2);
    vec3 a = sqrt(max(0.5 * (a2b2 + t0), 0.0));
    vec3 t1 = a2b2 + c2;
    vec3 t2 = 2.0 * cos_i * a;
    vec3 rs = (t1 - t2) / max(t1 + t2, 1e-30);
    vec3 t3 = c2 * a2b2 + s2 * s2;
    vec3 t4 = t2 * s2;
    vec3 rp = rs * (t3 - t4) / max(t3 + t4, 1e-30);
    return 0.5 * (rp + rs);
}

#endif
