// Curved reflectors by geometry transformation (survey §5, EMD*05/EMDT06): what the
// geometry image, the reflection-point search and the virtual objects share.
#ifndef GEOMETRY_CURVED_GLSL
#define GEOMETRY_CURVED_GLSL
#include "common/scene.glsl"

// The reflector layer of a `geometry.virtual` or `geometry.curved` draw.
uint curved_reflector() {
    return push.flags >> CURVED_REFLECTOR_SHIFT;
}
#endif
