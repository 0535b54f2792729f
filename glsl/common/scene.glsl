// What every scene-drawing shader shares with the Rust side: the structs (View, Material,
// Object, Light, SearchKnobs), the consts (KIND_*, LIGHT_*, MAP_SHADING_*, FLAG_*), the
// descriptor sets 0 (frame) and 1 (maps) and the push constants (`push`). All of it is
// declared once in src/frame/layout.in.rs; build.rs writes `generated/layout.glsl` from it.
#ifndef SCENE_GLSL
#define SCENE_GLSL

#include "generated/layout.glsl"

// A camera shader's interpolated inputs: at each sample's position in its PER_SAMPLE
// variant (aa=msaaN with msaa_shading=sample runs it once per sample), else at the pixel.
#ifdef PER_SAMPLE
#define SAMPLE_INTERP sample
#else
#define SAMPLE_INTERP
#endif

#endif
