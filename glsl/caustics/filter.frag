#version 460
#extension GL_GOOGLE_include_directive : require
// caustics.filter: a box filter of radius caustic.filter texels over each face of the light
// cube maps (layer push.object) before projection (survey §6.3). Neighbours beyond a face's
// edge are read from the adjacent face: the taps are directions into the cube map.
#include "common/scene.glsl"

layout(location = 0) in vec2 in_ndc;
layout(location = 1) flat in uint in_view;
layout(location = 0) out vec4 out_intensity;

void main() {
    View v = views[in_view];
    float texel = 2.0 / float(caustic.cube_size);
    int r = int(caustic.filter_radius);
    vec3 sum = vec3(0.0);
    for (int dy = -r; dy <= r; ++dy) {
        for (int dx = -r; dx <= r; ++dx) {
            vec2 ndc = in_ndc + vec2(dx, dy) * texel;
            vec4 w = v.inv_view_proj * vec4(ndc, 1.0, 1.0);
            vec3 dir = w.xyz / w.w - v.eye.xyz;
            sum += textureLod(caustic_raw, vec4(dir, float(push.object)), 0.0).rgb;
        }
    }
    float taps = float((2 * r + 1) * (2 * r + 1));
    out_intensity = vec4(sum / taps, 0.0);
}
