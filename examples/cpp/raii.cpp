// raii.cpp — specula from C++: a small RAII wrapper that turns result codes into
// exceptions carrying the library's message, and frees the context on scope exit.
//
//   c++ -std=c++17 -I include examples/cpp/raii.cpp -L target/release -lspecula -o raii
//   ./raii assets/demo/demo.gltf out.f32
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "specula.h"

namespace specula {

class Error : public std::runtime_error {
  public:
    Error(SpeculaResult code, const std::string &what) : std::runtime_error(what), code(code) {}
    SpeculaResult code;
};

class Context {
  public:
    explicit Context(const char *device_name = nullptr, bool validate = false) {
        SpeculaContextDesc desc{SPECULA_STRUCT_CONTEXT_DESC, sizeof desc, device_name, validate ? 1u : 0u};
        SpeculaContext *raw = nullptr;
        SpeculaResult r = specula_context_create(&desc, &raw);
        if (r != SPECULA_SUCCESS) throw Error(r, std::string("specula_context_create: ") + specula_creation_error());
        ctx_.reset(raw);
    }

    void load_gltf(const std::string &path) { check(specula_context_load_gltf(ctx_.get(), path.c_str()), "load_gltf"); }
    void knob(const std::string &key, const std::string &value) { check(specula_context_set_knob(ctx_.get(), key.c_str(), value.c_str()), "set_knob"); }
    void configure(SpeculaMethod method, uint32_t width, uint32_t height) {
        SpeculaRenderDesc desc{SPECULA_STRUCT_RENDER_DESC, sizeof desc, method, width, height};
        check(specula_context_configure(ctx_.get(), &desc), "configure");
        width_ = width;
        height_ = height;
    }
    std::vector<float> render_linear() {
        std::vector<float> pixels(size_t(width_) * height_ * 4);
        check(specula_context_render(ctx_.get(), SPECULA_PIXEL_RGBA32F, pixels.data(), pixels.size() * sizeof(float)), "render");
        return pixels;
    }
    std::vector<SpeculaPassTiming> timings() {
        uint32_t count = 0;
        check(specula_get_pass_timings(ctx_.get(), nullptr, 0, &count), "timings");
        std::vector<SpeculaPassTiming> t(count);
        check(specula_get_pass_timings(ctx_.get(), t.data(), count, &count), "timings");
        return t;
    }

  private:
    struct Destroy {
        void operator()(SpeculaContext *c) const { specula_context_destroy(c); }
    };
    void check(SpeculaResult r, const char *what) {
        if (r < 0) throw Error(r, std::string(what) + ": " + specula_context_last_error(ctx_.get()));
    }
    std::unique_ptr<SpeculaContext, Destroy> ctx_;
    uint32_t width_ = 0, height_ = 0;
};

}  // namespace specula

int main(int argc, char **argv) {
    if (argc < 3) {
        std::fprintf(stderr, "usage: %s SCENE.gltf OUT.f32\n", argv[0]);
        return 2;
    }
    try {
        specula::Context ctx(nullptr, std::getenv("SPECULA_VALIDATE") != nullptr);
        ctx.load_gltf(argv[1]);
        ctx.knob("cube_size", "64");
        ctx.knob("shadow_size", "64");
        ctx.configure(SPECULA_METHOD_ENVMAP, 128, 96);
        std::vector<float> image = ctx.render_linear();
        for (const SpeculaPassTiming &t : ctx.timings()) std::printf("%-20s %8.3f ms GPU\n", t.name, t.gpu_ms);
        std::ofstream(argv[2], std::ios::binary).write(reinterpret_cast<const char *>(image.data()), std::streamsize(image.size() * sizeof(float)));
        try {
            ctx.knob("cube_size", "1");  // out of range: an exception with the library's message
            return 1;
        } catch (const specula::Error &e) {
            std::printf("expected error %d: %s\n", e.code, e.what());
        }
    } catch (const std::exception &e) {
        std::fprintf(stderr, "%s\n", e.what());
        return 1;
    }
    return 0;
}
