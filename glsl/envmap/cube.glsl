// An environment-mapped object's own cube map (§3.1), looked up in direction `dir` from its
// reference point: in the radiance cubes, or — where composition draws its cube as a distance
// map in the inter-object cycles (§4.3; its map shading is then other than sky,
// src/methods/distance/mod.rs `cubes_converted`) — in the distance maps, radiance in rgb.
#ifndef ENVMAP_CUBE_GLSL
#define ENVMAP_CUBE_GLSL
#include "common/scene.glsl"

vec3 own_cube(Object o, vec3 dir) {
    vec4 at = vec4(dir, float(o.envmap_layer));
    if (o.map_shading == MAP_SHADING_SKY) return textureLod(envmaps, at, 0.0).rgb;
    return textureLod(distance_maps, at, 0.0).rgb;
}
#endif
