#version 460
#extension GL_GOOGLE_include_directive : require
// One cone per tile of the ray texture, on the GPU from its rays: the axis is the mean
// direction, the half angle θ the widest ray from it; the apex lies behind the ball around
// the rays' origins, at r / sin θ, so that the cone holds every origin and every direction.
// Nearly parallel rays (sin θ < 1e-3) or rays wider than ~80° get CONE_ALL.
layout(local_size_x = 64) in;
#include "raytrace/hierarchy.glsl"

void main() {
    uint k = gl_GlobalInvocationID.x;
    uint ts = trace.tile_size;
    uint rows = engine_rows();
    uint tiles_y = (rows + ts - 1u) / ts;
    if (k >= trace.tiles_per_row * max(tiles_y, 1u) || trace.tiles_per_row == 0u) return;
    uvec2 t0 = uvec2(k % trace.tiles_per_row, k / trace.tiles_per_row) * ts;
    uint n = 0u;
    vec3 sum_d = vec3(0.0);
    vec3 sum_o = vec3(0.0);
    for (uint j = 0u; j < ts * ts; ++j) {
        uint t = texel_slot(t0 + uvec2(j % ts, j / ts));
        if (t >= queue_rays()) continue;
        uint i = ray_at(t);
        if ((queries[i].flags & RAY_HIT_KNOWN) != 0u) continue;
        sum_d += normalize(queries[i].direction.xyz);
        sum_o += queries[i].origin.xyz;
        n++;
    }
    if (n == 0u) {
        tile_cones[2u * k] = vec4(0.0, 0.0, 0.0, CONE_EMPTY);
        return;
    }
    vec3 axis = length(sum_d) > 1e-6 ? normalize(sum_d) : vec3(0.0, 0.0, 1.0);
    vec3 c = sum_o / float(n);
    float cos_t = 1.0;
    float r = 0.0;
    for (uint j = 0u; j < ts * ts; ++j) {
        uint t = texel_slot(t0 + uvec2(j % ts, j / ts));
        if (t >= queue_rays()) continue;
        uint i = ray_at(t);
        if ((queries[i].flags & RAY_HIT_KNOWN) != 0u) continue;
        cos_t = min(cos_t, dot(normalize(queries[i].direction.xyz), axis));
        r = max(r, length(queries[i].origin.xyz - c));
    }
    // Rays that all end near one point (shadow rays towards a point light) are segments
    // inside the cone from that point back over the origins' ball, which is far narrower.
    bool bounded = true;
    vec3 sum_e = vec3(0.0);
    for (uint j = 0u; j < ts * ts && bounded; ++j) {
        uint t = texel_slot(t0 + uvec2(j % ts, j / ts));
        if (t >= queue_rays()) continue;
        uint i = ray_at(t);
        if ((queries[i].flags & RAY_HIT_KNOWN) != 0u) continue;
        float t_max = queries[i].direction.w;
        bounded = !isinf(t_max);
        sum_e += queries[i].origin.xyz + queries[i].direction.xyz * t_max;
    }
    if (bounded) {
        vec3 e = sum_e / float(n);
        float re = 0.0;
        float scale = 0.0;
        for (uint j = 0u; j < ts * ts; ++j) {
            uint t = texel_slot(t0 + uvec2(j % ts, j / ts));
            if (t >= queue_rays()) continue;
            uint i = ray_at(t);
            if ((queries[i].flags & RAY_HIT_KNOWN) != 0u) continue;
            vec3 o = queries[i].origin.xyz;
            vec4 d = queries[i].direction;
            re = max(re, length(o + d.xyz * d.w - e));
            vec3 m = abs(o) + abs(d.xyz) * d.w;
            scale = max(scale, max(max(m.x, m.y), m.z));
        }
        // The end points are computed, the origins stored: the exact end o + t_max·d lies
        // within a few ulps of the magnitudes involved of the computed one, which for
        // shadow rays (ends ≈ t_min from the light, all within ~t_min of e) is most of re.
        re += 1e-6 * scale;
        float dist = length(c - e);
        float s = (r + re) * 1.0001 / max(dist, 1e-30);
        if (s < 0.98 && is_finite(e)) {
            vec3 ax = (c - e) / dist;
            float sin_b = s;
            float cos_b = sqrt(1.0 - s * s);
            // Apex behind e so that the ball around the end points lies inside too.
            vec3 apex = e - ax * (re * 1.0001 / sin_b);
            tile_cones[2u * k] = vec4(apex, cos_b - 1e-5);
            tile_cones[2u * k + 1u] = vec4(ax, sqrt(max(1.0 - (cos_b - 1e-5) * (cos_b - 1e-5), 0.0)));
            return;
        }
    }
    // Rounding margin on the angle, then the apex behind the origins' ball.
    cos_t = cos_t - 1e-5;
    float sin_t = sqrt(max(1.0 - cos_t * cos_t, 0.0));
    if (cos_t < 0.17 || sin_t < 1e-3 || !is_finite(c)) {
        tile_cones[2u * k] = vec4(0.0, 0.0, 0.0, CONE_ALL);
        return;
    }
    vec3 apex = c - axis * (r * 1.0001 / sin_t);
    tile_cones[2u * k] = vec4(apex, cos_t);
    tile_cones[2u * k + 1u] = vec4(axis, sin_t);
}
