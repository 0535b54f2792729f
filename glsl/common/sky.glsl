// Equirectangular environment lookup: u = 0.5 + atan(d.x, −d.z)/2π, v = acos(d.y)/π.
#ifndef SKY_GLSL
#define SKY_GLSL
#include "common/scene.glsl"

const float PI = 3.14159265358979;

vec3 sky_radiance(vec3 d) {
    if ((push.flags & FLAG_HAS_ENVIRONMENT) == 0u) return vec3(0.0);
    d = normalize(d);
    vec2 uv = vec2(0.5 + atan(d.x, -d.z) / (2.0 * PI), acos(clamp(d.y, -1.0, 1.0)) / PI);
    // Explicit LOD 0: the derivative of atan jumps across the seam.
    return textureLod(environment_map, uv, 0.0).rgb;
}
#endif
