/*
 * mlab.hpp: a header-only C++17 wrapper of the mlab C API (mlab.h; guide: docs/c.md).
 * License: MIT OR Apache-2.0.
 *
 *   mlab::Framebuffer fb(mlab::Method::Mlab, 4, mlab::Arithmetic::Unbiased, width, height);
 *   if (!fb) { std::fprintf(stderr, "%s\n", mlab::message(fb.status())); }
 *   MlabStatus st = fb.insert_straight(x, y, r, g, b, a, depth, key);   // keyed
 *   st = fb.resolve_rgba8(background, rgba);                            // a std::vector
 *
 * mlab::Framebuffer owns its storage (a std::vector of MlabRow) and the C state over it:
 * move-only (a move hands both over and leaves the source empty: every call on it returns
 * MLAB_STATUS_NOT_INITIALIZED), freed with it. mlab::View is the C state alone, a view of rows
 * owned elsewhere (a band for another thread, fb.band(...)): copyable, valid while the
 * framebuffer it views lives and is not moved from. Every call returns the C function's
 * MlabStatus, [[nodiscard]]; nothing throws but the allocation of the storage (std::bad_alloc).
 */
#ifndef MLAB_HPP
#define MLAB_HPP

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "mlab.h"

namespace mlab {

/** The method: MLAB_METHOD_MLAB or MLAB_METHOD_HYBRID. */
enum class Method : MlabMethod { Mlab = MLAB_METHOD_MLAB, Hybrid = MLAB_METHOD_HYBRID };

/** The arithmetic: MLAB_ARITHMETIC_UNBIASED (the default) or MLAB_ARITHMETIC_PAPER. */
enum class Arithmetic : MlabArithmetic { Unbiased = MLAB_ARITHMETIC_UNBIASED, Paper = MLAB_ARITHMETIC_PAPER };

/** The static English message of a status (mlab_error_message). */
inline const char *message(MlabStatus status) noexcept { return mlab_error_message(static_cast<int>(status)); }

/** A framebuffer's C state over rows owned elsewhere; each call is the C function's. */
class View {
  public:
    /** An empty view: every call returns MLAB_STATUS_NOT_INITIALIZED. */
    View() noexcept = default;

    std::uint32_t width() const noexcept { return width_; }
    std::uint32_t height() const noexcept { return height_; }
    /** width() * height(): the pixels of a resolve's output. */
    std::size_t pixels() const noexcept { return static_cast<std::size_t>(width_) * height_; }

    [[nodiscard]] MlabStatus clear() noexcept { return mlab_framebuffer_clear(&fb_); }

    /** Lines first_line .. first_line + lines as a view of their own (mlab_framebuffer_band). */
    [[nodiscard]] MlabStatus band(std::uint32_t first_line, std::uint32_t lines, View &out) const noexcept {
        MlabStatus st = mlab_framebuffer_band(&fb_, first_line, lines, &out.fb_);
        out.width_ = st == MLAB_STATUS_OK ? width_ : 0;
        out.height_ = st == MLAB_STATUS_OK ? lines : 0;
        return st;
    }

    [[nodiscard]] MlabStatus insert_straight(std::uint32_t x, std::uint32_t y, float r, float g, float b, float a,
                                             float depth) noexcept {
        return mlab_insert_straight(&fb_, x, y, r, g, b, a, depth);
    }
    [[nodiscard]] MlabStatus insert_straight(std::uint32_t x, std::uint32_t y, float r, float g, float b, float a,
                                             float depth, std::uint32_t key) noexcept {
        return mlab_insert_straight_keyed(&fb_, x, y, r, g, b, a, depth, key);
    }
    [[nodiscard]] MlabStatus insert_premultiplied(std::uint32_t x, std::uint32_t y, float r, float g, float b,
                                                  float a, float depth) noexcept {
        return mlab_insert_premultiplied(&fb_, x, y, r, g, b, a, depth);
    }
    [[nodiscard]] MlabStatus insert_premultiplied(std::uint32_t x, std::uint32_t y, float r, float g, float b,
                                                  float a, float depth, std::uint32_t key) noexcept {
        return mlab_insert_premultiplied_keyed(&fb_, x, y, r, g, b, a, depth, key);
    }

    [[nodiscard]] MlabStatus insert_span_straight(std::uint32_t x, std::uint32_t y, const MlabFragmentSpan &span,
                                                  std::uint8_t mask, std::uint8_t &refused) noexcept {
        return mlab_insert_span_straight(&fb_, x, y, &span, mask, &refused);
    }
    [[nodiscard]] MlabStatus insert_span_straight(std::uint32_t x, std::uint32_t y,
                                                  const MlabFragmentSpanKeyed &span, std::uint8_t mask,
                                                  std::uint8_t &refused) noexcept {
        return mlab_insert_span_straight_keyed(&fb_, x, y, &span, mask, &refused);
    }
    [[nodiscard]] MlabStatus insert_span_premultiplied(std::uint32_t x, std::uint32_t y,
                                                       const MlabFragmentSpan &span, std::uint8_t mask,
                                                       std::uint8_t &refused) noexcept {
        return mlab_insert_span_premultiplied(&fb_, x, y, &span, mask, &refused);
    }
    [[nodiscard]] MlabStatus insert_span_premultiplied(std::uint32_t x, std::uint32_t y,
                                                       const MlabFragmentSpanKeyed &span, std::uint8_t mask,
                                                       std::uint8_t &refused) noexcept {
        return mlab_insert_span_premultiplied_keyed(&fb_, x, y, &span, mask, &refused);
    }

    /** A batch (an empty vector's data() and size() are fine: nothing inserted, OK). */
    [[nodiscard]] MlabStatus insert_batch_straight(const MlabPixelFragment *fragments, std::size_t count,
                                                   std::size_t &inserted) noexcept {
        return mlab_insert_batch_straight(&fb_, fragments, count, &inserted);
    }
    [[nodiscard]] MlabStatus insert_batch_straight(const MlabPixelFragmentKeyed *fragments, std::size_t count,
                                                   std::size_t &inserted) noexcept {
        return mlab_insert_batch_straight_keyed(&fb_, fragments, count, &inserted);
    }
    [[nodiscard]] MlabStatus insert_batch_premultiplied(const MlabPixelFragment *fragments, std::size_t count,
                                                        std::size_t &inserted) noexcept {
        return mlab_insert_batch_premultiplied(&fb_, fragments, count, &inserted);
    }
    [[nodiscard]] MlabStatus insert_batch_premultiplied(const MlabPixelFragmentKeyed *fragments,
                                                        std::size_t count, std::size_t &inserted) noexcept {
        return mlab_insert_batch_premultiplied_keyed(&fb_, fragments, count, &inserted);
    }

    /** RGBA8, 4 bytes a pixel, row-major: `out` resized to 4 * pixels(). */
    [[nodiscard]] MlabStatus resolve_rgba8(MlabBackground background, std::vector<std::uint8_t> &out) const {
        out.resize(4 * pixels());
        return mlab_resolve_rgba8(&fb_, background, out.data(), pixels());
    }
    /** One pixel of the f32 resolve: linear RGBA, 16-byte aligned as the C function asks. */
    struct alignas(16) Rgba32f {
        float rgba[4];
    };
    /** f32 RGBA, row-major: `out` resized to pixels(). */
    [[nodiscard]] MlabStatus resolve_f32(MlabBackground background, std::vector<Rgba32f> &out) const {
        out.resize(pixels());
        return mlab_resolve_f32(&fb_, background, out.empty() ? nullptr : out[0].rgba, pixels());
    }
    /** RGBA16F (IEEE half as std::uint16_t), row-major: `out` resized to 4 * pixels(). */
    [[nodiscard]] MlabStatus resolve_rgba16f(MlabBackground background, std::vector<std::uint16_t> &out) const {
        out.resize(4 * pixels());
        return mlab_resolve_rgba16f(&fb_, background, out.data(), pixels());
    }
    /** The C state, for a C function this wrapper does not cover. */
    const MlabFramebuffer &c_state() const noexcept { return fb_; }

  protected:
    MlabFramebuffer fb_{};
    std::uint32_t width_ = 0;
    std::uint32_t height_ = 0;
};

/** A framebuffer that owns its storage: RAII, move-only. */
class Framebuffer : public View {
  public:
    /** An empty framebuffer (status() MLAB_STATUS_NOT_INITIALIZED). */
    Framebuffer() noexcept = default;

    /** Allocates the storage and initializes it (cleared); on error status() says why and
     * the framebuffer is empty. */
    Framebuffer(Method method, std::uint32_t layers, Arithmetic arithmetic, std::uint32_t width,
                std::uint32_t height) {
        std::size_t rows = 0;
        auto m = static_cast<MlabMethod>(method);
        status_ = mlab_rows_needed(m, layers, width, height, &rows);
        if (status_ != MLAB_STATUS_OK) {
            return;
        }
        storage_.resize(rows);
        status_ = mlab_framebuffer_init(&fb_, m, layers, static_cast<MlabArithmetic>(arithmetic), storage_.data(),
                                        rows, width, height);
        if (status_ != MLAB_STATUS_OK) {
            storage_ = std::vector<MlabRow>();
            return;
        }
        width_ = width;
        height_ = height;
    }

    Framebuffer(const Framebuffer &) = delete;
    Framebuffer &operator=(const Framebuffer &) = delete;

    /** Takes `other`'s storage (the same heap block: the C state still points to it). */
    Framebuffer(Framebuffer &&other) noexcept
        : View(std::exchange(static_cast<View &>(other), View())), storage_(std::move(other.storage_)),
          status_(std::exchange(other.status_, MLAB_STATUS_NOT_INITIALIZED)) {
        other.storage_.clear();
    }
    Framebuffer &operator=(Framebuffer &&other) noexcept {
        if (this != &other) {
            static_cast<View &>(*this) = std::exchange(static_cast<View &>(other), View());
            storage_ = std::move(other.storage_);
            other.storage_.clear();
            status_ = std::exchange(other.status_, MLAB_STATUS_NOT_INITIALIZED);
        }
        return *this;
    }
    ~Framebuffer() = default;

    /** How the construction went (MLAB_STATUS_NOT_INITIALIZED: empty or moved from). */
    [[nodiscard]] MlabStatus status() const noexcept { return status_; }
    explicit operator bool() const noexcept { return status_ == MLAB_STATUS_OK; }

    /** The rows (the kernel's layout, docs/layout.md): to upload, or to save. */
    const std::vector<MlabRow> &rows() const noexcept { return storage_; }

  private:
    std::vector<MlabRow> storage_;
    MlabStatus status_ = MLAB_STATUS_NOT_INITIALIZED;
};

} // namespace mlab

#endif
