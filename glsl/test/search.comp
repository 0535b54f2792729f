#version 460
#extension GL_GOOGLE_include_directive : require
// GLSL-vs-Rust conformance of glsl/common/search.glsl: each case searches an analytic
// distance map (an axis-aligned box room seen from a centre, the same room open to the sky
// at its top, or nothing at all) with the same steps as src/search.rs.
layout(local_size_x = 64) in;

struct Case {
    vec4 x;         // ray start relative to the reference point; w: tolerance
    vec4 r;         // unit direction; w: 1 when the map is empty (sky everywhere), 2 open top
    uvec4 knobs;    // linear, secant, binary, parallax iterations (linear 0: parallax)
    vec4 box_min;   // room, world space
    vec4 box_max;
    vec4 center;    // reference point, world space
};

layout(std430, set = 0, binding = 0) readonly buffer Cases { Case cases[]; };
layout(std430, set = 0, binding = 1) writeonly buffer Results { vec4 results[]; };

vec3 g_min, g_max, g_center;
bool g_sky, g_open_top;

float box_distance(vec3 dir) {
    if (g_sky) return 1.0 / 0.0;
    vec3 d = normalize(dir);
    float t = 1.0 / 0.0;
    int face = -1;
    for (int a = 0; a < 3; ++a) {
        float ta = d[a] > 0.0 ? (g_max[a] - g_center[a]) / d[a] : d[a] < 0.0 ? (g_min[a] - g_center[a]) / d[a] : 1.0 / 0.0;
        if (ta < t) { t = ta; face = d[a] > 0.0 ? 2 * a + 1 : 2 * a; }
    }
    return g_open_top && face == 3 ? 1.0 / 0.0 : t;  // face 3: +y, the ceiling
}

#define SEARCH_DISTANCE(dir) box_distance(dir)
#include "common/search.glsl"

void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= cases.length()) return;
    Case c = cases[i];
    g_min = c.box_min.xyz;
    g_max = c.box_max.xyz;
    g_center = c.center.xyz;
    g_sky = c.r.w == 1.0;
    g_open_top = c.r.w == 2.0;
    SearchResult s = c.knobs.x == 0u ? parallax_search(c.x.xyz, c.r.xyz, int(c.knobs.w))
                                     : linear_search(c.x.xyz, c.r.xyz, int(c.knobs.x), int(c.knobs.z), int(c.knobs.y), c.x.w);
    results[i] = vec4(s.d, s.escaped ? 1.0 : 0.0, float(s.lookups), 0.0);
}
