/* standalone.c — the minimal specula host: the library makes its own device, loads a glTF
 * scene, renders it with classic environment mapping and writes the image.
 *
 *   cc -std=c11 -I include examples/c/standalone.c -L target/release -lspecula -o standalone
 *   ./standalone assets/demo/demo.gltf out.ppm [out.f32 [METHOD]]
 *
 * out.ppm: sRGB 8-bit; out.f32 (optional): the linear RGBA32F radiance, raw; METHOD: a
 * SPECULA_METHOD_* value (default SPECULA_METHOD_ENVMAP). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "specula.h"

#define W 128
#define H 96

static int check(SpeculaContext *ctx, SpeculaResult r, const char *what) {
    if (r < 0) {
        fprintf(stderr, "%s failed (%d): %s\n", what, r, specula_context_last_error(ctx));
        return 0;
    }
    return 1;
}

/* An optional KEY=VALUE knob from the command line (e.g. depth=4). */
static int knob(SpeculaContext *ctx, const char *pair) {
    const char *eq = strchr(pair, '=');
    char key[64];
    if (!eq || (size_t)(eq - pair) >= sizeof key) {
        fprintf(stderr, "knob '%s' is not KEY=VALUE\n", pair);
        return 0;
    }
    memcpy(key, pair, (size_t)(eq - pair));
    key[eq - pair] = 0;
    return check(ctx, specula_context_set_knob(ctx, key, eq + 1), "set_knob");
}

int main(int argc, char **argv) {
    if (argc < 3) {
        fprintf(stderr, "usage: %s SCENE.gltf OUT.ppm [OUT.f32 [METHOD [KEY=VALUE]]]\n", argv[0]);
        return 2;
    }
    SpeculaContextDesc desc = {SPECULA_STRUCT_CONTEXT_DESC, sizeof desc, NULL, getenv("SPECULA_VALIDATE") != NULL};
    SpeculaContext *ctx = NULL;
    if (specula_context_create(&desc, &ctx) != SPECULA_SUCCESS) {
        fprintf(stderr, "specula_context_create: %s\n", specula_creation_error());
        return 1;
    }
    SpeculaMethod method = argc > 4 ? (SpeculaMethod)atoi(argv[4]) : SPECULA_METHOD_ENVMAP;
    SpeculaRenderDesc render = {SPECULA_STRUCT_RENDER_DESC, sizeof render, method, W, H};
    static unsigned char rgba8[W * H * 4];
    static float rgba32f[W * H * 4];
    int ok = check(ctx, specula_context_load_gltf(ctx, argv[1]), "load_gltf") &&
             check(ctx, specula_context_set_knob(ctx, "cube_size", "64"), "set_knob") &&
             check(ctx, specula_context_set_knob(ctx, "shadow_size", "64"), "set_knob") && (argc <= 5 || knob(ctx, argv[5])) &&
             check(ctx, specula_context_configure(ctx, &render), "configure") &&
             check(ctx, specula_context_render(ctx, SPECULA_PIXEL_RGBA8_SRGB, rgba8, sizeof rgba8), "render");
    if (ok) {
        /* The first frame's passes: it generates every map (later frames of a scene that
         * does not change only record the camera passes). */
        SpeculaPassTiming timings[16];
        uint32_t count = 0;
        if (check(ctx, specula_get_pass_timings(ctx, timings, 16, &count), "timings")) {
            for (uint32_t i = 0; i < count && i < 16; ++i) printf("%-20s %8.3f ms GPU\n", timings[i].name, timings[i].gpu_ms);
        }
        ok = check(ctx, specula_context_render(ctx, SPECULA_PIXEL_RGBA32F, rgba32f, sizeof rgba32f), "render");
    }
    if (ok) {
        FILE *f = fopen(argv[2], "wb");
        ok = f != NULL;
        if (f) {
            fprintf(f, "P6\n%d %d\n255\n", W, H);
            for (int i = 0; i < W * H; ++i) fwrite(&rgba8[4 * i], 1, 3, f);
            fclose(f);
        }
        if (ok && argc > 3) {
            FILE *g = fopen(argv[3], "wb");
            ok = g && fwrite(rgba32f, sizeof rgba32f, 1, g) == 1;
            if (g) fclose(g);
        }
    }
    specula_context_destroy(ctx);
    return ok ? 0 : 1;
}
