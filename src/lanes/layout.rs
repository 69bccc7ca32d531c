//! Where each pixel of a span sits in the registers of a resolve: the rows' first words of a
//! layer in one register ([`POSITION`] order), the tails' fields, and back to pixel order.

use super::LANES;
use super::w256::{Rows8, words0, words1};
use crate::resolve::FloatLanes;
use crate::row::Row;
use crate::tail::{Layout, TailFormat};
use crate::vector::Layer8;
use bytemuck::cast;
use wide::{f32x8, u32x8};

/// Where pixel `p` of a span sits in the registers of the resolve: the 8 row words are
/// packed without a shuffle as `(a & LO) | (b << 32)`, which orders the pixels
/// `[0, 4, 1, 5, 2, 6, 3, 7]`. Every resolve step is per lane, so the order only matters when
/// the results are written out.
pub(super) const POSITION: [usize; LANES] = [0, 2, 4, 6, 1, 3, 5, 7];

/// Back to pixel order.
#[inline(always)]
pub(super) fn unpermute<T: Copy>(x: [T; LANES]) -> [T; LANES] {
    core::array::from_fn(|p| x[POSITION[p]])
}

/// Color and transmittance bytes of one layer of 8 rows, as exact f32 (`[R, G, B, T]`).
#[inline(always)]
pub(super) fn layer_bytes(layer: &[Row; LANES]) -> [f32x8; 4] {
    rgbt_bytes(words0(Rows8::load(layer)))
}

/// The `[R, G, B, T]` bytes of 8 color words, as exact f32.
#[inline(always)]
pub(super) fn rgbt_bytes(rgbt: u32x8) -> [f32x8; 4] {
    let byte = u32x8::splat(0xff);
    [rgbt & byte, (rgbt >> 8) & byte, (rgbt >> 16) & byte, rgbt >> 24].map(f32x8::from_u)
}

/// `word0` (the `[R, G, B, T]` bytes) of one layer of 8 rows, pixels in [`POSITION`] order.
#[inline(always)]
pub(super) fn layer_words(layer: &[Row; LANES]) -> u32x8 {
    words0(Rows8::load(layer))
}

/// The fields of 8 tails (color sums, alpha sum, count), pixels in [`POSITION`] order.
#[inline(always)]
pub(super) fn tail_fields<T: TailFormat>(tails: &[T; LANES]) -> ([u32x8; 3], u32x8, u32x8) {
    let tails = Rows8::from_rows(cast(*tails));
    let (w0, w1) = (words0(tails), words1(tails));
    match T::LAYOUT {
        Layout::Paper => {
            let field = u32x8::splat(0x3ff);
            let sums = [w0 & field, (w0 >> 10) & field, (w0 >> 20) & field];
            (sums, w1 & u32x8::splat(0xffff), w1 >> 16)
        }
        Layout::Wide => {
            // Colors at bits 0, 13, 26 (the last one across the words), alpha at 39, count at 53.
            let field = u32x8::splat(0x1fff);
            let blue = (w0 >> 26) | ((w1 & u32x8::splat(0x7f)) << 6);
            (
                [w0 & field, (w0 >> 13) & field, blue],
                (w1 >> 7) & u32x8::splat(0x3fff),
                w1 >> 21,
            )
        }
    }
}
