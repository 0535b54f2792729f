/* misuse.c — every misuse the C ABI promises to survive, called from C: each returns its
 * code and a message, and the process goes on. Exits 0 when every case behaved. */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <stddef.h>

#include "specula.h"

static int failures = 0;

/* The log callback sees every error message. */
static int logged = 0;
static char last_logged[256];
static void on_log(void *user, SpeculaLogLevel level, const char *message) {
    ++*(int *)user;
    if (level == SPECULA_LOG_ERROR) snprintf(last_logged, sizeof last_logged, "%s", message);
}

static void expect(const char *what, SpeculaResult got, SpeculaResult want, const char *message) {
    int ok = got == want && message != NULL && (want == SPECULA_SUCCESS || strlen(message) > 0);
    printf("%-44s %4d (want %4d) %s: %s\n", what, got, want, ok ? "ok" : "FAIL", message ? message : "(null)");
    if (!ok) ++failures;
}

/* The call first, then its message: C leaves argument evaluation order open. */
/* Same for the create calls, whose message lives per thread. */
#define CREATE_CASE(what, call, want)                           \
    do {                                                        \
        SpeculaResult got_ = (call);                            \
        expect(what, got_, (want), specula_creation_error());   \
    } while (0)
#define CASE(what, call, want)                                  \
    do {                                                        \
        SpeculaResult got_ = (call);                            \
        expect(what, got_, (want), specula_context_last_error(ctx)); \
    } while (0)

int main(int argc, char **argv) {
    const char *scene = argc > 1 ? argv[1] : "assets/demo/demo.gltf";
    SpeculaContext *ctx = NULL;

    /* Creation: NULL pointers, wrong tags and sizes. */
    SpeculaContextDesc desc = {SPECULA_STRUCT_CONTEXT_DESC, sizeof desc, NULL, 1};
    CREATE_CASE("create: NULL desc", specula_context_create(NULL, &ctx), SPECULA_ERROR_NULL_POINTER);
    CREATE_CASE("create: NULL out", specula_context_create(&desc, NULL), SPECULA_ERROR_NULL_POINTER);
    SpeculaContextDesc bad_tag = desc;
    bad_tag.type = SPECULA_STRUCT_MESH_DESC;
    CREATE_CASE("create: wrong struct tag", specula_context_create(&bad_tag, &ctx), SPECULA_ERROR_STRUCT_MISMATCH);
    SpeculaContextDesc bad_size = desc;
    bad_size.size = 4;
    CREATE_CASE("create: wrong struct size", specula_context_create(&bad_size, &ctx), SPECULA_ERROR_STRUCT_MISMATCH);
    SpeculaContextDesc no_device = desc;
    no_device.device_name = "no-such-device-anywhere";
    CREATE_CASE("create: no matching device", specula_context_create(&no_device, &ctx), SPECULA_ERROR_UNSUPPORTED);
    SpeculaHostDesc null_host = {SPECULA_STRUCT_HOST_DESC, sizeof null_host};
    CREATE_CASE("create_host: NULL handles", specula_context_create_host(&null_host, &ctx), SPECULA_ERROR_NULL_POINTER);
    SpeculaRequirements req = {SPECULA_STRUCT_REQUIREMENTS, 8};
    CREATE_CASE("requirements: wrong size", specula_get_requirements(&req), SPECULA_ERROR_STRUCT_MISMATCH);

    if (specula_context_create(&desc, &ctx) != SPECULA_SUCCESS) {
        printf("cannot create a context: %s\n", specula_creation_error());
        return 1;
    }
    unsigned char pixels[64 * 64 * 4];
    SpeculaRenderDesc render = {SPECULA_STRUCT_RENDER_DESC, sizeof render, SPECULA_METHOD_ENVMAP, 64, 64};

    /* Version and log callback. */
    expect("version is 0.1.x", (SpeculaResult)(specula_version() >> 12), (SpeculaResult)((0u << 10) | 1u), "VK_MAKE_API_VERSION(0, 0, 1, patch)");
    CASE("set_log_callback", specula_context_set_log_callback(ctx, on_log, &logged), SPECULA_SUCCESS);
    CASE("knob error goes to the log", specula_context_set_knob(ctx, "fresnel", "approximately"), SPECULA_ERROR_INVALID_ARGUMENT);
    expect("log callback called with the message", logged == 1 && strstr(last_logged, "fresnel") ? 0 : -1, 0, last_logged);
    CASE("remove log callback", specula_context_set_log_callback(ctx, NULL, NULL), SPECULA_SUCCESS);

    /* Calls in the wrong order. */
    CASE("render before configure", specula_context_render(ctx, SPECULA_PIXEL_RGBA8_SRGB, pixels, sizeof pixels), SPECULA_ERROR_WRONG_ORDER);
    uint32_t count = 0;
    CASE("timings before configure", specula_get_pass_timings(ctx, NULL, 0, &count), SPECULA_ERROR_WRONG_ORDER);
    CASE("configure an empty scene", specula_context_configure(ctx, &render), SPECULA_ERROR_INVALID_ARGUMENT);

    /* Bad scene input. */
    CASE("load_gltf: NULL path", specula_context_load_gltf(ctx, NULL), SPECULA_ERROR_NULL_POINTER);
    CASE("load_gltf: missing file", specula_context_load_gltf(ctx, "/nonexistent/scene.gltf"), SPECULA_ERROR_IO);
    SpeculaMaterialDesc glass = {SPECULA_STRUCT_MATERIAL_DESC, sizeof glass, SPECULA_SURFACE_DIELECTRIC, {1, 1, 1}, {0, 0, 0}, {1, 1, 1}, {0, 0, 0}, 0.0f, 0};
    CASE("material: IOR 0", specula_context_add_material(ctx, &glass, NULL), SPECULA_ERROR_INVALID_ARGUMENT);
    glass.ior = -1.5f;
    CASE("material: IOR < 0", specula_context_add_material(ctx, &glass, NULL), SPECULA_ERROR_INVALID_ARGUMENT);
    glass.ior = 1.5f;
    glass.surface = 77;
    CASE("material: unknown surface enum", specula_context_add_material(ctx, &glass, NULL), SPECULA_ERROR_INVALID_ARGUMENT);
    glass.surface = SPECULA_SURFACE_DIELECTRIC;
    glass.base_color[0] = 2.0f; /* refused by the glTF schema too: one material validation */
    CASE("material: base colour above 1", specula_context_add_material(ctx, &glass, NULL), SPECULA_ERROR_INVALID_ARGUMENT);
    expect("message names base_color and the value", strstr(specula_context_last_error(ctx), "base_color") && strstr(specula_context_last_error(ctx), "[2, 1, 1]") ? 0 : -1, 0,
           specula_context_last_error(ctx));
    glass.base_color[0] = 1.0f;
    glass.emission[2] = -1.0f;
    CASE("material: negative emission", specula_context_add_material(ctx, &glass, NULL), SPECULA_ERROR_INVALID_ARGUMENT);
    expect("message names emission and the value", strstr(specula_context_last_error(ctx), "emission") && strstr(specula_context_last_error(ctx), "-1") ? 0 : -1, 0,
           specula_context_last_error(ctx));
    glass.emission[2] = 0.0f;
    /* KHR_materials_volume's absorption: the colour in 0..1, the distance > 0 (0: none). */
    glass.attenuation_color[1] = 1.5f;
    glass.attenuation_distance = 2.0f;
    CASE("material: attenuation colour above 1", specula_context_add_material(ctx, &glass, NULL), SPECULA_ERROR_INVALID_ARGUMENT);
    expect("message names attenuation_color and the value", strstr(specula_context_last_error(ctx), "attenuation_color") && strstr(specula_context_last_error(ctx), "1.5") ? 0 : -1, 0,
           specula_context_last_error(ctx));
    glass.attenuation_color[1] = 0.5f;
    glass.attenuation_distance = -1.0f;
    CASE("material: negative attenuation distance", specula_context_add_material(ctx, &glass, NULL), SPECULA_ERROR_INVALID_ARGUMENT);
    glass.attenuation_distance = NAN;
    CASE("material: NaN attenuation distance", specula_context_add_material(ctx, &glass, NULL), SPECULA_ERROR_INVALID_ARGUMENT);
    glass.attenuation_distance = 0.0f;
    glass.dispersion = -0.5f;
    CASE("material: negative dispersion", specula_context_add_material(ctx, &glass, NULL), SPECULA_ERROR_INVALID_ARGUMENT);
    expect("message names dispersion and the value", strstr(specula_context_last_error(ctx), "dispersion") && strstr(specula_context_last_error(ctx), "-0.5") ? 0 : -1, 0,
           specula_context_last_error(ctx));
    glass.dispersion = 0.0f;
    /* A graded index (survey §6.5): a non-symmetric Hessian cannot be stored (the struct
       holds six entries), a NaN gradient is refused naming the field, a thin pane has no
       volume for it; a valid field is accepted. */
    glass.graded = 1;
    glass.index_gradient[1] = NAN;
    CASE("material: NaN index gradient", specula_context_add_material(ctx, &glass, NULL), SPECULA_ERROR_INVALID_ARGUMENT);
    expect("message names graded_index.gradient", strstr(specula_context_last_error(ctx), "graded_index.gradient") ? 0 : -1, 0,
           specula_context_last_error(ctx));
    glass.index_gradient[1] = 0.2f;
    glass.thin = 1;
    CASE("material: graded thin pane", specula_context_add_material(ctx, &glass, NULL), SPECULA_ERROR_INVALID_ARGUMENT);
    glass.thin = 0;
    glass.index_hessian[3] = -0.5f; /* xy */
    CASE("material: graded index", specula_context_add_material(ctx, &glass, NULL), SPECULA_SUCCESS);
    /* A host built against the volume release's header (no graded fields) gets a uniform index. */
    glass.size = (uint32_t)offsetof(SpeculaMaterialDesc, graded);
    glass.index_gradient[1] = NAN; /* beyond its size: never read */
    CASE("material of the volume release's size", specula_context_add_material(ctx, &glass, NULL), SPECULA_SUCCESS);
    glass.size = sizeof glass;
    glass.graded = 0;
    glass.index_gradient[1] = 0.0f;
    glass.index_hessian[3] = 0.0f;
    /* A host built against the first release's header (no volume fields) still adds glass. */
    glass.size = (uint32_t)offsetof(SpeculaMaterialDesc, attenuation_color);
    glass.attenuation_distance = -1.0f; /* beyond its size: never read */
    CASE("material of the first release's size", specula_context_add_material(ctx, &glass, NULL), SPECULA_SUCCESS);
    glass.size = (uint32_t)offsetof(SpeculaMaterialDesc, attenuation_color) - 4;
    CASE("material shorter than the first release", specula_context_add_material(ctx, &glass, NULL), SPECULA_ERROR_STRUCT_MISMATCH);
    glass.size = sizeof glass;
    glass.attenuation_distance = 0.0f;
    uint32_t mat = 99;
    CASE("material: valid", specula_context_add_material(ctx, &glass, &mat), SPECULA_SUCCESS);
    float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    uint32_t idx[3] = {0, 1, 2};
    SpeculaMeshDesc mesh = {SPECULA_STRUCT_MESH_DESC, sizeof mesh, pos, NULL, 3, idx, 3, NULL, mat};
    SpeculaMeshDesc m2 = mesh;
    m2.positions = NULL;
    CASE("mesh: NULL positions", specula_context_add_mesh(ctx, &m2, NULL), SPECULA_ERROR_NULL_POINTER);
    uint32_t bad_idx[3] = {0, 1, 7};
    m2 = mesh;
    m2.indices = bad_idx;
    CASE("mesh: index out of range", specula_context_add_mesh(ctx, &m2, NULL), SPECULA_ERROR_INVALID_ARGUMENT);
    expect("message names the index and the value", strstr(specula_context_last_error(ctx), "mesh.indices[2]: 7") ? 0 : -1, 0, specula_context_last_error(ctx));
    float nan_pos[9] = {0, 0, 0, NAN, 0, 0, 0, 1, 0};
    m2 = mesh;
    m2.positions = nan_pos;
    CASE("mesh: NaN position", specula_context_add_mesh(ctx, &m2, NULL), SPECULA_ERROR_INVALID_ARGUMENT);
    expect("message names the vertex as given", strstr(specula_context_last_error(ctx), "mesh.positions: vertex 1") ? 0 : -1, 0, specula_context_last_error(ctx));
    float flat[16] = {1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}; /* scale y = 0 */
    m2 = mesh;
    m2.transform = flat;
    CASE("mesh: zero-scale transform", specula_context_add_mesh(ctx, &m2, NULL), SPECULA_ERROR_INVALID_ARGUMENT);
    expect("message names the transform and its determinant", strstr(specula_context_last_error(ctx), "mesh.transform") && strstr(specula_context_last_error(ctx), "determinant 0") ? 0 : -1, 0,
           specula_context_last_error(ctx));
    flat[5] = 1.0f;
    flat[13] = NAN;
    CASE("mesh: NaN transform", specula_context_add_mesh(ctx, &m2, NULL), SPECULA_ERROR_INVALID_ARGUMENT);
    expect("message names the transform entry", strstr(specula_context_last_error(ctx), "mesh.transform") && strstr(specula_context_last_error(ctx), "NaN at column 3 row 1") ? 0 : -1, 0,
           specula_context_last_error(ctx));
    m2 = mesh;
    m2.material = 12345;
    CASE("mesh: material out of range", specula_context_add_mesh(ctx, &m2, NULL), SPECULA_ERROR_INVALID_ARGUMENT);
    m2 = mesh;
    m2.type = SPECULA_STRUCT_LIGHT_DESC;
    CASE("mesh: wrong struct tag", specula_context_add_mesh(ctx, &m2, NULL), SPECULA_ERROR_STRUCT_MISMATCH);
    SpeculaLightDesc light = {SPECULA_STRUCT_LIGHT_DESC, sizeof light, 9};
    CASE("light: unknown kind enum", specula_context_add_light(ctx, &light), SPECULA_ERROR_INVALID_ARGUMENT);
    light.kind = SPECULA_LIGHT_POINT;
    light.intensity[1] = -2.0f;
    CASE("light: negative intensity", specula_context_add_light(ctx, &light), SPECULA_ERROR_INVALID_ARGUMENT);
    expect("message names the field and the value", strstr(specula_context_last_error(ctx), "intensity") && strstr(specula_context_last_error(ctx), "-2") ? 0 : -1, 0,
           specula_context_last_error(ctx));
    light.intensity[1] = 1.0f;
    light.range = -1.0f;
    CASE("light: negative range", specula_context_add_light(ctx, &light), SPECULA_ERROR_INVALID_ARGUMENT);
    expect("message names range and the value", strstr(specula_context_last_error(ctx), "range") && strstr(specula_context_last_error(ctx), "-1") ? 0 : -1, 0,
           specula_context_last_error(ctx));
    light.range = 0.0f;

    /* Knobs and camera. */
    CASE("knob: out of range", specula_context_set_knob(ctx, "cube_size", "100000"), SPECULA_ERROR_INVALID_ARGUMENT);
    CASE("knob: unknown", specula_context_set_knob(ctx, "warp_speed", "9"), SPECULA_ERROR_INVALID_ARGUMENT);
    CASE("knob: NULL value", specula_context_set_knob(ctx, "cube_size", NULL), SPECULA_ERROR_NULL_POINTER);
    SpeculaCameraDesc cam = {SPECULA_STRUCT_CAMERA_DESC, sizeof cam, {0, 1, NAN}, {0, 0, 0}, 1.0f, 0.01f};
    CASE("camera: NaN position", specula_context_set_camera(ctx, &cam), SPECULA_ERROR_INVALID_ARGUMENT);
    cam.position[2] = 3.0f;
    cam.yfov = 0.0f;
    CASE("camera: zero field of view", specula_context_set_camera(ctx, &cam), SPECULA_ERROR_INVALID_ARGUMENT);
    expect("message names yfov", strstr(specula_context_last_error(ctx), "camera.yfov") ? 0 : -1, 0, specula_context_last_error(ctx));
    cam.yfov = 1.0f;
    cam.znear = INFINITY;
    CASE("camera: infinite znear", specula_context_set_camera(ctx, &cam), SPECULA_ERROR_INVALID_ARGUMENT);
    expect("message names znear and the value", strstr(specula_context_last_error(ctx), "camera.znear") && strstr(specula_context_last_error(ctx), "inf") ? 0 : -1, 0,
           specula_context_last_error(ctx));
    cam.znear = 0.01f;
    cam.target[0] = cam.position[0], cam.target[1] = cam.position[1], cam.target[2] = cam.position[2];
    CASE("camera: target equals position", specula_context_set_camera(ctx, &cam), SPECULA_ERROR_INVALID_ARGUMENT);

    /* A valid frame, then misuse around it. */
    CASE("load_gltf: demo", specula_context_load_gltf(ctx, scene), SPECULA_SUCCESS);
    CASE("knob: cube_size=32", specula_context_set_knob(ctx, "cube_size", "32"), SPECULA_SUCCESS);
    SpeculaRenderDesc bad_method = render;
    bad_method.method = 42;
    CASE("configure: unknown method enum", specula_context_configure(ctx, &bad_method), SPECULA_ERROR_INVALID_ARGUMENT);
    SpeculaRenderDesc zero = render;
    zero.width = 0;
    CASE("configure: zero width", specula_context_configure(ctx, &zero), SPECULA_ERROR_INVALID_ARGUMENT);
    CASE("configure: valid", specula_context_configure(ctx, &render), SPECULA_SUCCESS);
    CASE("render: unknown pixel format", specula_context_render(ctx, 5, pixels, sizeof pixels), SPECULA_ERROR_INVALID_ARGUMENT);
    CASE("render: buffer too small", specula_context_render(ctx, SPECULA_PIXEL_RGBA8_SRGB, pixels, 100), SPECULA_ERROR_BUFFER_TOO_SMALL);
    CASE("render: NULL dst", specula_context_render(ctx, SPECULA_PIXEL_RGBA8_SRGB, NULL, sizeof pixels), SPECULA_ERROR_NULL_POINTER);
    CASE("render: valid", specula_context_render(ctx, SPECULA_PIXEL_RGBA8_SRGB, pixels, sizeof pixels), SPECULA_SUCCESS);
    /* Every method the header names configures and renders (64², small maps). */
    const SpeculaMethod methods[] = {SPECULA_METHOD_ENVMAP,   SPECULA_METHOD_PROXY_SPHERE,   SPECULA_METHOD_PROXY_BOX,
                                     SPECULA_METHOD_DISTANCE, SPECULA_METHOD_DISTANCE_MULTI, SPECULA_METHOD_REFRACTOR_MAP,
                                     SPECULA_METHOD_IMAGE_SPACE_REFRACTION};
    CASE("knob: cycles=2", specula_context_set_knob(ctx, "cycles", "2"), SPECULA_SUCCESS);
    for (unsigned i = 0; i < sizeof methods / sizeof methods[0]; ++i) {
        SpeculaRenderDesc each = render;
        each.method = methods[i];
        CASE("configure each method", specula_context_configure(ctx, &each), SPECULA_SUCCESS);
        CASE("render each method", specula_context_render(ctx, SPECULA_PIXEL_RGBA8_SRGB, pixels, sizeof pixels), SPECULA_SUCCESS);
    }
    /* Per-object methods: auto, names, overrides, and every way to get them wrong. */
    SpeculaRenderDesc auto_desc = render;
    auto_desc.method = SPECULA_METHOD_AUTO;
    CASE("configure: auto", specula_context_configure(ctx, &auto_desc), SPECULA_SUCCESS);
    CASE("render: auto", specula_context_render(ctx, SPECULA_PIXEL_RGBA8_SRGB, pixels, sizeof pixels), SPECULA_SUCCESS);
    uint32_t objects = 0;
    CASE("object_count", specula_context_object_count(ctx, &objects), SPECULA_SUCCESS);
    expect("the demo has objects", objects >= 8 ? 0 : -1, 0, "object count");
    CASE("object_count: NULL out", specula_context_object_count(ctx, NULL), SPECULA_ERROR_NULL_POINTER);
    char name[64];
    CASE("object_name: 0", specula_context_object_name(ctx, 0, name, sizeof name), SPECULA_SUCCESS);
    char tiny[3];
    CASE("object_name: truncated", specula_context_object_name(ctx, 0, tiny, sizeof tiny), SPECULA_WARNING_TRUNCATED);
    expect("truncated name is NUL-terminated", strlen(tiny) == 2 ? 0 : -1, 0, tiny);
    CASE("object_name: index out of range", specula_context_object_name(ctx, objects, name, sizeof name), SPECULA_ERROR_INVALID_ARGUMENT);
    CASE("object_name: NULL buffer", specula_context_object_name(ctx, 0, NULL, 8), SPECULA_ERROR_NULL_POINTER);
    CASE("set_object_method: mirror=distance", specula_context_set_object_method(ctx, "mirror_sphere", SPECULA_METHOD_DISTANCE), SPECULA_SUCCESS);
    CASE("set_object_method: glass=refractor-map", specula_context_set_object_method(ctx, "glass_sphere", SPECULA_METHOD_REFRACTOR_MAP), SPECULA_SUCCESS);
    CASE("configure: mixed methods", specula_context_configure(ctx, &auto_desc), SPECULA_SUCCESS);
    CASE("render: mixed methods", specula_context_render(ctx, SPECULA_PIXEL_RGBA8_SRGB, pixels, sizeof pixels), SPECULA_SUCCESS);
    CASE("set_object_method: unknown object", specula_context_set_object_method(ctx, "teapot", SPECULA_METHOD_DISTANCE), SPECULA_ERROR_INVALID_ARGUMENT);
    expect("message names the object", strstr(specula_context_last_error(ctx), "'teapot'") ? 0 : -1, 0, specula_context_last_error(ctx));
    CASE("set_object_method: unknown method", specula_context_set_object_method(ctx, "mirror_sphere", 42), SPECULA_ERROR_INVALID_ARGUMENT);
    CASE("set_object_method: CPU method", specula_context_set_object_method(ctx, "mirror_sphere", SPECULA_METHOD_REFERENCE), SPECULA_ERROR_INVALID_ARGUMENT);
    CASE("set_object_method: cannot serve", specula_context_set_object_method(ctx, "mirror_sphere", SPECULA_METHOD_REFRACTOR_MAP), SPECULA_ERROR_INVALID_ARGUMENT);
    expect("message says why", strstr(specula_context_last_error(ctx), "cannot serve a mirror") ? 0 : -1, 0, specula_context_last_error(ctx));
    CASE("set_object_method: diffuse object", specula_context_set_object_method(ctx, "wall_floor", SPECULA_METHOD_DISTANCE), SPECULA_ERROR_INVALID_ARGUMENT);
    CASE("set_object_method: NULL name", specula_context_set_object_method(ctx, NULL, SPECULA_METHOD_DISTANCE), SPECULA_ERROR_NULL_POINTER);
    CASE("set_object_method_at: out of range", specula_context_set_object_method_at(ctx, 100000, SPECULA_METHOD_DISTANCE), SPECULA_ERROR_INVALID_ARGUMENT);
    CASE("set_object_method: auto clears", specula_context_set_object_method(ctx, "glass_sphere", SPECULA_METHOD_AUTO), SPECULA_SUCCESS);
    CASE("configure after the errors", specula_context_configure(ctx, &auto_desc), SPECULA_SUCCESS);
    CASE("render after the errors", specula_context_render(ctx, SPECULA_PIXEL_RGBA8_SRGB, pixels, sizeof pixels), SPECULA_SUCCESS);
    /* The budgeted planner: the stored defaults cover the demo's mirror and glass. */
    SpeculaRenderDesc budget = auto_desc;
    budget.min_psnr_db = 20.0;
    CASE("configure: min_psnr_db", specula_context_configure(ctx, &budget), SPECULA_SUCCESS);
    CASE("predictions: count", specula_get_predictions(ctx, NULL, 0, &count), SPECULA_WARNING_TRUNCATED);
    expect("a prediction per object and the frame", count == 3 ? 0 : -1, 0, "prediction count");
    SpeculaPrediction predictions[3];
    CASE("predictions: all", specula_get_predictions(ctx, predictions, 3, &count), SPECULA_SUCCESS);
    expect("the last one is the frame", strcmp(predictions[2].name, "frame") == 0 && predictions[2].predicted_ms > 0.0 ? 0 : -1, 0, predictions[2].name);
    CASE("predictions: NULL count", specula_get_predictions(ctx, predictions, 3, NULL), SPECULA_ERROR_NULL_POINTER);
    CASE("render: budgeted", specula_context_render(ctx, SPECULA_PIXEL_RGBA8_SRGB, pixels, sizeof pixels), SPECULA_SUCCESS);
    SpeculaRenderDesc both = budget;
    both.max_ms = 10.0;
    CASE("configure: both budgets", specula_context_configure(ctx, &both), SPECULA_ERROR_INVALID_ARGUMENT);
    expect("message names the budget", strstr(specula_context_last_error(ctx), "budget") ? 0 : -1, 0, specula_context_last_error(ctx));
    SpeculaRenderDesc negative = auto_desc;
    negative.max_ms = -1.0;
    CASE("configure: negative max_ms", specula_context_configure(ctx, &negative), SPECULA_ERROR_INVALID_ARGUMENT);
    expect("message names the field", strstr(specula_context_last_error(ctx), "max_ms") ? 0 : -1, 0, specula_context_last_error(ctx));
    SpeculaRenderDesc not_auto = budget;
    not_auto.method = SPECULA_METHOD_ENVMAP;
    CASE("configure: budget without auto", specula_context_configure(ctx, &not_auto), SPECULA_ERROR_INVALID_ARGUMENT);
    SpeculaRenderDesc missing = budget;
    missing.models_path = "no/such/models.json";
    CASE("configure: missing models file", specula_context_configure(ctx, &missing), SPECULA_ERROR_IO);
    expect("message names the file", strstr(specula_context_last_error(ctx), "no/such/models.json") ? 0 : -1, 0, specula_context_last_error(ctx));
    SpeculaRenderDesc v1 = auto_desc;
    v1.size = SPECULA_RENDER_DESC_SIZE_V1;
    v1.min_psnr_db = 99.0; /* past the first version's size: not read */
    CASE("configure: first-version desc", specula_context_configure(ctx, &v1), SPECULA_SUCCESS);
    CASE("render: first-version desc", specula_context_render(ctx, SPECULA_PIXEL_RGBA8_SRGB, pixels, sizeof pixels), SPECULA_SUCCESS);
    CASE("predictions: none without a budget", specula_get_predictions(ctx, NULL, 0, &count), SPECULA_SUCCESS);
    expect("no predictions", count == 0 ? 0 : -1, 0, "prediction count");
    SpeculaRenderDesc short_desc = auto_desc;
    short_desc.size = SPECULA_RENDER_DESC_SIZE_V1 + 4;
    CASE("configure: desc between versions", specula_context_configure(ctx, &short_desc), SPECULA_ERROR_STRUCT_MISMATCH);
    SpeculaPassTiming one[1];
    CASE("timings: capacity 1", specula_get_pass_timings(ctx, one, 1, &count), SPECULA_WARNING_TRUNCATED);
    CASE("timings: NULL out with capacity", specula_get_pass_timings(ctx, NULL, 4, &count), SPECULA_ERROR_NULL_POINTER);
    SpeculaHostImage target = {SPECULA_STRUCT_HOST_IMAGE, sizeof target, 1, 0, 109, 64, 64, 0, 7, NULL};
    CASE("record on a standalone context", specula_context_record(ctx, (void *)1, &target), SPECULA_ERROR_WRONG_ORDER);
    CASE("scene changed after configure", specula_context_add_material(ctx, &glass, NULL), SPECULA_SUCCESS);
    CASE("render with a stale configuration", specula_context_render(ctx, SPECULA_PIXEL_RGBA8_SRGB, pixels, sizeof pixels), SPECULA_ERROR_WRONG_ORDER);

    /* A destroyed handle, used again. */
    expect("destroy", specula_context_destroy(ctx), SPECULA_SUCCESS, "");
    CASE("destroy twice", specula_context_destroy(ctx), SPECULA_ERROR_INVALID_HANDLE);
    CASE("render on a destroyed handle", specula_context_render(ctx, SPECULA_PIXEL_RGBA8_SRGB, pixels, sizeof pixels), SPECULA_ERROR_INVALID_HANDLE);
    expect("set_knob on a foreign pointer", specula_context_set_knob((SpeculaContext *)pixels, "cube_size", "32"), SPECULA_ERROR_INVALID_HANDLE,
           specula_context_last_error((SpeculaContext *)pixels));
    expect("NULL handle", specula_context_configure(NULL, &render), SPECULA_ERROR_INVALID_HANDLE, specula_context_last_error(NULL));

    printf("%d failure(s)\n", failures);
    return failures ? 1 : 0;
}
