/* updates.c — frames over time from C: a mirror moved every frame, a material and a light
 * changed, the maps each frame rebuilt and why, misuse (NaN, zero scale, unknown object,
 * NULL, a change of kind) answered with a code and a message while the previous state stays,
 * and a 1000-frame loop with an update every frame whose C heap stays flat.
 * Prints "N failure(s)"; exits 0 when every case behaved. */
#define _GNU_SOURCE /* setenv, mallinfo2 */
#include <malloc.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "specula.h"

#define W 16
#define H 12

static int failures = 0;

static void check(const char *what, int ok, const char *detail) {
    printf("%-52s %s %s\n", what, ok ? "ok" : "FAIL", detail ? detail : "");
    if (!ok) ++failures;
}

static void expect(SpeculaContext *ctx, const char *what, SpeculaResult got, SpeculaResult want) {
    const char *msg = specula_context_last_error(ctx);
    char detail[600];
    snprintf(detail, sizeof detail, "(%d, want %d): %s", got, want, msg ? msg : "(null)");
    check(what, got == want && (want == SPECULA_SUCCESS || (msg && strlen(msg) > 0)), detail);
}

/* The maps the last frame rebuilt, as "stage(reason) stage(reason)". */
static void updates(SpeculaContext *ctx, char *out, size_t size) {
    SpeculaMapUpdate u[8];
    uint32_t n = 0;
    out[0] = 0;
    if (specula_get_map_updates(ctx, u, 8, &n) < 0) {
        snprintf(out, size, "error: %s", specula_context_last_error(ctx));
        return;
    }
    for (uint32_t i = 0; i < n && i < 8; ++i) {
        size_t len = strlen(out);
        snprintf(out + len, size - len, "%s%s(%s)", i ? " " : "", u[i].stage, u[i].reason);
    }
}

static void translation(float m[16], float x, float y, float z) {
    memset(m, 0, 16 * sizeof(float));
    m[0] = m[5] = m[10] = m[15] = 1.0f;
    m[12] = x, m[13] = y, m[14] = z;
}

/* Materials 0 (diffuse) and 1 (mirror), meshes 0 (floor) and 1 (a mirror octahedron above
 * it), light 0 (point), a camera; the distance-map method at W×H with small maps. */
/* A UV sphere of radius 0.5: SEG × RINGS quads. */
#define SEG 40
#define RINGS 20
static float sphere_p[(SEG + 1) * (RINGS + 1) * 3];
static uint32_t sphere_i[SEG * RINGS * 6];
static void make_sphere(void) {
    for (int r = 0; r <= RINGS; ++r)
        for (int k = 0; k <= SEG; ++k) {
            float th = 3.14159265f * r / RINGS, ph = 6.2831853f * k / SEG;
            float *p = &sphere_p[3 * (r * (SEG + 1) + k)];
            p[0] = 0.5f * sinf(th) * cosf(ph), p[1] = 0.5f * cosf(th), p[2] = 0.5f * sinf(th) * sinf(ph);
        }
    uint32_t *t = sphere_i;
    for (int r = 0; r < RINGS; ++r)
        for (int k = 0; k < SEG; ++k) {
            uint32_t a = r * (SEG + 1) + k, b = a + SEG + 1;
            *t++ = a, *t++ = a + 1, *t++ = b, *t++ = a + 1, *t++ = b + 1, *t++ = b;
        }
}

/* sphere = 0: the mirror is an octahedron; 1: a UV sphere of (SEG + 1)(RINGS + 1) vertices. */
static SpeculaContext *create(SpeculaMaterialDesc *white, SpeculaLightDesc *light, int sphere) {
    SpeculaContextDesc desc = {SPECULA_STRUCT_CONTEXT_DESC, sizeof desc, NULL, 1};
    SpeculaContext *ctx = NULL;
    if (specula_context_create(&desc, &ctx) != SPECULA_SUCCESS) {
        check("specula_context_create", 0, specula_creation_error());
        return NULL;
    }
    SpeculaMaterialDesc mirror = {SPECULA_STRUCT_MATERIAL_DESC, sizeof mirror, SPECULA_SURFACE_MIRROR, {1, 1, 1}, {0, 0, 0},
                                  {0.2f, 0.2f, 0.2f}, {3.0f, 3.0f, 3.0f}};
    uint32_t m_white = 0, m_mirror = 0, floor_id = 0, mirror_id = 0;
    expect(ctx, "add material (diffuse)", specula_context_add_material(ctx, white, &m_white), SPECULA_SUCCESS);
    expect(ctx, "add material (mirror)", specula_context_add_material(ctx, &mirror, &m_mirror), SPECULA_SUCCESS);
    static const float floor_p[] = {-2, 0, -2, 2, 0, -2, 2, 0, 2, -2, 0, 2};
    static const uint32_t floor_i[] = {0, 2, 1, 0, 3, 2};
    SpeculaMeshDesc floor_d = {SPECULA_STRUCT_MESH_DESC, sizeof floor_d, floor_p, NULL, 4, floor_i, 6, NULL, m_white};
    expect(ctx, "add mesh (floor)", specula_context_add_mesh(ctx, &floor_d, &floor_id), SPECULA_SUCCESS);
    static const float oct_p[] = {0.5f, 0, 0, -0.5f, 0, 0, 0, 0.5f, 0, 0, -0.5f, 0, 0, 0, 0.5f, 0, 0, -0.5f};
    static const uint32_t oct_i[] = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};
    float start[16];
    translation(start, 0.0f, 0.8f, 0.0f);
    SpeculaMeshDesc oct_d = {SPECULA_STRUCT_MESH_DESC, sizeof oct_d, oct_p, NULL, 6, oct_i, 24, start, m_mirror};
    if (sphere) {
        make_sphere();
        oct_d.positions = sphere_p, oct_d.vertex_count = (SEG + 1) * (RINGS + 1);
        oct_d.indices = sphere_i, oct_d.index_count = SEG * RINGS * 6;
    }
    expect(ctx, "add mesh (mirror)", specula_context_add_mesh(ctx, &oct_d, &mirror_id), SPECULA_SUCCESS);
    expect(ctx, "add light", specula_context_add_light(ctx, light), SPECULA_SUCCESS);
    check("indices as main expects them", m_white == 0 && m_mirror == 1 && floor_id == 0 && mirror_id == 1, NULL);
    SpeculaCameraDesc cam = {SPECULA_STRUCT_CAMERA_DESC, sizeof cam, {0, 1.2f, 3}, {0, 0.6f, 0}, 0.9f, 0.01f};
    expect(ctx, "set camera", specula_context_set_camera(ctx, &cam), SPECULA_SUCCESS);
    expect(ctx, "knob cube_size", specula_context_set_knob(ctx, "cube_size", "16"), SPECULA_SUCCESS);
    expect(ctx, "knob shadow_size", specula_context_set_knob(ctx, "shadow_size", "16"), SPECULA_SUCCESS);
    SpeculaRenderDesc render = {SPECULA_STRUCT_RENDER_DESC, sizeof render, SPECULA_METHOD_DISTANCE, W, H};
    expect(ctx, "configure", specula_context_configure(ctx, &render), SPECULA_SUCCESS);
    return ctx;
}

int main(void) {
    SpeculaMaterialDesc white = {SPECULA_STRUCT_MATERIAL_DESC, sizeof white, SPECULA_SURFACE_DIFFUSE, {0.8f, 0.8f, 0.8f}};
    SpeculaLightDesc light = {SPECULA_STRUCT_LIGHT_DESC, sizeof light, SPECULA_LIGHT_POINT, {0, 2.5f, 1}, {0, -1, 0}, {8, 8, 8}};
    const uint32_t m_white = 0, m_mirror = 1, mirror_id = 1;
    SpeculaMaterialDesc mirror = {SPECULA_STRUCT_MATERIAL_DESC, sizeof mirror, SPECULA_SURFACE_MIRROR, {1, 1, 1}, {0, 0, 0},
                                  {0.2f, 0.2f, 0.2f}, {3.0f, 3.0f, 3.0f}};
    SpeculaContext *ctx = create(&white, &light, 0);
    if (!ctx) {
        printf("%d failure(s)\n", failures);
        return 1;
    }
    static float img[W * H * 4], before[W * H * 4];
    char u[1024];
    expect(ctx, "frame 1", specula_context_render(ctx, SPECULA_PIXEL_RGBA32F, img, sizeof img), SPECULA_SUCCESS);
    updates(ctx, u, sizeof u);
    check("frame 1 builds every map", strstr(u, "shadow.generate(first frame)") && strstr(u, "distance.generate(first frame)"), u);
    expect(ctx, "frame 2", specula_context_render(ctx, SPECULA_PIXEL_RGBA32F, before, sizeof before), SPECULA_SUCCESS);
    updates(ctx, u, sizeof u);
    check("a static frame 2 rebuilds no map", u[0] == 0, u);
    check("a static frame 2 equals frame 1", memcmp(img, before, sizeof img) == 0, NULL);

    /* Moving the mirror: shadow and distance maps (the faces that see it: "moved 'mesh1'; 2 of
       6 faces"), and the image changes. */
    float m[16];
    translation(m, 0.3f, 0.8f, 0.0f);
    expect(ctx, "move the mirror", specula_context_set_object_transform(ctx, mirror_id, m), SPECULA_SUCCESS);
    expect(ctx, "frame 3", specula_context_render(ctx, SPECULA_PIXEL_RGBA32F, img, sizeof img), SPECULA_SUCCESS);
    updates(ctx, u, sizeof u);
    check("a move rebuilds shadow and distance maps", strstr(u, "shadow.generate(moved 'mesh1'") && strstr(u, "distance.generate(moved 'mesh1'"), u);
    check("the moved mirror changes the image", memcmp(img, before, sizeof img) != 0, NULL);
    memcpy(before, img, sizeof img);

    /* A light: shadow and distance maps. A material: distance maps only. */
    light.position[0] = 0.5f;
    expect(ctx, "move the light", specula_context_set_light(ctx, 0, &light), SPECULA_SUCCESS);
    expect(ctx, "frame 4", specula_context_render(ctx, SPECULA_PIXEL_RGBA32F, img, sizeof img), SPECULA_SUCCESS);
    updates(ctx, u, sizeof u);
    check("a light rebuilds shadow and distance maps", strstr(u, "shadow.generate(light 'light0')") && strstr(u, "distance.generate(light 'light0')"), u);
    white.base_color[1] = 0.3f;
    expect(ctx, "recolour the floor", specula_context_set_material(ctx, m_white, &white), SPECULA_SUCCESS);
    expect(ctx, "frame 5", specula_context_render(ctx, SPECULA_PIXEL_RGBA32F, before, sizeof before), SPECULA_SUCCESS);
    updates(ctx, u, sizeof u);
    /* (the faces that see the floor: "; 5 of 6 faces"; the caustics keep theirs: their light
       does not depend on what it falls on) */
    check("a material rebuilds the distance maps only",
          strncmp(u, "distance.generate(material 'material0'", 38) == 0 && !strstr(u, "shadow.generate") && !strstr(u, "caustics"), u);

    /* Hiding the mirror changes the image and rebuilds the maps; showing it restores frame 5. */
    expect(ctx, "hide the mirror", specula_context_set_object_visible(ctx, mirror_id, 0), SPECULA_SUCCESS);
    expect(ctx, "frame 5a", specula_context_render(ctx, SPECULA_PIXEL_RGBA32F, img, sizeof img), SPECULA_SUCCESS);
    updates(ctx, u, sizeof u);
    check("hiding rebuilds shadow and distance maps", strstr(u, "shadow.generate(moved 'mesh1'") && strstr(u, "distance.generate(moved 'mesh1'"), u);
    check("the hidden mirror is gone from the image", memcmp(img, before, sizeof img) != 0, NULL);
    expect(ctx, "show the mirror", specula_context_set_object_visible(ctx, mirror_id, 1), SPECULA_SUCCESS);
    expect(ctx, "frame 5b", specula_context_render(ctx, SPECULA_PIXEL_RGBA32F, img, sizeof img), SPECULA_SUCCESS);
    check("shown again, the image of frame 5 returns", memcmp(img, before, sizeof img) == 0, NULL);
    expect(ctx, "hide an unknown object", specula_context_set_object_visible(ctx, 9, 0), SPECULA_ERROR_INVALID_ARGUMENT);

    /* Misuse: a code, a message, and the previous state kept (the next frame equals frame 5). */
    float nan_m[16];
    translation(nan_m, NAN, 0, 0);
    expect(ctx, "transform with NaN", specula_context_set_object_transform(ctx, mirror_id, nan_m), SPECULA_ERROR_INVALID_ARGUMENT);
    check("  names the object and the value", strstr(specula_context_last_error(ctx), "mesh1") && strstr(specula_context_last_error(ctx), "NaN"), specula_context_last_error(ctx));
    float zero[16];
    translation(zero, 0, 0, 0);
    zero[5] = 0.0f;
    expect(ctx, "transform of zero scale", specula_context_set_object_transform(ctx, mirror_id, zero), SPECULA_ERROR_INVALID_ARGUMENT);
    expect(ctx, "transform of an unknown object", specula_context_set_object_transform(ctx, 7, m), SPECULA_ERROR_INVALID_ARGUMENT);
    expect(ctx, "transform NULL", specula_context_set_object_transform(ctx, mirror_id, NULL), SPECULA_ERROR_NULL_POINTER);
    SpeculaMaterialDesc glass = mirror;
    glass.surface = SPECULA_SURFACE_DIELECTRIC;
    glass.ior = 1.5f;
    expect(ctx, "material changes kind", specula_context_set_material(ctx, m_mirror, &glass), SPECULA_ERROR_INVALID_ARGUMENT);
    SpeculaMaterialDesc bad = white;
    bad.base_color[0] = NAN;
    expect(ctx, "material with NaN", specula_context_set_material(ctx, m_white, &bad), SPECULA_ERROR_INVALID_ARGUMENT);
    bad.size = 8;
    expect(ctx, "material of the wrong size", specula_context_set_material(ctx, m_white, &bad), SPECULA_ERROR_STRUCT_MISMATCH);
    SpeculaLightDesc dir = light;
    dir.kind = SPECULA_LIGHT_DIRECTIONAL;
    expect(ctx, "light changes kind", specula_context_set_light(ctx, 0, &dir), SPECULA_ERROR_INVALID_ARGUMENT);
    expect(ctx, "light out of range", specula_context_set_light(ctx, 3, &light), SPECULA_ERROR_INVALID_ARGUMENT);
    expect(ctx, "map updates: NULL count", specula_get_map_updates(ctx, NULL, 0, NULL), SPECULA_ERROR_NULL_POINTER);
    expect(ctx, "frame 6", specula_context_render(ctx, SPECULA_PIXEL_RGBA32F, img, sizeof img), SPECULA_SUCCESS);
    updates(ctx, u, sizeof u);
    check("refused updates rebuild nothing", u[0] == 0, u);
    check("refused updates keep the image", memcmp(img, before, sizeof img) == 0, NULL);

    specula_context_destroy(ctx);

    /* 400 frames, the mirror moving every frame: the C heap stays flat. Measured on a
     * second context without the layer's synchronization validation, whose own state grows
     * by about 150 KiB per submitted frame in this layer version (1.3.239); the core
     * validation stays on. Its own bookkeeping still grows by 80 to 400 B per frame (it
     * varied between runs), so the mirror here is an 861-vertex sphere: any per-frame copy of
     * its geometry the library kept (≥ 27 KiB a frame) stands far above that. */
    setenv("SPECULA_SYNC_VALIDATION", "0", 1);
    white.base_color[1] = 0.8f;
    ctx = create(&white, &light, 1);
    if (!ctx) {
        printf("%d failure(s)\n", failures);
        return 1;
    }
    size_t heap0 = 0, heap_half = 0;
    int ok = 1;
    for (int k = 0; k < 400 && ok; ++k) {
        translation(m, 0.4f * sinf(0.01f * k), 0.8f, 0.3f * cosf(0.01f * k));
        ok = specula_context_set_object_transform(ctx, mirror_id, m) == SPECULA_SUCCESS &&
             specula_context_render(ctx, SPECULA_PIXEL_RGBA32F, img, sizeof img) == SPECULA_SUCCESS;
        if (k == 99) heap0 = mallinfo2().uordblks;
        if (k == 249) heap_half = mallinfo2().uordblks;
    }
    check("400 frames with a move each", ok, specula_context_last_error(ctx));
    size_t heap1 = mallinfo2().uordblks;
    char growth[128];
    snprintf(growth, sizeof growth, "C heap %+ld bytes over frames 100..250, %+ld over 250..400", (long)heap_half - (long)heap0,
             (long)heap1 - (long)heap_half);
    /* Below 2 KiB per frame over the last 150 frames: far above the layer's noise, far below
     * one leaked copy of the moved sphere's vertices (861 × 32 B) or triangles per frame. */
    check("the C heap stays flat (< 300 KiB over the last 150)", (long)heap1 - (long)heap_half < 150 * 2048, growth);

    specula_context_destroy(ctx);
    printf("%d failure(s)\n", failures);
    return failures ? 1 : 0;
}
