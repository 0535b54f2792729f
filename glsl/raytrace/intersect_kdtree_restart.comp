#version 460
#extension GL_GOOGLE_include_directive : require
// variants: GRADED_MEDIA
// kd-tree, pure kd-restart: from the root at each leaf's exit (survey §2.3.3, FS05).
#define KD_SHORT_STACK 0
#include "raytrace/kdtree.glsl"
#define INTERSECT intersect_kdtree
#include "raytrace/intersect_main.glsl"
