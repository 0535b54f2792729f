#version 460
#extension GL_GOOGLE_include_directive : require
// geometry.image: position (w 1: covered) and unit normal of the texel's surface point.
layout(location = 0) in vec3 in_position;
layout(location = 1) in vec3 in_normal;
layout(location = 0) out vec4 out_position;
layout(location = 1) out vec4 out_normal;

void main() {
    out_position = vec4(in_position, 1.0);
    vec3 n = in_normal;
    out_normal = vec4(dot(n, n) > 0.0 ? normalize(n) : vec3(0.0), 0.0);
}
