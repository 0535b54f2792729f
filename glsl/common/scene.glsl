// The frame's descriptor set (set 0), shared by every pass that draws the scene.
// Bindings that a scene does not need (no lights, no textures, no specular objects) hold
// null descriptors (VK_EXT_robustness2 nullDescriptor), so nothing is allocated for them.
#ifndef SCENE_GLSL
#define SCENE_GLSL

struct View {
    mat4 view_proj;      // world -> clip (reversed-Z, Vulkan y-down)
    mat4 inv_view_proj;  // clip -> world, for the sky
    vec4 eye;            // xyz: eye or reference point; w: 0 radial distance, 1 planar distance
    vec4 dir;            // xyz: direction for planar distance (directional shadow maps)
};

const uint KIND_DIFFUSE = 0u;
const uint KIND_MIRROR = 1u;
const uint KIND_DIELECTRIC = 2u;

struct Material {
    vec4 base_color;     // rgb linear albedo, a: unused
    vec4 emissive;       // rgb emitted radiance
    vec4 nu;             // mirror: ν per rgb; dielectric: x = ior
    vec4 kappa;          // mirror: κ per rgb
    vec4 specular;       // rgb KHR_materials_specular colour, a factor
    uint kind;
    int base_texture;    // -1: none
    int emissive_texture;
    uint thin;           // dielectric: thin-walled
};

struct Object {
    uint material;
    int envmap_layer;    // cube index in the environment/distance-map arrays, -1: none
    int refractor_layer; // cube index in the refractor-map array, -1: none
    uint map_shading;    // how it looks in other objects' distance maps: MAP_SHADING_*
    vec4 reference_point; // xyz; w: proxy sphere radius (§3.2)
    vec4 proxy_min;       // proxy box (§3.2), world space
    vec4 proxy_max;
};

// How a specular object is drawn into the other objects' distance maps (§4.3), when the
// frame runs inter-object cycles (FLAG_INTER_OBJECT): the environment only, its own
// distance map of the previous cycle, or self refraction in its refractor map (§4.4).
const uint MAP_SHADING_SKY = 0u;
const uint MAP_SHADING_TRACED = 1u;
const uint MAP_SHADING_REFRACTOR = 2u;

const uint LIGHT_POINT = 0u;
const uint LIGHT_SPOT = 1u;
const uint LIGHT_DIRECTIONAL = 2u;

struct Light {
    vec4 position_range;   // xyz position, w range (0: unbounded)
    vec4 direction_kind;   // xyz direction the light travels, w kind
    vec4 intensity;        // rgb W/sr (point, spot) or W/m^2 (directional); w: directional shadow texel [m]
    vec4 cone;             // x cos(outer), y cos(inner), z shadow layer (-1 none), w shadow map size
    mat4 shadow_view_proj; // directional: world -> shadow clip
};

layout(std430, set = 0, binding = 0) readonly buffer Views { View views[]; };
layout(std430, set = 0, binding = 1) readonly buffer Materials { Material materials[]; };
layout(std430, set = 0, binding = 2) readonly buffer Objects { Object objects[]; };
layout(std430, set = 0, binding = 3) readonly buffer Lights { Light lights[]; };
// All base-colour and emissive textures as layers of one array: lavapipe has no
// dynamic indexing of sampler arrays (shaderSampledImageArrayDynamicIndexing = false).
layout(set = 0, binding = 4) uniform sampler2DArray textures;
layout(set = 0, binding = 5) uniform sampler2D environment_map;
layout(set = 0, binding = 6) uniform samplerCubeArray shadow_cubes;
layout(set = 0, binding = 7) uniform sampler2DArray shadow_planes;
layout(set = 0, binding = 8) uniform samplerCubeArray envmaps;

// Maps of ray tracing in the sampled geometry (survey §4), bound per pass as set 1.
layout(set = 1, binding = 0) uniform samplerCubeArray distance_maps;   // rgb radiance, a distance
layout(set = 1, binding = 1) uniform samplerCubeArray refractor_maps;  // xyz normal, w distance
layout(set = 1, binding = 2) uniform sampler2D backface_map;           // xyz normal, w distance from the eye

const uint FLAG_FRESNEL_EXACT = 1u;
const uint FLAG_HAS_ENVIRONMENT = 2u;
// Specular objects drawn into maps search their own (previous-cycle) distance maps (§4.3).
const uint FLAG_INTER_OBJECT = 4u;
// Proxy geometry of localised environment mapping (§3.2): box, else sphere.
const uint FLAG_PROXY_BOX = 8u;
// First inter-object cycle: no map holds anything yet, specular objects in maps are black
// (paths longer than the requested depth end black, as in the reference).
const uint FLAG_FIRST_CYCLE = 16u;

layout(push_constant) uniform Push {
    uint view;         // first view of this draw (multiview adds gl_ViewIndex)
    uint object;
    uint flags;
    uint light_count;
    // Search knobs (§4.1).
    uint linear_steps;        // 0: parallax correction only
    uint secant_steps;
    uint binary_steps;
    uint parallax_iterations;
    float tolerance;         // early exit when | |l|/|l'| − 1 | ≤ tolerance
    uint internal_bounces;   // self refraction: total internal reflections followed (§4.4)
    uint pad0;
    uint pad1;
} push;

#endif
