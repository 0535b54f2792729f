// Radiance along a ray found in the sampled geometry: the distance-map search (§4.1) in an
// object's own map, then the radiance of the texel the hit lies in (§4.2).
#ifndef TRACED_GLSL
#define TRACED_GLSL
#include "common/scene.glsl"

// Which map SEARCH_DISTANCE reads: 0 the environment's distance map, 1 a refractor map,
// 2 a caustic generator's receiver distance map (§6).
int search_map = 0;
float search_layer = 0.0;

float search_lookup(vec3 dir) {
    if (search_map == 1) return textureLod(refractor_maps, vec4(dir, search_layer), 0.0).w;
    if (search_map == 2) return textureLod(caustic_distances, vec4(dir, search_layer), 0.0).r;
    return textureLod(distance_maps, vec4(dir, search_layer), 0.0).a;
}
#define SEARCH_DISTANCE(dir) search_lookup(dir)
#include "common/search.glsl"

// The knobs decide: linear steps 0 means parallax correction alone.
SearchResult search_ray(vec3 x, vec3 dir) {
    if (push_search_linear_steps() == 0u) return parallax_search(x, dir, int(max(push_search_parallax_iterations(), 1u)));
    return linear_search(x, dir, int(push_search_linear_steps()), int(push_search_binary_steps()), int(push_search_secant_steps()), push_search_tolerance());
}

// Object o as it shows in the other objects' maps: its cube in the distance maps at
// shown_layer where composition gave it one apart from its own maps (image-based captures,
// relief height maps), else at envmap_layer.
Object as_shown(Object o) {
    if (o.shown_layer >= 0) o.envmap_layer = o.shown_layer;
    return o;
}

// Radiance arriving at world point p from direction dir, traced in the distance map of
// object o (whose reference point is the map's origin).
vec3 traced_radiance(Object o, vec3 p, vec3 dir) {
    search_map = 0;
    search_layer = float(o.envmap_layer);
    SearchResult s = search_ray(p - o.reference_point.xyz, dir);
    return textureLod(distance_maps, vec4(s.dir, search_layer), 0.0).rgb;
}
#endif
