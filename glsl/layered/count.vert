#version 460
// layered.count (survey §4.5): the scene's depth complexity seen from the layered map's
// reference point, one cube face per draw: every surface along a texel's ray adds one.
// The face's view-projection comes in the push constants (this pass runs before the
// frame's view table exists).
layout(push_constant) uniform CountPush { mat4 view_proj; } count;

layout(location = 0) in vec3 in_position;

void main() {
    gl_Position = count.view_proj * vec4(in_position, 1.0);
}
