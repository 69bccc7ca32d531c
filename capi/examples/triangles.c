/*
 * A few overlapping transparent triangles through the mlab C API: fragments in submission
 * order (triangle by triangle, unsorted), resolved to RGBA8 over white and written as binary
 * PPM, once per method, size and arithmetic (MLAB 1-8, HT 1-8, Unbiased and Paper: 32 files).
 *
 *   cargo build --release -p mlab-capi
 *   cc -std=c11 -O2 -Icapi/include capi/examples/triangles.c target/release/libmlab_capi.a \
 *      -lpthread -ldl -lm -o triangles
 *   ./triangles out-dir        # writes out-dir/mlab4_unbiased.ppm, out-dir/ht3_paper.ppm, ...
 *
 * The fragments are made with integer arithmetic and one correctly rounded division, so the
 * same scene written in Rust (capi/tests/triangles.rs) gives the same floats, and the files
 * must equal that test's byte for byte (capi/ci.sh compares them).
 *
 * Each fragment carries its triangle's index as its stable key (mlab_insert_straight_keyed):
 * the id of the primitive, unique in the frame and the same in every frame, so that the
 * default arithmetic rounds it the same way in every frame while the camera moves. A
 * renderer with several draws mixes the draw or instance id into it.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "mlab.h"

#define WIDTH 96
#define HEIGHT 64

/* Vertices in 1/16 pixel; depth z0 + dzdx * x + dzdy * y, in 1/256 units; straight color. */
typedef struct {
    int32_t x[3], y[3];
    int32_t z0, dzdx, dzdy;
    float rgb[3];
    float alpha;
} Triangle;

static const Triangle SCENE[] = {
    {{160, 1400, 300}, {100, 300, 980}, 2560, 8, 0, {1.0f, 0.2f, 0.1f}, 0.6f},
    {{1500, 1480, 200}, {60, 1000, 700}, 4096, -24, 4, {0.1f, 0.4f, 1.0f}, 0.5f},
    {{700, 1200, 100}, {20, 900, 600}, 1024, 12, 12, {0.2f, 0.9f, 0.3f}, 0.45f},
    {{300, 900, 1500}, {900, 40, 800}, 3000, 0, -16, {1.0f, 0.9f, 0.1f}, 0.35f},
    {{40, 1520, 760}, {500, 500, 1000}, 2000, 0, 0, {0.8f, 0.1f, 0.9f}, 0.3f},
    {{600, 1000, 800}, {200, 200, 960}, 2000, 0, 0, {0.1f, 0.9f, 0.9f}, 0.7f},   /* ties the one above */
    {{0, 1536, 0}, {0, 0, 1024}, 500, 2, 2, {1.0f, 1.0f, 1.0f}, 0.04f},          /* faint veil */
    {{1536, 1536, 0}, {0, 1024, 1024}, 6000, -8, -8, {0.05f, 0.05f, 0.05f}, 0.8f}, /* far, dark */
};

/* Prints the status's message and returns 1 if it is not MLAB_STATUS_OK. */
static int failed(MlabStatus status, const char *what) {
    if (status == MLAB_STATUS_OK) {
        return 0;
    }
    fprintf(stderr, "%s: %s (status %d)\n", what, mlab_error_message(status), (int)status);
    return 1;
}

static int64_t edge(const Triangle *t, int i, int64_t px, int64_t py) {
    int j = (i + 1) % 3;
    return (int64_t)(t->x[j] - t->x[i]) * (py - t->y[i]) - (int64_t)(t->y[j] - t->y[i]) * (px - t->x[i]);
}

/* Every pixel whose center is inside (either winding) gets one fragment, keyed by the
 * triangle's index. */
static int draw(MlabFramebuffer *fb, const Triangle *t, uint32_t key) {
    for (uint32_t y = 0; y < HEIGHT; y++) {
        for (uint32_t x = 0; x < WIDTH; x++) {
            int64_t px = 16 * (int64_t)x + 8, py = 16 * (int64_t)y + 8;
            int64_t e0 = edge(t, 0, px, py), e1 = edge(t, 1, px, py), e2 = edge(t, 2, px, py);
            int inside = (e0 >= 0 && e1 >= 0 && e2 >= 0) || (e0 <= 0 && e1 <= 0 && e2 <= 0);
            if (!inside) {
                continue;
            }
            float depth = (float)(t->z0 + t->dzdx * (int32_t)x + t->dzdy * (int32_t)y) / 256.0f;
            MlabStatus st =
                mlab_insert_straight_keyed(fb, x, y, t->rgb[0], t->rgb[1], t->rgb[2], t->alpha, depth, key);
            if (failed(st, "mlab_insert_straight_keyed")) {
                return 1;
            }
        }
    }
    return 0;
}

static int render(MlabMethod method, uint32_t layers, MlabArithmetic arithmetic, const char *path) {
    size_t rows = 0;
    if (failed(mlab_rows_needed(method, layers, WIDTH, HEIGHT, &rows), "mlab_rows_needed")) {
        return 1;
    }
    /* The caller owns the storage: malloc memory is aligned enough for MlabRow (8 bytes). */
    MlabRow *storage = malloc(rows * sizeof *storage);
    uint8_t *rgba = malloc((size_t)WIDTH * HEIGHT * 4);
    int err = storage == NULL || rgba == NULL;
    MlabFramebuffer fb;
    err = err || failed(mlab_framebuffer_init(&fb, method, layers, arithmetic, storage, rows, WIDTH, HEIGHT),
                        "mlab_framebuffer_init");
    for (size_t i = 0; !err && i < sizeof SCENE / sizeof SCENE[0]; i++) {
        err = draw(&fb, &SCENE[i], (uint32_t)i);
    }
    MlabBackground white = {MLAB_BACKGROUND_OPAQUE, {1.0f, 1.0f, 1.0f}};
    err = err || failed(mlab_resolve_rgba8(&fb, white, rgba, (size_t)WIDTH * HEIGHT), "mlab_resolve_rgba8");
    FILE *f = err ? NULL : fopen(path, "wb");
    if (!err && f == NULL) {
        perror(path);
        err = 1;
    }
    if (f != NULL) {
        fprintf(f, "P6\n%d %d\n255\n", WIDTH, HEIGHT);
        for (size_t p = 0; p < (size_t)WIDTH * HEIGHT; p++) {
            fwrite(&rgba[4 * p], 1, 3, f); /* alpha is 255 over an opaque background */
        }
        err = fclose(f) != 0;
    }
    free(rgba);
    free(storage);
    return err;
}

int main(int argc, char **argv) {
    if (argc != 2) {
        fprintf(stderr, "usage: %s OUT_DIR\n", argv[0]);
        return 2;
    }
    if (mlab_abi_version() != MLAB_ABI_VERSION) {
        fprintf(stderr, "mlab.h is for C API version %d, the library is %u\n", MLAB_ABI_VERSION,
                (unsigned)mlab_abi_version());
        return 1;
    }
    static const char *METHODS[] = {"mlab", "ht"};
    static const char *ARITHMETICS[] = {"unbiased", "paper"};
    for (MlabMethod method = MLAB_METHOD_MLAB; method <= MLAB_METHOD_HYBRID; method++) {
        for (uint32_t layers = 1; layers <= 8; layers++) {
            for (MlabArithmetic a = MLAB_ARITHMETIC_UNBIASED; a <= MLAB_ARITHMETIC_PAPER; a++) {
                char path[4096];
                snprintf(path, sizeof path, "%s/%s%u_%s.ppm", argv[1], METHODS[method], (unsigned)layers,
                         ARITHMETICS[a]);
                if (render(method, layers, a, path)) {
                    return 1;
                }
            }
        }
    }
    return 0;
}
