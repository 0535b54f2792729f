#version 460
#extension GL_GOOGLE_include_directive : require
// variants: GRADED_MEDIA
// BVH, stackless along hit/miss links (survey §2.3.5, CHCH06).
#include "raytrace/bvh.glsl"
#define INTERSECT intersect_bvh_stackless
#include "raytrace/intersect_main.glsl"
