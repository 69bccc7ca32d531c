//! The f32 resolves in registers (Eq. 5-6 and the HT tail over `FloatLanes`): MLAB spans,
//! pixel-major MLAB pixels and HT spans, and the RGBA8 writer of their results.

use super::layout::{layer_bytes, rgbt_bytes, tail_fields, unpermute};
use super::w256::{Rows8, words0};
use super::{LANES, MlabSpan};
use crate::resolve::Background;
use crate::row::Row;
use crate::tail::TailFormat;
use bytemuck::cast;
use wide::{f32x8, i32x8, u32x8, u64x4};

/// The HT resolve in registers, pixels in [`POSITION`] order.
#[inline(always)]
fn hybrid_resolve_regs<T: TailFormat, const K: usize>(
    head: &[[Row; LANES]; K],
    tails: &[T; LANES],
) -> ([f32x8; 3], f32x8) {
    let head = crate::resolve::resolve_layers(head.iter().map(layer_bytes));
    let (sums, alpha, count) = tail_fields(tails);
    crate::resolve::resolve_lanes::<f32x8>(head, sums, alpha, count)
}

/// `x` clamped to `[0, 1]` with NaN to 0, as [`crate::to_rgba8`] clamps: `x > 1 ? 1 : x`,
/// then `x >= 0 ? x : 0`. On x86 these are exactly `minps(1, x)` then `maxps(x, 0)` (each
/// returns its second operand when the compare is false, NaN included); elsewhere `wide`'s
/// min and max differ on NaN between backends, so the selects are written out.
#[inline(always)]
fn clamp01(x: f32x8) -> f32x8 {
    let (zero, one) = (f32x8::ZERO, f32x8::ONE);
    if cfg!(any(target_arch = "x86", target_arch = "x86_64")) && cfg!(target_feature = "sse") {
        one.fast_min(x).fast_max(zero)
    } else {
        let x = x.simd_gt(one).select(one, x);
        x.simd_ge(zero).select(x, zero)
    }
}

/// [`crate::to_rgba8`] for 8 lanes, one channel: the byte in the low 8 bits of each lane,
/// the other bits zero (`x * 255 + 0.5` lies in `[0.5, 255.5]`: no mask needed).
#[inline(always)]
fn to_unorm8_lanes(x: f32x8) -> u32x8 {
    let q = clamp01(x) * f32x8::splat(255.0) + f32x8::splat(0.5);
    cast::<i32x8, u32x8>(q.fast_trunc_int())
}

/// [`crate::to_rgba8`] of [`Resolved::pixel`] for 8 lanes; the output keeps the lane order.
/// Over an opaque background the alpha byte is the constant 255 (`to_rgba8` of 1).
#[inline(always)]
fn rgba8_lanes(c: [f32x8; 3], t: f32x8, background: Background) -> [[u8; 4]; LANES] {
    let packed = match background {
        Background::Opaque(bg) => {
            let bg = bg.to_array().map(f32x8::splat);
            let q: [u32x8; 3] = core::array::from_fn(|i| to_unorm8_lanes(c[i] + bg[i] * t));
            q[0] | (q[1] << 8) | (q[2] << 16) | u32x8::splat(0xff00_0000)
        }
        Background::Transparent => {
            let q = [c[0], c[1], c[2], f32x8::ONE - t].map(to_unorm8_lanes);
            q[0] | (q[1] << 8) | (q[2] << 16) | (q[3] << 24)
        }
    };
    cast::<u32x8, [u32; LANES]>(packed).map(u32::to_le_bytes)
}

/// A resolve of 8 pixels in registers, pixels in [`POSITION`] order.
#[derive(Clone, Copy)]
pub(super) struct Resolved8 {
    color: [f32x8; 3],
    t: f32x8,
}

impl Resolved8 {
    /// Structure of arrays, in pixel order.
    #[inline(always)]
    pub(super) fn lanes(self) -> super::ResolvedLanes {
        super::ResolvedLanes {
            color: self.color.map(|c| unpermute(c.to_array())),
            transmittance: unpermute(self.t.to_array()),
        }
    }
}

/// Eq. 5 over an MLAB span.
#[inline(always)]
pub(super) fn mlab_resolve<const M: usize>(span: &MlabSpan<M>) -> Resolved8 {
    let (color, t) = crate::resolve::resolve_layers(span.iter().map(layer_bytes));
    Resolved8 { color, t }
}

/// Eq. 5 over 8 pixels stored pixel-major (`pixels[lane][layer]`): each layer's color and
/// transmittance words are read straight into a register in [`POSITION`] order, without
/// transposing whole rows first. The same values as [`mlab_resolve`] of the transposed span.
#[inline(always)]
pub(super) fn mlab_resolve_pixel_major<const M: usize>(pixels: &[[Row; M]; LANES]) -> Resolved8 {
    let layer = |j: usize| {
        let words = if M == 1 {
            // The rows are contiguous: two vector loads, then the color words in
            // [`POSITION`] order as for a span's layer ([`words0`]). (Eight 32-bit inserts
            // instead ran slower on AVX2 than on SSE2: docs/performance.md, resolves.)
            let q = |p: usize| cast::<Row, u64>(pixels[p][j]);
            let (a, b) = (
                u64x4::new([q(0), q(1), q(2), q(3)]),
                u64x4::new([q(4), q(5), q(6), q(7)]),
            );
            words0(Rows8 { a: cast(a), b: cast(b) })
        } else {
            // Lane `POSITION[p]` holds pixel `p`: lanes 0..8 are pixels 0, 4, 1, 5, 2, 6, 3, 7.
            let w = |p: usize| pixels[p][j].words()[0];
            u32x8::new([w(0), w(4), w(1), w(5), w(2), w(6), w(3), w(7)])
        };
        rgbt_bytes(words)
    };
    let (color, t) = crate::resolve::resolve_layers((0..M).map(layer));
    Resolved8 { color, t }
}

/// The HT resolve of head layers and tails.
#[inline(always)]
pub(super) fn hybrid_resolve<T: TailFormat, const K: usize>(head: &[[Row; LANES]; K], tails: &[T; LANES]) -> Resolved8 {
    let (color, t) = hybrid_resolve_regs(head, tails);
    Resolved8 { color, t }
}

/// [`crate::to_rgba8`] per lane of a resolve given as arrays (lane order kept).
#[inline(always)]
pub(super) fn rgba8(color: &[[f32; LANES]; 3], t: &[f32; LANES], background: Background) -> [[u8; 4]; LANES] {
    rgba8_lanes(color.map(f32x8::new), f32x8::new(*t), background)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lane writer against the scalar one ([`crate::to_rgba8`]) for every f32 whose bits
    /// are a multiple of 509 (8.4 M values spread over the whole bit range: NaNs, infinities,
    /// negatives, subnormals), every f32 in `[0, 1]` within 64 ulps of a rounding boundary
    /// `(k + 0.5) / 255`, and the special values; over both backgrounds' alpha paths.
    #[test]
    fn unorm8_writer_matches_the_scalar_writer() {
        let scalar = |x: f32| crate::to_rgba8(glam::Vec4::splat(x))[0] as u32;
        let check = |xs: [f32; 8]| {
            let got = to_unorm8_lanes(f32x8::new(xs)).to_array();
            for (x, g) in xs.iter().zip(got) {
                assert_eq!(g, scalar(*x), "x = {x:e} ({:#x})", x.to_bits());
            }
        };
        let batch = |bits: &mut dyn Iterator<Item = u32>| {
            let mut xs = [0.0f32; 8];
            let mut n = 0;
            for b in bits {
                xs[n] = f32::from_bits(b);
                n += 1;
                if n == 8 {
                    check(xs);
                    n = 0;
                }
            }
            if n > 0 {
                check(xs);
            }
        };
        batch(&mut (0..=u32::MAX / 509).map(|i| i * 509));
        for k in 0..255u32 {
            let b = ((k as f32 + 0.5) / 255.0).to_bits();
            batch(&mut (b - 64..b + 64));
        }
        let specials = [
            0.0,
            -0.0,
            1.0,
            f32::NAN,
            -f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::MIN_POSITIVE,
        ];
        batch(&mut specials.iter().map(|x| x.to_bits()));
    }
}
