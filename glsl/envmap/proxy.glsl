// Where a ray leaves the proxy box of localised environment mapping (survey §3.2): the exit of
// the slab intersection of p + t·dir with the scene's box (o.proxy_min, o.proxy_max), or
// false where p lies outside the box and the ray misses it (then only its direction counts).
#ifndef ENVMAP_PROXY_GLSL
#define ENVMAP_PROXY_GLSL

bool proxy_box_exit(Object o, vec3 p, vec3 dir, out vec3 exit) {
    vec3 inv = 1.0 / dir;
    vec3 t0 = (o.proxy_min.xyz - p) * inv;
    vec3 t1 = (o.proxy_max.xyz - p) * inv;
    vec3 tmax = max(t0, t1);
    float t = min(min(tmax.x, tmax.y), tmax.z);
    exit = p + dir * t;
    return t > 0.0;
}
#endif
