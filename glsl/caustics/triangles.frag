#version 460
// caustics.triangles: a caustic triangle's radiant intensity, blended additively; a small
// triangle's share of it in each of the 2×2 texels around its centroid (tent weights).
layout(location = 0) flat in vec3 in_intensity;
layout(location = 1) flat in vec2 in_centre;
layout(location = 2) flat in float in_tent;
layout(location = 0) out vec4 out_intensity;

void main() {
    float w = 1.0;
    if (in_tent != 0.0) {
        vec2 d = abs(gl_FragCoord.xy - in_centre);
        w = max(1.0 - d.x, 0.0) * max(1.0 - d.y, 0.0);
        if (w <= 0.0) discard;
    }
    out_intensity = vec4(in_intensity * w, 0.0);
}
