#version 460
#extension GL_GOOGLE_include_directive : require
// caustics.screen (caustic_space=screen, LC04/WD06b), first: every surface from the camera
// into the pass's depth buffer, so that the splats that follow land only where their photon
// is the surface the camera sees (blended additively: nothing is added to the irradiance).
#include "common/scene.glsl"

layout(location = 0) out vec4 out_irradiance;

void main() {
    out_irradiance = vec4(0.0);
}
