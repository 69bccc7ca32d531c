//! The integer resolve (`crate::resolve::int`) in 16-bit lanes: four pixels per register,
//! each pixel's four 16-bit slots `[R, G, B, T]` (its 8 bytes of a 128-bit half). Per layer,
//! one shuffle, one shift, one `pmulhrsw`, one saturating add and one shuffle.

use super::Cell;
use crate::lanes::LANES;
use crate::resolve::int;
use crate::row::Row;
use bytemuck::cast;
use wide::i8x32;
use wide::{i16x16, u16x16};

/// A zeroing shuffle index.
const Z: i8 = -128;

/// Two copies of a 16-byte shuffle (each 128-bit half shuffles its own bytes).
const fn halves(h: [i8; 16]) -> i8x32 {
    let mut out = [0i8; 32];
    let mut i = 0;
    while i < 16 {
        out[i] = h[i];
        out[i + 16] = h[i];
        i += 1;
    }
    i8x32::new(out)
}

/// Each row's bytes to the 16-bit slots `[256 R, 256 G, 256 B, 257 T]` (two rows per half;
/// the depth bytes are dropped).
const ROW_SLOTS: [i8; 16] = [Z, 0, Z, 1, Z, 2, 3, 3, Z, 8, Z, 9, Z, 10, 11, 11];
/// Slot 3 of each pixel (its visibility product) to all four of its slots.
const BROADCAST_T: [i8; 16] = [6, 7, 6, 7, 6, 7, 6, 7, 14, 15, 14, 15, 14, 15, 14, 15];
/// The low bytes of the 16-bit slots of a half to its bytes 0..8 (`PACK_LO`) or 8..16
/// (`PACK_HI`), the other bytes zero.
const PACK_LO: [i8; 16] = [0, 2, 4, 6, 8, 10, 12, 14, Z, Z, Z, Z, Z, Z, Z, Z];
const PACK_HI: [i8; 16] = [Z, Z, Z, Z, Z, Z, Z, Z, 0, 2, 4, 6, 8, 10, 12, 14];

/// Four rows (pixels) as the factors `[128 R, 128 G, 128 B, floor(257 T / 2)]`.
#[inline(always)]
fn factors(rows: [Row; 4]) -> i16x16 {
    let x: i8x32 = cast(rows);
    let s: u16x16 = cast(x.swizzle_half(halves(ROW_SLOTS)));
    cast(s >> 1)
}

/// One layer of four pixels: `acc += q15(f, v)` (saturating at 32767), then
/// `v = q15(T factor, v)` in every slot of the pixel.
#[inline(always)]
pub(super) fn layer(acc: &mut i16x16, v: &mut i16x16, f: i16x16) {
    let p = f.mul_scale_round(*v);
    *acc = acc.saturating_add(p);
    *v = cast(cast::<i16x16, i8x32>(p).swizzle_half(halves(BROADCAST_T)));
}

/// Eq. 5 in integers over the `M` layers of 8 pixels of `cell` (`layer_factors(j)`: the
/// factors of pixels 0..4 and 4..8), then the pixels (`int::pixel` per lane): over the
/// opaque background `bg` when `OPAQUE`, else premultiplied (`bg` unused).
#[inline(always)]
pub(super) fn resolve<const M: usize, const OPAQUE: bool>(cell: impl Cell<M>, bg: [u32; 3]) -> [[u8; 4]; LANES] {
    let layer_factors = |j: usize| {
        let l = cell.layer(j);
        [factors([l[0], l[1], l[2], l[3]]), factors([l[4], l[5], l[6], l[7]])]
    };
    // Over an opaque background slot 3 (the visibility products, not read) starts at
    // 32767 and stays there (saturating adds of non-negative values): its byte is the
    // alpha 255.
    let start = int::ACC_START as i16;
    let alpha = if OPAQUE { int::ACC_MAX as i16 } else { start };
    let mut acc = [i16x16::new(core::array::from_fn(|i| if i % 4 == 3 { alpha } else { start })); 2];
    let mut v = [i16x16::splat(int::VIS_ONE as i16); 2];
    for j in 0..M {
        let f = layer_factors(j);
        layer(&mut acc[0], &mut v[0], f[0]);
        layer(&mut acc[1], &mut v[1], f[1]);
    }
    pixels::<OPAQUE>(acc, v, bg)
}

/// `int::pixel` on 8 pixels: the 16-bit results, then their low bytes in pixel order.
#[inline(always)]
fn pixels<const OPAQUE: bool>(acc: [i16x16; 2], v: [i16x16; 2], bg: [u32; 3]) -> [[u8; 4]; LANES] {
    let q: [u16x16; 2] = if OPAQUE {
        let [r, g, b] = bg;
        let bg = i16x16::new(core::array::from_fn(|i| [r, g, b, 0][i % 4] as i16));
        [0, 1].map(|i| cast::<i16x16, u16x16>(acc[i].saturating_add(bg.mul_scale_round(v[i]))) >> 7)
    } else {
        let color = u16x16::new(core::array::from_fn(|i| if i % 4 == 3 { 0 } else { 0xffff }));
        [0, 1].map(|i| {
            let a = (i16x16::splat(int::VIS_ONE as i16) - v[i]).mul_scale_round(i16x16::splat(32640));
            let a = cast::<i16x16, u16x16>(a + i16x16::splat(64)) >> 7;
            let c = cast::<i16x16, u16x16>(acc[i]) >> 7;
            (c & color) | (a & !color)
        })
    };
    let lo = cast::<u16x16, i8x32>(q[0]).swizzle_half(halves(PACK_LO));
    let hi = cast::<u16x16, i8x32>(q[1]).swizzle_half(halves(PACK_HI));
    let bytes: [u64; 4] = cast(lo | hi);
    // The halves hold pixels [0, 1, 4, 5] and [2, 3, 6, 7].
    let words: [u32; LANES] = cast([bytes[0], bytes[2], bytes[1], bytes[3]]);
    words.map(u32::to_le_bytes)
}
