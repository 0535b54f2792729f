#version 460
// caustics.triangles: a caustic triangle's radiant intensity, blended additively.
layout(location = 0) flat in vec3 in_intensity;
layout(location = 0) out vec4 out_intensity;

void main() {
    out_intensity = vec4(in_intensity, 0.0);
}
