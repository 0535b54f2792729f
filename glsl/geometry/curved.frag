#version 460
#extension GL_GOOGLE_include_directive : require
// variants: PER_SAMPLE
// geometry.curved: a curved reflector (survey §5, EMD*05/EMDT06). Its reflection is its
// virtual objects' image at the pixel (geometry.virtual), weighted by the mirror's Fresnel
// reflectance at the eye ray's incidence. At the reflector's silhouette and rim the virtual
// image has holes (triangles with a corner that has no reflection point are dropped): such
// a pixel takes the nearest covered pixel within CURVED_FILL pixels; beyond, the
// environment along the reflected ray.
#include "common/specular.glsl"
#include "common/sky.glsl"
#include "geometry/curved.glsl"

layout(location = 0) SAMPLE_INTERP in vec3 in_position;
layout(location = 1) SAMPLE_INTERP in vec3 in_normal;
layout(location = 2) SAMPLE_INTERP in vec2 in_uv;
layout(location = 3) flat in uint in_view;
layout(location = 0) out vec4 out_color;

void main() {
    Object o = objects[push.object];
    Material m = materials[o.material];
    SpecularSplit s = specular_split(m, in_position, normalize(in_normal), views[in_view].eye.xyz);
    ivec2 pixel = ivec2(gl_FragCoord.xy);
    int layer = int(curved_reflector());
    ivec2 size = textureSize(virtual_images, 0).xy;
    vec4 v = texelFetch(virtual_images, ivec3(pixel, layer), 0);
    float nearest = 1e30;
    for (int dy = -CURVED_FILL; dy <= CURVED_FILL && v.a < 0.5; ++dy) {
        for (int dx = -CURVED_FILL; dx <= CURVED_FILL; ++dx) {
            ivec2 q = pixel + ivec2(dx, dy);
            if (any(lessThan(q, ivec2(0))) || any(greaterThanEqual(q, size))) continue;
            vec4 c = texelFetch(virtual_images, ivec3(q, layer), 0);
            float d2 = float(dx * dx + dy * dy);
            if (c.a > 0.5 && d2 < nearest) { nearest = d2; v.rgb = c.rgb; }
        }
    }
    vec3 reflected = (v.a > 0.5 || nearest < 1e30) ? v.rgb : sky_radiance(s.r);
    out_color = vec4(s.fr * reflected, 1.0);
}
