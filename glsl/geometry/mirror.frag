#version 460
#extension GL_GOOGLE_include_directive : require
// variants: PER_SAMPLE COUNT_FALLBACKS COUNT_FALLBACKS_PER_SAMPLE
#ifdef COUNT_FALLBACKS_PER_SAMPLE
#define COUNT_FALLBACKS
#define PER_SAMPLE
#endif
// geometry.mirror: a planar mirror (survey §5, DB97/MBGN00). Its reflection is the scene
// rendered from the camera mirrored through its plane, which lands on the mirror's own
// pixels: the pixel's texel of that view, weighted by the mirror's Fresnel reflectance at
// the eye ray's incidence. Beyond the view budget the reflected ray is traced in the
// mirror's own distance map where the plan gave it one (a mirror whose views the budget
// can cut, src/methods/geometry/mod.rs); at the recursion depth (FLAG_MIRROR_DEPTH_END), or
// without the map, the environment along it (where the reference's paths end).
#include "common/specular.glsl"
#include "common/sky.glsl"
#include "common/traced.glsl"

#ifdef COUNT_FALLBACKS
// The fallback is counted per fragment that survives the depth test (geometry.fallback_pixels).
layout(early_fragment_tests) in;
#define COUNT_FALLBACK() atomicAdd(fallbacks[push.object], 1u)
#else
#define COUNT_FALLBACK()
#endif
layout(location = 0) SAMPLE_INTERP in vec3 in_position;
layout(location = 1) SAMPLE_INTERP in vec3 in_normal;
layout(location = 2) SAMPLE_INTERP in vec2 in_uv;
layout(location = 3) flat in uint in_view;
layout(location = 0) out vec4 out_color;

void main() {
    Object o = objects[push.object];
    Material m = materials[o.material];
    SpecularSplit s = specular_split(m, in_position, normalize(in_normal), views[in_view].eye.xyz);
    vec3 reflected;
    if ((push.flags & FLAG_MIRROR_VIEW) != 0u) {
        ivec3 texel = ivec3(ivec2(gl_FragCoord.xy), int((push.flags >> MIRROR_LAYER_SHIFT) & 0xffu));
        reflected = texelFetch(mirror_views, texel, 0).rgb;
    } else if (o.envmap_layer >= 0 && (push.flags & FLAG_MIRROR_DEPTH_END) == 0u) {
        reflected = traced_radiance(o, in_position, s.r);
        // The image's own fragments (not the mirrored views'): geometry.fallback_pixels.
        if (push.view < push_extra_view_base()) COUNT_FALLBACK();
    } else {
        reflected = sky_radiance(s.r);
    }
    out_color = vec4(s.fr * reflected, 1.0);
}
