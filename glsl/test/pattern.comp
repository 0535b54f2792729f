#version 460
// Backend test: writes a known pattern, value(x, y) = x + 1000 y, into a storage image.
layout(local_size_x = 8, local_size_y = 8) in;
layout(set = 0, binding = 0, r32f) uniform writeonly image2D target;
layout(push_constant) uniform Push { float scale; } push;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (any(greaterThanEqual(p, imageSize(target)))) return;
    imageStore(target, p, vec4(push.scale * float(p.x + 1000 * p.y)));
}
