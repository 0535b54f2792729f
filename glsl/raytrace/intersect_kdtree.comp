#version 460
#extension GL_GOOGLE_include_directive : require
// variants: GRADED_MEDIA
// kd-tree, front to back with a short stack of 4 entries, restarting (from the push-down
// node) when it runs dry (survey §2.3.3, HSHH07).
#define KD_SHORT_STACK 4
#include "raytrace/kdtree.glsl"
#define INTERSECT intersect_kdtree
#include "raytrace/intersect_main.glsl"
