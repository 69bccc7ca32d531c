//! The integer resolve (`crate::resolve::int`) on SSE2: two pixels per 128-bit register, each
//! pixel's four 16-bit slots, with the factors and the visibility both doubled:
//! `q15(f, v) = (pmulhuw(2 f, 2 v) + 1) >> 1` (`pmulhuw` gives `floor(4 f v / 65536) =
//! floor(p / 16384) = 2 (p >> 15) + bit 14 of p`, and `(x + 1) >> 1` of that is
//! `(p + 16384) >> 15`). The doubled factors `[256 R, 256 G, 256 B, 2 floor(257 T / 2)]` are one
//! `punpcklbw` of the rows with their T bytes `& 0xfe` (`257 T & !1 = 2 floor(257 T / 2)`).

use super::Cell;
use crate::lanes::LANES;
use crate::resolve::int;
use crate::row::Row;
use bytemuck::cast;
use wide::{i16x8, u8x16, u16x8, u32x4};

/// `q15(f, v)` from `f2 = 2 f` (at most 65534) and `v2 = 2 v` (at most 65534).
#[inline(always)]
fn q15(f2: u16x8, v2: u16x8) -> u16x8 {
    (f2.mul_keep_high(v2) + u16x8::splat(1)) >> 1
}

/// Two rows (pixels) as the doubled factors `[256 R, 256 G, 256 B, 2 floor(257 T / 2)]`.
#[inline(always)]
fn factors(rows: [Row; 2]) -> u16x8 {
    let w: [u32; 4] = cast(rows);
    // The color words of both rows in the low 8 bytes (`pshufd`).
    let x: u8x16 = cast(u32x4::new([w[0], w[2], w[1], w[3]]));
    let t: u8x16 = x & cast::<u32x4, u8x16>(u32x4::splat(0xfe00_0000));
    cast(u8x16::unpack_low(t, x))
}

/// One layer of two pixels: `acc += q15(f, v)` (saturating at 32767), then the new `2 v`
/// in every slot of the pixel (`pshuflw`, `pshufhw`, `paddw`).
#[inline(always)]
fn layer(acc: &mut i16x8, v2: &mut u16x8, f2: u16x8) {
    let p = q15(f2, *v2);
    *acc = acc.saturating_add(cast(p));
    let a = p.to_array();
    let v = u16x8::new([a[3], a[3], a[3], a[3], a[7], a[7], a[7], a[7]]);
    *v2 = v + v;
}

/// The integer resolve of the `M` layers of 8 pixels of `cell`, as the SSSE3/AVX2 form
/// computes it.
#[inline(always)]
pub(super) fn resolve<const M: usize, const OPAQUE: bool>(cell: impl Cell<M>, bg: [u32; 3]) -> [[u8; 4]; LANES] {
    let start = int::ACC_START as i16;
    let alpha = if OPAQUE { int::ACC_MAX as i16 } else { start };
    let mut acc = [i16x8::new(core::array::from_fn(|i| if i % 4 == 3 { alpha } else { start })); 4];
    let mut v2 = [u16x8::splat(2 * int::VIS_ONE as u16); 4];
    for j in 0..M {
        let l = cell.layer(j);
        for k in 0..4 {
            layer(&mut acc[k], &mut v2[k], factors([l[2 * k], l[2 * k + 1]]));
        }
    }
    let q: [i16x8; 4] = core::array::from_fn(|k| {
        if OPAQUE {
            let [r, g, b] = bg;
            let bg2 = u16x8::new(core::array::from_fn(|i| (2 * [r, g, b, 0][i % 4]) as u16));
            cast::<u16x8, i16x8>(cast::<i16x8, u16x8>(acc[k].saturating_add(cast(q15(bg2, v2[k])))) >> 7)
        } else {
            let color = u16x8::new(core::array::from_fn(|i| if i % 4 == 3 { 0 } else { 0xffff }));
            let a = q15(u16x8::splat(2 * 32640), u16x8::splat(2 * int::VIS_ONE as u16) - v2[k]);
            let a = (a + u16x8::splat(64)) >> 7;
            let c = cast::<i16x8, u16x8>(acc[k]) >> 7;
            cast((c & color) | (a & !color))
        }
    });
    let lo: [u32; 4] = cast(u8x16::narrow_i16x8(q[0], q[1]));
    let hi: [u32; 4] = cast(u8x16::narrow_i16x8(q[2], q[3]));
    core::array::from_fn(|p| if p < 4 { lo[p] } else { hi[p - 4] }.to_le_bytes())
}
