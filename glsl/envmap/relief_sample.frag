#version 460
#extension GL_GOOGLE_include_directive : require
// envmap.relief with relief_source=distance (src/methods/envmap/relief.rs): one texel of a
// displacement-mapped proxy's height map sampled from the object's distance map (survey
// §3.2 with §4.1): the texel's ray leaves the view's near plane along its direction and is
// searched in the distance map (the search knobs); the hit's depth along the direction and
// the radiance the map holds there are the texel, or nothing (1e30) where it escapes.
// views[in_view].dir.w is the object's layer in the distance maps.
#include "common/scene.glsl"

float relief_search_layer = 0.0;
#define SEARCH_DISTANCE(dir) textureLod(distance_maps, vec4(dir, relief_search_layer), 0.0).a
#include "common/search.glsl"

layout(location = 0) in vec2 in_ndc;
layout(location = 1) flat in uint in_view;
layout(location = 0) out vec4 out_radiance_depth;

void main() {
    View v = views[in_view];
    vec4 w = v.inv_view_proj * vec4(in_ndc, 1.0, 1.0);  // reversed depth 1: the near plane
    vec3 start = w.xyz / w.w;
    vec3 x = start - objects[push.object].reference_point.xyz;
    vec3 dir = v.dir.xyz;
    relief_search_layer = v.dir.w;
    SearchResult s = push_search_linear_steps() == 0u
        ? parallax_search(x, dir, int(max(push_search_parallax_iterations(), 1u)))
        : linear_search(x, dir, int(push_search_linear_steps()), int(push_search_binary_steps()), int(push_search_secant_steps()), push_search_tolerance());
    vec3 radiance = textureLod(distance_maps, vec4(s.dir, relief_search_layer), 0.0).rgb;
    // Depths from the eye, which lies before the near plane (the object's back).
    out_radiance_depth = vec4(radiance, s.escaped ? 1e30 : dot(start - v.eye.xyz, dir) + s.d);
}
