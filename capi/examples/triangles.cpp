// The scene of triangles.c through the C++ wrapper (mlab.hpp): each triangle's fragments
// gathered into a std::vector and inserted as one keyed batch (byte-identical to per-pixel
// inserts in the same order), so the 32 PPM files equal the C example's byte for byte
// (capi/ci.sh compares them). Also checks what the wrapper promises: a move hands the
// storage over and leaves the source empty, an empty batch is fine.
//
//   c++ -std=c++17 -O2 $(pkg-config --cflags mlab-static) capi/examples/triangles.cpp
//       $(pkg-config --libs mlab-static) -o triangles-cpp
//   ./triangles-cpp out-dir
#include <cstdint>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "mlab.hpp"

namespace {

constexpr std::uint32_t WIDTH = 96;
constexpr std::uint32_t HEIGHT = 64;

// Vertices in 1/16 pixel; depth z0 + dzdx * x + dzdy * y, in 1/256 units; straight color.
struct Triangle {
    std::int32_t x[3], y[3];
    std::int32_t z0, dzdx, dzdy;
    float rgb[3];
    float alpha;
};

const Triangle SCENE[] = {
    {{160, 1400, 300}, {100, 300, 980}, 2560, 8, 0, {1.0f, 0.2f, 0.1f}, 0.6f},
    {{1500, 1480, 200}, {60, 1000, 700}, 4096, -24, 4, {0.1f, 0.4f, 1.0f}, 0.5f},
    {{700, 1200, 100}, {20, 900, 600}, 1024, 12, 12, {0.2f, 0.9f, 0.3f}, 0.45f},
    {{300, 900, 1500}, {900, 40, 800}, 3000, 0, -16, {1.0f, 0.9f, 0.1f}, 0.35f},
    {{40, 1520, 760}, {500, 500, 1000}, 2000, 0, 0, {0.8f, 0.1f, 0.9f}, 0.3f},
    {{600, 1000, 800}, {200, 200, 960}, 2000, 0, 0, {0.1f, 0.9f, 0.9f}, 0.7f},
    {{0, 1536, 0}, {0, 0, 1024}, 500, 2, 2, {1.0f, 1.0f, 1.0f}, 0.04f},
    {{1536, 1536, 0}, {0, 1024, 1024}, 6000, -8, -8, {0.05f, 0.05f, 0.05f}, 0.8f},
};

bool failed(MlabStatus status, const char *what) {
    if (status == MLAB_STATUS_OK) {
        return false;
    }
    std::fprintf(stderr, "%s: %s (status %d)\n", what, mlab::message(status), static_cast<int>(status));
    return true;
}

std::int64_t edge(const Triangle &t, int i, std::int64_t px, std::int64_t py) {
    int j = (i + 1) % 3;
    return std::int64_t{t.x[j] - t.x[i]} * (py - t.y[i]) - std::int64_t{t.y[j] - t.y[i]} * (px - t.x[i]);
}

// The triangle's fragments in the C example's order (line by line), keyed by its index.
std::vector<MlabPixelFragmentKeyed> fragments(const Triangle &t, std::uint32_t key) {
    std::vector<MlabPixelFragmentKeyed> out;
    for (std::uint32_t y = 0; y < HEIGHT; y++) {
        for (std::uint32_t x = 0; x < WIDTH; x++) {
            std::int64_t px = 16 * std::int64_t{x} + 8, py = 16 * std::int64_t{y} + 8;
            std::int64_t e0 = edge(t, 0, px, py), e1 = edge(t, 1, px, py), e2 = edge(t, 2, px, py);
            if ((e0 >= 0 && e1 >= 0 && e2 >= 0) || (e0 <= 0 && e1 <= 0 && e2 <= 0)) {
                float depth = static_cast<float>(t.z0 + t.dzdx * static_cast<std::int32_t>(x) +
                                                 t.dzdy * static_cast<std::int32_t>(y)) /
                              256.0f;
                out.push_back({x, y, {t.rgb[0], t.rgb[1], t.rgb[2], t.alpha}, depth, key});
            }
        }
    }
    return out;
}

bool render(mlab::Method method, std::uint32_t layers, mlab::Arithmetic arithmetic, const std::string &path) {
    mlab::Framebuffer built(method, layers, arithmetic, WIDTH, HEIGHT);
    if (failed(built.status(), "mlab::Framebuffer")) {
        return false;
    }
    // Moved: `fb` views the same storage, `built` is empty.
    mlab::Framebuffer fb = std::move(built);
    if (built.clear() != MLAB_STATUS_NOT_INITIALIZED || built || !fb) {
        std::fprintf(stderr, "a moved-from framebuffer must be empty\n");
        return false;
    }
    std::size_t inserted = 1;
    std::vector<MlabPixelFragmentKeyed> none;
    if (failed(fb.insert_batch_straight(none.data(), none.size(), inserted), "empty batch") || inserted != 0) {
        return false;
    }
    for (std::uint32_t i = 0; i < sizeof SCENE / sizeof SCENE[0]; i++) {
        std::vector<MlabPixelFragmentKeyed> batch = fragments(SCENE[i], i);
        if (failed(fb.insert_batch_straight(batch.data(), batch.size(), inserted), "insert_batch_straight")) {
            return false;
        }
    }
    std::vector<std::uint8_t> rgba;
    if (failed(fb.resolve_rgba8({MLAB_BACKGROUND_OPAQUE, {1.0f, 1.0f, 1.0f}}, rgba), "resolve_rgba8")) {
        return false;
    }
    std::FILE *f = std::fopen(path.c_str(), "wb");
    if (f == nullptr) {
        std::perror(path.c_str());
        return false;
    }
    std::fprintf(f, "P6\n%u %u\n255\n", static_cast<unsigned>(WIDTH), static_cast<unsigned>(HEIGHT));
    for (std::size_t p = 0; p < fb.pixels(); p++) {
        std::fwrite(&rgba[4 * p], 1, 3, f); // alpha is 255 over an opaque background
    }
    return std::fclose(f) == 0;
}

} // namespace

int main(int argc, char **argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: %s OUT_DIR\n", argv[0]);
        return 2;
    }
    if (mlab_abi_version() != MLAB_ABI_VERSION) {
        std::fprintf(stderr, "mlab.h is for C API version %d, the library is %u\n", MLAB_ABI_VERSION,
                     static_cast<unsigned>(mlab_abi_version()));
        return 1;
    }
    const std::pair<mlab::Method, const char *> methods[] = {{mlab::Method::Mlab, "mlab"},
                                                              {mlab::Method::Hybrid, "ht"}};
    const std::pair<mlab::Arithmetic, const char *> arithmetics[] = {{mlab::Arithmetic::Unbiased, "unbiased"},
                                                                      {mlab::Arithmetic::Paper, "paper"}};
    for (const auto &[method, mname] : methods) {
        for (std::uint32_t layers = 1; layers <= 8; layers++) {
            for (const auto &[arithmetic, aname] : arithmetics) {
                std::string path = std::string(argv[1]) + "/" + mname + std::to_string(layers) + "_" + aname + ".ppm";
                if (!render(method, layers, arithmetic, path)) {
                    return 1;
                }
            }
        }
    }
    return 0;
}
