#version 460
#extension GL_GOOGLE_include_directive : require
// variants: GRADED_MEDIA
// BVH, nearest child first with a short stack (survey §2.3.5).
#include "raytrace/bvh.glsl"
#define INTERSECT intersect_bvh
#include "raytrace/intersect_main.glsl"
