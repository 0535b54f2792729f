#version 460
// The nearest triangle's id per pixel (the depth test keeps it).
layout(location = 0) flat in uint triangle_id;
layout(location = 0) out uint id_out;

void main() {
    id_out = triangle_id;
}
