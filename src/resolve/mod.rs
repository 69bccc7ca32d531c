//! Resolve: paper Eq. 5 and 6, and the pixel writers.
//!
//! ```text
//! A_transp = sum_j A_j * prod_{i<j} T_i          (Eq. 5, rows front to back, T_-1 = 1)
//! A_pixel  = A_opaque * prod_i T_i + A_transp     (Eq. 6)
//! ```
//!
//! Evaluated in f32 in one fixed order (per row, with `v` the visibility so far and bytes
//! as exact f32: `w = v * (1/255)`, `a += byte * w`, `v = T_byte * w`, every row visited,
//! empty rows too), with separate multiplies and adds, never FMA; the exact programs of
//! the MLAB and HT f32 resolves, and of the background and the pixel writers, are in
//! `docs/layout.md` ("Resolve"). The lane kernels evaluate the same expression tree, so
//! their pixels are bit-identical.
//!
//! MLAB's RGBA8 ([`Framebuffer::resolve_rgba8`](crate::Framebuffer::resolve_rgba8)) is the
//! integer resolve of `docs/layout.md` ("Integer resolve"), crate-private module `int`: Q15
//! visibility, `(x y + 16384) >> 15` products, saturating 16-bit accumulators.

use glam::{Vec3, Vec4};
use half::f16;

use crate::row::Row;

/// f32 values of one or more pixels: what the resolve is written over.
pub(crate) trait FloatLanes:
    Copy + core::ops::Add<Output = Self> + core::ops::Sub<Output = Self> + core::ops::Mul<Output = Self>
{
    /// Per-lane unsigned integer (tail fields).
    type U: Copy;
    /// Per-lane condition.
    type Mask: Copy;
    /// All lanes `v`.
    fn splat(v: f32) -> Self;
    /// `if mask { a } else { b }`.
    fn select(mask: Self::Mask, a: Self, b: Self) -> Self;
    /// Bit `bit` of `n` is set.
    fn bit(n: Self::U, bit: u32) -> Self::Mask;
    /// `n == 0`.
    fn is_zero(n: Self::U) -> Self::Mask;
    /// `self > other`.
    fn gt(self, other: Self) -> Self::Mask;
    /// `self / other` (IEEE, correctly rounded in both widths).
    fn div(self, other: Self) -> Self;
    /// Exact conversion of a small integer (below 2^24).
    fn from_u(n: Self::U) -> Self;
    /// Number of significant bits of the largest lane of `n`.
    fn bit_length(n: Self::U) -> u32;
}

impl FloatLanes for f32 {
    type U = u32;
    type Mask = bool;
    #[inline(always)]
    fn splat(v: f32) -> Self {
        v
    }
    #[inline(always)]
    fn select(mask: bool, a: Self, b: Self) -> Self {
        if mask { a } else { b }
    }
    #[inline(always)]
    fn bit(n: u32, bit: u32) -> bool {
        (n >> bit) & 1 != 0
    }
    #[inline(always)]
    fn is_zero(n: u32) -> bool {
        n == 0
    }
    #[inline(always)]
    fn gt(self, other: Self) -> bool {
        self > other
    }
    #[inline(always)]
    fn div(self, other: Self) -> Self {
        self / other
    }
    #[inline(always)]
    fn from_u(n: u32) -> Self {
        n as f32
    }
    #[inline(always)]
    fn bit_length(n: u32) -> u32 {
        u32::BITS - n.leading_zeros()
    }
}

/// `1 / 255` rounded to f32; `255.0 * INV255 == 1.0` exactly (tested).
pub(crate) const INV255: f32 = 1.0 / 255.0;

/// The composite of the transparent layers of one pixel, before the background.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Resolved {
    /// Premultiplied color of the transparent layers, `A_transp` of Eq. 5. May exceed 1
    /// where additive light was accumulated.
    pub color: Vec3,
    /// Visibility of the background, the product of all transmittances (`1 - alpha`).
    pub transmittance: f32,
}

impl Resolved {
    /// Nothing drawn: color 0, background fully visible.
    pub const CLEAR: Resolved = Resolved {
        color: Vec3::ZERO,
        transmittance: 1.0,
    };

    /// Eq. 6: composite over an opaque background, `color + background * transmittance`.
    #[inline]
    pub fn over(self, background: Vec3) -> Vec3 {
        self.color + background * self.transmittance
    }

    /// Premultiplied RGBA for compositing later: `(color, 1 - transmittance)`.
    #[inline]
    fn premultiplied(self) -> Vec4 {
        self.color.extend(1.0 - self.transmittance)
    }

    /// The pixel for a [`Background`]: opaque (alpha 1) or premultiplied.
    #[inline]
    pub fn pixel(self, background: Background) -> Vec4 {
        match background {
            Background::Opaque(bg) => self.over(bg).extend(1.0),
            Background::Transparent => self.premultiplied(),
        }
    }
}

/// What the transparent layers are composited onto when writing pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Background {
    /// An opaque color (Eq. 6); the written alpha is 1.
    Opaque(Vec3),
    /// Nothing: write premultiplied RGBA (`alpha = 1 - prod T`) for compositing later.
    Transparent,
}

impl Background {
    /// The background as the integer RGBA8 resolve takes it (`docs/layout.md`, "Integer
    /// resolve": `bgq`): each channel clamped to `[0, 1]` as [`to_rgba8`] clamps (NaN to 0),
    /// then `floor(b * 32640 + 0.5)` in f32, a multiply and then an add (`32640 = 255 * 128`,
    /// the accumulator's unit); `None` for [`Background::Transparent`].
    ///
    /// The contract a port of the integer resolve relies on: these three integers are what
    /// [`Framebuffer::resolve_rgba8`](crate::Framebuffer::resolve_rgba8) composites under the
    /// layers of every pixel, so a port that receives them (as `mlab-gpu`'s shader does,
    /// computed on the CPU) writes the same bytes.
    ///
    /// ```
    /// use mlab::{Background, glam::Vec3};
    /// assert_eq!(Background::Opaque(Vec3::new(0.0, 0.5, 2.0)).integer_channels(), Some([0, 16320, 32640]));
    /// assert_eq!(Background::Transparent.integer_channels(), None);
    /// ```
    #[inline]
    pub fn integer_channels(self) -> Option<[u32; 3]> {
        int::background(self)
    }
}

/// Eq. 5 over rows sorted front to back (any rows are accepted: the result is finite,
/// color channels in `[0, rows.len()]`, transmittance in `[0, 1]`).
#[inline]
pub fn resolve_rows(rows: &[Row]) -> Resolved {
    let ([r, g, b], t) = resolve_layers(rows.iter().map(row_bytes));
    Resolved {
        color: Vec3::new(r, g, b),
        transmittance: t,
    }
}

/// A row's `[R, G, B, T]` bytes as exact f32.
#[inline(always)]
pub(crate) fn row_bytes(row: &Row) -> [f32; 4] {
    row.rgbt().map(|b| b as f32)
}

/// Eq. 5, written once for every lane width (`f32` or `f32x8`), over layers given as byte
/// values `[R, G, B, T]` front to back. Per layer, with `v` the visibility so far:
/// `w = v * INV255`, `a += byte * w` per channel, then `v = T * w`.
#[inline(always)]
pub(crate) fn resolve_layers<F: FloatLanes>(layers: impl Iterator<Item = [F; 4]>) -> ([F; 3], F) {
    let inv = F::splat(INV255);
    let mut a = [F::splat(0.0); 3];
    let mut v = F::splat(1.0);
    for [r, g, b, t] in layers {
        let w = v * inv;
        a = [a[0] + r * w, a[1] + g * w, a[2] + b * w];
        v = t * w;
    }
    (a, v)
}

/// The tail resolve, written once for every lane width (`f32` or `f32x8`): color and
/// transmittance of the tail from its sums. Multiplies and adds are separate (no FMA).
#[inline(always)]
pub(crate) fn tail_lanes<F: FloatLanes>(sums: [F::U; 3], alpha: F::U, count: F::U) -> ([F; 3], F) {
    let inv = F::splat(INV255);
    let one = F::splat(1.0);
    let empty = F::is_zero(count);
    let s_a = F::from_u(alpha) * inv;
    let n = F::select(empty, one, F::from_u(count));
    let mean = s_a.div(n);
    // A mean alpha above 1 (arbitrary bytes only) is clamped to 1: the tail is opaque.
    let clamped = mean.gt(one);
    let mean = F::select(clamped, one, mean);
    let x = one - mean;
    // T_tail = x^n and the geometric sum S_n = 1 + x + ... + x^(n-1), both by binary
    // exponentiation over the bits of the count (at most 16; bits above the largest count of
    // all lanes are zero and would change nothing). The color factor
    // g = (1 - T_tail) / S_a = (1 - x^n) / (n (1 - x)) = S_n / n
    // is computed from S_n: only products and sums of non-negative terms, where the printed
    // formula subtracts two numbers close to 1 (for a tiny mean alpha it lost a third of the
    // tail's light in f32). g = 1 exactly for pure additive light (x = 1).
    let mut power = one; // x^k for the bits seen so far
    let mut sum = F::splat(0.0); // S_k
    let mut base = x; // x^(2^i)
    let mut base_sum = one; // S_(2^i)
    for bit in 0..F::bit_length(count).min(16) {
        let on = F::bit(count, bit);
        sum = F::select(on, sum + power * base_sum, sum); // S_(k + 2^i) = S_k + x^k S_(2^i)
        power = F::select(on, power * base, power);
        base_sum = base_sum * (one + base); // S_(2^(i+1)) = S_(2^i) (1 + x^(2^i))
        base = base * base;
    }
    let t_tail = F::select(empty, x, power);
    // A zero count (arbitrary bytes only) resolves as a count of 1: S_1 / 1 = 1. With the
    // mean clamped, S_a is no longer n (1 - x): x = 0, T_tail = 0 and g = (1 - 0) / S_a.
    let g = F::select(empty, one, sum.div(n));
    let g = F::select(clamped, one.div(s_a), g);
    let g = F::select(g.gt(one), one, g); // rounding only: S_n <= n
    let [r, gr, b] = sums;
    (
        [F::from_u(r) * inv * g, F::from_u(gr) * inv * g, F::from_u(b) * inv * g],
        t_tail,
    )
}

/// Head then tail: `C = C_head + T_head * C_tail`, `T = T_head * T_tail`.
#[inline(always)]
pub(crate) fn combine_lanes<F: FloatLanes>(head: ([F; 3], F), tail: ([F; 3], F)) -> ([F; 3], F) {
    let ([hr, hg, hb], ht) = head;
    let ([tr, tg, tb], tt) = tail;
    ([hr + tr * ht, hg + tg * ht, hb + tb * ht], ht * tt)
}

/// Resolved head and tail fields to a resolved pixel, for every lane width.
#[inline(always)]
pub(crate) fn resolve_lanes<F: FloatLanes>(
    head: ([F; 3], F),
    sums: [F::U; 3],
    alpha: F::U,
    count: F::U,
) -> ([F; 3], F) {
    combine_lanes(head, tail_lanes::<F>(sums, alpha, count))
}

pub(crate) mod int;

/// RGBA8 from a pixel: each channel clamped to `[0, 1]`, then `floor(x * 255 + 0.5)`
/// (NaN becomes 0). Byte order R, G, B, A.
#[inline]
pub fn to_rgba8(pixel: Vec4) -> [u8; 4] {
    pixel.to_array().map(|x| {
        // The same steps as the lanes writer: select-based clamp (NaN fails both tests).
        let x = if x > 1.0 { 1.0 } else { x };
        let x = if x >= 0.0 { x } else { 0.0 };
        crate::unorm::quantize(x)
    })
}

/// RGBA16F (IEEE half) from a pixel, rounded to nearest even; values above 1 (additive
/// light) are kept; values below 65520 round to at most 65504 (the largest finite half),
/// 65520 and above become infinity.
#[inline]
pub fn to_rgba16f(pixel: Vec4) -> [f16; 4] {
    pixel.to_array().map(f16::from_f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inv255_is_exact_at_255() {
        assert_eq!(255.0 * INV255, 1.0);
    }

    #[test]
    fn empty_rows_resolve_to_clear() {
        assert_eq!(resolve_rows(&[Row::EMPTY; 4]), Resolved::CLEAR);
    }

    #[test]
    fn writers_clamp_and_round() {
        assert_eq!(to_rgba8(Vec4::new(-1.0, 0.5, 2.0, f32::NAN)), [0, 128, 255, 0]);
        assert_eq!(
            to_rgba16f(Vec4::new(0.0, 0.5, 4.0, 1.0)).map(f16::to_f32),
            [0.0, 0.5, 4.0, 1.0]
        );
    }
}
