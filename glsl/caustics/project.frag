#version 460
#extension GL_GOOGLE_include_directive : require
// variants: CAUSTICS_PHOTON_MAP CAUSTICS_TEXTURE
// caustics.project (survey §6.3.3): the camera's diffuse surfaces again, at the depth
// scene.direct left, adding the caustics' radiance albedo/π · E (blended additively). The
// map-generation passes project inside their own shading (common/shading.glsl).
//
// CAUSTICS_TEXTURE (caustic_space=texture, SKALP05): the light map at the fragment's
// triangle (CAUSTIC_TRIANGLE_HERE, caustics/project.glsl).
#include "common/shading.glsl"

layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 2) in vec2 in_uv;
layout(location = 3) flat in uint in_view;
layout(location = 0) out vec4 out_color;

void main() {
    Material m = materials[objects[push.object].material];
    vec3 n = normalize(in_normal);
    vec3 v = views[in_view].eye.xyz - in_position;
    if (dot(n, v) < 0.0) n = -n;  // two-sided, as shade_diffuse
    // Screen space: the camera's view (view 0) reads its pixel; a mirrored view gets none.
#ifdef CAUSTICS_TEXTURE
    CAUSTIC_TRIANGLE_HERE();
    vec3 e = caustic_texture_irradiance(caustic_triangle, in_position, v);
#else
    vec3 e = (caustic.flags & CAUSTIC_SCREEN_SPACE) == 0u ? caustic_irradiance(in_position, n)
           : in_view == 0u                          ? caustic_screen_irradiance(ivec2(gl_FragCoord.xy), n, normalize(v))
                                                    : vec3(0.0);
#endif
    out_color = vec4(material_base_color(m, in_uv) / PI * e, 0.0);
}
