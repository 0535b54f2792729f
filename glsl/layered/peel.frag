#version 460
#extension GL_GOOGLE_include_directive : require
// variants: CAUSTICS_TEXTURE
// layered.peel (survey §4.5, UPSK07): layer k of the multi-layer distance map, the k-th
// surface along each texel's ray from the map's reference point, by depth peeling
// (Everitt): a fragment survives only behind the previous layer's depth at its texel.
// A texel holds the Euclidean distance from the reference point and the normal; a diffuse
// surface its reflected radiance (the shading every map uses, shadows included), a
// specular one its material (index + 1: Fresnel from ν, κ per channel or the dielectric's
// ν), so that the search can continue the ray there. CAUSTICS_TEXTURE (caustic_space=texture):
// diffuse surfaces read the receivers' light map at their triangle.
#include "common/shading.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 3) flat in uint in_view;
layout(location = 0) out vec4 out_radiance_distance;
layout(location = 1) out vec4 out_normal_material;

void main() {
    if ((push.flags & LAYERED_FIRST) == 0u) {
        uint face = in_view - push.view + ((push.flags >> LAYERED_FACE_SHIFT) & 7u);
        float previous = texelFetch(layered_previous, ivec3(ivec2(gl_FragCoord.xy), int(face)), 0).r;
        // Reversed-Z: nearer is greater; keep what lies behind the previous layer.
        if (!(gl_FragCoord.z < previous * (1.0 - LAYERED_PEEL_EPSILON))) discard;
    }
    CAUSTIC_TRIANGLE_HERE();
    Object o = objects[push.object];
    Material m = materials[o.material];
    vec3 n = normalize(in_normal);
    vec3 eye = views[in_view].eye.xyz;
    float dist = length(in_position - eye);
    if (m.kind == KIND_DIFFUSE) {
        out_radiance_distance = vec4(shade_diffuse(m, in_position, n, eye, in_uv), dist);
        out_normal_material = vec4(n, 0.0);
    } else {
        out_radiance_distance = vec4(0.0, 0.0, 0.0, dist);
        out_normal_material = vec4(n, float(o.material + 1u));
    }
}
