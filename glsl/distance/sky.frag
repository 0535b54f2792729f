#version 460
#extension GL_GOOGLE_include_directive : require
// The environment at infinity in a distance map: its radiance, and a distance no surface
// has (+inf in half precision, 1e30 in single; the search treats both as "nothing there").
#include "common/sky.glsl"

layout(location = 0) in vec2 in_ndc;
layout(location = 1) flat in uint in_view;
layout(location = 0) out vec4 out_radiance_distance;

void main() {
    View v = views[in_view];
    vec4 w = v.inv_view_proj * vec4(in_ndc, 0.5, 1.0);
    out_radiance_distance = vec4(sky_radiance(w.xyz / w.w - v.eye.xyz), 1e30);
}
